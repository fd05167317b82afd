"""Plane fit: total least squares (orthogonal distances), robust to edge outliers.

Method
------
The plane minimising the sum of squared *orthogonal* distances passes through the centroid and
is normal to the smallest right-singular vector of the centred points (Pearson 1901, "On lines
and planes of closest fit"; orthogonal regression). Unlike ``z = A x + B y + C`` it treats the
three coordinates alike, so vertical walls are fitted as well as floors.

Robustness: starts from the all-points plane and from the best of random point triples by
trimmed cost (Fischler & Bolles 1981), concentration steps, then the exact SVD plane of the
inliers (see :func:`asbuilt.fit._robust.robust_geometric_fit`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from asbuilt.errors import FitError
from asbuilt.fit._common import (
    covariance_from_jacobian,
    noise_level,
    orient,
    orthonormal_basis,
    principal_axes,
    require_spread,
    scoring_subset,
    stderr_of,
    validate_points,
)
from asbuilt.fit._mixture import mixture_score
from asbuilt.fit._robust import (
    GeometricModel,
    RobustFit,
    keep_count,
    likelier,
    robust_geometric_fit,
    settled_fit,
)
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Plane
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = ["fit_plane", "plane_outline", "METHOD"]

METHOD = "total least squares by SVD (Pearson 1901) on robustly chosen inliers"


# State: (unit normal (3,), point on the plane (3,)).


def _residuals(state, points):
    normal, point = state
    return (points - point) @ normal


def _jacobian(state, points):
    normal, point = state
    u, v = orthonormal_basis(normal)
    rel = points - point
    jac = np.empty((len(points), 3))
    jac[:, 0] = rel @ u
    jac[:, 1] = rel @ v
    jac[:, 2] = -1.0
    return rel @ normal, jac


def _update(state, delta, points, weights):
    normal, point = state
    u, v = orthonormal_basis(normal)
    new_normal = normal + delta[0] * u + delta[1] * v
    new_normal = new_normal / np.linalg.norm(new_normal)
    new_point = point + delta[2] * normal
    total = weights.sum()
    centroid = (weights @ points) / total if total > 0 else points.mean(axis=0)
    # Slide the point within the plane to the foot of the weighted centroid.
    new_point = centroid - ((centroid - new_point) @ new_normal) * new_normal
    return new_normal, new_point


_MODEL = GeometricModel(_residuals, _jacobian, _update, 3)


def _triple_planes(points: np.ndarray, samples: int, rng, minimum: float):
    """Planes through ``samples`` random point triples of ``points`` (n, 3) metres: unit
    normals (s, 3) and a point of each (s, 3) metres, leaving out triples whose cross product
    is at most ``minimum`` (m^2; degenerate); None when every triple is."""
    n = len(points)
    index = rng.integers(0, n, (samples, 3))
    a, b, c = points[index[:, 0]], points[index[:, 1]], points[index[:, 2]]
    normal = np.cross(b - a, c - a)
    norm = np.linalg.norm(normal, axis=1)
    good = norm > minimum
    if not np.any(good):
        return None
    return normal[good] / norm[good, None], a[good]


def _triple_start(points: np.ndarray, keep: int, samples: int = 48):
    rng = np.random.default_rng(len(points))
    minimum = 1e-12 * max(float(np.ptp(points, axis=0).max()), 1e-12) ** 2
    planes = _triple_planes(points, samples, rng, minimum)
    if planes is None:
        return None
    normal, a = planes
    points, keep = scoring_subset(points, keep, rng)
    distance = np.einsum("snk,sk->sn", points[None, :, :] - a[:, None, :], normal)
    cost = np.partition(distance * distance, keep - 1, axis=1)[:, :keep].sum(axis=1)
    best = int(np.argmin(cost))
    return normal[best], a[best]


def _best_supported(points: np.ndarray, sigma, tolerances: Tolerances):
    """The plane holding the most of ``points`` (n, 3) metres within the inlier cut (the best of
    up to ``SUPPORT_TRIPLES`` point triples, RANSAC: Fischler & Bolles 1981): ``(count, cutoff
    metres, state)`` with ``state = (unit normal (3,), point (3,) metres)``, or None when every
    triple is degenerate."""
    n = len(points)
    cutoff = tolerances.outlier_cutoff_sigma * (
        float(sigma) if sigma is not None else tolerances.prior_range_sigma
    )
    planes = _triple_planes(points, SUPPORT_TRIPLES, np.random.default_rng(n), 0.0)
    if planes is None:
        return None
    normal, a = planes
    offsets = np.einsum("sk,sk->s", a, normal)
    most, best = -1, 0
    # In chunks of triples, so a dense object's distances stay a few megabytes.
    chunk = max(1, 2_000_000 // n)
    for start in range(0, len(normal), chunk):
        distance = np.abs(points @ normal[start : start + chunk].T - offsets[start : start + chunk])
        counts = (distance <= cutoff).sum(axis=0)
        k = int(counts.argmax())
        if counts[k] > most:
            most, best = int(counts[k]), start + k
    return most, cutoff, (normal[best], a[best])


def _support_fit(points: np.ndarray, sigma, tolerances: Tolerances, rival: RobustFit | None = None):
    """The plane that holds the most ``points`` (n, 3) metres (:func:`_best_supported`), settled
    by least squares on its inliers, when it holds as many as a plane fit needs; else the
    error that says how many it holds (a :class:`FitError`, returned, not raised). None when
    every triple is degenerate or the settled fit fails.

    With a ``rival`` (a fit without the sensor's sigma, whose scale the residuals set), that
    plane answers only where it explains the points better than the rival by the mixture
    likelihood of Gaussian inliers and uniform outliers (:func:`~asbuilt.fit._robust.likelier`;
    Torr's GRIC mixture): a rough surface keeps its fit, a plane through two surfaces does not.
    """
    found = _best_supported(points, sigma, tolerances)
    if found is None:
        return None
    most, cutoff, state = found
    n = len(points)
    needed = int(np.ceil((1.0 - tolerances.max_outlier_fraction) * n))
    if rival is not None:
        residuals = _residuals(state, points)
        extent = float(np.linalg.norm(np.ptp(points, axis=0)))
        floor = tolerances.sigma_floor
        inliers = np.abs(residuals) <= cutoff
        if mixture_score(residuals, inliers, extent, floor) >= mixture_score(
            rival.residuals, rival.inliers, extent, floor
        ):
            return None
    if most < needed:
        return FitError(
            f"At most {most} of the {n} points lie on one plane (within {cutoff * 1000:.3g} mm),"
            f" and a plane fit needs {needed} ({1.0 - tolerances.max_outlier_fraction:.0%}): the"
            " others are on other surfaces. Give only the points of one surface, or fit them as"
            ' kind "hull".'
        )
    settled = settled_fit(points, state, _MODEL, kind="plane", sigma=sigma, tolerances=tolerances)
    if settled is None or (rival is not None and not likelier(settled, rival, points, tolerances)):
        return None
    return settled


#: Without the sensor's sigma, a plane fit whose inliers were judged at a scale this many times
#: the prior range sigma (10 mm at 2 mm) is compared with the plane holding the most points.
ROUGH_SCALE = 5.0

#: Point triples tried by :func:`_best_supported`: a plane holding 30% of the points is among
#: them about 54 times (0.3^3 x 2,000), so the count is that of the best plane, not a near miss.
SUPPORT_TRIPLES = 2000


def plane_outline(points: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Convex outline of points projected on a plane, counter-clockwise about the normal.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    point : ndarray, shape (3,), metres
        A point on the plane.
    normal : ndarray, shape (3,)
        Unit normal.

    Returns
    -------
    ndarray, shape (k, 3), metres
        The outline's corners, on the plane (scipy.spatial.ConvexHull of the 2D projections).

    Raises
    ------
    FitError
        The projected points are collinear (no area).
    """
    u, v = orthonormal_basis(normal)  # u x v = normal: counter-clockwise in (u, v) is CCW about n
    rel = points - point
    xy = np.column_stack([rel @ u, rel @ v])
    try:
        hull = ConvexHull(xy)
    except (QhullError, ValueError):
        raise FitError(
            "The points must not be collinear; a plane needs points spread over an area."
        ) from None
    corners = xy[hull.vertices]
    area = 0.5 * float(
        np.sum(
            corners[:, 0] * np.roll(corners[:, 1], -1) - np.roll(corners[:, 0], -1) * corners[:, 1]
        )
    )
    if area < 0:
        corners = corners[::-1]
    return point + np.outer(corners[:, 0], u) + np.outer(corners[:, 1], v)


def _oriented_normal(normal: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Normal pointing from the plane towards the coordinate origin (the station of a scan)."""
    offset = float(point @ normal)
    scale = max(float(np.linalg.norm(point)), 1.0)
    if abs(offset) <= 1e-9 * scale:
        return orient(normal)
    return -normal if offset > 0 else normal


def fit_plane(points, *, sigma=None, tolerances: Tolerances = DEFAULT_TOLERANCES) -> FitResult:
    """Fit a bounded plane by total least squares (orthogonal distances), robust to outliers.

    Algorithm: the SVD plane of the centred inliers (Pearson 1901, orthogonal regression), after
    a robust start (random triples by trimmed cost, concentration steps); see the module
    docstring.

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    sigma : float, optional, metres
        The sensor's range sigma; scales the standard errors when given.
    tolerances : Tolerances

    Returns
    -------
    FitResult
        ``primitive`` is a :class:`~asbuilt.primitives.Plane` through the inliers' centroid.
        Its normal points from the plane towards the coordinate origin (the scanner station
        in a scan's frame), or, for a plane through the origin, follows
        :func:`asbuilt.fit._common.orient` (+z, else +x, else +y). The outline is the
        convex hull of the inliers projected on the plane, counter-clockwise about the
        normal. Residuals are signed distances along the normal. ``covariance`` (3 x 3) is
        over (tilt of the normal towards ``u``, towards ``v`` (radians, about the centroid),
        offset along the normal (metres)) with ``u, v = orthonormal_basis(normal)``.
        ``stderr``: ``normal_deg`` (RMS normal angle error), ``offset`` (metres, at the
        centroid). Diagnostics: ``extent`` (largest distance across the outline, metres),
        ``area`` (outline area, m^2), ``thickness`` (RMS inlier distance, metres).

    Raises
    ------
    FitError
        Too few points, identical or collinear points, or too many outliers.
    """
    pts = validate_points(points, "plane")
    require_spread(pts, "plane", 2)
    offset = pts.mean(axis=0)
    local = pts - offset
    centroid, _, directions = principal_axes(local)
    starts = [(directions[2], centroid)]
    triple = _triple_start(local, keep_count(len(local), tolerances))
    if triple is not None:
        starts.append(triple)
    try:
        robust = robust_geometric_fit(
            local,
            starts,
            _MODEL,
            kind="plane",
            sigma=sigma,
            tolerances=tolerances,
            always_refine=2,
            max_starts=2,
        )
    except FitError:
        # The robust fit's count is of its compromise plane (through two surfaces at once),
        # which says little; the plane holding the most points is fitted if it holds enough,
        # else its count says what is wrong.
        found = _support_fit(local, sigma, tolerances)
        if found is None:
            raise
        if isinstance(found, FitError):
            raise found from None
        robust = found
    if sigma is None and robust.scale > ROUGH_SCALE * tolerances.prior_range_sigma:
        # Without the sensor's sigma the residuals set the scale, and a plane through two
        # surfaces (a wall and the floor, 57% and 43%) explains every point at a scale of
        # decimetres. The plane holding the most points at the prior noise is settled too, and
        # the likelier of the two is kept; a likelier plane holding too few points for a fit is
        # the error it is with the sigma (a rough surface keeps its own fit).
        found = _support_fit(local, None, tolerances, rival=robust)
        if isinstance(found, FitError):
            raise found
        if found is not None:
            robust = found
    kept = local[robust.inliers]
    # The exact total-least-squares plane of the inliers.
    point, _, directions = principal_axes(kept)
    normal = directions[2]
    residuals_local, jacobian = _jacobian((normal, point), kept)
    noise, source = noise_level(residuals_local, 3, sigma, tolerances)
    covariance = covariance_from_jacobian(jacobian, noise)
    world_point = point + offset
    oriented = _oriented_normal(normal, world_point)
    if oriented @ normal < 0:
        # Negating the normal negates the offset and swaps the basis (u, v): re-express.
        u_old, v_old = orthonormal_basis(normal)
        u_new, v_new = orthonormal_basis(oriented)
        rotation = -np.array([[u_new @ u_old, u_new @ v_old], [v_new @ u_old, v_new @ v_old]])
        transform = np.eye(3)
        transform[:2, :2] = rotation
        transform[2, 2] = -1.0
        covariance = transform @ covariance @ transform.T
    outline = plane_outline(kept + offset, world_point, oriented)
    plane = Plane(world_point, oriented, outline)
    residuals = plane.distance(pts)
    rel = outline - world_point
    u, v = orthonormal_basis(oriented)
    xy = np.column_stack([rel @ u, rel @ v])
    area = 0.5 * float(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
    diff = outline[:, None, :] - outline[None, :, :]
    extent = float(np.sqrt(np.einsum("ijk,ijk->ij", diff, diff).max()))
    stderr = {
        "normal_deg": float(np.degrees(stderr_of(covariance[0, 0] + covariance[1, 1]))),
        "offset": stderr_of(covariance[2, 2]),
    }
    notes = []
    outliers = int(len(pts) - np.count_nonzero(robust.inliers))
    if outliers:
        notes.append(
            f"{outliers} outlier point(s) rejected (beyond {tolerances.outlier_cutoff_sigma:g}"
            f" x {robust.scale * 1000:.3g} mm)."
        )
    return FitResult(
        primitive=plane,
        residuals=residuals,
        inliers=robust.inliers,
        stderr=stderr,
        sigma=noise,
        sigma_source=source,
        method=METHOD,
        covariance=covariance,
        diagnostics={
            "extent": extent,
            "area": area,
            "thickness": float(np.sqrt(np.mean(residuals[robust.inliers] ** 2))),
        },
        notes=tuple(notes),
    )
