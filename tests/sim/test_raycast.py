"""Ray casting against analytic truths: hit distances, normals, occlusion, meshes."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asbuilt.sim.geometry import frustum_mesh, rotation_zyx
from asbuilt.sim.raycast import (
    BoxShape,
    CylinderShape,
    MeshShape,
    PlaneShape,
    SphereShape,
    angles_from_direction,
    direction_from_angles,
    raycast,
)

X = np.array([1.0, 0.0, 0.0])


def cast(shape, origin, direction):
    hits = raycast([shape], np.array([origin], float), np.array([direction], float))
    return float(hits.range[0]), hits.normal[0], float(hits.cos_incidence[0])


@pytest.mark.parametrize(
    "origin, direction, expected",
    [
        ([0, 0, 0], [1, 0, 0], 4.0),  # head-on
        ([0, 0, 0], [-1, 0, 0], np.inf),  # pointing away
        ([5, 0, 0], [1, 0, 0], 1.0),  # from the centre: the exit
        ([0, 0.6, 0], [1, 0, 0], 5.0 - 0.8),  # off-centre chord: sqrt(1 - 0.36) = 0.8
        ([0, 1.0, 0], [1, 0, 0], 5.0),  # tangent
        ([0, 1.01, 0], [1, 0, 0], np.inf),
    ],
)
def test_sphere_hit_distances(origin, direction, expected):
    t, _, _ = cast(SphereShape(center=np.array([5.0, 0, 0]), radius=1.0), origin, direction)
    assert t == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize(
    "origin, direction, expected, normal",
    [
        ([0, 0, 0], [1, 0, 0], 4.5, [-1, 0, 0]),  # lateral surface, head-on
        ([0, 0, 0.3], [1, 0, 0], 5.0 - 0.4, [-0.8, 0, 0.6]),  # 0.5^2 - 0.3^2 = 0.4^2
        ([5, -3, 0], [0, 1, 0], 1.0, [0, -1, 0]),  # along the axis into the bottom cap
        ([5, 3, 0.2], [0, -1, 0], 1.0, [0, 1, 0]),  # top cap, off-axis
        ([5, 3, 0.6], [0, -1, 0], np.inf, [0, 0, 0]),  # outside the cap's disc
        ([0, 2.5, 0], [1, 0, 0], np.inf, [0, 0, 0]),  # beyond the end
        ([5, 0, 0], [0, 0, 1], 0.5, [0, 0, 1]),  # from inside: the exit
    ],
)
def test_cylinder_hit_distances_and_normals(origin, direction, expected, normal):
    shape = CylinderShape(start=np.array([5.0, -2.0, 0]), end=np.array([5.0, 2.0, 0]), radius=0.5)
    t, n, _ = cast(shape, origin, direction)
    assert t == pytest.approx(expected, abs=1e-9)
    np.testing.assert_allclose(n, normal, atol=1e-9)


def test_open_cylinder_has_no_caps():
    shape = CylinderShape(
        start=np.array([5.0, -2.0, 0]), end=np.array([5.0, 2.0, 0]), radius=0.5, capped=False
    )
    t, _, _ = cast(shape, [5, -3, 0.2], [0, 1, 0])
    assert t == np.inf


@pytest.mark.parametrize(
    "origin, direction, expected, normal",
    [
        ([0, 0, 0], [1, 0, 0], 9.5, [-1, 0, 0]),
        ([10, 5, 0], [0, -1, 0], 4.0, [0, 1, 0]),  # +y face (half size 1 along y)
        ([10, 0, -5], [0, 0, 1], 3.5, [0, 0, -1]),  # bottom (half size 1.5 along z)
        ([0, 2, 0], [1, 0, 0], np.inf, [0, 0, 0]),  # parallel to a slab, outside it
        ([10, 0, 0], [0, 1, 0], 1.0, [0, 1, 0]),  # from inside: the exit face
    ],
)
def test_box_slab_method(origin, direction, expected, normal):
    box = BoxShape(center=np.array([10.0, 0, 0]), axes=np.eye(3), size=np.array([1.0, 2.0, 3.0]))
    t, n, cos = cast(box, origin, direction)
    assert t == pytest.approx(expected, abs=1e-9)
    np.testing.assert_allclose(n, normal, atol=1e-9)
    assert cos == pytest.approx(1.0 if np.isfinite(expected) else 0.0)


def test_rotated_box_corner_distance():
    # A unit cube turned 45 degrees about z presents its vertical edge: the ray meets it at
    # distance centre - half diagonal.
    box = BoxShape(center=np.array([5.0, 0, 0]), axes=rotation_zyx(45, 0, 0), size=np.ones(3))
    t, _, _ = cast(box, [0, 0, 0], [1, 0, 0])
    assert t == pytest.approx(5.0 - np.sqrt(0.5), abs=1e-9)


def test_plane_and_incidence():
    plane = PlaneShape(point=np.array([0.0, 0, 0]), normal=np.array([0.0, 0, 1]))
    d = np.array([1.0, 0, -1]) / np.sqrt(2)
    t, n, cos = cast(plane, [0, 0, 2], d)
    assert t == pytest.approx(2 * np.sqrt(2))
    np.testing.assert_allclose(n, [0, 0, 1])
    assert cos == pytest.approx(np.cos(np.radians(45)))


def test_mesh_matches_analytic_box():
    box = BoxShape(
        center=np.array([3.0, 1.0, 0.5]),
        axes=rotation_zyx(20, 10, 5),
        size=np.array([1.0, 0.6, 0.8]),
    )
    corners = box.corners()
    # 12 triangles of the box from its corners (index bits: x, y, z signs).
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    faces = [[a, b, c] for a, b, c, _ in quads] + [[a, c, d] for a, _, c, d in quads]
    mesh = MeshShape(vertices=corners, faces=np.array(faces))
    rng = np.random.default_rng(1)
    targets = box.center + rng.uniform(-0.6, 0.6, size=(300, 3))
    origins = np.zeros((300, 3))
    a = raycast([box], origins, targets - origins)
    b = raycast([mesh], origins, targets - origins)
    np.testing.assert_array_equal(a.object_index, b.object_index)
    hit = a.hit
    assert hit.sum() > 100
    np.testing.assert_allclose(a.range[hit], b.range[hit], atol=1e-9)
    np.testing.assert_allclose(a.cos_incidence[hit], b.cos_incidence[hit], atol=1e-9)


def test_frustum_mesh_radius():
    vertices, faces = frustum_mesh([0, 0, 0], [0, 0, 1], 0.2, 0.1, segments=256)
    mesh = MeshShape(vertices=vertices, faces=faces)
    t, _, _ = cast(mesh, [-5, 0, 0.5], [1, 0, 0])
    # radius 0.15 at mid-height (polygon: between the inscribed and the circumscribed circle)
    assert 5 - 0.15 <= t <= 5 - 0.15 * np.cos(np.pi / 256) + 1e-9


def test_occlusion_nearest_object_wins():
    near = SphereShape(center=np.array([3.0, 0, 0]), radius=0.5)
    far = BoxShape(center=np.array([8.0, 0, 0]), axes=np.eye(3), size=np.ones(3) * 4)
    dirs = np.array([[1.0, 0, 0], [1.0, 0.2, 0]])
    hits = raycast([far, near], np.zeros(3), dirs)
    assert hits.object_index.tolist() == [1, 0]
    assert hits.range[0] == pytest.approx(2.5)
    assert hits.range[1] == pytest.approx(6.0 * np.sqrt(1 + 0.04))
    behind = raycast([far, near], np.zeros(3), dirs, exclude=1)
    assert behind.object_index.tolist() == [0, 0]
    assert behind.range[0] == pytest.approx(6.0)


def test_miss_conventions():
    hits = raycast(
        [SphereShape(center=np.array([3.0, 0, 0]), radius=0.5)],
        np.zeros(3),
        np.array([[0.0, 1, 0]]),
    )
    assert hits.range[0] == np.inf and hits.object_index[0] == -1
    assert hits.cos_incidence[0] == 0 and not hits.hit[0]
    assert np.isnan(hits.points(np.zeros(3), np.array([[0.0, 1, 0]]))).all()


def test_bad_rays_rejected():
    with pytest.raises(ValueError):
        raycast([], np.zeros((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError):
        raycast([], np.zeros((2, 3)), np.ones((3, 3)))


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-3, 3),
    st.floats(-3, 3),
    st.floats(-3, 3),
    st.floats(0.05, 2.0),
    st.floats(-np.pi, np.pi),
    st.floats(-1.4, 1.4),
)
def test_cylinder_hits_lie_on_surface(cx, cy, cz, radius, pan, tilt):
    axis = direction_from_angles(pan, tilt)
    centre = np.array([cx, cy, cz]) + np.array([10.0, 0, 0])
    shape = CylinderShape(start=centre - axis, end=centre + axis, radius=radius)
    rng = np.random.default_rng(0)
    targets = centre + rng.normal(scale=radius, size=(50, 3))
    hits = raycast([shape], np.zeros(3), targets)
    pts = hits.points(np.zeros(3), targets)[hits.hit]
    rel = pts - shape.start
    h = rel @ axis
    radial = np.linalg.norm(rel - np.outer(h, axis), axis=1)
    on_side = np.abs(radial - radius) < 1e-7
    on_cap = (np.abs(h) < 1e-7) | (np.abs(h - 2.0) < 1e-7)
    assert np.all(on_side | on_cap)
    assert np.all((h > -1e-7) & (h < 2.0 + 1e-7))


@settings(max_examples=40, deadline=None)
@given(st.floats(-np.pi, np.pi), st.floats(-1.5, 1.5))
def test_angles_round_trip(pan, tilt):
    p, t = angles_from_direction(direction_from_angles(pan, tilt))
    assert float(t) == pytest.approx(tilt, abs=1e-12)
    assert np.cos(float(p) - pan) == pytest.approx(1.0, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    st.floats(-180, 180),
    st.floats(-80, 80),
    st.floats(-180, 180),
    st.tuples(st.floats(0.05, 3), st.floats(0.05, 3), st.floats(0.05, 3)),
)
def test_box_hits_lie_on_the_cuboid_surface(yaw, pitch, roll, size):
    from asbuilt.primitives import Cuboid

    axes = rotation_zyx(yaw, pitch, roll)
    centre = np.array([6.0, -1.0, 0.5])
    box = BoxShape(center=centre, axes=axes, size=np.array(size))
    truth = Cuboid(center=centre, axes=axes, size=np.array(size))
    rng = np.random.default_rng(0)
    # aim at points inside the box: every ray hits it
    targets = centre + (rng.uniform(-0.5, 0.5, size=(80, 3)) * np.array(size)) @ axes
    hits = raycast([box], np.zeros(3), targets)
    assert hits.hit.all()
    pts = hits.points(np.zeros(3), targets)
    assert np.abs(truth.distance(pts)).max() < 1e-9
    # the normal at the hit is the outward normal of a face, facing the ray
    normals = hits.normal[hits.hit]
    assert np.allclose(np.abs(normals @ axes.T).max(axis=1), 1.0)
    assert np.all(np.einsum("ij,ij->i", normals, targets[hits.hit]) < 0)
