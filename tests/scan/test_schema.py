"""The JSON Schema: generated from the code, shipped up to date, and in agreement with the loader."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import jsonschema
import pytest
from scan_cases import BAD, make_doc

from asbuilt.errors import ScanError
from asbuilt.scan import KINDS, loads_scan, scan_schema
from asbuilt.scan.schema import SCHEMA_PATH, main, schema_text, write_schema
from asbuilt.tolerances import MIN_POINTS
from asbuilt.units import UNITS

SAMPLES = Path(__file__).resolve().parents[2] / "samples"


def validator() -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator(scan_schema())


def test_schema_is_a_valid_draft_2020_12_schema():
    jsonschema.Draft202012Validator.check_schema(scan_schema())


def test_shipped_schema_equals_the_generated_one():
    assert SCHEMA_PATH.read_text(encoding="utf-8") == schema_text()
    assert json.loads(SCHEMA_PATH.read_text(encoding="utf-8")) == scan_schema()
    assert main(["--check"]) == 0


def test_write_schema_round_trip(tmp_path):
    path = write_schema(tmp_path / "scan.schema.json")
    assert json.loads(path.read_text(encoding="utf-8")) == scan_schema()


def test_schema_is_built_from_the_code_constants():
    schema = scan_schema()
    assert schema["properties"]["units"]["enum"] == list(UNITS)
    item = schema["properties"]["objects"]["items"]
    assert item["properties"]["kind"]["enum"] == list(KINDS)
    minimum = {
        rule["if"]["properties"]["kind"]["const"]: rule["then"]["properties"]["points"]["minItems"]
        for rule in item["allOf"]
        if "const" in rule["if"]["properties"]["kind"]
    }
    assert minimum == MIN_POINTS


@pytest.mark.parametrize("units", list(UNITS))
def test_good_documents_pass_both(units):
    doc = make_doc(units)
    doc.update(
        name="x",
        sensor={"position": [0, 0, 1], "range_sigma": 0.002 / UNITS[units]},
        links=[["K1", "K2"]],
    )
    doc["objects"][0]["measurements"] = [[1.0, 2.0, 3.0]] * len(doc["objects"][0]["points"])
    doc["objects"][0]["extra_key"] = {"anything": [1, 2]}
    doc["future_key"] = True
    validator().validate(doc)
    loads_scan(json.dumps(doc))


@pytest.mark.parametrize("case", BAD, ids=[case.name for case in BAD])
def test_schema_and_loader_agree_on_bad_documents(case):
    built = case.build(copy.deepcopy(make_doc()))
    text = built if isinstance(built, str) else json.dumps(built)
    with pytest.raises(ScanError):
        loads_scan(text)
    if case.message.startswith(("line ", "the file is empty")):
        return  # not JSON: nothing for a schema to judge
    document = json.loads(text)
    schema_errors = list(validator().iter_errors(document))
    # the schema catches exactly the problems it can express; the rest are documented in
    # asbuilt/scan/schema.py as checked by the loader only
    assert bool(schema_errors) == case.schema_catches, [e.message for e in schema_errors]


@pytest.mark.parametrize(
    "path", sorted(SAMPLES.glob("*.json")) if SAMPLES.is_dir() else [], ids=lambda p: p.name
)
def test_samples_pass_both(path):
    document = json.loads(path.read_text(encoding="utf-8"))
    if document.get("format") != "asbuilt-scan":
        pytest.skip(f"{path.name} is not a scan file")
    validator().validate(document)
    loads_scan(path.read_text(encoding="utf-8"), source=str(path))
