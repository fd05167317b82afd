"""``asbuilt model``: every sample to every format, summaries, errors as one line with exit 2."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from asbuilt.cli import main

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = sorted((ROOT / "samples").glob("*.json"))


def _load_export_conftest():
    """The glTF validator fixture's helpers live in tests/export/conftest.py."""
    spec = importlib.util.spec_from_file_location(
        "export_conftest_for_cli", ROOT / "tests" / "export" / "conftest.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


gltf_validator = _load_export_conftest().gltf_validator


@pytest.fixture(scope="module")
def spool_outputs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("spool")
    outputs = [folder / f"spool{suffix}" for suffix in (".step", ".glb", ".dxf", ".json")]
    argv = ["model", str(ROOT / "samples" / "spool.json")]
    for path in outputs:
        argv += ["--out", str(path)]
    return argv, outputs


def test_spool_to_step_glb_dxf_json(spool_outputs, capsys, gltf_validator):
    argv, outputs = spool_outputs
    assert main(argv) == 0
    out, _ = capsys.readouterr()
    lines = out.splitlines()
    document = json.loads(outputs[3].read_text())
    n = len(document["components"])
    for path, line, name in zip(outputs, lines, ("STEP", "glTF", "DXF", "JSON")):
        assert line.startswith(f"wrote {path} ({name}, ")
        assert line.endswith(f" {n} objects)")
    assert lines[-1].startswith(f"{n} components, 1 spool; findings: ")
    # Merging ran: the pipes became one spool with fittings.
    assert {c["type"] for c in document["components"]} >= {"pipe", "elbow"}
    assert document["spools"][0]["id"] == "SP-101"

    from asbuilt.export.step import declared_length_unit, read_step

    assert declared_length_unit(outputs[0]) == "mm"
    assert [s.name for s in read_step(outputs[0])] == [c["id"] for c in document["components"]]
    (report,) = gltf_validator(outputs[1])
    assert report["errors"] == 0


@pytest.mark.parametrize("sample", SAMPLES, ids=[p.stem for p in SAMPLES])
def test_every_sample_exports(sample, tmp_path, capsys):
    outputs = [tmp_path / f"x{s}" for s in (".step", ".glb", ".dxf", ".json")]
    argv = ["model", str(sample), "--quiet"]
    for path in outputs:
        argv += ["--out", str(path)]
    assert main(argv) == 0
    assert capsys.readouterr().out == ""  # --quiet
    assert all(path.stat().st_size > 0 for path in outputs)
    document = json.loads(outputs[3].read_text())
    from asbuilt.export.step import read_step

    # one solid per component, and one more per insulated component (its jacket)
    jackets = sum(1 for comp in document["components"] if comp.get("insulation"))
    assert len(read_step(outputs[0])) == len(document["components"]) + jackets


def test_no_merge_no_check_plate_thickness(tmp_path, capsys):
    out = tmp_path / "plant.json"
    step = tmp_path / "plant.step"
    code = main(
        [
            "model",
            str(ROOT / "samples" / "plant.json"),
            "--out",
            str(out),
            "--out",
            str(step),
            "--no-merge",
            "--no-check",
            "--plate-thickness",
            "25",
        ]
    )
    assert code == 0
    document = json.loads(out.read_text())
    assert document["spools"] == [] and document["findings"] == []
    assert {c["type"] for c in document["components"]} <= {
        "cylinder",
        "cuboid",
        "sphere",
        "plane",
        "hull",
    }
    planes = [c for c in document["components"] if c["type"] == "plane"]
    assert planes  # the plant has a wall
    from asbuilt.export.step import read_step

    volumes = {s.name: s.volume for s in read_step(step)}
    outline = np.array(planes[0]["outline"])
    normal = np.array(planes[0]["normal"])
    # Shoelace area of the outline polygon, projected on the plane.
    twice_area = (
        sum(np.cross(outline[i], outline[(i + 1) % len(outline)]) for i in range(len(outline)))
        @ normal
    )
    expected_mm3 = abs(0.5 * twice_area) * 0.025 * 1e9
    assert volumes[planes[0]["id"]] == pytest.approx(expected_mm3, rel=1e-3)


@pytest.mark.parametrize(
    ("outputs", "message"),
    [
        (["model.xyz"], "model.xyz: unknown output format '.xyz'"),
        (["missing/model.step"], "missing/model.step: directory does not exist"),
        (["model.json", "model.json"], "model.json: this output is given twice"),
    ],
)
def test_bad_outputs_are_one_line_exit_2_and_write_nothing(
    tmp_path, capsys, outputs, message, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    argv = ["model", str(ROOT / "samples" / "spool.json")]
    for name in outputs:
        argv += ["--out", name]
    assert main(argv) == 2
    _, err = capsys.readouterr()
    assert err.startswith(f"asbuilt: error: {message}")
    assert err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_an_unbuildable_solid_names_the_object(tmp_path, capsys, monkeypatch):
    import asbuilt.pipeline
    from asbuilt.model import Component, Model
    from asbuilt.primitives import Plane, Sphere

    bad = Model(
        components=(
            Component("S1", "sphere", Sphere([0, 0, 0], 1.0)),
            Component("W9", "plane", Plane([0, 0, 0], [0, 0, 1])),
        )
    )
    monkeypatch.setattr(asbuilt.pipeline, "build_model", lambda scan, **options: bad)
    target = tmp_path / "x.step"
    target.write_text("old")
    argv = [
        "model",
        str(ROOT / "samples" / "spool.json"),
        "--out",
        str(target),
        "--out",
        str(tmp_path / "x.json"),
    ]
    assert main(argv) == 2
    _, err = capsys.readouterr()
    assert err.startswith("asbuilt: error: object W9: ") and err.count("\n") == 1
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.step"]


@pytest.mark.parametrize("value", ["0", "-3", "abc"])
def test_bad_plate_thickness(value, capsys):
    with pytest.raises(SystemExit) as info:
        main(["model", "scan.json", "--out", "x.step", "--plate-thickness", value])
    assert info.value.code == 2
    assert "--plate-thickness" in capsys.readouterr().err


def test_missing_scan_is_exit_2(tmp_path, capsys):
    assert main(["model", str(tmp_path / "nope.json"), "--out", str(tmp_path / "x.json")]) == 2
    assert "nope.json" in capsys.readouterr().err


def test_help_reads_well(capsys):
    with pytest.raises(SystemExit):
        main(["model", "--help"])
    text = capsys.readouterr().out
    for option in (
        "--out FILE",
        "--plate-thickness MM",
        "--catalog NAME|FILE",
        "--schedule S",
        "--rules FILE",
        "--design FILE",
        "--quiet",
        ".step",
        ".glb",
        ".dxf",
    ):
        assert option in text


def test_version_and_top_level_help_list_model(capsys):
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out.startswith("asbuilt ")
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "model" in capsys.readouterr().out


def test_registering_the_command_does_not_load_cadquery():
    code = (
        "import sys; from asbuilt.cli import build_parser; build_parser();"
        "print('cadquery' in sys.modules)"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert out.stdout.strip() == "False"


def test_report_is_written_after_the_outputs(tmp_path, capsys):
    glb, html = tmp_path / "spool.glb", tmp_path / "spool.html"
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--out", str(glb), "--report", str(html)]
    assert main(argv) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"wrote {glb} (glTF, ")
    assert out[1] == f"wrote {html} (report)"
    assert html.read_text(encoding="utf-8").lstrip().lower().startswith("<!doctype html")


def test_a_report_that_fails_leaves_no_model_file_either(tmp_path, capsys, monkeypatch):
    # "Either every file is written or none is": the model files wait for the reports (a full
    # disk under the report once left the STEP published with exit 2).
    import asbuilt.report.table_csv as table_csv

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(table_csv, "write_csv", full_disk)
    step, csv = tmp_path / "m.step", tmp_path / "qa.csv"
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--out", str(step), "--report", str(csv)]
    assert main(argv) == 2
    assert "cannot write the report (No space left on device)" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_the_html_reports_view_embeds_the_glb_of_the_same_run(tmp_path, capsys):
    glb, html = tmp_path / "m.glb", tmp_path / "qa.html"
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--out", str(glb), "--report", str(html)]
    assert main(argv) == 0
    page = html.read_text(encoding="utf-8")
    assert "data:model/gltf-binary;base64," in page and ".part" not in page


def test_every_report_given_is_written(tmp_path, capsys):
    """--report twice wrote only the last one (audit D12)."""
    reports = [tmp_path / "qa.csv", tmp_path / "qa.html", tmp_path / "qa.json"]
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--out", str(tmp_path / "m.json")]
    for report in reports:
        argv += ["--report", str(report)]
    assert main(argv) == 0
    out = capsys.readouterr().out.splitlines()
    assert [line for line in out if line.endswith("(report)")] == [
        f"wrote {report} (report)" for report in reports
    ]
    assert all(report.stat().st_size > 0 for report in reports)


@pytest.mark.parametrize(
    ("reports", "message"),
    [
        (["r.pdf"], "r.pdf: unknown report format '.pdf'"),
        (["x.json"], "x.json: this report is also an --out file or another --report"),
        (["r.csv", "r.csv"], "r.csv: this report is also an --out file or another --report"),
        (["r.csv", "nope/r.html"], "nope/r.html: directory does not exist"),
    ],
)
def test_bad_report_fails_before_any_work(tmp_path, capsys, monkeypatch, reports, message):
    monkeypatch.chdir(tmp_path)
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--out", "x.json"]
    for report in reports:
        argv += ["--report", report]
    assert main(argv) == 2
    assert capsys.readouterr().err.startswith(f"asbuilt: error: {message}")
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("option", "value", "words"),
    [
        ("--schedule", "XYZ", "schedule 'XYZ' is not in catalog"),
        ("--catalog", "nope", "unknown catalog 'nope'"),
        ("--rules", "missing.toml", "missing.toml"),
        ("--design", "missing.json", "missing.json"),
    ],
)
def test_bad_catalog_schedule_rules_design_are_exit_2(
    tmp_path, capsys, monkeypatch, option, value, words
):
    monkeypatch.chdir(tmp_path)
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--out", "x.json", option, value]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("asbuilt: error: ") and words in err and err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["model", "SPOOL", "--out", "a.step", "--out", "b.dxf", "--out", "taken"],
            "taken: is a directory; give a file name",
        ),
        (
            ["model", "SPOOL", "--out", "a.step", "--report", "taken"],
            "taken: is a directory; give a file name",
        ),
        (["fit", "SPOOL", "--json", "-o", "taken"], "taken: is a directory; give a file name"),
        (["fit", "SPOOL", "-o", ""], "'': the output file name is empty"),
        (["check", "SPOOL", "--fix", "taken"], "taken: is a directory; give a file name"),
        (["report", "SPOOL", "--out", "taken"], "taken: is a directory; give a file name"),
    ],
)
def test_an_output_that_is_a_directory_fails_before_any_work(
    tmp_path, capsys, monkeypatch, argv, message
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "taken").mkdir()
    argv = [str(ROOT / "samples" / "spool.json") if a == "SPOOL" else a for a in argv]
    if argv[0] in ("model", "report", "check"):
        # The suffix picks the format; a directory named like an output is the case users hit.
        (tmp_path / "taken").rename(tmp_path / "taken.json")
        argv = ["taken.json" if a == "taken" else a for a in argv]
        message = message.replace("taken", "taken.json", 1)
    assert main(argv) == 2
    out, err = capsys.readouterr()
    assert err.startswith(f"asbuilt: error: {message}") and err.count("\n") == 1
    assert [p.name for p in tmp_path.iterdir()] in (["taken"], ["taken.json"])


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["model", "SPOOL", "--out", "taken/"], "taken/: is a directory; give a file name"),
        (["model", "SPOOL", "--out", "taken"], "taken: is a directory; give a file name"),
        (["model", "SPOOL", "--out", "new/"], "new/: ends with a slash, so it names a directory"),
        (
            ["model", "SPOOL", "--out", "a.step", "--report", "taken/"],
            "taken/: is a directory; give a file name to write (e.g. add /report.html)",
        ),
        (["report", "SPOOL", "--out", "taken/"], "taken/: is a directory; give a file name"),
        (["model", "SPOOL", "--out", "a.stq"], "a.stq: unknown output format '.stq'"),
        (["model", "SPOOL", "--out", "a"], "a: the output has no suffix"),
    ],
)
def test_a_directory_output_is_named_as_typed_before_its_suffix_is_tested(
    tmp_path, capsys, monkeypatch, argv, message
):
    """A directory without a suffix, or any name ending in a slash, is said to be a directory
    (not "the output has no suffix" with the slash dropped); an unknown suffix is still named."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "taken").mkdir()
    argv = [str(ROOT / "samples" / "spool.json") if a == "SPOOL" else a for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"asbuilt: error: {message}") and err.count("\n") == 1
    assert [p.name for p in tmp_path.iterdir()] == ["taken"]
    assert list((tmp_path / "taken").iterdir()) == []


def test_sigterm_while_writing_leaves_no_partial_files(tmp_path, capsys, monkeypatch):
    """A ``kill`` (SIGTERM) during writing is handled like Ctrl-C: the staged files are removed
    and the exit code is 143 (audit D13: hidden ``.part`` files were left behind)."""
    import os
    import signal
    import time

    from asbuilt.export import pcf

    def killed_while_writing(model, path):
        with open(path, "w") as stream:
            stream.write("ISOGEN-FILES")
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)  # the handler raises before this ends
        raise AssertionError("SIGTERM was not handled")

    monkeypatch.setattr(pcf, "write_pcf", killed_while_writing)
    before = signal.getsignal(signal.SIGTERM)
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--quiet"]
    argv += ["--out", str(tmp_path / "m.json"), "--out", str(tmp_path / "m.pcf")]
    assert main(argv) == 143
    assert capsys.readouterr().err.strip() == "asbuilt: terminated"
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGTERM) is before  # restored for the caller


class _KillOnImport:
    """A meta path finder that sends this process a SIGTERM when ``name`` is imported and notes
    the files in ``folder`` at that moment and whether the import went on after the signal."""

    def __init__(self, name: str, folder: Path):
        self.name, self.folder = name, folder
        self.files_then: list[str] | None = None
        self.went_on = False

    def find_spec(self, fullname, path=None, target=None):
        import os
        import signal
        import time

        if fullname == self.name and self.files_then is None:
            self.files_then = sorted(p.name for p in self.folder.iterdir())
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)  # the handler would raise here, in the middle of the import
            self.went_on = True
        return None  # the usual finders import it


def test_sigterm_while_the_kernel_loads_stops_before_any_file(tmp_path, capsys, monkeypatch):
    """A kill while the CAD kernel is imported: it used to come after the outputs were staged
    (an exception in the middle of VTK's initialisation crashed the process, exit 139, and
    left empty ``.part`` files); now the kernel is imported first and the signal is held back
    until the import is done."""
    import signal

    for name in [m for m in sys.modules if m == "asbuilt.cad" or m.startswith("asbuilt.cad.")]:
        monkeypatch.delitem(sys.modules, name)
    finder = _KillOnImport("asbuilt.cad", tmp_path)
    monkeypatch.setattr(sys, "meta_path", [finder, *sys.meta_path])
    before = signal.getsignal(signal.SIGTERM)
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--quiet"]
    argv += ["--out", str(tmp_path / "m.glb"), "--out", str(tmp_path / "m.json")]
    assert main(argv) == 143
    assert capsys.readouterr().err.strip() == "asbuilt: terminated"
    assert finder.files_then == []  # nothing staged yet
    assert finder.went_on  # not interrupted half way
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGTERM) is before


@pytest.mark.parametrize("then", ["fails", "carries on"])
def test_sigterm_a_writer_swallows_still_terminates(tmp_path, capsys, monkeypatch, then):
    """ifcopenshell's bare ``except`` swallows the SIGTERM handler's exception: the run then
    failed with an unrelated traceback (exit 1), or could have published its outputs."""
    import os
    import signal
    import time

    from asbuilt.export import pcf

    def swallowing_writer(model, path):
        with open(path, "w") as stream:
            stream.write("ISOGEN-FILES")
        try:
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(5)
        except BaseException:  # what the third-party writer does
            pass
        if then == "fails":
            raise RuntimeError("Couldn't find express schema")

    monkeypatch.setattr(pcf, "write_pcf", swallowing_writer)
    argv = ["model", str(ROOT / "samples" / "spool.json"), "--quiet"]
    argv += ["--out", str(tmp_path / "m.json"), "--out", str(tmp_path / "m.pcf")]
    assert main(argv) == 143
    assert capsys.readouterr().err.strip() == "asbuilt: terminated"
    assert list(tmp_path.iterdir()) == []
    # The next command in this process is not taken for terminated.
    assert (
        main(
            ["model", str(ROOT / "samples" / "spool.json"), "-q", "--out", str(tmp_path / "n.json")]
        )
        == 0
    )


@pytest.mark.parametrize(
    "argv",
    [
        ["model", "site.json", "--out", "site.json"],
        ["model", "site.json", "--out", "site.step", "--report", "site.json"],
        ["check", "site.json", "--fix", "site.json"],
        ["fit", "site.json", "--output", "site.json"],
        ["report", "site.json", "--out", "site.json"],
    ],
    ids=lambda argv: " ".join(argv[:1] + argv[2:3]),
)
def test_an_output_naming_the_scan_is_refused_and_the_scan_kept(
    argv, tmp_path, monkeypatch, capsys
):
    """Writing the model over its own scan lost the measured points (audit)."""
    scan = tmp_path / "site.json"
    scan.write_bytes((ROOT / "samples" / "spool.json").read_bytes())
    before = scan.read_bytes()
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "is the input file itself" in err and err.count("\n") == 1
    assert scan.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["site.json"]


def test_a_refused_object_is_left_out_said_and_exits_1(tmp_path, capsys):
    """The spool sample's six pipes and the ray caster's refused NPS 1 scan X1: the outputs
    are written without X1, standard error says why, the model's findings keep it."""
    from refused_scans import spool_with_refused, write

    scan = write(tmp_path / "scan.json", spool_with_refused())
    out_json, out_dxf = tmp_path / "m.json", tmp_path / "m.dxf"
    capsys.readouterr()
    assert main(["model", str(scan), "--out", str(out_json), "--out", str(out_dxf)]) == 1
    out, err = capsys.readouterr()
    assert err.startswith(f"asbuilt: {scan}: X1: not fitted as a cylinder, so it is not in")
    assert err.count("\n") == 1 and "Rescan" in err
    assert f"wrote {out_json}" in out and f"wrote {out_dxf}" in out
    assert "findings: 1 error, 0 warnings" in out
    document = json.loads(out_json.read_text())
    assert [c["id"] for c in document["components"] if c["id"].startswith("X")] == []
    assert [(f["code"], f["slug"], f["objects"]) for f in document["findings"]] == [
        ("AB001", "fit-refused", ["X1"])
    ]


def test_no_object_fitted_writes_nothing_and_exits_2(tmp_path, capsys):
    from refused_scans import spool_with_refused, write

    scan = write(tmp_path / "scan.json", spool_with_refused(2, good=False))
    out_json = tmp_path / "m.json"
    assert main(["model", str(scan), "--out", str(out_json)]) == 2
    out, err = capsys.readouterr()
    lines = err.splitlines()
    assert out == "" and len(lines) == 2 and not out_json.exists()
    assert lines[0].startswith(f"asbuilt: error: {scan}: objects[0] (X1): ")
    assert lines[0].endswith("the other object (X2) was refused too.")
    assert lines[1].startswith(f"asbuilt: error: {scan}: objects[1] (X2): ")


#: An output named like an option's input file: the input (a design, rules, a catalog, a glTF,
#: calibration targets, a plan...) would be replaced by the output. Before, model, check and
#: report compared outputs with the SCAN only, and calibrate and scan with nothing: the design,
#: the measured scan given to calibrate or the plan given to scan was silently overwritten.
_INPUT_AS_OUTPUT = [
    ("model", ["model", "SPOOL", "-q", "--design", "design.json", "--out", "design.json"]),
    (
        "model-report",
        ["model", "SPOOL", "-q", "--out", "m.json", "--design", "d.json", "--report", "d.json"],
    ),
    ("check", ["check", "SPOOL", "--design", "design.json", "--fix", "design.json"]),
    ("report", ["report", "SPOOL", "-q", "--design", "design.json", "--out", "design.json"]),
    ("report-catalog", ["report", "SPOOL", "-q", "--catalog", "cat.csv", "--out", "cat.csv"]),
    ("calibrate-scan", ["calibrate", "scan.json", "--targets", "t.json", "--out", "scan.json"]),
    ("calibrate-targets", ["calibrate", "SPOOL", "--targets", "t.json", "--out", "t.json"]),
    (
        "calibrate-initial",
        ["calibrate", "SPOOL", "--targets", "t.json", "--initial", "c.json", "--out", "c.json"],
    ),
    (
        "scan-plan",
        [
            "scan",
            "--ptu",
            "sim-ptu://x",
            "--lrf",
            "sim-lrf://x",
            "--plan",
            "p.json",
            "--out",
            "p.json",
        ],
    ),
    (
        "scan-calibration",
        [
            "scan",
            "--ptu",
            "sim-ptu://x",
            "--lrf",
            "sim-lrf://x",
            "--calibration",
            "c.json",
            "--out",
            "c.json",
        ],
    ),
]


@pytest.mark.parametrize(
    "argv", [a for _, a in _INPUT_AS_OUTPUT], ids=[i for i, _ in _INPUT_AS_OUTPUT]
)
def test_an_output_that_is_one_of_the_inputs_is_refused_and_the_input_kept(
    tmp_path, capsys, monkeypatch, argv
):
    monkeypatch.chdir(tmp_path)
    spool = (ROOT / "samples" / "spool.json").read_bytes()
    contents = {
        "design.json": b'{"format": "asbuilt-design", "version": 1}',
        "d.json": b'{"format": "asbuilt-design", "version": 1}',
        "cat.csv": (ROOT / "catalogs" / "asme-b36.10m.csv").read_bytes(),
        "scan.json": spool,
        "t.json": b'{"format": "asbuilt-targets", "version": 1, "targets": {}}',
        "c.json": b'{"format": "asbuilt-calibration", "version": 1}',
        "p.json": b'{"format": "asbuilt-scan-plan", "version": 1, "targets": []}',
    }
    for name, data in contents.items():
        (tmp_path / name).write_bytes(data)
    argv = [str(ROOT / "samples" / "spool.json") if a == "SPOOL" else a for a in argv]
    target = argv[-1]
    assert main(argv) == 2
    err = capsys.readouterr().err
    option = argv[-2]
    assert err == (
        f"asbuilt: error: {target}: is the input file itself, which the output would replace; "
        f"choose another {option}\n"
    )
    for name, data in contents.items():
        assert (tmp_path / name).read_bytes() == data
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(contents)


class _InterruptOnImport:
    """A meta path finder that sends this process a SIGINT (Ctrl-C) when ``name`` is imported and
    turns the KeyboardInterrupt into the ImportError an extension module's initialisation gives
    (OCP: "initialization failed")."""

    def __init__(self, name: str):
        self.name = name
        self.done = False

    def find_spec(self, fullname, path=None, target=None):
        import os
        import signal
        import time

        if fullname == self.name and not self.done:
            self.done = True
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(5)  # the handler raises before this ends
            except KeyboardInterrupt:
                raise ImportError("initialization failed") from None
        return None


def test_ctrl_c_while_the_kernel_loads_is_an_interruption(tmp_path, capsys, monkeypatch):
    """Ctrl-C while the CAD kernel initialised ended with OCP's ImportError traceback and exit 1;
    it is reported as the interruption it is (exit 130), with nothing written."""
    import signal

    for name in [m for m in sys.modules if m == "asbuilt.cad" or m.startswith("asbuilt.cad.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setattr(sys, "meta_path", [_InterruptOnImport("asbuilt.cad"), *sys.meta_path])
    # Ctrl-C live, as at a terminal: a suite started in the background (nohup, `&`) inherits it
    # ignored, and then the interruption never comes.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        before = signal.getsignal(signal.SIGINT)
        out = tmp_path / "m.step"
        out.write_text("KEEP")
        argv = ["model", str(ROOT / "samples" / "spool.json"), "--quiet"]
        argv += ["--out", str(out), "--out", str(tmp_path / "m.json")]
        assert main(argv) == 130
        assert capsys.readouterr().err == "asbuilt: interrupted\n"
        assert [p.name for p in tmp_path.iterdir()] == ["m.step"]
        assert out.read_text() == "KEEP"
        assert signal.getsignal(signal.SIGINT) is before  # restored for the caller
    finally:
        signal.signal(signal.SIGINT, previous)
