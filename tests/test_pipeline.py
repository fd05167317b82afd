"""build_model: fit, then merge, then check — the real stages, and the fallbacks' rules."""

from __future__ import annotations

from pathlib import Path

import pytest

from asbuilt.fit import fit
from asbuilt.model import model_from_fits
from asbuilt.pipeline import _optional, build_model, stage_available
from asbuilt.scan import load_scan

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def spool_scan():
    return load_scan(ROOT / "samples" / "spool.json")


def test_the_real_merge_and_rules_are_used(spool_scan):
    from asbuilt.merge import merge_model
    from asbuilt.rules import check_model

    assert stage_available("merge") and stage_available("rules")
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


def test_optional_returns_none_only_for_a_missing_stage(monkeypatch):
    assert _optional("asbuilt.no_such_stage", "anything") is None

    def fail(name):  # the stage exists but one of *its* imports is missing: a real error
        raise ModuleNotFoundError("No module named 'scipy.missing'", name="scipy.missing")

    monkeypatch.setattr("asbuilt.pipeline.import_module", fail)
    with pytest.raises(ModuleNotFoundError):
        _optional("asbuilt.merge", "merge_model")


def test_unknown_stage_name():
    with pytest.raises(ValueError, match="unknown stage"):
        stage_available("report")
