"""Fit results as the ``asbuilt fit --json`` dict and as table rows, in file units."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from asbuilt.fit.output import (
    TABLE_COLUMNS,
    display_units,
    fit_report_to_dict,
    fit_table_rows,
    note_in_units,
    object_fit_to_dict,
    primitive_to_dict,
)
from asbuilt.fit.result import FitReport, FitResult, ObjectFit
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.scan.model import Scan, ScanObject

# Millimetres per unit from the definitions (the inch is exactly 25.4 mm), not from asbuilt.units.
MM_PER = {"m": 1000.0, "mm": 1.0, "cm": 10.0, "in": 25.4, "ft": 304.8}

COMMON_KEYS = [
    "rms",
    "max_residual",
    "n_points",
    "n_inliers",
    "stderr",
    "outliers",
    "method",
    "sigma",
    "sigma_source",
    "notes",
]


def result_for(primitive, stderr=None, inliers=(True, True, True, False), **extra) -> FitResult:
    return FitResult(
        primitive=primitive,
        residuals=np.array([0.001, -0.002, 0.0, 0.05]),
        inliers=np.array(inliers),
        stderr=stderr or {},
        sigma=0.002,
        sigma_source="sensor",
        method="test method (Author 1999)",
        **extra,
    )


PIPE = Cylinder(center=(1.0, 2.0, 3.0), axis=(0.0, 0.0, 1.0), radius=0.05715, length=2.0)
BOX = Cuboid(center=(5.0, 5.0, 0.5), axes=np.eye(3), size=(1.2, 0.8, 12.5))
BALL = Sphere(center=(0.0, 0.254, 0.0), radius=0.3048)
WALL = Plane(
    point=(0.0, 0.0, 2.5),
    normal=(0.0, 0.0, 1.0),
    outline=[[0, 0, 2.5], [2, 0, 2.5], [2, 1.5, 2.5], [0, 1.5, 2.5]],
)
ROCK = Hull(
    vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
    faces=[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
)


def report_of(*items: tuple[str, str, FitResult], units: str = "m") -> FitReport:
    fits = []
    for index, (object_id, requested, result) in enumerate(items):
        obj = ScanObject(id=object_id, kind=requested, points=np.zeros((4, 3)), index=index)
        fits.append(ObjectFit(object=obj, result=result, requested=requested))
    scan = Scan(units=units, objects=tuple(f.object for f in fits))
    return FitReport(scan=scan, fits=tuple(fits))


def test_cylinder_in_millimetres():
    stderr = {"radius": 0.0003, "axis_deg": 0.4, "center": (0.0002, 0.0004), "length": 0.01}
    item = report_of(("P1", "cylinder", result_for(PIPE, stderr))).fits[0]
    out = object_fit_to_dict(item, "mm")
    assert list(out) == ["id", "kind", "center", "axis", "radius", "length", *COMMON_KEYS]
    assert out["id"] == "P1" and out["kind"] == "cylinder"
    assert out["center"] == pytest.approx([1000.0, 2000.0, 3000.0])
    assert out["axis"] == [0.0, 0.0, 1.0]
    assert out["radius"] == pytest.approx(57.15) and out["length"] == pytest.approx(2000.0)
    assert out["rms"] == pytest.approx(math.sqrt((1.0 + 4.0 + 0.0) / 3))  # inliers only
    assert out["max_residual"] == pytest.approx(2.0)
    assert (out["n_points"], out["n_inliers"], out["outliers"]) == (4, 3, [3])
    assert list(out["stderr"]) == ["radius", "axis_deg", "center", "length"]
    assert out["stderr"]["radius"] == pytest.approx(0.3)
    assert out["stderr"]["axis_deg"] == 0.4
    assert out["stderr"]["center"] == pytest.approx([0.2, 0.4])
    assert out["stderr"]["length"] == pytest.approx(10.0)
    assert out["sigma"] == pytest.approx(2.0) and out["sigma_source"] == "sensor"
    assert out["method"] == "test method (Author 1999)" and out["notes"] == []


@pytest.mark.parametrize("units", list(MM_PER))
def test_every_length_is_converted_and_angles_are_not(units):
    stderr = {"radius": 0.001, "axis_deg": 0.5}
    out = object_fit_to_dict(report_of(("P", "cylinder", result_for(PIPE, stderr))).fits[0], units)
    scale = 1000.0 / MM_PER[units]  # file units per metre
    assert out["radius"] == pytest.approx(0.05715 * scale, rel=1e-12)
    assert out["center"] == pytest.approx([1.0 * scale, 2.0 * scale, 3.0 * scale], rel=1e-12)
    assert out["stderr"]["radius"] == pytest.approx(0.001 * scale, rel=1e-12)
    assert out["stderr"]["axis_deg"] == 0.5
    assert out["sigma"] == pytest.approx(0.002 * scale, rel=1e-12)


def test_inch_values_from_the_definition():
    out = object_fit_to_dict(report_of(("S", "sphere", result_for(BALL))).fits[0], "in")
    assert out["radius"] == pytest.approx(12.0) and out["center"] == pytest.approx([0, 10.0, 0])
    assert list(out) == ["id", "kind", "center", "radius", *COMMON_KEYS]


def test_cuboid_plane_hull_shapes():
    report = report_of(
        (
            "C1",
            "cuboid",
            result_for(
                BOX, {"size": (0.001, 0.002, 0.004), "axes_deg": 0.3}, observed=(True, True, False)
            ),
        ),
        ("W1", "plane", result_for(WALL, {"normal_deg": 0.1, "offset": 0.0005})),
        ("H1", "hull", result_for(ROCK)),
        units="cm",
    )
    box, wall, rock = fit_report_to_dict(report)["objects"]
    assert list(box) == ["id", "kind", "center", "axes", "size", "observed", *COMMON_KEYS]
    assert box["axes"] == np.eye(3).tolist()
    assert box["size"] == pytest.approx([120, 80, 1250])
    assert box["observed"] == [True, True, False]
    assert box["stderr"]["size"] == pytest.approx([0.1, 0.2, 0.4])
    assert box["stderr"]["axes_deg"] == 0.3
    assert list(wall) == ["id", "kind", "normal", "point", "outline", *COMMON_KEYS]
    np.testing.assert_allclose(wall["outline"], WALL.outline * 100)
    assert wall["stderr"] == pytest.approx({"normal_deg": 0.1, "offset": 0.05})
    assert list(rock) == ["id", "kind", "vertices", "faces", *COMMON_KEYS]
    assert rock["faces"] == ROCK.faces.tolist() and all(
        type(i) is int for face in rock["faces"] for i in face
    )
    np.testing.assert_allclose(rock["vertices"], ROCK.vertices * 100)


def test_auto_names_the_chosen_kind_and_why():
    result = result_for(PIPE, notes=("cylinder RMS 0.4 mm vs cuboid 3.1 mm",))
    out = object_fit_to_dict(report_of(("X1", "auto", result)).fits[0], "m")
    assert list(out)[:3] == ["id", "kind", "chosen"]
    assert (out["kind"], out["chosen"]) == ("auto", "cylinder")
    assert out["radius"] == pytest.approx(0.05715)
    assert out["notes"] == ["cylinder RMS 0.4 mm vs cuboid 3.1 mm"]


def test_report_defaults_to_the_scan_units_and_is_strict_json():
    result = result_for(BALL, inliers=(False, False, False, False))  # RMS of nothing is NaN
    report = report_of(("S1", "sphere", result), units="ft")
    out = fit_report_to_dict(report)
    assert out["units"] == "ft" and len(out["objects"]) == 1
    assert out["objects"][0]["rms"] is None and out["objects"][0]["outliers"] == [0, 1, 2, 3]
    assert json.loads(json.dumps(out, allow_nan=False)) == out
    assert fit_report_to_dict(report, "mm")["objects"][0]["radius"] == pytest.approx(304.8)


def test_unknown_output_unit():
    with pytest.raises(ValueError, match="unknown unit 'yd'; use one of m, mm, cm, in, ft"):
        fit_report_to_dict(report_of(("S1", "sphere", result_for(BALL))), "yd")


def test_primitive_to_dict_rejects_other_objects():
    with pytest.raises(TypeError):
        primitive_to_dict(object())


@pytest.mark.parametrize(
    ("units", "expected"),
    [
        ("m", ("mm", "m")),
        ("mm", ("mm", "m")),
        ("cm", ("mm", "m")),
        ("in", ("in", "ft")),
        ("ft", ("in", "ft")),
    ],
)
def test_display_units(units, expected):
    assert display_units(units) == expected


def test_table_rows_metric():
    stderr = {"radius": 0.0003, "axis_deg": 0.4}
    report = report_of(
        ("P1", "cylinder", result_for(PIPE, stderr)),
        ("C1", "cuboid", result_for(BOX, {}, observed=(True, True, False))),
        ("X1", "auto", result_for(BALL)),
        ("W1", "plane", result_for(WALL)),
        ("H1", "hull", result_for(ROCK)),
        units="mm",
    )
    rows = fit_table_rows(report)
    assert all(len(row) == len(TABLE_COLUMNS) for row in rows)
    pipe, box, ball, wall, rock = rows
    assert pipe == (
        "P1",
        "cylinder",
        "r 57.1 mm, L 2.000 m",
        "(1.000, 2.000, 3.000) m",
        "1.3 mm",
        "3/4",
        "radius ±0.3 mm, axis ±0.40°",
    )
    # a box with a side of 10 m or more is shown in metres; the unseen depth is estimated
    assert box[2] == "1.200 × 0.800 × ≈12.500 m"
    assert ball[1] == "auto→sphere" and ball[2] == "r 304.8 mm"
    assert wall[2] == "n (0.00, 0.00, 1.00), 3.00 m²" and wall[3] == "(0.000, 0.000, 2.500) m"
    assert rock[2] == "4 vertices, 4 faces" and rock[3] == "(0.250, 0.250, 0.250) m"


def test_table_rows_imperial():
    report = report_of(("S1", "sphere", result_for(BALL, {"radius": 0.000254})), units="ft")
    (row,) = fit_table_rows(report)
    assert row[2] == "r 12.00 in" and row[3] == "(0.000, 0.833, 0.000) ft"
    assert row[6] == "radius ±0.01 in"
    (row,) = fit_table_rows(report, "mm")
    assert row[2] == "r 304.8 mm"


@pytest.mark.parametrize(
    "note, units, expected",
    [
        ("2 outlier point(s) rejected (beyond 3 x 2 mm).", "in", "beyond 3 x 0.0787 in)"),
        ("best fit r 1.339e+04 m, a median 0.2 m away", "ft", "r 4.39e+04 ft, a median 7.87 in"),
        ("beyond 3 x 2 mm", "mm", "beyond 3 x 2 mm"),
        ("beyond 3 x 2 mm", "m", "beyond 3 x 2 mm"),
        ("3 of 9 shots, 5 mm2", "in", "3 of 9 shots, 5 mm2"),
    ],
)
def test_notes_give_lengths_in_inches_and_feet_for_imperial_output(note, units, expected):
    # The fits write their notes in mm and m; a scan in inches or feet shows its table, and
    # its notes, in inches and feet (2 mm = 0.0787 in; 13.39 km = 43,930 ft).
    assert expected in note_in_units(note, units)


@pytest.mark.parametrize(
    ("thickness", "expected"),
    [
        (
            0.02,
            "fitted on its insulation: the cladding's radius; with 20 mm of insulation the pipe "
            "inside has radius 37.2 mm (OD 74.3 mm), which merging snaps",
        ),
        (
            0.06,
            "fitted on its insulation: the cladding's radius; with 60 mm of insulation no "
            "pipe is left inside, so model, check and report leave it out (fit-refused): check "
            "the thickness and the file's units",
        ),
    ],
)
def test_an_insulated_cylinder_notes_the_pipe_inside(thickness, expected):
    from asbuilt.fit.output import fit_table_notes

    report = report_of(("P1", "cylinder", result_for(PIPE)), ("B1", "cuboid", result_for(BOX)))
    objects = (
        dataclasses.replace(report.scan.objects[0], insulation=thickness),
        report.scan.objects[1],
    )
    scan = dataclasses.replace(report.scan, objects=objects)
    fits = tuple(dataclasses.replace(item, object=obj) for item, obj in zip(report.fits, objects))
    notes = fit_table_notes(FitReport(scan=scan, fits=fits))
    assert notes == [("P1", expected)]
    # the JSON keeps what was measured: the cladding
    assert fit_report_to_dict(FitReport(scan=scan, fits=fits))["objects"][0]["radius"] == 0.05715
