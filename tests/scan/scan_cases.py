"""Hand-made ``asbuilt-scan`` documents: valid ones (points on known surfaces) and a table of bad ones.

Shared by tests/scan and tests/cli (which loads this file by path).
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


def surface_points(kind: str) -> np.ndarray:
    """Deterministic points, shape (n, 3) metres, spread over one surface of ``kind``."""
    if kind in ("cylinder", "auto"):
        # a 4" pipe (OD 114.3 mm) along x: 5 stations x 6 angles over a 150 degree arc
        s, phi = np.meshgrid(np.linspace(-0.9, 0.9, 5), np.radians(np.linspace(-75, 75, 6)))
        r = 0.05715
        return np.column_stack(
            [1.0 + s.ravel(), 2.0 - r * np.cos(phi.ravel()), 0.5 + r * np.sin(phi.ravel())]
        )
    if kind == "sphere":
        k = np.arange(20) + 0.5
        z = 1 - k / 20  # upper hemisphere, golden-angle spiral
        phi = np.pi * (1 + 5**0.5) * k
        rho = np.sqrt(1 - z * z)
        return np.array([3.0, 0.0, 1.0]) + 0.3 * np.column_stack(
            [rho * np.cos(phi), rho * np.sin(phi), z]
        )
    if kind == "plane":
        x, y = np.meshgrid(np.linspace(0, 2, 4), np.linspace(0, 1.5, 4))
        return np.column_stack([x.ravel(), y.ravel(), np.full(16, 2.5)])
    if kind == "cuboid":
        u, v = np.meshgrid(np.linspace(-0.4, 0.4, 4), np.linspace(-0.4, 0.4, 4))
        u, v = u.ravel(), v.ravel()
        half = 0.5
        front = np.column_stack([np.full(16, -half), u, v])
        side = np.column_stack([u, np.full(16, -half), v])
        top = np.column_stack([u, v, np.full(16, half)])
        return np.array([5.0, 5.0, 0.5]) + np.vstack([front, side, top])
    if kind == "hull":
        rng = np.random.default_rng(7)
        return rng.uniform([-1, -1, 0], [1, 1, 2], size=(12, 3))
    raise KeyError(kind)


def make_doc(
    units: str = "m", kinds=("cylinder", "cuboid", "sphere", "plane", "hull", "auto")
) -> dict:
    """A valid document with one object per kind (ids K1, K2...), points in ``units``."""
    from asbuilt.units import UNITS

    objects = [
        {"id": f"K{i + 1}", "kind": kind, "points": (surface_points(kind) / UNITS[units]).tolist()}
        for i, kind in enumerate(kinds)
    ]
    return {"format": "asbuilt-scan", "version": 1, "units": units, "objects": objects}


def _set(path: str, value):
    """A builder that sets ``doc[path]`` (dotted, with integer indices) to ``value``."""

    def build(doc: dict):
        *parents, last = [int(p) if p.isdigit() else p for p in path.split(".")]
        target = doc
        for key in parents:
            target = target[key]
        target[last] = value
        return doc

    return build


def _delete(key: str):
    def build(doc: dict):
        del doc[key]
        return doc

    return build


def _delete_in_object(index: int, key: str):
    def build(doc: dict):
        del doc["objects"][index][key]
        return doc

    return build


def _text(text: str):
    return lambda doc: text


def _nan_text(literal: str):
    """The valid document with objects[0].points[17][2] written as a bare JSON ``literal``."""

    def build(doc: dict):
        doc["objects"][0]["points"][17][2] = 123456.0
        return json.dumps(doc).replace("123456.0", literal)

    return build


def _duplicate_id(doc: dict):
    doc["objects"][3]["id"] = "K1"
    return doc


def _identical(doc: dict):
    doc["objects"][0]["points"] = [[1.5, 2.0, 0.25]] * 30
    return doc


def _unresolvable(doc: dict):
    # A millimetre-sized cluster at survey-frame coordinates (1e6 m): not identical, but
    # closer together than the loader resolves there.
    doc["objects"][0]["points"] = [
        [1e6 + 1e-4 * (i % 3), 2e6 + 1e-4 * (i % 5), 3e5 + 1e-4 * (i % 7)] for i in range(30)
    ]
    return doc


def _collinear(doc: dict):
    doc["objects"][0]["points"] = [[0.1 * i, 0.2 * i, 1.0 - 0.05 * i] for i in range(30)]
    return doc


def _far_point(value):
    """Point 7 of object K1 moved ``value`` metres away in x (a survey-frame point pasted in;
    an integer beyond 64 bits)."""

    def build(doc: dict):
        doc["objects"][0]["points"][7][0] = value
        return doc

    return build


@dataclass(frozen=True)
class Bad:
    """A bad document: how to build it from :func:`make_doc`, and the loader's exact message.

    ``message`` follows ``scan.json: `` (the file's name); ``schema_catches`` says whether the
    JSON Schema can see the problem too (some rules are beyond JSON Schema: see schema.py).
    """

    name: str
    build: Callable[[dict], object]
    message: str
    schema_catches: bool = True


BAD = (
    Bad(
        "an empty file",
        _text(""),
        "the file is empty (or only white space); give an asbuilt-scan JSON document",
        schema_catches=False,  # not JSON at all
    ),
    Bad(
        "a file of white space",
        _text(" \n\t\n"),
        "the file is empty (or only white space); give an asbuilt-scan JSON document",
        schema_catches=False,
    ),
    Bad(
        "malformed JSON",
        _text('{"format": "asbuilt-scan",\n  "version": 1\n  "units": "m"}'),
        "line 3 column 3: invalid JSON (Expecting ',' delimiter); fix the syntax there",
        schema_catches=False,  # not JSON at all
    ),
    Bad(
        "a key given twice",
        _text(
            '{"format": "asbuilt-scan", "version": 1, "units": "mm", "units": "m", "objects": []}'
        ),
        "units: given twice in one JSON object; keep one (JSON readers differ on which one counts)",
        schema_catches=False,  # a parsed document keeps one of the two
    ),
    Bad(
        "an object's key given twice",
        _text(
            '{"format": "asbuilt-scan", "version": 1, "units": "m", "objects": [{"id": "K1", '
            '"kind": "plane", "points": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], "kind": "plane"}]}'
        ),
        "objects[0] (K1).kind: given twice in one JSON object; keep one (JSON readers differ on "
        "which one counts)",
        schema_catches=False,
    ),
    Bad(
        "top level not an object",
        _text("[1, 2, 3]"),
        "the top level is an array; an asbuilt-scan file is a JSON object starting "
        '{"format": "asbuilt-scan", "version": 1, ...}',
    ),
    Bad(
        "wrong format",
        _set("format", "asbuilt-model"),
        'format: is "asbuilt-model", not "asbuilt-scan"; this is not an asbuilt scan file (a '
        "model document: re-export it with 'asbuilt check MODEL.json --fix OUT', or report on it "
        "with 'asbuilt report')",
    ),
    Bad(
        "missing format",
        _delete("format"),
        'format: missing; this is not an asbuilt scan (start the file with "format": '
        '"asbuilt-scan", "version": 1)',
    ),
    Bad(
        "wrong version",
        _set("version", 2),
        "version: version 2 is not supported; this asbuilt reads version 1 (upgrade asbuilt or "
        "convert the file)",
    ),
    Bad(
        "version as text", _set("version", "1"), 'version: must be the number 1, not a string ("1")'
    ),
    Bad("missing version", _delete("version"), 'version: missing; add "version": 1'),
    Bad(
        "missing units",
        _delete("units"),
        'units: missing; add "units": one of m, mm, cm, in, ft (e.g. "units": "m")',
    ),
    Bad(
        "unknown units",
        _set("units", "metres"),
        'units: unknown unit "metres"; use one of m, mm, cm, in, ft',
    ),
    Bad(
        "duplicate ids",
        _duplicate_id,
        'objects[3] (K1).id: duplicate id "K1" (also objects[0]); give every object its own id',
        schema_catches=False,
    ),
    Bad(
        "link to an unknown id",
        _set("links", [["K1", "K2"], ["K1", "K9"]]),
        'links[1]: unknown object id "K9"; link only ids listed in objects',
        schema_catches=False,
    ),
    Bad(
        "link to itself",
        _set("links", [["K2", "K2"]]),
        'links[0]: links "K2" to itself; link two different objects',
        schema_catches=False,
    ),
    Bad(
        "link not a pair",
        _set("links", [["K1", "K2", "K3"]]),
        'links[0]: must be a pair of object ids like ["P1", "P2"], not an array of 3 items',
    ),
    Bad(
        "non-numeric coordinate",
        _set("objects.3.points.5.1", "2.5"),
        'objects[3] (K4).points[5]: coordinate is a string ("2.5"), not a number',
    ),
    Bad(
        "null coordinate",
        _set("objects.0.points.7.0", None),
        "objects[0] (K1).points[7]: coordinate is null, not a number",
    ),
    Bad(
        "boolean coordinate",
        _set("objects.0.points.7.0", True),
        "objects[0] (K1).points[7]: coordinate is true, not a number",
    ),
    Bad(
        "NaN coordinate",
        _nan_text("NaN"),
        "objects[0] (K1).points[17]: coordinate is NaN",
        schema_catches=False,  # JSON has no NaN; Python's parser accepts it
    ),
    Bad(
        "infinite coordinate",
        _nan_text("-Infinity"),
        "objects[0] (K1).points[17]: coordinate is infinite",
        schema_catches=False,
    ),
    Bad(
        "coordinate overflowing to infinity",
        _nan_text("1e999"),
        "objects[0] (K1).points[17]: coordinate is infinite",
        schema_catches=False,
    ),
    Bad(
        "point of 2 numbers",
        _set("objects.1.points.4", [5.0, 5.0]),
        "objects[1] (K2).points[4]: a point must be 3 numbers [x, y, z], not 2",
    ),
    Bad(
        "point of 4 numbers",
        _set("objects.1.points.0", [5.0, 5.0, 1.0, 1.0]),
        "objects[1] (K2).points[0]: a point must be 3 numbers [x, y, z], not 4",
    ),
    Bad(
        "point not an array",
        _set("objects.2.points.2", 7),
        "objects[2] (K3).points[2]: a point must be an array of 3 numbers [x, y, z], not 7",
    ),
    Bad(
        "points not an array",
        _set("objects.2.points", {"x": 1}),
        "objects[2] (K3).points: must be an array of points [x, y, z], not an object",
    ),
    Bad(
        "too few points",
        _set("objects.2.points", [[3.0, 0.0, 1.3], [3.3, 0.0, 1.0], [3.0, 0.3, 1.0]]),
        "objects[2] (K3).points: has 3 points; a sphere needs at least 4; scan more points on "
        "the object",
    ),
    Bad(
        "too few points for auto",
        _set(
            "objects.5.points", [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, 0, 1]]
        ),
        'objects[5] (K6).points: has 6 points; an object of kind "auto" needs at least 7; scan '
        "more points on the object",
    ),
    Bad(
        "no points",
        _set("objects.0.points", []),
        "objects[0] (K1).points: has 0 points; a cylinder needs at least 6; scan more points on "
        "the object",
    ),
    Bad(
        "all points identical",
        _identical,
        "objects[0] (K1).points: all 30 points are identical; a cylinder needs points spread "
        "across its surface (re-aim and rescan)",
        schema_catches=False,
    ),
    Bad(
        "points too close for their coordinates",
        _unresolvable,
        "objects[0] (K1).points: the 30 points span only 0.0006 m at coordinates of 2e+06 m, too "
        "little to resolve there (under 1e-09 of the coordinates); check the units, or give the "
        "points relative to a site origin",
        schema_catches=False,
    ),
    Bad(
        "collinear points",
        _collinear,
        "objects[0] (K1).points: the points are collinear; a cylinder needs points spread across "
        "its surface (re-aim and rescan)",
        schema_catches=False,
    ),
    Bad(
        "one point far from the others",
        _far_point(5000000.0),
        "objects[0] (K1).points[7]: this point lies 5e+06 m from the others' median, which "
        "makes them look collinear; check its coordinates (units, a point from another frame)",
        schema_catches=False,
    ),
    Bad(
        "an integer coordinate beyond 64 bits",
        _far_point(10**20),
        "objects[0] (K1).points[7]: a coordinate of 1e+20 m is beyond any site (at most 1e+08 "
        "m, after the file's units); check the units and the number",
        schema_catches=False,
    ),
    Bad(
        "a point from another frame (50,000 km off)",
        _far_point(5e7),
        "objects[0] (K1).points[7]: this point lies 5e+07 m from the others' median, which "
        "makes them look collinear; check its coordinates (units, a point from another frame)",
        schema_catches=False,
    ),
    Bad(
        "a coordinate beyond any site (1e200 m, whose square overflows)",
        _far_point(1e200),
        "objects[0] (K1).points[7]: a coordinate of 1e+200 m is beyond any site (at most 1e+08 "
        "m, after the file's units); check the units and the number",
        schema_catches=False,
    ),
    Bad(
        "a station beyond any site",
        _set("objects.1.station", [0, 0, 2e8]),
        "objects[1] (K2).station: a coordinate of 2e+08 m is beyond any site (at most 1e+08 m, "
        "after the file's units); check the units and the number",
        schema_catches=False,
    ),
    Bad(
        "a line break in an id",
        _set("objects.2.id", "K3\nasbuilt: ok"),
        "objects[2].id: holds a control character (\\u000a) at character 3; use printable text",
    ),
    Bad(
        "an escape sequence in an id",
        _set("objects.2.id", "K3\u001b[31m"),
        "objects[2].id: holds a control character (\\u001b) at character 3; use printable text",
    ),
    Bad(
        "an unpaired surrogate in an id (legal JSON, no UTF-8)",
        _set("objects.2.id", "K3\ud800"),
        "objects[2].id: holds an unpaired surrogate (\\ud800) at character 3; use printable text",
        schema_catches=False,  # a JSON Schema pattern cannot name unpaired surrogates
    ),
    Bad(
        "an id too long for CAD names",
        _set("objects.2.id", "K" * 300),
        "objects[2].id: is 300 characters long; use at most 255 (CAD names hold no more)",
    ),
    Bad(
        "a NUL in a label",
        _set("objects.0.label", "pipe\x00rack"),
        "objects[0] (K1).label: holds a control character (\\u0000) at character 5; use "
        "printable text",
    ),
    Bad(
        "an unpaired surrogate in the scan name",
        _set("name", "site\udc00"),
        "name: holds an unpaired surrogate (\\udc00) at character 5; use printable text",
        schema_catches=False,
    ),
    Bad(
        "an integer too long for Python to parse",
        _text(
            '{"format": "asbuilt-scan", "version": 1, "units": "mm",\n'
            ' "objects": [{"id": "K1", "kind": "cylinder",\n'
            f'   "points": [[12, 0, 0], [{"1" * 5000}, 0, 0]]}}]}}'
        ),
        "line 3 column 28: a number of 5,000 digits is too long to be a coordinate; fix the "
        "number there",
    ),
    Bad(
        "unknown kind",
        _set("objects.4.kind", "cone"),
        'objects[4] (K5).kind: unknown kind "cone"; use one of cylinder, cuboid, sphere, plane, '
        "hull, auto",
    ),
    Bad(
        "missing kind",
        _delete_in_object(4, "kind"),
        "objects[4] (K5).kind: missing; use one of cylinder, cuboid, sphere, plane, hull, auto",
    ),
    Bad(
        "missing id",
        _delete_in_object(1, "id"),
        'objects[1].id: missing; give the object an id such as "P1"',
    ),
    Bad(
        "empty id",
        _set("objects.1.id", ""),
        'objects[1].id: must be non-empty text, not an empty string; give the object an id such as "P1"',
    ),
    Bad(
        "blank id",
        _set("objects.1.id", "  "),
        'objects[1].id: "  " starts or ends with white space (or is only white space); remove it',
    ),
    Bad(
        "id with a trailing space",
        _set("objects.1.id", "H1 "),
        'objects[1].id: "H1 " starts or ends with white space (or is only white space); remove it',
    ),
    Bad(
        "missing points",
        _delete_in_object(5, "points"),
        "objects[5] (K6).points: missing; add the measured points [[x, y, z], ...]",
    ),
    Bad(
        "object not an object",
        _set("objects.2", "K3"),
        'objects[2]: must be an object like {"id": "P1", "kind": "cylinder", "points": [...]}, '
        'not a string ("K3")',
    ),
    Bad(
        "missing objects",
        _delete("objects"),
        'objects: missing; add "objects": [{"id": ..., "kind": ..., "points": [...]}]',
    ),
    Bad(
        "label not text",
        _set("objects.0.label", 12),
        "objects[0] (K1).label: must be text (a JSON string), not 12",
    ),
    Bad(
        "negative range sigma",
        _set("sensor", {"range_sigma": -0.002}),
        "sensor.range_sigma: must be a positive number (the range noise in the file's units), "
        "not -0.002",
    ),
    Bad(
        "sensor sigma in the wrong unit",
        _set("sensor", {"range_sigma": 2}),
        "sensor.range_sigma: 2 m is not a range finder's noise (expected 1e-05 to 0.1 m); it is "
        "in the file's units (m): check the value and the units",
        schema_catches=False,  # the plausible range depends on the units
    ),
    Bad(
        "sensor position of 2 numbers",
        _set("sensor", {"position": [0.0, 0.0]}),
        "sensor.position: must be 3 finite numbers [x, y, z] in the file's units",
    ),
    Bad(
        "measurements of the wrong length",
        _set("objects.3.measurements", [[10.0, 5.0, 2.5]] * 3),
        "objects[3] (K4).measurements: 3 measurements for 16 points; give one "
        "[pan_deg, tilt_deg, range] per point, in the same order, or leave measurements out",
        schema_catches=False,
    ),
    Bad(
        "measurement with a zero range",
        _set("objects.3.measurements", [[10.0, 5.0, 2.5]] * 15 + [[10.0, 5.0, 0]]),
        "objects[3] (K4).measurements[15]: range must be positive (in the file's units)",
    ),
    Bad(
        "measurement with a pan angle beyond a full turn (steps, not degrees)",
        _set("objects.3.measurements", [[10.0, 5.0, 2.5]] * 2 + [[5120, 5.0, 2.5]] * 14),
        "objects[3] (K4).measurements[2]: a pan angle of 5120 degrees is beyond a full turn "
        "(at most 360); give the pan-tilt unit's angles in degrees",
        schema_catches=False,
    ),
    Bad(
        "measurement with a tilt angle of 1e300 degrees",
        _set("objects.3.measurements", [[10.0, 5.0, 2.5]] * 15 + [[10.0, -1e300, 2.5]]),
        "objects[3] (K4).measurements[15]: a tilt angle of -1e+300 degrees is beyond a full turn "
        "(at most 360); give the pan-tilt unit's angles in degrees",
        schema_catches=False,
    ),
    Bad(
        "insulation on a cuboid",
        _set("objects.1.insulation", 0.05),
        "objects[1] (K2).insulation: insulation is a radial thickness on a cylinder, not on kind "
        '"cuboid"; give the object "kind": "cylinder" or remove its insulation',
    ),
    Bad(
        "insulation on an auto object",
        _set("objects.5.insulation", 0.05),
        "objects[5] (K6).insulation: insulation is a radial thickness on a cylinder, not on kind "
        '"auto"; give the object "kind": "cylinder" or remove its insulation',
    ),
    Bad(
        "negative insulation",
        _set("objects.0.insulation", -0.01),
        "objects[0] (K1).insulation: must be a number >= 0 (the insulation's thickness in the "
        "file's units), not -0.01",
    ),
    Bad(
        "insulation as text",
        _set("objects.0.insulation", "50 mm"),
        "objects[0] (K1).insulation: must be a number >= 0 (the insulation's thickness in the "
        'file\'s units), not a string ("50 mm")',
    ),
    Bad(
        "insulation in millimetres in a metre file",
        _set("objects.0.insulation", 50),
        "objects[0] (K1).insulation: 50 m is thicker than any pipe insulation (at most 0.5 m); "
        "it is in the file's units (m): check the value and the units",
        schema_catches=False,
    ),
    Bad(
        "measurement of 2 numbers",
        _set("objects.3.measurements", [[10.0, 5.0]] * 16),
        "objects[3] (K4).measurements[0]: a measurement must be 3 numbers "
        "[pan_deg, tilt_deg, range], not 2",
    ),
)
