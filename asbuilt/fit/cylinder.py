"""Cylinder fit for sparse scans of pipes and columns: partial arcs, short stubs, edge outliers.

Method
------
1. Axis starts: the direction most perpendicular to the local surface normals (smallest
   eigenvector of ``sum n n^T`` over k-nearest-neighbour PCA normals, Hoppe et al. 1992, with a
   Tukey reweighting against normals spoiled by outliers) and its other eigenvectors, the
   points' principal directions, the cross products of the normals of the three best two-point
   samples (Schnabel, Wahl & Klein 2007; short stubs, whose principal direction is across the axis),
   and a robust line through the points (long thin pipes with background shots).
2. For each start, a robust circle in the plane perpendicular to the axis gives the centre and
   radius: the Kasa (1976) algebraic circle or the best circumcircle of random triples, polished
   by least-trimmed-squares concentration steps. Below ``POLISH_BELOW`` points the best start's
   axis is also refined by a pattern search on that circle's trimmed cost.
3. Geometric least squares over five parameters (two axis tilts, two across-axis centre
   offsets, the radius) minimising the orthogonal distances ``|P_perp (p - c)| - r``
   (Lukacs, Marshall & Martin 1998, "Faithful least-squares fitting of spheres, cylinders,
   cones and tori"; Eberly, "Fitting 3D data with a cylinder"), by Gauss-Newton with an
   analytic Jacobian, wrapped in the robust scheme of
   :func:`asbuilt.fit._common.robust_geometric_fit` (concentration steps from the best starts,
   MSAC choice, then least squares on the inliers). The normal-based start and the best other
   one are both refined unless that is redundant (:func:`_trust_order`: the same hypothesis
   twice, or a normal-based start far worse and far off).
4. When the viewpoint is known and the fit is in doubt (a sparse scan, rejected shots, or a beam
   that would have passed through the fitted pipe), the best starts are settled again and the
   shots' beams decide (:mod:`asbuilt.fit._visibility`): a fit that explains some shots only by
   placing them on its own far side, behind it along their beams, pays for them as outliers.
5. Shots on the far side of a pipe seen from one side are rejected (a station cannot see them:
   they are background shots that landed on the infinite cylinder), and the inliers are refitted
   with weights from a fitted incidence noise model (range noise along the beam makes grazing
   shots more precise than square-on ones).

The geometric estimate is the final one: algebraic circle fits alone are biased on partial arcs.
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._circles import INSIDE_CAP, circle_starts
from asbuilt.fit._common import (
    GeometricModel,
    RobustFit,
    arc_coverage_deg,
    basis_floats,
    check_spread,
    covariance_from_jacobian,
    gauss_newton,
    incidence_variance,
    keep_count,
    local_normals,
    median_spacing,
    mixture_score,
    noise_level,
    orient,
    orthonormal_basis,
    principal_axes,
    quick_median,
    random_subset,
    robust_geometric_fit,
    robust_scale,
    settled_fit,
    stderr_of,
    tukey_weights,
    validate_points,
)
from asbuilt.fit._visibility import (
    cylinder_beam_excess,
    edge_on_degrees,
    one_side_could_see,
    reconsidered,
)
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Cylinder
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = ["fit_cylinder", "METHOD"]

METHOD = (
    "normal-based axis starts + Kasa circle + robust geometric Gauss-Newton on orthogonal "
    "distances (Lukacs, Marshall & Martin 1998)"
)


# State: (axis (3,), centre on the axis (3,), radius).

_FRAME_CACHE: dict[bytes, tuple] = {}


def _frame(axis: np.ndarray):
    """``(u, v, frame, u_and_v)`` for an axis: its :func:`orthonormal_basis`, the (3, 3) matrix
    whose columns are ``axis, u, v``, and ``u, v`` as Python floats (six of them, for
    :func:`_update`'s scalar arithmetic). Gauss-Newton asks for the same axis several times
    (the Jacobian at a state, then the update from it), so the last few frames are
    remembered."""
    key = axis.tobytes()
    found = _FRAME_CACHE.get(key)
    if found is None:
        floats = basis_floats(*axis.tolist())
        u, v = np.array(floats[:3]), np.array(floats[3:])
        found = (u, v, np.array((axis, u, v)).T, floats)
        if len(_FRAME_CACHE) >= 8:
            _FRAME_CACHE.clear()
        _FRAME_CACHE[key] = found
    return found


def _residuals(state, points):
    axis, center, radius = state
    across = (points - center) @ _frame(axis)[2][:, 1:]
    return np.sqrt(np.einsum("ij,ij->i", across, across)) - radius


def _jacobian(state, points):
    axis, center, radius = state
    local = (points - center) @ _frame(axis)[2]
    # One-dimensional column views: numpy's per-call cost on (n, 2) views is paid per row.
    along, across_u, across_v = local[:, 0], local[:, 1], local[:, 2]
    rho = across_u * across_u
    rho += across_v * across_v
    np.sqrt(rho, out=rho)
    np.maximum(rho, 1e-300, out=rho)
    jac = np.empty((len(points), 5))
    minus = np.negative(rho)
    np.divide(across_u, minus, out=jac[:, 2])  # -(eu, ev)
    np.divide(across_v, minus, out=jac[:, 3])
    np.multiply(jac[:, 2], along, out=jac[:, 0])  # -along (eu, ev)
    np.multiply(jac[:, 3], along, out=jac[:, 1])
    jac[:, 4] = -1.0
    rho -= radius
    return rho, jac


def _update(state, delta, points, weights):
    axis, center, radius = state
    ux, uy, uz, vx, vy, vz = _frame(axis)[3]
    d0, d1, d2, d3, d4 = delta.tolist()
    # Python floats: the same operations in the same order as on the arrays (so the same
    # rounding), without a numpy call per operation on 3-vectors.
    ax, ay, az = axis.tolist()
    ax, ay, az = ax + d0 * ux + d1 * vx, ay + d0 * uy + d1 * vy, az + d0 * uz + d1 * vz
    norm = (ax * ax + ay * ay + az * az) ** 0.5
    ax, ay, az = ax / norm, ay / norm, az / norm
    cx, cy, cz = center.tolist()
    cx, cy, cz = cx + d2 * ux + d3 * vx, cy + d2 * uy + d3 * vy, cz + d2 * uz + d3 * vz
    # Slide the centre along the axis to the weighted centroid's foot (residuals unchanged),
    # which keeps the axis tilts and the centre offsets uncorrelated.
    total = float(weights.sum())
    centroid = (weights @ points) / total if total > 0 else points.mean(axis=0)
    gx, gy, gz = centroid.tolist()
    slide = (gx - cx) * ax + (gy - cy) * ay + (gz - cz) * az
    new_axis = np.array((ax, ay, az))
    new_center = np.array((cx + slide * ax, cy + slide * ay, cz + slide * az))
    return new_axis, new_center, abs(radius + d4)


_MODEL = GeometricModel(_residuals, _jacobian, _update, 5)

#: Scans with fewer points than this always get the axis pattern search (:func:`_polish_axes`)
#: on their best starts; larger ones only when the first fit rejected points (background shots
#: present), keeping the likelier of the two fits. With 20% background shots, starts several
#: degrees off otherwise converge to a wrong radius in a few percent of scenes; the search
#: costs 1-3 ms, which the 40-point speed target on clean scans cannot afford every time.
POLISH_BELOW = 35
#: Trimmed-cost ratio above which the normal-based start (the first) is taken as off ...
OFF_START = 100.0
#: ... when its axis is also more than 45 degrees from the best start's.
OFF_START_COS = float(np.cos(np.radians(45.0)))
#: Two starts are one hypothesis when their axes are within 2 degrees and their centres (across
#: the axis) and radii within 2% of the radius.
SAME_START_COS = float(np.cos(np.radians(2.0)))
SAME_START_RELATIVE = 0.02
#: How many of the best starts get the pattern search (two: with the reconsideration below a
#: third changed one cell of the benchmark by noise and cost about 1 ms with background shots).
POLISHED_STARTS = 2
#: How many of the best starts are settled again and judged by their beams when the viewpoint
#: is known (:func:`asbuilt.fit._visibility.reconsidered`).
RECONSIDERED_STARTS = 4
#: Two states are in one basin when their axes are within 5 degrees and radii within 10%.
SAME_BASIN_COS = float(np.cos(np.radians(5.0)))
SAME_BASIN_RELATIVE = 0.10
#: A cylinder this many times wider than the points' extent is, over them, nearly a plane.
PLANE_LIKE = 3.0
#: Above this many points (a dense cloud, not a sparse scan) the starts are found on this many
#: of them at random (memory and time otherwise grow with starts x samples x points).
DENSE_POINTS = 2000


def _rms(values: np.ndarray) -> float:
    """Root mean square of a 1-D array (0 when empty)."""
    return float(np.sqrt(values @ values / max(values.size, 1)))


def _same_start(one, other) -> bool:
    """Whether two starts (axis, centre, radius) are one hypothesis (``SAME_START_*``)."""
    axis, center, radius = one
    if abs(float(axis @ other[0])) < SAME_START_COS:
        return False
    scale = SAME_START_RELATIVE * max(radius, other[2])
    offset = other[1] - center
    across = offset - float(offset @ axis) * axis
    return abs(radius - other[2]) <= scale and float(np.sqrt(across @ across)) <= scale


def _stacked(states) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axes (s, 3), centres (s, 3) and radii (s,) of a list of states."""
    return (
        np.array([state[0] for state in states]),
        np.array([state[1] for state in states]),
        np.array([state[2] for state in states]),
    )


def _robust_fit(local, starts, costs, robust_from, polished, tolerances) -> RobustFit:
    """The robust fit from the starts (already polished below ``POLISH_BELOW`` points); above,
    the polished starts are tried too when the first fit rejected shots, and the likelier fit
    kept."""
    robust = robust_from(starts, costs)
    if len(local) < POLISH_BELOW:
        return robust
    if starts and not robust.inliers.all():
        # Background shots present: also try the polished starts and keep the likelier fit.
        try:
            second = robust_from(*polished(starts, costs))
        except FitError:
            second = None
        if second is not None and _likelier(second, robust, local, tolerances):
            robust = second
    return robust


def _same_basin(one, other, extent: float) -> bool:
    """Whether two states are near enough to settle in one place (``SAME_BASIN_*``): a coarser
    test than :func:`_same_start`, for choosing which starts to settle again. Two cylinders
    both wider than ``PLANE_LIKE`` times the points' ``extent`` (metres) are one basin whatever
    their axes: over the points both are nearly the same plane, along which the axis is
    unobservable."""
    if min(one[2], other[2]) > PLANE_LIKE * extent:
        return True
    if abs(float(one[0] @ other[0])) < SAME_BASIN_COS:
        return False
    return abs(one[2] - other[2]) <= SAME_BASIN_RELATIVE * max(one[2], other[2])


def _trust_order(starts: list, costs: list) -> tuple[list, list, int]:
    """The starts in the order :func:`robust_geometric_fit` trusts them and how many it must
    refine (its ``always_refine``).

    The normal-based start comes first and is refined together with the best other start
    (lowest trimmed cost), except where that pair is redundant: when the best other start is
    the same hypothesis (:func:`_same_start`), refining it again would land in the same place;
    when the normal-based start is a far worse, different one (axis more than 45 degrees off,
    trimmed cost ``OFF_START`` times higher), the best start goes first alone. Either way
    further starts are still refined while their cost is below the best refined fit's.
    """
    if len(starts) < 2:
        return starts, costs, 2
    second = 1 + int(np.argmin(costs[1:]))
    if _same_start(starts[0], starts[second]):
        return starts, costs, 1
    best = second if costs[second] < costs[0] else 0
    if (
        costs[0] > OFF_START * costs[best]
        and abs(float(starts[0][0] @ starts[best][0])) < OFF_START_COS
    ):
        order = [best] + [k for k in range(len(starts)) if k != best]
        return [starts[k] for k in order], [costs[k] for k in order], 1
    return starts, costs, 2


def _normal_axis(normals: np.ndarray, flatness: np.ndarray):
    """Eigenvectors of the Tukey-reweighted ``sum n n^T``, most perpendicular to normals first."""
    weights = 1.0 / (1.0 + flatness / max(quick_median(flatness), 1e-12))
    vectors = None
    for _ in range(2):
        scatter = (normals * weights[:, None]).T @ normals
        _, vectors = np.linalg.eigh(scatter)
        cosines = normals @ vectors[:, 0]
        scale = robust_scale(cosines, 0.02)
        weights = tukey_weights(cosines, scale)
        if np.count_nonzero(weights) < 3:
            break
    return vectors.T


def _unique(candidates, limit: float = 0.995) -> list[np.ndarray]:
    """Drop directions within ``arccos(limit)`` (about 6 degrees) of an earlier one."""
    unique: list[np.ndarray] = []
    for axis in candidates:
        if all(abs(float(axis @ other)) < limit for other in unique):
            unique.append(axis)
    return unique


def _axis_starts(points: np.ndarray, normals, flatness, directions=None) -> list[np.ndarray]:
    """The normals' eigenvectors (most perpendicular first) and the points' principal axes
    (``directions``, rows, when the caller has them already)."""
    if directions is None:
        _, _, directions = principal_axes(points)
    return _unique(list(_normal_axis(normals, flatness)) + list(directions))


def _polish_axes(
    points, states, costs, keep, rng, steps=(8.0, 4.0, 2.0, 1.0, 0.5, 0.25), cutoff=None
):
    """Pattern search on the axis (Hooke & Jeeves 1961) around each start, on the trimmed cost
    of the robust circle across each trial axis (all starts' rings in one batch per step).

    The robust circle's trimmed cost is sharp in the axis (a pipe seen over 1.8 m is smeared by
    3 cm when the axis is 1 degree off), so a start some degrees off, which a local
    least-squares descent may pull onto a background shot, is first brought within a quarter
    degree. Returns the polished (states, costs).
    """
    ring = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
    cos_ring, sin_ring = np.cos(ring)[:, None], np.sin(ring)[:, None]
    states, costs = list(states), list(costs)
    for step in steps:
        tilt = np.tan(np.radians(step))
        trials = []
        for state in states:
            u, v = orthonormal_basis(state[0])
            trial = state[0] + tilt * (cos_ring * u + sin_ring * v)
            trials.extend(trial / np.linalg.norm(trial, axis=1)[:, None])
        found, found_costs = circle_starts(
            points, trials, keep, rng, keep_invalid=True, cutoff=cutoff
        )
        for k in range(len(states)):
            block = found_costs[8 * k : 8 * k + 8]
            best = int(np.argmin(block))
            if block[best] < costs[k]:
                states[k], costs[k] = found[8 * k + best], block[best]
    return states, costs


def _line_axis(points: np.ndarray, keep: int, rng, samples: int = 32, steps: int = 1):
    """Robust principal direction: the best line through two points by trimmed cost, then
    concentration steps (principal direction of the ``keep`` points closest to the line).

    A long pipe's points lie within a radius of its axis, so this is its axis even when
    background shots far behind it spoil the ordinary principal directions.
    """
    n = len(points)
    first = rng.integers(0, n, samples)
    second = rng.integers(0, n, samples)
    direction = points[second] - points[first]
    norm = np.linalg.norm(direction, axis=1)
    good = norm > 1e-12
    if not np.any(good):
        return None
    direction = direction[good] / norm[good, None]
    base = points[first[good]]
    _, distance = _line_distances(points, base, direction)
    cost = np.partition(distance, keep - 1, axis=1)[:, :keep].sum(axis=1)
    best = int(np.argmin(cost))
    axis, point = direction[best], base[best]
    for _ in range(steps):
        rel = points - point
        along = rel @ axis
        distance = np.einsum("ij,ij->i", rel, rel) - along * along
        closest = points[np.argpartition(distance, keep - 1)[:keep]]
        point = closest.sum(axis=0) / len(closest)  # closest.mean(axis=0), less overhead
        centred = closest - point
        # Principal direction: the scatter matrix's leading eigenvector.
        axis = np.linalg.eigh(centred.T @ centred)[1][:, 2]
    return axis


def _line_distances(points: np.ndarray, base: np.ndarray, direction: np.ndarray):
    """Coordinates of points along lines and squared distances from them.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres (centred)
    base : ndarray, shape (s, 3), metres
        A point on each line.
    direction : ndarray, shape (s, 3)
        Unit directions.

    Returns
    -------
    along : ndarray, shape (s, n), metres
    squared : ndarray, shape (s, n), metres^2
        Written out as ``|p|^2 + |b|^2 - 2 p.b - along^2`` (two matrix products instead of an
        (s, n, 3) array of differences; the points are centred, so nothing cancels badly).
    """
    products = np.concatenate([direction, base]) @ points.T
    count = len(base)
    along = products[:count] - np.einsum("ij,ij->i", base, direction)[:, None]
    squared = np.einsum("ij,ij->i", points, points)[None, :] - 2.0 * products[count:]
    squared += np.einsum("ij,ij->i", base, base)[:, None]
    squared -= along * along
    return along, squared


_NEXT, _AFTER = [1, 2, 0], [2, 0, 1]
#: Two-point samples whose normals are within 10 degrees of parallel give no axis.
_PAIR_COS = float(np.cos(np.radians(10.0)))


def _pair_starts(points, normals, keep: int, count: int, samples: int = 48):
    """Minimal-sample starts (Schnabel, Wahl & Klein 2007): two points and their normals.

    The axis is the cross product of the normals, the centre the closest approach of the two
    normal lines, the radius the mean distance of the two points from that axis. Every sample
    is scored by its least-trimmed-squares cost over all points; the ``count`` best are kept.
    Shots on the background spoil their own normals, so samples of two clean points (most of
    them with 20% outliers) give starts near the true cylinder even when a fit on all points
    is dragged away.
    """
    n = len(points)
    rng = np.random.default_rng(n)
    first = rng.integers(0, n, samples)
    second = rng.integers(0, n, samples)
    d1, d2 = normals[first], normals[second]
    b = np.einsum("ij,ij->i", d1, d2)
    good = (first != second) & (np.abs(b) < _PAIR_COS)
    if not np.any(good):
        return []
    first, second, d1, d2, b = first[good], second[good], d1[good], d2[good], b[good]
    p1, p2 = points[first], points[second]
    # Cross products, written out (np.cross is slow on short stacks).
    axis = d1[:, _NEXT] * d2[:, _AFTER] - d1[:, _AFTER] * d2[:, _NEXT]
    axis /= np.sqrt(np.einsum("ij,ij->i", axis, axis))[:, None]
    w = p1 - p2
    d = np.einsum("ij,ij->i", d1, w)
    e = np.einsum("ij,ij->i", d2, w)
    denom = 1.0 - b * b
    s = (b * e - d) / denom
    t = (e - b * d) / denom
    center = 0.5 * (p1 + s[:, None] * d1 + p2 + t[:, None] * d2)
    _, squared = _line_distances(points, center, axis)
    rho = np.sqrt(np.maximum(squared, 0.0, out=squared), out=squared)
    rows = np.arange(len(first))
    radius = 0.5 * (rho[rows, first] + rho[rows, second])
    residuals = rho - radius[:, None]
    keep = min(keep, n)
    cost = np.partition(residuals * residuals, keep - 1, axis=1)[:, :keep].sum(axis=1)
    order = np.argsort(cost)[:count]
    return [axis[i] for i in order if radius[i] > 0]


def fit_cylinder(
    points,
    *,
    sigma=None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    viewpoint=None,
) -> FitResult:
    """Fit a bounded circular cylinder to points on its visible side.

    Works on partial arcs down to about 90 degrees and on stubs shorter than their diameter;
    up to ``tolerances.max_outlier_fraction`` of edge outliers are rejected and reported. See
    the module docstring for the algorithm (normal, two-point and line starts, robust circles,
    axis pattern search, robust geometric Gauss-Newton after Lukacs, Marshall & Martin 1998,
    least squares on the inliers weighted by a fitted incidence noise model).

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    sigma : float, optional, metres
        The sensor's range sigma (of a square-on shot); sets the inlier threshold and scales
        the standard errors when given.
    tolerances : Tolerances
    viewpoint : array_like, shape (3,), metres, optional
        Where the shots were taken from. When given and the fit is in doubt (:func:`_doubtful`),
        the fit is settled again from the best starts of other basins and the beams decide
        between them (a shot's beam must reach it without passing through the pipe,
        :mod:`asbuilt.fit._visibility`); a viewpoint the shots cannot have come from is ignored
        with a note.

    Returns
    -------
    FitResult
        ``primitive`` is a :class:`~asbuilt.primitives.Cylinder` whose ``center`` is the
        mid-point of the inliers' extent along the axis and ``length`` that extent. The axis
        sign follows :func:`asbuilt.fit._common.orient` (largest component positive).
        Residuals are orthogonal distances, positive outside. ``covariance`` (5 x 5) is over
        (tilt of the axis towards ``u``, tilt towards ``v`` (radians, about ``center``), centre
        offset along ``u``, along ``v`` (metres), radius (metres)) with
        ``u, v = orthonormal_basis(axis)``: ``sigma^2 (J^T W J)^-1``, ``W`` the inliers'
        weights (1 / variance relative to a square-on shot, see :func:`_incidence_weighted`;
        all 1 when the noise looks even) and ``sigma`` the square-on noise level (the sensor's,
        else the weighted residuals' RMS with the degrees of freedom corrected). ``stderr``:
        ``radius``; ``axis_deg`` (RMS axis angle error, the root of the two tilt variances);
        ``center`` (across-axis position, root of the two offset variances); ``length``
        (end-point uncertainty: each end lies somewhere between the last shot and the next
        one, so ``s / sqrt(6)`` with ``s`` the median nearest-neighbour spacing of the
        points, plus the noise and the axis-tilt effect, in quadrature). Measured against the
        scatter of repeated simulated scans (range 2 mm, angle 0.01 degree): the radius error
        is overstated by up to 1.4x at 3 m and understated by up to 1.25x at 10 m on the
        benchmark's raster, overstated up to 3.4x on rasters reaching the silhouette (oblique
        shots' noise lies mostly along the beam); see docs/fitting.md. Diagnostics: ``arc_deg`` (angular coverage of the inliers about
        the axis), ``length_over_diameter``, ``starts`` (starts tried).

    Raises
    ------
    FitError
        Too few points, identical, collinear or coplanar points, or too many outliers.
    """
    pts = validate_points(points, "cylinder")
    offset = pts.sum(axis=0) / len(pts)  # pts.mean(axis=0), without its overhead
    local = pts - offset
    everything = None
    if len(local) > DENSE_POINTS:
        # A dense cloud: the starts and the robust choice run on a random subsample (their
        # batched circles grow as starts x samples x points), and the chosen fit is then
        # settled on every point.
        rng = np.random.default_rng(len(local))
        everything, local = local, random_subset(local, DENSE_POINTS, rng)
    _, spread, directions = principal_axes(local)
    check_spread(spread, "cylinder", 3)
    normals, flatness = local_normals(local, tolerances.normal_neighbours)
    keep = keep_count(len(local), tolerances)
    starts = []
    rng = np.random.default_rng(len(local))
    axes = _axis_starts(local, normals, flatness, directions) + _pair_starts(
        local, normals, keep, 3
    )
    line = _line_axis(local, keep, rng)
    if line is not None:
        axes.append(line)
    starts, costs = circle_starts(local, axes, keep, rng)

    def robust_from(starts, costs):
        starts, costs, trusted = _trust_order(starts, costs)
        return robust_geometric_fit(
            local,
            starts,
            _MODEL,
            kind="cylinder",
            sigma=sigma,
            tolerances=tolerances,
            start_costs=costs,
            always_refine=trusted,
        )

    def polished(starts, costs):
        order = np.argsort(costs)[:POLISHED_STARTS]
        better, better_costs = _polish_axes(
            local, [starts[k] for k in order], [costs[k] for k in order], keep, rng
        )
        return starts[:1] + better + starts[1:], costs[:1] + better_costs + costs[1:]

    view = None if viewpoint is None else np.asarray(viewpoint, dtype=np.float64) - offset
    # The MSAC circles' fits, made once per kind of rescue (judged by the beams, or blind and
    # by the shots inside the pipe), when a rescue first needs them.
    msac: dict = {}

    def rescue(current, seen_from):
        blind = seen_from is None
        if blind not in msac:
            msac[blind] = _msac_fits(local, axes, sigma, tolerances, keep, rng, inside=blind)
        cutoff = tolerances.outlier_cutoff_sigma * sigma
        return _better_fit(msac[blind], current, local, seen_from, cutoff)

    if starts and len(local) < POLISH_BELOW:
        starts, costs = polished(starts, costs)
    try:
        robust = _robust_fit(local, starts, costs, robust_from, polished, tolerances)
    except FitError:
        # Too many outliers to the robust choice; with the beams to judge, the other starts
        # may still settle on the pipe, and without them the MSAC circles may.
        if sigma is None or not starts:
            raise
        if view is None:
            robust = rescue(None, None)
            if robust is None:
                raise
        else:
            robust = None
    blind, ignored_view = robust, False

    def reconsider(robust, excess):
        # The robust fit itself (settled: its concentration steps fit subsets) and the best
        # starts from other basins: one in the robust fit's basin (or an earlier seed's) would
        # settle where that one did.
        seeds = []
        known = [] if robust is None else [robust.state]
        # The points' extent, robustly: four times their median distance from their median
        # (about the full length of a pipe seen over its length; background shots ignored).
        middle = np.median(local, axis=0)
        extent = 4.0 * quick_median(np.sqrt(np.einsum("ij,ij->i", local - middle, local - middle)))
        for k in np.argsort(costs):
            if len(seeds) == RECONSIDERED_STARTS:
                break
            if not any(_same_basin(starts[k], other, extent) for other in [*known, *seeds]):
                seeds.append(starts[k])
        return reconsidered(
            robust,
            local,
            known + seeds,
            _MODEL,
            excess,
            kind="cylinder",
            sigma=sigma,
            tolerances=tolerances,
            # Sparse scans get the thorough search (hidden or rejected good shots decide their
            # fits); on denser ones the plain settle finds the pipe (benchmark) in half the time.
            thorough=len(local) < POLISH_BELOW,
        )

    if (
        view is not None
        and starts
        and (robust is None or _doubtful(robust, local, view, len(local), sigma, tolerances))
    ):
        try:
            robust = reconsider(
                robust, lambda states, x: cylinder_beam_excess(*_stacked(states), x, view)
            )
        except FitError:
            # No seed settled on the pipe: the MSAC rescue below is the last chance.
            if sigma is None or robust is not None:
                raise
            rescued = rescue(None, view)
            if rescued is None:
                raise
            robust = rescued
        rescued = None
        if (robust is None or _unseen(robust, local, view)) and sigma is not None:
            rescued = rescue(robust, view)
        if rescued is not None:
            robust = rescued
        elif blind is not None and _unseen(robust, local, view):
            # Even the best fit hides a third of the shots behind itself: the shots were not
            # taken from this viewpoint (if one station could have seen the fit of the shots
            # alone; checked below).
            robust, ignored_view = blind, True
    if (
        sigma is not None
        and robust is not None
        and everything is None
        and (
            np.mean(~robust.inliers) >= RESCUE_REJECTED
            or (
                (view is None or ignored_view)
                and not _admissible(robust, local, tolerances.outlier_cutoff_sigma * sigma)
            )
        )
    ):
        # A fifth of the shots rejected (near the background the trimmed cost can take), or,
        # without the beams to judge, shots inside the pipe: the circles chosen by MSAC get
        # their say (every shot decides).
        rescued = rescue(robust, None if ignored_view else view)
        if rescued is not None:
            robust = rescued
    if ignored_view and not _one_station_could_see(robust, local):
        # The fit of the shots alone is no pipe either (a thin pipe's front shots and the wall
        # behind it): the viewpoint is not to blame.
        raise FitError(
            "No cylinder fits these shots as seen from the viewpoint (each would hide more than"
            " a third of them behind itself), and the best fit of the shots alone could not"
            " have been seen from any one station either. Check the scan's sensor position or"
            " the object's station; if they are right, the shots are mostly background and"
            " mixed returns around a thin pipe: rescan with more shots on the pipe."
        )
    if view is not None and _edge_on(robust, local, view):
        # Shots strung along the viewpoint's own beams also say that the viewpoint is right.
        raise FitError(
            "The shots this cylinder fits were nearly all seen edge-on from the viewpoint (half"
            f" of them within {90 - EDGE_ON_DEG:g} degrees of grazing): they are returns strung"
            " along their beams (mixed pixels between a thin pipe and what lies behind it), not"
            " a pipe's surface. Rescan with more shots across the pipe, or check the station.",
        )
    if everything is not None:
        local = everything
        robust = robust_geometric_fit(
            local, [robust.state], _MODEL, kind="cylinder", sigma=sigma, tolerances=tolerances
        )
    near = robust
    robust = _drop_far_side(near, local, tolerances)
    far_side = int(np.count_nonzero(near.inliers & ~robust.inliers))
    if view is None and starts and far_side and _doubtful_blind(robust, local):
        # The far-side refit slid onto a plane: the likeliest other basin replaces it if closer
        # (a plate with shots behind it is nearly a plane; a looser cylinder is no better).
        settled = reconsider(robust, None)
        if _rms(settled.residuals[settled.inliers]) < _rms(robust.residuals[robust.inliers]):
            robust, far_side = settled, 0
    robust, relative = _incidence_weighted(robust, local)
    axis, center, radius = robust.state
    kept = local[robust.inliers]
    along = (kept - center) @ axis
    low, high = float(along.min()), float(along.max())
    length = high - low
    if length <= 0:
        raise FitError("The points must spread along the cylinder's axis to give it a length.")
    mid = center + 0.5 * (low + high) * axis
    # Noise level of a square-on shot; the inliers' weights are 1 / relative variance.
    weights = 1.0 / relative[robust.inliers]
    noise, source = noise_level(
        robust.residuals[robust.inliers] * np.sqrt(weights), 5, sigma, tolerances
    )
    # Re-express the Jacobian about the mid-point (the reported centre): shift the along-axis
    # coordinate used by the tilt columns.
    jac = robust.jacobian.copy()
    shift = 0.5 * (low + high)
    jac[:, 0] -= shift * jac[:, 2]
    jac[:, 1] -= shift * jac[:, 3]
    covariance = covariance_from_jacobian(jac * np.sqrt(weights)[:, None], noise)
    tilt_var = covariance[0, 0] + covariance[1, 1]
    spacing = median_spacing(kept)
    length_se = stderr_of(spacing**2 / 6.0 + 2.0 * noise**2 + (radius**2) * tilt_var)
    oriented = orient(axis)
    cylinder = Cylinder(mid + offset, oriented, radius, length)
    angles = _angles_about(axis, center, kept)
    stderr = {
        "radius": stderr_of(covariance[4, 4]),
        "axis_deg": float(np.degrees(stderr_of(tilt_var))),
        "center": stderr_of(covariance[2, 2] + covariance[3, 3]),
        "length": length_se,
    }
    if oriented is not axis:
        covariance = _flip_covariance(covariance, axis, oriented)
    notes = []
    if ignored_view:
        notes.append(
            "The viewpoint was ignored: more than a third of the shots would have been seen "
            "through the pipe from it (check the scan's sensor position or the station)."
        )
    outliers = int(len(pts) - robust.inliers.sum())
    if outliers:
        notes.append(
            f"{outliers} outlier point(s) rejected (beyond {tolerances.outlier_cutoff_sigma:g}"
            f" x {robust.scale * 1000:.3g} mm"
            + (f", or {far_side} on the far side of the pipe" if far_side else "")
            + ")."
        )
    diagnostics = {
        "arc_deg": arc_coverage_deg(angles),
        "length_over_diameter": length / (2.0 * radius),
        "starts": float(len(starts)),
    }
    return FitResult(
        primitive=cylinder,
        residuals=cylinder.distance(pts),
        inliers=robust.inliers,
        stderr=stderr,
        sigma=noise,
        sigma_source=source,
        method=METHOD,
        covariance=covariance,
        diagnostics=diagnostics,
        notes=tuple(notes),
    )


#: Largest noise level, as a fraction of the radius, at which the inliers are weighted by
#: incidence. Range noise lies along the beam; on a curved surface seen obliquely its sideways
#: part (second order, about noise / radius of the first) biases an orthogonal fit's radius
#: low, and weighting the oblique shots up doubles that bias and makes the standard error too
#: small (measured: NPS 2-10 pipes seen by four raster columns within 55 degrees, 2-5 mm range
#: noise). Above 1% the even-weighted fit is the safer one.
WEIGHTED_NOISE_RATIO = 0.01
#: Mean resultant length of the inliers' directions about the axis above which they are taken as
#: seen from one side (one station): 0.64 for a 180 degree arc, 0.74 for 150, 0 all round.
ONE_SIDED = 0.5
#: Angle from the seen side's mean direction beyond which a point faces away from it.
FAR_SIDE_DEG = 95.0


#: Fraction of the best fit's inliers seen through the pipe beyond which the viewpoint is taken
#: as wrong: from a wrong viewpoint about half of the shots of the true pipe are.
UNSEEN_FRACTION = 1.0 / 3.0


#: Circles (best by MSAC cost, one per candidate axis) settled by :func:`_msac_fits`, and
#: the random triples it tries per axis: MSAC needs one triple of pipe shots from three raster
#: columns, 1 in 6 triples when a third of the shots are background.
RESCUE_STARTS = 4
RESCUE_SAMPLES = 96
#: Share of rejected shots from which a fit is compared with the MSAC circles' fits. Fits that
#: rejected 20-25% were wrong in 4 of 20 independent wall-line scans with 25% (the trimmed
#: cost's design contamination); it costs the benchmark's 20%-outlier fits about 3 ms.
RESCUE_REJECTED = 0.2
#: Shots inside the fitted pipe (:func:`_inside`) from which a fit is compared with the MSAC
#: circles' fits: one good shot lies beyond 3 sigma inside with probability 0.13%, two of 40
#: in under 0.2% of scans.
INSIDE_SHOTS = 2
#: Candidate axes within this many degrees of plumb or level also get their plumb/level twin.
SNAP_DEG = 5.0


def _msac_fits(points, axes, sigma: float, tolerances, keep, rng, inside: bool) -> list:
    """Fits from circles chosen by MSAC cost (``circle_starts(cutoff=...)``), for when the
    beams reject the robust choice (it hides a third of the shots behind the pipe, or no start
    settled) or it rejected ``RESCUE_REJECTED`` of the shots: whole raster lines on the wall
    behind a pipe are more background than the trimmed cost allows, and a large circle through
    pipe and wall shots wins it. Each of the ``RESCUE_STARTS`` best circles is settled by least
    squares on its inliers; plane-like cylinders (:func:`_doubtful_blind`) are left out.
    :func:`_better_fit` chooses among them."""
    cutoff = tolerances.outlier_cutoff_sigma * sigma
    # Background shots tilt every axis estimate by a degree or two, which smears a 3 m pipe's
    # projection by centimetres; plant pipes are mostly plumb or level, so each candidate
    # within SNAP_DEG of either gets its plumb or level twin (least squares then settles the
    # axis freely).
    snapped = []
    for axis in axes:
        if abs(axis[2]) >= np.cos(np.radians(SNAP_DEG)):
            snapped.append(np.array([0.0, 0.0, 1.0]))
        elif abs(axis[2]) <= np.sin(np.radians(SNAP_DEG)):
            level = np.array([axis[0], axis[1], 0.0])
            snapped.append(level / np.linalg.norm(level))
    starts, costs = circle_starts(
        points,
        list(axes) + snapped,
        keep,
        rng,
        samples=RESCUE_SAMPLES,
        cutoff=cutoff,
        inside=inside,
    )
    order = np.argsort(costs)[:RESCUE_STARTS]
    starts, costs = [starts[k] for k in order], [costs[k] for k in order]
    if inside:
        # A candidate axis a degree off smears a long pipe's circle by centimetres and leaves
        # its flank shots inside, so without the beams the best circles' axes are searched
        # (on the same cost) before they are settled.
        starts, costs = _polish_axes(points, starts, costs, keep, rng, cutoff=cutoff)
    fits = []
    for k in range(len(starts)):
        fit = settled_fit(
            points, starts[k], _MODEL, kind="cylinder", sigma=sigma, tolerances=tolerances
        )
        # A cylinder metres wide is a plane through pipe and wall shots, not a pipe.
        if fit is not None and not _doubtful_blind(fit, points):
            fits.append(fit)
    return fits


def _inside(robust: RobustFit, points: np.ndarray, cutoff: float) -> np.ndarray:
    """Shots deeper than ``cutoff`` (metres) inside a fit's solid, within its inliers' extent
    along the axis (beyond its ends the infinite cylinder is not the pipe), shape (n,) bool.

    No beam reaches the inside of an opaque pipe, from any viewpoint: a background shot lies
    outside the pipe, and a mixed-pixel return at its silhouette at most a footprint radius
    inside. Shots well inside a fitted cylinder say that it is the wrong one (a large circle
    through the pipe's front shots and the wall behind leaves the pipe's flanks inside it).
    """
    axis, center, _ = robust.state
    along = (points - center) @ axis
    kept = along[robust.inliers]
    if kept.size == 0:
        return np.zeros(len(points), dtype=bool)
    within = (along >= kept.min() - cutoff) & (along <= kept.max() + cutoff)
    return within & (robust.residuals < -cutoff) & (robust.residuals >= -INSIDE_CAP * cutoff)


def _admissible(robust: RobustFit, points: np.ndarray, cutoff: float) -> bool:
    """Whether fewer than ``INSIDE_SHOTS`` shots lie inside the fit's pipe (:func:`_inside`)."""
    return int(np.count_nonzero(_inside(robust, points, cutoff))) < INSIDE_SHOTS


def _better_fit(candidates, robust, points, view, cutoff: float):
    """The candidate with the lowest MSAC cost (every shot, threshold ``cutoff`` metres;
    Torr & Zisserman 2000) that is consistent with the scan, if it beats ``robust``; else None.

    With ``view`` known, consistent means hiding no third of the shots behind the pipe
    (:func:`_unseen`). Without it, leaving no shots inside the pipe (:func:`_admissible`),
    and any consistent candidate beats a ``robust`` fit that is not.
    """

    def cost(fit):
        return float(np.minimum(fit.residuals**2, cutoff**2).sum())

    def consistent(fit):
        if view is None:
            return _admissible(fit, points, cutoff)
        return not _unseen(fit, points, view)

    best, best_cost = None, np.inf
    if robust is not None and (view is not None or _admissible(robust, points, cutoff)):
        best_cost = cost(robust)
    for fit in candidates:
        if cost(fit) < best_cost and consistent(fit):
            best, best_cost = fit, cost(fit)
    return best


#: Median incidence across the axis (:func:`edge_on_degrees`) of a fit's inliers above which
#: they are taken as returns strung along their beams, not a surface: half of a real pipe's
#: shots would lie within 1.5% of its radius from its silhouette. Measured: at most 76 degrees
#: over the benchmark's 4,500 cylinder fits (a wrong 20-shot fit of a thin pipe; right fits at
#: most 70), 77-88 for the mixed-pixel "pipes" metres wide fitted to an independent ray
#: caster's NPS 1 pipe 10 m away seen by three raster rows.
EDGE_ON_DEG = 80.0


def _edge_on(robust: RobustFit, points: np.ndarray, view: np.ndarray) -> bool:
    """Whether the fit's inliers were mostly seen edge-on from ``view`` (``EDGE_ON_DEG``)."""
    axis, center, _ = robust.state
    angles = edge_on_degrees(axis, center, points[robust.inliers], view)
    angles = angles[np.isfinite(angles)]
    return bool(angles.size) and float(np.median(angles)) > EDGE_ON_DEG


#: Median incidence below which a fit's inliers could have been seen from one unknown station
#: (:func:`_one_station_could_see`). A raster across a pipe samples its silhouette about evenly,
#: a median incidence near 30 degrees; a "pipe" through a thin pipe's front shots and the wall
#: behind (two clusters some 165 degrees apart) shows one cluster at 75 degrees or more from any
#: direction that faces both.
ONE_STATION_DEG = 60.0


def _one_station_could_see(robust: RobustFit, points: np.ndarray) -> bool:
    """Whether one unknown station could have seen the fit's inliers (:func:`one_side_could_see`,
    with all but ``UNSEEN_FRACTION`` of them facing it, not edge-on)."""
    axis, center, _ = robust.state
    angles = _angles_about(axis, center, points[robust.inliers])
    return one_side_could_see(angles, 1.0 - UNSEEN_FRACTION, ONE_STATION_DEG)


def _unseen(robust: RobustFit, points, view) -> bool:
    """Whether the viewpoint cannot be where the shots came from: more than ``UNSEEN_FRACTION``
    of the best fit's inliers lie beyond its pipe along their beams by more than a tenth of its
    radius (a scan whose sensor position is in another frame, or shots from several stations
    without their ``station``). Asked of the fit the beams chose, so a wrong fit hiding shots
    behind itself is not mistaken for a wrong viewpoint."""
    axis, center, radius = robust.state
    excess = cylinder_beam_excess(axis, center, radius, points[robust.inliers], view)
    return bool(np.mean(excess > 0.1 * radius) > UNSEEN_FRACTION)


def _doubtful(robust: RobustFit, points, view, count: int, sigma, tolerances: Tolerances) -> bool:
    """Whether a robust fit deserves a second look at the other starts (:func:`reconsidered`).

    Sparse scans (below ``POLISH_BELOW`` points) always do: there a subset of the shots can
    pull the choice of start into the wrong basin. Larger ones do when the fit rejected shots
    or some inlier's beam ran through the fitted pipe by more than the inlier threshold.
    """
    if count < POLISH_BELOW or not robust.inliers.all():
        return True
    threshold = tolerances.outlier_cutoff_sigma * (sigma if sigma is not None else robust.scale)
    return bool(np.any(cylinder_beam_excess(*robust.state, points, view) > threshold))


def _doubtful_blind(robust: RobustFit, points: np.ndarray) -> bool:
    """Without a viewpoint: whether a fit is nearly a plane over the points (radius above
    ``PLANE_LIKE`` times their extent): a long thin pipe's silhouette shots and the wall shots
    beyond them lie in one plane through the station, which a cylinder of kilometres fits to a
    centimetre. (Reconsidering every doubtful fit by likelihood turned stubs' axes by 90
    degrees: a likelihood with each fit's own noise rewards fitting fewer shots closely.)"""
    middle = np.median(points, axis=0)
    extent = 4.0 * quick_median(np.sqrt(np.einsum("ij,ij->i", points - middle, points - middle)))
    return robust.state[2] > PLANE_LIKE * extent


def _angles_about(axis: np.ndarray, center: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Each point's direction about the axis through ``center`` (3,) metres, in radians,
    shape (m,), measured in the frame ``orthonormal_basis(axis)``; ``points`` (m, 3) metres."""
    u, v = orthonormal_basis(axis)
    rel = points - center
    return np.arctan2(rel @ v, rel @ u)


def _mean_direction(angles: np.ndarray) -> np.ndarray:
    """The mean of the unit vectors at ``angles`` (m,) radians: ``(mean cos, mean sin)``, shape
    (2,), summed and divided as :meth:`numpy.ndarray.mean` does."""
    count = angles.size
    return np.array([np.cos(angles).sum() / count, np.sin(angles).sum() / count])


def _drop_far_side(robust: RobustFit, points: np.ndarray, tolerances: Tolerances) -> RobustFit:
    """Reject inliers on the far side of a pipe seen from one side, and refit without them.

    A station sees at most the half of a pipe that faces it. A shot that passed the pipe and hit
    the wall behind can land within millimetres of the *far* side of the (infinite) cylinder,
    where its distance alone cannot tell it from a surface point; there it would decide the
    radius. When the inliers' directions about the axis are concentrated (mean resultant length
    above ``ONE_SIDED``, circular statistics: Mardia & Jupp 2000), inliers more than
    ``FAR_SIDE_DEG`` from their mean direction are rejected and the fit is redone by least
    squares on the rest.
    """
    axis, center, _ = robust.state
    angles = _angles_about(axis, center, points)
    kept = robust.inliers
    mean = _mean_direction(angles[kept])
    resultant = float(np.hypot(*mean))
    if resultant <= ONE_SIDED:
        return robust
    offset = np.angle(np.exp(1j * (angles - np.arctan2(mean[1], mean[0]))))
    far = kept & (np.abs(offset) > np.radians(FAR_SIDE_DEG))
    if not far.any():
        return robust
    mask = kept & ~far
    if np.count_nonzero(mask) <= _MODEL.n_params:
        return robust
    weights = mask.astype(np.float64)
    state, residuals, jacobian = gauss_newton(
        _MODEL, robust.state, points, lambda _r, w=weights: w, 50, 1e-9
    )
    return RobustFit(state, residuals, mask, jacobian[mask], robust.scale)


def _incidence_weighted(robust: RobustFit, points: np.ndarray) -> tuple[RobustFit, np.ndarray]:
    """Refit the inliers by weighted least squares with a fitted incidence noise model.

    For a pipe seen from one side by a distant station, the cosine of a shot's incidence is
    proportional to ``cos(phi - phi0)``, ``phi`` its direction about the axis and ``phi0`` the
    seen side's mean direction; :func:`asbuilt.fit._common.incidence_variance` fits the noise
    model ``A + B cos^2`` and the fit is redone with weights ``1 / (A + B cos^2)``. At 3 m the
    grazing shots are several times more precise than square-on ones and weighting brings the
    radius error of a 0.6 m pipe from about 1.2 to about 1.05 times the Cramer-Rao bound
    (measured). With even noise (as at 10 m), a pipe seen all round, or a noise level above
    ``WEIGHTED_NOISE_RATIO`` of the radius (thin pipes, where the range noise's sideways part
    biases the radius and weighting would make that worse) the weights are 1.

    Returns the refitted RobustFit (same inliers) and each point's variance relative to a
    square-on shot, shape (n,).
    """
    n = len(points)
    uniform = np.ones(n)
    axis, center, radius = robust.state
    if robust.scale > WEIGHTED_NOISE_RATIO * radius:
        return robust, uniform
    angles = _angles_about(axis, center, points)
    kept = robust.inliers
    mean = _mean_direction(angles[kept])
    if float(np.hypot(*mean)) <= ONE_SIDED or np.count_nonzero(kept) < 8:
        return robust, uniform
    square_on = np.cos(angles - np.arctan2(mean[1], mean[0])) ** 2
    relative = incidence_variance(robust.residuals, square_on, kept)
    if relative is None:
        return robust, uniform
    weights = np.where(kept, 1.0 / relative, 0.0)
    # With every point an inlier, the fit's Jacobian is the full one at its state.
    current = (robust.residuals, robust.jacobian) if kept.all() else None
    state, residuals, jacobian = gauss_newton(
        _MODEL, robust.state, points, lambda _r, w=weights: w, 6, 1e-7, current
    )
    return RobustFit(state, residuals, kept, jacobian[kept], robust.scale), relative


def _likelier(first, second, points, tolerances: Tolerances) -> bool:
    """Whether robust fit ``first`` explains the points better than ``second``: mixture
    likelihood of Gaussian inliers (own sigma) and uniform outliers over the points' extent."""
    extent = float(np.linalg.norm(np.ptp(points, axis=0)))
    floor = tolerances.sigma_floor
    one = mixture_score(first.residuals, first.inliers, extent, floor)
    two = mixture_score(second.residuals, second.inliers, extent, floor)
    return one < two


def _flip_covariance(covariance, axis, oriented):
    """Express the covariance in the basis of the oriented (possibly negated) axis."""
    u_old, v_old = orthonormal_basis(axis)
    u_new, v_new = orthonormal_basis(oriented)
    rotation = np.array([[u_new @ u_old, u_new @ v_old], [v_new @ u_old, v_new @ v_old]])
    transform = np.eye(5)
    transform[0:2, 0:2] = -rotation
    transform[2:4, 2:4] = rotation
    return transform @ covariance @ transform.T
