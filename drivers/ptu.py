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
from dataclasses import dataclass

from asbuilt.errors import DeviceError, DeviceProtocolError

from .transport import LineChannel, open_port

__all__ = [
    "PTUError",
    "PTUCommandError",
    "PTULimitError",
    "PTULimits",
    "PanTiltUnit",
]

_ARCSEC = math.pi / (180.0 * 3600.0)  # radians per second of arc
_NUMBER = re.compile(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")
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
        self.limits: PTULimits | None = None

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
            Send ``FT``/``ED`` and read resolution and limits.
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
    def command(self, text: str, *, timeout: float | None = None) -> str:
        """Send one command and return the reply's payload (text after ``*``, maybe empty).

        Parameters
        ----------
        text : str
            The command without delimiter, e.g. ``"PP100"``.
        timeout : float, optional
            Seconds to wait for the reply.

        Raises
        ------
        PTUCommandError
            ``! <message>``.
        PTULimitError
            ``!P`` / ``!T`` arrived before the reply (the reply itself is consumed first).
        DeviceTimeout, DeviceProtocolError
            Silence or a reply the protocol does not allow.
        """
        cmd = text.strip()
        self.channel.write(cmd + " ")
        notices: list[str] = []
        while True:
            line = self.channel.read_line(timeout, expecting=f"reply to {cmd!r}")
            line = self._strip_echo(line, cmd)
            if not line:
                continue  # the echo came on its own line
            compact = line.replace(" ", "")
            if _LIMIT_NOTICE.match(compact):
                notices.extend(ch for ch in compact.upper() if ch in "PT")
                continue
            if compact.endswith("*") and _LIMIT_NOTICE.match(compact[:-1]):
                notices.extend(ch for ch in compact[:-1].upper() if ch in "PT")
                line = "*"  # e.g. the reset sweep's "!T!T!P!P*"
            if line.startswith("*"):
                if notices and cmd.upper() not in ("R",):
                    axes = " and ".join(sorted({"pan" if n == "P" else "tilt" for n in notices}))
                    raise PTULimitError(
                        f"{self.channel.name}: the {axes} axis hit its limit during {cmd!r}; "
                        "aim inside the limits"
                    )
                return line[1:].strip()
            if line.startswith("!"):
                raise PTUCommandError(
                    f"{self.channel.name}: {cmd!r} refused: {line[1:].strip() or 'error'}"
                )
            raise DeviceProtocolError(
                f"{self.channel.name}: unexpected reply {line!r} to {cmd!r} (neither '*' nor "
                "'!'); check the baud rate and that this is a FLIR/DP ASCII unit"
            )

    @staticmethod
    def _strip_echo(line: str, cmd: str) -> str:
        if line.upper().startswith(cmd.upper()) and cmd:
            return line[len(cmd) :].strip()
        return line

    def query_number(self, text: str) -> float:
        """Send a query (``PP``, ``PR``...) and parse the number of its reply (terse or verbose)."""
        payload = self.command(text)
        match = _NUMBER.search(payload)
        if match is None:
            raise DeviceProtocolError(
                f"{self.channel.name}: reply {payload!r} to {text!r} holds no number"
            )
        return float(match.group())

    def initialize(self) -> PTULimits:
        """Terse feedback, echo off, immediate mode, then read resolution and limits.

        Returns
        -------
        PTULimits
            Also kept as :attr:`limits`.
        """
        self.channel.discard_input()
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
        return self.limits

    def _need_limits(self) -> PTULimits:
        if self.limits is None:
            self.initialize()
        return self.limits

    def to_counts(self, pan: float, tilt: float) -> tuple[int, int]:
        """Unit angles (rad) to the nearest counts."""
        lim = self._need_limits()
        return (
            int(round(pan / (lim.pan_resolution * _ARCSEC))),
            int(round(tilt / (lim.tilt_resolution * _ARCSEC))),
        )

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
            The target is outside the limits read from the unit (nothing is sent), or the unit
            reported a limit hit.
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
        self.command(f"PP{pc}")
        self.command(f"TP{tc}")
        if wait:
            self.await_completion()
        return self.to_angles(pc, tc)

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
