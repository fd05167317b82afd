"""A vessel's fit notes and refusals in its label's noun (asbuilt.fit._object_words)."""

from __future__ import annotations

import json

import pytest
from sim_tanks import tank_before_wall

from asbuilt.errors import FitError
from asbuilt.fit import fit
from asbuilt.fit._object_words import named_report, renamed
from asbuilt.fit.result import FitFailure, FitReport
from asbuilt.labels import DEFAULT_WORDS, LabelWords
from asbuilt.scan import loads_scan


@pytest.mark.parametrize(
    ("text", "noun", "expected"),
    [
        ("on the far side of the pipe", "tank", "on the far side of the tank"),
        ("so they are not one pipe.", "column", "so they are not one column."),
        ("a pipe's surface", "drum", "a drum's surface"),
        ("a pipe's surface", "accumulator", "an accumulator's surface"),
        ("A pipe before a wall", "exchanger", "An exchanger before a wall"),
        ("Pipe shots; two pipes", "silo", "Silo shots; two silos"),
        # Other words are left alone.
        ("piping, pipeline, pipes' ends", "tank", "piping, pipeline, tanks' ends"),
    ],
)
def test_pipe_is_renamed_with_its_article_plural_and_possessive(text, noun, expected):
    assert renamed(text, noun) == expected


@pytest.mark.parametrize(
    ("label", "group", "noun"),
    [
        ("vertical tank", None, "tank"),
        ("Tanks 3 and 4", None, "tank"),
        ("TK-101", None, "vessel"),
        ("column C-3", None, "column"),
        (None, "drum area", "drum"),
        # A pipe word wins, as in the merge: "line from the tank" is a pipe.
        ("NPS 8 line from the tank", None, None),
        ("R2", None, None),
        (None, None, None),
    ],
)
def test_vessel_noun_reads_labels_as_the_merge_does(label, group, noun):
    assert DEFAULT_WORDS.vessel_noun(label, group) == noun


def _tank_scan(label: str | None):
    # Seed 27 without a station: the tank's fit leaves out one shot on its far side, and its
    # note says so ("... on the far side of the pipe").
    points, _, _ = tank_before_wall(27)
    obj = {"id": "T1", "kind": "cylinder", "points": points.tolist()}
    if label is not None:
        obj["label"] = label
    text = {"format": "asbuilt-scan", "version": 1, "units": "m", "objects": [obj]}
    return loads_scan(json.dumps(text), source="tank.json")


def test_a_labelled_tank_is_named_a_tank_in_its_notes():
    (plain,) = fit(_tank_scan(None)).fits
    (tank,) = fit(_tank_scan("tank T-1")).fits
    (line,) = fit(_tank_scan("line 7")).fits
    assert any("far side of the pipe" in note for note in plain.result.notes)
    assert line.result.notes == plain.result.notes
    assert tank.result.notes == tuple(renamed(note, "tank") for note in plain.result.notes)
    assert not any("pipe" in note for note in tank.result.notes)
    # The geometry is the same fit.
    assert tank.result.primitive.radius == plain.result.primitive.radius


def test_a_rules_files_vessel_words_name_the_object():
    words = LabelWords(vessel=("behaelter",))
    (fitted,) = fit(_tank_scan("Behaelter 2"), words=words).fits
    assert any("far side of the behaelter" in note for note in fitted.result.notes)


def test_a_refusal_keeps_its_place_and_takes_the_noun():
    report = fit(_tank_scan("drum"))
    obj = report.scan.objects[0]
    error = FitError("two lines along the pipe", source="tank.json", where="objects[0] (T1)")
    failed = FitReport(scan=report.scan, fits=(), failures=(FitFailure(object=obj, error=error),))
    (named,) = named_report(failed, DEFAULT_WORDS).failures
    assert named.message == "two lines along the drum"
    assert str(named.error) == "tank.json: objects[0] (T1): two lines along the drum"
    assert named.object is obj


def test_a_strict_fit_raises_the_refusal_in_the_labels_word(monkeypatch):
    # strict mode raises the first refusal at once: in the label's word too.
    import asbuilt.fit as fitting

    def refuse(obj, **options):
        raise FitError("two lines along the pipe", where=obj.where)

    monkeypatch.setattr(fitting, "fit_object", refuse)
    with pytest.raises(FitError) as raised:
        fit(_tank_scan("tank T-1"), strict=True)
    assert str(raised.value) == "tank.json: objects[0] (T1): two lines along the tank"
