"""Triangle meshes of the model geometries computed directly with numpy (no CAD kernel).

Tessellating B-rep solids with the kernel costs 5-25 ms per pipe; these closed forms cost well
under a millisecond and describe the same surfaces as :mod:`asbuilt.cad.solids`:

* tubes (straights, fitted cylinders, reducers, bends) are rings of ``SEGMENTS`` vertices swept
  along the axis (bends: one ring every 360/``SEGMENTS`` degrees of the arc), with end caps
  (discs, or annuli when the wall is known). Ring radii are enlarged by
  ``sqrt(2*pi / (n * sin(2*pi/n)))`` so each polygon has the circle's area (the "equal-area
  polygon"), and bends' by ``sqrt(step / sin(step))`` for the chords of the arc, hence the
  mesh's volume matches the solid's;
* cuboids are their 6 faces; plates their outline polygon top and bottom plus the sides;
  spheres a latitude/longitude grid rescaled to the sphere's volume; hulls their triangles.

Each returns a :class:`asbuilt.cad.mesh.Mesh` with vertices per smooth patch (so averaged normals
stay sharp at edges). Tees (a boolean union) are not covered: :func:`mesh_for` returns None and
the caller tessellates the solid.
"""

from __future__ import annotations

import numpy as np

from asbuilt.cad.mesh import Mesh, vertex_normals
from asbuilt.model import Bend, Reducer, Straight
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

__all__ = [
    "SEGMENTS",
    "mesh_for",
    "tube_mesh",
    "box_mesh",
    "sphere_mesh",
    "plate_mesh",
    "hull_mesh",
]

#: Vertices around a pipe: 32 keeps every facet within 11.25 degrees (finer than the kernel's
#: 0.25 rad angular deflection used for solids that are tessellated).
SEGMENTS = 32


def _equal_area(n: int) -> float:
    return float(np.sqrt(2 * np.pi / (n * np.sin(2 * np.pi / n))))


class _Builder:
    """Collects patches (vertices, faces); normals are averaged within each patch only."""

    def __init__(self) -> None:
        self.vertices: list[np.ndarray] = []
        self.faces: list[np.ndarray] = []
        self.normals: list[np.ndarray] = []
        self.count = 0

    def patch(self, vertices: np.ndarray, faces: np.ndarray) -> None:
        self.vertices.append(vertices)
        self.faces.append(faces + self.count)
        self.normals.append(vertex_normals(vertices, faces))
        self.count += len(vertices)

    def mesh(self) -> Mesh:
        return Mesh(
            np.concatenate(self.vertices),
            np.concatenate(self.faces).astype(np.int64),
            np.concatenate(self.normals),
        )


def _perpendicular(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


def _strip(rows: int, n: int, flip: bool = False) -> np.ndarray:
    """Quads between consecutive rings of ``n`` vertices (ring k at k*n), as triangles."""
    k = np.arange(rows - 1)[:, None] * n
    j = np.arange(n)[None, :]
    a = (k + j).ravel()
    b = (k + (j + 1) % n).ravel()
    c = a + n
    d = b + n
    tris = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    return tris[:, ::-1] if flip else tris


def tube_mesh(
    centres: np.ndarray,
    us: np.ndarray,
    vs: np.ndarray,
    radii: np.ndarray,
    wall: float | np.ndarray = 0.0,
    n: int = SEGMENTS,
) -> Mesh:
    """A tube swept through rings.

    Parameters
    ----------
    centres : ndarray, shape (k, 3), metres
        Ring centres along the axis (k >= 2).
    us, vs : ndarray, shape (k, 3)
        Each ring's orthonormal in-plane axes, with ``cross(u, v)`` along the sweep direction.
    radii : ndarray, shape (k,), metres
        Outer radius at each ring.
    wall : float or ndarray of shape (k,), metres
        Wall thickness, one for every ring or one at each (a reducer's bore runs from one
        end's to the other's); 0 everywhere: solid, with disc caps.
    n : int
        Vertices per ring.
    """
    angles = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    cos, sin = np.cos(angles), np.sin(angles)
    scale = _equal_area(n)

    def rings(radius: np.ndarray) -> np.ndarray:
        r = (radius * scale)[:, None, None]
        points = centres[:, None, :] + r * (
            cos[None, :, None] * us[:, None, :] + sin[None, :, None] * vs[:, None, :]
        )
        return points.reshape(-1, 3)

    rows = len(centres)
    builder = _Builder()
    outer = rings(radii)
    builder.patch(outer, _strip(rows, n))
    first, last = outer[:n], outer[-n:]
    if np.any(np.asarray(wall) > 0):
        inner = rings(radii - wall)
        builder.patch(inner, _strip(rows, n, flip=True))
        for ring_out, ring_in, flip in ((first, inner[:n], True), (last, inner[-n:], False)):
            vertices = np.concatenate([ring_out, ring_in])
            builder.patch(vertices, _strip(2, n, flip=flip))
    else:
        fan = np.stack([np.zeros(n, int), np.arange(n) + 1, (np.arange(n) + 1) % n + 1], 1)
        builder.patch(np.concatenate([centres[:1], first]), fan[:, ::-1])
        builder.patch(np.concatenate([centres[-1:], last]), fan)
    return builder.mesh()


def _line_tube(start, end, radius_start, radius_end, wall) -> Mesh:
    axis = (end - start) / np.linalg.norm(end - start)
    u, v = _perpendicular(axis)
    return tube_mesh(
        np.array([start, end]),
        np.array([u, u]),
        np.array([v, v]),
        np.array([radius_start, radius_end]),
        wall,
    )


def _bend_mesh(geometry: Bend) -> Mesh:
    r_start = geometry.start - geometry.center
    normal = np.cross(r_start, geometry.end - geometry.center)
    normal /= np.linalg.norm(normal)
    e1 = r_start / np.linalg.norm(r_start)
    e2 = np.cross(normal, e1)
    angle = np.radians(geometry.angle_deg)
    steps = max(2, int(np.ceil(angle / (2 * np.pi / SEGMENTS))) + 1)
    theta = np.linspace(0.0, angle, steps)[:, None]
    radial = np.cos(theta) * e1 + np.sin(theta) * e2
    centres = geometry.center + geometry.bend_radius * radial
    # Ring plane spanned by the bend normal and the radial direction: cross(normal, radial) is
    # the tangent, the sweep direction.
    # Each wedge between rings is an oblique prism: volume = area * chord * cos(step/2), i.e.
    # sin(step)/step of the true sweep. Enlarging the ring radii by sqrt(step/sin(step)) (0.3%
    # at 11.25 degrees) restores the bend's volume.
    step = angle / (steps - 1)
    stretch = float(np.sqrt(step / np.sin(step)))
    us = np.repeat(normal[None, :], steps, axis=0)
    # a reducing elbow's radii and walls change evenly with the angle turned (as the solid's)
    share = np.linspace(0.0, 1.0, steps)
    (r1, r2), (w1, w2) = geometry.radii, geometry.walls
    return tube_mesh(
        centres,
        us,
        radial,
        (r1 + share * (r2 - r1)) * stretch,
        (w1 + share * (w2 - w1)) * stretch,
    )


def box_mesh(geometry: Cuboid) -> Mesh:
    """The cuboid's six faces (4 vertices each), metres."""
    builder = _Builder()
    half = 0.5 * geometry.size
    for axis in range(3):
        for sign in (-1.0, 1.0):
            a, b = (axis + 1) % 3, (axis + 2) % 3
            corners = np.zeros((4, 3))
            corners[:, axis] = sign * half[axis]
            corners[:, a] = np.array([-1, 1, 1, -1]) * half[a]
            corners[:, b] = np.array([-1, -1, 1, 1]) * half[b]
            faces = np.array([[0, 1, 2], [0, 2, 3]])
            if sign < 0:
                faces = faces[:, ::-1]
            builder.patch(geometry.center + corners @ geometry.axes, faces)
    return builder.mesh()


def sphere_mesh(geometry: Sphere, n: int = SEGMENTS) -> Mesh:
    """A latitude/longitude sphere (n around, n/2 rings), scaled to the sphere's volume."""
    rings = n // 2
    lat = np.linspace(0.0, np.pi, rings + 1)[1:-1]
    lon = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    unit = np.stack(
        [
            np.sin(lat)[:, None] * np.cos(lon)[None, :],
            np.sin(lat)[:, None] * np.sin(lon)[None, :],
            np.repeat(np.cos(lat)[:, None], n, axis=1),
        ],
        axis=-1,
    ).reshape(-1, 3)
    points = np.concatenate([[[0.0, 0.0, 1.0]], unit, [[0.0, 0.0, -1.0]]])
    body = _strip(rings - 1, n) + 1
    j = np.arange(n)
    top = np.stack([np.zeros(n, int), j + 1, (j + 1) % n + 1], 1)
    bottom_start = 1 + (rings - 2) * n
    bottom = np.stack(
        [np.full(n, len(points) - 1), bottom_start + (j + 1) % n, bottom_start + j], 1
    )
    faces = np.concatenate([top, body[:, ::-1], bottom])
    faces = faces[:, ::-1] if _signed_volume(points, faces) < 0 else faces
    scale = (4.0 / 3.0 * np.pi / _signed_volume(points, faces)) ** (1.0 / 3.0)
    vertices = geometry.center + geometry.radius * scale * points
    return Mesh(vertices, faces.astype(np.int64), points.copy())


def plate_mesh(geometry: Plane, thickness: float) -> Mesh:
    """The plate of a plane's outline, ``thickness`` metres thick, centred on the plane.

    The outline (convex, counter-clockwise about the normal) is projected on the plane first,
    as in :func:`asbuilt.cad.solids.plate_solid`.
    """
    normal = geometry.normal
    rel = geometry.outline - geometry.point
    flat = geometry.outline - np.outer(rel @ normal, normal)
    keep = [flat[0]]
    for point in flat[1:]:
        if np.linalg.norm(point - keep[-1]) > 1e-7:
            keep.append(point)
    if len(keep) > 1 and np.linalg.norm(keep[-1] - keep[0]) <= 1e-7:
        keep.pop()
    polygon = np.asarray(keep)
    k = len(polygon)
    fan = np.stack([np.zeros(k - 2, int), np.arange(1, k - 1), np.arange(2, k)], 1)
    top = polygon + 0.5 * thickness * normal
    bottom = polygon - 0.5 * thickness * normal
    area_normal = np.cross(polygon[1:-1] - polygon[0], polygon[2:] - polygon[0]).sum(axis=0)
    ccw = float(area_normal @ normal) > 0
    builder = _Builder()
    builder.patch(top, fan if ccw else fan[:, ::-1])
    builder.patch(bottom, fan[:, ::-1] if ccw else fan)
    for i in range(k):
        j = (i + 1) % k
        quad = np.array([bottom[i], bottom[j], top[j], top[i]])
        faces = np.array([[0, 1, 2], [0, 2, 3]])
        builder.patch(quad, faces if ccw else faces[:, ::-1])
    return builder.mesh()


def _signed_volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The signed volume (m3) the faces enclose, summed about the vertices' mean: about the
    scan's origin a small hull at survey coordinates (4,000 km) sums products of 1e13 m3 that
    cancel to noise larger than its volume, and its winding came out inverted."""
    vertices = vertices - vertices.mean(axis=0)
    tri = vertices[faces]
    return float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6)


def hull_mesh(geometry: Hull) -> Mesh:
    """The hull's triangles, flat shaded (3 vertices each), wound outwards."""
    faces = geometry.faces
    if _signed_volume(geometry.vertices, faces) < 0:
        faces = faces[:, ::-1]
    tri = geometry.vertices[faces].reshape(-1, 3)
    index = np.arange(len(tri)).reshape(-1, 3)
    normals = np.cross(tri[1::3] - tri[0::3], tri[2::3] - tri[0::3])
    lengths = np.linalg.norm(normals, axis=1)
    normals = np.where(
        lengths[:, None] > 0,
        normals / np.maximum(lengths, 1e-300)[:, None],
        np.array([0.0, 0.0, 1.0]),
    )
    return Mesh(tri.copy(), index.astype(np.int64), np.repeat(normals, 3, axis=0))


def mesh_for(geometry, *, plate_thickness: float) -> Mesh | None:
    """The numpy mesh of a geometry (metres), or None when only the kernel can mesh it (tees).

    Parameters
    ----------
    geometry : asbuilt.model.Geometry
    plate_thickness : float, metres
        For planes.
    """
    if isinstance(geometry, Straight):
        return _line_tube(
            geometry.start,
            geometry.end,
            geometry.outer_radius,
            geometry.outer_radius,
            geometry.wall,
        )
    if isinstance(geometry, Cylinder):
        start, end = geometry.ends
        return _line_tube(start, end, geometry.radius, geometry.radius, 0.0)
    if isinstance(geometry, Reducer):
        # rings in planes perpendicular to the run (an eccentric reducer's end circles are
        # offset sideways): the oblique frustum of two similar polygons has the volume of the
        # right one, h/3 (A1 + A2 + sqrt(A1 A2)), so the equal-area rings keep it exact
        u, v = _perpendicular(geometry.direction)
        return tube_mesh(
            np.array([geometry.start, geometry.end]),
            np.array([u, u]),
            np.array([v, v]),
            np.array([geometry.outer_radius_start, geometry.outer_radius_end]),
            np.array([geometry.wall_start, geometry.wall_end]),
        )
    if isinstance(geometry, Bend):
        return _bend_mesh(geometry)
    if isinstance(geometry, Cuboid):
        return box_mesh(geometry)
    if isinstance(geometry, Sphere):
        return sphere_mesh(geometry)
    if isinstance(geometry, Plane):
        return plate_mesh(geometry, plate_thickness)
    if isinstance(geometry, Hull):
        return hull_mesh(geometry)
    return None
