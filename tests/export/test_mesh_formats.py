"""STL and OBJ through trimesh: closed meshes, the model's units, named OBJ objects."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from asbuilt.export.mesh import trimesh_scene, write_obj, write_stl


def _total_volume(zoo_cad) -> float:
    return sum(zoo_cad.mesh(part).volume for part in zoo_cad.parts)


@pytest.mark.parametrize(("units", "factor"), [("m", 1.0), ("mm", 1e9), ("in", 1 / 0.0254**3)])
def test_stl_volume_in_the_output_units(zoo_cad, tmp_path, units, factor):
    path = tmp_path / "zoo.stl"
    write_stl(zoo_cad, path, units=units)
    mesh = trimesh.load(path, file_type="stl")
    assert mesh.volume == pytest.approx(_total_volume(zoo_cad) * factor, rel=1e-5)


def test_stl_defaults_to_the_model_units(zoo_cad, tmp_path):
    assert zoo_cad.model.units == "mm"
    path = tmp_path / "zoo.stl"
    write_stl(zoo_cad, path)
    mesh = trimesh.load(path, file_type="stl")
    assert mesh.bounds[1][0] > 1000  # millimetres


def _parse_obj(text: str) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """A minimal OBJ reader (v, f, o), independent of trimesh: name -> (vertices, faces)."""
    vertices, objects, current = [], {}, None
    for line in text.splitlines():
        head, _, rest = line.partition(" ")
        if head == "v":
            vertices.append([float(x) for x in rest.split()[:3]])
        elif head == "o":
            current = objects.setdefault(rest.strip(), [])
        elif head == "f":
            current.append([int(token.split("/")[0]) - 1 for token in rest.split()])
    points = np.array(vertices)
    return {name: (points, np.array(faces)) for name, faces in objects.items()}


def test_obj_has_one_named_object_per_component(zoo_cad, tmp_path):
    path = tmp_path / "zoo.obj"
    write_obj(zoo_cad, path, units="m")
    objects = _parse_obj(path.read_text())
    assert list(objects) == [part.id for part in zoo_cad.parts]
    for part in zoo_cad.parts:
        points, faces = objects[part.id]
        tri = points[faces]
        volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
        assert volume == pytest.approx(zoo_cad.mesh(part).volume, rel=1e-6), part.id


def test_scene_meshes_are_watertight(zoo_cad):
    scene = trimesh_scene(zoo_cad, units="m")
    leaky = [name for name, mesh in scene.geometry.items() if not mesh.is_watertight]
    # The kernel-tessellated tee may keep seams; every closed-form mesh must be closed.
    assert set(leaky) <= {"T1"}
