"""Simulated range finders: Dimetix DLS and Jenoptik LDM41/42 protocols as byte state machines.

Written from the manuals' descriptions (/work/shared/reference/protocols.md), independently of
the drivers. Both measure along the current beam of a :class:`~asbuilt.drivers.simrig.SimulatedRig`.

Dimetix DLS (device id N): commands end with CR LF (a bare CR or LF is accepted);
``sNg`` -> ``gNg+xxxxxxxx`` (0.1 mm, user offset added) or ``gN@E255`` (signal too weak);
``sNc`` stop, ``sNo`` / ``sNp`` laser on / off -> ``gN?``; ``sNt`` -> ``gNt+xxxxxxxx``
(temperature, 0.1 degC); ``sNuof`` -> ``gNuof+xxxxxxxx``, ``sNuof+xxxxxxxx`` sets the user
offset (0.1 mm) -> ``gN?``; anything else addressed to N -> ``gN@E203``; commands for another
id are ignored (a bus). At power-up the device sends ``gN?``.

LDM41/42: ``DM`` (also ``DW`` / ``DX`` on a white target) -> ``004.996`` in output format d or
``004.996 000985`` in format s (signal quality 0-1024) at scale 1, or ``E15`` (poor
reflectance). ``SDd`` / ``SDs`` choose the format, ``OF<metres>`` an offset (both answered with
the setting read back: the simulator's assumption, the manual's exact acknowledgement may differ),
``TP`` the temperature. Unknown commands get no reply (or ``unknown_reply``).

Options (constructor keywords; :class:`~asbuilt.drivers.pty_sim.PtyServer` passes them on):
both take ``measure_time`` (seconds per measurement); the Dimetix ``parity_bit7`` (7E1 bytes as
an 8N1 pty passes them) and ``refuse`` (an error code for every ``sNg``); both ``command_end``
(``"cr-keep-lf"``: commands end at CR, an LF starts the next one; ``"lf-keep-cr"``: commands
end at LF, a CR before it is part of the command); the LDM
``output_format``, ``hex_digits`` (0: unpadded format h) and ``unknown_reply``.
"""

from __future__ import annotations

import re
import time
from abc import ABC, abstractmethod

from .simrig import SimulatedRig

__all__ = ["DimetixSimulator", "LDMSimulator"]

_DIMETIX = re.compile(rb"^s(\d)([a-z]+)([+-]\d+)?$")
_ENDINGS = ("any", "cr-keep-lf", "lf-keep-cr")


class _LineDevice(ABC):
    """Common line assembly: bytes in, one command per CR/LF-terminated line.

    Parameters
    ----------
    rig : SimulatedRig
    measure_time : float
        Seconds a measurement takes: its reply is sent that long after the command (or after
        the previous measurement's reply, the device measuring one at a time).
    command_end : {"any", "cr-keep-lf", "lf-keep-cr"}
        ``"any"``: CR or LF ends a command (empty ones ignored). ``"cr-keep-lf"``: only CR does;
        an LF is kept as the first byte of the next command, which then is no command this
        device knows (a meter whose commands end at CR, sent CR LF). ``"lf-keep-cr"``: only LF
        does, and a CR before it stays in the command, which then is no command either.
    """

    def __init__(self, rig: SimulatedRig, measure_time: float = 0.0, command_end: str = "any"):
        if command_end not in _ENDINGS:
            raise ValueError(f"command_end must be one of {_ENDINGS}, got {command_end!r}")
        self.rig = rig
        self.measure_time = float(measure_time)
        self.command_end = command_end
        self._line = bytearray()
        self._busy_until = 0.0

    def feed(self, data: bytes) -> list[tuple[float, bytes]]:
        """Consume bytes from the host; return ``(deliver_at, bytes)`` chunks to send back."""
        now = time.monotonic()
        out: list[tuple[float, bytes]] = []
        ends = {"cr-keep-lf": b"\r", "lf-keep-cr": b"\n"}.get(self.command_end, b"\r\n")
        kept = self.command_end != "any"  # the other byte is part of the command
        for byte in data:
            if byte in ends:
                if self._line:
                    raw = bytes(self._line)
                    line = raw.strip(b" ") if kept else raw.strip()
                    self._line.clear()
                    if line:
                        at = now
                        if self._measures(line) and self.measure_time > 0:
                            at = max(now, self._busy_until) + self.measure_time
                            self._busy_until = at
                        out.extend((at, reply + b"\r\n") for reply in self._execute(line))
            else:
                self._line.append(byte)
                if len(self._line) > 64:
                    self._line.clear()
        return out

    def _measures(self, line: bytes) -> bool:
        """Whether the command ``line`` takes a measurement (``measure_time``)."""
        return False

    @abstractmethod
    def _execute(self, line: bytes) -> list[bytes]:
        """The replies, without their line ends, to one command line."""


class DimetixSimulator(_LineDevice):
    """A Dimetix DLS sensor with id ``device_id`` over a rig."""

    def __init__(
        self,
        rig: SimulatedRig,
        device_id: int = 0,
        *,
        measure_time: float = 0.0,
        parity_bit7: bool = False,
        refuse: int | None = None,
        command_end: str = "any",
    ):
        super().__init__(rig, measure_time, command_end)
        self.device_id = device_id
        self.user_offset = 0  # 0.1 mm
        self.laser = False
        #: Send 7E1 characters as an 8N1 port (a pseudo-terminal) passes them on: the even
        #: parity bit as bit 7.
        self.parity_bit7 = bool(parity_bit7)
        #: Answer every ``sNg`` with this error code (a device that needs attention: E203,
        #: E222-E224, E252, E254...).
        self.refuse = refuse

    def startup(self) -> list[tuple[float, bytes]]:
        """Power-up message ``gN?``."""
        return [(time.monotonic(), self._wire(f"g{self.device_id}?\r\n".encode()))]

    def feed(self, data: bytes) -> list[tuple[float, bytes]]:
        return [(at, self._wire(chunk)) for at, chunk in super().feed(data)]

    def _wire(self, data: bytes) -> bytes:
        if not self.parity_bit7:
            return data
        return bytes(b | (0x80 if bin(b).count("1") % 2 else 0) for b in data)

    def _measures(self, line: bytes) -> bool:
        return line.endswith(b"g") and len(line) == 3

    def _execute(self, line: bytes) -> list[bytes]:
        m = _DIMETIX.match(line)
        if m is None:
            return []  # not addressed in a form this device parses
        n = int(m.group(1))
        if n != self.device_id:
            return []
        cmd, arg = m.group(2).decode(), m.group(3)
        ok = f"g{n}?".encode()
        if cmd == "g" and arg is None:
            if self.refuse is not None:
                return [f"g{n}@E{int(self.refuse):03d}".encode()]
            value = self.rig.measure()
            if value is None:
                return [f"g{n}@E255".encode()]
            tenths = int(round(value * 1e4)) + self.user_offset
            if abs(tenths) > 99_999_999:
                return [f"g{n}@E255".encode()]
            return [f"g{n}g{tenths:+09d}".encode()]
        if cmd in ("c", "h") and arg is None:
            return [ok]
        if cmd in ("o", "p") and arg is None:
            self.laser = cmd == "o"
            return [ok]
        if cmd == "t" and arg is None:
            return [f"g{n}t+00000250".encode()]
        if cmd == "uof":
            if arg is None:
                return [f"g{n}uof{self.user_offset:+09d}".encode()]
            self.user_offset = int(arg)
            return [ok]
        return [f"g{n}@E203".encode()]


class LDMSimulator(_LineDevice):
    """A Jenoptik LDM41/42 over a rig."""

    def __init__(
        self,
        rig: SimulatedRig,
        *,
        measure_time: float = 0.0,
        command_end: str = "any",
        output_format: str = "d",
        hex_digits: int = 6,
        unknown_reply: str | None = None,
    ):
        super().__init__(rig, measure_time, command_end)
        if output_format not in ("d", "s", "h"):
            raise ValueError(f"output_format must be d, s or h, got {output_format!r}")
        self.format = output_format
        #: Zero-padded width of format h (0: no padding, e.g. ``E10`` for 3600 mm).
        self.hex_digits = int(hex_digits)
        #: Reply to a command this device does not know (None: silence).
        self.unknown_reply = unknown_reply
        self.offset = 0.0

    def _measures(self, line: bytes) -> bool:
        return line.upper() in (b"DM", b"DW", b"DX")

    def startup(self) -> list[tuple[float, bytes]]:
        """Output at power-up (none with autostart off)."""
        return []

    def _execute(self, line: bytes) -> list[bytes]:
        text = line.decode("ascii", "replace")
        text = text.strip(" ") if self.command_end != "any" else text.strip()  # "\nDM", "DM\r"
        cmd, arg = text[:2].upper(), text[2:].strip(" " if self.command_end != "any" else None)
        if cmd in ("DM", "DW", "DX") and not arg:
            value = self.rig.measure()
            if value is None:
                return [b"E15"]
            value += self.offset
            if not -99.999 <= value <= 999.999:
                return [b"E15"]
            if self.format == "s":
                return [f"{value:07.3f} {1000:06d}".encode()]
            if self.format == "h":  # hexadecimal millimetres
                return [f"{max(round(value * 1000), 0):0{self.hex_digits}X}".encode()]
            return [f"{value:07.3f}".encode()]
        if cmd == "SD" and arg.lower() in ("d", "s", "h"):
            self.format = arg.lower()
            return [f"SD{self.format}".encode()]
        if cmd == "OF":
            try:
                self.offset = float(arg) if arg else self.offset
            except ValueError:
                return []
            return [f"OF{self.offset:+.3f}".encode()]
        if cmd == "TP" and not arg:
            return [b"+25.0"]
        return [] if self.unknown_reply is None else [self.unknown_reply.encode("ascii")]
