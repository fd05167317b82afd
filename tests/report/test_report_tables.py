"""CSV and JSON reports: columns, units, numbers and the same data in both."""

import csv
import datetime as dt
import io
import json
import math

import pytest
from report_helpers import known_model, many_findings

from asbuilt.report import report_data
from asbuilt.report.json_report import FORMAT, dumps_report, report_document
from asbuilt.report.table_csv import COLUMNS, csv_text

STAMP = dt.datetime(2026, 11, 21, 7, 0, tzinfo=dt.timezone.utc)


@pytest.fixture(scope="module")
def known_data():
    model = known_model()
    return report_data(model.replace(findings=many_findings(model)), generated=STAMP)


def rows_of(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text, newline="")))


def test_csv_header_and_one_row_per_component(known_data):
    text = csv_text(known_data)
    assert text.splitlines()[0].split(",") == list(COLUMNS)
    assert text.endswith("\r\n")  # RFC 4180 line ends
    rows = rows_of(text)
    assert [r["id"] for r in rows] == [c.id for c in known_data.model.components]
    assert set(COLUMNS) >= {
        "id",
        "type",
        "spool",
        "nominal",
        "schedule",
        "length_m",
        "quantity_unit",
        "quantity",
        "findings",
    }


def test_csv_values_and_units(known_data):
    rows = {r["id"]: r for r in rows_of(csv_text(known_data))}
    p1 = rows["P1"]
    assert (p1["type"], p1["spool"], p1["nominal"], p1["size"], p1["schedule"]) == (
        "pipe",
        "SP-1",
        "4",
        "NPS 4",
        "STD",
    )
    assert (p1["length_m"], p1["length_ft"], p1["quantity_unit"], p1["quantity"]) == (
        "1.000",
        "3.281",
        "m",
        "1.000",
    )
    assert float(p1["weight_kg"]) == pytest.approx(16.08, abs=0.005)
    assert float(p1["surface_area_m2"]) == pytest.approx(math.pi * 0.1143, abs=5e-4)
    assert p1["findings"] == "AB900 AB901 AB902" and p1["severity"] == "error"
    elbow = rows["P1-P2"]
    assert (elbow["length_m"], elbow["quantity_unit"], elbow["quantity"]) == ("", "ea", "1")
    column = rows["C1"]
    assert (column["quantity_unit"], column["quantity"], column["length_m"]) == (
        "m3",
        "0.4800",
        "3.000",
    )
    assert column["label"] == "column C1"


def test_csv_quotes_commas_and_quotes():
    model = known_model()
    from asbuilt.model import Component

    comps = list(model.components)
    comps[3] = Component("C1", "cuboid", comps[3].geometry, label='beam "A", front')
    data = report_data(model.replace(components=tuple(comps)), generated=STAMP)
    (row,) = [r for r in rows_of(csv_text(data)) if r["id"] == "C1"]
    assert row["label"] == 'beam "A", front'


def test_json_carries_the_same_rows(known_data):
    document = json.loads(dumps_report(known_data))
    assert (document["format"], document["version"], document["units"]) == (FORMAT, 1, "m")
    csv_rows = rows_of(csv_text(known_data))
    assert [c["id"] for c in document["components"]] == [r["id"] for r in csv_rows]
    for entry, row in zip(document["components"], csv_rows):
        assert entry["quantity_unit"] == row["quantity_unit"]
        assert float(row["quantity"]) == pytest.approx(entry["quantity"], abs=5e-4)
        assert " ".join(entry["findings"]) == row["findings"]
    totals = document["takeoff"]["totals"]
    assert totals["pipe_length"] == pytest.approx(2.0)
    assert totals["pipe_length_ft"] == pytest.approx(2.0 / 0.3048)
    assert totals["density"] == 7850
    assert totals["volumes"]["member"] == pytest.approx(0.48)
    assert document["findings_summary"] == {"error": 5, "warning": 5, "info": 5, "unverifiable": 5}
    assert len(document["findings"]) == 15
    assert document["generated"] == "2026-11-21T07:00:00Z"


def test_json_quality_of_a_fitted_model(plant_model):
    document = report_document(report_data(plant_model, generated=STAMP))
    quality = {q["id"]: q for q in document["quality"]}
    fitted = [c for c in plant_model.components if c.fit is not None]
    assert set(quality) == {c.id for c in fitted}
    for comp in fitted:
        q = quality[comp.id]
        assert q["points"] == comp.fit.n_points == len(q["residuals"])
        assert q["inliers"] == sum(q["inlier_mask"])
        assert q["rms"] == pytest.approx(comp.fit.rms)
    p1 = quality["P1"]
    snap = plant_model.component("P1").snap
    assert p1["snap_offset"] == pytest.approx(snap["od_fit"] - snap["od_catalog"])
    assert p1["size"] == "NPS 8"
    json.dumps(document, allow_nan=False)  # plain JSON, no NaN


def test_empty_model_reports():
    from asbuilt.model import Model

    data = report_data(Model(components=()), generated=STAMP)
    assert csv_text(data).splitlines() == [",".join(COLUMNS)]
    document = report_document(data)
    assert document["components"] == [] and document["title"] == "as-built model"


def test_json_reports_follow_the_schema(known_data, plant_model):
    import jsonschema

    from asbuilt.model import Model
    from asbuilt.report.json_report import report_schema

    schema = report_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    for data in (
        known_data,
        report_data(plant_model, generated=STAMP),
        report_data(Model(components=()), generated=STAMP),
    ):
        document = json.loads(dumps_report(data))
        errors = [f"{list(e.path)}: {e.message}" for e in validator.iter_errors(document)]
        assert errors == []
    broken = json.loads(dumps_report(known_data))
    broken["components"][0]["quantity_unit"] = "kg"
    del broken["takeoff"]["totals"]["pipe_length"]
    assert len(list(validator.iter_errors(broken))) == 2


def test_shipped_schema_is_up_to_date():
    from asbuilt.report.json_report import report_schema
    from asbuilt.report.schema import build_report_schema, main

    assert report_schema() == build_report_schema()
    assert main(["--check"]) == 0


@pytest.mark.parametrize(
    ("text", "cell"),
    [
        ('=HYPERLINK("http://x","C1")', '\'=HYPERLINK("http://x","C1")'),
        ("+SUM(A1:A9)", "'+SUM(A1:A9)"),
        ("-2+3", "'-2+3"),
        ("@cmd", "'@cmd"),
        ("\tTAB", "'\tTAB"),
        ("\rCR", "'\rCR"),
        ("column 1", "column 1"),
        ("Rohr-Ä1 = main", "Rohr-Ä1 = main"),  # only a leading character matters
    ],
)
def test_csv_text_cells_cannot_become_formulas(text, cell):
    """OWASP CSV injection: a spreadsheet runs a cell starting = + - @ tab CR (audit D3)."""
    import numpy as np

    from asbuilt.model import Component, Model
    from asbuilt.primitives import Cuboid

    column = Component(
        text, "cuboid", Cuboid([0, 0, 1.5], np.eye(3), [0.4, 0.4, 3.0]), label=text, spool=text
    )
    (row,) = rows_of(csv_text(report_data(Model(components=(column,)), generated=STAMP)))
    assert row["id"] == row["label"] == row["spool"] == cell
    assert row["quantity"] == "0.4800" and row["length_m"] == "3.000"  # numbers as they are
    assert report_document(report_data(Model(components=(column,))))["components"][0]["id"] == text


def test_csv_file_has_a_byte_order_mark_for_spreadsheets(tmp_path):
    """Excel reads a CSV without a BOM in the Windows code page (Rohr-Ä1 -> Rohr-Ã„1)."""
    from asbuilt.model import Component
    from asbuilt.report import write_report

    model = known_model()
    column = model.components[3]
    comps = model.components + (Component("Rohr-Ä1", column.type, column.geometry),)
    path = write_report(model.replace(components=comps), tmp_path / "qa.csv")
    raw = path.read_bytes()
    assert raw.startswith(b"\xef\xbb\xbfid,type,")
    assert "Rohr-Ä1".encode() in raw
    with open(path, newline="", encoding="utf-8-sig") as handle:
        assert list(csv.DictReader(handle))[-1]["id"] == "Rohr-Ä1"
