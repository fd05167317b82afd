"""A report made from an ``asbuilt-model`` document shows what the report made from its scan
shows, per-point data included: the rejected shots' crosses in the pictures, the residual
histograms and the JSON report's ``residuals`` and ``inlier_mask``.

The reference is the report of the scan-built model; the planted-outlier test knows its answer
from how the scan was made (which shot was moved, and by how much)."""

from __future__ import annotations

import datetime as dt
import json

import numpy as np
import pytest
from report_helpers import ROOT

from asbuilt.export.model_json import load_model, write_model_json
from asbuilt.pipeline import build_model
from asbuilt.report import write_reports
from asbuilt.report.data import report_data
from asbuilt.report.figures import _points
from asbuilt.scan import load_scan

#: One fixed time stamp, so that two reports of one model are byte for byte comparable.
STAMP = dt.datetime(2025, 1, 2, 3, 4, 5, tzinfo=dt.timezone.utc)


def _reports(model, folder, stem) -> tuple[str, dict]:
    html, js = folder / f"{stem}.html", folder / f"{stem}.json"
    write_reports(model, [html, js], generated=STAMP)
    return html.read_text(encoding="utf-8"), json.loads(js.read_text(encoding="utf-8"))


@pytest.mark.parametrize("name", ["spool", "plant", "structural-bay"])
def test_report_from_the_document_equals_the_report_from_the_scan(tmp_path, name):
    scan_model = build_model(load_scan(ROOT / "samples" / f"{name}.json"))
    write_model_json(scan_model, tmp_path / "model.json")
    doc_model = load_model(tmp_path / "model.json")
    scan_html, scan_json = _reports(scan_model, tmp_path, "from-scan")
    doc_html, doc_json = _reports(doc_model, tmp_path, "from-document")

    quality = doc_json["quality"]
    # every sample has shots its fits rejected (spool P5, plant C2/C3/B2/CH1, bay B2)
    assert any(not flag for q in quality for flag in q["inlier_mask"])
    for q in quality:
        assert len(q["residuals"]) == len(q["inlier_mask"]) == q["points"] > 0
        assert sum(q["inlier_mask"]) == q["inliers"]
    # one histogram per fitted object, none of the old "not stored" notes
    assert doc_html.count('<svg class="hist"') == len(quality)
    assert "not stored in the model file" not in doc_html
    # the same page and JSON, crosses for rejected shots and histograms included
    assert doc_json == scan_json
    assert doc_html == scan_html


def _outlier_scan(path, moved: int, offset: float):
    """A scan of one NPS 4 pipe (OD 114.3 mm, ASME B36.10M) seen from one side: 8 rings of
    5 shots over 120 deg, 0.5 mm range noise, shot ``moved`` pushed ``offset`` metres out
    along its surface normal (a shot that hit something behind the pipe)."""
    rng = np.random.default_rng(4)
    radius, axis_at = 0.1143 / 2, np.array([0.0, 2.0, 1.0])
    shots = [
        [x, 2.0 - radius * np.cos(a), 1.0 + radius * np.sin(a)]
        for x in np.linspace(0.2, 1.8, 8)
        for a in np.radians(np.linspace(-60.0, 60.0, 5))
    ]
    points = np.array(shots)
    normals = points - axis_at
    normals[:, 0] = 0.0
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    points += normals * rng.normal(0.0, 0.0005, len(points))[:, None]
    points[moved] += normals[moved] * offset
    scan = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "name": "one pipe, one stray shot",
        "sensor": {"position": [1.0, 0.0, 1.0], "range_sigma": 0.0005},
        "objects": [{"id": "P1", "kind": "cylinder", "points": points.round(6).tolist()}],
    }
    path.write_text(json.dumps(scan), encoding="utf-8")
    return points


def test_planted_outlier_is_the_rejected_shot_in_the_documents_report(tmp_path):
    moved, offset = 17, 0.030
    points = _outlier_scan(tmp_path / "scan.json", moved, offset)
    scan_model = build_model(load_scan(tmp_path / "scan.json"))
    write_model_json(scan_model, tmp_path / "model.json")
    doc_model = load_model(tmp_path / "model.json")

    (row,) = report_data(doc_model).quality
    assert row.residuals.shape == (40,) and row.inlier_mask.shape == (40,)
    assert np.flatnonzero(~row.inlier_mask).tolist() == [moved]
    # signed: the shot lies 30 mm outside the surface (the fit moves by a fraction of the noise)
    assert row.residuals[moved] == pytest.approx(offset, abs=0.002)
    assert np.max(np.abs(np.delete(row.residuals, moved))) < 0.003
    # the plan view draws that shot, and only it, as a cross, as the scan's report does
    keep, drop = _points(doc_model, (0, 1))
    np.testing.assert_allclose(drop, points[[moved]][:, :2], atol=1e-6)
    assert len(keep) == 39
    for a, b in zip(_points(scan_model, (0, 1)), (keep, drop)):
        np.testing.assert_array_equal(a, b)


def _pipe_fit(object_id, start, end, od, index, rejected=()):
    """A scan object of 20 shots along a segment and its cylinder fit, residuals
    0.1 mm x (shot number + 1) (so that every shot's residual is told apart), the shots in
    ``rejected`` 50 mm out and not inliers."""
    from asbuilt.fit.result import FitResult, ObjectFit
    from asbuilt.primitives import Cylinder
    from asbuilt.scan.model import ScanObject

    start, end = np.asarray(start, float), np.asarray(end, float)
    length = float(np.linalg.norm(end - start))
    cylinder = Cylinder((start + end) / 2, (end - start) / length, od / 2, length)
    points = start + np.linspace(0.05, 0.95, 20)[:, None] * (end - start)
    residuals = 0.0001 * np.arange(1, 21)
    inliers = np.ones(20, bool)
    inliers[list(rejected)] = False
    residuals[list(rejected)] = 0.05
    fit = FitResult(
        primitive=cylinder,
        residuals=residuals,
        inliers=inliers,
        stderr={"radius": 0.0005, "axis_deg": 0.2, "center": 0.001, "length": 0.01},
        sigma=0.002,
        sigma_source="sensor",
        method="synthetic",
    )
    obj = ScanObject(id=object_id, kind="cylinder", points=points, index=index)
    return ObjectFit(obj, fit, "cylinder")


def test_pieces_of_a_pipe_cut_at_a_tee_keep_their_fits_points(tmp_path):
    """Merging cuts P1 at the tee into pieces that share P1's fit: each piece's fit quality and
    the pictures' crosses follow P1's points, P3's follow P3's, from the document as from
    the scan."""
    from asbuilt.fit.result import FitReport
    from asbuilt.merge import merge_model
    from asbuilt.scan.model import Scan

    # NPS 4 (OD 114.3 mm) run with a branch at its middle
    fits = (
        _pipe_fit("P1", (0, 0, 0), (4, 0, 0), 0.1143, 0, rejected=(3, 15)),
        _pipe_fit("P3", (2, 0.15, 0), (2, 2, 0), 0.1143, 1, rejected=(7,)),
    )
    scan = Scan(units="m", objects=tuple(f.object for f in fits), name="tee")
    model = merge_model(FitReport(scan=scan, fits=fits))
    write_model_json(model, tmp_path / "model.json")
    again = load_model(tmp_path / "model.json")

    by_source = {"P1": fits[0].result, "P3": fits[1].result}
    rows = report_data(again).quality
    pieces = [c for c in again.components if c.sources == ("P1",)]
    assert len(pieces) == 2 and pieces[0].fit is pieces[1].fit
    assert sorted(q.id for q in rows) == sorted(q.id for q in report_data(model).quality)
    for comp in again.components:
        if comp.fit is None:
            continue
        (row,) = [q for q in rows if q.id == comp.id]
        truth = by_source[comp.sources[0]]
        np.testing.assert_array_equal(row.residuals, truth.residuals)
        np.testing.assert_array_equal(row.inlier_mask, truth.inliers)
    # crosses: P1's shots 3 and 15 and P3's shot 7, as from the scan-built model
    expected = np.vstack([fits[0].object.points[[3, 15]], fits[1].object.points[[7]]])
    for view in ((0, 1), (0, 2)):
        keep, drop = _points(again, view)
        np.testing.assert_array_equal(drop, expected[:, list(view)])
        assert len(keep) == 37
        for a, b in zip(_points(model, view), (keep, drop)):
            np.testing.assert_array_equal(a, b)


def test_old_document_reports_without_per_point_data(tmp_path):
    """A document written before the per-point data was stored still reports: every point
    alike, no histogram (the cell says so), empty ``residuals`` and ``inlier_mask``."""
    scan_model = build_model(load_scan(ROOT / "samples" / "spool.json"))
    write_model_json(scan_model, tmp_path / "model.json")
    document = json.loads((tmp_path / "model.json").read_text(encoding="utf-8"))
    for entry in document["components"]:
        if entry["fitted"] is not None:
            del entry["fitted"]["residuals"], entry["fitted"]["inlier_mask"]
    (tmp_path / "old.json").write_text(json.dumps(document), encoding="utf-8")
    old = load_model(tmp_path / "old.json")

    data = report_data(old)
    assert all(q.residuals.shape == (0,) and q.inlier_mask.shape == (0,) for q in data.quality)
    keep, drop = _points(old, (0, 1))
    assert len(drop) == 0 and len(keep) == sum(len(o.points) for o in old.scan.objects)
    html = tmp_path / "old.html"
    js = tmp_path / "old.json.report.json"
    write_reports(old, [html], generated=STAMP)
    write_reports(old, [js], generated=STAMP)
    page = html.read_text(encoding="utf-8")
    assert page.count("not stored in the model file") == len(data.quality)
    assert '<svg class="hist"' not in page
    quality = json.loads(js.read_text(encoding="utf-8"))["quality"]
    assert all(q["residuals"] == [] and q["inlier_mask"] == [] for q in quality)
