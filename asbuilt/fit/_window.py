"""Sizes an acquisition session saw run on beyond the operator's window: lower bounds only.

An ``asbuilt scan`` session shoots an object's window, then pairs each object cell on the
window's border with the cell beyond it; when that shot hits the object too, the object runs on
past the window (docs/acquisition.md, edge seeking) and its end was never seen. The fits bound
an unseen end by the outermost shot (a cylinder's length) or the raster's silhouette window (a
cuboid's extent sizes), with the standard error of a raster step: right when the window held
the object's end, and metres wrong when it did not (the docs' simulated site column came out
2.33 m of 3.0 m, +-52 mm).

The session records each object's window (``acquisition.window_deg``, kept by the loader in
``ScanObject.extra``) and each shot's pan and tilt (``measurements``). A shot outside the window
is one of those beyond-the-border shots; when it is the outermost shot along a size whose end no
seen face bounds, that size is a lower bound: its standard error is infinite and a note says
so. Numpy only.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from asbuilt.fit.result import FitResult
from asbuilt.primitives import Cuboid, Cylinder
from asbuilt.scan.model import ScanObject

__all__ = ["beyond_window", "open_ends"]

#: Angle (radians) a shot must lie outside the recorded window to count as beyond it: the
#: window's corners are stored to a few decimals of a degree, its raster cells lie inside.
_OUTSIDE = math.radians(1e-4)


def beyond_window(obj: ScanObject) -> np.ndarray | None:
    """Which of ``obj``'s shots, shape (n,) bool, were taken outside its acquisition window,
    from its ``measurements`` (pan and tilt, radians) and ``extra["acquisition"]["window_deg"]``
    ([pan1, tilt1, pan2, tilt2] degrees); None when the scan does not record both."""
    acquisition = obj.extra.get("acquisition") if obj.extra else None
    window = acquisition.get("window_deg") if isinstance(acquisition, dict) else None
    if obj.measurements is None or not isinstance(window, (list, tuple)) or len(window) != 4:
        return None
    try:
        corners = np.radians(np.asarray(window, dtype=np.float64))
    except (TypeError, ValueError):
        return None
    if not np.all(np.isfinite(corners)):
        return None
    pan, tilt = obj.measurements[:, 0], obj.measurements[:, 1]
    pans, tilts = sorted(corners[[0, 2]]), sorted(corners[[1, 3]])
    return (
        (pan < pans[0] - _OUTSIDE)
        | (pan > pans[1] + _OUTSIDE)
        | (tilt < tilts[0] - _OUTSIDE)
        | (tilt > tilts[1] + _OUTSIDE)
    )


def open_ends(result: FitResult, points: np.ndarray, beyond: np.ndarray, viewpoint) -> FitResult:
    """``result`` with the sizes whose outermost inlier is a shot beyond the window made lower
    bounds (standard error infinite, a cuboid's centre's too, a note, and
    ``diagnostics["open_sizes"]`` their count), or ``result`` itself when none is.

    Parameters
    ----------
    result : FitResult
        A cylinder's (its ``length``) or a cuboid's (each size no seen face bounds at that end:
        both ends with no face normal to it, the end away from ``viewpoint`` with one) fit.
    points : ndarray, shape (n, 3), metres
        The fitted points, in ``result``'s rows.
    beyond : ndarray, shape (n,), bool
        :func:`beyond_window`.
    viewpoint : ndarray, shape (3,), metres, or None
        Where the shots came from (the side a single seen face is on).
    """
    kept = result.inliers & np.isfinite(points).all(axis=1)
    if not np.any(beyond & kept):
        return result
    primitive = result.primitive
    if isinstance(primitive, Cylinder):
        along = (points[kept] - primitive.center) @ primitive.axis
        ends = _open_sides(along, beyond[kept], (True, True))
        if not any(ends):
            return result
        stderr = {**result.stderr, "length": math.inf}
        what = f"its length ({primitive.length:.3f} m)"
        return _with_note(result, stderr, what, ends)
    if not isinstance(primitive, Cuboid):
        return result
    axes = np.asarray(primitive.axes)
    local = (points[kept] - primitive.center) @ axes.T
    faces = [int(result.diagnostics.get(f"faces_axis{k}", 0)) for k in range(3)]
    size_se = list(result.stderr["size"])
    observed = list(result.observed) if result.observed is not None else [False] * 3
    opened = []
    for k in range(3):
        if faces[k] >= 2 or observed[k]:
            continue
        free = (True, True)
        if faces[k] == 1:
            # The one seen face is on the viewpoint's side: only the far end is an extent.
            toward = 0.0 if viewpoint is None else float((viewpoint - primitive.center) @ axes[k])
            free = (toward > 0, toward < 0) if toward else (False, False)
        ends = _open_sides(local[:, k], beyond[kept], free)
        if any(ends):
            size_se[k] = math.inf
            opened.append((k, ends))
    if not opened:
        return result
    # Where the box lies along an open size is as unknown as how far it runs.
    stderr = {**result.stderr, "size": tuple(size_se), "center": math.inf}
    sizes = ", ".join(f"{primitive.size[k]:.3f} m" for k, _ in opened)
    what = f"its size{'s' if len(opened) > 1 else ''} {sizes}"
    either = (any(e[0] for _, e in opened), any(e[1] for _, e in opened))
    return _with_note(result, stderr, what, either, len(opened))


def _open_sides(coordinate: np.ndarray, beyond: np.ndarray, free) -> tuple[bool, bool]:
    """Whether the least and the greatest of ``coordinate`` (m,) metres is a shot beyond the
    window, at the ends ``free`` (no seen face there)."""
    low, high = int(np.argmin(coordinate)), int(np.argmax(coordinate))
    return bool(free[0] and beyond[low]), bool(free[1] and beyond[high])


def _with_note(result: FitResult, stderr, what: str, ends, sizes: int = 1) -> FitResult:
    where = "both ends" if all(ends) else "one end"
    note = (
        f"The object runs on beyond the operator's window at {where} (shots the session took "
        f"past the window hit it): {what} is a lower bound, not a measurement (standard error "
        "infinite). Widen the window over the object's ends to measure it."
    )
    # As data too: the weak-geometry rule reports a size the scan did not measure.
    diagnostics = {**result.diagnostics, "open_sizes": float(sizes)}
    return dataclasses.replace(
        result, stderr=stderr, notes=(*result.notes, note), diagnostics=diagnostics
    )
