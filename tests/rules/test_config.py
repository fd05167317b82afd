import dataclasses
import re

import pytest

from asbuilt.errors import RulesConfigError
from asbuilt.rules import RULES, load_rules, loads_rules
from asbuilt.rules.config import _shipped
from asbuilt.tolerances import DEFAULT_TOLERANCES


def test_defaults_enable_every_rule_with_its_registry_severity():
    config = load_rules()
    assert config.active_rules() == RULES
    for r in RULES:
        assert config.severity(r.slug) == r.severity
    assert config.source is None
    assert config.k_sigma == 2.0


def test_shipped_file_has_one_table_per_rule_and_nothing_else():
    shipped = _shipped()
    tables = {k for k, v in shipped.items() if isinstance(v, dict)} - {"general"}
    assert tables == {r.slug for r in RULES}


def test_tolerances_have_one_source_of_truth():
    config = load_rules()
    assert config.tolerances == DEFAULT_TOLERANCES
    for f in dataclasses.fields(DEFAULT_TOLERANCES):
        assert config.general[f.name] == getattr(DEFAULT_TOLERANCES, f.name)
    # the shipped file does not repeat them (only comments do)
    assert "angle_snap_deg" not in _shipped()["general"]


def test_user_file_overrides_per_key(tmp_path):
    path = tmp_path / "project.toml"
    path.write_text(
        "[out-of-plumb]\nsteel_ratio = 1000\n[general]\nangle_snap_deg = 1.5\n", encoding="utf-8"
    )
    config = load_rules(path)
    assert config.option("out-of-plumb", "steel_ratio") == 1000.0
    assert isinstance(config.option("out-of-plumb", "steel_ratio"), float)
    # untouched keys keep their defaults
    assert config.option("out-of-plumb", "concrete_max") == 0.025
    assert config.severity("out-of-plumb") == "error"
    assert config.tolerances.angle_snap_deg == 1.5
    assert config.tolerances.intended_angle_deg == DEFAULT_TOLERANCES.intended_angle_deg
    assert config.source == str(path)


@pytest.mark.parametrize(
    "text, active, inactive",
    [
        ('select = ["AB2"]', {"out-of-plumb", "slope"}, {"clash", "too-few-points"}),
        ('ignore = ["too-few-points", "AB501"]', {"out-of-plumb"}, {"too-few-points", "clash"}),
        ('select = ["AB4"]\nignore = ["outliers"]', {"poor-fit"}, {"outliers", "out-of-plumb"}),
        ('select = ["out-of-plumb"]', {"out-of-plumb"}, {"slope"}),
    ],
)
def test_select_and_ignore(text, active, inactive):
    config = loads_rules(text, source="r.toml")
    for slug in active:
        assert config.is_active(slug)
    for slug in inactive:
        assert not config.is_active(slug)


def test_with_selection_replaces_select_and_extends_ignore():
    config = loads_rules('ignore = ["clash"]').with_selection(
        select=["AB5", "AB2"], ignore=["slope"]
    )
    assert {r.slug for r in config.active_rules()} == {"misaligned-axis", "out-of-plumb"}


@pytest.mark.parametrize(
    "text, where, hint",
    [
        ("[no-such-rule]\nx = 1", "[no-such-rule]", "unknown rule"),
        ('[out-of-plumb]\nsteel_ratio = "500"', "[out-of-plumb].steel_ratio", "must be a number"),
        ("[out-of-plumb]\nsteel_ratio = true", "[out-of-plumb].steel_ratio", "must be a number"),
        ("[clash]\nsamples = 1.5", "[clash].samples", "must be an integer"),
        ('[out-of-plumb]\nseverity = "fatal"', "[out-of-plumb].severity", "error, warning, info"),
        ("[out-of-plumb]\nsteel_rato = 400", "[out-of-plumb].steel_rato", "unknown option"),
        ("[general]\nk_sigma = -1", "[general].k_sigma", "must be a number at least 0"),
        ('[general]\ndefault_material = "wood"', "[general].default_material", "steel"),
        ("[general]\nsteel_keywords = [1, 2]", "[general].steel_keywords[0]", "string"),
        ('select = ["AB999"]', "select", "unknown rule"),
        ('ignore = "clash"', "ignore", "must be a list"),
        ("out-of-plumb = 3", "out-of-plumb", "must be a table"),
        ("[out-of-plumb\n", None, "not valid TOML"),
    ],
)
def test_bad_rules_files_are_one_clear_line(text, where, hint):
    with pytest.raises(RulesConfigError) as err:
        loads_rules(text, source="project.toml")
    message = str(err.value)
    assert "\n" not in message
    assert message.startswith("project.toml: ")
    if where:
        assert where in message
    assert re.search(re.escape(hint), message)


def test_missing_file(tmp_path):
    with pytest.raises(RulesConfigError, match="no such file"):
        load_rules(tmp_path / "missing.toml")


def test_rules_tables_may_be_named_by_code():
    config = loads_rules("[AB202]\nsteel_ratio = 250")
    assert config.option("out-of-plumb", "steel_ratio") == 250.0


def test_documented_rules_file_example_loads():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[2] / "docs" / "rules.md").read_text(encoding="utf-8")
    block = re.search(r"```toml\n(.*?)```", text, re.S).group(1)
    config = loads_rules(block, source="docs/rules.md")
    assert config.option("out-of-plumb", "steel_ratio") == 1000.0
    assert not config.is_active("too-few-points")
    assert config.severity("clash") == "warning"
    assert config.tolerances.angle_snap_deg == 1.5


# Found by mutation fuzzing (asbuilt check MODEL --rules FILE, 3,000 mutants of the shipped and
# of a user rules file): each was a traceback and is now one located line.
@pytest.mark.parametrize(
    "text, message",
    [
        (
            "[general]\nk_sigma = 1" + "0" * 400,
            "[general].k_sigma: must be a number at least 0 (standard errors a violation must "
            "exceed its limit by), not an integer of 401 digits",
        ),
        (
            "[general]\nrecommended_points_cylinder = 1" + "0" * 400,
            "[general].recommended_points_cylinder: must be an integer at least 1 (points wanted "
            "on a cylinder), not an integer of 401 digits",
        ),
        (
            "[design-deviation]\nlength_tolerance = [[1" + "0" * 400 + ", 0.003]]",
            "[design-deviation].length_tolerance[0][0]: must be a number, not an integer of 401 "
            "digits",
        ),
        (
            "[general]\nk_sigma = 1" + "0" * 5000,
            "line 2: a number of over 4,300 digits; fix the number there",
        ),
        (
            "x = " + "[" * 100_000,
            "not valid TOML (nested too deeply); a rules file nests lists two levels at most",
        ),
    ],
    ids=["float-option", "integer-option", "list-row", "beyond-int-limit", "nested-too-deeply"],
)
def test_fuzzed_rules_files_are_one_located_line(text, message):
    with pytest.raises(RulesConfigError) as info:
        loads_rules(text, source="rules.toml")
    assert str(info.value) == f"rules.toml: {message}"
