"""An insulated cylinder whose insulation leaves no pipe inside is refused on its own, as a
refused fit is: the rest of the scan is modelled (seen in review: 120 mm of insulation on an
r 84 mm pipe made ``model``, ``check`` and ``report`` exit 2 and write nothing for the whole
scan, although its other object fitted)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from asbuilt.cli import main
from asbuilt.findings import FIT_REFUSED_CODE
from asbuilt.fit import NothingFittedError, fit
from asbuilt.pipeline import build_model
from asbuilt.scan import load_scan

ROOT = Path(__file__).resolve().parents[1]
SPOOL = ROOT / "samples" / "spool.json"  # six pipes in metres; P5 is NPS 4 (r 57.2 mm)
TOO_THICK = "60 mm of insulation is as thick as the fitted radius"
WHAT_TO_DO = "so no pipe is left inside; check the thickness and the file's units"


def scan_file(tmp_path, thickness=0.06, *, only=False) -> Path:
    """``samples/spool.json`` with ``thickness`` metres of insulation on P5 (P5 alone when
    ``only``)."""
    document = json.loads(SPOOL.read_text())
    for obj in document["objects"]:
        if obj["id"] == "P5":
            obj["insulation"] = thickness
    if only:
        document["objects"] = [o for o in document["objects"] if o["id"] == "P5"]
        document.pop("links", None)
    path = tmp_path / "lagged.json"
    path.write_text(json.dumps(document), encoding="utf-8")
    return path


def p5_points():
    scan = load_scan(SPOOL)
    return next(o for o in scan.objects if o.id == "P5").points


def test_model_refuses_the_object_and_writes_the_rest(tmp_path, capsys):
    out = tmp_path / "out" / "model.json"
    out.parent.mkdir()
    assert main(["model", str(scan_file(tmp_path)), "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"P5: fitted as a cylinder, but not in the model: {TOO_THICK}" in err
    assert [p.name for p in out.parent.iterdir()] == ["model.json"]  # atomic: no part files
    document = json.loads(out.read_text())
    sources = {s for c in document["components"] for s in c.get("sources", [c["id"]])}
    assert "P5" not in sources and {"P1", "P2", "P3", "P4", "P6"} <= sources
    (refused,) = [f for f in document["findings"] if f["code"] == FIT_REFUSED_CODE]
    assert refused["objects"] == ["P5"] and WHAT_TO_DO in refused["message"]
    keep = refused["suggestions"][0]
    assert keep["description"].startswith("check P5's insulation thickness and the file's units")
    np.testing.assert_allclose(keep["change"]["points"], p5_points())


@pytest.mark.parametrize("command", ["check", "report"])
def test_check_and_report_give_a_fit_refused_error_for_that_object(command, tmp_path, capsys):
    argv = [command, str(scan_file(tmp_path))]
    if command == "report":
        argv += ["--out", str(tmp_path / "qa.csv")]
    assert main(argv) == 1
    out = capsys.readouterr()
    if command == "check":
        assert (
            f"P5: error fit-refused: fitted as a cylinder, but not in the model: {TOO_THICK}"
            in (out.out)
        )
    else:
        assert (tmp_path / "qa.csv").is_file()
        assert "P1" in (tmp_path / "qa.csv").read_text()


def test_fit_shows_the_refusal_on_that_object_in_the_table_and_json(tmp_path, capsys):
    path = scan_file(tmp_path)
    assert main(["fit", str(path)]) == 0  # the points fit the cladding: no fit is refused
    table = " ".join(capsys.readouterr().out.split())
    assert "no pipe is left inside, so model, check and report leave it out (fit-refused)" in table
    assert main(["fit", str(path), "--json"]) == 0
    entry = next(o for o in json.loads(capsys.readouterr().out)["objects"] if o["id"] == "P5")
    assert any("no pipe is left inside" in note for note in entry["notes"])


def test_insulation_exactly_the_fitted_radius_is_refused_too():
    from asbuilt.model import without_pipeless_insulation

    report = fit(load_scan(SPOOL))
    item = next(i for i in report.fits if i.object.id == "P5")
    obj = dataclasses.replace(item.object, insulation=float(item.result.primitive.radius))
    scan = dataclasses.replace(
        report.scan, objects=tuple(obj if o.id == "P5" else o for o in report.scan.objects)
    )
    fits = tuple(dataclasses.replace(i, object=obj) if i is item else i for i in report.fits)
    refused = without_pipeless_insulation(dataclasses.replace(report, scan=scan, fits=fits))
    assert [f.object.id for f in refused.failures] == ["P5"]
    assert refused.failures[0].error.where == "objects[4] (P5).insulation"
    assert len(refused.fits) == len(report.fits) - 1


def test_a_scan_whose_only_object_is_refused_so_is_bad_input(tmp_path, capsys):
    path = scan_file(tmp_path, only=True)
    with pytest.raises(NothingFittedError):
        build_model(load_scan(path))
    out = tmp_path / "model.json"
    assert main(["model", str(path), "--out", str(out)]) == 2
    assert not out.exists()
    assert f"objects[0] (P5).insulation: {TOO_THICK}" in capsys.readouterr().err


@pytest.mark.parametrize("thickness", [-0.01, 0.6, "50"])
def test_bad_insulation_values_stay_bad_input(thickness, tmp_path, capsys):
    out = tmp_path / "model.json"
    assert main(["model", str(scan_file(tmp_path, thickness)), "--out", str(out)]) == 2
    assert not out.exists()
    assert "objects[4] (P5).insulation" in capsys.readouterr().err


def test_an_empty_scan_is_still_checked_without_error(tmp_path, capsys):
    # the refusal must not make "nothing fitted" of a scan with nothing to fit
    document = json.loads(SPOOL.read_text())
    document["objects"], document["links"] = [], []
    path = tmp_path / "empty.json"
    path.write_text(json.dumps(document), encoding="utf-8")
    assert main(["check", str(path)]) == 0
    assert build_model(load_scan(path)).components == ()
