"""Extent sizes whose end the fit's own left-out shots show the box may run past.

Private helper of the cuboid fit. A size no two opposite faces bound is an extent: the box
ends somewhere past the last inlier along it (padded into the gap to the next raster line,
:mod:`asbuilt.fit._cuboid_sizes`). That presumes every shot past the end missed the box. A
beam seen obliquely, its far part at 80-86 degrees of incidence, is cut at range jumps along
its length; the fit of its nearest surfaces (:mod:`asbuilt.fit._cuboid_foreground`) or the
robust refit can leave the far part out (as background, or as outliers), and the fit then
reported the near part's length with a standard error of centimetres: on an independent ray
caster's 80 such beams with a wall 1-3 m behind, 44 came out over 0.5 m short, 35 of them by
over three standard errors (up to metres at millimetres).

Shots left out of the fit that lie on the plane of one of its seen faces, within that face
across it, past the extent bound along the size, are what the face would carry if the box ran
on to them: the box does not end where the fit put it, or not provably. No other surface is
expected there (a wall behind meets a side's plane along one line only; a shot inside the
box's prolongation, rather than on its faces, would say the box ended before it). The size is
then a lower bound: its standard error (and the centre's) is infinite, as for a size an
acquisition session saw run on past its window (:mod:`asbuilt.fit._window`), and a note says
so. The face's plane is allowed its fitted tilt: at distance ``d`` past the end, three
standard errors of its normal's direction times ``d``, besides the inlier cutoff. Numpy only;
metres.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from asbuilt.fit.result import FitResult
from asbuilt.primitives import Cuboid

__all__ = ["ON_FACE_SHOTS", "open_past_faces"]

#: Left-out shots on a seen face's plane past the end that make the size a lower bound: one
#: can be a stray return (a mixed return at the edge, lying on the plane by chance).
ON_FACE_SHOTS = 2
#: Shots on a face's plane within the box this many make it a seen face.
_SEEN_SHOTS = 3
#: Standard errors of a face's tilt allowed at distance along the plane.
_TILT_SIGMAS = 3.0


def _seen_faces(local: np.ndarray, half: np.ndarray, kept: np.ndarray, cutoff: float) -> list:
    """The faces ``(axis, sign)`` that at least ``_SEEN_SHOTS`` kept shots lie on, in the box."""
    inside = np.all(np.abs(local) <= half + cutoff, axis=1) & kept
    faces = []
    for j in range(3):
        for sign in (-1.0, 1.0):
            on = inside & (np.abs(local[:, j] - sign * half[j]) <= cutoff)
            if np.count_nonzero(on) >= _SEEN_SHOTS:
                faces.append((j, sign))
    return faces


def open_ends(result: FitResult, points: np.ndarray, cutoff: float):
    """Per extent size and end, the left-out shots on a seen face's plane past that end.

    Returns a list of ``(k, sign, count, farthest)``: the size's output axis, the end (+1 or
    -1 along it), how many such shots, and how far past the end (metres) the farthest is.
    """
    box = result.primitive
    if not isinstance(box, Cuboid) or result.observed is None:
        return []
    axes = np.asarray(box.axes)
    half = 0.5 * np.asarray(box.size, dtype=np.float64)
    local = (np.asarray(points, dtype=np.float64) - np.asarray(box.center)) @ axes.T
    finite = np.isfinite(local).all(axis=1)
    kept = result.inliers & finite
    left = ~result.inliers & finite
    if not left.any():
        return []
    faces = _seen_faces(local, half, kept, cutoff)
    tilt = np.radians(np.asarray(result.stderr.get("axes_deg", (0.0,) * 3), dtype=np.float64))
    if "turn_deg" in result.diagnostics:
        # A frame splitting the raster lines otherwise is another answer, not a tilt: its
        # faces lie elsewhere, and a wedge that wide around this frame's faces would take in
        # any shot past the box (asbuilt.fit._cuboid_sparse.line_split_spread).
        other = np.arange(3) != int(result.diagnostics["turn_axis"])
        spread = math.radians(result.diagnostics["turn_deg"])
        tilt[other] = np.sqrt(np.maximum(tilt[other] ** 2 - spread**2, 0.0))
    tilt = np.where(np.isfinite(tilt), tilt, math.pi / 2)
    found = []
    for k in range(3):
        if result.observed[k]:
            continue
        for sign in (-1.0, 1.0):
            if (k, sign) in faces:
                continue  # an end face seen: nothing runs on past it
            past = sign * local[:, k] - half[k]
            candidates = left & (past > cutoff)
            if not candidates.any():
                continue
            on_any = np.zeros(len(local), dtype=bool)
            for j, face_sign in faces:
                if j == k:
                    continue
                m = 3 - j - k
                # The face's plane tilts about the end by its normal's direction error.
                tol = cutoff + np.tan(min(_TILT_SIGMAS * tilt[j], 1.0)) * np.maximum(past, 0.0)
                on = np.abs(local[:, j] - face_sign * half[j]) <= tol
                on &= np.abs(local[:, m]) <= half[m] + tol
                on_any |= candidates & on
            count = int(np.count_nonzero(on_any))
            if count >= ON_FACE_SHOTS:
                found.append((k, sign, count, float(past[on_any].max())))
    return found


def open_past_faces(result: FitResult, points: np.ndarray, cutoff: float) -> FitResult:
    """``result`` with each extent size that left-out shots on a seen face's plane run past
    (:func:`open_ends`) made a lower bound: its standard error and the centre's infinite, a
    note, ``diagnostics["open_sizes"]`` their count; ``result`` itself when there is none.

    Parameters
    ----------
    result : FitResult
        A cuboid fit over ``points``.
    points : ndarray, shape (n, 3), metres
        The fitted shots, in ``result``'s rows.
    cutoff : float, metres
        The inlier cutoff (how far from a face's plane a shot on it may lie).
    """
    ends = open_ends(result, points, cutoff)
    if not ends:
        return result
    size_se = list(result.stderr["size"])
    sizes = sorted({k for k, *_ in ends})
    for k in sizes:
        size_se[k] = math.inf
    stderr = {**result.stderr, "size": tuple(size_se), "center": math.inf}
    shots = sum(count for *_, count, _ in ends)
    farthest = max(far for *_, far in ends)
    what = ", ".join(f"{result.primitive.size[k]:.3f} m" for k in sizes)
    note = (
        f"{shots} shot(s) left out of the fit lie on the plane of a seen face up to "
        f"{farthest:.2f} m past the end of its size{'s' if len(sizes) > 1 else ''} {what}: "
        "the box may run on to them, so that size is a lower bound, not a measurement "
        "(standard error infinite). Check the object's far end or scan it square-on."
    )
    diagnostics = {**result.diagnostics, "open_sizes": float(len(sizes))}
    return dataclasses.replace(
        result, stderr=stderr, notes=(*result.notes, note), diagnostics=diagnostics
    )
