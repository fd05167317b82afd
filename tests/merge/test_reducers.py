"""Which reducers ASME B16.9 makes: the shipped list against rows copied by hand from the
standard's reducer tables (large end x small end, NPS), and what merging does with a pair the
standard does not make (NPS 6: OD 168.3 mm, H 140 mm; NPS 12: OD 323.8 mm, H 203 mm)."""

from __future__ import annotations

import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.merge.reducers import reducer_made
from asbuilt.rules import check_model


@pytest.mark.parametrize(
    ("large", "small", "made"),
    [
        ("3/4", "1/2", True),
        ("2", "3/4", True),
        ("2", "1/2", False),
        ("4", "1 1/2", True),
        ("4", "1", False),
        ("6", "4", True),
        ("6", "2", False),
        ("8", "4", True),
        ("8", "3", False),
        ("12", "5", True),
        ("12", "4", False),  # the review's case: 12 x 4 takes two reducers
        ("24", "10", True),
        ("24", "8", False),
        ("4", "6", False),  # small end larger than the large end
    ],
)
def test_b16_9_reducer_pairs(large, small, made):
    assert reducer_made("asme-b16.9", large, small) is made


@pytest.mark.parametrize(
    ("fittings", "large", "small"),
    [("rule", "6", "4"), (None, "6", "4"), ("asme-b16.9", None, "4"), ("asme-b16.9", "6", None)],
)
def test_no_verdict_without_a_list_or_a_size(fittings, large, small):
    assert reducer_made(fittings, large, small) is None


@pytest.mark.parametrize(
    ("large_od", "small_od", "length", "standard"),
    [(0.3238, 0.1143, 0.203, False), (0.1683, 0.1143, 0.140, True)],
    ids=["12x4", "6x4"],
)
def test_a_reducer_the_standard_does_not_make_is_said_so(large_od, small_od, length, standard):
    """A 12 x 4 concentric reducer was built with the 12 inch H (203 mm) and recorded as a
    B16.9 fitting, nothing said; the length stays, the record and a note say what it is."""
    pipes = [
        Pipe("P1", (-1.5, 0, 1), (0, 0, 1), large_od),
        Pipe("P2", (length, 0, 1), (length + 1.5, 0, 1), small_od),
    ]
    model = merge_model(report_of(pipes, links=[("P1", "P2")]))
    reducer = next(c for c in model.components if c.type == "reducer")
    assert reducer.snap["length"] == pytest.approx(length)
    assert reducer.snap["standard"] is standard
    said = [f for f in check_model(model) if f.code == "AB302" and "reducer in" in f.message]
    if standard:
        assert reducer.snap["dimensions"] == "asme-b16.9" and not said
        return
    assert "non-standard" in reducer.snap["dimensions"]
    (finding,) = said
    assert finding.objects == ("P1", "P2")
    assert finding.message.startswith("no NPS 12 x 4 reducer in asme-b16.9")
    assert "10, 8, 6, 5 only" in finding.message


@pytest.mark.parametrize(
    ("gap", "either_way", "noted"),
    [(0.140, 0.0, False), (0.156, 0.008, False), (0.400, 0.130, True)],
    ids=["exact", "within-10-mm", "long-gap"],
)
def test_a_reducer_in_a_longer_gap_says_how_far_it_may_lie_either_way(gap, either_way, noted):
    """The shots bound each pipe's end from inside: a 6 x 4 reducer (H 140 mm) in a 400 mm gap
    may lie anywhere in it, 130 mm either way of the middle where it is built."""
    pipes = [
        Pipe("P1", (-1.5, 0, 1), (0, 0, 1), 0.1683),
        Pipe("P2", (gap, 0, 1), (gap + 1.5, 0, 1), 0.1143),
    ]
    model = merge_model(report_of(pipes, links=[("P1", "P2")]))
    reducer = next(c for c in model.components if c.type == "reducer")
    assert reducer.snap["position_range"] == pytest.approx(either_way, abs=1e-9)
    said = [n for n in reducer.snap["notes"] if "either way" in n]
    assert said == (
        [
            "the reducer fills 140 of the 400 mm between P1's and P2's shots: built in the "
            "middle, it may lie up to 130 mm either way along the line; scan up to it to place it"
        ]
        if noted
        else []
    )
