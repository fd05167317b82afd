"""A raster line on something in front of a box, fitted as the box's one face.

Private helper of :mod:`asbuilt.fit.cuboid`. The cuboid fit takes the nearest surfaces in a
window for the box (a column before the wall behind it). A thin object in front of the box
breaks that: a vertical pipe before a column puts one raster column of shots nearest the
station, a straight line of them, and the fit made it the box's one seen face, rejected the
column's own shots behind it and was refused as "one raster line" (an independent review: 6
shots on an NPS 6 pipe 0.5 m before a 0.5 m column, whose 12 shots on two raster columns were
left out; the message named the pipe's line as the column's face).

When a one-face fit is refused so, :func:`behind_occluder` fits the shots it rejected. That
fit stands for the box when it is itself a fit (every check of the cuboid fit passed), every
shot of the refused line lies in front of it along its beam, as an occluder's shots do (its
beam reaches the shot before the box, or passes the box by), and the box stands before a
background of its own: at least ``BEHIND_SHOTS`` of the shots it rejected lie farther than
all of its own. Without that last test the wall behind a thin column was taken for the box
and the column's one raster line for something in front of it (a 0.8 m "box" through the
wall's shots on the clutter benchmark, for a 0.28 x 0.20 m column). The line is then left
out, counted as background (the ``outliers`` rule does not count them), and a note says so.
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import row_norms
from asbuilt.fit._cuboid_foreground import beam_box
from asbuilt.fit._cylinder_background import rescued
from asbuilt.fit.result import BACKGROUND_SHOTS, FitResult
from asbuilt.primitives import Cuboid

__all__ = ["BEHIND_SHOTS", "behind_occluder", "in_front_of"]

#: Least shots the box behind a line must reject beyond all of its own (a wall behind it): a
#: box with nothing behind it may be the background itself.
BEHIND_SHOTS = 3


def in_front_of(box: Cuboid, points: np.ndarray, view: np.ndarray, width: float) -> np.ndarray:
    """Which ``points`` (m, 3) metres lie in front of ``box`` as seen from ``view`` (3,)
    metres, shape (m,) bool: each one's beam from ``view`` passes the box by, or enters it
    more than ``width`` metres beyond the point (:func:`beam_box`'s slab test)."""
    ranges, enter, leave = beam_box(box, points, view)
    misses = ~(enter <= leave) | (leave < 0.0)
    return misses | (ranges < enter - width)


def behind_occluder(
    fit, refused: FitResult, points: np.ndarray, view, width: float
) -> FitResult | None:
    """The fit of the box behind a refused one-line face (module docstring), or None.

    Parameters
    ----------
    fit : callable
        ``fit(points)`` fits a subset (the cuboid fit with the same sigma, tolerances and
        viewpoint) and raises :class:`~asbuilt.errors.FitError` when it is refused.
    refused : FitResult
        The one-face fit refused as one raster line; its ``inliers`` (n,) are that line.
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres, or None
    width : float, metres
        How far in front of the box a shot must lie (the inlier cutoff).
    """
    if view is None:
        return None
    line = refused.inliers
    rest = ~line
    if np.count_nonzero(rest) < 7:
        return None
    try:
        found = fit(points[rest])
    except FitError:
        return None
    if not in_front_of(found.primitive, points[line], view, width).all():
        return None
    ranges = row_norms(points[rest] - view)
    farthest = float(ranges[found.inliers].max())
    if np.count_nonzero(ranges[~found.inliers] > farthest + width) < BEHIND_SHOTS:
        return None
    inliers = np.zeros(len(points), dtype=bool)
    inliers[rest] = found.inliers
    left = int(np.count_nonzero(line))
    background = left + int((found.diagnostics or {}).get(BACKGROUND_SHOTS, 0))
    note = (
        f"{left} shot(s) on one raster line in front of the box (something before it, such"
        " as a pipe) were left out before the fit."
    )
    return rescued(found, points, inliers, note, background=background)
