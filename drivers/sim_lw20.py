"""A simulated LightWare LW20 / SF20 in serial mode, written from the reference's description
(/work/shared/reference/protocols.md), independently of :mod:`asbuilt.drivers.lw20`.

Commands end with CR LF (a bare CR or LF is accepted). Until ``www`` selects serial mode every
command is ignored (the device is not listening on its serial port yet); ``www`` itself gets no
reply (the simulator's assumption: the reference gives none). Then ``LD`` answers the distance
along the rig's beam in metres with two decimals (the LW20's centimetre resolution), e.g.
``4.99``, and ``-1.00`` when there is no return (the simulator's choice of "no target"; the
reference is silent; ``no_target`` sets another text, e.g. ``no target`` or ``--.--``). A
``prefix`` option puts a label before the value (``ld:4.99``).
Other commands get no reply.
"""

from __future__ import annotations

from .sim_lrf import _LineDevice
from .simrig import SimulatedRig

__all__ = ["LW20Simulator"]


class LW20Simulator(_LineDevice):
    """An LW20 over a rig; ``prefix`` is put before every distance, ``no_target`` (after the
    prefix) is the answer when there is no return."""

    def __init__(self, rig: SimulatedRig, prefix: str = "", *, no_target: str = "-1.00"):
        super().__init__(rig)
        self.prefix = prefix
        self.no_target = no_target
        self.serial_mode = False

    def startup(self) -> list[tuple[float, bytes]]:
        """Output at power-up (none)."""
        return []

    def _execute(self, line: bytes) -> list[bytes]:
        text = line.decode("ascii", "replace").strip()
        if text.lower() == "www":
            self.serial_mode = True
            return []
        if not self.serial_mode:
            return []
        if text.upper() == "LD":
            value = self.rig.measure()
            if value is None or not 0 < value < 1000:
                return [f"{self.prefix}{self.no_target}".encode()]
            return [f"{self.prefix}{value:.2f}".encode()]
        return []
