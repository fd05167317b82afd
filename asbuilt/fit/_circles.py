"""Robust circle starts for the cylinder fit: the circle across each candidate axis.

Private helper of :mod:`asbuilt.fit.cylinder`. For a candidate axis the points are projected on
the plane perpendicular to it; a pipe's shots then lie on a circle (background shots off it).
Everything here is batched over many candidate axes at once; lengths in metres.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._common import basis_floats
from asbuilt.fit._small_linalg import solve

__all__ = ["circle_starts", "kasa_batch", "INSIDE_CAP"]

#: In MSAC costs (``cutoff`` given), a shot between 1 and this many cutoffs inside a circle
#: keeps its full square instead of the outlier's capped one: no beam reaches the inside of a
#: pipe, so such shots are evidence against the circle, not background. Deeper ones are left
#: to the cap: a mixed return from a wide footprint can land anywhere along its beam.
INSIDE_CAP = 4.0


def _kasa_design(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The Kasa least-squares system's rows ``(x, y, 1, -(x^2 + y^2))``, shape (a, n, 4), from
    the projections' coordinates ``x``, ``y`` (a, n), metres."""
    design = np.empty(x.shape + (4,))
    design[:, :, 0] = x
    design[:, :, 1] = y
    design[:, :, 2] = 1.0
    np.negative(x * x + y * y, out=design[:, :, 3])
    return design


def kasa_batch(xy: np.ndarray, weights: np.ndarray, design: np.ndarray | None = None):
    """Weighted Kasa circles (Kasa 1976) for a batch of projections.

    Parameters
    ----------
    xy : ndarray, shape (a, n, 2), metres, or None
        The projections (unused, and may be None, when ``design`` is given).
    weights : ndarray, shape (a, n)
    design : ndarray, shape (a, n, 4), optional
        ``_kasa_design(x, y)`` when the caller has it already.

    Returns
    -------
    center : ndarray, shape (a, 2), metres
    radius : ndarray, shape (a,), metres (NaN where undefined)
    """
    if design is None:
        design = _kasa_design(xy[:, :, 0], xy[:, :, 1])
    # One product gives the normal matrix (first three columns) and the right-hand side.
    system = (design.transpose(0, 2, 1) * weights[:, None, :]) @ design
    normal, right = system[:, :3, :3], system[:, :3, 3:]
    try:
        solution = solve(normal, right)[:, :, 0]
    except np.linalg.LinAlgError:
        # Some projections are degenerate (points on a line across the axis): no circle there.
        singular = np.linalg.svd(normal, compute_uv=False)
        degenerate = singular[:, -1] <= 1e-12 * singular[:, 0]
        solution = (np.linalg.pinv(normal) @ right)[:, :, 0]
        solution[degenerate] = np.nan
    center = -0.5 * solution[:, :2]
    cx, cy = center[:, 0], center[:, 1]
    squared = cx * cx + cy * cy - solution[:, 2]
    # NaN where not positive (no real circle); ``where=`` instead of an errstate block, which
    # costs more than the root itself on a few axes.
    radius = np.full(squared.shape, np.nan)
    np.sqrt(squared, out=radius, where=squared > 0)
    return center, radius


def _norm2(dx: np.ndarray, dy: np.ndarray) -> np.ndarray:
    """``sqrt(dx^2 + dy^2)`` in place in ``dx`` (which must be a fresh array); several times
    faster than :func:`numpy.hypot`, whose overflow care the centred points do not need."""
    dx *= dx
    dy *= dy
    dx += dy
    return np.sqrt(dx, out=dx)


def circle_starts(
    points: np.ndarray,
    axes: list,
    keep: int,
    rng,
    samples: int = 24,
    keep_invalid: bool = False,
    cutoff: float | None = None,
    inside: bool = True,
):
    """Centre and radius for each candidate axis, robust to background shots.

    For every axis (all at once, vectorised), the points are projected on the plane across it;
    the Kasa circle of all of them and the best circumcircle of random point triples (by
    trimmed cost, a RANSAC-style start: Fischler & Bolles 1981) compete by trimmed cost, and the
    winner is polished by two least-trimmed-squares concentration steps (Rousseeuw & Van
    Driessen 2006: the Kasa circle of the ``keep`` points closest to the current circle).

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres (centred)
    axes : list of ndarray, shape (3,)
    keep : int
    rng : numpy.random.Generator
    samples : int
        Random triples per axis.
    keep_invalid : bool
        Return a state for every axis (cost infinite where no circle was found) instead of
        dropping those.
    cutoff : float, optional, metres
        When given, circles compete by MSAC cost (Torr & Zisserman 2000: ``sum min(d^2,
        cutoff^2)``, except that shots 1 to ``INSIDE_CAP`` cutoffs inside the circle count in
        full) and are polished on the points within ``cutoff`` instead: the trimmed
        cost keeps ``keep`` points, so when more than ``n - keep`` shots are background (whole
        raster lines on the wall behind a pipe) it prefers a large circle through pipe and
        wall shots alike.
    inside : bool
        With ``cutoff``: whether shots 1 to ``INSIDE_CAP`` cutoffs inside a circle count in
        full (the cylinder fit asks this only without a viewpoint, where nothing else says
        that a shot lies inside the pipe; with one, the beams do). Plain MSAC otherwise.

    Returns
    -------
    states : list of (axis, center (3,), radius)
    costs : list of float
        Each state's least-trimmed-squares cost (the projected circle distances are the
        cylinder's orthogonal residuals).
    """
    n = len(points)
    keep = min(keep, n)
    count = len(axes)
    axis_array = np.asarray(axes, dtype=np.float64)
    # Every axis's u, then every v (orthonormal_bases' floats), built as one array.
    bases = [basis_floats(*axis) for axis in axis_array.tolist()]
    frame = np.array(([basis[:3] for basis in bases], [basis[3:] for basis in bases]))
    u, v = frame[0], frame[1]
    projected = points @ frame.reshape(2 * count, 3).T  # (n, 2a): every u, then every v
    # Contiguous (a, n) coordinates: numpy is several times slower on strided views.
    coordinates = np.ascontiguousarray(projected.T).reshape(2, count, n)
    x, y = coordinates[0], coordinates[1]  # (indexing costs less than unpacking)
    design = _kasa_design(x, y)
    rows = np.arange(count)

    def signed(center, radius):
        distance = _norm2(x - center[:, :1], y - center[:, 1:])
        distance -= radius[:, None]
        return distance

    def distances(center, radius):
        distance = signed(center, radius)
        np.abs(distance, out=distance)
        # NaN (no circle) to infinity; the rest are >= 0 or infinite, which fmin keeps.
        np.fmin(distance, np.inf, out=distance)
        return distance

    def msac(distance, scratch=None):
        # Signed distances (negative inside), overwritten. A shot 1 to INSIDE_CAP cutoffs
        # inside the circle keeps its full square: background explains a shot outside a pipe,
        # nothing explains one inside it. NaN (no circle) costs a cutoff, as an outlier.
        # In place (``scratch``, like ``distance``, takes the capped squares): on the (a, t, n)
        # triples' distances fresh temporaries cost more than the arithmetic.
        if not inside:
            squared = np.multiply(distance, distance, out=distance)
            return np.fmin(squared, cutoff * cutoff, out=squared).sum(axis=-1)
        shallow = distance < -cutoff
        shallow &= distance >= -INSIDE_CAP * cutoff
        squared = np.multiply(distance, distance, out=distance)
        capped = np.fmin(squared, cutoff * cutoff, out=scratch)
        np.copyto(capped, squared, where=shallow)
        return capped.sum(axis=-1)

    def cost_of(center, radius):
        if cutoff is not None:
            return msac(signed(center, radius))
        # In place on the temporary squares (np.partition would copy them first).
        distance = distances(center, radius)
        squared = np.multiply(distance, distance, out=distance)
        squared.partition(keep - 1, axis=1)
        return squared[:, :keep].sum(axis=1)

    center, radius = kasa_batch(None, np.ones((count, n)), design)
    cost = cost_of(center, radius)
    # Circumcircles of random triples, shared across axes.
    index = rng.integers(0, n, (samples, 3))
    # Every corner's coordinates in one gather, as contiguous (a, t) blocks (numpy is slower
    # on the strided ones the gather itself gives).
    corners = np.ascontiguousarray(coordinates[:, :, index.T].transpose(0, 2, 1, 3))
    xs, ys = corners[0], corners[1]
    ax_, bx, cx, ay_, by, cy = xs[0], xs[1], xs[2], ys[0], ys[1], ys[2]
    bcy, cay, aby = by - cy, cy - ay_, ay_ - by
    det = 2.0 * (ax_ * bcy + bx * cay + cx * aby)
    sa, sb, sc = ax_ * ax_ + ay_ * ay_, bx * bx + by * by, cx * cx + cy * cy
    with np.errstate(divide="ignore", invalid="ignore"):
        ux = (sa * bcy + sb * cay + sc * aby) / det
        uy = (sa * (cx - bx) + sb * (ax_ - cx) + sc * (bx - ax_)) / det
        tr = _norm2(ax_ - ux, ay_ - uy)
        dy = y[:, None, :] - uy[..., None]  # squared by _norm2, then the MSAC's scratch
        sq = _norm2(x[:, None, :] - ux[..., None], dy)
        sq -= tr[..., None]
        if cutoff is None:
            sq *= sq
    # NaN (collinear or repeated triples) costs a cutoff in MSAC, infinity in the trimmed cost;
    # the latter in place on the (a, t, n) squares, the largest arrays of the fit.
    if cutoff is not None:
        tcost = msac(sq, dy)  # (a, t)
    else:
        np.fmin(sq, np.inf, out=sq)
        sq.partition(keep - 1, axis=2)
        tcost = sq[:, :, :keep].sum(axis=2)  # (a, t)
    best = np.argmin(tcost, axis=1)
    better = tcost[rows, best] < np.where(np.isfinite(cost), cost, np.inf)
    chosen = np.empty((count, 2))
    chosen[:, 0], chosen[:, 1] = ux[rows, best], uy[rows, best]
    center = np.where(better[:, None], chosen, center)
    radius = np.where(better, tr[rows, best], radius)
    weights = np.empty((count, n))
    for _ in range(2):
        if cutoff is not None:
            weights[:] = distances(center, radius) <= cutoff
        else:
            closest = distances(center, radius).argpartition(keep - 1, axis=1)[:, :keep]
            weights.fill(0.0)
            weights[rows[:, None], closest] = 1.0
        new_center, new_radius = kasa_batch(None, weights, design)
        ok = np.isfinite(new_radius)
        center = np.where(ok[:, None], new_center, center)
        radius = np.where(ok, new_radius, radius)
    cost = cost_of(center, radius)
    centroid = points.sum(axis=0) / n  # points.mean(axis=0), as numpy computes it
    middles = center[:, :1] * u + center[:, 1:] * v + (axis_array @ centroid)[:, None] * axis_array
    valid = np.isfinite(radius) & (radius > 0) & np.isfinite(middles).all(axis=1)
    if keep_invalid:
        costs = np.where(valid, cost, np.inf).tolist()
        return [(axes[k], middles[k], float(radius[k])) for k in range(count)], costs
    keep_rows = np.flatnonzero(valid).tolist()
    radii, costs = radius.tolist(), cost.tolist()
    return [(axes[k], middles[k], radii[k]) for k in keep_rows], [costs[k] for k in keep_rows]
