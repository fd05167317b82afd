"""Merging's sentences (snap reasons, merge notes, fitting notes) tell lengths in inches for a
scan in inches or feet, as the fits' notes do; a metric scan's stay millimetres. The snap's
numbers stay metres."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.merge.snap import TEXT_FIELDS
from asbuilt.rules import check_model

NPS4 = 0.1143
LR90_NPS4 = 0.152  # B16.9 NPS 4 90 degree long-radius centre-to-end

LENGTH = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?) (mm|m|in|ft)\b")


def merged(units: str):
    # pipes end 0.40 m short of the corner; the NPS 4 LR elbow needs 0.152 m: 248 mm extended
    pipes = [Pipe("P1", (0, 0, 0), (1.6, 0, 0), NPS4), Pipe("P2", (2, 0.4, 0), (2, 2, 0), NPS4)]
    report = report_of(pipes, links=[("P1", "P2")])
    return merge_model(replace(report, scan=replace(report.scan, units=units)))


def sentences(model):
    out = []
    for comp in model.components:
        for key in TEXT_FIELDS:
            value = (comp.snap or {}).get(key)
            out.extend([value] if isinstance(value, str) else value or [])
    return out


def test_an_extension_is_said_in_inches():
    extension = (0.40 - LR90_NPS4) / 0.0254  # 9.76 in
    model = merged("in")
    notes = model.component("P1").snap["merge_notes"]
    assert f"extended {extension:.3g} in at its end to elbow P1-P2" in notes[0]
    assert "mm" not in notes[0]
    (finding,) = [f for f in check_model(model) if f.slug == "merge-note" and "P1" in f.objects]
    assert f"extended {extension:.3g} in" in finding.message


@pytest.mark.parametrize("units", ["in", "ft"])
def test_every_merge_sentence_is_the_metric_one_in_inches(units):
    metric, imperial = merged("m"), merged(units)
    said_mm, said_in = sentences(metric), sentences(imperial)
    assert len(said_mm) == len(said_in) >= 4  # two reasons, two merge notes
    told = 0
    for text_mm, text_in in zip(said_mm, said_in, strict=True):
        assert not re.search(r"\d (mm|m)\b", text_in), text_in
        assert LENGTH.sub("#", text_mm) == LENGTH.sub("#", text_in)
        for (value, unit), (inches, unit_in) in zip(
            LENGTH.findall(text_mm), LENGTH.findall(text_in), strict=True
        ):
            assert unit_in == "in"
            metres = float(value) * (0.001 if unit == "mm" else 1.0)
            assert float(inches) == pytest.approx(metres / 0.0254, rel=5e-3, abs=0.003)
            told += 1
    assert told >= 6
    # the data stay metres
    for a, b in zip(metric.components, imperial.components, strict=True):
        numbers = {k: v for k, v in a.snap.items() if k not in TEXT_FIELDS}
        assert numbers == {k: v for k, v in b.snap.items() if k not in TEXT_FIELDS}


def test_a_metric_scans_merge_notes_stay_millimetres():
    for units in ("m", "mm", "cm"):
        model = merged(units)
        notes = model.component("P1").snap["merge_notes"]
        assert "extended 248 mm at its end to elbow P1-P2" in notes[0]
        assert sentences(model) == sentences(merged("m"))
