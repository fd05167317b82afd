from pathlib import Path

import pytest

from asbuilt.findings import SEVERITIES
from asbuilt.rules import RULES, match_rules, rule

ROOT = Path(__file__).resolve().parents[2]

REQUIRED = (
    "nonstandard-diameter",
    "ambiguous-size",
    "hint-mismatch",
    "contiguous-diameter-mismatch",
    "misaligned-axis",
    "out-of-plumb",
    "slope",
    "joint-gap",
    "too-few-points",
    "weak-geometry",
    "poor-fit",
    "outliers",
    "clash",
    "design-deviation",
)


def test_codes_and_slugs_are_unique():
    assert len({r.code for r in RULES}) == len(RULES)
    assert len({r.slug for r in RULES}) == len(RULES)


@pytest.mark.parametrize("slug", REQUIRED)
def test_every_required_rule_is_registered(slug):
    r = rule(slug)
    assert r.severity in SEVERITIES
    assert r.message and r.source
    assert r.code.startswith("AB") and r.code[2:].isdigit()


@pytest.mark.parametrize(
    "selector, expected",
    [
        ("AB202", {"out-of-plumb"}),
        ("ab202", {"out-of-plumb"}),
        ("out-of-plumb", {"out-of-plumb"}),
        ("AB2", {"misaligned-axis", "out-of-plumb", "slope"}),
        (
            "AB4",
            {
                "too-few-points",
                "weak-geometry",
                "poor-fit",
                "outliers",
                "ambiguous-kind",
                "another-object",
                "viewpoint-ignored",
            },
        ),
        ("nope", set()),
        ("AB9", set()),
    ],
)
def test_match_rules(selector, expected):
    assert {r.slug for r in match_rules(selector)} == expected


def test_all_selects_everything():
    assert match_rules("ALL") == RULES


def test_docs_describe_every_rule():
    text = (ROOT / "docs" / "rules.md").read_text(encoding="utf-8")
    for r in RULES:
        assert f"`{r.slug}`" in text and r.code in text, r.slug
