"""A model document edited by hand: every field the program reads back is checked on loading.

The cases are those a mutation fuzzer of a real document (``asbuilt model samples/spool.json
--out model.json``, then ``asbuilt check model.json``) found failing deep in a rule or a
reader with a traceback: each must now be one located error, and the CLI's exit code 2.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from asbuilt.cli import main
from asbuilt.export.model_json import (
    ModelDocumentError,
    load_model,
    model_from_document,
)

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def spool_document(tmp_path_factory) -> dict:
    """The sample spool's model document, as ``asbuilt model`` writes it."""
    path = tmp_path_factory.mktemp("doc") / "spool.json"
    assert main(["model", str(ROOT / "samples" / "spool.json"), "--out", str(path)]) == 0
    return json.loads(path.read_text())


def _component(document: dict, kind: str) -> tuple[int, dict]:
    """The first component of ``type`` ``kind`` with a fit, and its index."""
    for index, component in enumerate(document["components"]):
        if component["type"] == kind and component.get("fitted"):
            return index, component
    raise AssertionError(f"no fitted {kind} in the sample")


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("od_fit", [1, 2], "snap.od_fit: must be a finite number or null, not [1, 2]"),
        ("od_stderr", "0.003", 'snap.od_stderr: must be a finite number or null, not "0.003"'),
        ("od_fit", 1e300, "snap.od_fit: must be at most 1e+08 in size"),
        ("status", 3, "snap.status: must be text or null, not 3"),
        ("standard", "yes", 'snap.standard: must be true, false or null, not "yes"'),
        ("connects", "P2", 'snap.connects: must be a list of text, not "P2"'),
        ("hint", [1], "snap.hint: must be an object or null, not [1]"),
        ("hint", {"od": "big"}, 'snap.hint.od: must be a finite number or null, not "big"'),
        ("candidates", {"a": 1}, 'snap.candidates: must be a list or null, not {"a": 1}'),
        ("candidates", [None], "snap.candidates[0]: must be an object, not null"),
        ("candidates", [{"od": []}], "snap.candidates[0].od: must be a finite number or null"),
        ("fit_up", [{"with": "P2"}], "snap.fit_up[0].miss: missing"),
    ],
)
def test_snap_fields_are_checked(spool_document, field, value, message):
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["snap"][field] = value
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith(f"m.json: components[{index}] ({pipe['id']}).{message}")


def test_unknown_snap_keys_are_kept(spool_document):
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["snap"]["site_note"] = ["anything", {"the": "user's"}]
    model = model_from_document(document, source="m.json")
    assert model.components[index].snap["site_note"] == ["anything", {"the": "user's"}]


@pytest.mark.parametrize(
    ("name", "value", "message"),
    [
        ("arc_deg", [1], "must be a finite number or null, not [1]"),
        ("length_over_diameter", "reducer", 'must be a finite number or null, not "reducer"'),
    ],
)
def test_fit_diagnostics_are_numbers(spool_document, name, value, message):
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["fitted"]["diagnostics"][name] = value
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    where = f"m.json: components[{index}] ({pipe['id']}).fitted.diagnostics.{name}: "
    assert str(info.value) == where + message


def test_numbers_beyond_any_site_are_refused(spool_document):
    """Finite but absurd: their squares overflowed the rules' distance searches."""
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["start"] = [1e300, 0.0, 0.0]
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith(
        f"m.json: components[{index}] ({pipe['id']}).start: 1e+300 is beyond any site"
    )
    document = copy.deepcopy(spool_document)
    document["components"][index]["od"] = 1e200
    with pytest.raises(ModelDocumentError, match=r"\.od: 1e\+200 is beyond any site"):
        model_from_document(document, source="m.json")


def test_an_integer_beyond_any_float_is_a_located_error(spool_document, tmp_path):
    """A 400-digit integer overflowed ``float()`` in whichever check met it first."""
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["od"] = 12345
    text = json.dumps(document).replace('"od": 12345', '"od": ' + "9" * 400, 1)
    path = tmp_path / "m.json"
    path.write_text(text)
    with pytest.raises(ModelDocumentError) as info:
        load_model(path)
    assert str(info.value) == (
        f"{path}: components[{index}] ({pipe['id']}).od: must be a finite number, not Infinity"
    )


def test_a_link_naming_a_list_is_a_located_error(spool_document):
    document = copy.deepcopy(spool_document)
    document["scan"]["links"] = [[["P1"], "P2"]]
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value) == (
        'm.json: scan.links[0]: must be a pair of ids listed in objects, not [["P1"], "P2"]'
    )


def test_check_reports_a_hand_edited_document_in_one_line(spool_document, tmp_path, capsys):
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["fitted"]["diagnostics"]["arc_deg"] = [1]
    path = tmp_path / "m.json"
    path.write_text(json.dumps(document))
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert err.startswith(f"asbuilt: error: {path}: components[{index}] ({pipe['id']}).fitted.")


def test_bare_nominal_candidates_are_read_and_skipped_by_the_rules(spool_document, tmp_path):
    """``candidates`` as bare sizes: the size rules took ``"3-1/2"`` apart as ("3", "-")."""
    document = copy.deepcopy(spool_document)
    _, pipe = _component(document, "pipe")
    pipe["snap"]["candidates"] = ["4", "3-1/2"]
    path = tmp_path / "m.json"
    path.write_text(json.dumps(document))
    assert main(["check", str(path)]) in (0, 1)


def _inf_in(document: dict, edit, tmp_path) -> Path:
    """The document with ``edit`` applied (it sets a value to 12345) and that value written as
    ``1e999``, which JSON readers read as infinity."""
    edit(document)
    text = json.dumps(document).replace("12345", "1e999")
    assert "1e999" in text
    path = tmp_path / "m.json"
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("edit", "where"),
    [
        (lambda d, i: d["components"][i]["fitted"].update(rms=12345), "fitted.rms"),
        (lambda d, i: d["components"][i]["fitted"].update(sigma=12345), "fitted.sigma"),
        (
            lambda d, i: d["components"][i]["fitted"]["residuals"].__setitem__(2, 12345),
            "fitted.residuals[2]",
        ),
        (
            lambda d, i: d["components"][i]["fitted"]["stderr"].update(radius=12345),
            "fitted.stderr.radius",
        ),
        (
            lambda d, i: d["components"][i]["corrections"][0].update(before=12345),
            "corrections[0].before",
        ),
    ],
)
def test_an_infinite_number_in_a_component_is_a_located_error(
    spool_document, tmp_path, edit, where
):
    """The document promises finite numbers (non-finite ones are written null); ``1e999`` was
    read as infinity and kept."""
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    path = _inf_in(document, lambda d: edit(d, index), tmp_path)
    with pytest.raises(ModelDocumentError) as info:
        load_model(path)
    assert str(info.value) == (
        f"{path}: components[{index}] ({pipe['id']}).{where}: must be a finite number or null, "
        "not Infinity"
    )


def test_an_infinite_number_outside_the_components_is_a_located_error(spool_document, tmp_path):
    """A spool's infinite ``pipe_length`` was kept, and writing IFC then failed inside
    ifcopenshell ("Only finite values are allowed")."""
    document = copy.deepcopy(spool_document)
    path = _inf_in(document, lambda d: d["spools"][0].update(pipe_length=12345), tmp_path)
    with pytest.raises(ModelDocumentError) as info:
        load_model(path)
    assert str(info.value) == (
        f"{path}: spools[0].pipe_length: must be a finite number or null, not Infinity"
    )
    document = copy.deepcopy(spool_document)
    document["findings"] = [
        {
            "code": "AB202",
            "slug": "out-of-plumb",
            "severity": "warning",
            "objects": [],
            "location": None,
            "message": "m",
            "measured": 12345,
            "allowed": None,
            "stderr": None,
            "unit": "m",
            "suggestions": [],
            "unverifiable": False,
        }
    ]
    path = _inf_in(document, lambda d: None, tmp_path)
    with pytest.raises(ModelDocumentError, match=r"findings\[0\]\.measured: must be a finite"):
        load_model(path)


def test_a_residual_beyond_any_site_is_refused(spool_document):
    """Fit summaries hold numbers of at most 1e8 (the scan's limit), residuals included."""
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["fitted"]["residuals"][0] = 1e300
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith(
        f"m.json: components[{index}] ({pipe['id']}).fitted.residuals[0]: must be at most 1e+08"
    )


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        (
            "display_units",
            "furlong",
            'display_units: must be one of m, mm, cm, in, ft or null, not "furlong"',
        ),
        ("display_units", 5, "display_units: must be one of m, mm, cm, in, ft or null, not 5"),
        ("name", 5, "name: must be text or null, not 5"),
        ("name", ["a"], 'name: must be text or null, not ["a"]'),
    ],
)
def test_top_level_texts_are_checked(spool_document, key, value, message):
    """An unknown ``display_units`` failed writing STL or OBJ (``ValueError: unknown unit``), a
    ``name`` that is not text failed writing IFC, glTF or STEP inside the writer."""
    document = copy.deepcopy(spool_document)
    document[key] = value
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value) == f"m.json: {message}"


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("radius", 1e300, "fitted.radius: must be at most 1e+08 in size, not 1e+300"),
        ("radius", "big", 'fitted.radius: must be a number or null, not "big"'),
        ("size", "x", 'fitted.size: must be 3 numbers or null (metres), not "x"'),
        ("size", [1, 2], "fitted.size: must be 3 numbers or null (metres), not [1, 2]"),
        ("size", [1, 2, 1e300], "fitted.size[2]: must be at most 1e+08 in size, not 1e+300"),
    ],
)
def test_fitted_radius_and_size_are_checked(spool_document, field, value, message):
    """The fit summary's ``radius`` and ``size`` (read by tools; the rules use ``primitive``)
    were kept whatever they held, although fit summaries hold numbers of at most 1e8."""
    document = copy.deepcopy(spool_document)
    index, pipe = _component(document, "pipe")
    pipe["fitted"][field] = value
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value) == f"m.json: components[{index}] ({pipe['id']}).{message}"
