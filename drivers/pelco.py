"""Driver for pan-tilt heads speaking Pelco-D (the binary protocol of inexpensive heads).

Protocol (/work/shared/reference/protocols.md, "Pelco-D"): every message is a 7-byte frame
``FF addr cmd1 cmd2 data1 data2 checksum``, the checksum being ``(addr + cmd1 + cmd2 + data1 +
data2) mod 256`` (the sync byte ``FF`` is not summed). Absolute pan is ``00 4B`` and absolute tilt
``00 4D`` with the angle in hundredths of a degree in data1 (high) data2 (low); the position
queries ``00 51`` (pan) and ``00 53`` (tilt) are answered ``00 59`` / ``00 5B`` with the value in
data1 (high) data2 (low).

What the reference leaves to "the unit" and this driver assumes (all of it documented in
docs/drivers.md and adjustable):

* the set commands get no reply (some heads acknowledge: whatever arrives unasked is dropped
  before the next query), so a move waits for arrival by *polling the position queries* until
  both axes report the target (within ``tolerance`` hundredths) or ``move_timeout`` passes. A
  head that has stopped (the same position reported for ``SETTLE_TIME`` seconds) within
  ``SETTLE_NEAR`` hundredths of the target (its steps do not fall on every hundredth) has
  arrived too; the position the head reports on arrival is returned as reached. A head seen
  moving that then stays away from the target for ``STALL_TIME`` seconds stopped short of it (a
  mechanical limit, which the protocol cannot report): a limit error, not a timeout;
* pan 0-35999 is a full turn: any finite pan angle is accepted and wrapped (``pan_limits``
  restricts it for a head with a stop); positions read back are signed, in (-180, 180] degrees;
* tilt: raw 0 is level (``tilt_zero``) and the raw value grows *downwards* (``tilt_sign=-1``:
  9000 straight down, 27000-35999 above the horizon), the convention of most heads that document
  it; angles returned are positive *up*, as :class:`~asbuilt.drivers.ptu.PanTiltUnit`'s are.
  The tilt range defaults to +-90 degrees (``tilt_limits``);
* tilt on the wire: the reference gives no encoding for negative angles. By default
  (``tilt_encoding="wrap"``) a tilt is sent as 0-35999 (-10 degrees raw is 35000); heads that use
  signed 16-bit two's complement instead (-10 degrees raw is ``FC 18``, 64536) take
  ``tilt_encoding="signed"``. Tilt *replies* are read either way: 0-35999 as such, and a value
  above 35999, which only a signed head sends, as its negative two's complement (noted once in
  :attr:`PelcoD.notes`, with a hint in any later move error, for a head set to "wrap");
* the host port is 2400 baud 8N1 (the usual factory setting of Pelco-D heads), address 1.

Every reply's checksum is verified. Bytes before a ``FF`` sync (noise, a late or foreign
acknowledgement) are dropped, and a ``FF`` that does not start a frame with a valid checksum is
skipped to the next ``FF``, so the reader finds the next good frame on its own (resync). What
cannot be read is said as such when the reply timeout ends: a bad checksum, frames only from
another address, a short frame, or silence (:class:`~asbuilt.errors.DeviceTimeout`). Replies may
arrive in any number of pieces.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import serial

from asbuilt.errors import DeviceError, DeviceProtocolError, DeviceTimeout

from .ptu import PTULimitError
from .transport import _seconds, open_port, read_bytes, reset_input, write_bytes

__all__ = [
    "PelcoLimits",
    "PelcoD",
    "checksum",
    "frame",
    "PAN_ABSOLUTE",
    "TILT_ABSOLUTE",
    "QUERY_PAN",
    "QUERY_TILT",
    "PAN_REPLY",
    "TILT_REPLY",
    "TILT_ENCODINGS",
]

SYNC = 0xFF
PAN_ABSOLUTE = 0x4B
TILT_ABSOLUTE = 0x4D
QUERY_PAN = 0x51
QUERY_TILT = 0x53
PAN_REPLY = 0x59
TILT_REPLY = 0x5B
FULL_TURN = 36000  # hundredths of a degree
WORD = 0x10000  # a 16-bit data1/data2 value
#: How a tilt goes on the wire (``tilt_encoding``): ``"wrap"`` 0-35999, ``"signed"`` 16-bit two's
#: complement.
TILT_ENCODINGS = ("wrap", "signed")

#: Seconds of quiet :meth:`PelcoD._resync` waits for after a failed exchange (late bytes).
RESYNC_QUIET = 0.1
#: Consecutive unreadable position replies a move's polling tolerates (line noise).
POLL_RETRIES = 3
#: Seconds a reported position must stay the same for the head to count as stopped.
SETTLE_TIME = 0.5
#: Hundredths of a degree a stopped head may lie off its target and still count as arrived: a
#: head whose steps do not fall on every hundredth (the reference gives no resolution) stops at
#: the step nearest the target, and reports that; the position it reports is then the one
#: returned as reached.
SETTLE_NEAR = 10
#: Seconds a reported position must stay the same, away from the target, for a head that has
#: been seen moving to count as stopped short of it (a mechanical limit the protocol cannot
#: report, an obstruction): the move is then refused as a limit instead of waiting out
#: ``move_timeout``.
STALL_TIME = 2.0


def checksum(addr: int, cmd1: int, cmd2: int, data1: int, data2: int) -> int:
    """The Pelco-D checksum: the sum of the five bytes after the sync, mod 256."""
    return (addr + cmd1 + cmd2 + data1 + data2) % 256


def frame(addr: int, cmd1: int, cmd2: int, data1: int = 0, data2: int = 0) -> bytes:
    """One 7-byte Pelco-D frame ``FF addr cmd1 cmd2 data1 data2 checksum``."""
    body = (addr, cmd1, cmd2, data1, data2)
    if not all(0 <= b <= 255 for b in body):
        raise ValueError(f"Pelco-D frame bytes must be 0-255, got {body}")
    return bytes((SYNC, *body, checksum(*body)))


def _hex(data: bytes) -> str:
    return " ".join(f"{b:02X}" for b in data)


def _signed(hundredths: int) -> int:
    """A raw angle 0-35999 as the signed value in (-18000, 18000]."""
    value = hundredths % FULL_TURN
    return value - FULL_TURN if value > FULL_TURN // 2 else value


@dataclass(frozen=True)
class PelcoLimits:
    """Angle limits of a Pelco-D head, in hundredths of a degree (unit angles: tilt up positive).

    Attributes
    ----------
    pan_min, pan_max : int or None
        Signed pan limits in (-18000, 18000]; None for a head that turns all the way round.
    tilt_min, tilt_max : int
        Tilt limits.
    """

    pan_min: int | None
    pan_max: int | None
    tilt_min: int
    tilt_max: int

    @property
    def continuous(self) -> bool:
        """Whether the pan axis turns all the way round (no pan limits)."""
        return self.pan_min is None

    def pan_range(self) -> tuple[float, float]:
        """Pan limits in radians (``-pi, pi`` for a continuous head)."""
        if self.continuous:
            return -math.pi, math.pi
        return math.radians(self.pan_min / 100), math.radians(self.pan_max / 100)

    def tilt_range(self) -> tuple[float, float]:
        """Tilt limits in radians."""
        return math.radians(self.tilt_min / 100), math.radians(self.tilt_max / 100)

    def pan_ok(self, hundredths: int) -> bool:
        """Whether a pan angle (hundredths, any turn) is within reach."""
        return self.continuous or self.pan_min <= _signed(hundredths) <= self.pan_max

    def tilt_ok(self, hundredths: int) -> bool:
        """Whether a tilt angle (hundredths) is within reach."""
        return self.tilt_min <= hundredths <= self.tilt_max

    def ranges_missed(self, angles) -> str:
        """The ranges that some of ``angles`` (pan, tilt in radians) fall outside, for a message.

        Same wording as :meth:`asbuilt.drivers.ptu.PTULimits.ranges_missed`; empty when every
        angle rounds to a reachable hundredth of a degree.
        """
        angles = list(angles)
        missed = []
        for axis, i, (lo, hi), ok in (
            ("pan", 0, self.pan_range(), self.pan_ok),
            ("tilt", 1, self.tilt_range(), self.tilt_ok),
        ):
            values = [math.degrees(a[i]) * 100 for a in angles]
            if not all(math.isfinite(v) and ok(round(v)) for v in values):
                missed.append(f"{axis} range [{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] deg")
        return " and ".join(missed)


def _limits(pan_limits, tilt_limits) -> PelcoLimits:
    def hundredths(pair, what):
        try:
            lo, hi = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ValueError(f"{what} must be two angles in degrees, got {pair!r}") from None
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
            raise ValueError(f"{what} must be two finite angles, low < high, got {pair!r}")
        return round(lo * 100), round(hi * 100)

    pan = (None, None)
    if pan_limits is not None:
        pan = hundredths(pan_limits, "pan_limits")
        if not (-18000 < pan[0] and pan[1] <= 18000):
            raise ValueError(f"pan_limits must lie in (-180, 180] degrees, got {pan_limits!r}")
    tilt = hundredths(tilt_limits, "tilt_limits")
    if not (-18000 < tilt[0] and tilt[1] <= 18000):
        raise ValueError(f"tilt_limits must lie in (-180, 180] degrees, got {tilt_limits!r}")
    return PelcoLimits(pan[0], pan[1], tilt[0], tilt[1])


class PelcoD:
    """A Pelco-D pan-tilt head on a serial port, with the interface of
    :class:`~asbuilt.drivers.ptu.PanTiltUnit` that scan sessions use (``move_to``,
    ``position``, ``limits``, ``close``).

    Parameters
    ----------
    port : serial.SerialBase
        The open port; use :meth:`open` to build one from a URL.
    name : str
        Device name for messages.
    address : int
        The head's address, 1-255.
    timeout : float
        Seconds to wait for the reply to a position query.
    move_timeout : float
        Seconds to wait for a move to arrive.
    tilt_sign : {-1, 1}
        How the raw tilt grows: -1 downwards (default), +1 upwards.
    tilt_zero : float
        Raw tilt of the level head, degrees (0).
    tilt_encoding : {"wrap", "signed"}
        How a raw tilt below zero is sent: ``"wrap"`` (default) into 0-35999, ``"signed"`` as
        16-bit two's complement. Replies are read in either encoding.
    pan_limits : (float, float) or None
        Signed pan limits in degrees; None (default) for a head turning all the way round.
    tilt_limits : (float, float)
        Tilt limits in degrees, up positive (-90, 90).
    tolerance : int
        Hundredths of a degree a reported position may differ from the target on arrival (1).
    poll_interval : float
        Seconds between position queries while a move is under way.

    Examples
    --------
    >>> with PelcoD.open("/dev/ttyUSB0", address=1) as head:     # doctest: +SKIP
    ...     head.move_to(math.radians(30), math.radians(-5))
    ...     pan, tilt = head.position()
    """

    def __init__(
        self,
        port,
        name: str,
        *,
        address: int = 1,
        timeout: float = 2.0,
        move_timeout: float = 30.0,
        tilt_sign: int = -1,
        tilt_zero: float = 0.0,
        tilt_encoding: str = "wrap",
        pan_limits=None,
        tilt_limits=(-90.0, 90.0),
        tolerance: int = 1,
        poll_interval: float = 0.02,
    ):
        if isinstance(address, bool) or int(address) != address or not 1 <= address <= 255:
            raise ValueError(f"address must be a Pelco-D address 1-255, got {address!r}")
        if tilt_sign not in (1, -1):
            raise ValueError(f"tilt_sign must be 1 or -1, got {tilt_sign!r}")
        if tilt_encoding not in TILT_ENCODINGS:
            raise ValueError(f"tilt_encoding must be 'wrap' or 'signed', got {tilt_encoding!r}")
        if not math.isfinite(float(tilt_zero)):
            raise ValueError(f"tilt_zero must be a finite angle in degrees, got {tilt_zero!r}")
        if int(tolerance) != tolerance or tolerance < 0:
            raise ValueError(
                f"tolerance must be a whole number of hundredths >= 0, not {tolerance}"
            )
        self.port = port
        self.name = name
        self.address = int(address)
        self.timeout = _seconds(timeout, "timeout")
        self.move_timeout = _seconds(move_timeout, "move_timeout")
        self.poll_interval = _seconds(poll_interval, "poll_interval", zero=True)
        self.tilt_sign = int(tilt_sign)
        self.tilt_zero = round(float(tilt_zero) * 100) % FULL_TURN
        self.tilt_encoding = tilt_encoding
        #: Whether the head has reported a tilt above 35999 (signed 16-bit: below zero).
        self.signed_tilt_seen = False
        #: What the driver found out about the head on the way (an encoding it did not expect),
        #: oldest first; whoever keeps a log takes them (the scan session journals them).
        self.notes: list[str] = []
        self.tolerance = int(tolerance)
        self.limits = _limits(pan_limits, tilt_limits)
        self._buffer = bytearray()
        self._unsynced = False  # an exchange failed: late bytes may still come
        self._seen_moving = False  # a position change seen while polling: the head obeys moves

    @classmethod
    def open(
        cls,
        url: str,
        *,
        baudrate: int = 2400,
        timeout: float = 2.0,
        move_timeout: float = 30.0,
        initialize: bool = True,
        **options,
    ) -> PelcoD:
        """Open the head at ``url`` (8N1, default 2400 baud) and, by default, :meth:`initialize`.

        ``options`` go to the constructor (``address``, ``tilt_sign``, ``tilt_zero``,
        ``tilt_encoding``, ``pan_limits``, ``tilt_limits``, ``tolerance``, ``poll_interval``).
        """
        port = open_port(url, baudrate=baudrate, write_timeout=timeout)
        try:
            head = cls(
                port,
                f"Pelco-D head on {url} (address {options.get('address', 1)})",
                timeout=timeout,
                move_timeout=move_timeout,
                **options,
            )
            if initialize:
                head.initialize()
        except BaseException:
            try:
                port.close()
            except (serial.SerialException, OSError):
                pass
            raise
        return head

    # -- context manager -------------------------------------------------------------------
    def __enter__(self) -> PelcoD:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the port (idempotent)."""
        try:
            self.port.close()
        except (serial.SerialException, OSError):
            pass

    # -- wire ------------------------------------------------------------------------------
    def send(self, cmd1: int, cmd2: int, data1: int = 0, data2: int = 0) -> None:
        """Send one frame to this head's address."""
        write_bytes(self.port, self.name, frame(self.address, cmd1, cmd2, data1, data2), "head")

    def _read_some(self) -> None:
        chunk = read_bytes(self.port, self.name)
        if chunk:
            self._buffer.extend(chunk)
            if len(self._buffer) > 4096:  # only possible with no 0xFF at all, see _pop_frame
                del self._buffer[:-7]

    def _discard_input(self) -> None:
        self._buffer.clear()
        reset_input(self.port, self.name)

    def _pop_frame(self, bad: list[bytes]) -> bytes | None:
        """The next frame with a valid checksum in the buffer, or None (wait for more bytes).

        Bytes before a ``FF`` sync are dropped; a ``FF`` whose 7 bytes fail the checksum is
        kept in ``bad`` and the search goes on from the byte after it.
        """
        buf = self._buffer
        while True:
            start = buf.find(SYNC)
            if start < 0:
                buf.clear()
                return None
            del buf[:start]
            if len(buf) < 7:
                return None
            candidate = bytes(buf[:7])
            if checksum(*candidate[1:6]) != candidate[6]:
                bad.append(candidate)
                del buf[:1]
                continue
            del buf[:7]
            return candidate

    def _reply(self, reply_cmd: int, what: str, request: bytes) -> int:
        """Wait for this address's ``00 reply_cmd`` frame; its data as one 16-bit value."""
        deadline = time.monotonic() + self.timeout
        bad: list[bytes] = []
        foreign: list[bytes] = []
        other: list[bytes] = []
        while True:
            got = self._pop_frame(bad)
            if got is not None:
                if got[1] != self.address:
                    foreign.append(got)
                elif got[2] != 0 or got[3] != reply_cmd:
                    other.append(got)  # a late reply, an acknowledgement: not this one
                else:
                    return (got[4] << 8) | got[5]
                continue
            if not time.monotonic() < deadline:
                raise self._failure(what, request, bad, foreign, other)
            self._read_some()

    def _failure(self, what, request, bad, foreign, other) -> DeviceError:
        head = f"{self.name}: {what} ({_hex(request)})"
        if bad:
            b = bad[-1]
            return DeviceProtocolError(
                f"{head}: bad checksum in the reply {_hex(b)} (expected {checksum(*b[1:6]):02X}); "
                "check the baud rate and the cable"
            )
        if foreign:
            addresses = ", ".join(str(a) for a in sorted({f[1] for f in foreign}))
            return DeviceProtocolError(
                f"{head}: replies came from address {addresses}, not {self.address}; "
                "set the head's address (--ptu-address)"
            )
        if self._buffer:
            return DeviceProtocolError(
                f"{head}: short frame, {len(self._buffer)} of 7 bytes "
                f"({_hex(bytes(self._buffer))}) within {self.timeout:g} s; check the baud rate"
            )
        if other:
            return DeviceProtocolError(
                f"{head}: unexpected reply {_hex(other[-1])}; check that the head answers "
                "Pelco-D position queries"
            )
        return DeviceTimeout(
            f"{head}: no reply within {self.timeout:g} s; check the cable, the baud rate "
            "(Pelco-D heads often use 2400), the address and that the head answers position "
            "queries"
        )

    def _resync(self) -> None:
        """After a failed exchange: drop what arrives until the line is quiet (late frames)."""
        self._discard_input()
        deadline = time.monotonic() + self.timeout
        quiet_from = time.monotonic()
        while time.monotonic() < deadline and time.monotonic() - quiet_from < RESYNC_QUIET:
            chunk = read_bytes(self.port, self.name, 0)  # no wait: only what has arrived
            if chunk:
                quiet_from = time.monotonic()
            else:
                time.sleep(0.01)
        self._buffer.clear()
        self._unsynced = False

    def query(self, cmd2: int, reply_cmd: int, what: str) -> int:
        """Send the query ``00 cmd2`` and return the 16-bit value of its ``00 reply_cmd`` reply.

        Raises
        ------
        DeviceTimeout
            No reply within the timeout.
        DeviceProtocolError
            Only a bad checksum, another address's frames, a short frame or another reply
            arrived; the next query first waits for the line to be quiet.
        """
        if self._unsynced:
            self._resync()
        self._discard_input()  # an acknowledgement of a set command, a late reply
        request = frame(self.address, 0x00, cmd2)
        self.send(0x00, cmd2)
        try:
            return self._reply(reply_cmd, what, request)
        except (DeviceTimeout, DeviceProtocolError):
            self._unsynced = True
            raise

    # -- angles ----------------------------------------------------------------------------
    def initialize(self) -> PelcoLimits:
        """Check that the head answers (one pan and one tilt query); returns :attr:`limits`."""
        self.position_raw()
        return self.limits

    def position_raw(self) -> tuple[int, int]:
        """The head's pan and tilt, hundredths of a degree (0-35999); a tilt reported in signed
        16-bit (above 35999: below zero) is brought into 0-35999."""
        pan = self.query(QUERY_PAN, PAN_REPLY, "pan position query")
        if pan >= FULL_TURN:
            self._unsynced = True
            raise DeviceProtocolError(
                f"{self.name}: the head reported pan {pan}, outside 0-35999 hundredths "
                "of a degree; check that it speaks Pelco-D"
            )
        tilt = self.query(QUERY_TILT, TILT_REPLY, "tilt position query")
        return pan, self._tilt_from_wire(tilt)

    def _tilt_from_wire(self, value: int) -> int:
        """A reported tilt as 0-35999: up to 35999 as it is (both encodings agree on 0-18000,
        and only "wrap" sends 18001-35999 within +-180 degrees); above, the negative signed
        16-bit value it can only be (noted once if the head is set to "wrap")."""
        if value < FULL_TURN:
            return value
        signed = value - WORD
        if not self.signed_tilt_seen and self.tilt_encoding == "wrap":
            self.notes.append(
                f"the head reported tilt {value} ({_hex(bytes((value >> 8, value & 0xFF)))}), "
                f"read as signed 16-bit {signed} hundredths of a degree; if tilts below zero "
                "go astray, set tilt_encoding='signed' (--ptu-tilt-encoding signed)"
            )
        self.signed_tilt_seen = True
        return signed % FULL_TURN

    def _tilt_to_wire(self, tilt_raw: int) -> int:
        """A raw tilt 0-35999 as sent: as it is ("wrap"), or signed 16-bit ("signed")."""
        if self.tilt_encoding == "signed":
            return _signed(tilt_raw) % WORD
        return tilt_raw

    def _encoding_hint(self) -> str:
        if self.signed_tilt_seen and self.tilt_encoding == "wrap":
            return (
                "; the head reports its tilt in signed 16-bit: try tilt_encoding='signed' "
                "(--ptu-tilt-encoding signed)"
            )
        return ""

    def raw_to_angles(self, pan_raw: int, tilt_raw: int) -> tuple[float, float]:
        """Raw positions (hundredths, 0-35999) to unit angles (rad): pan signed, tilt up."""
        tilt = self.tilt_sign * _signed(tilt_raw - self.tilt_zero)
        return math.radians(_signed(pan_raw) / 100), math.radians(tilt / 100)

    def _tilt_raw(self, tilt_hundredths: int) -> int:
        return (self.tilt_zero + self.tilt_sign * tilt_hundredths) % FULL_TURN

    def position(self) -> tuple[float, float]:
        """Current pan and tilt, unit angles in radians (pan in (-pi, pi], tilt up positive)."""
        return self.raw_to_angles(*self.position_raw())

    def to_hundredths(self, pan: float, tilt: float) -> tuple[int, int]:
        """Unit angles (rad) to whole hundredths of a degree (not wrapped).

        Raises
        ------
        PTULimitError
            An angle is not finite, or outside the head's limits.
        """
        lim = self.limits
        counts = []
        for axis, angle, (lo, hi) in (
            ("pan", pan, lim.pan_range()),
            ("tilt", tilt, lim.tilt_range()),
        ):
            value = math.degrees(angle) * 100 if math.isfinite(angle) else math.nan
            ok = math.isfinite(value) and (lim.pan_ok if axis == "pan" else lim.tilt_ok)(
                round(value)
            )
            if not ok:
                raise PTULimitError(
                    f"{self.name}: {axis} {math.degrees(angle):.3f} deg is outside the head's "
                    f"limits [{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] deg; aim inside them"
                )
            counts.append(round(value))
        return counts[0], counts[1]

    def move_to(self, pan: float, tilt: float, *, wait: bool = True) -> tuple[float, float]:
        """Move to absolute unit angles and (by default) wait until the head reports them.

        Parameters
        ----------
        pan, tilt : float
            Radians (tilt up positive); pan may be any finite angle on a continuous head.
        wait : bool
            Poll the position queries until both axes are within :attr:`tolerance` of the
            target, up to :attr:`move_timeout`.

        Returns
        -------
        (float, float)
            Where the head reports it arrived (see :meth:`wait_for`; without ``wait``, the
            commanded angles rounded to hundredths of a degree), radians, pan unwrapped as
            asked.

        Raises
        ------
        PTULimitError
            The target is outside the limits or not finite (nothing is sent), or the head
            stopped short of it (see :meth:`wait_for`).
        DeviceTimeout
            The head is not at the target within ``move_timeout``.
        """
        pc, tc = self.to_hundredths(pan, tilt)
        pan_raw, tilt_raw = pc % FULL_TURN, self._tilt_raw(tc)
        if self._unsynced:
            self._resync()
        self.send(0x00, PAN_ABSOLUTE, pan_raw >> 8, pan_raw & 0xFF)
        tilt_wire = self._tilt_to_wire(tilt_raw)
        self.send(0x00, TILT_ABSOLUTE, tilt_wire >> 8, tilt_wire & 0xFF)
        if wait:
            at = self.wait_for(pan_raw, tilt_raw)
            # where the head says it is (within tolerance of the target, or at the step
            # nearest it), pan unwrapped as asked
            pc += _signed(at[0] - pan_raw)
            tc += self.tilt_sign * _signed(at[1] - tilt_raw)
        return math.radians(pc / 100), math.radians(tc / 100)

    def _near(self, a: int, b: int) -> bool:
        return abs(_signed(a - b)) <= self.tolerance

    def wait_for(self, pan_raw: int, tilt_raw: int) -> tuple[int, int]:
        """Poll the position until it is the target (raw hundredths), up to ``move_timeout``;
        returns the position last reported.

        The head has arrived when both axes are within :attr:`tolerance` of the target, or when
        it has stopped (the same position reported for ``SETTLE_TIME`` seconds) within
        ``SETTLE_NEAR`` hundredths of it (a head whose steps do not fall on every hundredth).
        A head that has been seen moving (in this move or an earlier one) and then reports the
        same position away from the target for ``STALL_TIME`` seconds has stopped short of it:
        :class:`~asbuilt.drivers.ptu.PTULimitError` (a head never seen moving, which may not
        take absolute moves at all, waits out ``move_timeout`` instead).
        A reply that cannot be read (noise: bad checksum, short frame) is queried again, up to
        ``POLL_RETRIES`` in a row. Silence (:class:`DeviceTimeout`: the reference does not say
        that a head answers position queries while it moves, and some do not) is queried
        again until ``move_timeout``, which then ends the wait with a timeout saying so.
        """
        deadline = time.monotonic() + self.move_timeout
        failures = 0
        at = None
        last, since = None, 0.0  # the last position reported, and since when unchanged
        while True:
            try:
                at = self.position_raw()
                failures = 0
            except DeviceProtocolError:
                failures += 1
                if failures > POLL_RETRIES or time.monotonic() > deadline:
                    raise
                continue
            except DeviceTimeout as exc:  # busy moving, maybe: ask again until the move's limit
                if time.monotonic() > deadline:
                    where = "" if at is None else f" (last reported pan {at[0]} / tilt {at[1]})"
                    raise DeviceTimeout(
                        f"{self.name}: the head did not answer position queries up to "
                        f"{self.move_timeout:g} s after the move to pan {pan_raw} / tilt "
                        f"{tilt_raw} hundredths of a degree{where}; last: {exc}"
                    ) from exc
                continue
            if self._near(at[0], pan_raw) and self._near(at[1], tilt_raw):
                return at
            now = time.monotonic()
            if at != last:
                self._seen_moving = self._seen_moving or last is not None
                last, since = at, now
            elif (
                now - since >= SETTLE_TIME
                and abs(_signed(at[0] - pan_raw)) <= SETTLE_NEAR
                and abs(_signed(at[1] - tilt_raw)) <= SETTLE_NEAR
            ):
                return at
            elif self._seen_moving and now - since >= STALL_TIME:
                raise PTULimitError(
                    f"{self.name}: the head stopped at pan {at[0]} / tilt {at[1]} hundredths of a "
                    f"degree, short of the target {pan_raw} / {tilt_raw} (a mechanical limit or "
                    "an obstruction); aim inside the head's reach" + self._encoding_hint()
                )
            if time.monotonic() > deadline:
                raise DeviceTimeout(
                    f"{self.name}: the head reports pan {at[0]} / tilt {at[1]} hundredths of a "
                    f"degree, not the target {pan_raw} / {tilt_raw}, {self.move_timeout:g} s "
                    "after the move; check the head, its limits and the move timeout"
                    + self._encoding_hint()
                )
            if self.poll_interval:
                time.sleep(self.poll_interval)

    def stop(self) -> None:
        """``00 00 00 00``: stop any motion."""
        self.send(0x00, 0x00)
