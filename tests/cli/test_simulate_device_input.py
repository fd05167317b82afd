"""Bad input to ``asbuilt simulate-device`` and bad mesh files (directly or named by a scene).

Found by mutation fuzzing (3,000 damaged STL/GLB/OBJ/PLY files given to ``simulate-device
--scene`` and to ``simulate`` through a scene's mesh object, plus the command's options): each
was a traceback, a misleading message or a damaged model served silently, and is now one line
naming the file and exit code 2.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
from pathlib import Path

import pytest
import trimesh

from asbuilt.cli import main

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(autouse=True)
def no_server(monkeypatch):
    """Accepting the input would serve forever: fail at once instead."""

    class Accepted:
        def __init__(self, *args, **kwargs):
            raise AssertionError("the bad input was accepted")

    monkeypatch.setattr("asbuilt.drivers.pty_sim.PtyServer", Accepted)


def _run(capsys, *argv):
    code = main(list(argv))
    err = capsys.readouterr().err
    return code, err


def _box_glb(**accessor_changes) -> bytes:
    """A box's GLB with the POSITION accessor's fields replaced."""
    data = trimesh.exchange.gltf.export_glb(trimesh.creation.box(extents=[1, 1, 1]))
    length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + length])
    position = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
    doc["accessors"][position].update(accessor_changes)
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text + data[20 + length :]
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


_BOX_PLY = trimesh.creation.box(extents=[1, 1, 1]).export(file_type="ply")

_BOX_PLY_TEXT = trimesh.creation.box(extents=[1, 1, 1]).export(file_type="ply", encoding="ascii")

_BOX_STL_TEXT = trimesh.creation.box(extents=[1, 1, 1]).export(file_type="stl_ascii").encode()

_BOX_OBJ = "v 3 0 0\nv 4 0 0\nv 3 1 0\nv 3 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"


@pytest.mark.parametrize(
    "name, content, message",
    [
        (
            "vec2.glb",
            _box_glb(type="VEC2"),
            "vertices must be [x, y, z] points; check the file or export it again",
        ),
        (
            "no-vertices.glb",
            _box_glb(count=0),
            "faces must index the vertices (0-based); check the file or export it again",
        ),
        (
            "nan.obj",
            _BOX_OBJ.replace("v 4 0 0", "v nan 0 0"),
            "vertex 1 is not finite (NaN or infinity; 1 in all); fix or export the model again",
        ),
        (
            "flat.obj",
            "v 3 0 0\nv 4 0 0\nv 5 0 0\nv 6 0 0\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n",
            "every triangle has zero area (its corners coincide or lie on a line), so nothing "
            "can be hit; check the file or export it again",
        ),
        (
            "far.obj",
            _BOX_OBJ.replace("v 4 0 0", "v 4e9 0 0"),
            "a vertex lies 4e+09 m from the origin, beyond any site (at most 1e+08 m); check "
            "the model's units",
        ),
        (
            "garbage.stl",
            b"\xff\xfe" * 100,
            "cannot read the file as STL (neither a valid binary file nor UTF-8 text); check "
            "the file or export it again",
        ),
        (
            "cut.obj",
            "v 3 0 0\nv 4 0 0\nv 3 ",
            "damaged or truncated: the vertex on line 3 has fewer than 3 coordinates; check the "
            "file or export it again",
        ),
        (
            "cut-face.obj",
            _BOX_OBJ[: _BOX_OBJ.rindex(" ")],
            # trimesh read the other three triangles and dropped this one without a word
            "damaged or truncated: the face on line 8 has fewer than 3 corners; check the file "
            "or export it again",
        ),
        (
            "cut.ply",
            _BOX_PLY[: _BOX_PLY.index(b"property float z")],
            "cannot read the file as PLY (damaged or truncated: a record ends early); check the "
            "file or export it again",
        ),
        (
            "cut-text.ply",
            _BOX_PLY_TEXT[: _BOX_PLY_TEXT.rindex(b"\n3 ")],
            # trimesh read 11 of the 12 triangles without a word
            "damaged or truncated: the header declares 12 faces, the file holds 11; check the "
            "file or export it again",
        ),
        (
            "cut-text.stl",
            _BOX_STL_TEXT[: len(_BOX_STL_TEXT) * 9 // 10],
            "damaged or truncated: a text STL without its closing 'endsolid' line; check the "
            "file or export it again",
        ),
        (
            "model",
            _BOX_OBJ,
            "unknown mesh format (no suffix); give a mesh file (.stl, .glb, .gltf, .obj, .ply)",
        ),
    ],
    ids=[
        "glb-vec2-positions",
        "glb-no-vertices",
        "nan",
        "zero-area",
        "beyond-site",
        "garbage",
        "obj-cut-mid-vertex",
        "obj-cut-mid-face",
        "ply-cut-in-header",
        "text-ply-cut-before-last-face",
        "text-stl-cut",
        "no-suffix",
    ],
)
def test_bad_mesh_for_simulate_device(tmp_path, capsys, name, content, message):
    path = tmp_path / name
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    code, err = _run(capsys, "simulate-device", "--scene", str(path))
    assert (code, err) == (2, f"asbuilt: error: {path}: {message}\n")


@pytest.mark.parametrize("cut", [False, True], ids=["buffer-missing", "buffer-cut-short"])
def test_gltf_with_a_bad_buffer_file(tmp_path, capsys, cut):
    files = trimesh.creation.box(extents=[1, 1, 1]).export(file_type="gltf")
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    buffer = tmp_path / next(name for name in files if name.endswith(".bin"))
    if cut:
        buffer.write_bytes(buffer.read_bytes()[:20])
        reason = "damaged or truncated: its parts disagree in length"
    else:
        buffer.unlink()
        reason = f"a file it refers to is missing: {buffer.name}"
    path = tmp_path / "model.gltf"
    code, err = _run(capsys, "simulate-device", "--scene", str(path))
    assert (code, err) == (
        2,
        f"asbuilt: error: {path}: cannot read the file as GLTF ({reason}); check the file or "
        "export it again\n",
    )


def _scene_with_mesh(tmp_path, mesh_name: str) -> Path:
    scene = {
        "stations": [{"id": "S1", "position": [0, -4, 1]}],
        "objects": [{"id": "M1", "kind": "hull", "geometry": {"type": "mesh", "file": mesh_name}}],
    }
    path = tmp_path / "s.scene.json"
    path.write_text(json.dumps(scene))
    return path


def test_nan_vertex_in_a_scene_mesh(tmp_path, capsys):
    # trimesh dropped the vertex and its triangles silently: a holed model was simulated
    (tmp_path / "m.obj").write_text(_BOX_OBJ.replace("v 3 1 0", "v 3 nan 0"))
    scene = _scene_with_mesh(tmp_path, "m.obj")
    out = tmp_path / "out.json"
    code, err = _run(capsys, "simulate", str(scene), "--out", str(out))
    assert (code, err) == (
        2,
        f"asbuilt: error: {scene}: objects[0] (M1).geometry.file: mesh "
        f"'{tmp_path / 'm.obj'}': vertex 2 is not finite (NaN or infinity; 1 in all); fix or "
        "export the model again\n",
    )
    assert not out.exists()


def test_trimesh_log_stays_off_stderr(tmp_path):
    # a damaged normal in an ASCII STL (normals are recomputed anyway) made trimesh log a warning
    # with two tracebacks on stderr; pytest captures logging, so run a real process
    text = trimesh.exchange.stl.export_stl_ascii(trimesh.creation.box(extents=[1, 1, 1]))
    (tmp_path / "m.stl").write_text(text.replace("facet normal", "facet normal x", 1))
    scene = _scene_with_mesh(tmp_path, "m.stl")
    out = tmp_path / "out.json"
    result = subprocess.run(
        [sys.executable, "-m", "asbuilt", "simulate", str(scene), "--out", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert result.stderr.startswith("simulated 1 object, 30 points")
    assert "Traceback" not in result.stderr and "face_normals" not in result.stderr


@pytest.mark.parametrize(
    "option, message",
    [
        (["--seed", "-1"], "seed must be a non-negative integer, not -1"),
        (
            ["--speed", "nan"],
            "speed must be a finite number >= 0 (positions per second; 0 moves instantly), not nan",
        ),
        (
            ["--speed", "-5"],
            "speed must be a finite number >= 0 (positions per second; 0 moves instantly), "
            "not -5.0",
        ),
        (
            ["--divergence-mrad", "3000"],
            "divergence 3000 mrad is not a laser beam's: a range finder's beam spreads by a few "
            "milliradians (at most 100)",
        ),
        (["--divergence-mrad", "nan"], "divergence must be a finite number >= 0"),
    ],
    ids=["negative-seed", "nan-speed", "negative-speed", "wide-beam", "nan-beam"],
)
def test_bad_simulate_device_options(tmp_path, capsys, option, message):
    path = tmp_path / "box.stl"
    trimesh.creation.box(extents=[1, 1, 1]).apply_translation([3.5, 0, 0]).export(path)
    code, err = _run(capsys, "simulate-device", "--scene", str(path), *option)
    assert (code, err) == (2, f"asbuilt: error: simulate-device: {message}\n")


def test_mesh_file_too_large(tmp_path, capsys):
    # a sparse file: the size is checked before trimesh reads a byte of it
    path = tmp_path / "plant.stl"
    with open(path, "wb") as handle:
        handle.truncate(512 * 1024 * 1024 + 1)
    code, err = _run(capsys, "simulate-device", "--scene", str(path))
    assert (code, err) == (
        2,
        f"asbuilt: error: {path}: the file is 536,870,913 bytes, larger than the 512 MiB a mesh "
        "may be; decimate the model or export only the objects to scan\n",
    )


def test_a_directory_as_the_scene(tmp_path, capsys):
    # was "scene file not found" for a directory that exists
    code, err = _run(capsys, "simulate-device", "--scene", str(tmp_path))
    assert (code, err) == (
        2,
        f"asbuilt: error: {tmp_path}: is a directory; give the scene or model file itself\n",
    )
