"""Unseen cuboid edges from the pan-tilt raster's silhouette window.

Private helper of :mod:`asbuilt.fit.cuboid`. A pan-tilt range finder records each point as
``station + range * direction(pan, tilt)`` with the *nominal* raster angles, so seen from the
station the points' directions fall exactly on the raster's columns (one pan each) and rows (one
tilt each), whatever the range noise. The operator's raster spans the object's angular window
with shots at the cells' centres (``asbuilt.sim.sensor``: ``EDGE_INSET`` = 0.5, the outer shots
half a raster step inside the silhouette), so the window is the points' angular extent widened by
half a step on each side. An edge no seen face bounds (the far side of a face, a column's top and
bottom) is then placed where the box's silhouette touches that window, instead of at the last
point, which stops short of it by up to a raster step.

Everything here is numpy; angles in radians, lengths in metres.
"""

from __future__ import annotations

import numpy as np

__all__ = ["raster_window", "solve_bounds"]

#: Samples per box edge when measuring the box's angular extent (the tilt extreme of a convex
#: box can lie inside an edge).
_EDGE_SAMPLES = 9
#: A line of shots is this much narrower than the raster step (relative) or it is not a raster.
_LINE_WIDTH = 0.02
#: Gaps between raster lines must be whole multiples of the step within this fraction.
_STEP_MULTIPLE = 0.15
#: Silhouette fit weights: window sides matched to 0.1 mrad, bounds kept within 0.1 m of their
#: start (a raster step at most) unless the window needs them moved.
_ANGLE_TOL = 1e-4
_PRIOR_M = 0.1


def _angles(points: np.ndarray, viewpoint: np.ndarray, pan0: float) -> np.ndarray:
    """Pan (relative to ``pan0``) and tilt of points (k, 3) seen from ``viewpoint``; (k, 2) rad."""
    rel = points - viewpoint
    pan = np.arctan2(rel[:, 1], rel[:, 0]) - pan0
    pan = (pan + np.pi) % (2.0 * np.pi) - np.pi
    tilt = np.arctan2(rel[:, 2], np.hypot(rel[:, 0], rel[:, 1]))
    return np.column_stack([pan, tilt])


def _grid_step(values: np.ndarray) -> float | None:
    """Raster step (radians) of 1-D angles falling on evenly spaced lines; None if they do not."""
    ordered = np.sort(values)
    gaps = np.diff(ordered)
    if gaps.size == 0 or gaps.max() <= 0.0:
        return None
    big = gaps > 0.25 * gaps.max()
    step = float(gaps[big].min())
    multiple = gaps[big] / step
    if np.any(np.abs(multiple - np.round(multiple)) > _STEP_MULTIPLE):
        return None
    # Width of each line of shots (sum of the small gaps between its members).
    line_id = np.concatenate([[0], np.cumsum(big)])
    width = np.zeros(line_id[-1] + 1)
    np.add.at(width, line_id[1:], np.where(big, 0.0, gaps))
    if width.max() > _LINE_WIDTH * step:
        return None
    return step


def raster_window(points: np.ndarray, viewpoint: np.ndarray):
    """The raster's angular window, if the points are a pan-tilt raster shot from ``viewpoint``.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
        All measured points (outliers too: their directions are still raster directions).
    viewpoint : ndarray, shape (3,), metres

    Returns
    -------
    tuple or None
        ``(pan0, window)``: the reference pan (radians) and ``window`` shape (4,) radians,
        ``[pan_min, pan_max, tilt_min, tilt_max]`` with pan relative to ``pan0``; None when the
        directions from ``viewpoint`` do not fall on at least two evenly spaced columns and rows.
    """
    rel = points - viewpoint
    if np.any(np.linalg.norm(rel, axis=1) < 1e-6):
        return None
    mean = rel.mean(axis=0)
    pan0 = float(np.arctan2(mean[1], mean[0]))
    ang = _angles(points, viewpoint, pan0)
    steps = [_grid_step(ang[:, j]) for j in range(2)]
    if steps[0] is None or steps[1] is None:
        return None
    window = np.array(
        [
            ang[:, 0].min() - 0.5 * steps[0],
            ang[:, 0].max() + 0.5 * steps[0],
            ang[:, 1].min() - 0.5 * steps[1],
            ang[:, 1].max() + 0.5 * steps[1],
        ]
    )
    return pan0, window


def _edge_fractions() -> np.ndarray:
    """Fractions (m, 3) in [0, 1]^3 sampling the 12 edges of the unit cube."""
    t = np.linspace(0.0, 1.0, _EDGE_SAMPLES)
    rows = []
    for k in range(3):
        a, b = [j for j in range(3) if j != k]
        for fa in (0.0, 1.0):
            for fb in (0.0, 1.0):
                block = np.zeros((t.size, 3))
                block[:, k] = t
                block[:, a] = fa
                block[:, b] = fb
                rows.append(block)
    return np.unique(np.concatenate(rows), axis=0)


_FRACTIONS = _edge_fractions()


def _extent(lo, hi, axes, origin, viewpoint, pan0) -> np.ndarray:
    """Angular extent [pan_min, pan_max, tilt_min, tilt_max] (4,) of the box lo..hi (local)."""
    return _extents(lo[None, :], hi[None, :], axes, origin, viewpoint, pan0)[0]


def _extents(lo, hi, axes, origin, viewpoint, pan0) -> np.ndarray:
    """Angular extents (b, 4) of b boxes given by bounds lo, hi (b, 3) in one batch."""
    local = lo[:, None, :] + _FRACTIONS[None, :, :] * (hi - lo)[:, None, :]
    world = origin + local.reshape(-1, 3) @ axes
    ang = _angles(world, viewpoint, pan0).reshape(lo.shape[0], -1, 2)
    return np.concatenate([ang.min(axis=1), ang.max(axis=1)], axis=1)[:, [0, 2, 1, 3]]


def solve_bounds(lo, hi, free, axes, origin, viewpoint, pan0, window, iterations=10):
    """Move the free bounds so that the box's angular extent matches the raster window.

    Parameters
    ----------
    lo, hi : ndarray, shape (3,), metres
        Box bounds along each row of ``axes`` (local coordinates about ``origin``).
    free : list of (int, int)
        The bounds to adjust: (axis, 0 for lo or 1 for hi).
    axes : ndarray, shape (3, 3)
        Rows: the box's unit axes.
    origin : ndarray, shape (3,), metres
    viewpoint : ndarray, shape (3,), metres
    pan0 : float, radians
    window : ndarray, shape (4,), radians
    iterations : int
        Gauss-Newton iterations (forward-difference Jacobian evaluated at the first and fourth
        iterate) of the window misfit plus a weak pull of each bound to its start value.

    Returns
    -------
    lo, hi : ndarray, shape (3,), metres
        The adjusted bounds (copies).
    """
    lo, hi = np.array(lo, float), np.array(hi, float)
    if not free:
        return lo, hi
    eps = 1e-6
    jac = None
    count = len(free)
    start = np.array([(hi if side else lo)[k] for k, side in free])
    # Weights: window sides to _ANGLE_TOL, bounds held to their start within _PRIOR_M, so that
    # bounds the window does not determine (several meeting at one silhouette corner) take the
    # smallest change.
    prior = np.eye(count) / _PRIOR_M**2
    for it in range(iterations):
        if jac is None or it == 3:
            # Chord method: the Jacobian of the first iterate (refreshed once) serves them all;
            # the box and its perturbed copies are measured in one batch.
            los, his = (
                np.repeat(lo[None], count + 1, axis=0),
                np.repeat(hi[None], count + 1, axis=0),
            )
            for c, (k, side) in enumerate(free):
                (his if side else los)[c + 1, k] += eps
            measured = _extents(los, his, axes, origin, viewpoint, pan0)
            base = measured[0]
            jac = ((measured[1:] - base) / eps).T / _ANGLE_TOL
            inverse = np.linalg.inv(jac.T @ jac + prior)
        else:
            base = _extent(lo, hi, axes, origin, viewpoint, pan0)
        now = np.array([(hi if side else lo)[k] for k, side in free])
        gradient = jac.T @ ((base - window) / _ANGLE_TOL) + prior @ (now - start)
        delta = -inverse @ gradient
        for c, (k, side) in enumerate(free):
            (hi if side else lo)[k] += delta[c]
        if np.abs(delta).max() < 1e-7:
            break
    return lo, hi
