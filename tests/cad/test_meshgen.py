"""Closed-form meshes: closed, outward, unit normals, and the same volume as the solids."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh
from cad_zoo import expected_volumes, zoo_components
from hypothesis import given, settings
from hypothesis import strategies as st

from asbuilt.cad.meshgen import SEGMENTS, mesh_for
from asbuilt.model import Bend, Reducer, Straight
from asbuilt.primitives import Cylinder, Plane

ZOO = {c.id: c for c in zoo_components()}
VOLUMES = expected_volumes()
MESHED = sorted(cid for cid, c in ZOO.items() if c.type != "tee")


def _closed(mesh) -> trimesh.Trimesh:
    vertices, faces = mesh.merged()
    return trimesh.Trimesh(vertices, faces, process=False)


@pytest.mark.parametrize("cid", MESHED)
def test_meshes_are_closed_outward_and_match_the_volume(cid):
    mesh = mesh_for(ZOO[cid].geometry, plate_thickness=0.010)
    closed = _closed(mesh)
    assert closed.is_watertight
    assert closed.is_winding_consistent
    assert mesh.volume > 0  # outward winding
    assert mesh.volume == pytest.approx(VOLUMES[cid], rel=1e-9)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)


def test_tee_has_no_closed_form_mesh():
    assert mesh_for(ZOO["T1"].geometry, plate_thickness=0.01) is None


def test_vertices_stay_near_the_true_surface():
    pipe = Straight([0, 0, 0], [2, 0, 0], 0.1)
    mesh = mesh_for(pipe, plate_thickness=0.01)
    radial = np.linalg.norm(mesh.vertices[:, 1:], axis=1)
    on_wall = radial > 1e-9
    # Equal-area polygon: vertices 0.32% outside the circle at 32 segments.
    expected = 0.1 * math.sqrt(2 * math.pi / (SEGMENTS * math.sin(2 * math.pi / SEGMENTS)))
    assert radial[on_wall] == pytest.approx(expected, rel=1e-12)
    assert expected / 0.1 - 1 < 0.004


def test_normals_point_outwards_on_a_cylinder_wall():
    mesh = mesh_for(Cylinder([0, 0, 0], [0, 0, 1], 0.5, 2.0), plate_thickness=0.01)
    radial = mesh.vertices.copy()
    radial[:, 2] = 0
    side = np.linalg.norm(radial, axis=1) > 1e-9
    side &= np.abs(mesh.normals[:, 2]) < 0.5
    cosines = np.einsum("ij,ij->i", mesh.normals[side], radial[side]) / np.linalg.norm(
        radial[side], axis=1
    )
    assert cosines.min() > 0.99


@given(
    angle=st.floats(5.0, 175.0),
    bend_radius=st.floats(0.1, 1.0),
    hollow=st.booleans(),
)
@settings(max_examples=30, deadline=None)
def test_bend_meshes_keep_pappus_volume(angle, bend_radius, hollow):
    a = math.radians(angle)
    wall = 0.01 if hollow else 0.0
    bend = Bend(
        [bend_radius, 0, 0],
        [bend_radius * math.cos(a), bend_radius * math.sin(a), 0],
        [0, 0, 0],
        0.05,
        wall,
    )
    mesh = mesh_for(bend, plate_thickness=0.01)
    area = math.pi * (0.05**2 - (0.05 - wall) ** 2) if hollow else math.pi * 0.05**2
    assert mesh.volume == pytest.approx(area * bend_radius * a, rel=1e-9)
    assert _closed(mesh).is_watertight


@given(
    r1=st.floats(0.01, 0.5),
    r2=st.floats(0.01, 0.5),
    direction=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
)
@settings(max_examples=30, deadline=None)
def test_reducer_meshes_keep_frustum_volume(r1, r2, direction):
    end = np.array(direction) / np.linalg.norm(direction) * 0.3
    mesh = mesh_for(Reducer([0, 0, 0], end, r1, r2), plate_thickness=0.01)
    assert mesh.volume == pytest.approx(math.pi * 0.3 * (r1 * r1 + r1 * r2 + r2 * r2) / 3, rel=1e-9)


def test_clockwise_outline_gives_the_same_plate():
    square = [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]
    ccw = mesh_for(Plane([0.5, 0.5, 0], [0, 0, 1], square), plate_thickness=0.02)
    cw = mesh_for(Plane([0.5, 0.5, 0], [0, 0, 1], square[::-1]), plate_thickness=0.02)
    assert ccw.volume == pytest.approx(0.02) and cw.volume == pytest.approx(0.02)


def _eccentric(r1, r2, direction, wall=0.0, turn=0.0, length=0.3):
    """An eccentric reducer from the origin along ``direction``, its end axis stepped sideways
    by the radii's difference in a direction ``turn`` radians around the run."""
    d = np.array(direction, float) / np.linalg.norm(direction)
    helper = np.array([1.0, 0, 0]) if abs(d[0]) < 0.9 else np.array([0, 1.0, 0])
    u = np.cross(d, helper)
    u /= np.linalg.norm(u)
    v = np.cross(d, u)
    offset = abs(r1 - r2) * (math.cos(turn) * u + math.sin(turn) * v)
    return Reducer([0, 0, 0], length * d + offset, r1, r2, wall, offset=offset)


def _frustum(r1, r2, h):
    """Volume of a truncated cone, right or oblique (Cavalieri): pi h (r1^2 + r1 r2 + r2^2) / 3."""
    return math.pi * h * (r1 * r1 + r1 * r2 + r2 * r2) / 3


@given(
    r1=st.floats(0.01, 0.5),
    r2=st.floats(0.01, 0.5),
    direction=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
    turn=st.floats(0, 2 * math.pi),
)
@settings(max_examples=30, deadline=None)
def test_eccentric_reducer_meshes_keep_the_oblique_frustum_volume(r1, r2, direction, turn):
    mesh = mesh_for(_eccentric(r1, r2, direction, turn=turn), plate_thickness=0.01)
    assert mesh.volume == pytest.approx(_frustum(r1, r2, 0.3), rel=1e-9)
    assert _closed(mesh).is_watertight


def test_hollow_eccentric_reducer_mesh():
    # NPS 6 x 4 STD (B36.10M: OD 168.3 / 114.3 mm, wall 7.11 / 6.02 mm), H 140 mm (B16.9)
    r6, r4, wall = 0.08415, 0.05715, 0.00602
    g = Reducer([0, 0, 0], [0.14, 0, r6 - r4], r6, r4, wall, offset=[0, 0, r6 - r4])
    mesh = mesh_for(g, plate_thickness=0.01)
    expected = _frustum(r6, r4, 0.14) - _frustum(r6 - wall, r4 - wall, 0.14)
    assert mesh.volume == pytest.approx(expected, rel=1e-9)
    assert _closed(mesh).is_watertight
    # the end rings are centred on the end centres, in planes across the run
    ring_end = mesh.vertices[np.isclose(mesh.vertices[:, 0], 0.14)]
    assert ring_end[:, 1:].mean(axis=0) == pytest.approx([0, r6 - r4], abs=1e-9)


def test_a_reducer_mesh_has_each_ends_own_wall():
    # NPS 6 x 4 SCH 40 (B36.10M: OD 168.3 / 114.3 mm, wall 7.11 / 6.02 mm), H 140 mm (B16.9)
    r6, r4, w6, w4 = 0.08415, 0.05715, 0.00711, 0.00602
    for offset in ([0, 0, 0], [0, 0, r6 - r4]):
        g = Reducer([0, 0, 0], np.array([0.14, 0, 0]) + offset, r6, r4, w6, offset, w4)
        mesh = mesh_for(g, plate_thickness=0.01)
        expected = _frustum(r6, r4, 0.14) - _frustum(r6 - w6, r4 - w4, 0.14)
        assert mesh.volume == pytest.approx(expected, rel=1e-9)
        assert _closed(mesh).is_watertight


def test_a_reducing_elbow_mesh_has_each_ends_size_and_wall():
    # NPS 6 x 4 SCH 40 (B36.10M: OD 168.3 / 114.3 mm, wall 7.11 / 6.02 mm) on a 229 mm radius
    r6, r4, w6, w4, radius = 0.08415, 0.05715, 0.00711, 0.00602, 0.229
    g = Bend([radius, 0, 0], [0, radius, 0], [0, 0, 0], r6, w6, r4, w4)
    mesh = mesh_for(g, plate_thickness=0.01)

    def tube(a, b):  # radius a -> b linear in the angle over a quarter turn (Pappus)
        return math.pi * radius * (math.pi / 2) * (a * a + a * b + b * b) / 3

    expected = tube(r6, r4) - tube(r6 - w6, r4 - w4)
    assert mesh.volume == pytest.approx(expected, rel=1e-9)
    assert _closed(mesh).is_watertight
    # the first and last rings are the ends' (enlarged to equal area by the same factor)
    rings = np.linalg.norm(mesh.vertices[:, :2], axis=1)
    at_start = np.abs(mesh.vertices[:, 1]) < 1e-12
    spread = np.ptp(rings[at_start])
    assert spread == pytest.approx(2 * r6 * (1 + 1e-3), rel=2e-2)


@pytest.mark.parametrize(
    "offset",
    [(512345.678, 4123456.789, 250.0), (500000.0, 4000000.0, 100.0), (-731000.5, 5612345.25, -3.0)],
)
def test_a_small_hull_at_survey_coordinates_is_wound_outwards(offset):
    # A 0.2 m obstacle's hull at UTM coordinates: its winding was judged by a volume summed
    # about the origin, which there is rounding noise larger than the hull (seen in review).
    from scipy.spatial import ConvexHull

    from asbuilt.fit import fit_points

    local = np.random.default_rng(3).normal(size=(30, 3)) * 0.06
    hull = fit_points("hull", local + np.asarray(offset)).primitive
    mesh = mesh_for(hull, plate_thickness=0.01)
    assert mesh.volume == pytest.approx(ConvexHull(local).volume, rel=1e-6)
    centre = mesh.vertices.mean(axis=0)
    outward = np.einsum("ij,ij->i", mesh.normals, mesh.vertices - centre)
    assert (outward > 0).all()
