"""The scan loader: good documents in every unit, and every kind of bad input, located exactly."""

from __future__ import annotations

import json
import math
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scan_cases import BAD, make_doc, surface_points

from asbuilt.errors import ScanError, ScanReadError
from asbuilt.scan import KINDS, MAX_FILE_BYTES, MAX_POINTS, Scan, load_scan, loads_scan

# Metres per unit from the definitions (independent of asbuilt.units): the inch is exactly
# 25.4 mm (international yard and pound agreement, 1959) and the foot 12 inches.
METRES_PER = {"m": 1.0, "mm": 0.001, "cm": 0.01, "in": 25.4 / 1000, "ft": 12 * 25.4 / 1000}


@pytest.mark.parametrize("units", list(METRES_PER))
def test_points_are_converted_to_metres(units, write):
    scan = load_scan(write(make_doc(units)))
    assert isinstance(scan, Scan)
    assert scan.units == units
    assert [o.kind for o in scan.objects] == list(KINDS)
    for obj in scan.objects:
        np.testing.assert_allclose(obj.points, surface_points(obj.kind), rtol=1e-12, atol=1e-12)
        assert obj.points.dtype == np.float64 and obj.points.shape[1] == 3
        assert not obj.points.flags.writeable


def test_every_field_is_read(write):
    doc = make_doc("mm", kinds=("cylinder", "plane"))
    doc.update(
        name="pump room",
        sensor={"position": [1000.0, -500.0, 1500.0], "range_sigma": 2.0},
        links=[["K1", "K2"]],
        operator="J. Doe",  # unknown top-level key: kept and ignored
    )
    n = len(doc["objects"][0]["points"])
    doc["objects"][0].update(
        group="spool 3",
        label="suction line",
        nominal='4"',
        measurements=[[30.0, -10.0, 2500.0]] * n,
        colour="red",  # unknown object key: kept
    )
    scan = load_scan(write(doc))
    assert scan.name == "pump room"
    np.testing.assert_allclose(scan.sensor.position, [1.0, -0.5, 1.5])
    assert scan.sensor.range_sigma == pytest.approx(0.002)
    assert scan.links == (("K1", "K2"),)
    assert dict(scan.extra) == {"operator": "J. Doe"}
    pipe, wall = scan.objects
    assert (pipe.group, pipe.label, pipe.nominal) == ("spool 3", "suction line", '4"')
    assert dict(pipe.extra) == {"colour": "red"}
    assert pipe.measurements.shape == (n, 3)
    np.testing.assert_allclose(pipe.measurements[0], [math.pi / 6, -math.pi / 18, 2.5])
    assert (wall.group, wall.label, wall.nominal, wall.measurements) == (None, None, None, None)
    assert dict(wall.extra) == {}
    assert (pipe.index, wall.index) == (0, 1)
    assert wall.where == "objects[1] (K2)"
    assert scan.object("K2") is wall
    assert scan.source == str(write(doc))


def test_optional_fields_may_be_null(write):
    doc = make_doc(kinds=("sphere",))
    doc.update(name=None, sensor=None, links=None)
    doc["objects"][0].update(group=None, label=None, nominal=None, measurements=None)
    scan = load_scan(write(doc))
    assert scan.name is None and scan.sensor.position is None and scan.sensor.range_sigma is None
    assert scan.links == ()


def test_empty_scan_and_version_as_float(write):
    scan = load_scan(
        write({"format": "asbuilt-scan", "version": 1.0, "units": "ft", "objects": []})
    )
    assert scan.objects == () and scan.units == "ft"


def test_utf8_bom_and_non_ascii_text(write, tmp_path):
    doc = make_doc(kinds=("plane",))
    doc["objects"][0]["label"] = "Wand Süd – Ø 3 m"
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(doc, ensure_ascii=False).encode("utf-8"))
    assert load_scan(path).objects[0].label == "Wand Süd – Ø 3 m"


def test_loads_scan_names_the_source():
    text = json.dumps(make_doc(kinds=("plane",)))
    assert loads_scan(text).source is None
    assert loads_scan(text, source="x.json").source == "x.json"
    with pytest.raises(ScanError) as err:
        loads_scan(text.replace('"m"', '"yd"'))
    assert str(err.value) == 'units: unknown unit "yd"; use one of m, mm, cm, in, ft'


@pytest.mark.parametrize("case", BAD, ids=[case.name for case in BAD])
def test_bad_input_is_located(case, write, monkeypatch, tmp_path):
    write(case.build(make_doc()))
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScanError) as err:
        load_scan("scan.json")
    assert str(err.value) == f"scan.json: {case.message}"
    assert "\n" not in str(err.value)
    assert err.value.source == "scan.json"


def test_missing_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScanReadError) as err:
        load_scan("nope.json")
    assert str(err.value) == (
        "nope.json: file does not exist; check the path and the current directory"
    )


def test_directory(tmp_path, monkeypatch):
    (tmp_path / "d.json").mkdir()
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScanReadError) as err:
        load_scan("d.json")
    assert str(err.value) == "d.json: is a directory; give the scan's JSON file"


@pytest.mark.skipif(
    not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root can read any file"
)
def test_unreadable_file(write, tmp_path, monkeypatch):
    path = write(make_doc())
    path.chmod(0)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScanReadError) as err:
        load_scan("scan.json")
    assert str(err.value) == (
        "scan.json: cannot be read (Permission denied); check the file's permissions"
    )


def test_too_large_file_is_refused_before_reading(tmp_path, monkeypatch):
    path = tmp_path / "huge.json"
    with open(path, "wb") as handle:  # sparse: no disk used, and never read
        handle.truncate(MAX_FILE_BYTES + 1)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScanReadError) as err:
        load_scan("huge.json")
    assert str(err.value) == (
        "huge.json: is 67,108,865 bytes, too large to be a sparse scan (the limit is 64 MiB and "
        "1,000,000 points); split it into several scans"
    )


def test_too_many_points(monkeypatch):
    monkeypatch.setattr("asbuilt.scan.load.MAX_POINTS", 50)
    with pytest.raises(ScanError) as err:
        loads_scan(json.dumps(make_doc()), source="s.json")
    # K1 (30) fits, K2 (48) does not
    assert str(err.value) == (
        "s.json: objects[1] (K2): the scan holds more than 50 points, too many for a sparse "
        "scan; split it into several scans"
    )
    assert MAX_POINTS == 1_000_000


def test_not_utf8(tmp_path, monkeypatch):
    (tmp_path / "latin.json").write_bytes(b'{"name": "W\xe4nd"}')
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScanError) as err:
        load_scan("latin.json")
    assert str(err.value) == (
        "latin.json: is not UTF-8 text (byte 0xe4 at offset 11); save the scan as UTF-8 JSON"
    )


@pytest.mark.parametrize(
    "encoding, name",
    [
        ("utf-16", "UTF-16"),  # with a byte-order mark
        ("utf-16-le", "UTF-16"),  # without one: was "line 1 column 2: invalid JSON"
        ("utf-16-be", "UTF-16"),
        ("utf-32", "UTF-32"),
        ("utf-32-le", "UTF-32"),
    ],
)
def test_utf16_and_utf32_are_named(tmp_path, monkeypatch, encoding, name):
    (tmp_path / "wide.json").write_bytes('{"format": "asbuilt-scan"}'.encode(encoding))
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ScanError) as err:
        load_scan("wide.json")
    assert str(err.value) == f"wide.json: is {name} text, not UTF-8; save the scan as UTF-8 JSON"


def test_noisy_nearly_collinear_points_are_left_to_the_fit():
    """Collinearity is an exact-geometry check: 1 mm of scatter about a line passes loading."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 2, 30)[:, None]
    points = t * np.array([1.0, 0.0, 0.0]) + rng.normal(0, 0.001, (30, 3))
    doc = make_doc(kinds=("cylinder",))
    doc["objects"][0]["points"] = points.tolist()
    scan = loads_scan(json.dumps(doc))
    np.testing.assert_array_equal(scan.objects[0].points, points)


finite = st.floats(min_value=-1e4, max_value=1e4, allow_nan=False, allow_infinity=False)


TETRAHEDRON = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])


@settings(max_examples=40, deadline=None)
@given(
    base=st.lists(st.tuples(finite, finite, finite), min_size=3, max_size=40),
    units=st.sampled_from(list(METRES_PER)),
)
def test_round_trip_of_any_finite_points(base, units):
    points = np.vstack([np.array(base), TETRAHEDRON])  # the tetrahedron keeps them spread
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": units,
        "objects": [{"id": "H", "kind": "hull", "points": points.tolist()}],
    }
    scan = loads_scan(json.dumps(doc))
    np.testing.assert_allclose(scan.objects[0].points, points * METRES_PER[units], rtol=1e-15)


@settings(max_examples=40, deadline=None)
@given(
    n=st.integers(min_value=6, max_value=60),
    data=st.data(),
    bad=st.sampled_from(
        [
            ("NaN", "coordinate is NaN"),
            ("Infinity", "coordinate is infinite"),
            ('"x"', 'coordinate is a string ("x"), not a number'),
            ("null", "coordinate is null, not a number"),
            ("false", "coordinate is false, not a number"),
        ]
    ),
)
def test_the_first_bad_coordinate_is_named(n, data, bad):
    index = data.draw(st.integers(min_value=0, max_value=n - 1))
    axis = data.draw(st.integers(min_value=0, max_value=2))
    points = (
        surface_points("cylinder")[:n]
        if n <= 30
        else np.vstack([surface_points("cylinder")] * 2)[:n]
    )
    rows = [[repr(float(c)) for c in p] for p in points]
    rows[index][axis] = bad[0]
    if index + 1 < n:
        rows[index + 1][0] = "NaN"  # a later bad point must not be the one reported
    text = (
        '{"format": "asbuilt-scan", "version": 1, "units": "m", "objects": [{"id": "P", '
        '"kind": "cylinder", "points": ['
        + ", ".join("[" + ", ".join(r) + "]" for r in rows)
        + "]}]}"
    )
    with pytest.raises(ScanError) as err:
        loads_scan(text, source="f.json")
    assert str(err.value) == f"f.json: objects[0] (P).points[{index}]: {bad[1]}"


def test_unreadable_file_even_as_root(write, tmp_path, monkeypatch):
    """The read itself failing (simulated, since root may read any file) is a ScanReadError."""
    write(make_doc())
    monkeypatch.chdir(tmp_path)

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr("asbuilt.scan.load.open", refuse, raising=False)
    with pytest.raises(ScanReadError) as err:
        load_scan("scan.json")
    assert str(err.value) == (
        "scan.json: cannot be read (Permission denied); check the file's permissions"
    )


def test_loads_scan_accepts_bytes():
    doc = make_doc(kinds=("plane",))
    doc["name"] = "Süd"
    scan = loads_scan(json.dumps(doc, ensure_ascii=False).encode("utf-8"), source="b.json")
    assert scan.name == "Süd" and scan.source == "b.json"
    with pytest.raises(ScanError) as err:
        loads_scan(b'{"name": "\xff"}', source="b.json")
    assert str(err.value) == (
        "b.json: is not UTF-8 text (byte 0xff at offset 10); save the scan as UTF-8 JSON"
    )


@pytest.mark.parametrize(
    ("sensor", "message"),
    [
        (
            {"position": [10**400, 0, 0]},
            "sensor.position: must be 3 finite numbers [x, y, z] in the file's units",
        ),
        (
            {"range_sigma": 10**400},
            "sensor.range_sigma: must be a positive number (the range "
            "noise in the file's units), not 10000000000000000...",
        ),
        (
            {"range_sigma": float("nan")},
            "sensor.range_sigma: must be a positive number (the "
            "range noise in the file's units), not NaN",
        ),
        (
            "laser",
            'sensor: must be an object like {"position": [x, y, z], "range_sigma": 0.002}, '
            'not a string ("laser")',
        ),
    ],
)
def test_bad_sensor_values(sensor, message):
    doc = make_doc(kinds=("plane",))
    doc["sensor"] = sensor
    with pytest.raises(ScanError) as err:
        loads_scan(json.dumps(doc))
    assert str(err.value) == message


def test_object_station_is_read_in_metres_and_is_the_viewpoint():
    doc = make_doc("mm", kinds=("cylinder", "plane"))
    doc["sensor"] = {"position": [0.0, 0.0, 1500.0]}
    doc["objects"][1]["station"] = [4000.0, 0.0, 1600.0]
    scan = loads_scan(json.dumps(doc))
    first, second = scan.objects
    assert first.station is None
    np.testing.assert_allclose(second.station, [4.0, 0.0, 1.6])
    assert not second.station.flags.writeable
    np.testing.assert_allclose(first.viewpoint(scan.sensor), [0.0, 0.0, 1.5])
    np.testing.assert_allclose(second.viewpoint(scan.sensor), [4.0, 0.0, 1.6])
    assert "station" not in second.extra


@pytest.mark.parametrize("station", [[1, 2], [1, 2, "x"], [1, 2, float("inf")], "here"])
def test_bad_object_station(station):
    doc = make_doc(kinds=("plane",))
    doc["objects"][0]["station"] = station
    with pytest.raises(ScanError) as err:
        loads_scan(json.dumps(doc))
    assert str(err.value) == (
        "objects[0] (K1).station: must be 3 finite numbers [x, y, z] in the file's units"
    )


def test_an_empty_file_name_is_named():
    with pytest.raises(ScanReadError) as err:
        load_scan("")
    assert str(err.value) == "'': the scan file name is empty; give the scan's JSON file"


@pytest.mark.parametrize(
    "value, message",
    [
        (1e200, "a coordinate of 1e+197 m is beyond any site"),  # its square overflows a float
        (9e10, "this point lies 9e+07 m from the others' median"),  # in mm
    ],
)
def test_a_far_point_is_measured_without_overflow_warnings(recwarn, value, message):
    doc = make_doc("mm", kinds=("plane",))
    doc["objects"][0]["points"][7][0] = value
    with pytest.raises(ScanError) as err:
        loads_scan(json.dumps(doc))
    assert message in str(err.value)
    assert not recwarn.list, [str(w.message) for w in recwarn.list]


@pytest.mark.parametrize(
    ("digits", "message"),
    [
        (640, "objects[0] (K1).points[7]: coordinate is too large to be a length"),
        (641, "line 1 column {column}: a number of 641 digits is too long to be a coordinate"),
        (9000, "line 1 column {column}: a number of 9,000 digits is too long to be a coordinate"),
    ],
)
def test_overlong_integers_are_located(digits, message):
    doc = make_doc("m", kinds=("plane",))
    doc["objects"][0]["points"][7][0] = 123456.0
    text = json.dumps(doc).replace("123456.0", "-" + "9" * digits)
    with pytest.raises(ScanError) as err:
        loads_scan(text)
    column = text.index("-999") + 1  # JSON columns count from 1
    assert str(err.value).startswith(message.format(column=column)), str(err.value)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    ("units", "given", "metres"),
    [("m", 0.05, 0.05), ("mm", 50, 0.05), ("in", 2, 0.0508), ("m", None, 0.0), ("mm", 0, 0.0)],
)
def test_insulation_is_read_in_metres(units, given, metres):
    doc = make_doc(units)
    doc["objects"][0]["insulation"] = given
    scan = loads_scan(json.dumps(doc))
    assert scan.objects[0].insulation == pytest.approx(metres)
    assert "insulation" not in scan.objects[0].extra
    assert all(obj.insulation == 0.0 for obj in scan.objects[1:])


def test_zero_insulation_is_allowed_on_any_kind():
    doc = make_doc()
    for obj in doc["objects"]:
        obj["insulation"] = 0
    assert [o.insulation for o in loads_scan(json.dumps(doc)).objects] == [0.0] * 6
