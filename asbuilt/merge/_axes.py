"""Geometry of pipe axes for the joint search: ends, closest points, how far axes may miss.

Private helper of :mod:`asbuilt.merge.contiguity` (which keeps these names in its ``__all__``):
the end points and outward directions of fitted pipes (:func:`pipe_ends`), the closest points
of two axis lines (:func:`line_closest_points`), the distance between two axis segments
(:func:`segment_distance`) and how far apart two axes may pass and still meet
(:func:`skew_tolerance`). Numpy only; metres.
"""

from __future__ import annotations

import numpy as np

from .crossing import segment_closest


def pipe_ends(centers: np.ndarray, axes: np.ndarray, lengths: np.ndarray):
    """End points and outward directions of pipes.

    Parameters
    ----------
    centers : ndarray, shape (n, 3), metres
    axes : ndarray, shape (n, 3), unit
    lengths : ndarray, shape (n,), metres

    Returns
    -------
    points : ndarray, shape (n, 2, 3), metres
        ``points[i, 0] = c - L/2 a`` and ``points[i, 1] = c + L/2 a``.
    outward : ndarray, shape (n, 2, 3)
        Unit vectors pointing out of the pipe at each end (``-a`` and ``+a``).
    """
    half = 0.5 * lengths[:, None] * axes
    points = np.stack([centers - half, centers + half], axis=1)
    outward = np.stack([-axes, axes], axis=1)
    return points, outward


def line_closest_points(p1, d1, p2, d2):
    """Closest points of two lines ``p1 + s d1`` and ``p2 + t d2`` (points (3,) m, unit d).

    Returns ``(s, t, q1, q2)``; for parallel lines ``s = 0`` and ``t`` projects ``p1``.
    """
    w = p1 - p2
    b = float(d1 @ d2)
    d = float(d1 @ w)
    e = float(d2 @ w)
    denom = 1.0 - b * b
    if denom < 1e-12:
        s, t = 0.0, e
    else:
        s = (b * e - d) / denom
        t = (e - b * d) / denom
    return s, t, p1 + s * d1, p2 + t * d2


def skew_tolerance(radius_a: float, radius_b: float) -> float:
    """How far apart (metres) two axes may pass and still meet: max(0.5 r_min, 10 mm)."""
    return max(0.5 * min(radius_a, radius_b), 0.010)


def segment_distance(p0, p1, q0, q1) -> float:
    """Closest distance (metres) between segments ``p0 p1`` and ``q0 q1`` (points (3,) m)."""
    return segment_closest(p0, p1, q0, q1)[0]
