"""Acquisition: pan-tilt and range finder drivers, device simulators, kinematics, calibration, scans.

Installed as ``asbuilt.drivers`` (the repository's top-level ``drivers/`` folder). Importing it
registers the simulator URL handlers (``sim-ptu://``, ``sim-lrf://``) with pyserial, so
:func:`serial.serial_for_url` can open them.

Main entry points::

    from asbuilt.drivers.ptu import PanTiltUnit
    from asbuilt.drivers.rangefinder import open_range_finder
    from asbuilt.drivers.kinematics import Calibration, forward, aim
    from asbuilt.drivers.calibration import load_calibration, estimate_calibration
    from asbuilt.drivers.session import ScanSession
"""

from .transport import register_url_handlers

register_url_handlers()

__all__ = ["register_url_handlers"]
