"""What an estimated calibration cannot be trusted for: checks :func:`estimate_calibration` runs.

* :func:`check_reach`: a length parameter (the base position, a lever arm, the range offset)
  that the estimate moved farther than the farthest shot lies from the instrument. The targets
  are described in the scan frame, where the initial calibration stands the instrument; no
  set-up error moves it outside everything it measured, but a slip in a target's numbers (a
  wall's offset of 40 m for 4 m) does, as the estimate shifts the whole chain onto the wrong
  plane. Refused, naming the target whose shots lie farthest from it at the start.
* :func:`single_target_parameters`: parameters that one target's known pose alone determines
  (without it they would not be observable). An error in that target's pose goes into the
  parameter whole and leaves no residual: it cannot be detected from these shots, only by a
  second target that fixes the same direction.
* :func:`correlated_pairs`: pairs of estimated parameters whose correlation (from the
  covariance) is near +-1: the targets determine mainly a combination of the two (the pan zero
  and the horizontal beam misalignment add up for targets seen at one tilt), and the values
  apart are uncertain even when the chain as a whole is right.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from asbuilt.errors import CalibrationError

from .kinematics import Calibration, forward

__all__ = [
    "CORRELATION_LIMIT",
    "check_reach",
    "single_target_parameters",
    "correlated_pairs",
]

#: |correlation| at or above which two estimated parameters are reported as a pair.
CORRELATION_LIMIT = 0.95

#: Length parameter groups checked by :func:`check_reach` (vectors by their components).
_LENGTHS = ("base_position", "tilt_axis_offset", "laser_offset", "range_offset")


def _vector(cal: Calibration, group: str) -> np.ndarray:
    return np.atleast_1d(np.asarray(getattr(cal, group), float))


def check_reach(
    shots: Sequence, initial: Calibration, estimate: Calibration, target_rms0: dict
) -> None:
    """Refuse an estimate that moved a length parameter beyond the shots' reach.

    Parameters
    ----------
    shots : sequence of TargetShots
    initial, estimate : Calibration
    target_rms0 : dict of str to float
        Each target's RMS residual (m) with the initial calibration.

    Raises
    ------
    CalibrationError
        One line: the parameter, how far it moved, the reach, the target to check.
    """
    pts = np.concatenate([forward(initial, s.pan, s.tilt, s.rng) for s in shots])
    reach = float(np.linalg.norm(pts - np.asarray(initial.base_position), axis=1).max())
    for group in _LENGTHS:
        moved = float(np.linalg.norm(_vector(estimate, group) - _vector(initial, group)))
        if moved <= reach:
            continue
        worst = max(target_rms0, key=target_rms0.get)
        raise CalibrationError(
            f"the estimate moves {group} {moved:.3g} m from the initial calibration, farther "
            f"than any shot lies from the instrument ({reach:.3g} m): a target is mis-described "
            f"(or not in the scan frame); the shots at {worst!r} lie {target_rms0[worst]:.3g} m "
            "(RMS) from it with the initial calibration: check its numbers"
        )


def _pose_unknown(target):
    """``target`` with its pose forgotten (a plane or sphere), or None (a point: no shape)."""
    from .calibration import PlaneTarget, SphereTarget

    if isinstance(target, PlaneTarget):
        return None if target.normal is None else PlaneTarget()
    if isinstance(target, SphereTarget):
        return None if target.center is None else SphereTarget(target.radius)
    return "drop"


def single_target_parameters(
    shots: Sequence, calibration: Calibration, free: Sequence[str], min_independence: float
) -> dict[str, str]:
    """Free parameters that one target's known pose alone determines: name -> target.

    Leave-one-out on observability: each target of known pose in turn is given an unknown
    pose (a point target is left out), and the parameters :func:`observable_parameters` then
    no longer finds among ``free`` rest on that target alone.
    """
    from .calibration import TargetShots, observable_parameters

    out: dict[str, str] = {}
    for i, s in enumerate(shots):
        other = _pose_unknown(s.target)
        if other is None:
            continue
        rest = [x for j, x in enumerate(shots) if j != i]
        if not isinstance(other, str):
            rest.insert(i, TargetShots(s.name, other, s.pan, s.tilt, s.rng))
        if sum(len(x.pan) for x in rest) == 0:
            continue
        kept, _ = observable_parameters(rest, calibration, free, min_independence)
        for name in free:
            if name not in kept:
                out.setdefault(name, s.name)
    return out


def correlated_pairs(
    names: Sequence[str], cov: np.ndarray, limit: float = CORRELATION_LIMIT
) -> list[tuple[str, str, float]]:
    """Pairs of ``names`` (the first rows/columns of ``cov``) with |correlation| >= ``limit``,
    strongest first, as ``(a, b, correlation)``."""
    n = len(names)
    sub = np.asarray(cov, float)[:n, :n]
    sd = np.sqrt(np.clip(np.diag(sub), 0, None))
    pairs = []
    for i in range(n):
        for j in range(i + 1, n):
            if sd[i] > 0 and sd[j] > 0:
                rho = float(sub[i, j] / (sd[i] * sd[j]))
                if abs(rho) >= limit:
                    pairs.append((names[i], names[j], max(-1.0, min(1.0, rho))))
    return sorted(pairs, key=lambda p: -abs(p[2]))
