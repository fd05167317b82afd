"""The edge-bisection shots of a scan session in a cuboid fit.

Private helpers of :mod:`asbuilt.fit.cuboid`. A scan session (``asbuilt scan``) adds shots
that bisect the gap between a raster line's last hit on the box and its first miss; they crowd
the silhouette, so the face segmentation takes the raster shots and only the bisection shots
that stand apart from them (:func:`spread_subset`), and a bisection shot pressed against an
edge that returned a mixed range is put back on the box along its beam
(:func:`mixed_returns`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from asbuilt.fit import _faces
from asbuilt.fit._joint import median

__all__ = ["mixed_returns", "spread_subset"]


def spread_subset(x: np.ndarray, base: np.ndarray) -> np.ndarray:
    """Indices of the ``base`` points (n,) bool plus the others that stand apart from them.

    Another point joins when it is at least half the base points' median nearest-neighbour
    distance from every point already taken (in the order given). Returns sorted indices.
    """
    taken = list(np.flatnonzero(base))
    if len(taken) < 2 or len(taken) == x.shape[0]:
        return np.flatnonzero(base) if len(taken) >= 2 else np.arange(x.shape[0])
    pts = x[taken]
    others = np.flatnonzero(~base)
    # Dense (``_faces._DENSE_LIMIT``): a k-d tree instead of a distance matrix, same result (a
    # matrix of 10,000 points is 2.4 GB).
    if max(len(taken), others.size) > _faces._DENSE_LIMIT:
        tree = cKDTree(pts)
        least = 0.5 * median(tree.query(pts, k=2)[0][:, 1])
        # Only a point far enough from every base point can join; those are few (bisection
        # shots), so the greedy pass over them is cheap.
        apart = others[tree.query(x[others], k=1)[0] >= least]
        joined: list[int] = []
        for i in apart:
            if not joined or np.linalg.norm(x[joined] - x[i], axis=1).min() >= least:
                joined.append(int(i))
        return np.sort(np.array(taken + joined, dtype=np.int64))
    d = np.linalg.norm(pts[:, None, :] - pts[None, :, :], axis=2)
    np.fill_diagonal(d, np.inf)
    least = 0.5 * median(d.min(axis=1))
    for i in others:
        if np.linalg.norm(x[taken] - x[i], axis=1).min() >= least:
            taken.append(i)
    return np.sort(np.array(taken, dtype=np.int64))


def mixed_returns(x, label, inliers, model, edges, view, tol):
    """Bisection shots rejected as outliers, put back on the box along their beam.

    A shot pressed against a silhouette edge often straddles it and returns a mixed range (the
    background's, or one in between), so the fit rejects it; its direction is still the
    shot's, just inside the silhouette. Where the beam from ``view`` (3,) (centred frame)
    through such a shot enters the box is where a clean return would have been: the last of
    its entries into the seen faces' half-spaces (the slab method: every seen face faces the
    viewpoint). Kept only if that is not farther than the measured point by more than ``tol``
    metres (a mixed return is never short), on the face of the inlier it leans on (its
    partner, or the partner's partner and so on back along the bisection) and no farther from
    that than the measured point: a shot on a face the fit did not find is left out.

    Returns the mended points (m, 3), their face labels (m,) and the indices (m,) of the shots
    they mend. The mended points are held fixed in the error propagation.
    """
    points, labels, index = [], [], []
    normals = model.normals()
    for i in np.flatnonzero((edges[0] >= 0) & ~inliers):
        beam = x[i] - view
        reach = float(np.linalg.norm(beam))
        if reach <= 0.0:
            continue
        unit = beam / reach
        facing = normals @ unit
        front = facing < -1e-6
        if not np.any(front):
            continue
        t = np.where(front, (model.offset - normals @ view) / np.where(front, facing, 1.0), -np.inf)
        f = int(np.argmax(t))
        if not (0.0 < t[f] <= reach + tol):
            continue
        mended = view + t[f] * unit
        # A bisection runs on one face from the raster shot it started from: the mended point
        # must be on the face of the shot it leans on (its partner, or the partner's, back to
        # a shot the fit kept) and no farther from it than the measured point (pushed away
        # along the beam by the mixed range).
        partner = int(edges[1][i])
        for _ in range(32):  # back along the bisection to a shot the fit kept
            if partner < 0 or inliers[partner] or edges[0][partner] < 0:
                break
            partner = int(edges[1][partner])
        if partner < 0 or not inliers[partner] or int(label[partner]) != f:
            continue
        if np.linalg.norm(mended - x[partner]) > np.linalg.norm(x[i] - x[partner]) + tol:
            continue
        points.append(mended)
        labels.append(f)
        index.append(i)
    if not index:
        return np.zeros((0, 3)), np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.array(points), np.array(labels, np.int64), np.array(index, np.int64)
