"""Driver for FLIR / Directed Perception pan-tilt units speaking the ASCII protocol (PTU-D46 family).

Protocol (PTU-D46 User's Manual v2.14, section 4; the ROS driver ros-drivers/flir_ptu): a command
is letters, an optional signed integer and a space delimiter; a reply line ends with CR LF and is
``*`` (done), ``* <value>`` (a query's answer; verbose feedback adds words around the value) or
``! <message>`` (refused). A move that runs into a limit sends ``!P`` or ``!T`` on its own.

The driver sets terse feedback (``FT``) and echo off (``ED``) first, then *reads* the resolution
(``PR``/``TR``, seconds of arc per position) and the limits (``PN``/``PX``/``TN``/``TX``) from the
unit instead of assuming the D46's values. It copes with echo still on and with verbose replies.
Angles here are the unit's own (counts times resolution), in radians; the kinematic chain
(:mod:`asbuilt.drivers.kinematics`) turns them into directions in the world.
"""

from __future__ import annotations

import math
import re
import time
from dataclasses import dataclass

from asbuilt.errors import DeviceError, DeviceProtocolError, DeviceTimeout

from .transport import LineChannel, open_port

__all__ = [
    "PTUError",
    "PTUCommandError",
    "PTULimitError",
    "PTULimits",
    "PanTiltUnit",
    "PAN_TILT_PROTOCOLS",
    "open_pan_tilt_unit",
]

_ARCSEC = math.pi / (180.0 * 3600.0)  # radians per second of arc
_NUMBER = re.compile(r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?")
#: Lines that are no reply (neither ``*`` nor ``!``) one command's reply may follow, at most.
MAX_UNSOLICITED = 20
_LIMIT_NOTICE = re.compile(r"^(?:!\s*[PT])+$", re.IGNORECASE)


class PTUError(DeviceError):
    """The pan-tilt unit failed or refused a command."""


class PTUCommandError(PTUError):
    """The unit answered ``! <message>`` (illegal command, position out of range...)."""


class PTULimitError(PTUError):
    """A move was outside the unit's limits, or the unit reported ``!P`` / ``!T`` (hit a limit)."""


@dataclass(frozen=True)
class PTULimits:
    """Position limits read from the unit, in counts (positions), and the resolutions.

    Attributes
    ----------
    pan_min, pan_max, tilt_min, tilt_max : int
        Counts (``PN``, ``PX``, ``TN``, ``TX``).
    pan_resolution, tilt_resolution : float
        Seconds of arc per count (``PR``, ``TR``).
    """

    pan_min: int
    pan_max: int
    tilt_min: int
    tilt_max: int
    pan_resolution: float
    tilt_resolution: float

    def pan_range(self) -> tuple[float, float]:
        """Pan limits in radians (unit angles)."""
        k = self.pan_resolution * _ARCSEC
        return self.pan_min * k, self.pan_max * k

    def tilt_range(self) -> tuple[float, float]:
        """Tilt limits in radians (unit angles)."""
        k = self.tilt_resolution * _ARCSEC
        return self.tilt_min * k, self.tilt_max * k

    def ranges_missed(self, angles) -> str:
        """The unit's ranges that some of ``angles`` fall outside, worded for a message.

        Parameters
        ----------
        angles : iterable of (float, float)
            Pan and tilt, radians (unit angles).

        Returns
        -------
        str
            E.g. ``"tilt range [-46.646, 31.063] deg"`` (pan and tilt joined with "and"); empty
            when every angle rounds to a count inside the limits (as :meth:`PanTiltUnit.move_to`
            checks them).
        """
        angles = list(angles)
        missed = []
        for axis, i, (lo, hi), resolution, first, last in (
            ("pan", 0, self.pan_range(), self.pan_resolution, self.pan_min, self.pan_max),
            ("tilt", 1, self.tilt_range(), self.tilt_resolution, self.tilt_min, self.tilt_max),
        ):
            counts = [a[i] / (resolution * _ARCSEC) for a in angles]  # as the unit checks them
            if not all(math.isfinite(c) and first <= round(c) <= last for c in counts):
                missed.append(f"{axis} range [{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] deg")
        return " and ".join(missed)


class PanTiltUnit:
    """A FLIR/DP pan-tilt unit on a serial port.

    Parameters
    ----------
    channel : LineChannel
        The open line channel; use :meth:`open` to build one from a URL.
    move_timeout : float
        Seconds to wait for a move to complete (``A``) before :class:`DeviceTimeout`.

    Examples
    --------
    >>> with PanTiltUnit.open("sim-ptu://demo") as ptu:     # doctest: +SKIP
    ...     ptu.move_to(0.1, -0.05)
    ...     pan, tilt = ptu.position()
    """

    def __init__(self, channel: LineChannel, *, move_timeout: float = 30.0):
        self.channel = channel
        self.move_timeout = float(move_timeout)
        if not (math.isfinite(self.move_timeout) and self.move_timeout > 0):
            raise ValueError(
                f"move_timeout must be a finite number of seconds > 0, got {move_timeout!r}"
            )
        self.limits: PTULimits | None = None
        self._notices: list[str] = []  # limit notices since the current move was commanded
        self._unsynced = False  # a reply may be owed (timeout): resynchronise first
        self._verify = False  # check the head's position after the next move
        #: Pan and tilt speeds read at opening (``PS`` / ``TS``, positions/s; None: refused).
        self.speeds: tuple[float | None, float | None] = (None, None)
        self._at: tuple[int, int] | None = None  # the last target acknowledged, counts
        #: Lines the unit sent that are no reply (a power-up banner...), skipped, oldest first;
        #: whoever keeps a log takes them (the scan session notes them in its journal).
        self.unsolicited: list[str] = []

    @classmethod
    def open(
        cls,
        url: str,
        *,
        baudrate: int = 9600,
        timeout: float = 2.0,
        move_timeout: float = 30.0,
        initialize: bool = True,
    ) -> PanTiltUnit:
        """Open the unit at ``url`` (8N1) and, by default, :meth:`initialize` it.

        Parameters
        ----------
        url : str
            Device path or pyserial URL.
        baudrate : int
            Host port speed (unit default 9600).
        timeout : float
            Seconds to wait for a reply to an ordinary command.
        move_timeout : float
            Seconds to wait for a move to finish.
        initialize : bool
            Send ``FT``/``ED`` and read resolution, limits and speeds.
        """
        port = open_port(url, baudrate=baudrate, write_timeout=timeout)
        unit = cls(LineChannel(port, f"pan-tilt unit on {url}", timeout), move_timeout=move_timeout)
        if initialize:
            try:
                unit.initialize()
            except BaseException:
                unit.close()
                raise
        return unit

    # -- context manager -------------------------------------------------------------------
    def __enter__(self) -> PanTiltUnit:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the port."""
        self.channel.close()

    # -- protocol --------------------------------------------------------------------------
    def command(self, text: str, *, timeout: float | None = None, query: bool = False) -> str:
        """Send one command and return the reply's payload (text after ``*``, maybe empty).

        Parameters
        ----------
        text : str
            The command without delimiter, e.g. ``"PP100"``.
        timeout : float, optional
            Seconds to wait for the reply.
        query : bool
            The reply must carry a value: a bare ``*`` is a late reply to an earlier command
            and is skipped.

        Raises
        ------
        PTUCommandError
            ``! <message>``.
        PTULimitError
            ``A`` (await) ended with ``!P`` / ``!T`` received since the move was commanded (with
            or without the ``*``; after a notice the ``*`` is awaited for the ordinary reply
            timeout only).
        DeviceTimeout, DeviceProtocolError
            Silence or a reply the protocol does not allow; the next command first
            resynchronises (:meth:`_sync`) and the next move checks where the head is.
        """
        cmd = text.strip()
        if self._unsynced:
            self._sync()
        self._collect_pending()
        self.channel.write(cmd + " ")
        try:
            return self._reply(cmd, timeout, query)
        except (DeviceTimeout, DeviceProtocolError):
            self._unsynced = True
            self._verify = True
            raise

    def _reply(self, cmd: str, timeout: float | None, query: bool) -> str:
        upper = cmd.upper()
        notice_seen = False
        skipped = 0
        while True:
            wait = timeout
            if notice_seen:  # the notice may have replaced the '*' (it came "on its own")
                wait = min(self.channel.timeout, self.move_timeout if timeout is None else timeout)
            try:
                line = self.channel.read_line(wait, expecting=f"reply to {cmd!r}")
            except DeviceTimeout:
                if notice_seen:
                    self._unsynced = self._verify = True  # a '*' may still come
                    raise self._limit_error(cmd) from None
                raise
            line = self._strip_echo(line, cmd)
            if not line:
                continue  # the echo came on its own line
            if self._take_notice(line):
                notice_seen = upper == "A"
                continue
            compact = line.replace(" ", "")
            if compact.endswith("*") and _LIMIT_NOTICE.match(compact[:-1]):
                self._take_notice(compact[:-1])
                line = "*"  # e.g. the reset sweep's "!T!T!P!P*"
            if line.startswith("*"):
                payload = line[1:].strip()
                if query and not payload:
                    continue  # a late '*' of an earlier command, not this query's answer
                if upper == "R":
                    self._notices.clear()
                elif upper == "A" and self._notices:
                    raise self._limit_error(cmd)
                return payload
            if line.startswith("!"):
                raise PTUCommandError(
                    f"{self.channel.name}: {cmd!r} refused: {line[1:].strip() or 'error'}"
                )
            # Not a reply (every reply starts with '*' or '!'): a power-up banner or other
            # text the unit sent on its own. Skipped and kept (:attr:`unsolicited`); a stream
            # of such lines is no unit speaking this protocol.
            skipped += 1
            if skipped > MAX_UNSOLICITED:
                raise DeviceProtocolError(
                    f"{self.channel.name}: unexpected reply {line!r} to {cmd!r} (neither '*' "
                    f"nor '!', after {MAX_UNSOLICITED} such lines); check the baud rate and "
                    "that this is a FLIR/DP ASCII unit"
                )
            self.unsolicited.append(line)

    def _take_notice(self, line: str) -> bool:
        """Keep a limit notice (``!P``, ``!T``, ``!P!T``...) for the move; False if ``line`` is none."""
        compact = line.replace(" ", "")
        if not _LIMIT_NOTICE.match(compact):
            return False
        self._notices.extend(ch for ch in compact.upper() if ch in "PT")
        return True

    def _limit_error(self, cmd: str) -> PTULimitError:
        axes = " and ".join(sorted({"pan" if n == "P" else "tilt" for n in self._notices}))
        self._notices.clear()
        return PTULimitError(
            f"{self.channel.name}: the {axes} axis hit its limit during {cmd!r}; "
            "aim inside the limits"
        )

    def _collect_pending(self) -> None:
        """Read what arrived unasked: limit notices are kept, late replies dropped."""
        for line in self.channel.pending_lines():
            if self._take_notice(line):
                continue
            if line.startswith(("*", "!")):
                self._verify = True  # a reply nobody waited for: check the next move
            else:
                self.unsolicited.append(line)  # no reply at all (a banner): kept, skipped

    def _sync(self) -> None:
        """Get back in step with the unit: a lone delimiter ends any half-written command (its
        reply, if any, is skipped), then the ``PR`` query's answer marks the point where every
        earlier reply has been read (late ``*`` and ``!`` lines before it are dropped).

        Raises
        ------
        DeviceTimeout, DeviceProtocolError
            No answer to ``PR``; bytes that are not ASCII.
        """
        self._unsynced = False
        self.channel.discard_input()
        self.channel.write(" PR ")
        known = self.limits.pan_resolution if self.limits is not None else None
        try:
            while True:
                line = self._strip_echo(self.channel.read_line(expecting="reply to 'PR'"), "PR")
                if self._take_notice(line) or not line.startswith("*"):
                    continue  # a notice, or the reply to a half-written command
                match = _NUMBER.search(line)
                if match is None:
                    continue  # a late '*'
                value = float(match.group())
                if known is None or math.isclose(value, known, rel_tol=1e-6):
                    return
        except (DeviceTimeout, DeviceProtocolError):
            self._unsynced = True
            raise

    @staticmethod
    def _strip_echo(line: str, cmd: str) -> str:
        if line.upper().startswith(cmd.upper()) and cmd:
            return line[len(cmd) :].strip()
        return line

    def query_number(self, text: str) -> float:
        """Send a query (``PP``, ``PR``...) and parse the number of its reply (terse or verbose)."""
        payload = self.command(text, query=True)
        match = _NUMBER.search(payload)
        if match is None:
            raise DeviceProtocolError(
                f"{self.channel.name}: reply {payload!r} to {text!r} holds no number"
            )
        return float(match.group())

    def initialize(self) -> PTULimits:
        """Resynchronise (:meth:`_sync`: a lone delimiter ends a command a killed program left
        half-written), then terse feedback, echo off, immediate mode, resolution and limits, and
        the axes' speeds (``PS`` / ``TS``, for the wait of a position command: see
        :meth:`_move_wait`; a unit refusing them keeps the reply timeout).

        Returns
        -------
        PTULimits
            Also kept as :attr:`limits`.
        """
        self._notices.clear()
        self._sync()
        self.command("FT")
        self.command("ED")
        self.command("I")
        self.limits = PTULimits(
            pan_min=int(round(self.query_number("PN"))),
            pan_max=int(round(self.query_number("PX"))),
            tilt_min=int(round(self.query_number("TN"))),
            tilt_max=int(round(self.query_number("TX"))),
            pan_resolution=self.query_number("PR"),
            tilt_resolution=self.query_number("TR"),
        )
        if self.limits.pan_resolution <= 0 or self.limits.tilt_resolution <= 0:
            raise DeviceProtocolError(
                f"{self.channel.name}: resolution must be positive, got "
                f"{self.limits.pan_resolution} / {self.limits.tilt_resolution} arcsec"
            )
        self.speeds = (self._speed("PS"), self._speed("TS"))
        self._at = None
        return self.limits

    def _speed(self, query: str) -> float | None:
        """An axis's speed (``PS`` / ``TS``, positions/s), or None if the unit refuses it."""
        try:
            speed = self.query_number(query)
        except PTUCommandError:
            return None
        return speed if math.isfinite(speed) and speed > 0 else None

    def _move_wait(self, axis: int, target: int) -> float | None:
        """Seconds to wait for the ``*`` of a ``PP`` / ``TP`` to ``target`` counts.

        A unit may acknowledge a position command only when the move has ended: the wait is
        the reply timeout plus twice the travel time at the speed read at opening (``PS`` /
        ``TS``; twice, for the acceleration ramps), from the last target (from the farthest
        limit before the first move), at most ``move_timeout``. None (the reply timeout) when
        the speed is unknown.
        """
        speed = self.speeds[axis]
        if speed is None or self.limits is None:
            return None
        lim = self.limits
        lo, hi = (lim.pan_min, lim.pan_max) if axis == 0 else (lim.tilt_min, lim.tilt_max)
        distance = (
            abs(target - self._at[axis]) if self._at is not None else max(target - lo, hi - target)
        )
        wait = self.channel.timeout + 2.0 * distance / speed
        return max(self.channel.timeout, min(wait, self.move_timeout))

    def limit_hit_after_move(self) -> bool:
        """Whether ``!P`` / ``!T`` arrived after the last move's ``*`` (read without waiting).

        A notice comes when a move runs into a limit, so a shot taken at that move is not
        where it was aimed; the next move then checks the head's position.
        """
        self._collect_pending()
        hit = bool(self._notices)
        if hit:
            self._notices.clear()
            self._verify = True
        return hit

    def _need_limits(self) -> PTULimits:
        if self.limits is None:
            self.initialize()
        return self.limits

    def to_counts(self, pan: float, tilt: float) -> tuple[int, int]:
        """Unit angles (rad) to the nearest counts.

        Raises
        ------
        PTULimitError
            An angle is not a finite number (``inf``, ``nan``) or too large to count.
        """
        lim = self._need_limits()
        counts = []
        for axis, angle, resolution, (lo, hi) in (
            ("pan", pan, lim.pan_resolution, lim.pan_range()),
            ("tilt", tilt, lim.tilt_resolution, lim.tilt_range()),
        ):
            value = angle / (resolution * _ARCSEC)
            if not math.isfinite(value):  # int() of it would be an OverflowError/ValueError
                raise PTULimitError(
                    f"{self.channel.name}: {axis} {math.degrees(angle):g} deg is not an angle "
                    f"inside the unit's limits [{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] "
                    "deg; aim inside them"
                )
            counts.append(int(round(value)))
        return counts[0], counts[1]

    def to_angles(self, pan_counts: int, tilt_counts: int) -> tuple[float, float]:
        """Counts to unit angles (rad)."""
        lim = self._need_limits()
        return (
            pan_counts * lim.pan_resolution * _ARCSEC,
            tilt_counts * lim.tilt_resolution * _ARCSEC,
        )

    def move_to(self, pan: float, tilt: float, *, wait: bool = True) -> tuple[float, float]:
        """Move to absolute unit angles and (by default) await completion.

        Parameters
        ----------
        pan, tilt : float
            Radians, the unit's own angles (zero and sign as the unit counts).
        wait : bool
            Send ``A`` and wait up to ``move_timeout`` for the move to finish.

        Returns
        -------
        (float, float)
            The commanded angles after rounding to whole counts, radians.

        Raises
        ------
        PTULimitError
            The target is outside the limits read from the unit or not a finite angle (nothing
            is sent), or the unit reported a limit hit.
        """
        lim = self._need_limits()
        pc, tc = self.to_counts(pan, tilt)
        if not lim.pan_min <= pc <= lim.pan_max:
            lo, hi = lim.pan_range()
            raise PTULimitError(
                f"{self.channel.name}: pan {math.degrees(pan):.3f} deg is outside the unit's "
                f"limits [{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] deg; aim inside them"
            )
        if not lim.tilt_min <= tc <= lim.tilt_max:
            lo, hi = lim.tilt_range()
            raise PTULimitError(
                f"{self.channel.name}: tilt {math.degrees(tilt):.3f} deg is outside the unit's "
                f"limits [{math.degrees(lo):.3f}, {math.degrees(hi):.3f}] deg; aim inside them"
            )
        self.limit_hit_after_move()  # a notice now is the previous move's, not this one's
        pan_wait, tilt_wait = self._move_wait(0, pc), self._move_wait(1, tc)
        self._at = None  # until both are acknowledged: where the head is is not known
        self.command(f"PP{pc}", timeout=pan_wait)
        self.command(f"TP{tc}", timeout=tilt_wait)
        self._at = (pc, tc)
        if wait:
            self.await_completion()
            if self._verify:
                self._check_position(pc, tc)
        return self.to_angles(pc, tc)

    def _check_position(self, pan_counts: int, tilt_counts: int) -> None:
        """After a resynchronisation: query the position until the head is at the target.

        A late ``*`` can end an ``A`` early; the position queries (``PP``, ``TP``) say whether
        the move is really over, and ``A`` is sent again until it is, up to ``move_timeout``.

        Raises
        ------
        DeviceTimeout
            The head is not at the target within ``move_timeout``.
        """
        deadline = time.monotonic() + self.move_timeout
        while True:
            at = self.position_counts()
            # Within a count: the manual does not promise that the position reported equals
            # the one commanded to the count (a stepper may settle a microstep off).
            if abs(at[0] - pan_counts) <= 1 and abs(at[1] - tilt_counts) <= 1:
                self._verify = False
                return
            if time.monotonic() > deadline:
                self._verify = True
                raise DeviceTimeout(
                    f"{self.channel.name}: the head is at {at[0]} / {at[1]} counts, not at the "
                    f"target {pan_counts} / {tilt_counts}, {self.move_timeout:g} s after the "
                    "move; check the unit and the move timeout"
                )
            self.await_completion()

    def await_completion(self) -> None:
        """Send ``A`` and wait up to ``move_timeout`` for the ``*`` that ends the move."""
        self.command("A", timeout=self.move_timeout)

    def position_counts(self) -> tuple[int, int]:
        """Current pan and tilt in counts (``PP`` and ``TP`` queries)."""
        return int(round(self.query_number("PP"))), int(round(self.query_number("TP")))

    def position(self) -> tuple[float, float]:
        """Current pan and tilt, unit angles in radians."""
        return self.to_angles(*self.position_counts())

    def reset(self, timeout: float = 120.0) -> None:
        """``R``: the unit's calibration sweep (it answers ``!T!T!P!P*`` when done).

        Parameters
        ----------
        timeout : float
            Seconds to wait for the sweep to end.
        """
        self.command("R", timeout=timeout)

    def set_limit_enforcement(self, enabled: bool) -> None:
        """``LE`` (enabled) or ``LD`` (disabled) limit enforcement."""
        self.command("LE" if enabled else "LD")

    def version(self) -> str:
        """Firmware version text (``V``)."""
        return self.command("V")


#: Head protocols accepted by :func:`open_pan_tilt_unit` and ``asbuilt scan --ptu-protocol``.
PAN_TILT_PROTOCOLS = ("flir", "pelco-d")


def open_pan_tilt_unit(url: str, protocol: str = "flir", **options):
    """Open the pan-tilt head at ``url`` with the driver for ``protocol``.

    Parameters
    ----------
    url : str
        Device path or pyserial URL.
    protocol : {"flir", "pelco-d"}
        FLIR / Directed Perception ASCII (:class:`PanTiltUnit`) or Pelco-D
        (:class:`~asbuilt.drivers.pelco.PelcoD`).
    **options
        Passed to the driver's ``open`` (``baudrate``, ``timeout``, ``move_timeout``; Pelco-D
        also ``address``, ``tilt_sign``, ``tilt_zero``...).
    """
    if protocol == "flir":
        return PanTiltUnit.open(url, **options)
    if protocol == "pelco-d":
        from .pelco import PelcoD

        return PelcoD.open(url, **options)
    raise DeviceError(
        f"{url}: unknown pan-tilt protocol {protocol!r}; use one of "
        + ", ".join(PAN_TILT_PROTOCOLS)
    )
