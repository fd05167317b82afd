"""Opposite seen faces without a station: do their shots share the box's outline?

Private helper of :mod:`asbuilt.fit.cuboid`. Without a viewpoint nothing rules out two
opposite faces (a box scanned from two stations has them), and a wall behind a column, shot
past its sides, fits the "back face" as closely as the column's own far side would: an
independent review's column 478 x 524 mm came out 5.51 x 1.22 m, the 1.22 m "observed" to
0.8 mm (every one of 14 such no-station sizes in its batches was off by 0.06-9 m with about a
millimetre of standard error). Two opposite faces of one box have one outline: across their
axis, each face's shots lie within the other's extent, up to a raster step where one stops
short of an edge the other reaches. A wall behind reaches past the box on either side, a row
of it far beyond the front's extent. (Comparing a face with all the other faces' shots
misses most of these: a frame fitted to a wall puts wall shots on the other faces too.) Such
a fit is refused (:func:`asbuilt.fit.cuboid.fit_cuboid`): the frame built on the wall is
wrong throughout, and leaving the face out and fitting again let the wall back in as well.

Everything here is numpy; lengths in metres.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit import _faces
from asbuilt.fit._common import median_spacing

__all__ = ["outside_outline"]

#: How far (in the shots' median nearest-neighbour spacing, about a raster step on a face
#: seen squarely) a face's shots may reach past the other shots' extent across its axis: the
#: others stop short of an edge by up to a step, this face's shots need not. The same 1.5
#: spacings the segmentation allows between a face and its neighbour's plane.
_REACH = 1.5


def outside_outline(model, x, label, inliers, width) -> int | None:
    """The face of an opposite pair whose shots reach past its opposite's outline, or None.

    ``model``: the fitted frame (:class:`asbuilt.fit._joint.FaceModel`); ``x`` (n, 3) the
    points (centred frame); ``label`` (n,) their faces; ``inliers`` (n,) bool; ``width``
    (metres): the inlier cut, the least tolerance. Two opposite faces of one box have one
    outline: along the two axes across theirs, each face's inliers lie within the other's
    extent, widened by ``_REACH`` times the inliers' nearest-neighbour spacing (each face's
    shots stop short of the edges by up to a step). The face reaching farthest past its
    opposite (a wall behind, wider than the box's far side would be) is returned.
    """
    if not _faces.has_opposite(model.face_axis):
        return None
    proj = x @ model.axes.T
    tol = max(width, _REACH * median_spacing(x[inliers]))
    worst, worst_face = tol, None
    for f in range(model.offset.shape[0]):
        k = int(model.face_axis[f])
        mine = inliers & (label == f)
        opposite = inliers & (label >= 0) & (model.face_axis[np.maximum(label, 0)] == k)
        opposite &= label != f
        if not mine.any() or not opposite.any():
            continue
        for j in range(3):
            if j == k:
                continue
            past = max(
                float(proj[opposite, j].min() - proj[mine, j].min()),
                float(proj[mine, j].max() - proj[opposite, j].max()),
            )
            if past > worst:
                worst, worst_face = past, f
    return worst_face
