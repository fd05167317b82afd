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
    with open(outs[1], newline="", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    document = json.loads(outs[2].read_text(encoding="utf-8"))
    assert [r["id"] for r in rows] == [c["id"] for c in document["components"]]
    assert len(rows) == 15
    assert "<svg" in outs[0].read_text(encoding="utf-8")


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
    with open(out, newline="", encoding="utf-8") as handle:
        types = {r["type"] for r in csv.DictReader(handle)}
    assert "pipe" not in types and "cylinder" in types


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--out", "{tmp}/qa.pdf"], "unknown report format '.pdf'"),
        (["--out", "{tmp}/nowhere/qa.html"], "directory does not exist"),
        (["--out", "{tmp}/qa.html", "--gltf", "{tmp}/model.step"], "--gltf must name"),
    ],
)
def test_bad_outputs_exit_2_with_one_line(tmp_path, capsys, extra, needle):
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
