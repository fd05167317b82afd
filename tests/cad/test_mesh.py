"""Kernel tessellation and the Mesh value object."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from cad_zoo import expected_volumes, zoo_components

from asbuilt.cad.mesh import Mesh, tessellate, vertex_normals
from asbuilt.cad.solids import solid_for

ZOO = {c.id: c for c in zoo_components()}


@pytest.mark.parametrize("cid", ["T1", "C1", "SP", "E1"])
def test_tessellated_solids_are_closed_with_the_solid_volume(cid):
    solid = solid_for(ZOO[cid])
    mesh = tessellate(solid)
    vertices, faces = mesh.merged()
    closed = trimesh.Trimesh(vertices, faces, process=False)
    assert closed.is_winding_consistent
    assert mesh.volume == pytest.approx(expected_volumes()[cid], rel=0.01)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1.0)


def test_mesh_volume_and_merge_on_a_unit_cube():
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    hull = trimesh.convex.convex_hull(corners)
    # Duplicate every vertex per triangle, as a per-face tessellation does.
    vertices = hull.vertices[hull.faces].reshape(-1, 3)
    faces = np.arange(len(vertices)).reshape(-1, 3)
    mesh = Mesh(vertices, faces, vertex_normals(vertices, faces))
    assert mesh.volume == pytest.approx(1.0)
    merged_vertices, merged_faces = mesh.merged()
    assert len(merged_vertices) == 8
    assert trimesh.Trimesh(merged_vertices, merged_faces, process=False).is_watertight


def test_mesh_volume_at_survey_coordinates():
    """A 0.1 m cube 5,000 km from the origin: summed about the origin, the volume was noise
    (and the mesh-only checks refused a sample's elbow as enclosing no volume)."""
    corners = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    hull = trimesh.convex.convex_hull(corners)
    vertices = hull.vertices * 0.1 + [500_000.0, 5_000_000.0, 250.0]
    mesh = Mesh(vertices, hull.faces, vertex_normals(vertices, hull.faces))
    assert mesh.volume == pytest.approx(1e-3, rel=1e-6)


def test_vertex_normals_of_a_flat_patch_are_its_normal():
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], float)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    assert np.allclose(vertex_normals(vertices, faces), [0, 0, 1])
