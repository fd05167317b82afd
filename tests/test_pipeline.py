"""build_model: fit, then merge, then check — the real stages, and the fallbacks' rules."""

from __future__ import annotations

from pathlib import Path

import pytest

from asbuilt.fit import fit
from asbuilt.model import model_from_fits
from asbuilt.pipeline import build_model
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
    rules.write_text("[general]\nangle_snap_deg = 0.001\n")
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
