"""One valid CadQuery solid per model component (metres, scan frame, z up).

Each geometry has its own builder: straights and fitted cylinders are cylinders (an annulus
extruded along the axis when the wall is known), bends revolve their cross-section about the
bend axis, reducers are truncated cones (eccentric ones a ruled loft between their end circles,
an oblique cone), tees fuse the run and branch cylinders (then cut the
bores), cuboids are transformed boxes, spheres are spheres, planes become plates extruded from
their outline (centred on the plane), hulls are polyhedra sewn from their triangles. Every
result is checked with the kernel's validity check (``BRepCheck_Analyzer`` via
:meth:`cadquery.Shape.isValid`) and must enclose a positive volume.

Every solid is built near the origin, about a *local origin* (the geometry's mean position
rounded to whole metres), and placed by a location: at survey coordinates (5e6 m) the kernel's
precision (1e-7) is below a double's resolution of the coordinates in millimetres, and a STEP
reader then turned extruded and cut solids inside out. :func:`placed_solid` gives the local
solid and its origin (the STEP assembly places it by a transform); :func:`solid_for` the solid
moved into place.
"""

from __future__ import annotations

import dataclasses

import cadquery as cq
import numpy as np
from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
from OCP.BRepPrimAPI import BRepPrimAPI_MakeCylinder
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Trsf
from OCP.ShapeUpgrade import ShapeUpgrade_ShapeDivideClosed

from asbuilt.errors import SolidBuildError
from asbuilt.model import Bend, Component, Cross, Reducer, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.tolerances import DEFAULT_TOLERANCES

__all__ = [
    "solid_for",
    "placed_solid",
    "place",
    "local_origin",
    "split_closed_faces",
    "check_solid",
    "check_geometry",
    "build_error",
    "plate_solid",
]

#: Geometry fields that are positions (shape (3,) or (k, 3) metres), shifted to the local origin;
#: the others (axes, normals, sizes, radii, faces) do not change under a translation.
_POSITION_FIELDS = frozenset(
    (
        "start",
        "end",
        "center",
        "run_start",
        "run_end",
        "branch_start",
        "branch_end",
        "point",
        "outline",
        "vertices",
    )
)

#: Points of an outline closer than this (metres) are merged before building a plate.
_POINT_MERGE = 1e-7


def _v(point) -> cq.Vector:
    return cq.Vector(float(point[0]), float(point[1]), float(point[2]))


def _unit(vector: np.ndarray) -> np.ndarray:
    return vector / np.linalg.norm(vector)


def _cylinder(start: np.ndarray, end: np.ndarray, radius: float, wall: float = 0.0) -> cq.Solid:
    """A cylinder of ``radius`` (m) from ``start`` to ``end`` (each (3,) m); hollow if ``wall``."""
    axis = end - start
    length = float(np.linalg.norm(axis))
    direction = _v(axis / length)
    if wall <= 0:
        return cq.Solid.makeCylinder(radius, length, _v(start), direction)
    outer = cq.Wire.makeCircle(radius, _v(start), direction)
    inner = cq.Wire.makeCircle(radius - wall, _v(start), direction)
    face = cq.Face.makeFromWires(outer, [inner])
    return cq.Solid.extrudeLinear(face, _v(axis))


def _straight(geometry: Straight) -> cq.Shape:
    return _cylinder(geometry.start, geometry.end, geometry.outer_radius, geometry.wall)


def _fitted_cylinder(geometry: Cylinder) -> cq.Shape:
    start, end = geometry.ends
    return _cylinder(start, end, geometry.radius)


def _bend_normal(geometry: Bend) -> np.ndarray:
    """The unit normal of the bend's plane (3,); ValueError for a bend no solid can have."""
    normal = np.cross(geometry.start - geometry.center, geometry.end - geometry.center)
    if np.linalg.norm(normal) < 1e-9 * geometry.bend_radius**2:
        raise ValueError("its ends and centre are collinear, so the bend plane is undefined")
    if max(geometry.radii) >= geometry.bend_radius:
        raise ValueError(
            f"the bend radius {geometry.bend_radius:.4g} m is not larger than the outer radius "
            f"{max(geometry.radii):.4g} m"
        )
    return _unit(normal)


def _bend(geometry: Bend) -> cq.Shape:
    """Revolve the pipe's cross-section at ``start`` about the bend axis by the bend angle.

    A reducing elbow (ends of two sizes or walls) is swept instead: the start end's circles to
    the end end's along the centreline arc, outside and bore each, the bore then cut out.
    """
    r_start = geometry.start - geometry.center
    normal = _bend_normal(geometry)
    tangent = _unit(np.cross(normal, r_start))
    if geometry.reducing:
        return _reducing_bend(geometry, normal, tangent)
    outer = cq.Wire.makeCircle(geometry.outer_radius, _v(geometry.start), _v(tangent))
    inner = []
    if geometry.wall > 0:
        inner = [
            cq.Wire.makeCircle(
                geometry.outer_radius - geometry.wall, _v(geometry.start), _v(tangent)
            )
        ]
    face = cq.Face.makeFromWires(outer, inner)
    return cq.Solid.revolve(
        face, geometry.angle_deg, _v(geometry.center), _v(geometry.center + normal)
    )


def _reducing_bend(geometry: Bend, normal: np.ndarray, tangent: np.ndarray) -> cq.Shape:
    """A bend whose ends differ: circles of each end's radius swept along the centreline arc
    (the radius changes evenly with the angle turned; the volume is that of the linear law to
    1e-4), the bore likewise between each end's bore when the walls are known.

    ``normal`` is the bend plane's unit normal, ``tangent`` the travel direction at ``start``.
    """
    r_end = geometry.end - geometry.center
    end_tangent = _unit(np.cross(normal, r_end))
    half = 0.5 * np.radians(geometry.angle_deg)
    bisector = _unit(geometry.start - geometry.center) * np.cos(half) + _unit(
        np.cross(normal, geometry.start - geometry.center)
    ) * np.sin(half)
    middle = geometry.center + geometry.bend_radius * bisector
    path = cq.Wire.assembleEdges(
        [cq.Edge.makeThreePointArc(_v(geometry.start), _v(middle), _v(geometry.end))]
    )

    def sweep(r_first: float, r_second: float) -> cq.Solid:
        sections = [
            cq.Wire.makeCircle(r_first, _v(geometry.start), _v(tangent)),
            cq.Wire.makeCircle(r_second, _v(geometry.end), _v(end_tangent)),
        ]
        return cq.Solid.sweep_multi(sections, path, True, False)

    (r1, r2), (w1, w2) = geometry.radii, geometry.walls
    outer = sweep(r1, r2)
    if w1 <= 0 and w2 <= 0:
        return outer
    return outer.cut(sweep(r1 - w1, r2 - w2))


def _oblique_frustum(geometry: Reducer, r_start: float, r_end: float) -> cq.Solid:
    """A ruled loft between circles of radius ``r_start`` and ``r_end`` (m) about the two end
    centres, each in the plane perpendicular to the run: an eccentric reducer's oblique
    truncated cone (its outside, or its bore)."""
    normal = _v(geometry.direction)
    circles = [
        cq.Wire.makeCircle(radius, _v(centre), normal)
        for centre, radius in ((geometry.start, r_start), (geometry.end, r_end))
    ]
    return cq.Solid.makeLoft(circles, True)


def _check_reducer(geometry: Reducer) -> None:
    if geometry.length <= 0:
        raise ValueError("its start and end coincide")


def _reducer(geometry: Reducer) -> cq.Shape:
    """A truncated cone from ``start`` to ``end``; oblique (a loft) when eccentric.

    The bore is a cone too, from the start end's bore to the end end's (each end's own wall),
    so it runs on from the bore of the pipe welded at either end without a step.
    """
    length = geometry.length
    _check_reducer(geometry)
    r1, r2 = geometry.outer_radius_start, geometry.outer_radius_end
    hollow = geometry.wall_start > 0 or geometry.wall_end > 0
    bore1, bore2 = r1 - geometry.wall_start, r2 - geometry.wall_end
    if geometry.eccentric:
        outer = _oblique_frustum(geometry, r1, r2)
        return outer.cut(_oblique_frustum(geometry, bore1, bore2)) if hollow else outer
    direction = _v(geometry.direction)
    outer = cq.Solid.makeCone(r1, r2, length, _v(geometry.start), direction)
    if not hollow:
        return outer
    inner = cq.Solid.makeCone(bore1, bore2, length, _v(geometry.start), direction)
    return outer.cut(inner)


def _seamed_cylinder(
    start: np.ndarray, end: np.ndarray, radius: float, seam: np.ndarray
) -> cq.Solid:
    """A solid cylinder of ``radius`` (m) from ``start`` to ``end`` whose lateral face has its
    seam on the side ``seam`` points to ((3,), not along the axis).

    The seam is the lateral face's u = 0 line, the x direction of the cylinder's frame;
    ``cq.Solid.makeCylinder`` lets the kernel pick that direction from the axis alone, so where
    the seam falls changes with tiny turns of the axis.
    """
    axis = end - start
    length = float(np.linalg.norm(axis))
    direction = axis / length
    side = seam - (seam @ direction) * direction
    frame = gp_Ax2(
        gp_Pnt(*(float(v) for v in start)),
        gp_Dir(*(float(v) for v in direction)),
        gp_Dir(*(float(v) for v in _unit(side))),
    )
    return cq.Solid(BRepPrimAPI_MakeCylinder(frame, radius, length).Shape())


def _tee(geometry: Tee) -> cq.Shape:
    """Run and branch cylinders fused, then both bores (each of its own wall) cut when the walls
    are known.

    The run's (and run bore's) seam is put through the middle of the branch hole, and the
    branch's seam on the run's side. Files get closed faces split in two at the middle of their
    parameter range (:func:`split_closed_faces`), which is then the run's side opposite the
    branch, clear of the hole; the hole itself crosses the seam, so no face keeps it as an inner
    wire. With the seam wherever the kernel put it, the seam or the split line ran along the
    hole's edge for some turns of the run (NPS 4 and smaller: up to half of the branch directions),
    and STEP readers rebuilt that face into intersecting wires (an invalid solid). Seam
    opposite the branch fails the same way for small branches, as the split then crosses the
    hole.
    """
    return _junction(geometry, "branch is")


def _cross(geometry: Cross) -> cq.Shape:
    """A cross as :func:`_tee` builds a tee: the run cylinder fused with the outlet cylinder
    through both sides (``branch_start`` to ``branch_end``), then both bores (each of its own
    wall) cut when the walls are known; the seams placed as the tee's (the run's through the
    middle of one outlet hole, so the split opposite goes through the middle of the other)."""
    return _junction(geometry, "outlets are")


def _junction(geometry: Tee | Cross, parallel: str) -> cq.Shape:
    """A tee's or cross's solid: the run cylinder fused with the outlet cylinder from its
    ``outlet_start`` (the tee's centre, or a cross's far outlet end) to ``branch_end``, then
    both bores (each of its own wall) cut when the walls are known; the run's seam through the
    middle of the (first) outlet hole (see :func:`_tee`)."""
    outlet_start = geometry.outlet_start
    run_axis = geometry.run_end - geometry.run_start
    outlet_axis = geometry.branch_end - outlet_start
    if np.linalg.norm(np.cross(run_axis, outlet_axis)) <= 1e-9 * (
        np.linalg.norm(run_axis) * np.linalg.norm(outlet_axis)
    ):
        raise ValueError(f"its {parallel} parallel to its run")

    def run(radius: float) -> cq.Solid:
        return _seamed_cylinder(geometry.run_start, geometry.run_end, radius, outlet_axis)

    def outlet(radius: float) -> cq.Solid:
        return _seamed_cylinder(outlet_start, geometry.branch_end, radius, run_axis)

    shape = run(geometry.outer_radius).fuse(outlet(geometry.branch_outer_radius))
    if geometry.wall > 0 or geometry.branch_wall > 0:
        # each bore is its own pipe's: the run's wall on the run, the outlet's on the outlet
        bores = run(geometry.outer_radius - geometry.wall).fuse(
            outlet(geometry.branch_outer_radius - geometry.branch_wall)
        )
        shape = shape.cut(bores)
    return shape.clean()


def split_closed_faces(shape: cq.Shape) -> cq.Shape:
    """``shape`` with every closed (periodic) face cut in two, for writing to files.

    The run's cylinder face of a tee is closed and holds the branch hole; in a STEP round trip
    readers rebuild its wires and, when the hole lies near the seam, get intersecting wires
    (``BRepCheck_IntersectingWires``: an invalid solid). Split faces have no seam in them. Not
    for solids that are fused later (the kernel's fuse of split tees can come out invalid).
    """
    divider = ShapeUpgrade_ShapeDivideClosed(shape.wrapped)
    divider.SetNbSplitPoints(1)
    divider.Perform()
    return cq.Shape.cast(divider.Result())


def _transformed(shape: cq.Shape, rotation: np.ndarray, translation: np.ndarray) -> cq.Shape:
    """``shape`` mapped by x -> rotation @ x + translation (rotation (3, 3), translation (3,) m)."""
    trsf = gp_Trsf()
    r, t = rotation, translation
    trsf.SetValues(
        *(float(v) for v in (r[0, 0], r[0, 1], r[0, 2], t[0])),
        *(float(v) for v in (r[1, 0], r[1, 1], r[1, 2], t[1])),
        *(float(v) for v in (r[2, 0], r[2, 1], r[2, 2], t[2])),
    )
    return cq.Shape.cast(BRepBuilderAPI_Transform(shape.wrapped, trsf, True).Shape())


def _cuboid(geometry: Cuboid) -> cq.Shape:
    sx, sy, sz = (float(s) for s in geometry.size)
    box = cq.Solid.makeBox(sx, sy, sz, cq.Vector(-sx / 2, -sy / 2, -sz / 2))
    return _transformed(box, geometry.axes.T, geometry.center)


def _sphere(geometry: Sphere) -> cq.Shape:
    return cq.Solid.makeSphere(
        geometry.radius, _v(geometry.center), angleDegrees1=-90, angleDegrees2=90
    )


def _plate_base(geometry: Plane, thickness: float) -> np.ndarray:
    """The plate's bottom polygon (k, 3) metres; ValueError for an outline no plate can have."""
    if len(geometry.outline) < 3:
        raise ValueError("it has no outline (a bounded plate needs at least 3 outline points)")
    if not thickness > 0:
        raise ValueError(f"the plate thickness must be positive, not {thickness!r}")
    normal = geometry.normal
    rel = geometry.outline - geometry.point
    flat = geometry.outline - np.outer(rel @ normal, normal)
    keep = [flat[0]]
    for point in flat[1:]:
        if np.linalg.norm(point - keep[-1]) > _POINT_MERGE:
            keep.append(point)
    if len(keep) > 1 and np.linalg.norm(keep[-1] - keep[0]) <= _POINT_MERGE:
        keep.pop()
    if len(keep) < 3:
        raise ValueError("its outline has fewer than 3 distinct points")
    return np.asarray(keep) - 0.5 * thickness * normal


def plate_solid(geometry: Plane, thickness: float) -> cq.Shape:
    """A plate ``thickness`` metres thick from a plane's outline, centred on the plane.

    Parameters
    ----------
    geometry : Plane
        Its ``outline`` (k, 3) metres (k >= 3) is projected on the plane first.
    thickness : float, metres
    """
    base = _plate_base(geometry, thickness)
    wire = cq.Wire.makePolygon([_v(p) for p in base], close=True)
    face = cq.Face.makeFromWires(wire)
    return cq.Solid.extrudeLinear(face, _v(thickness * geometry.normal))


def _convex_facets(vertices: np.ndarray, faces: np.ndarray) -> list[np.ndarray] | None:
    """The hull's planar facets as convex polygons (each (k, 3) metres, unordered winding), or
    None when the polyhedron is not convex (then its triangles are used as they are).

    Coplanar triangles of a convex polyhedron form one convex polygon: its boundary is the 2D
    convex hull of their vertices in the facet's plane.
    """
    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    lengths = np.linalg.norm(normals, axis=1)
    keep = lengths > 1e-14
    tri, normals = tri[keep], normals[keep] / lengths[keep, None]
    centre = vertices.mean(axis=0)
    # Orient every normal away from the centre (the winding may be inconsistent).
    flip = np.einsum("ij,ij->i", normals, tri[:, 0] - centre) < 0
    normals[flip] *= -1
    offsets = np.einsum("ij,ij->i", normals, tri[:, 0])
    scale = float(np.ptp(vertices, axis=0).max())
    tolerance = 1e-9 * max(scale, 1.0)
    if np.any(vertices @ normals.T - offsets > tolerance * 10):
        return None  # some vertex lies outside a face plane: not convex
    facets: list[np.ndarray] = []
    used = np.zeros(len(tri), bool)
    for k in range(len(tri)):
        if used[k]:
            continue
        same = (
            (~used)
            & (normals @ normals[k] > 1 - 1e-9)
            & (np.abs(offsets - offsets[k]) <= tolerance * 10)
        )
        used |= same
        points = np.unique(np.round(tri[same].reshape(-1, 3), 12), axis=0)
        u = tri[k, 1] - tri[k, 0]
        u /= np.linalg.norm(u)
        v = np.cross(normals[k], u)
        flat = np.stack([(points - points[0]) @ u, (points - points[0]) @ v], axis=1)
        order = _hull_2d(flat)
        facets.append(points[order])
    return facets


def _hull_2d(points: np.ndarray) -> list[int]:
    """Indices of the 2D convex hull (Andrew's monotone chain), counter-clockwise."""
    order = np.lexsort((points[:, 1], points[:, 0]))

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[int] = []
    for i in order:
        while len(lower) >= 2 and cross(points[lower[-2]], points[lower[-1]], points[i]) <= 0:
            lower.pop()
        lower.append(int(i))
    upper: list[int] = []
    for i in order[::-1]:
        while len(upper) >= 2 and cross(points[upper[-2]], points[upper[-1]], points[i]) <= 0:
            upper.pop()
        upper.append(int(i))
    return lower[:-1] + upper[:-1]


def _check_closed(geometry: Hull) -> None:
    """ValueError unless every edge of the hull's triangles joins exactly two of them: a closed
    surface, which sewing makes one shell of."""
    faces = np.asarray(geometry.faces)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    if len(faces) < 4 or np.any(counts != 2):
        raise ValueError("its triangles do not sew into one closed shell")


def _hull(geometry: Hull) -> cq.Shape:
    """Sew the hull's facets (coplanar triangles merged when the hull is convex) into a solid."""
    polygons = _convex_facets(geometry.vertices, geometry.faces)
    if polygons is None:
        polygons = [
            tri
            for tri in geometry.vertices[geometry.faces]
            if np.linalg.norm(np.cross(tri[1] - tri[0], tri[2] - tri[0])) > 1e-14
        ]
    faces = [
        cq.Face.makeFromWires(cq.Wire.makePolygon([_v(p) for p in polygon], close=True))
        for polygon in polygons
    ]
    shell = cq.Shell.makeShell(faces)
    if shell.wrapped.ShapeType().name != "TopAbs_SHELL":
        shells = shell.Shells()
        if len(shells) != 1:
            raise ValueError("its triangles do not sew into one closed shell")
        shell = shells[0]
    solid = cq.Solid.makeSolid(shell)
    if solid.Volume() < 0:
        solid = cq.Solid(solid.wrapped.Reversed())
    return solid


_BUILDERS = {
    Straight: _straight,
    Cylinder: _fitted_cylinder,
    Bend: _bend,
    Reducer: _reducer,
    Tee: _tee,
    Cross: _cross,
    Cuboid: _cuboid,
    Sphere: _sphere,
    Hull: _hull,
}


def check_solid(shape: cq.Shape, name: str) -> cq.Solid:
    """Return the one valid, positive-volume solid in ``shape``; SolidBuildError otherwise.

    Parameters
    ----------
    shape : cadquery.Shape
    name : str
        The object id, for the message.
    """
    solids = shape.Solids()
    if len(solids) != 1:
        raise SolidBuildError(
            f"the CAD kernel made {len(solids)} solids instead of one; check the object's "
            "geometry (parts that should touch may be apart)",
            where=f"object {name}",
        )
    solid = solids[0]
    if not solid.isValid():
        raise SolidBuildError(
            "the CAD kernel's validity check failed for its solid; check its fitted size "
            "and refit it",
            where=f"object {name}",
        )
    if not solid.Volume() > 0:
        raise SolidBuildError(
            "its solid encloses no volume; check its fitted size and refit it",
            where=f"object {name}",
        )
    return solid


def local_origin(geometry) -> np.ndarray:
    """The point a geometry's solid is built about: its mean position, whole metres, shape (3,).

    Whole metres so the placement is exact in a STEP file (13 significant digits, millimetres).
    """
    points = [
        np.asarray(getattr(geometry, f.name), dtype=np.float64).reshape(-1, 3)
        for f in dataclasses.fields(geometry)
        if f.name in _POSITION_FIELDS and getattr(geometry, f.name) is not None
    ]
    points = [p for p in points if len(p)]
    if not points:
        return np.zeros(3)
    return np.round(np.concatenate(points).mean(axis=0)) + 0.0  # + 0.0: no -0.0


def _shifted(geometry, offset: np.ndarray):
    """``geometry`` translated by ``-offset`` ((3,) metres)."""
    changes = {
        f.name: np.asarray(getattr(geometry, f.name), dtype=np.float64) - offset
        for f in dataclasses.fields(geometry)
        if f.name in _POSITION_FIELDS and getattr(geometry, f.name) is not None
    }
    return dataclasses.replace(geometry, **changes)


def solid_for(component: Component, *, plate_thickness: float | None = None) -> cq.Solid:
    """The valid CadQuery solid of one component, in metres in the scan frame.

    Built about :func:`local_origin` and moved into place by a location (see
    :func:`placed_solid`).

    Parameters
    ----------
    component : asbuilt.model.Component
        Its ``geometry`` decides the shape (see the module docstring).
    plate_thickness : float, metres, optional
        Thickness of plates made from planes (default ``Tolerances.plate_thickness``, 10 mm).

    Raises
    ------
    SolidBuildError
        Naming the object, when the kernel cannot build a valid solid for it.
    """
    local, origin = placed_solid(component, plate_thickness=plate_thickness)
    return place(local, origin)


def place(local: cq.Solid, origin: np.ndarray) -> cq.Solid:
    """``local`` moved by ``origin`` ((3,) metres) through a location (its geometry stays)."""
    return local.moved(cq.Location(_v(origin)))


def placed_solid(
    component: Component, *, plate_thickness: float | None = None
) -> tuple[cq.Solid, np.ndarray]:
    """The component's valid solid built about its local origin, and that origin.

    Returns
    -------
    local : cadquery.Solid
        Metres, in the scan frame's axes shifted to ``origin``.
    origin : ndarray, shape (3,), metres
        :func:`local_origin` of the geometry; ``local`` moved by it is the solid in place.

    Raises
    ------
    SolidBuildError
        Naming the object, when the kernel cannot build a valid solid for it.
    """
    geometry = component.geometry
    if plate_thickness is None:
        plate_thickness = DEFAULT_TOLERANCES.plate_thickness
    origin = np.zeros(3)
    try:
        builder = _BUILDERS.get(type(geometry))
        if builder is None and not isinstance(geometry, Plane):
            raise ValueError(f"there is no solid for geometry {type(geometry).__name__}")
        origin = local_origin(geometry)
        geometry = _shifted(geometry, origin)
        if builder is None:
            shape = plate_solid(geometry, float(plate_thickness))
        else:
            shape = builder(geometry)
    except SolidBuildError:
        raise
    except Exception as exc:  # the OCC kernel raises its own Standard_Failure types
        raise build_error(component, exc) from None
    return check_solid(shape, component.id), origin


def build_error(component: Component, exc: Exception) -> SolidBuildError:
    """The one-line error naming the object whose solid the kernel (or a check) refused."""
    reason = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    return SolidBuildError(
        f"cannot build its {component.type} solid: {reason}; check its fitted geometry",
        where=f"object {component.id}",
    )


#: The checks of the solid builders that need no kernel, by geometry.
_CHECKS = {Bend: _bend_normal, Reducer: _check_reducer, Hull: _check_closed}


def check_geometry(component: Component, *, plate_thickness: float | None = None) -> None:
    """Refuse, as :func:`placed_solid` would, a geometry no solid can be built from, without
    building the solid (for outputs that need only meshes).

    Runs the builders' own checks that need no kernel: a bend's ends and centre not collinear
    and its radius larger than the pipe's, a reducer's ends apart, a plate's outline of at
    least 3 distinct points, a hull's triangles closed (every edge shared by two). The
    kernel's validity check of the solid itself is not run.

    Raises
    ------
    SolidBuildError
        Naming the object, with :func:`placed_solid`'s message.
    """
    geometry = component.geometry
    if plate_thickness is None:
        plate_thickness = DEFAULT_TOLERANCES.plate_thickness
    try:
        if isinstance(geometry, Plane):
            _plate_base(geometry, float(plate_thickness))
        elif type(geometry) in _CHECKS:
            _CHECKS[type(geometry)](geometry)
        elif type(geometry) not in _BUILDERS:
            raise ValueError(f"there is no solid for geometry {type(geometry).__name__}")
    except Exception as exc:
        raise build_error(component, exc) from None
