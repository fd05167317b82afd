"""The asbuilt-model document: shape, round trip through the reader, clear errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from asbuilt.export.model_json import (
    FORMAT,
    ModelDocumentError,
    dumps_model,
    load_model,
    load_model_document,
    model_document,
    model_from_document,
    write_model_json,
)
from asbuilt.model import Correction

ROOT = Path(__file__).resolve().parents[2]


def test_document_head_and_component_fields(zoo):
    document = model_document(zoo)
    assert (document["format"], document["version"], document["units"]) == (FORMAT, 1, "m")
    assert document["display_units"] == "mm" and document["catalog"] == "asme-b36.10m"
    pipe = document["components"][0]
    assert pipe["id"] == "P1" and pipe["type"] == "pipe" and pipe["shape"] == "straight"
    assert pipe["nominal"] == "4" and pipe["schedule"] == "STD"
    assert pipe["od"] == pytest.approx(0.1143) and pipe["start"] == [0, 0, 0]
    assert pipe["spool"] == "S1" and pipe["source"] == "P1" and pipe["sources"] == ["P1"]
    elbow = document["components"][1]
    assert elbow["type"] == "elbow" and elbow["angle_deg"] == pytest.approx(90.0)
    assert elbow["bend_radius"] == pytest.approx(0.2) and len(elbow["ends"]) == 2
    assert elbow["source"] is None
    assert document["spools"] == [
        {"id": "S1", "components": ["P1", "E1", "P2"], "pipe_length": 2.0}
    ]


def test_findings_have_the_documented_shape(zoo):
    findings = model_document(zoo)["findings"]
    assert [f["severity"] for f in findings] == ["error", "warning", "info"]
    assert set(findings[0]) == {
        "code",
        "slug",
        "severity",
        "objects",
        "location",
        "message",
        "measured",
        "allowed",
        "stderr",
        "unit",
        "suggestions",
        "unverifiable",
        "waived",
    }
    assert findings[0]["waived"] is None  # set only by a rules file's [[waive]]
    assert findings[0]["location"] == [6, 2, 1]
    assert findings[1]["measured"] == 1.5 and findings[1]["unit"] == "deg"


def test_round_trip_restores_everything_but_fits(zoo, tmp_path):
    path = tmp_path / "zoo.json"
    write_model_json(zoo, path)
    again = load_model(path)
    assert model_document(again) == model_document(zoo)
    for before, after in zip(zoo.components, again.components):
        assert type(after.geometry) is type(before.geometry)
    assert path.read_text() == dumps_model(again)  # stable text


def test_document_is_strict_json(zoo):
    text = dumps_model(zoo)
    json.loads(text, parse_constant=lambda name: pytest.fail(f"non-standard {name}"))


def test_corrections_and_snap_survive(zoo):
    pipe = zoo.components[0]
    changed = zoo.replace(
        components=(
            type(pipe)(
                **{
                    **pipe.__dict__,
                    "corrections": (Correction("diameter snapped", 0.1139, 0.1143, 0.0004, "m"),),
                    "snap": {
                        "status": "snapped",
                        "od_fit": np.float64(0.1139),
                        "candidates": ("4", "3-1/2"),
                    },
                }
            ),
            *zoo.components[1:],
        )
    )
    entry = model_document(changed)["components"][0]
    assert entry["corrections"] == [
        {"what": "diameter snapped", "before": 0.1139, "after": 0.1143, "size": 0.0004, "unit": "m"}
    ]
    assert entry["snap"] == {"status": "snapped", "od_fit": 0.1139, "candidates": ["4", "3-1/2"]}
    again = model_from_document(model_document(changed))
    assert again.components[0].corrections[0].what == "diameter snapped"


def test_real_pipeline_model_round_trips(tmp_path):
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    model = build_model(load_scan(ROOT / "samples" / "spool.json"))
    path = tmp_path / "spool.json"
    write_model_json(model, path)
    document = load_model_document(path)
    assert document["source"].endswith("spool.json")
    fitted = [c for c in document["components"] if c["fitted"] is not None]
    assert fitted and all({"method", "rms", "stderr", "points"} <= set(c["fitted"]) for c in fitted)
    assert (
        model_document(model_from_document(document))["components"][0]["id"]
        == document["components"][0]["id"]
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("{", "line 1 column 2: invalid JSON"),
        ("[]", "the document must be a JSON object"),
        ('{"format": "asbuilt-scan", "version": 1}', "format: format is 'asbuilt-scan'"),
        ('{"format": "asbuilt-model", "version": 9}', "version: version 9 is not supported"),
        ('{"format": "asbuilt-model", "version": 1, "units": "mm"}', "units: units must be 'm'"),
        ('{"format": "asbuilt-model", "version": 1, "components": {}}', "components: must be"),
    ],
)
def test_bad_documents_name_the_file_and_field(tmp_path, text, message):
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(ModelDocumentError) as info:
        load_model_document(path)
    assert str(info.value).startswith(f"{path}: ")
    assert message in str(info.value)


@pytest.mark.parametrize(
    ("component", "field", "message"),
    [
        (
            {"id": "P1", "type": "pipe", "shape": "straight", "start": [0, 0, 0]},
            "",
            "missing field 'end'",
        ),
        ({"id": "P1", "type": "pipe", "shape": "blob"}, ".shape", 'unknown shape "blob"; use'),
        (
            {"id": "P1", "type": "bolt", "shape": "sphere", "center": [0, 0, 0], "radius": 1},
            "",
            "component type must be one of",
        ),
        (
            {"id": "S", "type": "sphere", "shape": "sphere", "center": [0, 0], "radius": 1},
            ".center",
            "must be 3 finite numbers [x, y, z], not [0, 0]",
        ),
        (
            {"id": "P1", "type": "pipe", "shape": "straight", "start": None, "end": [1, 0, 0]},
            ".start",
            "must be 3 finite numbers [x, y, z], not null",
        ),
        (
            {
                "id": "P1",
                "type": "pipe",
                "shape": "straight",
                "start": [0, 0, 0],
                "end": [1, 0, 0],
                "od": "4in",
            },
            ".od",
            'must be a finite number, not "4in"',
        ),
        (
            {
                "id": "E",
                "type": "elbow",
                "shape": "bend",
                "ends": [[0, 0, 0]],
                "center": [0, 0, 0],
                "od": 0.1,
            },
            ".ends",
            "must be two points [[x, y, z], [x, y, z]], not [[0, 0, 0]]",
        ),
    ],
)
def test_bad_components_are_located(component, field, message):
    document = {"format": FORMAT, "version": 1, "components": [component]}
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith(f"m.json: components[0] ({component['id']}){field}: ")
    assert message in str(info.value)


@pytest.mark.parametrize("od", [-0.1, 0])
def test_a_diameter_that_is_no_length_is_named_as_such(od):
    pipe = {"id": "P1", "type": "pipe", "shape": "straight", "start": [0, 0, 0], "end": [1, 0, 0]}
    document = {"format": FORMAT, "version": 1, "components": [{**pipe, "od": od}]}
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value) == (
        f"m.json: components[0] (P1).od: must be a positive length in metres, not {od:g}"
    )


def test_two_components_of_one_id_are_refused_when_read():
    # findings, spools and CAD names refer to components by id (only writing CAD caught it)
    pipe = {"type": "pipe", "shape": "straight", "start": [0, 0, 0], "end": [1, 0, 0]}
    pipe["od"] = 0.1
    components = [{"id": "P1", **pipe}, {"id": "P2", **pipe}, {"id": "P1", **pipe}]
    document = {"format": FORMAT, "version": 1, "components": components}
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value) == (
        "m.json: components[2] (P1).id: duplicate id 'P1' (also components[0]); give every "
        "component its own id"
    )


@pytest.mark.parametrize(
    ("document", "message"),
    [
        ({"format": FORMAT, "version": 1}, 'components: missing; add "components": [...]'),
        (
            {"format": FORMAT, "version": 1, "units": "m", "objects": []},
            'components: missing; it has "objects", so it looks like a scan',
        ),
        (
            {"format": FORMAT, "version": 1, "components": [5]},
            "components[0]: must be a JSON object (a component), not 5",
        ),
        (
            {"format": FORMAT, "version": 1, "components": [], "findings": ["x"]},
            'findings[0]: must be a JSON object (a finding), not "x"',
        ),
    ],
)
def test_documents_that_are_not_models(document, message):
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value) == f"m.json: {message}" or str(info.value).startswith(
        f"m.json: {message}"
    )


@pytest.mark.parametrize(
    ("key", "entry", "where", "message"),
    [
        ("spools", {"components": ["P1"]}, "spools[0]", "missing field 'id'"),
        (
            "findings",
            {"code": "AB1", "slug": "x", "severity": "fatal", "message": "m"},
            "findings[0]",
            "severity must be one of",
        ),
        (
            "findings",
            {"code": "AB1", "severity": "error", "message": "m"},
            "findings[0]",
            "missing field 'slug'",
        ),
    ],
)
def test_bad_spools_and_findings_are_located(key, entry, where, message):
    document = {"format": FORMAT, "version": 1, "components": [], key: [entry]}
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith(f"m.json: {where}: ")
    assert message in str(info.value)


def test_missing_file(tmp_path):
    with pytest.raises(ModelDocumentError, match="cannot read the file"):
        load_model_document(tmp_path / "nope.json")


def test_documents_follow_the_shipped_schema(zoo):
    import jsonschema

    from asbuilt.export.model_json import model_schema
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    schema = model_schema()
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    validator.validate(model_document(zoo))
    for sample in ("spool", "plant", "structural-bay"):
        model = build_model(load_scan(ROOT / "samples" / f"{sample}.json"))
        validator.validate(json.loads(dumps_model(model)))


@pytest.mark.parametrize(
    ("change", "path"),
    [
        (lambda d: d["components"][0].pop("end"), ["components", 0]),
        (lambda d: d["findings"][0].update(severity="fatal"), ["findings", 0, "severity"]),
        (lambda d: d["components"][1].update(ends=[[0, 0, 0]]), ["components", 1, "ends"]),
        (lambda d: d.update(version=2), ["version"]),
    ],
)
def test_schema_rejects_broken_documents(zoo, change, path):
    import jsonschema

    from asbuilt.export.model_json import model_schema

    document = model_document(zoo)
    change(document)
    errors = list(jsonschema.Draft202012Validator(model_schema()).iter_errors(document))
    assert errors
    assert any(list(error.absolute_path)[: len(path)] == path for error in errors)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"id": [1]}, "components[0] ([1]).id: must be non-empty text, not [1]"),
        ({"sources": "P1"}, 'components[0] (P1).sources: must be a list of object ids, not "P1"'),
        ({"snap": [1]}, "components[0] (P1).snap: must be an object or null, not [1]"),
        ({"corrections": "x"}, 'components[0] (P1).corrections: must be a list, not "x"'),
        (
            {"corrections": [{"what": "moved", "size": "big"}]},
            'components[0] (P1).corrections[0].size: must be a finite number, not "big"',
        ),
        ({"od": float("inf")}, "components[0] (P1).od: must be a finite number, not Infinity"),
    ],
)
def test_component_fields_are_checked_by_type(change, message):
    component = {
        "id": "P1",
        "type": "pipe",
        "shape": "straight",
        "start": [0, 0, 0],
        "end": [1, 0, 0],
        "od": 0.1143,
        **change,
    }
    document = {"format": FORMAT, "version": 1, "components": [component]}
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value) == f"m.json: {message}"


def _reducer_model(offset):
    from asbuilt.model import Component, Model, Reducer

    # NPS 6 x 4 (OD 168.3 / 114.3 mm, B36.10M), H = 140 mm (B16.9), axes 27 mm apart
    end = np.array([0.14, 0.0, 1.0]) + np.asarray(offset, float)
    geometry = Reducer([0, 0, 1.0], end, 0.08415, 0.05715, 0.00711, offset=offset)
    return Model(components=(Component(id="R1", type="reducer", geometry=geometry),))


@pytest.mark.parametrize("offset", [[0, 0, 0], [0, 0, 0.027], [0, -0.027, 0]])
def test_reducer_offset_round_trips(tmp_path, offset):
    import jsonschema

    from asbuilt.export.model_json import model_schema

    model = _reducer_model(offset)
    document = json.loads(dumps_model(model))
    entry = document["components"][0]
    assert entry["offset"] == pytest.approx(offset)
    assert entry["eccentric"] is bool(np.any(offset))
    jsonschema.Draft202012Validator(model_schema()).validate(document)
    path = tmp_path / "m.json"
    write_model_json(model, path)
    back = load_model(path).components[0].geometry
    assert back.offset == pytest.approx(offset)
    assert back.eccentric is bool(np.any(offset))
    assert back.end == pytest.approx(model.components[0].geometry.end)


def test_reducer_without_offset_loads_concentric():
    """Documents written before eccentric reducers have no ``offset``: concentric."""
    entry = {
        "id": "R1",
        "type": "reducer",
        "shape": "reducer",
        "start": [0, 0, 1],
        "end": [0.14, 0, 1],
        "od_start": 0.1683,
        "od_end": 0.1143,
        "wall": 0.0,
    }
    document = {"format": FORMAT, "version": 1, "components": [entry]}
    geometry = model_from_document(document, source="old.json").components[0].geometry
    assert not geometry.eccentric and geometry.offset.tolist() == [0.0, 0.0, 0.0]


def test_reducer_offset_too_large_is_located():
    entry = {
        "id": "R1",
        "type": "reducer",
        "shape": "reducer",
        "start": [0, 0, 1],
        "end": [0.14, 0, 1.05],
        "od_start": 0.1683,
        "od_end": 0.1143,
        "offset": [0, 0, 0.05],
    }
    document = {"format": FORMAT, "version": 1, "components": [entry]}
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith("m.json: components[0] (R1)")
    assert "must not exceed the difference of the end radii" in str(info.value)


def test_per_end_walls_round_trip(tmp_path, spool_6x4x2):
    import jsonschema

    from asbuilt.export.model_json import model_schema

    model, path = spool_6x4x2, tmp_path / "m.json"
    write_model_json(model, path)
    document, back = json.loads(path.read_text()), load_model(path)
    jsonschema.Draft202012Validator(model_schema()).validate(document)
    entries = {e["type"]: e for e in document["components"]}
    # ASME B36.10M SCH 40 walls: NPS 6 7.11 mm, NPS 4 6.02 mm, NPS 2 3.91 mm
    reducer, tee = entries["reducer"], entries["tee"]
    assert (reducer["wall_start"], reducer["wall_end"]) == pytest.approx((0.00711, 0.00602))
    assert reducer["wall"] == pytest.approx(0.00602)  # the thinner, for older readers
    assert (tee["wall"], tee["branch_wall"]) == pytest.approx((0.00711, 0.00391))
    for before, after in zip(model.components, back.components):
        for name in ("wall", "wall_start", "wall_end", "branch_wall"):
            assert getattr(after.geometry, name, None) == getattr(before.geometry, name, None)


def test_documents_with_one_wall_per_fitting_still_read():
    """Documents written before per-end walls have one ``wall`` for a reducer or tee (the
    thinner pipe's): it is the wall at every end, as those versions built them."""
    common = {"format": FORMAT, "version": 1}
    reducer = {
        "id": "R1",
        "type": "reducer",
        "shape": "reducer",
        "start": [0, 0, 1],
        "end": [0.14, 0, 1],
        "od_start": 0.1683,
        "od_end": 0.1143,
        "wall": 0.00602,
    }
    tee = {
        "id": "T1",
        "type": "tee",
        "shape": "tee",
        "center": [1, 0, 1],
        "run": [[0.857, 0, 1], [1.143, 0, 1]],
        "branch_end": [1, 0.143, 1],
        "od": 0.1683,
        "branch_od": 0.0603,
        "wall": 0.00391,
    }
    model = model_from_document({**common, "components": [reducer, tee]}, source="old.json")
    r, t = (c.geometry for c in model.components)
    assert (r.wall_start, r.wall_end) == (0.00602, 0.00602)
    assert (t.wall, t.branch_wall) == (0.00391, 0.00391)


def test_a_reducing_elbow_round_trips_with_each_ends_size_and_wall(tmp_path, elbow_6x4):
    import jsonschema

    from asbuilt.export.model_json import model_schema

    path = tmp_path / "elbow.json"
    write_model_json(elbow_6x4, path)
    document = json.loads(path.read_text())
    jsonschema.Draft202012Validator(model_schema()).validate(document)
    (entry,) = [e for e in document["components"] if e["type"] == "elbow"]
    # ASME B36.10M SCH 40: NPS 6 OD 168.3 mm, wall 7.11 mm; NPS 4 OD 114.3 mm, wall 6.02 mm
    assert (entry["od"], entry["od_end"]) == pytest.approx((0.1683, 0.1143))
    assert (entry["wall_start"], entry["wall_end"]) == pytest.approx((0.00711, 0.00602))
    # for older readers, od and wall are what they built: the larger OD, the thinner wall
    assert entry["wall"] == pytest.approx(0.00602)
    before, after = elbow_6x4.component("P1-P2").geometry, load_model(path).component("P1-P2")
    assert after.geometry.radii == before.radii and after.geometry.walls == before.walls


def test_elbows_with_one_size_still_read():
    """Documents written before per-end sizes have one ``od`` and ``wall`` per elbow: the same
    at both ends, as those versions built them."""
    elbow = {
        "id": "E1",
        "type": "elbow",
        "shape": "bend",
        "center": [0, 0.229, 1],
        "ends": [[0, 0, 1], [0.229, 0.229, 1]],
        "od": 0.1683,
        "wall": 0.00602,
    }
    document = {"format": FORMAT, "version": 1, "components": [elbow]}
    (component,) = model_from_document(document, source="old.json").components
    assert component.geometry.radii == (0.1683 / 2, 0.1683 / 2)
    assert component.geometry.walls == (0.00602, 0.00602)
    assert not component.geometry.reducing


def test_insulation_round_trips_in_components_and_the_scan(tmp_path):
    import dataclasses

    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    scan = load_scan(ROOT / "samples" / "spool.json")
    objects = tuple(
        dataclasses.replace(o, insulation=0.04) if o.kind == "cylinder" else o for o in scan.objects
    )
    # the sample's points lie on the bare pipes; 40 mm less leaves every one a pipe inside
    model = build_model(dataclasses.replace(scan, objects=objects))
    assert {c.insulation for c in model.components} == {0.04}
    path = tmp_path / "lagged.json"
    write_model_json(model, path)
    document = load_model_document(path)
    assert {c["insulation"] for c in document["components"]} == {0.04}
    assert {o.get("insulation") for o in document["scan"]["objects"]} == {0.04}
    again = load_model(path)
    assert [c.insulation for c in again.components] == [c.insulation for c in model.components]
    assert {o.insulation for o in again.scan.objects} == {0.04}


@pytest.mark.parametrize(("given", "read"), [(None, 0.0), ("absent", 0.0), (0.03, 0.03)])
def test_insulation_absent_or_null_reads_as_bare(given, read):
    pipe = {"id": "P1", "type": "pipe", "shape": "straight", "start": [0, 0, 0], "end": [1, 0, 0]}
    pipe["od"] = 0.1143
    if given != "absent":
        pipe["insulation"] = given
    document = {"format": FORMAT, "version": 1, "components": [pipe]}
    assert model_from_document(document).components[0].insulation == read


@pytest.mark.parametrize(
    ("value", "message"), [(-0.01, "must be >= 0 (metres), not -0.01"), ("5", "finite number")]
)
def test_bad_insulation_is_located(value, message):
    pipe = {"id": "P1", "type": "pipe", "shape": "straight", "start": [0, 0, 0], "end": [1, 0, 0]}
    document = {
        "format": FORMAT,
        "version": 1,
        "components": [{**pipe, "od": 0.1, "insulation": value}],
    }
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith("m.json: components[0] (P1).insulation: ")
    assert message in str(info.value)


def test_a_reducer_to_a_pipe_of_no_catalog_size_round_trips(tmp_path, monkeypatch):
    # its snap "sizes" holds null for the unsnapped end; documents holding it were refused
    from asbuilt.merge import merge_model
    from asbuilt.report.takeoff import take_off

    monkeypatch.syspath_prepend(str(ROOT / "tests" / "merge"))
    from synthetic_pipes import Pipe, report_of

    pipes = [Pipe("P1", (0, 0, 0), (1, 0, 0), 0.1143), Pipe("P2", (1.2, 0, 0), (2.2, 0, 0), 0.08)]
    model = merge_model(report_of(pipes))
    reducer = next(c for c in model.components if c.type == "reducer")
    assert reducer.snap["sizes"] == ["4", None]
    path = tmp_path / "m.json"
    write_model_json(model, path)
    again = load_model(path)
    assert next(c for c in again.components if c.type == "reducer").snap["sizes"] == ["4", None]
    (line,) = [f for f in take_off(again).fittings if f.type.endswith("reducer")]
    assert line.size == "NPS 4 x 80.0 mm"
