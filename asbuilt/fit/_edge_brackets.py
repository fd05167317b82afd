"""Edge-bisection brackets a scan session recorded: where a pinned cuboid edge may lie.

An ``asbuilt scan`` session bisects the silhouette of a box between a shot on it and one past
it (docs/acquisition.md). The cuboid fit takes the last hit of a bisection for the edge
itself (no pad, no gap: :func:`asbuilt.fit._cuboid_sizes.bounds`), which holds when the
bracket left is a couple of millimetres across the beam. It is not always: a pan-tilt head
aims in whole positions (a PTU-D46's 0.0514 degree is 4.9 mm across the beam at 5.5 m), so a
bisection cannot narrow its bracket below a position whatever its tolerance, and along a face
seen at grazing incidence that bracket is several times longer (a 0.4 m column's side seen
at 71 degrees came out 11 mm short, with a standard error of 0.1 micrometre, noiseless).

The session records, per bisected pair, its last hit (an index into the object's points) and
the first miss beyond it: the difference of the two beams' unit directions and the miss's
(``acquisition.edge_brackets``: ``[[index, dx, dy, dz, ux, uy, uz], ...]``, unitless, scan
frame; docs/scan-format.md). The miss's beam passes the hit's range at the hit plus that
difference times the range, and runs on along its direction. It met nothing, so where it
crosses the plane of a seen face, within that face across, the face ends before it: an
extent bound pinned at its extreme hit (no pad: the fit's bound is the hit itself) has its
edge between that hit and the nearest such crossing beyond it. The bound is put in the middle
of that gap and the gap enters the size's variance as a uniform one (``gap^2 / 12``; the
centre's a quarter of it). A bound with a pad (a raster's: its gap is in its standard error
already) and a size that is a lower bound (standard error infinite) are left alone. A
bisection's last "hit" may be a mixed return (a phantom between the edge and the wall,
which the fit leaves out): the miss after it bounds the edge all the same. Numpy only.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from asbuilt.fit.result import FitResult
from asbuilt.primitives import Cuboid
from asbuilt.scan.model import ScanObject

__all__ = ["edge_brackets", "widen_pinned"]


def edge_brackets(obj: ScanObject) -> tuple[np.ndarray, np.ndarray] | None:
    """The brackets ``obj``'s session recorded: hit indices (m,) int and (m, 6) rows of the
    miss's beam direction less the hit's, then the miss's; None when the scan records none
    (another tool, an older session) or they are malformed."""
    acquisition = obj.extra.get("acquisition") if obj.extra else None
    rows = acquisition.get("edge_brackets") if isinstance(acquisition, dict) else None
    if not isinstance(rows, (list, tuple)) or not rows:
        return None
    try:
        table = np.asarray(rows, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    n = len(obj.points)
    if table.ndim != 2 or table.shape[1] != 7 or not np.isfinite(table).all():
        return None
    index = table[:, 0]
    if np.any(index != np.round(index)) or np.any((index < 0) | (index >= n)):
        return None
    return index.astype(np.int64), table[:, 1:]


def _face_sides(result: FitResult, local_view) -> np.ndarray:
    """(2, 3) bool: the sides (row 0 low, row 1 high; output axes) a seen face bounds."""
    faces = [int(result.diagnostics.get(f"faces_axis{k}", 0)) for k in range(3)]
    out = np.zeros((2, 3), dtype=bool)
    for k in range(3):
        if faces[k] >= 2:
            out[:, k] = True
        elif faces[k] == 1 and local_view[k] != 0.0:
            out[int(local_view[k] > 0), k] = True  # the face is on the viewpoint's side
        elif faces[k] == 1:
            out[:, k] = True  # which side is unknown: touch neither
    return out


def widen_pinned(
    result: FitResult, points: np.ndarray, hits: np.ndarray, rays: np.ndarray, viewpoint
) -> FitResult:
    """``result`` (a cuboid fit of ``points`` (n, 3), metres, in its rows) with each extent
    bound pinned at its extreme hit moved to the middle of the gap up to the nearest recorded
    miss beyond it, and that gap added to the size's standard error (module docstring);
    ``result`` itself when none is.

    ``hits`` (m,) int and ``rays`` (m, 6) as :func:`edge_brackets` gives them; ``viewpoint``
    (3,) metres, where the beams start (the range is measured from it).
    """
    box = result.primitive
    if not isinstance(box, Cuboid) or result.inliers is None or viewpoint is None:
        return result
    if not result.inliers.any():
        return result
    size_se = np.asarray(result.stderr.get("size", (math.inf,) * 3), dtype=np.float64)
    axes = np.asarray(box.axes, dtype=np.float64)
    half = 0.5 * np.asarray(box.size, dtype=np.float64)
    station = np.asarray(viewpoint, dtype=np.float64)
    faces = _face_sides(result, (station - box.center) @ axes.T)
    local = (points - box.center) @ axes.T
    inner = local[result.inliers]
    # Where each miss's beam passes the hit's range, and its direction, in the box's frame.
    reach = np.linalg.norm(points[hits] - station, axis=1)
    start = local[hits] + reach[:, None] * (rays[:, :3] @ axes.T)
    heading = rays[:, 3:] @ axes.T
    tol = 3.0 * (float(result.sigma) if result.sigma else 0.0)
    gaps = np.zeros((2, 3))
    for k in range(3):
        if not math.isfinite(size_se[k]):
            continue
        for side, sign in ((0, -1.0), (1, 1.0)):
            if faces[side, k]:
                continue
            extreme = float(np.max(sign * inner[:, k]))
            if half[k] - extreme > tol:
                continue  # a padded bound: its gap is in its standard error already
            upper = math.inf
            for f_side, f in zip(*np.nonzero(faces)):
                if f == k:
                    continue
                j = 3 - k - f  # the third axis: the crossing must lie within the face across
                plane = half[f] if f_side else -half[f]
                ok = np.abs(heading[:, f]) > 1e-9
                t = (plane - start[ok, f]) / heading[ok, f]
                cross = start[ok] + t[:, None] * heading[ok]
                within = (np.abs(cross[:, j]) <= half[j]) & (sign * cross[:, k] > extreme)
                if within.any():
                    upper = min(upper, float(np.min(sign * cross[within, k])))
            if math.isfinite(upper):
                gaps[side, k] = upper - extreme
    if not gaps.any():
        return result
    # The bound moves to the middle of its gap; the edge is uniform over it.
    lo, hi = -half - 0.5 * gaps[0], half + 0.5 * gaps[1]
    extra = (gaps**2).sum(axis=0) / 12.0
    size = hi - lo
    centre = box.center + axes.T @ (0.5 * (hi + lo))
    size_se = np.sqrt(size_se**2 + extra)
    centre_se = result.stderr.get("center")
    if centre_se is not None and math.isfinite(centre_se):
        centre_se = math.sqrt(centre_se**2 + float(extra.sum()) / 4.0)
    stderr = {**result.stderr, "size": tuple(float(v) for v in size_se), "center": centre_se}
    diagnostics = {**result.diagnostics, "bracketed": float(np.count_nonzero(gaps))}
    return dataclasses.replace(
        result,
        primitive=Cuboid(center=centre, axes=box.axes, size=size),
        stderr=stderr,
        diagnostics=diagnostics,
    )
