"""Primitives: validation with exact messages, immutability, and distances against hand values."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere


def test_cylinder_distance_and_ends():
    cyl = Cylinder(center=[1, 2, 3], axis=[0, 0, 1], radius=0.5, length=2.0)
    pts = np.array([[1.5, 2, 3], [1, 2, 10], [3, 2, 0]])
    np.testing.assert_allclose(cyl.distance(pts), [0.0, -0.5, 1.5])
    a, b = cyl.ends
    np.testing.assert_allclose(a, [1, 2, 2])
    np.testing.assert_allclose(b, [1, 2, 4])


def test_sphere_and_plane_distance():
    np.testing.assert_allclose(Sphere([0, 0, 0], 1.0).distance([[0, 0, 3], [0, 0, 0]]), [2, -1])
    plane = Plane(point=[0, 0, 1], normal=[0, 0, 1])
    np.testing.assert_allclose(plane.distance([[5, 5, 3], [0, 0, 0]]), [2, -1])
    assert plane.outline.shape == (0, 3)


def test_cuboid_distance_inside_outside_and_corners():
    box = Cuboid(center=[0, 0, 0], axes=np.eye(3), size=[2, 4, 6])
    d = box.distance([[0, 0, 0], [2, 0, 0], [2, 3, 0]])
    np.testing.assert_allclose(d, [-1.0, 1.0, np.hypot(1, 1)])
    assert box.corners.shape == (8, 3)
    np.testing.assert_allclose(np.abs(box.corners).max(axis=0), [1, 2, 3])


def test_cuboid_left_handed_axes_are_made_right_handed():
    axes = np.diag([1.0, 1.0, -1.0])
    box = Cuboid(center=[0, 0, 0], axes=axes, size=[1, 1, 1])
    assert np.linalg.det(box.axes) == pytest.approx(1.0)


def test_hull_distance_of_a_unit_tetrahedron():
    verts = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    hull = Hull(verts, faces)
    assert hull.distance([[0.1, 0.1, 0.1]])[0] == pytest.approx(-0.1)
    assert hull.distance([[0, 0, -2]])[0] == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("factory", "message"),
    [
        (lambda: Cylinder([0, 0, 0], [0, 0, 2], 1, 1), "The axis must be a unit vector"),
        (lambda: Cylinder([0, 0, 0], [0, 0, 1], -1, 1), "The radius must be a positive"),
        (lambda: Cylinder([0, 0, np.nan], [0, 0, 1], 1, 1), "The center must be finite."),
        (lambda: Cylinder([0, 0], [0, 0, 1], 1, 1), "The center must have shape (3,)"),
        (lambda: Sphere([0, 0, 0], 0.0), "The radius must be a positive"),
        (lambda: Plane([0, 0, 0], [1, 1, 0]), "The normal must be a unit vector"),
        (lambda: Cuboid([0, 0, 0], np.ones((3, 3)), [1, 1, 1]), "The axes must be orthonormal."),
        (lambda: Cuboid([0, 0, 0], np.eye(3), [1, 0, 1]), "The size must be positive"),
        (lambda: Hull([[0, 0, 0]] * 3, [[0, 1, 2]] * 4), "A hull needs at least 4 vertices."),
        (lambda: Hull(np.eye(4)[:, :3], [[0, 1, 9]] * 4), "The faces must index the vertices."),
    ],
)
def test_validation_messages(factory, message):
    with pytest.raises(ValueError) as info:
        factory()
    assert str(info.value).startswith(message)


def test_arrays_are_read_only_float64_copies():
    center = np.array([0.0, 0.0, 0.0])
    cyl = Cylinder(center, [0, 0, 1], 1, 1)
    center[0] = 5.0
    assert cyl.center[0] == 0.0
    assert cyl.center.dtype == np.float64
    with pytest.raises(ValueError):
        cyl.center[0] = 1.0
    with pytest.raises(AttributeError):
        cyl.radius = 2.0  # type: ignore[misc]


def test_hull_distance_in_blocks_equals_the_direct_product():
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(2)
    sphere = rng.normal(size=(3000, 3))
    sphere /= np.linalg.norm(sphere, axis=1)[:, None]
    hull = ConvexHull(sphere)
    used = np.unique(hull.simplices)
    remap = np.full(len(sphere), -1)
    remap[used] = np.arange(len(used))
    shape = Hull(sphere[used], remap[hull.simplices])
    points = rng.uniform(-1.5, 1.5, (3000, 3))  # 3,000 x ~6,000 faces: several blocks
    tri = shape.vertices[shape.faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = np.einsum("ij,ij->i", normals, tri[:, 0])
    direct = (points @ normals.T - offsets).max(axis=1)
    np.testing.assert_allclose(shape.distance(points), direct, rtol=0, atol=1e-12)


# Site coordinates (UTM, state plane in feet): eastings and northings of 1e5 to 1.2e7.
_SITE_OFFSETS = [(0.0, 0.0, 0.0), (512345.678, 5403210.123, 250.0), (4.0e6, 1.2e7, 300.0)]


@pytest.mark.parametrize("offset", _SITE_OFFSETS)
def test_hull_volume_and_area_of_a_rotated_unit_cube_anywhere(offset):
    # A unit cube (volume 1 m³, area 6 m²) turned 30 degrees about z, as 12 outward triangles.
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    turn = np.radians(30.0)
    rotation = np.array(
        [[np.cos(turn), -np.sin(turn), 0], [np.sin(turn), np.cos(turn), 0], [0, 0, 1]]
    )
    faces = [
        [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
        [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3],
    ]  # fmt: skip
    hull = Hull(corners @ rotation.T + np.array(offset), faces)
    assert hull.volume == pytest.approx(1.0, abs=1e-6)
    assert hull.area == pytest.approx(6.0, abs=1e-6)


@pytest.mark.parametrize("offset", _SITE_OFFSETS)
def test_plane_area_of_a_sloped_rectangle_anywhere(offset):
    # A 3 m x 2 m rectangle on a plane sloped 20 degrees: 6 m².
    slope = np.radians(20.0)
    u = np.array([1.0, 0.0, 0.0])
    v = np.array([0.0, np.cos(slope), np.sin(slope)])
    outline = np.array([0 * u, 3 * u, 3 * u + 2 * v, 2 * v]) + np.array(offset)
    plane = Plane(point=outline[0], normal=np.cross(u, v), outline=outline)
    assert plane.area == pytest.approx(6.0, abs=1e-6)
    assert Plane(point=[0, 0, 0], normal=[0, 0, 1]).area == 0.0
