"""The suffix registry and all-or-nothing batches of outputs."""

from __future__ import annotations

import os
import stat
import subprocess
import sys
from importlib.util import find_spec
from pathlib import Path

import pytest

from asbuilt.errors import ExportError, SolidBuildError, UnknownFormatError
from asbuilt.export import SUFFIXES, export_model, export_models, exporter_for
from asbuilt.model import Component
from asbuilt.primitives import Plane

#: IFC needs the optional ifcopenshell package (the test extra installs it).
HAS_IFC = find_spec("ifcopenshell") is not None

ALL = [
    "zoo.step",
    "zoo.stp",
    "zoo.glb",
    "zoo.gltf",
    "zoo.dxf",
    "zoo.stl",
    "zoo.obj",
    "zoo.pcf",
    *(["zoo.ifc"] if HAS_IFC else []),
    "zoo.json",
]


@pytest.mark.parametrize(
    ("name", "format_"),
    [
        ("a.step", "STEP"),
        ("a.STP", "STEP"),
        ("a.glb", "glTF"),
        ("a.gltf", "glTF"),
        ("a.Dxf", "DXF"),
        ("a.stl", "STL"),
        ("a.obj", "OBJ"),
        ("a.IFC", "IFC"),
        ("dir.v2/a.json", "JSON"),
    ],
)
def test_exporter_for_suffix(name, format_):
    assert exporter_for(name).name == format_


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("model.xyz", "unknown output format '.xyz'; use one of .step, .stp"),
        ("model", "the output has no suffix; use one of"),
    ],
)
def test_unknown_suffix_is_one_clear_line(name, message):
    with pytest.raises(UnknownFormatError) as info:
        exporter_for(name)
    assert str(info.value).startswith(f"{name}: {message}")
    assert "\n" not in str(info.value)


def test_every_suffix_is_registered_once():
    assert set(SUFFIXES) == {Path(n).suffix for n in ALL} | {".ifc"}


def test_all_formats_in_one_run(zoo, tmp_path):
    calls = []
    results = export_models(
        zoo,
        [tmp_path / n for n in ALL],
        progress=lambda task, done, total: calls.append((task, done, total)),
    )
    assert [r.path.name for r in results] == ALL
    for result in results:
        assert result.size == result.path.stat().st_size > 0
        assert result.objects == len(zoo.components)
    assert ("files", len(ALL), len(ALL)) in calls
    assert ("solids", len(zoo.components), len(zoo.components)) in calls
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(ALL)  # no temporary leftovers


def test_written_files_respect_the_umask(zoo, tmp_path):
    old = os.umask(0o022)
    try:
        result = export_model(zoo, tmp_path / "zoo.json")
    finally:
        os.umask(old)
    assert stat.S_IMODE(result.path.stat().st_mode) == 0o644


def test_a_failing_writer_leaves_no_new_file_and_keeps_old_ones(zoo, tmp_path, monkeypatch):
    import asbuilt.export.dxf as dxf

    old = tmp_path / "zoo.step"
    old.write_text("previous version")

    def broken(cad, path):
        Path(path).write_text("half a DXF")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(dxf, "write_dxf", broken)
    outputs = [tmp_path / "zoo.step", tmp_path / "zoo.glb", tmp_path / "zoo.dxf"]
    with pytest.raises(ExportError) as info:
        export_models(zoo, outputs)
    assert (
        str(info.value)
        == f"{tmp_path / 'zoo.dxf'}: cannot write the file (No space left on device)"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["zoo.step"]
    assert old.read_text() == "previous version"


def test_an_object_without_a_solid_is_named_and_nothing_is_written(zoo, tmp_path):
    bad = Component("F9", "plane", Plane([0, 0, 0], [0, 0, 1]))
    model = zoo.replace(components=(*zoo.components, bad))
    with pytest.raises(SolidBuildError, match=r"^object F9: "):
        export_models(model, [tmp_path / "a.step", tmp_path / "a.json"])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("outputs", "built"),
    [
        ((".glb", ".gltf", ".dxf", ".stl", ".obj"), {"tee"}),
        ((".glb", ".step"), None),  # every kind: STEP needs every solid
    ],
    ids=["mesh formats", "with STEP"],
)
def test_mesh_formats_build_no_solids_but_the_tees(zoo, tmp_path, monkeypatch, outputs, built):
    """A 5,000-point hull to .glb spent 30 s sewing a B-rep solid nobody wrote (its mesh
    takes milliseconds)."""
    from asbuilt.cad import assembly

    kinds = []
    real = assembly.placed_solid

    def counting(component, **options):
        kinds.append(component.type)
        return real(component, **options)

    monkeypatch.setattr(assembly, "placed_solid", counting)
    export_models(zoo, [tmp_path / f"zoo{suffix}" for suffix in outputs])
    assert set(kinds) == (built or {c.type for c in zoo.components})
    assert len(list(tmp_path.iterdir())) == len(outputs)


def test_unknown_suffix_fails_before_anything_is_written(zoo, tmp_path):
    with pytest.raises(UnknownFormatError):
        export_models(zoo, [tmp_path / "a.json", tmp_path / "a.xyz"])
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("parent", ["missing-dir", "a-file"])
def test_unusable_directory(zoo, tmp_path, parent):
    (tmp_path / "a-file").write_text("x")
    target = tmp_path / parent / "zoo.json"
    with pytest.raises(ExportError, match=r"directory does not exist"):
        export_model(zoo, target)


@pytest.mark.skipif(
    hasattr(os, "geteuid") and os.geteuid() == 0, reason="root writes into read-only directories"
)
def test_read_only_directory(zoo, tmp_path):
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o500)
    try:
        with pytest.raises(ExportError, match=r"cannot write here .*choose a writable directory"):
            export_model(zoo, folder / "zoo.json")
    finally:
        folder.chmod(0o700)


def test_an_empty_model_has_no_cad_to_write(tmp_path):
    from asbuilt.model import Model

    empty = Model(components=(), name="empty")
    with pytest.raises(ExportError, match=r"e\.step: the model has no objects"):
        export_models(empty, [tmp_path / "e.json", tmp_path / "e.step"])
    assert list(tmp_path.iterdir()) == []
    assert export_model(empty, tmp_path / "e.json").objects == 0


def test_the_same_output_twice_is_refused(zoo, tmp_path):
    with pytest.raises(ExportError, match="given twice"):
        export_models(zoo, [tmp_path / "a.json", tmp_path / "." / "a.json"])


def test_json_alone_does_not_load_the_cad_kernel(tmp_path):
    code = (
        "import sys; sys.path.insert(0, 'tests/cad'); from cad_zoo import zoo_model;"
        "from asbuilt.export import export_model;"
        f"export_model(zoo_model(), {str(tmp_path / 'z.json')!r});"
        "print('cadquery' in sys.modules, 'OCP' in sys.modules)"
    )
    root = Path(__file__).resolve().parents[2]
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=root, check=True
    )
    assert out.stdout.split() == ["False", "False"]


def test_an_eccentric_reducer_reaches_step_gltf_and_dxf(tmp_path):
    """NPS 6 x 4 eccentric reducer (OD 168.3 / 114.3 mm, H 140 mm, axes 27 mm apart): the STEP
    solid reads back valid with the oblique frustum's volume, glTF and DXF carry its mesh."""
    import math

    import ezdxf
    import numpy as np

    from asbuilt.export.step import read_step
    from asbuilt.model import Model, Reducer

    r6, r4, h = 0.08415, 0.05715, 0.14
    geometry = Reducer([0, 0, 1], [h, 0, 1 + r6 - r4], r6, r4, offset=[0, 0, r6 - r4])
    model = Model(components=(Component("R1", "reducer", geometry),), name="ecc")
    paths = [tmp_path / "ecc.step", tmp_path / "ecc.glb", tmp_path / "ecc.dxf"]
    export_models(model, paths)
    (read,) = read_step(paths[0])
    volume_mm3 = math.pi * h * (r6 * r6 + r6 * r4 + r4 * r4) / 3 * 1e9
    assert read.valid and read.volume == pytest.approx(volume_mm3, rel=1e-4)
    assert paths[1].stat().st_size > 0
    doc = ezdxf.readfile(paths[2])
    # the elevation's centreline runs from centre to centre of the end circles: 140 mm along,
    # 27 mm up (millimetres)
    (line,) = doc.modelspace().query('LWPOLYLINE[layer=="ELEV-CENTRELINE"]')
    points = np.array([p[:2] for p in line.get_points()])
    assert points[-1] - points[0] == pytest.approx([h * 1000, (r6 - r4) * 1000], abs=1e-6)


def test_kernel_import_holds_back_ctrl_c_and_sigterm_until_it_ends():
    """A signal during the CAD kernel's import is delivered after it (an exception raised inside
    an extension module's initialisation left it half made)."""
    import signal

    from asbuilt.export import _sigterm_deferred

    seen = []
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: seen.append(signum))
    # Ctrl-C live, as at a terminal: a suite started in the background (nohup, `&`) inherits it
    # ignored, and an ignored Ctrl-C stays ignored (the next test).
    previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt):
            with _sigterm_deferred():
                signal.raise_signal(signal.SIGINT)
                signal.raise_signal(signal.SIGTERM)
                seen.append("import finished")
        assert seen == ["import finished", signal.SIGTERM]
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)


def test_an_ignored_ctrl_c_stays_ignored_through_the_kernel_import():
    import signal

    from asbuilt.export import _sigterm_deferred

    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with _sigterm_deferred():
            signal.raise_signal(signal.SIGINT)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, previous)
