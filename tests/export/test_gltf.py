"""glTF/GLB: validator-clean, named nodes in the scan > group > object tree, Y up, metres."""

from __future__ import annotations

import base64
import json

import numpy as np
import pytest
import trimesh

from asbuilt.cad import prepare
from asbuilt.cad.colours import KIND_COLOURS, STATUS_COLOURS
from asbuilt.export.gltf import read_glb, write_gltf, z_up_to_y_up
from asbuilt.model import Component, Model, Straight


@pytest.fixture(scope="module")
def glb(zoo_cad, tmp_path_factory):
    path = tmp_path_factory.mktemp("gltf") / "zoo.glb"
    write_gltf(zoo_cad, path)
    return path


def _accessor(document, data, index):
    accessor = document["accessors"][index]
    view = document["bufferViews"][accessor["bufferView"]]
    dtype = {5126: np.float32, 5123: np.uint16, 5125: np.uint32}[accessor["componentType"]]
    width = {"SCALAR": 1, "VEC3": 3}[accessor["type"]]
    raw = np.frombuffer(
        data, dtype=dtype, count=accessor["count"] * width, offset=view["byteOffset"]
    )
    return raw.reshape(-1, width) if width > 1 else raw


def test_golden_glb_and_gltf_pass_the_khronos_validator(zoo_cad, glb, tmp_path, gltf_validator):
    text = tmp_path / "zoo.gltf"
    write_gltf(zoo_cad, text)
    reports = gltf_validator(glb, text)
    assert [r["errors"] for r in reports] == [0, 0], reports
    assert [r["warnings"] for r in reports] == [0, 0], reports


def test_validator_reports_a_broken_file(tmp_path, gltf_validator):
    bad = tmp_path / "bad.gltf"
    bad.write_text(json.dumps({"asset": {"version": "2.0"}, "nodes": [{"mesh": 3}]}))
    (report,) = gltf_validator(bad)
    assert report["errors"] > 0


def test_one_named_node_per_object_under_groups(zoo_cad, glb):
    document, _ = read_glb(glb)
    nodes = document["nodes"]
    root = nodes[document["scenes"][0]["nodes"][0]]
    assert root["name"] == "zoo"
    children = [nodes[i]["name"] for i in root["children"]]
    assert children == ["S1", "S2", "frame", "SP", "PL", "H"]
    spool = nodes[root["children"][0]]
    assert [nodes[i]["name"] for i in spool["children"]] == ["P1", "E1", "P2"]
    leaves = [n["name"] for n in nodes if "mesh" in n]
    assert leaves == [part.id for part in zoo_cad.parts]


def test_materials_carry_kind_and_status_colours_in_linear_rgb(glb):
    document, _ = read_glb(glb)
    materials = {m["name"]: m for m in document["materials"]}
    assert {"pipe", "elbow", "error", "warning", "hull"} <= set(materials)

    def linear(c):
        return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4

    for name, colour in (("pipe", KIND_COLOURS["pipe"]), ("error", STATUS_COLOURS["error"])):
        factor = materials[name]["pbrMetallicRoughness"]["baseColorFactor"]
        assert factor[:3] == pytest.approx([linear(c) for c in colour[:3]])
    assert materials["hull"]["alphaMode"] == "BLEND"
    node = next(n for n in document["nodes"] if n.get("name") == "C1")
    mesh = document["meshes"][node["mesh"]]
    assert document["materials"][mesh["primitives"][0]["material"]]["name"] == "error"


def test_positions_are_metres_y_up_and_match_the_meshes(zoo_cad, glb):
    document, data = read_glb(glb)
    by_name = {n["name"]: n for n in document["nodes"] if "mesh" in n}
    for part in zoo_cad.parts:
        node = by_name[part.id]
        primitive = document["meshes"][node["mesh"]]["primitives"][0]
        positions = _accessor(document, data, primitive["attributes"]["POSITION"])
        world = positions.astype(np.float64) + node["translation"]
        expected = z_up_to_y_up(zoo_cad.mesh(part).vertices)
        assert np.abs(world - expected).max() < 1e-6, part.id
        indices = _accessor(document, data, primitive["indices"]).reshape(-1, 3)
        assert np.array_equal(indices, zoo_cad.mesh(part).faces)


def test_a_vertical_column_stands_along_y():
    column = Component("COL", "pipe", Straight([0, 0, 0], [0, 0, 3], 0.2))
    cad = prepare(Model(components=(column,)))
    scene = trimesh.load(
        trimesh.util.wrap_as_stream(_glb_bytes(cad)), file_type="glb", force="scene"
    )
    low, high = scene.bounds
    assert high - low == pytest.approx([0.4, 3.0, 0.4], rel=0.01)  # tall along +Y, metres
    assert low[1] == pytest.approx(0.0, abs=1e-6)


def _glb_bytes(cad) -> bytes:
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "x.glb"
        write_gltf(cad, path)
        return path.read_bytes()


def test_gltf_text_embeds_the_same_buffer(zoo_cad, glb, tmp_path):
    path = tmp_path / "zoo.gltf"
    write_gltf(zoo_cad, path)
    document = json.loads(path.read_text())
    uri = document["buffers"][0]["uri"]
    assert uri.startswith("data:application/octet-stream;base64,")
    _, data = read_glb(glb)
    assert base64.b64decode(uri.split(",", 1)[1]) == data
    assert document["buffers"][0]["byteLength"] == len(data)


def test_trimesh_reads_the_glb_with_the_same_volumes(zoo_cad, glb):
    scene = trimesh.load(glb, force="scene")
    names = set(scene.graph.nodes_geometry)
    assert {part.id for part in zoo_cad.parts} <= names
    total = sum(zoo_cad.mesh(part).volume for part in zoo_cad.parts)
    assert sum(g.volume for g in scene.dump()) == pytest.approx(total, rel=1e-4)


def test_empty_model_still_makes_a_valid_file(tmp_path, gltf_validator):
    cad = prepare(Model(components=(), name="empty"))
    path = tmp_path / "empty.glb"
    write_gltf(cad, path)
    (report,) = gltf_validator(path)
    assert report["errors"] == 0
