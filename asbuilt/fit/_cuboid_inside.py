"""Shots inside a fitted box: a fit no beam can have measured.

Private helper of :func:`asbuilt.fit.cuboid.fit_cuboid`. A range finder's beam stops at the
first surface it meets, so no shot can lie inside a solid box by more than the range noise.
A fit that leaves out many of its shots that far inside its box took another surface for the
object: on the clutter benchmark, a column 0.22 x 0.28 m before a wall was fitted as a box
1.2 x 3.5 x 3.8 m of wall and floor with 16 of the column's 100 shots inside it, and another
column's one face was fitted on the wall with 14 of 105 inside.

Why a count and a share, not any shot: a fit's own frame errors and mixed returns at a
silhouette (a beam that grazed an edge and came back between the edge and the wall) leave a
few shots just past the inlier cutoff inside a good box. On the 756 gathered fits with a
known truth (the accuracy, speed, sparse and two-station benchmarks' point sets), no good fit
had more than 3 shots inside; on the clutter benchmark, the three fits with 6 or more were all
wrong (two gross, one 25% off).
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._cuboid_foreground import FRONT_SHOTS

__all__ = ["INSIDE_SHARE", "INSIDE_SHOTS", "ShotsInside", "shots_inside", "too_many_inside"]

#: Fewest shots inside a box that refuse it: twice the few that make a surface in front of one
#: (``FRONT_SHOTS``), since a good fit can leave a stray return or two at each silhouette.
INSIDE_SHOTS = 2 * FRONT_SHOTS
#: ... and at least this share of the shots: a dense scan's silhouettes hold more mixed returns.
INSIDE_SHARE = 0.1


class ShotsInside(FitError):
    """A cuboid fit refused: too many of its shots lie inside its box (:func:`too_many_inside`),
    where no beam can measure one. Not retried at another noise level: the shots are
    centimetres to metres inside, not a noise level's cutoff."""


def shots_inside(cuboid, points: np.ndarray, width: float) -> np.ndarray:
    """Which of ``points`` (n, 3) metres lie more than ``width`` metres inside ``cuboid``
    (its signed distance, negative inside), shape (n,) bool."""
    return cuboid.distance(points) < -width


def too_many_inside(cuboid, points: np.ndarray, inliers: np.ndarray, width: float) -> int:
    """The number of ``points`` (n, 3) metres outside the fit's ``inliers`` (n,) bool and more
    than ``width`` metres inside ``cuboid`` when it is at least ``INSIDE_SHOTS`` and
    ``INSIDE_SHARE`` of all the points, else 0.

    Inliers are left out: each lies within the cutoff of its own face's fitted plane, and the
    box's surface, its unseen sides placed by the extent or the raster window, can pass a few
    millimetres inside that plane near an edge (a column's two raster lines on its front, 8-11
    mm inside its box and on their face)."""
    count = int(np.count_nonzero(shots_inside(cuboid, points, width) & ~inliers))
    if count >= max(INSIDE_SHOTS, INSIDE_SHARE * len(points)):
        return count
    return 0
