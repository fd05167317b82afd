"""A shot and the device shooter: one range reading at one head position (:class:`Shot`, as
the journal records it) and the shooter that takes it with a real or simulated pan-tilt unit
and range finder, with retries (:class:`DeviceShooter`); a private helper of
:mod:`asbuilt.drivers.session`, which re-exports both."""

from __future__ import annotations

import math
from dataclasses import dataclass

from asbuilt.errors import DeviceProtocolError, DeviceTimeout

from .plan import DEFAULT_SETTINGS, SessionSettings


@dataclass(frozen=True)
class Shot:
    """One shot.

    Attributes
    ----------
    pan_req, tilt_req : float
        Requested unit angles, radians.
    pan, tilt : float
        Unit angles the head reached (whole counts), radians.
    range : float or None
        Raw range, metres; None when no valid return (see ``error``).
    error : str or None
        Last device error code (``"E255"``, ``"timeout"``, ``"limit"``, ``"refused"``...) when ``range`` is None.
    attempts : int
        Measurements tried.
    phase : str
        ``"raster"``, ``"fill"`` or ``"edge"``.
    """

    pan_req: float
    tilt_req: float
    pan: float
    tilt: float
    range: float | None
    error: str | None = None
    attempts: int = 1
    phase: str = "raster"

    def to_record(self, object_id: str, seq: int) -> dict:
        """The journal line for this shot."""
        return {
            "type": "shot",
            "object": object_id,
            "seq": seq,
            "phase": self.phase,
            "req": [self.pan_req, self.tilt_req],
            "pan": self.pan,
            "tilt": self.tilt,
            "range": self.range,
            "error": self.error,
            "attempts": self.attempts,
        }

    @classmethod
    def from_record(cls, rec: dict) -> Shot:
        """Inverse of :meth:`to_record`."""
        return cls(
            pan_req=float(rec["req"][0]),
            tilt_req=float(rec["req"][1]),
            pan=float(rec["pan"]),
            tilt=float(rec["tilt"]),
            range=None if rec.get("range") is None else float(rec["range"]),
            error=rec.get("error"),
            attempts=int(rec.get("attempts", 1)),
            phase=str(rec.get("phase", "raster")),
        )


class DeviceShooter:
    """Shoots with a real (or simulated) pan-tilt unit and range finder, with retries.

    Parameters
    ----------
    ptu : PanTiltUnit
    lrf : object with ``measure() -> float``
    settings : SessionSettings
    """

    def __init__(self, ptu, lrf, settings: SessionSettings = DEFAULT_SETTINGS):
        self.ptu = ptu
        self.lrf = lrf
        self.settings = settings
        self.lost_in_a_row = 0  # shots whose every attempt failed (not a miss)

    def __call__(self, pan: float, tilt: float, phase: str) -> Shot:
        from .ptu import PTUCommandError, PTULimitError
        from .rangefinder import (
            RangeFinderError,
            SignalTooStrong,
            SignalTooWeak,
            TooMuchBackgroundLight,
        )

        misses = (SignalTooWeak, SignalTooStrong, TooMuchBackgroundLight)

        try:
            pan_at, tilt_at = self._move(pan, tilt)
        except PTULimitError:
            return Shot(pan, tilt, pan, tilt, None, "limit", 0, phase)
        except PTUCommandError as exc:
            # The unit refused the move ('! <message>', which the manual allows for any
            # command, e.g. a limit it holds exclusive): this shot is skipped, the session goes
            # on; a unit refusing ``lost_after`` moves in a row ends it.
            self._lost(exc)
            return Shot(pan, tilt, pan, tilt, None, "refused", 0, phase)
        error = failure = None
        attempts = 0
        for _ in range(1 + self.settings.retries):
            attempts += 1
            try:
                value = float(self.lrf.measure())
            except RangeFinderError as exc:
                error = exc.code or type(exc).__name__
                # no return at this aim (a miss) vs a device that needs attention (a refused
                # command, an interface or temperature error, a code of unknown meaning)
                failure = None if isinstance(exc, misses) else exc
                continue
            except (DeviceTimeout, DeviceProtocolError) as exc:  # silence, wrong line settings
                error = "timeout" if isinstance(exc, DeviceTimeout) else "protocol"
                failure = exc
                continue
            if not math.isfinite(value) or value <= 0:
                error, failure = "range<=0", None
                continue
            self.lost_in_a_row = 0
            limit_hit = getattr(self.ptu, "limit_hit_after_move", None)
            if limit_hit is not None and limit_hit():  # '!P'/'!T' after the move's '*'
                return Shot(pan, tilt, pan_at, tilt_at, None, "limit", attempts, phase)
            return Shot(pan, tilt, pan_at, tilt_at, value, None, attempts, phase)
        if failure is None:
            self.lost_in_a_row = 0
        else:
            self._lost(failure)
        return Shot(pan, tilt, pan_at, tilt_at, None, error, attempts, phase)

    def _lost(self, failure: Exception) -> None:
        """Count a shot lost to ``failure``; raise its kind once ``lost_after`` are in a row."""
        self.lost_in_a_row += 1
        if self.lost_in_a_row >= self.settings.lost_after:
            message = (
                f"{failure} ({self.lost_in_a_row} shots in a row); then continue with "
                "asbuilt scan --resume"
            )
            code = getattr(failure, "code", None)
            raise type(failure)(message, code=code) if code else type(failure)(message)

    def _move(self, pan: float, tilt: float) -> tuple[float, float]:
        """Move with retries on timeouts; the last timeout propagates (the unit is lost)."""
        attempts = 0
        while True:
            attempts += 1
            try:
                return self.ptu.move_to(pan, tilt)
            except DeviceTimeout:
                if attempts > self.settings.retries:
                    raise
