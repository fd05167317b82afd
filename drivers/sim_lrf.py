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
``TP`` the temperature. Unknown commands get no reply.
"""

from __future__ import annotations

import re
import time
from abc import ABC, abstractmethod

from .simrig import SimulatedRig

__all__ = ["DimetixSimulator", "LDMSimulator"]

_DIMETIX = re.compile(rb"^s(\d)([a-z]+)([+-]\d+)?$")


class _LineDevice(ABC):
    """Common line assembly: bytes in, one command per CR/LF-terminated line."""

    def __init__(self, rig: SimulatedRig):
        self.rig = rig
        self._line = bytearray()

    def feed(self, data: bytes) -> list[tuple[float, bytes]]:
        """Consume bytes from the host; return ``(deliver_at, bytes)`` chunks to send back."""
        now = time.monotonic()
        out: list[tuple[float, bytes]] = []
        for byte in data:
            if byte in b"\r\n":
                if self._line:
                    line = bytes(self._line).strip()
                    self._line.clear()
                    if line:
                        out.extend((now, reply + b"\r\n") for reply in self._execute(line))
            else:
                self._line.append(byte)
                if len(self._line) > 64:
                    self._line.clear()
        return out

    @abstractmethod
    def _execute(self, line: bytes) -> list[bytes]:
        """The replies, without their line ends, to one command line."""


class DimetixSimulator(_LineDevice):
    """A Dimetix DLS sensor with id ``device_id`` over a rig."""

    def __init__(self, rig: SimulatedRig, device_id: int = 0):
        super().__init__(rig)
        self.device_id = device_id
        self.user_offset = 0  # 0.1 mm
        self.laser = False

    def startup(self) -> list[tuple[float, bytes]]:
        """Power-up message ``gN?``."""
        return [(time.monotonic(), f"g{self.device_id}?\r\n".encode())]

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

    def __init__(self, rig: SimulatedRig):
        super().__init__(rig)
        self.format = "d"
        self.offset = 0.0

    def startup(self) -> list[tuple[float, bytes]]:
        """Output at power-up (none with autostart off)."""
        return []

    def _execute(self, line: bytes) -> list[bytes]:
        text = line.decode("ascii", "replace").strip()
        cmd, arg = text[:2].upper(), text[2:].strip()
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
                return [f"{max(round(value * 1000), 0):06X}".encode()]
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
        return []
