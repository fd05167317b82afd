"""Convex hull of the points: a closed bounding model for obstacles and peripheral objects.

Method
------
The convex hull by Quickhull (Barber, Dobkin & Huhdanpaa 1996, via ``scipy.spatial.ConvexHull``),
its triangles re-wound counter-clockwise seen from outside. A (nearly) planar set - a wall seen
from one side - has no volume, so it is extruded before the hull is taken: every point gets a
copy ``tolerances.plate_thickness`` behind it, along the plane's normal pointing away from the
coordinate origin (the scanner station in a scan's frame; see
:func:`asbuilt.fit.plane.fit_plane` for the orientation rule). The measured points stay on the
hull's front face, so their residuals stay 0.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from asbuilt.errors import FitError
from asbuilt.fit._common import noise_level, orient, principal_axes, require_spread, validate_points
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Hull
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = ["fit_hull", "METHOD"]

METHOD = "convex hull by Quickhull (Barber et al. 1996)"


def _extrusion_normal(points: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """The plane normal pointing away from the origin (behind the wall seen from the station)."""
    centroid = points.mean(axis=0)
    offset = float(centroid @ normal)
    if abs(offset) <= 1e-9 * max(float(np.linalg.norm(centroid)), 1.0):
        return -orient(normal)
    return normal if offset > 0 else -normal


def _outward_faces(vertices: np.ndarray, simplices: np.ndarray) -> np.ndarray:
    """Wind every triangle counter-clockwise seen from outside (normal away from the interior)."""
    inside = vertices.mean(axis=0)
    tri = vertices[simplices]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    outward = np.einsum("ij,ij->i", normals, tri.mean(axis=1) - inside) >= 0
    faces = simplices.copy()
    faces[~outward] = faces[~outward][:, ::-1]
    return faces


def fit_hull(points, *, sigma=None, tolerances: Tolerances = DEFAULT_TOLERANCES) -> FitResult:
    """Convex hull of the points, as a closed polyhedron.

    Algorithm: Quickhull (Barber, Dobkin & Huhdanpaa 1996); planar sets are first extruded by
    ``tolerances.plate_thickness`` behind the points (see the module docstring).

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    sigma : float, optional, metres
        The sensor's range sigma; reported as the result's ``sigma`` when given (otherwise
        ``tolerances.sigma_floor`` with ``sigma_source`` ``"residuals"``: a hull estimates no
        noise level).
    tolerances : Tolerances

    Returns
    -------
    FitResult
        ``primitive`` is a :class:`~asbuilt.primitives.Hull` whose vertices are the hull's
        corners and whose triangles are wound counter-clockwise seen from outside. Residuals
        are each point's signed distance to the hull surface (0 on it, negative inside); every
        point is an inlier (a hull has no outliers). ``stderr`` is empty and ``covariance``
        None: a hull is a bound, not an estimate. Diagnostics: ``volume`` (m^3), ``area``
        (m^2), ``extruded`` (1.0 when a planar set was given thickness).

    Raises
    ------
    FitError
        Too few points, or identical or collinear points.
    """
    pts = validate_points(points, "hull")
    spread = require_spread(pts, "hull", 2)
    notes = []
    extruded = False
    cloud = pts
    if spread[2] * 2.0 < tolerances.plate_thickness:
        _, _, directions = principal_axes(pts)
        back = _extrusion_normal(pts, directions[2])
        cloud = np.vstack([pts, pts + tolerances.plate_thickness * back])
        extruded = True
        notes.append(
            f"The points are (nearly) planar: extruded {tolerances.plate_thickness * 1000:g} mm "
            "behind them to close the hull."
        )
    try:
        hull = ConvexHull(cloud)
    except (QhullError, ValueError) as exc:
        raise FitError(f"No convex hull for these points ({str(exc).splitlines()[0]}).") from None
    used = np.unique(hull.simplices)
    remap = np.full(len(cloud), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    vertices = cloud[used]
    faces = _outward_faces(vertices, remap[hull.simplices])
    primitive = Hull(vertices, faces)
    residuals = np.minimum(primitive.distance(pts), 0.0)
    residuals[np.abs(residuals) < 1e-12 * max(float(np.ptp(pts, axis=0).max()), 1.0)] = 0.0
    noise, source = (
        (float(sigma), "sensor")
        if sigma is not None
        else (noise_level(np.zeros(0), 0, None, tolerances))
    )
    notes.append("A hull is a bound, not an estimate: it has no standard errors.")
    return FitResult(
        primitive=primitive,
        residuals=residuals,
        inliers=np.ones(len(pts), dtype=bool),
        stderr={},
        sigma=noise,
        sigma_source=source,
        method=METHOD,
        covariance=None,
        diagnostics={
            "volume": float(hull.volume),
            "area": float(hull.area),
            "extruded": 1.0 if extruded else 0.0,
        },
        notes=tuple(notes),
    )
