"""Convex hull of the points: a closed bounding model for obstacles and peripheral objects.

Method
------
The convex hull by Quickhull (Barber, Dobkin & Huhdanpaa 1996, via ``scipy.spatial.ConvexHull``),
its triangles re-wound counter-clockwise seen from outside. A (nearly) planar set - a wall seen
from one side - has no volume, so it is extruded before the hull is taken: every point gets a
copy behind it, along the plane's normal pointing away from the coordinate origin (the scanner
station in a scan's frame; see :func:`asbuilt.fit.plane.fit_plane` for the orientation rule).
The measured points stay on the hull's front face, so their residuals stay 0.

"Nearly planar" is judged against the set itself: its RMS thickness (the spread along the
third principal axis) is within the noise (at most ``FLAT_NOISE`` times the sensor's sigma, or
``tolerances.sigma_floor`` without one) or below ``FLAT_RATIO`` of its RMS width (the spread
along the second). The copy lies ``tolerances.plate_thickness`` behind, but no more than
``PAD_RATIO`` of the set's width (its extent along the second principal axis): a plate for a
wall, a sliver for a small flat part. Before, the test compared the thickness with the plate
thickness itself, so a 6 x 6 x 3 mm part was "planar" and grew 10 mm behind its points (6.5
times its volume).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from asbuilt.errors import FitError
from asbuilt.fit._common import noise_level, orient, principal_axes, require_spread, validate_points
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Hull
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = ["fit_hull", "METHOD", "FLAT_NOISE", "FLAT_RATIO", "PAD_RATIO"]

METHOD = "convex hull by Quickhull (Barber et al. 1996)"

#: A set whose RMS thickness is at most this many noise sigmas is flat: its thickness is noise.
FLAT_NOISE = 3.0
#: A set whose RMS thickness is below this fraction of its RMS width is flat (a plate 1 m wide
#: and under 10 mm thick), whatever the noise.
FLAT_RATIO = 0.01
#: A flat set is padded by at most this fraction of its width: enough for a solid with a volume
#: CAD kernels and mesh viewers handle, small against the object itself.
PAD_RATIO = 0.05


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

    Algorithm: Quickhull (Barber, Dobkin & Huhdanpaa 1996); (nearly) planar sets are first
    extruded behind the points by ``tolerances.plate_thickness``, at most ``PAD_RATIO`` of
    their width (see the module docstring).

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    sigma : float, optional, metres
        The sensor's range sigma; reported as the result's ``sigma`` when given (otherwise
        ``tolerances.sigma_floor`` with ``sigma_source`` ``"residuals"``: a hull estimates no
        noise level). A set no thicker than ``FLAT_NOISE`` times it is flat.
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
    noise = float(sigma) if sigma is not None else tolerances.sigma_floor
    if spread[2] <= max(FLAT_NOISE * noise, FLAT_RATIO * spread[1]):
        _, _, directions = principal_axes(pts)
        back = _extrusion_normal(pts, directions[2])
        width = float(np.ptp(pts @ directions[1]))
        pad = min(tolerances.plate_thickness, PAD_RATIO * width)
        cloud = np.vstack([pts, pts + pad * back])
        extruded = True
        notes.append(
            f"The points are (nearly) planar: extruded {pad * 1000:.3g} mm behind them to close "
            "the hull."
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
