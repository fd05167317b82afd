"""Accepting chosen suggestions (check --accept): choices named by finding key and number."""

import numpy as np
import pytest
from rules_builders import B36, model, pipe

from asbuilt.errors import AsbuiltError, SuggestionError
from asbuilt.findings import Finding, Suggestion
from asbuilt.rules import apply_suggestions, check_model, choose_suggestions, finding_key
from asbuilt.rules.accept import parse_choice


def finding(code, slug, objects, *suggestions):
    return Finding(code, slug, "error", tuple(objects), "m", suggestions=tuple(suggestions))


RESIZE_4 = Suggestion("use NPS 4", {"object": "P5", "field": "nominal", "value": "4"})
RESIZE_5 = Suggestion("use NPS 5", {"object": "P5", "field": "nominal", "value": "5"})
ADVICE = Suggestion("rescan the pipe")
BETWEEN = finding("AB101", "nonstandard-diameter", ["P5"], RESIZE_4, RESIZE_5, ADVICE)
CLASH = finding("AB501", "clash", ["P1", "P2"], Suggestion("check on site"))
LEVEL = finding(
    "AB201",
    "misaligned-axis",
    ["P9"],
    Suggestion("make P9 level", {"object": "P9", "field": "rotation"}, unambiguous=True),
)
FINDINGS = [BETWEEN, CLASH, LEVEL]


def test_key_is_code_at_objects():
    assert finding_key(BETWEEN) == "AB101@P5"
    assert finding_key(CLASH) == "AB501@P1,P2"


@pytest.mark.parametrize(
    "text, rule, objects, number",
    [
        ("AB101@P5:2", "AB101", "P5", 2),
        ("nonstandard-diameter@P5", "nonstandard-diameter", "P5", None),
        ("AB501@P1,P2", "AB501", "P1,P2", None),
        ("AB101@pipe@7:1", "AB101", "pipe@7", 1),  # only the first @ splits
    ],
)
def test_parse(text, rule, objects, number):
    choice = parse_choice(text)
    assert (choice.rule, choice.objects, choice.number) == (rule, objects, number)


@pytest.mark.parametrize(
    "choices, chosen",
    [
        (["AB101@P5:2"], [(BETWEEN, RESIZE_5)]),
        (["ab101@P5:1"], [(BETWEEN, RESIZE_4)]),  # codes in any case
        (["nonstandard-diameter@P5:1"], [(BETWEEN, RESIZE_4)]),
        (["AB201@P9"], [(LEVEL, LEVEL.suggestions[0])]),  # one change: no number needed
        (["AB201@P9:1", "AB201@P9"], [(LEVEL, LEVEL.suggestions[0])]),  # twice is once
        (["AB201@P9", "AB101@P5:1"], [(LEVEL, LEVEL.suggestions[0]), (BETWEEN, RESIZE_4)]),
    ],
)
def test_choose(choices, chosen):
    got = choose_suggestions(FINDINGS, choices)
    assert [(f, s) for f, s in got] == chosen


@pytest.mark.parametrize(
    "choices, message",
    [
        (["P5"], "give a finding as RULE@OBJECTS[:N]"),
        (["@P5"], "give a finding as RULE@OBJECTS[:N]"),
        (["AB101@"], "give a finding as RULE@OBJECTS[:N]"),
        (["AB101@P5:0"], "suggestions are numbered from 1"),
        (["AB101@P5"], "AB101@P5 has 2 suggestions to choose from: add :1 (use NPS 4) or :2"),
        (["AB101@P5:3"], "suggestion 3 of AB101@P5 is advice, not a change to accept"),
        (["AB101@P5:4"], "AB101@P5 has 3 suggestions, not 4"),
        (["AB101@P6"], "no AB101 finding on P6 in this check; findings with a change to "),
        (["AB101@P1,P2"], "no AB101 finding on P1,P2"),
        (["AB501@P1,P2"], "AB501@P1,P2 suggests no change to accept, only advice"),
        (["AB101@P5:1", "AB101@P5:2"], "both change the nominal of P5: accept one of them"),
    ],
)
def test_bad_choices_are_one_line_errors(choices, message):
    with pytest.raises(SuggestionError, match=".*") as info:
        choose_suggestions(FINDINGS, choices)
    text = str(info.value)
    assert message in text and "\n" not in text
    assert isinstance(info.value, AsbuiltError) and isinstance(info.value, ValueError)


def test_the_listing_names_findings_with_changes_only():
    with pytest.raises(SuggestionError) as info:
        choose_suggestions(FINDINGS, ["AB101@P6"])
    assert str(info.value).endswith("findings with a change to accept: AB101@P5, AB201@P9")


def test_an_id_ending_in_colon_number_is_taken_whole_when_a_finding_has_it():
    odd = finding("AB101", "nonstandard-diameter", ["P:2"], RESIZE_4, RESIZE_5)
    with pytest.raises(SuggestionError, match="has 2 suggestions to choose"):
        choose_suggestions([odd], ["AB101@P:2"])
    ((_, chosen),) = choose_suggestions([odd], ["AB101@P:2:2"])
    assert chosen is RESIZE_5


def test_an_ambiguous_size_is_applied_when_chosen():
    """A pipe fitted at 126 mm, no size of the catalog: --fix alone changes nothing (two sizes
    are offered), the second is applied when chosen, and the re-check finds it standard."""
    built = model(pipe("P5", [0, 0, 1], [2, 0, 1], 0.126, status="no-size"))
    before = check_model(built, catalog=B36)
    (between,) = [f for f in before if f.slug == "nonstandard-diameter"]
    assert not any(s.unambiguous for s in between.suggestions)
    second = between.suggestions[1].change
    assert second["value"] != between.suggestions[0].change["value"]
    chosen = choose_suggestions(before, ["AB101@P5:2"])
    fixed, changes = apply_suggestions(built, chosen, catalog=B36)
    geom = fixed.component("P5").geometry
    assert 2 * geom.outer_radius == pytest.approx(second["od"])
    assert fixed.component("P5").nominal == second["value"]
    assert changes == [f"P5: {chosen[0][1].description} (nonstandard-diameter)"]
    after = check_model(fixed, catalog=B36)
    assert "nonstandard-diameter" not in {f.slug for f in after}
    np.testing.assert_allclose(geom.start, built.component("P5").geometry.start)


def test_advice_applies_nothing():
    built = model(pipe("P5", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4"))
    fixed, changes = apply_suggestions(built, [(CLASH, CLASH.suggestions[0])])
    assert changes == [] and fixed.components == built.components
