"""``asbuilt report``: formats by suffix, exit codes, model documents, ``asbuilt model --report``."""

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from asbuilt.cli import main

ROOT = Path(__file__).resolve().parents[2]
BAY = ROOT / "samples" / "structural-bay.json"
PLANT = ROOT / "samples" / "plant.json"


def run(argv, capsys):
    code = main(list(map(str, argv)))
    out, err = capsys.readouterr()
    return code, out, err


def test_three_reports_in_one_run(tmp_path, capsys):
    outs = [tmp_path / "qa.html", tmp_path / "qa.csv", tmp_path / "qa.json"]
    code, out, _ = run(["report", PLANT, *[a for p in outs for a in ("--out", p)]], capsys)
    assert code == 0
    lines = out.splitlines()
    assert lines[0].startswith(f"wrote {outs[0]} (HTML report, ")
    assert lines[1].startswith(f"wrote {outs[1]} (CSV report, ")
    assert lines[2].startswith(f"wrote {outs[2]} (JSON report, ")
    assert lines[3].startswith("15 components; findings: ")
    with open(outs[1], newline="", encoding="utf-8-sig") as handle:
        rows = list(csv.DictReader(handle))
    document = json.loads(outs[2].read_text(encoding="utf-8"))
    assert [r["id"] for r in rows] == [c["id"] for c in document["components"]]
    assert len(rows) == 15
    assert "<svg" in outs[0].read_text(encoding="utf-8")


@pytest.fixture
def one_pipe(tmp_path):
    """A scan of one pipe: every count in the summaries is 1 or 0."""
    scene = {
        "format": "asbuilt-scene",
        "version": 1,
        "units": "m",
        "stations": [{"id": "S1", "position": [0, 0, 1.5], "range_sigma": 0.002}],
        "objects": [
            {
                "id": "P1",
                "kind": "cylinder",
                "points": 30,
                "geometry": {
                    "type": "cylinder",
                    "start": [-1.5, 4, 1.0],
                    "end": [1.5, 4, 1.0],
                    "od": 0.1143,
                },
            }
        ],
    }
    (tmp_path / "scene.json").write_text(json.dumps(scene), encoding="utf-8")
    assert (
        main(["simulate", str(tmp_path / "scene.json"), "--out", str(tmp_path / "one.json")]) == 0
    )
    return tmp_path / "one.json"


def test_counts_of_one_are_singular(one_pipe, tmp_path, capsys):
    code, out, _ = run(["report", one_pipe, "--out", tmp_path / "qa.json"], capsys)
    assert code == 0
    assert out.splitlines()[-1] == "1 component; findings: 0 errors, 0 warnings, 0 info"
    code, out, _ = run(["model", one_pipe, "--out", tmp_path / "one.step"], capsys)
    assert code == 0
    assert out.splitlines()[0].endswith(" 1 object)")
    assert out.splitlines()[-1] == "1 component, 1 spool; findings: 0 errors, 0 warnings, 0 info"
    code, out, _ = run(["fit", one_pipe], capsys)
    assert code == 0 and ": 1 object" in out and "1 objects" not in out


def test_the_cli_plural_helper():
    from asbuilt.cli._text import plural

    assert [plural(n, "component") for n in (0, 1, 2)] == [
        "0 components",
        "1 component",
        "2 components",
    ]
    assert [plural(n, "fix") for n in (1, 3)] == ["1 fix", "3 fixes"]


def test_options(tmp_path, capsys):
    out = tmp_path / "qa.json"
    code, stdout, _ = run(
        ["report", PLANT, "--out", out, "--density", "7900", "--no-check", "--quiet"], capsys
    )
    assert (code, stdout) == (0, "")
    document = json.loads(out.read_text(encoding="utf-8"))
    assert document["takeoff"]["totals"]["density"] == 7900
    assert document["findings"] == []


def test_no_merge_counts_cylinders(tmp_path, capsys):
    out = tmp_path / "qa.csv"
    assert run(["report", PLANT, "--out", out, "--no-merge", "-q"], capsys)[0] == 0
    with open(out, newline="", encoding="utf-8-sig") as handle:
        types = {r["type"] for r in csv.DictReader(handle)}
    assert "pipe" not in types and "cylinder" in types


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--out", "{tmp}/qa.pdf"], "unknown report format '.pdf'"),
        (["--out", "{tmp}/nowhere/qa.html"], "directory does not exist"),
        (["--out", "{tmp}/qa.html", "--gltf", "{tmp}/model.step"], "--gltf must name"),
        (["--out", "{tmp}/qa.html", "--gltf", "{tmp}/none.glb"], "none.glb: --gltf file not found"),
        # Before: any bytes named .glb/.gltf were embedded (exit 0) and the 3-D view failed
        # only in the reader's browser; a directory was "not found".
        (["--out", "{tmp}/qa.html", "--gltf", "{tmp}/dir.glb"], "dir.glb: --gltf is a directory"),
        (
            ["--out", "{tmp}/qa.html", "--gltf", "{tmp}/empty.glb"],
            "empty.glb: --gltf file is not a glTF binary (it does not start with 'glTF')",
        ),
        (
            ["--out", "{tmp}/qa.html", "--gltf", "{tmp}/scan.glb"],
            "scan.glb: --gltf file is not a glTF binary (it does not start with 'glTF')",
        ),
        (
            ["--out", "{tmp}/qa.html", "--gltf", "{tmp}/cut.glb"],
            "cut.glb: --gltf file is truncated or padded (20 bytes, its header says 1,000)",
        ),
        (
            ["--out", "{tmp}/qa.html", "--gltf", "{tmp}/scan.gltf"],
            'scan.gltf: --gltf file is not glTF JSON (no "asset" object)',
        ),
        (
            ["--out", "{tmp}/qa.html", "--gltf", "{tmp}/latin.gltf"],
            "latin.gltf: --gltf file is not glTF JSON (not UTF-8 JSON)",
        ),
    ],
)
def test_bad_outputs_exit_2_with_one_line(tmp_path, capsys, extra, needle):
    (tmp_path / "dir.glb").mkdir()
    (tmp_path / "empty.glb").write_bytes(b"")
    (tmp_path / "scan.glb").write_bytes(Path(BAY).read_bytes())
    (tmp_path / "cut.glb").write_bytes(
        b"glTF" + (2).to_bytes(4, "little") + (1000).to_bytes(4, "little") + b"\0" * 8
    )
    (tmp_path / "scan.gltf").write_bytes(Path(BAY).read_bytes())
    (tmp_path / "latin.gltf").write_bytes('{"asset": {"generator": "caf\u00e9"}}'.encode("latin-1"))
    argv = ["report", BAY, *[a.format(tmp=tmp_path) for a in extra]]
    code, out, err = run(argv, capsys)
    assert code == 2 and out == ""
    assert err.startswith("asbuilt: error: ") and needle in err
    assert len(err.strip().splitlines()) == 1
    assert not (tmp_path / "qa.html").exists()


def test_missing_scan_exits_2(tmp_path, capsys):
    code, _, err = run(["report", tmp_path / "none.json", "--out", tmp_path / "a.csv"], capsys)
    assert code == 2 and "none.json" in err
    assert not (tmp_path / "a.csv").exists()


def test_bad_density_is_an_argument_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["report", str(BAY), "--out", str(tmp_path / "a.csv"), "--density", "-3"])
    assert info.value.code == 2
    assert "density" in capsys.readouterr().err


def test_model_document_keeps_its_findings(tmp_path, capsys):
    from asbuilt.export.model_json import write_model_json
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    model = build_model(load_scan(BAY))
    document = tmp_path / "bay-model.json"
    write_model_json(model, document)
    out = tmp_path / "qa.json"
    assert run(["report", document, "--out", out, "-q"], capsys)[0] == 0
    report = json.loads(out.read_text(encoding="utf-8"))
    assert model.findings  # the bay has findings (unverifiable plumbness at least)
    assert sorted(
        (f["code"], f["severity"], tuple(f["objects"])) for f in report["findings"]
    ) == sorted((f.code, f.severity, f.objects) for f in model.findings)
    assert len(report["components"]) == len(model.components)


def test_asbuilt_model_report_option(tmp_path, capsys):
    report = tmp_path / "qa.html"
    code, out, _ = run(["model", BAY, "--out", tmp_path / "bay.json", "--report", report], capsys)
    assert code == 0, out
    assert report.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
    assert f"wrote {report}" in out


def test_report_never_loads_the_cad_kernel(tmp_path):
    code = (
        "import sys; from asbuilt.cli import main; "
        f"rc = main(['report', {str(BAY)!r}, '--out', {str(tmp_path / 'a.html')!r}, '-q']); "
        "assert rc == 0; "
        "assert not any(m == 'cadquery' or m.startswith(('cadquery.', 'OCP')) "
        "for m in sys.modules), 'CAD kernel imported'"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert result.returncode == 0, result.stderr


def test_help_lists_report():
    result = subprocess.run(
        [sys.executable, "-m", "asbuilt", "report", "--help"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert result.returncode == 0
    assert "--out" in result.stdout and ".html .csv .json" in result.stdout


SPOOL = ROOT / "samples" / "spool.json"
# A user's catalog (docs/catalogs.md format) with the ASME B36.10M-2004 NPS 4 and 6 rows.
USER_CATALOG = (
    "# name: my-pipes\n# title: Our plant's pipe\n# standard: PS-7\n# kind: pipe\n# units: mm\n"
    "# material: carbon steel\n# designation: NPS\n# default_schedule: STD\n"
    "nominal,dn,od,wall_std,source\n"
    "4,100,114.3,6.02,ASME B36.10M-2004 Table 1\n6,150,168.3,7.11,ASME B36.10M-2004 Table 1\n"
)


def _csv_rows(path):
    with open(path, newline="", encoding="utf-8-sig") as handle:
        return {r["id"]: r for r in csv.DictReader(handle)}


def test_user_catalog_in_every_way_to_a_report(tmp_path, capsys):
    """--catalog FILE: sizes, walls and weights from the file, whether the report is made from
    the scan, by 'asbuilt model --report', or later from the model document (audit D1)."""
    catalog = tmp_path / "pipes.csv"
    catalog.write_text(USER_CATALOG, encoding="utf-8")
    direct, by_model, later = tmp_path / "a.csv", tmp_path / "b.csv", tmp_path / "c.json"
    document = tmp_path / "model.json"
    assert run(["report", SPOOL, "--catalog", catalog, "--out", direct, "-q"], capsys)[0] == 0
    argv = ["model", SPOOL, "--catalog", catalog, "--out", document, "--report", by_model, "-q"]
    assert run(argv, capsys)[0] == 0
    assert run(["report", document, "--out", later, "-q"], capsys)[0] == 0
    for path in (direct, by_model):
        row = _csv_rows(path)["P1"]
        # NPS 6 STD: 0.0246615 (168.3 - 7.11) 7.11 = 28.26 kg/m (B36.10M) times the length
        assert row["size"] == "NPS 6" and row["nominal"] == "6"
        expected = 0.0246615 * (168.3 - 7.11) * 7.11 * float(row["length_m"])
        assert float(row["weight_kg"]) == pytest.approx(expected, abs=0.02)
    report = json.loads(later.read_text(encoding="utf-8"))
    assert report["catalog"] == "my-pipes" and report["catalog_title"] == "PS-7 (Our plant's pipe)"
    assert report["catalog_file"] == str(catalog.resolve())
    p1 = next(c for c in report["components"] if c["id"] == "P1")
    assert p1["size"] == "NPS 6" and p1["weight"] is not None


@pytest.mark.parametrize(
    ("extra", "named"),
    [
        (["--schedule", "XS"], "--schedule applies only when building from a scan"),
        (["--catalog", "en-10220"], "--catalog applies only when"),
        (["--no-merge"], "--no-merge applies only when"),
        (["--schedule", "XS", "--catalog", "en-10220"], "--schedule, --catalog apply only when"),
    ],
)
def test_build_options_on_a_model_document_are_refused(tmp_path, capsys, extra, named):
    """They only shape how a scan is built; a model document was built already (audit D6)."""
    import numpy as np

    from asbuilt.export.model_json import write_model_json
    from asbuilt.model import Component, Model
    from asbuilt.primitives import Cuboid

    column = Component("C1", "cuboid", Cuboid([0, 0, 1.5], np.eye(3), [0.4, 0.4, 3.0]))
    document = tmp_path / "model.json"
    write_model_json(Model(components=(column,)), document)
    out = tmp_path / "qa.json"
    code, stdout, err = run(["report", document, "--out", out, *extra], capsys)
    assert code == 2 and stdout == "" and named in err
    assert err.rstrip().endswith(
        f"leave {'them' if sum(a.startswith('--') for a in extra) > 1 else 'it'} out"
    )
    assert err.startswith(f"asbuilt: error: {document}: ") and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_report_from_a_model_document_names_the_scan(tmp_path, capsys):
    """The document's "source" is the scan; the report shows it (audit D11)."""
    out, document = tmp_path / "qa.html", tmp_path / "model.json"
    assert run(["model", BAY, "--out", document, "-q"], capsys)[0] == 0
    assert json.loads(document.read_text(encoding="utf-8"))["source"] == str(BAY)
    assert (
        run(["report", document, "--out", out, "--out", tmp_path / "qa.json", "-q"], capsys)[0] == 0
    )
    assert f"<dt>Scan</dt><dd>{BAY}</dd>" in out.read_text(encoding="utf-8")
    assert json.loads((tmp_path / "qa.json").read_text(encoding="utf-8"))["source"] == str(BAY)


def test_a_refused_object_is_reported_and_exits_1(tmp_path, capsys):
    """The reports are written without the object whose fit was refused; its error finding is
    in them, standard error says so, and the exit code is 1 (the reports lack it)."""
    from refused_scans import spool_with_refused, write

    scan = write(tmp_path / "scan.json", spool_with_refused())
    outs = [tmp_path / "qa.json", tmp_path / "qa.html"]
    code, out, err = run(["report", scan, "--out", outs[0], "--out", outs[1]], capsys)
    assert code == 1 and "findings: 1 error" in out
    assert err.startswith(f"asbuilt: {scan}: X1: not fitted as a cylinder") and err.count("\n") == 1
    data = json.loads(outs[0].read_text())
    assert [(f["code"], f["objects"]) for f in data["findings"]] == [("AB001", ["X1"])]
    assert "X1" not in {c["id"] for c in data["components"]}
    assert "fit-refused" in outs[1].read_text()


@pytest.mark.parametrize(
    ("command", "name"), [("report", "out.html"), ("report", "qa.csv"), ("model", "qa.json")]
)
def test_a_report_path_that_is_a_directory_suggests_a_report_file(
    tmp_path, capsys, monkeypatch, command, name
):
    """The hint names a report of the suffix asked for, not a model (audit 25)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / name).mkdir()
    option = ["--out", name] if command == "report" else ["--out", "m.step", "--report", name]
    code, _, err = run([command, BAY, *option], capsys)
    assert code == 2
    suffix = name.rsplit(".", 1)[1]
    assert err == (
        f"asbuilt: error: {name}: is a directory; give a file name to write "
        f"(e.g. add /report.{suffix})\n"
    )
    assert [p.name for p in tmp_path.iterdir()] == [name]
