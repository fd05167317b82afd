"""build_model: fit, then merge, then check — the real stages, and the fallbacks' rules."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from refused_scans import spool_with_refused, write  # tests/refused_scans.py

from asbuilt.errors import FitError
from asbuilt.findings import FIT_REFUSED_CODE, FIT_REFUSED_SLUG
from asbuilt.fit import NothingFittedError, fit, fit_points
from asbuilt.model import model_from_fits
from asbuilt.pipeline import build_model, recheck
from asbuilt.scan import load_scan

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def spool_scan():
    return load_scan(ROOT / "samples" / "spool.json")


def test_the_real_merge_and_rules_are_used(spool_scan):
    from asbuilt.merge import merge_model
    from asbuilt.rules import check_model

    model = build_model(spool_scan)
    merged = merge_model(fit(spool_scan))
    assert [c.id for c in model.components] == [c.id for c in merged.components]
    assert any(c.type == "elbow" for c in model.components)
    assert [s.id for s in model.spools] == ["SP-101"]
    expected = check_model(merged)
    assert [(f.code, f.objects) for f in model.findings] == [(f.code, f.objects) for f in expected]


def test_without_merge_it_is_the_fitted_model(spool_scan):
    model = build_model(spool_scan, merge=False, check=False)
    plain = model_from_fits(fit(spool_scan))
    assert [(c.id, c.type) for c in model.components] == [(c.id, c.type) for c in plain.components]
    assert model.findings == () and model.spools == ()


def test_schedule_makes_hollow_pipes(spool_scan):
    model = build_model(spool_scan, schedule="40", check=False)
    pipes = [c for c in model.components if c.type == "pipe" and c.nominal]
    assert pipes and all(c.geometry.wall > 0 for c in pipes)


def test_rules_file_path_is_loaded(spool_scan, tmp_path):
    rules = tmp_path / "rules.toml"
    rules.write_text('ignore = ["ALL"]\n')
    from asbuilt.rules import load_rules

    config = load_rules(rules)
    assert list(config.active_rules()) == []
    assert build_model(spool_scan, rules=rules).findings == ()


def test_progress_is_passed_to_the_fit(spool_scan):
    seen = []
    build_model(spool_scan, check=False, progress=lambda d, t, oid: seen.append(oid))
    assert seen == [obj.id for obj in spool_scan.objects]


def test_the_rules_file_tolerances_drive_the_merge(spool_scan, tmp_path):
    rules = tmp_path / "rules.toml"
    rules.write_text("[general]\nangle_snap_deg = 0.001\nangle_snap_max_deg = 0.001\n")
    default = build_model(spool_scan, check=False)
    strict = build_model(spool_scan, rules=rules, check=False)

    def vertical_or_horizontal(model):
        return {
            c.id
            for c in model.components
            for k in c.corrections
            if k.what.startswith("axis regularised")
            and ("vertical" in k.what or "horizontal" in k.what)
        }

    assert vertical_or_horizontal(default), "the default 2 degrees regularise the sample's axes"
    assert not vertical_or_horizontal(strict)


def test_short_elbows_on_request(spool_scan):
    long = build_model(spool_scan, check=False)
    short = build_model(spool_scan, check=False, elbow_radius="short")
    radius = {c.id: c.geometry.bend_radius for c in long.components if c.type == "elbow"}
    shorter = {c.id: c.geometry.bend_radius for c in short.components if c.type == "elbow"}
    assert radius and all(shorter[k] < radius[k] for k in radius)


# --- objects whose fit is refused ------------------------------------------------------------


@pytest.fixture(scope="module")
def refused_scan(tmp_path_factory):
    """The spool sample with a refused NPS 1 scan X1 appended, linked to P5."""
    path = tmp_path_factory.mktemp("refused") / "scan.json"
    return load_scan(write(path, spool_with_refused(link=True)))


def _geometry(model):
    return [(c.id, c.type, c.nominal, c.spool) for c in model.components]


def test_a_refused_object_does_not_stop_the_others(spool_scan, refused_scan):
    model = build_model(refused_scan)
    alone = build_model(spool_scan)  # the same six pipes without the refused one
    assert _geometry(model) == _geometry(alone) and model.spools == alone.spools
    for got, want in zip(model.components, alone.components):
        for name, value in vars(want.geometry).items():
            if value is None:  # a bend's end size or wall: None is the start's
                assert getattr(got.geometry, name) is None, name
                continue
            np.testing.assert_allclose(getattr(got.geometry, name), value, rtol=0, atol=1e-12)
    x1 = refused_scan.objects[-1]
    with pytest.raises(FitError) as direct:  # the fit's own reason, fitted alone
        fit_points("cylinder", x1.points, sigma=0.002, viewpoint=x1.station)
    (finding,) = model.findings  # the sample itself is clean: no merge note for the link to X1
    assert (finding.code, finding.slug, finding.severity) == (
        FIT_REFUSED_CODE,
        FIT_REFUSED_SLUG,
        "error",
    )
    assert finding.objects == ("X1",)
    assert finding.message == (
        f"not fitted as a cylinder, so it is not in the model: {direct.value.message}"
    )
    assert "Rescan" in finding.message and "\n" not in finding.message
    np.testing.assert_allclose(finding.location, x1.points.mean(axis=0))
    (keep,) = finding.suggestions
    assert not keep.unambiguous and keep.change["object"] == "X1"
    np.testing.assert_array_equal(keep.change["points"], x1.points)  # nothing measured is lost
    assert [f.object.id for f in model.fits.failures] == ["X1"]
    assert model.scan is refused_scan and model.scan.links[-1] == ("P5", "X1")


def test_the_refusal_is_said_without_the_rules_and_without_merging(refused_scan):
    for options in ({"check": False}, {"merge": False, "check": False}, {"merge": False}):
        model = build_model(refused_scan, **options)
        assert "X1" not in {c.id for c in model.components}
        assert [f.slug for f in model.findings if f.severity == "error"] == [FIT_REFUSED_SLUG]


def test_a_recheck_keeps_the_refusal_through_the_model_document(refused_scan, tmp_path):
    from asbuilt.export.model_json import load_model, write_model_json

    model = build_model(refused_scan)
    write_model_json(model, tmp_path / "model.json")
    again = load_model(tmp_path / "model.json")
    findings = recheck(again)
    assert [(f.code, f.objects) for f in findings] == [(FIT_REFUSED_CODE, ("X1",))]
    np.testing.assert_allclose(
        findings[0].suggestions[0].change["points"], refused_scan.objects[-1].points
    )


def test_strict_fit_raises_the_first_refusal(refused_scan):
    with pytest.raises(FitError) as err:
        fit(refused_scan, strict=True)
    assert str(err.value).startswith(f"{refused_scan.source}: objects[6] (X1): The shots")


def test_a_scan_no_object_of_which_fits_is_refused_whole(tmp_path):
    scan = load_scan(write(tmp_path / "bad.json", spool_with_refused(3, good=False)))
    with pytest.raises(NothingFittedError) as err:
        build_model(scan)
    assert str(err.value).startswith(f"{scan.source}: objects[0] (X1): The shots")
    assert str(err.value).endswith("the 2 other objects (X2, X3) were refused too.")


def test_a_refused_objects_id_is_not_given_to_a_spool(tmp_path):
    """Spool ids never take a scan object's id (merge, audit); a refused object keeps its id
    reserved although it is no component (ungrouped pipes make a generated spool S<n>)."""
    document = spool_with_refused(link=True)
    for obj in document["objects"]:
        obj.pop("group", None)
    document["objects"][-1]["id"] = "S1"
    document["links"][-1] = ["P5", "S1"]
    model = build_model(load_scan(write(tmp_path / "scan.json", document)))
    assert [f.objects for f in model.findings] == [("S1",)]
    assert [s.id for s in model.spools] == ["S2"]


def _facing_model(gap=0.6):
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent / "merge"))
    from synthetic_pipes import Pipe, report_of

    from asbuilt.merge import merge_model

    od = 0.1143
    pipes = [
        Pipe("P1", (0, 0, 1), (2, 0, 1), od),
        Pipe("P2", (2 + gap, 0.8 * gap, 1), (2 + gap, 3, 1), od),
    ]
    report = report_of(pipes)
    return merge_model(report).replace(scan=report.scan, fits=report)


def test_relink_merges_again_with_the_link_and_joins_the_pair():
    from asbuilt.pipeline import relink

    model = _facing_model()
    assert {c.type for c in model.components} == {"pipe"}
    joined = relink(model, [("P1", "P2")])
    assert [c.type for c in joined.components] == ["pipe", "elbow", "pipe"]
    assert len({c.spool for c in joined.components}) == 1
    assert joined.scan.links == (("P1", "P2"),)
    assert joined.fits is model.fits or joined.fits.fits == model.fits.fits  # fits kept
    assert not [f for f in joined.findings if f.slug == "unjoined-end"]


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"scan": None}, "linking objects needs the scan, and this model does not store it"),
        ({}, "cannot link P1 and P7: the scan has no object P7"),
    ],
)
def test_relink_refuses_what_it_cannot_do(change, message):
    from asbuilt.errors import SuggestionError
    from asbuilt.pipeline import relink

    model = _facing_model().replace(**change)
    with pytest.raises(SuggestionError, match=message):
        relink(model, [("P1", "P7")] if change == {} else [("P1", "P2")])


def test_relink_says_when_the_link_does_not_join():
    from asbuilt.errors import SuggestionError
    from asbuilt.pipeline import relink

    with pytest.raises(SuggestionError, match="linking P1 and P2 does not join them"):
        relink(_facing_model(gap=1.2), [("P1", "P2")])


@pytest.mark.parametrize(
    ("units", "said"), [("m", "within 4 mm of a line"), ("in", "within 0.157 in of a line")]
)
def test_a_refused_fit_is_told_in_the_scans_units(units, said):
    # the fit's reason says mm; a scan in inches reads its findings in inches, as its fit notes
    from asbuilt.fit.result import FitFailure
    from asbuilt.pipeline import fit_refused_finding
    from asbuilt.scan.model import ScanObject

    obj = ScanObject(id="P3", kind="cylinder", points=np.zeros((5, 3)))
    failure = FitFailure(obj, FitError("The points lie within 4 mm of a line."))
    finding = fit_refused_finding(failure, units)
    assert said in finding.message
    assert finding.suggestions[0].change["points"] == np.zeros((5, 3)).tolist()
