"""Fits read back from a model document: the rules and the report judge a document as they
judge the scan it was made from (the scan-built model is the reference)."""

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
from asbuilt.export.stored_fit import StoredFit
from asbuilt.pipeline import build_model
from asbuilt.rules import check_model
from asbuilt.scan import load_scan

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def built():
    """Sample name -> (model built from the scan, its document as read from JSON text)."""
    out = {}
    for name in ("structural-bay", "plant", "spool"):
        model = build_model(load_scan(ROOT / "samples" / f"{name}.json"))
        out[name] = (model, json.loads(dumps_model(model)))
    return out


def _findings(model):
    return [
        (f.code, f.severity, f.objects, f.message, f.unverifiable, f.measured, f.stderr)
        for f in check_model(model)
    ]


@pytest.mark.parametrize("name", ["structural-bay", "plant", "spool"])
def test_check_from_the_document_equals_check_from_the_scan(built, name):
    model, document = built[name]
    assert _findings(model_from_document(document)) == _findings(model)


def test_unverifiable_plumb_stays_unverifiable(built):
    # The scan's own check (README, docs/rules.md): C4 leans 12.8 mm, known to +- 2.9 mm, so it
    # "cannot verify" (a warning), not an error; without the fit's stderr it became an error.
    findings = check_model(model_from_document(built["structural-bay"][1]))
    (plumb,) = [f for f in findings if f.slug == "out-of-plumb"]
    assert plumb.objects == ("C4",) and plumb.severity == "warning" and plumb.unverifiable


def test_restored_fit_carries_what_the_fit_had(built):
    model, document = built["structural-bay"]
    again = model_from_document(document)
    for before, after in zip(model.components, again.components):
        fit, stored = before.fit, after.fit
        assert isinstance(stored, StoredFit) and stored.kind == fit.kind
        assert (stored.n_points, stored.n_inliers) == (fit.n_points, fit.n_inliers)
        assert (stored.rms, stored.max_residual, stored.sigma) == (
            fit.rms,
            fit.max_residual,
            fit.sigma,
        )
        assert stored.sigma_source == fit.sigma_source and stored.notes == fit.notes
        assert stored.observed == fit.observed and stored.method == fit.method
        for key, value in fit.stderr.items():
            np.testing.assert_array_equal(np.asarray(stored.stderr[key]), np.asarray(value))
        # the fit's own primitive, not the (possibly regularised) component geometry
        np.testing.assert_allclose(stored.primitive.center, fit.primitive.center, atol=1e-12)
        np.testing.assert_allclose(stored.primitive.size, fit.primitive.size, atol=1e-12)
        # per-point data, one per given point in the object's point order, bit for bit
        assert stored.residuals.dtype == np.float64 and stored.inliers.dtype == bool
        np.testing.assert_array_equal(stored.residuals, fit.residuals)
        np.testing.assert_array_equal(stored.inliers, fit.inliers)


def _pipe(object_id: str, start, end, od: float, index: int):
    """A scan object and a cylinder fit of it (20 points, residuals 1 mm) from a segment."""
    from asbuilt.fit.result import FitResult, ObjectFit
    from asbuilt.primitives import Cylinder
    from asbuilt.scan.model import ScanObject

    start, end = np.asarray(start, float), np.asarray(end, float)
    length = float(np.linalg.norm(end - start))
    cylinder = Cylinder((start + end) / 2, (end - start) / length, od / 2, length)
    fit = FitResult(
        primitive=cylinder,
        residuals=np.full(20, 0.001),
        inliers=np.ones(20, bool),
        stderr={"radius": 0.0005, "axis_deg": 0.2, "center": 0.001, "length": 0.01},
        sigma=0.002,
        sigma_source="sensor",
        method="synthetic",
    )
    obj = ScanObject(id=object_id, kind="cylinder", points=np.zeros((20, 3)), index=index)
    return ObjectFit(obj, fit, "cylinder")


def test_pieces_of_one_fit_share_one_restored_fit():
    from asbuilt.fit.result import FitReport
    from asbuilt.merge import merge_model
    from asbuilt.rules.alignment import _one_per_fit
    from asbuilt.scan.model import Scan

    # NPS 4 (OD 114.3 mm) run with a branch at its middle: merging cuts P1 at the tee
    fits = (
        _pipe("P1", (0, 0, 0), (4, 0, 0), 0.1143, 0),
        _pipe("P3", (2, 0.15, 0), (2, 2, 0), 0.1143, 1),
    )
    scan = Scan(units="m", objects=tuple(f.object for f in fits), name="tee")
    model = merge_model(FitReport(scan=scan, fits=fits))
    again = model_from_document(json.loads(dumps_model(model)))
    pieces = [c for c in again.components if c.sources == ("P1",)]
    assert len(pieces) == 2 and pieces[0].fit is pieces[1].fit
    groups = lambda m: [ids for _, ids in _one_per_fit(m.components)]  # noqa: E731
    assert groups(again) == groups(model)
    assert _findings(again) == _findings(model)


def test_document_without_the_fitted_primitive_still_loads(built):
    model, document = built["structural-bay"]
    old = json.loads(json.dumps(document))
    for entry in old["components"]:
        entry["fitted"].pop("primitive")
    again = model_from_document(old)
    assert all(isinstance(c.fit, StoredFit) for c in again.components)
    codes = [(f.code, f.severity, f.objects) for f in check_model(again)]
    assert codes == [(f.code, f.severity, f.objects) for f in check_model(model)]


def test_documents_with_fits_follow_the_schema(built):
    validator = jsonschema.Draft202012Validator(model_schema())
    for _, document in built.values():
        validator.validate(document)
        assert all(
            c["fitted"]["primitive"]["shape"] == c["fitted"]["kind"]
            for c in document["components"]
            if c["fitted"] is not None
        )


@pytest.mark.parametrize(
    ("change", "where"),
    [
        ({"points": "many"}, "fitted.points: must be a whole number of points"),
        ({"stderr": {"radius": "small"}}, 'fitted.stderr.radius: must be numbers or null, not "'),
        ({"kind": "torus"}, "fitted.kind: must be one of cylinder, cuboid"),
        ({"primitive": {"shape": "sphere", "center": [0, 0, 0]}}, "fitted.primitive.radius"),
    ],
)
def test_bad_fit_summaries_are_located(built, change, where):
    document = json.loads(json.dumps(built["structural-bay"][1]))
    document["components"][0]["fitted"].update(change)
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    assert str(info.value).startswith(f"m.json: components[0] (C1).{where}")


def test_report_quality_from_an_old_document(built):
    """A document written before the per-point data was stored: every column but the
    histogram from the stored summary, and the cell says the residuals are not stored."""
    from asbuilt.report.data import report_data
    from asbuilt.report.html import html_text

    model, document = built["structural-bay"]
    old = json.loads(json.dumps(document))
    for entry in old["components"]:
        del entry["fitted"]["residuals"], entry["fitted"]["inlier_mask"]
    again = model_from_document(old)
    assert all(
        c.fit.residuals.shape == (0,) and c.fit.inliers.shape == (0,) for c in again.components
    )
    scan_rows = report_data(model).quality
    doc_rows = report_data(again).quality
    assert [q.id for q in doc_rows] == [q.id for q in scan_rows] and len(doc_rows) == 8
    for a, b in zip(scan_rows, doc_rows):
        assert (a.points, a.inliers, a.rms, a.sigma) == (b.points, b.inliers, b.rms, b.sigma)
    page = html_text(report_data(again))
    assert page.count("not stored in the model file") == 8


def _fitted_c1(built):
    document = json.loads(json.dumps(built["structural-bay"][1]))
    return document, document["components"][0]["fitted"]


@pytest.mark.parametrize(
    ("change", "where"),
    [
        (
            lambda f: f["residuals"].pop(),
            "fitted.residuals: has {m} values but points is {n}; give one per measured point",
        ),
        (
            lambda f: f["inlier_mask"].append(True),
            "fitted.inlier_mask: has {p} values but points is {n}; give one per measured point",
        ),
        (
            lambda f: f.update(points=f["points"] + 1),
            "fitted.residuals: has {n} values but points is {p}",
        ),
        (
            lambda f: f["inlier_mask"].__setitem__(0, False),
            "fitted.inlier_mask: marks {m} points as inliers but inliers is {n}",
        ),
        (lambda f: f.pop("inlier_mask"), "fitted.inlier_mask: missing while residuals is given"),
        (lambda f: f.pop("residuals"), "fitted.residuals: missing while inlier_mask is given"),
        (
            lambda f: f.update(residuals="small"),
            'fitted.residuals: must be a list of numbers or null (metres), not "small"',
        ),
        (
            lambda f: f["inlier_mask"].__setitem__(2, 1),
            "fitted.inlier_mask: must be a list of true/false, not [true, true, 1,",
        ),
    ],
)
def test_bad_per_point_data_is_one_located_line(built, change, where):
    document, fitted = _fitted_c1(built)
    # C1's shots, counted in the document's scan section; the fit kept them all
    n = len(next(o for o in document["scan"]["objects"] if o["id"] == "C1")["points"])
    assert fitted["points"] == fitted["inliers"] == len(fitted["residuals"]) == n
    change(fitted)
    with pytest.raises(ModelDocumentError) as info:
        model_from_document(document, source="m.json")
    message = str(info.value)
    assert message.startswith("m.json: components[0] (C1)." + where.format(n=n, m=n - 1, p=n + 1))
    assert "\n" not in message


def test_null_residual_reads_back_as_nan(built):
    document, fitted = _fitted_c1(built)
    fitted["residuals"][4] = None  # a non-finite residual is written as null
    stored = model_from_document(document).components[0].fit
    assert np.isnan(stored.residuals[4]) and np.isfinite(np.delete(stored.residuals, 4)).all()


def test_schema_wants_residuals_and_inlier_mask_together(built):
    validator = jsonschema.Draft202012Validator(model_schema())
    for key in ("residuals", "inlier_mask"):
        document, fitted = _fitted_c1(built)
        del fitted[key]
        errors = list(validator.iter_errors(document))
        assert errors and all(list(e.absolute_path) == ["components", 0, "fitted"] for e in errors)
        del fitted["residuals" if key == "inlier_mask" else "inlier_mask"]
        validator.validate(document)  # neither: an older document


def test_a_document_read_back_writes_its_per_point_data_again(built):
    """``asbuilt check MODEL --fix OUT`` writes a model read from a document: the per-point
    data goes with it, and an older document's (none) stays none rather than empty lists."""
    model, document = built["spool"]
    assert json.loads(dumps_model(model_from_document(document))) == document
    old = json.loads(json.dumps(document))
    for entry in old["components"]:
        if entry["fitted"] is not None:
            del entry["fitted"]["residuals"], entry["fitted"]["inlier_mask"]
    assert json.loads(dumps_model(model_from_document(old))) == old
