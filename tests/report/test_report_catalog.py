"""Reports read the catalog the model was built with: a user's catalog file, recorded in the model
and in its document, never swapped for a shipped catalog of the same name (audit D1)."""

import datetime as dt
import json
import math

import pytest
from report_helpers import ROOT, known_model

from asbuilt.export.model_json import dumps_model, load_model, model_document, write_model_json
from asbuilt.report import report_data
from asbuilt.report.json_report import report_document

STAMP = dt.datetime(2026, 11, 21, 7, 30, tzinfo=dt.timezone.utc)

# ASME B36.10M-2004 (standards.md): NPS 4 OD 114.3 mm STD wall 6.02 mm; NPS 6 OD 168.3 mm STD
# wall 7.11 mm. Plain-end mass m = rho * pi * (D - t) t; stainless steel 7900 kg/m3 (EN 10088-1).
NPS6_STAINLESS = 7900 * math.pi * (0.1683 - 0.00711) * 0.00711  # 28.44 kg/m
NPS6_CARBON = 0.0246615 * (168.3 - 7.11) * 7.11  # B36.10M's own formula, 28.26 kg/m


def user_catalog(path, *, name="my-pipes", title="Our plant's pipe", material="carbon steel"):
    """A user's pipe catalog file (the format of docs/catalogs.md) with NPS 4 and NPS 6."""
    path.write_text(
        f"# name: {name}\n# title: {title}\n# standard: plant standard PS-7\n# kind: pipe\n"
        f"# units: mm\n# material: {material}\n# designation: NPS\n# default_schedule: STD\n"
        "nominal,dn,od,wall_std,source\n"
        "4,100,114.3,6.02,ASME B36.10M-2004 Table 1\n"
        "6,150,168.3,7.11,ASME B36.10M-2004 Table 1\n",
        encoding="utf-8",
    )
    return path


@pytest.fixture(scope="module")
def spool_scan():
    from asbuilt.scan import load_scan

    return load_scan(ROOT / "samples" / "spool.json")


def _pipe6(data):
    (line,) = [p for p in data.takeoff.pipes if p.nominal == "6"]
    return line


def test_user_catalog_reaches_the_report(tmp_path, spool_scan):
    from asbuilt.pipeline import build_model

    catalog = user_catalog(tmp_path / "pipes.csv")
    model = build_model(spool_scan, catalog=catalog)
    assert model.catalog == "my-pipes"
    assert model.catalog_file == str(catalog.resolve())
    data = report_data(model, generated=STAMP)
    assert data.catalog_title == "plant standard PS-7 (Our plant's pipe)"
    assert data.catalog_file == str(catalog.resolve()) and data.catalog_problem is None
    line = _pipe6(data)
    assert line.size == "NPS 6" and line.wall == pytest.approx(0.00711)
    assert line.weight_per_m == pytest.approx(NPS6_CARBON, abs=0.01)
    rows = {r.id: r for r in data.takeoff.rows}
    assert rows["P1"].size == "NPS 6" and rows["P1"].weight is not None
    # ... and again from the model document, written and read back
    write_model_json(model, tmp_path / "model.json")
    again = report_data(load_model(tmp_path / "model.json"), generated=STAMP)
    assert again.catalog_title == data.catalog_title
    assert _pipe6(again).weight == pytest.approx(line.weight)


def test_user_catalog_named_like_a_shipped_one_keeps_its_own_data(tmp_path):
    """A user's file named 'asme-b36.10m' (stainless here) must not get the shipped data."""
    from asbuilt.catalog import load_catalog
    from asbuilt.pipeline import catalog_file

    path = user_catalog(
        tmp_path / "b3610.csv", name="asme-b36.10m", title="stainless", material="stainless steel"
    )
    catalog = load_catalog(path)
    assert catalog_file(catalog) == str(path.resolve())
    assert catalog_file(load_catalog("asme-b36.10m")) is None  # the shipped one: no file
    model = known_model().replace(catalog="asme-b36.10m", catalog_file=str(path.resolve()))
    document = json.loads(dumps_model(model))
    assert document["catalog_file"] == str(path.resolve())
    data = report_data(_load(document, tmp_path), generated=STAMP)
    assert data.catalog_title == "plant standard PS-7 (stainless)"
    assert data.takeoff.material == "stainless steel" and data.takeoff.density == 7900


def _load(document, tmp_path):
    path = tmp_path / "doc.json"
    path.write_text(json.dumps(document), encoding="utf-8")
    return load_model(path)


def test_stainless_user_catalog_weights(tmp_path, spool_scan):
    from asbuilt.pipeline import build_model

    path = user_catalog(
        tmp_path / "b3610.csv", name="asme-b36.10m", title="stainless", material="stainless steel"
    )
    model = build_model(spool_scan, catalog=path, check=False)
    line = _pipe6(report_data(model, generated=STAMP))
    assert line.weight_per_m == pytest.approx(NPS6_STAINLESS, abs=0.01)


def test_a_catalog_file_that_is_gone_is_said(tmp_path):
    model = known_model().replace(catalog="my-pipes", catalog_file=str(tmp_path / "gone.csv"))
    data = report_data(model, generated=STAMP)
    assert "catalog file cannot be read" in data.catalog_problem
    assert "gone.csv" in data.catalog_problem
    (line,) = data.takeoff.pipes
    assert line.size == "4" and line.weight is None
    assert report_document(data)["catalog_problem"] == data.catalog_problem


def test_an_older_document_naming_a_user_catalog_is_said():
    data = report_data(known_model().replace(catalog="my-pipes"), generated=STAMP)
    assert "'my-pipes' is no shipped catalog" in data.catalog_problem


def test_a_shipped_catalog_has_no_file_and_no_problem():
    data = report_data(known_model(), generated=STAMP)
    assert data.catalog_file is None and data.catalog_problem is None
    assert model_document(known_model())["catalog_file"] is None


def test_an_explicit_catalog_wins(tmp_path):
    from asbuilt.catalog import load_catalog

    catalog = load_catalog(user_catalog(tmp_path / "pipes.csv", title="given"))
    data = report_data(known_model().replace(catalog="my-pipes"), catalog=catalog)
    assert data.catalog_title == "plant standard PS-7 (given)" and data.catalog_problem is None
