"""Concentric or eccentric: which reducer the scan shows where two pipe sizes meet in line.

An eccentric reducer (ASME B16.9) keeps one side of both pipes flush (flat on top at pump
suctions so no air pocket forms, flat on bottom in pipe racks so both pipes sit on the same
steel); its axes are parallel and offset sideways by ``R_large - R_small``. A concentric reducer
keeps them coaxial. The decision is made from the fitted axes at the joint:

* each pipe's fitted axis is evaluated at the joint (the midpoint of the two facing ends); the
  measured offset ``m`` is the part of the step between them perpendicular to the (regularised,
  common) run direction;
* each position's standard error is ``sqrt(se_center^2 + (s * se_axis)^2)`` (the fit's
  ``center`` standard error, and its axis error, radians, times the distance ``s`` from the
  fit's centre to the joint); ``tol = k_sigma * hypot(sigma_i, sigma_j) + ECCENTRIC_MARGIN``;
* **eccentric** when ``|m| > tol`` (clearly not coaxial) and ``| |m| - dR | <= tol`` (consistent
  with the radii; for a pipe without a catalog size the window grows by ``k_sigma`` standard
  errors of ``dR`` from its run's diameter estimate); otherwise concentric, as merging always
  did. Unknown standard errors never make an eccentric reducer;
* the imposed offset has length ``dR`` exactly, along ``m``; it is snapped to the vertical of the
  plane across the run (flat on top or bottom) when that moves it by no more than ``tol``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .contiguity import Joint

__all__ = ["ECCENTRIC_MARGIN", "Eccentricity", "eccentric_joints"]

#: Added to the ``k_sigma`` position window (metres): fitted axes carry a few millimetres of
#: bias a standard error does not describe (a sparse arc, a weld bead, out-of-round pipe).
ECCENTRIC_MARGIN = 0.003

_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Eccentricity:
    """An eccentric reducer found at an inline joint.

    Attributes
    ----------
    pipes : (int, int)
        The joint's pipes ``(i, j)`` in the joint's order.
    offset : ndarray, shape (3,), metres
        Imposed step from pipe i's axis to pipe j's axis, perpendicular to the run, of length
        ``R_large - R_small``.
    measured : ndarray, shape (3,), metres
        The measured step at the joint.
    tolerance : float
        The window used, metres.
    flat : str
        ``"top"``, ``"bottom"`` or ``"side"``: where both pipes are flush.
    """

    pipes: tuple[int, int]
    offset: np.ndarray
    measured: np.ndarray
    tolerance: float
    flat: str

    def note(self, names: Sequence[str]) -> str:
        """The sentence for the reducer's notes."""
        i, j = self.pipes
        return (
            f"eccentric reducer, flat on {self.flat}: the axes of {names[i]} and {names[j]} "
            f"are {np.linalg.norm(self.measured) * 1000:.1f} mm apart at the joint (+-"
            f"{self.tolerance * 1000:.1f} mm), consistent with the radii's difference "
            f"{np.linalg.norm(self.offset) * 1000:.1f} mm, not with 0"
        )


def eccentric_joints(
    joints: Sequence[Joint],
    centers,
    axes,
    lengths,
    run_axes,
    ods,
    runs,
    center_se,
    axis_se_deg,
    *,
    od_se=None,
    k_sigma: float = 3.0,
    margin: float = ECCENTRIC_MARGIN,
) -> dict[int, Eccentricity]:
    """Find the inline joints between two sizes whose axes are offset like an eccentric reducer.

    Parameters
    ----------
    joints : sequence of Joint
    centers : array_like, shape (n, 3), metres
        Fitted axis points (the fits' centres).
    axes : array_like, shape (n, 3)
        Fitted unit axes.
    lengths : array_like, shape (n,), metres
        Fitted lengths.
    run_axes : array_like, shape (n, 3)
        Regularised unit axes (inline pipes are exactly parallel).
    ods : array_like, shape (n,), metres
        Outside diameters to build with (the catalog's, else the run's estimate).
    runs : array_like, shape (n,), int
        Run of one size of each pipe (same run: no reducer).
    center_se : array_like, shape (n,), metres
        Standard error of each fitted axis position across the axis (NaN: unknown).
    axis_se_deg : array_like, shape (n,), degrees
        Standard error of each fitted axis direction (NaN: unknown).
    od_se : array_like, shape (n,), metres, optional
        Standard error of each diameter in ``ods``: 0 for a catalog size (the default for all),
        the run estimate's for a pipe without one (NaN: unknown, never eccentric).
    k_sigma : float
        Width of the window in combined standard errors (merging's 3).
    margin : float
        Added to the window, metres.

    Returns
    -------
    dict of int to Eccentricity
        By index into ``joints``; joints not listed stay concentric.
    """
    centers = np.asarray(centers, float).reshape(-1, 3)
    axes = np.asarray(axes, float).reshape(-1, 3)
    lengths = np.asarray(lengths, float).reshape(-1)
    run_axes = np.asarray(run_axes, float).reshape(-1, 3)
    ods = np.asarray(ods, float).reshape(-1)
    runs = np.asarray(runs).reshape(-1)
    center_se = np.asarray(center_se, float).reshape(-1)
    axis_se = np.radians(np.asarray(axis_se_deg, float).reshape(-1))
    od_se = np.zeros(len(ods)) if od_se is None else np.asarray(od_se, float).reshape(-1)
    found: dict[int, Eccentricity] = {}
    for index, joint in enumerate(joints):
        if joint.kind != "inline":
            continue
        (i, ki), (j, kj) = joint.ends
        step = 0.5 * abs(ods[i] - ods[j])
        if runs[i] == runs[j] or not step >= 1e-9:
            continue
        ends = [centers[m] + (k - 0.5) * lengths[m] * axes[m] for m, k in ((i, ki), (j, kj))]
        joint_point = 0.5 * (ends[0] + ends[1])
        along = [float((joint_point - centers[m]) @ axes[m]) for m in (i, j)]
        qi, qj = (centers[m] + s * axes[m] for m, s in zip((i, j), along))
        d = run_axes[i] / np.linalg.norm(run_axes[i])
        measured = (qj - qi) - float((qj - qi) @ d) * d
        sigmas = [np.hypot(center_se[m], s * axis_se[m]) for m, s in zip((i, j), along)]
        if not all(np.isfinite(sigmas)):
            continue
        tolerance = k_sigma * float(np.hypot(*sigmas)) + margin
        step_se = 0.5 * float(np.hypot(od_se[i], od_se[j]))
        if not np.isfinite(step_se):
            continue
        size = float(np.linalg.norm(measured))
        if size <= tolerance or abs(size - step) > tolerance + k_sigma * step_se:
            continue
        towards = measured / size
        offset = step * towards
        up = _Z - float(_Z @ d) * d
        flat = "side"
        if np.linalg.norm(up) > 1e-6:
            up /= np.linalg.norm(up)
            vertical = step * up * np.sign(float(towards @ up) or 1.0)
            if np.linalg.norm(vertical - measured) <= tolerance:
                offset = vertical
                # the small pipe's axis is displaced towards the flat side
                to_small = offset if ods[j] < ods[i] else -offset
                flat = "top" if float(to_small @ up) > 0 else "bottom"
        found[index] = Eccentricity((int(i), int(j)), offset, measured, tolerance, flat)
    return found
