"""Minimum-area bounding rectangle of planar points, for a cuboid seen on one face only.

Private helper of :mod:`asbuilt.fit._joint`: with one seen face the in-plane axes come from
the rectangle of that face's shots. Lengths in metres, directions unit vectors.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._vectors import unit_rows

__all__ = ["min_area_rectangle"]


def _hull_2d(xy: np.ndarray) -> np.ndarray:
    """Convex hull (Andrew's monotone chain) of points (n, 2); vertices (h, 2) counter-clockwise."""
    pts = np.unique(xy, axis=0)
    if pts.shape[0] < 3:
        return pts

    def half(seq):
        out: list[np.ndarray] = []
        for p in seq:
            while len(out) >= 2:
                a, b = out[-2], out[-1]
                if (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def min_area_rectangle(xy: np.ndarray) -> np.ndarray:
    """Direction of the minimum-area bounding rectangle of points (n, 2) (rotating calipers).

    One rectangle side is collinear with a hull edge (Freeman and Shapira 1975), so every hull
    edge direction is tried.

    Returns
    -------
    ndarray, shape (2, 2)
        Rows: the rectangle's two unit side directions (right-handed).
    """
    hull = _hull_2d(xy)
    if hull.shape[0] < 3:
        spread = xy - xy.mean(axis=0)
        _, _, vt = np.linalg.svd(spread, full_matrices=True)
        first = vt[0]
    else:
        edges, ok = unit_rows(np.roll(hull, -1, axis=0) - hull)
        edges = edges[ok]
        perp = np.stack([-edges[:, 1], edges[:, 0]], axis=1)
        u = hull @ edges.T
        v = hull @ perp.T
        area = (u.max(axis=0) - u.min(axis=0)) * (v.max(axis=0) - v.min(axis=0))
        first = edges[int(np.argmin(area))]
    return np.array([first, [-first[1], first[0]]])
