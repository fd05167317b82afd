"""asbuilt.labels in the merge: the words that tell pipes from vessels, and a rules file's own."""

from __future__ import annotations

import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.errors import RulesConfigError
from asbuilt.labels import EQUIPMENT_TAGS, PIPE_WORDS, VESSEL_WORDS, LabelWords
from asbuilt.merge import DEFAULT_WORDS, merge_model
from asbuilt.rules import load_rules, loads_rules


def test_the_shipped_rules_file_holds_the_merge_defaults():
    # One vocabulary: the rules file lists it for users to edit, the merge has it for callers
    # without one.
    assert load_rules(None).label_words == DEFAULT_WORDS
    assert DEFAULT_WORDS == LabelWords(PIPE_WORDS, VESSEL_WORDS, EQUIPMENT_TAGS)


@pytest.mark.parametrize(
    "text, says",
    [
        ("NPS 8 line from the tank", ("pipe", "nps")),
        ("Tanks", ("vessel", "tank")),
        ("risers 3 and 4", ("pipe", "riser")),
        ("tk101 north", ("vessel", "tk101")),
        ("V-101A", ("vessel", "V-101A")),
        ('4"-V-1001-A1', (None, None)),
        ("a bare cylinder", (None, None)),
        (None, (None, None)),
    ],
)
def test_default_words(text, says):
    assert DEFAULT_WORDS.says(text) == says


def test_a_plants_own_words_and_tags():
    words = LabelWords(pipe=("leitung",), vessel=("behaelter", "bullet"), tags=("T", "TB"))
    assert words.says("Behaelter B2") == ("vessel", "behaelter")
    assert words.says("LPG bullets") == ("vessel", "bullet")
    assert words.says("T-204") == ("vessel", "T-204")
    assert words.says("TB12") == ("vessel", "TB12")
    assert words.says("T12") == (None, None)  # one letter needs its dash
    assert words.says("Leitung vom Behaelter") == ("pipe", "leitung")
    assert words.says("storage tank") == (None, None)  # the defaults are replaced, not added
    assert LabelWords(pipe=(), vessel=(), tags=()).says("tank line TK-1") == (None, None)


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("vessel", ("tank farm",), "vessel: 'tank farm' is not a word of letters, digits"),
        ("pipe", ("line.*",), "pipe: 'line.*' is not a word"),
        ("pipe", ("-run",), "pipe: '-run' is not a word"),
        ("tags", ("TK-",), "tags: 'TK-' is not a word of letters"),
        ("tags", ("T1",), "tags: 'T1' is not a word of letters"),
        ("vessel", (3,), "vessel: 3 is not a word"),
        ("vessel", "tank", "vessel: give a list of words, not the string 'tank'"),
    ],
)
def test_bad_words_are_refused(field, value, message):
    with pytest.raises(ValueError, match="^" + message.replace("*", r"\*").replace(".", r"\.")):
        LabelWords(**{field: value})


def test_merging_reads_labels_with_the_given_words():
    # A 1.2 m LPG bullet (NPS 48 by its size) and a 4 in pipe labelled in German.
    pipes = [
        Pipe("B1", (0, 0, 0), (6, 0, 0), 1.2192, label="LPG bullet B1"),
        Pipe("L1", (0, 3, 0), (0, 6, 0), 0.1143, label="Leitung 4"),
    ]
    default = {c.id: c.type for c in merge_model(report_of(pipes)).components}
    assert default == {"B1": "pipe", "L1": "pipe"}
    words = LabelWords(vessel=("bullet",))
    model = merge_model(report_of(pipes), words=words)
    kinds = {c.id: c for c in model.components}
    assert kinds["B1"].type == "cylinder" and kinds["L1"].type == "pipe"
    assert "labelled 'bullet'" in kinds["B1"].snap["reason"]


def test_a_rules_file_sets_the_words(tmp_path):
    config = loads_rules('[general]\nvessel_keywords = ["bullet", "tank"]\nequipment_tags = []')
    assert config.label_words.vessel == ("bullet", "tank")
    assert config.label_words.tags == ()
    assert config.label_words.pipe == PIPE_WORDS


@pytest.mark.parametrize(
    "text, where, wanted",
    [
        ('vessel_keywords = ["tank farm"]', "vessel_keywords", "letters, digits and inner dashes"),
        ('equipment_tags = ["TK-"]', "equipment_tags", "a list of letters"),
        ("pipe_keywords = [1]", "pipe_keywords[0]", "a string"),
    ],
)
def test_bad_words_in_a_rules_file_are_one_line_errors(text, where, wanted):
    with pytest.raises(RulesConfigError) as err:
        loads_rules(f"[general]\n{text}\n", source="plant.toml")
    message = str(err.value)
    assert message.startswith(f"plant.toml: [general].{where}: must be ")
    assert wanted in message and "\n" not in message
