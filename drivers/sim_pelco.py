"""A simulated Pelco-D pan-tilt head: the binary protocol as a byte state machine.

Written from the reference's description (/work/shared/reference/protocols.md, "Pelco-D"),
independently of :mod:`asbuilt.drivers.pelco`:

* a frame is ``FF addr cmd1 cmd2 data1 data2 checksum`` with checksum ``(addr + cmd1 + cmd2 +
  data1 + data2) mod 256``; bytes are taken one at a time, in any pieces: anything before a
  ``FF`` is ignored, and a frame with a bad checksum is dropped by resynchronising on the next
  ``FF`` inside it (as a receiver has to);
* frames for another address are ignored (a bus);
* ``00 4B`` / ``00 4D`` set the absolute pan / tilt in hundredths of a degree (data1 high, data2
  low; values of 36000 and above are ignored) and get no reply; ``00 00 00 00`` stops;
* ``00 51`` / ``00 53`` query the pan / tilt: answered ``00 59`` / ``00 5B`` with the current
  position (while moving, where the head is now) in data1 (high) data2 (low);
* the simulator's own assumptions where the reference is silent: pan turns all the way round
  (0-35999); tilt raw 0 is level and grows downwards (``tilt_sign=-1``), mechanically limited
  to +-90 degrees (a target beyond is clamped); other commands are ignored. With
  ``tilt_encoding="signed"`` the tilt is 16-bit two's complement instead, set and reported
  (-10 degrees raw is ``FC 18``), as some heads do;
* ``busy_silent``: a position query gets no answer while the head is moving (some heads are
  busy then).

Options for tests of the driver: ``trickle`` sends every reply byte by byte, ``trickle``
seconds apart (replies split across reads); ``corrupt`` (a set of reply numbers, 1-based) sends
those replies with a wrong checksum.

The head moves the :class:`~asbuilt.drivers.simrig.SimulatedRig`'s axes, whose counts are the
rig's resolution (so the rig's beam is where the head points). Output is *timed*: each chunk
carries the monotonic time the wire would deliver it.
"""

from __future__ import annotations

import time

from .simrig import SimulatedRig

__all__ = ["PelcoDSimulator"]

_FULL = 36000


def _signed(hundredths: float) -> float:
    value = hundredths % _FULL
    return value - _FULL if value > _FULL / 2 else value


class PelcoDSimulator:
    """A Pelco-D head at ``address`` over a :class:`SimulatedRig`.

    Parameters
    ----------
    rig : SimulatedRig
    address : int
        1-255.
    tilt_sign : {-1, 1}
        How the raw tilt grows: -1 downwards, +1 upwards.
    tilt_range : (float, float)
        Mechanical tilt range, degrees up positive.
    tilt_encoding : {"wrap", "signed"}
        Raw tilt in 0-35999 (default) or in signed 16-bit two's complement.
    busy_silent : bool
        No answer to position queries while moving.
    trickle : float
        Seconds between the bytes of a reply (0: a reply in one piece).
    corrupt : iterable of int
        Replies (1-based) sent with a wrong checksum.
    """

    def __init__(
        self,
        rig: SimulatedRig,
        address: int = 1,
        *,
        tilt_sign: int = -1,
        tilt_range=(-90.0, 90.0),
        tilt_encoding: str = "wrap",
        busy_silent: bool = False,
        trickle: float = 0.0,
        corrupt=(),
    ):
        self.rig = rig
        self.address = int(address)
        self.tilt_sign = tilt_sign
        self.tilt_range = tuple(float(v) for v in tilt_range)
        if tilt_encoding not in ("wrap", "signed"):
            raise ValueError(f"tilt_encoding must be 'wrap' or 'signed', got {tilt_encoding!r}")
        self.tilt_encoding = tilt_encoding
        self.busy_silent = bool(busy_silent)
        self.trickle = float(trickle)
        self.corrupt = set(corrupt)
        self.replies = 0
        self.frames: list[bytes] = []  # every valid frame received (any address)
        self._rx = bytearray()

    def startup(self) -> list[tuple[float, bytes]]:
        """Output at power-up (none)."""
        return []

    # -- angles: raw hundredths <-> rig counts ----------------------------------------------
    def _to_counts(self, degrees: float, axis: int) -> float:
        return degrees * 3600.0 / self.rig.resolution[axis]

    def _to_degrees(self, counts: float, axis: int) -> float:
        return counts * self.rig.resolution[axis] / 3600.0

    def _raw_position(self, now: float) -> tuple[int, int]:
        pan_c, tilt_c = self.rig.counts(now)
        pan = round(self._to_degrees(pan_c, 0) * 100) % _FULL
        tilt = round(self.tilt_sign * self._to_degrees(tilt_c, 1) * 100)
        return pan, tilt % (0x10000 if self.tilt_encoding == "signed" else _FULL)

    # -- bytes -----------------------------------------------------------------------------
    def feed(self, data: bytes) -> list[tuple[float, bytes]]:
        """Consume bytes from the host; return ``(deliver_at, bytes)`` chunks to send back."""
        now = time.monotonic()
        out: list[tuple[float, bytes]] = []
        for byte in data:
            if not self._rx and byte != 0xFF:
                continue  # waiting for a sync byte
            self._rx.append(byte)
            if len(self._rx) < 7:
                continue
            if sum(self._rx[1:6]) % 256 == self._rx[6]:
                frame = bytes(self._rx)
                self._rx.clear()
                self.frames.append(frame)
                if frame[1] == self.address:
                    out.extend(self._execute(frame, now))
            else:  # resynchronise on the next FF inside the bad frame
                rest = self._rx[1:]
                self._rx.clear()
                i = rest.find(0xFF)
                if i >= 0:
                    out.extend(self.feed(bytes(rest[i:])))
        return out

    def _reply(self, now: float, cmd2: int, value: int) -> list[tuple[float, bytes]]:
        self.replies += 1
        body = bytes((self.address, 0x00, cmd2, value >> 8, value & 0xFF))
        check = sum(body) % 256
        if self.replies in self.corrupt:
            check = (check + 1) % 256
        data = b"\xff" + body + bytes((check,))
        if self.trickle <= 0:
            return [(now, data)]
        return [(now + i * self.trickle, data[i : i + 1]) for i in range(len(data))]

    def _execute(self, frame: bytes, now: float) -> list[tuple[float, bytes]]:
        cmd1, cmd2, value = frame[2], frame[3], (frame[4] << 8) | frame[5]
        if cmd1 != 0x00:
            return []
        if cmd2 == 0x4B and value < _FULL:
            self.rig.move(pan_counts=self._to_counts(_signed(value) / 100, 0))
        elif cmd2 == 0x4D and self.tilt_encoding == "signed":
            self._tilt_to(self.tilt_sign * (value - 0x10000 if value >= 0x8000 else value) / 100)
        elif cmd2 == 0x4D and value < _FULL:
            self._tilt_to(self.tilt_sign * _signed(value) / 100)
        elif cmd2 == 0x00 and value == 0:  # stop where the head is
            pan_c, tilt_c = self.rig.counts(now)
            self.rig.move(pan_c, tilt_c)
        elif cmd2 in (0x51, 0x53) and self.busy_silent and self._moving(now):
            return []
        elif cmd2 == 0x51:
            return self._reply(now, 0x59, self._raw_position(now)[0])
        elif cmd2 == 0x53:
            return self._reply(now, 0x5B, self._raw_position(now)[1])
        return []

    def _moving(self, now: float) -> bool:
        return now < self.rig.move_end()

    def _tilt_to(self, up: float) -> None:
        """Tilt to ``up`` degrees, clamped to the mechanical range."""
        lo, hi = self.tilt_range
        self.rig.move(tilt_counts=self._to_counts(min(max(up, lo), hi), 1))
