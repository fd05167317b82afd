"""Solids: valid, right volume (from formulas), right place; clear errors naming the object."""

from __future__ import annotations

import math

import numpy as np
import pytest
from cad_zoo import expected_volumes, zoo_components
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull
from scipy.spatial.transform import Rotation

from asbuilt.cad.solids import plate_solid, solid_for
from asbuilt.errors import ExportError, SolidBuildError
from asbuilt.model import Bend, Component, Straight
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

ZOO = {c.id: c for c in zoo_components()}
VOLUMES = expected_volumes()


@pytest.mark.parametrize("cid", sorted(ZOO))
def test_every_geometry_gives_one_valid_solid_with_the_formula_volume(cid):
    solid = solid_for(ZOO[cid])
    assert solid.isValid()
    assert len(solid.Solids()) == 1
    assert solid.Volume() == pytest.approx(VOLUMES[cid], rel=1e-5)


@pytest.mark.parametrize(
    ("cid", "low", "high"),
    [
        ("P1", (0, -0.05715, -0.05715), (1, 0.05715, 0.05715)),
        ("CY", (4.85, -0.15, 0.0), (5.15, 0.15, 3.0)),
        ("SP", (6.5, -0.5, 0.5), (7.5, 0.5, 1.5)),
        ("PL", (7, -1, -0.005), (9, 1, 0.005)),
    ],
)
def test_solids_sit_where_the_geometry_says(cid, low, high):
    box = solid_for(ZOO[cid]).BoundingBox()
    assert (box.xmin, box.ymin, box.zmin) == pytest.approx(low, abs=2e-4)
    assert (box.xmax, box.ymax, box.zmax) == pytest.approx(high, abs=2e-4)


def test_hollow_pipe_is_an_annulus_and_solid_bar_without_wall():
    hollow = solid_for(Component("P", "pipe", Straight([0, 0, 0], [0, 0, 2], 0.1, 0.01)))
    bar = solid_for(Component("P", "pipe", Straight([0, 0, 0], [0, 0, 2], 0.1)))
    assert hollow.Volume() == pytest.approx(math.pi * (0.1**2 - 0.09**2) * 2, rel=1e-9)
    assert bar.Volume() == pytest.approx(math.pi * 0.1**2 * 2, rel=1e-9)
    assert len(hollow.Faces()) > len(bar.Faces())  # the bore adds a face


@pytest.mark.parametrize("thickness", [0.001, 0.010, 0.05])
def test_plate_thickness_is_configurable_and_centred_on_the_plane(thickness):
    plane = Plane([0, 0, 1], [0, 0, 1], [[0, 0, 1], [2, 0, 1], [2, 3, 1], [0, 3, 1]])
    solid = plate_solid(plane, thickness)
    assert solid.Volume() == pytest.approx(6 * thickness, rel=1e-9)
    box = solid.BoundingBox()
    assert (box.zmin, box.zmax) == pytest.approx((1 - thickness / 2, 1 + thickness / 2))


def test_plate_from_an_outline_slightly_off_the_plane_is_projected():
    outline = [[0, 0, 0.001], [1, 0, -0.001], [1, 1, 0.002], [0, 1, 0]]
    plane = Plane([0.5, 0.5, 0], [0, 0, 1], outline)
    solid = solid_for(Component("F", "plane", plane), plate_thickness=0.02)
    assert solid.Volume() == pytest.approx(0.02, rel=1e-9)


@given(
    axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
    radius=st.floats(0.01, 1.0),
    length=st.floats(0.05, 10.0),
)
@settings(max_examples=25, deadline=None)
def test_cylinders_in_any_direction(axis, radius, length):
    axis = np.array(axis) / np.linalg.norm(axis)
    solid = solid_for(Component("C", "cylinder", Cylinder([1, 2, 3], axis, radius, length)))
    assert solid.isValid()
    assert solid.Volume() == pytest.approx(math.pi * radius**2 * length, rel=1e-6)
    centre = solid.Center()
    assert (centre.x, centre.y, centre.z) == pytest.approx((1, 2, 3), abs=1e-6 * length + 1e-9)


@given(
    angles=st.tuples(*[st.floats(-180, 180)] * 3),
    size=st.tuples(*[st.floats(0.01, 5.0)] * 3),
)
@settings(max_examples=25, deadline=None)
def test_cuboids_in_any_orientation_have_their_corners(angles, size):
    axes = Rotation.from_euler("xyz", angles, degrees=True).as_matrix().T
    cuboid = Cuboid([0.5, -1, 2], axes, size)
    solid = solid_for(Component("B", "cuboid", cuboid))
    assert solid.Volume() == pytest.approx(np.prod(size), rel=1e-9)
    vertices = np.array([v.toTuple() for v in solid.Vertices()])
    corners = cuboid.corners
    distance = np.linalg.norm(vertices[:, None, :] - corners[None, :, :], axis=2).min(axis=0)
    assert distance.max() < 1e-9


@given(seed=st.integers(0, 10_000), count=st.integers(6, 40))
@settings(max_examples=20, deadline=None)
def test_hulls_sew_into_a_closed_solid_of_qhull_volume(seed, count):
    points = np.random.default_rng(seed).uniform(-1, 1, size=(count, 3))
    hull = ConvexHull(points)
    # Qhull's triangles are not oriented; the builder must cope with any winding.
    solid = solid_for(Component("H", "hull", Hull(points, hull.simplices)))
    assert solid.isValid()
    assert solid.Volume() == pytest.approx(hull.volume, rel=1e-9)


@pytest.mark.parametrize("angle", [15.0, 45.0, 90.0, 135.0])
def test_bends_follow_pappus(angle):
    a = math.radians(angle)
    bend = Bend([0.3, 0, 0], [0.3 * math.cos(a), 0.3 * math.sin(a), 0], [0, 0, 0], 0.05, 0.004)
    solid = solid_for(Component("E", "elbow", bend))
    area = math.pi * (0.05**2 - 0.046**2)
    assert solid.Volume() == pytest.approx(area * 0.3 * a, rel=1e-7)


@pytest.mark.parametrize(
    ("component", "words"),
    [
        (Component("F7", "plane", Plane([0, 0, 0], [0, 0, 1])), "no outline"),
        (
            Component(
                "F8", "plane", Plane([0, 0, 0], [0, 0, 1], [[0, 0, 0], [1, 0, 0], [1, 0, 0]])
            ),
            "fewer than 3",
        ),
        (
            Component("E3", "elbow", Bend([0.05, 0, 0], [0, 0.05, 0], [0, 0, 0], 0.06)),
            "not larger than the outer radius",
        ),
        (
            Component("E4", "elbow", Bend([1, 0, 0], [-1, 0, 0], [0, 0, 0], 0.06)),
            "bend plane is undefined",
        ),
    ],
)
def test_impossible_solids_raise_one_line_naming_the_object(component, words):
    with pytest.raises(SolidBuildError) as info:
        solid_for(component)
    message = str(info.value)
    assert message.startswith(f"object {component.id}: ")
    assert words in message
    assert "\n" not in message
    assert isinstance(info.value, ExportError)


def test_degenerate_hull_is_a_solid_build_error():
    flat = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]], float)
    hull = Hull(flat, [[0, 1, 2], [1, 3, 2], [0, 2, 1], [1, 2, 3]])
    with pytest.raises(SolidBuildError, match="object HX"):
        solid_for(Component("HX", "hull", hull))


def test_sphere_solid_is_whole():
    solid = solid_for(Component("S", "sphere", Sphere([0, 0, 0], 2.0)))
    assert solid.Volume() == pytest.approx(4 / 3 * math.pi * 8, rel=1e-9)


def test_coplanar_hull_triangles_become_one_face_each():
    import trimesh

    box = trimesh.creation.box(extents=[1.0, 2.0, 3.0])
    solid = solid_for(Component("HB", "hull", Hull(box.vertices, box.faces)))
    assert len(solid.Faces()) == 6
    assert solid.Volume() == pytest.approx(6.0)


def test_non_convex_closed_mesh_keeps_its_triangles():
    # An L-shaped prism, 0.5 high: a closed but non-convex polyhedron.
    ell = np.array([(0, 0), (2, 0), (2, 1), (1, 1), (1, 2), (0, 2)], float)
    n = len(ell)
    vertices = np.vstack([np.c_[ell, np.zeros(n)], np.c_[ell, np.full(n, 0.5)]])
    fan = [(0, i, i + 1) for i in range(1, n - 1)]  # the L is star-shaped from vertex 0
    faces = [(a, c, b) for a, b, c in fan] + [(a + n, b + n, c + n) for a, b, c in fan]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    solid = solid_for(Component("HL", "hull", Hull(vertices, faces)))
    assert solid.isValid()
    assert solid.Volume() == pytest.approx(3.0 * 0.5)


@pytest.mark.parametrize("wall", [0.0, 0.00602])
@pytest.mark.parametrize("offset", [[0, 0, 0.027], [0, -0.027, 0], [0, 0.0191, -0.0191]])
def test_eccentric_reducer_is_a_valid_oblique_frustum(wall, offset):
    """NPS 6 x 4 (OD 168.3 / 114.3 mm, B36.10M), H = 140 mm (B16.9), axes 27 mm apart: the
    volume of an oblique frustum equals the right frustum's (Cavalieri)."""
    from asbuilt.model import Reducer

    r6, r4, h = 0.08415, 0.05715, 0.14
    offset = np.array(offset) * (r6 - r4) / np.linalg.norm(offset)
    g = Reducer([2, 1, 1], np.array([2 + h, 1, 1]) + offset, r6, r4, wall, offset=offset)
    solid = solid_for(Component("R1", "reducer", g))

    def frustum(a, b):
        return math.pi * h * (a * a + a * b + b * b) / 3

    assert solid.isValid() and len(solid.Solids()) == 1
    expected = frustum(r6, r4) - (frustum(r6 - wall, r4 - wall) if wall else 0.0)
    assert solid.Volume() == pytest.approx(expected, rel=1e-6)
    # flush on the flat side (the small end is stepped towards it): both outer end circles
    # reach the large radius along it
    flat = offset / np.linalg.norm(offset)
    reach = {}
    for edge in solid.Edges():
        if edge.geomType() == "CIRCLE" and edge.radius() in (pytest.approx(r6), pytest.approx(r4)):
            points = np.array([edge.positionAt(t).toTuple() for t in np.linspace(0, 1, 721)])
            reach[round(edge.radius(), 5)] = float(((points - [2, 1, 1]) @ flat).max())
    assert reach == {
        round(r6, 5): pytest.approx(r6, abs=1e-5),
        round(r4, 5): pytest.approx(r6, abs=1e-5),
    }


def _circles_at(solid, point) -> list[float]:
    """Radii (m) of the circular edges centred on ``point`` (3,), smallest first."""
    radii = []
    for edge in solid.Edges():
        if edge.geomType() == "CIRCLE" and np.allclose(edge.Center().toTuple(), point, atol=1e-7):
            radii.append(edge.radius())
    return sorted(radii)


# NPS 6 / 4 / 2 SCH 40 (ASME B36.10M): OD 168.3 / 114.3 / 60.3 mm, wall 7.11 / 6.02 / 3.91 mm;
# NPS 6 x 4 reducer H = 140 mm (ASME B16.9)
R6, R4, R2, W6, W4, W2 = 0.08415, 0.05715, 0.03015, 0.00711, 0.00602, 0.00391


@pytest.mark.parametrize("step", [0.0, R6 - R4])
def test_a_reducers_bore_is_a_cone_from_one_ends_bore_to_the_others(step):
    """Each end circle of the bore is its pipe's bore; the volume is the outer frustum less
    the bore's (concentric and eccentric alike, Cavalieri)."""
    from asbuilt.model import Reducer

    h, offset = 0.14, np.array([0.0, 0.0, step])
    g = Reducer([2, 1, 1], np.array([2 + h, 1, 1]) + offset, R6, R4, W6, offset, W4)
    solid = solid_for(Component("R1", "reducer", g))

    def frustum(a, b):
        return math.pi * h * (a * a + a * b + b * b) / 3

    assert solid.isValid() and len(solid.Solids()) == 1
    assert solid.Volume() == pytest.approx(frustum(R6, R4) - frustum(R6 - W6, R4 - W4), rel=1e-6)
    assert _circles_at(solid, g.start) == pytest.approx([R6 - W6, R6], abs=1e-9)
    assert _circles_at(solid, g.end) == pytest.approx([R4 - W4, R4], abs=1e-9)


def test_a_reducing_tees_bores_are_the_run_pipes_and_the_outlet_pipes():
    from asbuilt.model import Tee

    c = np.array([0.0, 0.0, 1.0])
    g = Tee(c, c - [0.143, 0, 0], c + [0.143, 0, 0], c + [0, 0.143, 0], R6, R2, W6, W2)
    solid = solid_for(Component("T1", "tee", g))
    assert solid.isValid() and len(solid.Solids()) == 1
    for end in (g.run_start, g.run_end):
        assert _circles_at(solid, end) == pytest.approx([R6 - W6, R6], abs=1e-9)
    assert _circles_at(solid, g.branch_end) == pytest.approx([R2 - W2, R2], abs=1e-9)


def _sampled_radii_at(solid, point) -> list[float]:
    """Mean distance (m) from ``point`` (3,) of each edge of ``solid`` that keeps a constant
    distance from it (to 1 um) on 64 samples, equal ones (to 1 um) once, smallest first."""
    radii = []
    for edge in solid.Edges():
        samples = [edge.positionAt(t).toTuple() for t in np.linspace(0, 1, 64)]
        distance = np.linalg.norm(np.array(samples) - point, axis=1)
        if np.ptp(distance) < 1e-6:
            radii.append(float(distance.mean()))
    merged = []  # a swept circle comes in two halves
    for radius in sorted(radii):
        if not merged or radius - merged[-1] > 1e-6:
            merged.append(radius)
    return merged


def _reducing_bend_volume(radius, angle, r1, r2) -> float:
    """Volume (m^3) of a tube of radius r1 -> r2, linear in the angle, about a bend: Pappus
    over each slice, pi R angle (r1^2 + r1 r2 + r2^2) / 3."""
    return math.pi * radius * angle * (r1 * r1 + r1 * r2 + r2 * r2) / 3


@pytest.mark.parametrize("angle_deg", [90.0, 45.0])
def test_a_reducing_elbow_has_each_pipes_circles_at_its_ends(angle_deg):
    """NPS 6 x 4 SCH 40 on the NPS 6 long radius (229 mm): each end's outside and bore are its
    pipe's, and the volume is that of radii changing evenly with the angle turned (to 5e-6)."""
    radius, angle = 0.229, math.radians(angle_deg)
    c = np.array([1.0, 2.0, 0.5])
    end = c + radius * np.array([math.cos(angle), math.sin(angle), 0.0])
    g = Bend(c + [radius, 0, 0], end, c, R6, W6, R4, W4)
    solid = solid_for(Component("E1", "elbow", g))
    assert solid.isValid() and len(solid.Solids()) == 1
    # the swept ends are B-spline circles: sampled, within 0.2 um of each pipe's radii
    assert _sampled_radii_at(solid, g.start) == pytest.approx([R6 - W6, R6], abs=2e-7)
    assert _sampled_radii_at(solid, g.end) == pytest.approx([R4 - W4, R4], abs=2e-7)
    expected = _reducing_bend_volume(radius, angle, R6, R4) - _reducing_bend_volume(
        radius, angle, R6 - W6, R4 - W4
    )
    assert solid.Volume() == pytest.approx(expected, rel=1e-4)
    solid_bar = solid_for(Component("E2", "elbow", Bend(g.start, g.end, c, R6, 0, R4, 0)))
    assert solid_bar.Volume() == pytest.approx(
        _reducing_bend_volume(radius, angle, R6, R4), rel=1e-4
    )
