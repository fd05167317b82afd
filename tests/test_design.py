"""The design file format: loading (units, validation) and matching (missing, extra)."""

import json

import numpy as np
import pytest

from asbuilt.design import load_design, loads_design, match_design
from asbuilt.errors import DesignError
from asbuilt.model import Component, Model, Straight
from asbuilt.primitives import Cuboid

DOC = {
    "format": "asbuilt-design",
    "version": 1,
    "units": "mm",
    "pipes": [
        {"id": "D1", "nominal": "4", "start": [0, 0, 1000], "end": [2000, 0, 1000]},
        {"id": "D2", "nominal": "4", "start": [2000, 0, 1000], "end": [2000, 2000, 1000]},
    ],
    "columns": [{"id": "C1", "base": [0, 5000, 0], "top": [0, 5000, 3000], "size": [300, 300]}],
    "boxes": [{"id": "T1", "center": [4000, 0, 500], "size": [1000, 800, 1000]}],
}


def test_round_trip_in_millimetres(tmp_path):
    path = tmp_path / "design.json"
    path.write_text(json.dumps(DOC), encoding="utf-8")
    design = load_design(path)
    assert design.units == "mm" and design.source == str(path)
    d1 = design.components[0]
    np.testing.assert_allclose(d1.start, [0, 0, 1.0])
    assert d1.length == pytest.approx(2.0)
    np.testing.assert_allclose(d1.axis, [1, 0, 0])
    column = design.components[2]
    assert column.kind == "column" and column.size == pytest.approx([0.3, 0.3])
    box = design.components[3]
    assert box.kind == "box" and box.center == pytest.approx([4, 0, 0.5])


@pytest.mark.parametrize(
    "change, where, hint",
    [
        ({"units": "yards"}, "units", "unknown units"),
        ({"format": "other"}, "format", "asbuilt-design"),
        ({"format": "asbuilt-scan"}, "format", 'not "asbuilt-scan"; --design takes the intended'),
        (
            {"pipes": [{"id": "D1", "start": [0, 0], "end": [1, 0, 0]}]},
            "pipes[0] (D1).start",
            "3 numbers",
        ),
        (
            {"pipes": [{"id": "D1", "start": [0, 0, 0], "end": [0, 0, 0]}]},
            "pipes[0] (D1)",
            "must differ",
        ),
        ({"pipes": [{"start": [0, 0, 0], "end": [1, 0, 0]}]}, "pipes[0]", "id"),
        (
            {"pipes": [{"id": "D1", "start": [0, 0, 0], "end": [1, 0, 0], "od": 3}]},
            "pipes[0] (D1)",
            "unknown field 'od'",
        ),
        (
            {"columns": [{"id": "C1", "base": [0, 0, 0], "top": [0, 0, 3], "size": [0, 1]}]},
            "columns[0] (C1).size",
            "positive",
        ),
        (
            {"boxes": [{"id": "D1", "center": [0, 0, 0], "size": [1, 1, 1]}]},
            "boxes[0]",
            "duplicate id",
        ),
        ({"tanks": []}, "tanks", "unknown key"),
        (
            {"pipes": [{"id": "D1", "nominal": "banana", "start": [0, 0, 0], "end": [1, 0, 0]}]},
            "pipes[0] (D1).nominal",
            "not a pipe size",
        ),
        (
            {"pipes": [{"id": "D1", "nominal": "100 mm", "start": [0, 0, 0], "end": [1, 0, 0]}]},
            "pipes[0] (D1).nominal",
            "not a pipe size",
        ),
        (
            {"pipes": [{"id": "D1", "nominal": True, "start": [0, 0, 0], "end": [1, 0, 0]}]},
            "pipes[0] (D1).nominal",
            "size like",
        ),
    ],
)
def test_bad_design_is_one_located_line(change, where, hint):
    doc = {**DOC, **change}
    with pytest.raises(DesignError) as err:
        loads_design(json.dumps(doc), source="design.json")
    message = str(err.value)
    assert message.startswith("design.json: ") and "\n" not in message
    assert where in message and hint in message


@pytest.mark.parametrize("nominal", ["6", '6"', "NPS 6", "DN150", "DN 150 PN16", '1-1/2"', 6, 1.5])
def test_readable_nominal_is_kept_as_written(nominal):
    doc = {"pipes": [{"id": "D1", "nominal": nominal, "start": [0, 0, 0], "end": [1, 0, 0]}]}
    (pipe,) = loads_design(json.dumps(doc), source="design.json").components
    assert pipe.nominal == str(nominal) and pipe.where == "pipes[0] (D1)"


def test_not_json():
    with pytest.raises(DesignError, match="invalid JSON.*fix the syntax there"):
        loads_design("{", source="d.json")


def test_missing_file(tmp_path):
    with pytest.raises(DesignError, match="no such file"):
        load_design(tmp_path / "nope.json")


def straight(cid, start, end, r=0.057):
    return Component(id=cid, type="pipe", geometry=Straight(start, end, r))


def test_matching_pairs_nearest_and_reports_missing_and_extra():
    design = loads_design(json.dumps(DOC))
    built = Model(
        components=(
            straight("P2", [2.0, 0.01, 1.0], [2.0, 2.0, 1.0]),
            straight("P1", [0.0, 0.0, 1.02], [2.0, 0.0, 1.02]),
            straight("PX", [9.0, 9.0, 1.0], [10.0, 9.0, 1.0]),
            Component(
                id="T1", type="cuboid", geometry=Cuboid([4.0, 0.0, 0.5], np.eye(3), [1.0, 0.8, 1.0])
            ),
        )
    )
    match = match_design(built, design, radius=0.5)
    assert {(d.id, c.id) for d, c in match.pairs} == {("D1", "P1"), ("D2", "P2"), ("T1", "T1")}
    assert [d.id for d in match.missing] == ["C1"]
    assert [c.id for c in match.extra] == ["PX"]


def test_incompatible_kinds_do_not_match():
    design = loads_design(
        json.dumps({"boxes": [{"id": "B", "center": [0, 0, 0], "size": [1, 1, 1]}]})
    )
    built = Model(components=(straight("P1", [-0.5, 0, 0], [0.5, 0, 0]),))
    match = match_design(built, design)
    assert not match.pairs and len(match.missing) == 1 and len(match.extra) == 1


def test_documented_example_loads():
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "design-format.md").read_text(
        encoding="utf-8"
    )
    block = re.search(r"```json\n(.*?)```", text, re.S).group(1)
    design = loads_design(block, source="docs/design-format.md")
    assert [d.kind for d in design.components] == ["pipe", "pipe", "column", "box"]


# Found by mutation fuzzing (asbuilt check MODEL --design FILE, 1,500 mutants of a design):
# each was a traceback (or a silently accepted file) and is now one located line.
_PIPE = '{"pipes": [{"id": "A", "start": %s, "end": [1, 0, 0]}]}'


@pytest.mark.parametrize(
    "text, message",
    [
        (
            '{"units": ["mm"]}',
            "units: unknown units ['mm']; use one of m, mm, cm, in, ft",
        ),
        (
            _PIPE % ("[1" + "0" * 400 + ", 0, 0]"),
            "pipes[0] (A).start: must be finite numbers",
        ),
        (
            _PIPE % ("[1" + "0" * 5000 + ", 0, 0]"),
            "pipes[0] (A).start: must be finite numbers",
        ),
        (
            "[" * 100_000,
            "invalid JSON (nested too deeply); a design nests lists three levels at most",
        ),
        (
            _PIPE % "[1e300, 0, 0]",
            "pipes[0] (A).start: 1e+300 m is beyond any site (at most 1e+08 m); check the number "
            'and the file\'s "units"',
        ),
        (
            '{"pipes": [{"id": "a\\nb", "start": [0, 0, 0], "end": [1, 0, 0]}]}',
            'pipes[0]: "id" holds a control character (\\u000a); use printable text',
        ),
        (
            '{"pipes": [{"id": "%s", "start": [0, 0, 0], "end": [1, 0, 0]}]}' % ("x" * 300),
            'pipes[0]: "id" is 300 characters long; use at most 255',
        ),
        ('{"version": true}', "version: only version 1 is known"),
        (
            '{"pipes": [], "pipes": [{"id": "A", "start": [0, 0, 0], "end": [1, 0, 0]}]}',
            "pipes: given twice in one JSON object; keep one (JSON readers differ on which one "
            "counts)",
        ),
    ],
    ids=[
        "units-list",
        "integer-400-digits",
        "integer-5000-digits",
        "nested-too-deeply",
        "coordinate-beyond-any-site",
        "id-control-character",
        "id-too-long",
        "version-true",
        "repeated-key",
    ],
)
def test_fuzzed_design_files_are_one_located_line(text, message):
    with pytest.raises(DesignError) as info:
        loads_design(text, source="design.json")
    assert str(info.value) == f"design.json: {message}"


def test_box_axes_are_not_held_to_the_site_limit():
    doc = {
        "boxes": [{"id": "B", "center": [0, 0, 0], "size": [1, 1, 1], "axes": [[2e8, 0, 0]] * 3}]
    }
    with pytest.raises(DesignError, match=r"boxes\[0\] \(B\)\.axes: must be orthonormal"):
        loads_design(json.dumps(doc), source="design.json")
