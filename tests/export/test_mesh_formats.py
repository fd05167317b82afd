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


def _pipe_at(offset, units: str):
    from asbuilt.model import Component, Model, Straight

    start = np.asarray(offset, dtype=float)
    pipe = Component("P1", "pipe", Straight(start, start + [2.0, 0.0, 0.0], 0.05))
    return Model(components=(pipe,), units=units, name="survey")


# float32 spacing near 5e6 is 2**(22 - 23) = 0.5, near 5e9 it is 2**(32 - 23) = 512: rounding
# moves a vertex by up to half of it, 250 mm (metres) or 256 mm (millimetres).
@pytest.mark.parametrize(("units", "worst"), [("m", "250 mm"), ("mm", "256 mm")])
def test_stl_at_survey_coordinates_is_refused_and_nothing_written(tmp_path, units, worst):
    from asbuilt.errors import ExportError
    from asbuilt.export import export_models

    model = _pipe_at([500_000.0, 5_000_000.0, 250.0], units)
    stl, obj = tmp_path / "survey.stl", tmp_path / "survey.obj"
    with pytest.raises(ExportError) as err:
        export_models(model, [obj, stl])
    message = str(err.value)
    assert message.startswith(f"{stl}: binary STL stores float32 coordinates")
    assert f"up to {worst}" in message and ".obj" in message and ".step" in message
    assert "\n" not in message
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def test_stl_cli_refusal_exits_2(tmp_path, capsys):
    import json
    from pathlib import Path

    from asbuilt.cli import main

    scan = json.loads((Path(__file__).parents[2] / "samples" / "spool.json").read_text())
    offset = [500_000.0, 5_000_000.0, 250.0]
    for entry in scan["objects"]:
        entry["points"] = [[p + o for p, o in zip(point, offset)] for point in entry["points"]]
    if (scan.get("sensor") or {}).get("position"):
        scan["sensor"]["position"] = [p + o for p, o in zip(scan["sensor"]["position"], offset)]
    document = tmp_path / "survey.json"
    document.write_text(json.dumps(scan))
    assert main(["model", str(document), "--out", str(tmp_path / "survey.stl")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "float32" in err
    assert not (tmp_path / "survey.stl").exists()


def test_stl_1_km_from_the_origin_in_mm_keeps_0_1_mm(tmp_path):
    from asbuilt.cad import prepare

    cad = prepare(_pipe_at([1000.0, 0.0, 0.0], "mm"))
    path = tmp_path / "km.stl"
    write_stl(cad, path)
    written = trimesh.load(path, file_type="stl").vertices
    exact = cad.mesh(cad.parts[0]).vertices * 1000.0
    # Every written vertex is within 0.1 mm of an exact one (float32 spacing at 1e6 is 1/16).
    nearest = np.min(np.linalg.norm(written[:, None, :] - exact[None, :, :], axis=2), axis=1)
    assert nearest.max() < 0.1
