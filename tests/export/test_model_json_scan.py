"""The scan a model document was made from travels in it: ``check`` and ``report`` on the
document see the sensor's range sigma, the operator's links and size hints and the measured
points as they see them on the scan (the scan-built model is the reference)."""

from __future__ import annotations

import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from asbuilt.export.model_json import (
    ModelDocumentError,
    dumps_model,
    model_from_document,
    model_schema,
)
from asbuilt.pipeline import build_model
from asbuilt.rules import check_model
from asbuilt.scan import loads_scan

ROOT = Path(__file__).resolve().parents[2]

#: ASME B36.10M outside diameters (docs: /work/shared/reference/standards.md), metres.
OD_NPS4 = 0.1143
OD_NPS6 = 0.1683


def _pipe_points(start, end, od: float, wobble: float = 0.0) -> list:
    """8 x 5 shots on the side of a pipe facing -y (a sensor at y < 0), in metres, each
    ``wobble`` metres off the surface, in and out alternately (so the residual RMS about the
    true pipe is exactly ``wobble``)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = (end - start) / np.linalg.norm(end - start)
    across = np.cross(axis, [0.0, 0.0, 1.0])
    if np.linalg.norm(across) < 1e-9:
        across = np.cross(axis, [1.0, 0.0, 0.0])
    across /= np.linalg.norm(across)
    up = np.cross(axis, across)
    points = []
    for i, t in enumerate(np.linspace(0.05, 0.95, 8)):
        for j, angle in enumerate(np.radians(np.linspace(-70.0, 70.0, 5))):
            radial = np.cos(angle) * across + np.sin(angle) * up
            off = wobble if (i + j) % 2 == 0 else -wobble
            points.append(start + t * (end - start) + (od / 2 + off) * radial)
    return np.round(points, 6).tolist()


def _scan(objects, links=(), sensor=None, **extra):
    document = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "name": "document test",
        "sensor": sensor or {"position": [1.0, -3.0, 1.0]},
        "objects": objects,
        "links": [list(link) for link in links],
        **extra,
    }
    return loads_scan(json.dumps(document), source="t.json")


def _document(model) -> dict:
    return json.loads(dumps_model(model))


def _findings(model, **options):
    return [
        (f.code, f.slug, f.objects, f.message, f.measured, f.stderr)
        for f in check_model(model, **options)
    ]


def _slugs(model) -> list:
    """The slugs of ``model``'s findings but AB407: P2's synthetic shots (:func:`_crossing_pipes`)
    lie on its sides facing +-x, which the station at y < 0 looks at end-on, so its fit ignores
    the station and says so, as it should; not what these tests are about."""
    return [f[1] for f in _findings(model) if f[1] != "viewpoint-ignored"]


def _crossing_pipes(links):
    """Two NPS 4 pipes crossing at (1, 0, 1), linked by the operator or not."""
    return _scan(
        [
            {"id": "P1", "kind": "cylinder", "points": _pipe_points((0, 0, 1), (2, 0, 1), OD_NPS4)},
            {
                "id": "P2",
                "kind": "cylinder",
                "points": _pipe_points((1, -1, 1), (1, 1, 1), OD_NPS4),
            },
        ],
        links=links,
    )


@pytest.mark.parametrize("merge", [False, True])
def test_links_reach_the_rules_from_the_document(merge):
    # The operator links P1 and P2 (joined, e.g. through a penetration): no clash on the scan.
    model = build_model(_crossing_pipes([("P1", "P2")]), merge=merge)
    assert "clash" not in [f[1] for f in _findings(model)]
    again = model_from_document(_document(model))
    assert _findings(again) == _findings(model)
    # the link is what decides it: the same scan unlinked clashes
    unlinked = build_model(_crossing_pipes([]), merge=merge)
    assert _slugs(unlinked) == ["clash"]


def test_sensor_sigma_reaches_poor_fit_from_the_document():
    # Shots 3.5 mm in and out of an NPS 6 pipe, a sensor of sigma 1 mm: the fit takes the
    # residuals' own noise level (3.5 mm is 1.5-5 sigmas) and poor-fit judges the RMS against
    # the sensor: 3.5 mm / 1 mm = 3.5 sigmas > 2 allowed.
    scan = _scan(
        [
            {
                "id": "T1",
                "kind": "cylinder",
                "points": _pipe_points((0, 0, 1), (2, 0, 1), OD_NPS6, wobble=0.0035),
            }
        ],
        sensor={"position": [1.0, -3.0, 1.0], "range_sigma": 0.001},
    )
    model = build_model(scan)
    assert model.components[0].fit.sigma_source == "residuals"
    (poor,) = [f for f in check_model(model) if f.slug == "poor-fit"]
    assert poor.measured == pytest.approx(3.5, abs=0.3)
    again = model_from_document(_document(model))
    assert _findings(again) == _findings(model)


def test_size_hint_reaches_the_rules_from_the_document():
    # An unmerged model checked against a catalog: the operator's hint NPS 4 (OD 114.3 mm)
    # disagrees with the fitted OD 168.3 mm (NPS 6) by 54 mm.
    points = _pipe_points((0, 0, 1), (2, 0, 1), OD_NPS6)
    scan = _scan([{"id": "P1", "kind": "cylinder", "nominal": "4", "points": points}])
    model = build_model(scan, merge=False, catalog="asme-b36.10m")
    expected = _findings(model, catalog="asme-b36.10m")
    (hint,) = [f for f in expected if f[1] == "hint-mismatch"]
    assert "114.3 mm" in hint[3] and "168.3 mm" in hint[3]
    again = model_from_document(_document(model))
    assert _findings(again, catalog="asme-b36.10m") == expected


def test_check_fix_round_trip_keeps_the_links(tmp_path, capsys):
    # asbuilt check SCAN --fix DOC, then asbuilt check DOC: the same findings as the scan's
    # (before, the document lost the link and P1/P2 clashed).
    from asbuilt.cli import main

    scan_path = tmp_path / "scan.json"
    scan = _crossing_pipes([("P1", "P2")])
    scan_path.write_text(json.dumps(_scan_file(scan)), encoding="utf-8")
    fixed = tmp_path / "fixed.json"
    assert main(["check", str(scan_path), "--fix", str(fixed), "--format", "json"]) == 0
    from_scan = json.loads(capsys.readouterr().out)
    assert main(["check", str(fixed), "--format", "json"]) == 0
    assert json.loads(capsys.readouterr().out) == from_scan
    assert json.loads(fixed.read_text(encoding="utf-8"))["scan"]["links"] == [["P1", "P2"]]


def _scan_file(scan) -> dict:
    """The asbuilt-scan document (metres) of an in-memory scan."""
    return {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"position": scan.sensor.position.tolist()},
        "objects": [
            {"id": o.id, "kind": o.kind, "points": o.points.tolist()} for o in scan.objects
        ],
        "links": [list(link) for link in scan.links],
    }


def test_the_scan_round_trips_whole():
    # A scan in millimetres with every field: stored in metres, read back equal.
    points = (np.array(_pipe_points((0, 0, 1), (2, 0, 1), OD_NPS4)) * 1000).round(3)
    pan_tilt_range = [[10.0 + i, -5.0 + 0.5 * i, 3000.0 + i] for i in range(len(points))]
    raw = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "mm",
        "name": "bay 3",
        "sensor": {"position": [1000.0, -3000.0, 1000.0], "range_sigma": 2.0},
        "objects": [
            {
                "id": "P1",
                "kind": "cylinder",
                "points": points.tolist(),
                "group": "SP-1",
                "label": "north run",
                "nominal": '4"',
                "measurements": pan_tilt_range,
                "station": [1000.0, -2500.0, 1000.0],
                "tag": {"asset": 17},
            },
            {
                "id": "P2",
                "kind": "auto",
                "points": (points + [0, 0, 500.0]).tolist(),
            },
        ],
        "links": [["P1", "P2"]],
        "date": "2024-05-02",
    }
    scan = loads_scan(json.dumps(raw), source="bay3.json")
    model = build_model(scan, merge=False, check=False)
    document = _document(model)
    assert document["source"] == "bay3.json" and document["scan"]["units"] == "m"
    back = model_from_document(document).scan
    assert (back.name, back.links, back.source, dict(back.extra)) == (
        "bay 3",
        (("P1", "P2"),),
        "bay3.json",
        {"date": "2024-05-02"},
    )
    assert back.sensor.range_sigma == pytest.approx(0.002, rel=1e-12)
    np.testing.assert_allclose(back.sensor.position, [1.0, -3.0, 1.0], rtol=1e-12)
    for before, after in zip(scan.objects, back.objects, strict=True):
        assert (after.id, after.kind, after.group, after.label, after.nominal) == (
            before.id,
            before.kind,
            before.group,
            before.label,
            before.nominal,
        )
        np.testing.assert_array_equal(after.points, before.points)
        assert dict(after.extra) == dict(before.extra)
    p1 = back.objects[0]
    np.testing.assert_allclose(p1.station, [1.0, -2.5, 1.0], rtol=1e-12)
    np.testing.assert_allclose(p1.measurements, scan.objects[0].measurements, rtol=1e-12)
    np.testing.assert_allclose(np.degrees(p1.measurements[0, :2]), [10.0, -5.0], rtol=1e-12)
    assert p1.measurements[0, 2] == pytest.approx(3.0, rel=1e-12)  # 3000 mm
    assert back.objects[1].measurements is None and back.objects[1].station is None
    # written again, the same bytes
    assert dumps_model(model_from_document(document)) == dumps_model(
        model_from_document(json.loads(dumps_model(model_from_document(document))))
    )


@pytest.mark.parametrize("name", ["plant", "spool", "structural-bay"])
def test_report_from_the_document_counts_what_the_scan_holds(name):
    from asbuilt.report.data import report_data
    from asbuilt.scan import load_scan

    scan = load_scan(ROOT / "samples" / f"{name}.json")
    model = build_model(scan)
    document = _document(model)
    jsonschema.Draft202012Validator(model_schema()).validate(document)
    again = model_from_document(document)
    # the sample's own counts, read from the scan file independently of asbuilt
    raw = json.loads((ROOT / "samples" / f"{name}.json").read_text(encoding="utf-8"))
    objects, points = len(raw["objects"]), sum(len(o["points"]) for o in raw["objects"])
    for data in (report_data(model), report_data(again)):
        assert (data.counts["objects"], data.counts["points"]) == (objects, points)
    assert _findings(again) == _findings(model)


def test_older_documents_load_as_before():
    # A document written before the scan section: no scan, so no links (the old behaviour).
    model = build_model(_crossing_pipes([("P1", "P2")]), merge=False)
    document = _document(model)
    for old in ({k: v for k, v in document.items() if k != "scan"}, {**document, "scan": None}):
        again = model_from_document(old)
        assert again.scan is None
        assert _slugs(again) == ["clash"]


@pytest.mark.parametrize(
    ("section", "where"),
    [
        ([1, 2], "scan: must be an asbuilt-scan object or null"),
        ({"units": "mm"}, 'scan.units: must be "m", not "mm"'),
        ({"objects": [{"id": "P1", "kind": "cylinder"}]}, "scan.objects[0] (P1).points: missing"),
        (
            {"objects": [{"id": "P1", "kind": "cylinder", "points": [[0, 0, "x"]]}]},
            "scan.objects[0] (P1).points: must be a list of points",
        ),
        (
            {"links": [["P1", "P9"]]},
            'scan.links[0]: must be a pair of ids listed in objects, not ["P1", "P9"]',
        ),
        ({"sensor": {"range_sigma": -1}}, "scan.sensor.range_sigma: must be a positive number"),
    ],
)
def test_bad_scan_sections_are_located(section, where):
    model = build_model(_crossing_pipes([("P1", "P2")]), merge=False, check=False)
    document = _document(model)
    document["scan"] = section if not isinstance(section, dict) else {**document["scan"], **section}
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith(f"m.json: {where}")
    assert "\n" not in str(info.value)


def test_an_unmerged_model_names_the_catalog_it_was_checked_with():
    # `asbuilt model SCAN --no-merge --catalog en-10220`: the document names the catalog, so
    # `asbuilt check` on it judges sizes as on the scan (before: catalog null, no size rule ran).
    # standards.md: OD 76.1 mm is EN 10220 DN 65 (ASME NPS 2 1/2 is 73.0); 108.0 mm is no
    # size in either (nearest DN 100 / NPS 4, 114.3 mm, 6.3 mm off).
    scan = _scan(
        [
            {"id": "P1", "kind": "cylinder", "points": _pipe_points((0, 0, 1), (2, 0, 1), 0.0761)},
            {"id": "P2", "kind": "cylinder", "points": _pipe_points((0, 2, 1), (2, 2, 1), 0.1080)},
        ]
    )
    model = build_model(scan, merge=False, catalog="en-10220")
    document = _document(model)
    assert document["catalog"] == "en-10220"
    again = model_from_document(document)
    sizes = [f for f in check_model(again) if f.slug == "nonstandard-diameter"]
    assert [f.objects for f in sizes] == [("P2",)]
    assert "EN 10220" in sizes[0].message and "114.3 mm, 6.3 mm off" in sizes[0].message
    assert _findings(again) == _findings(model, catalog="en-10220")
