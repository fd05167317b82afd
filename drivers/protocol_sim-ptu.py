"""pyserial URL handler for ``sim-ptu://``: see :mod:`asbuilt.drivers.simport`.

pyserial imports ``<package>.protocol_<scheme>`` for a URL ``<scheme>://...``, hence the hyphen.
"""

from asbuilt.drivers.simport import Serial

__all__ = ["Serial"]
