"""Reducing elbows (two pipe sizes at one elbow): ASME B16.9 makes them only as 90 degree
long-radius elbows of listed pairs, centre-to-end A that of the large end's 90 degree LR elbow.

Truth, typed from the wermac.org table "Dimensions Butt Weld Reducing Elbows 90 deg LR ASME
B16.9" (large x small, A in mm): 6 x 4 229, 6 x 3 229, 8 x 5 305, 12 x 6 457, 24 x 12 914; NPS 6
reduces to 5, 4, 3 1/2, 3 only (no 6 x 2). ODs from ASME B36.10M.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.merge.spool import connection_mismatches
from asbuilt.rules import check_model

OD = {
    "2": 0.0603,
    "3": 0.0889,
    "4": 0.1143,
    "5": 0.1413,
    "6": 0.1683,
    "8": 0.2191,
    "12": 0.3238,
    "24": 0.610,
}
ROWS = [("6", "4", 229), ("6", "3", 229), ("8", "5", 305), ("12", "6", 457), ("24", "12", 914)]
CORNER = np.array([0.0, 0.0, 1.0])


def _bend(angle_deg, reach, od_1, od_2):
    """P1 along +x ending ``reach`` before a corner at the origin (z = 1); P2 leaving it at
    ``angle_deg``, starting ``reach`` after it."""
    d = np.array([math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg)), 0.0])
    return [
        Pipe("P1", (-1.2 - reach, 0, 1), (-reach, 0, 1), od_1),
        Pipe("P2", tuple(reach * d + CORNER), tuple((reach + 1.2) * d + CORNER), od_2),
    ]


def _elbow(model):
    (elbow,) = [c for c in model.components if c.type == "elbow"]
    return elbow


def _notes(model, pid):
    comp = next(c for c in model.components if c.id == pid)
    return list((comp.snap or {}).get("merge_notes") or [])


@pytest.mark.parametrize(("large", "small", "a"), ROWS)
def test_a_listed_90_degree_reducing_elbow_is_standard_with_its_a(large, small, a):
    pipes = _bend(90, a / 1000, OD[large], OD[small])
    model = merge_model(report_of(pipes, links=[("P1", "P2")]))
    elbow = _elbow(model)
    g = elbow.geometry
    assert elbow.snap["standard"] is True
    for end in (g.start, g.end):
        assert np.linalg.norm(end - CORNER) == pytest.approx(a / 1000, abs=1e-6)
    assert sorted(2 * r for r in g.radii) == pytest.approx(sorted([OD[large], OD[small]]))
    assert connection_mismatches(model.components, tolerance=1e-4)[1] == []
    assert not [f for f in check_model(model) if f.code == "AB302"]


def test_a_45_degree_reducing_elbow_is_not_standard():
    """B16.9 makes no 45 degree reducing elbow: it was `standard: true`, nothing said."""
    reach = 0.095  # NPS 6 45 degree LR centre-to-end B
    model = merge_model(report_of(_bend(45, reach, OD["6"], OD["4"]), links=[("P1", "P2")]))
    elbow = _elbow(model)
    assert elbow.snap["standard"] is False
    # built on the NPS 6 45 degree elbow's B, not cut from a 90: that note and record, which
    # also said "no ASME B16.9 elbow" turns 45 degrees, were added too before
    assert elbow.snap["dimensions"] == "asme-b16.9, reducing elbow at 45 degrees (non-standard)"
    assert not [n for n in _notes(model, "P1") if "cut to" in n or "no ASME B16.9 elbow" in n]
    said = [n for n in _notes(model, "P1") if "reducing elbow" in n]
    assert len(said) == 1 and "45 degrees" in said[0] and "90 degree long-radius" in said[0]
    assert said == [n for n in _notes(model, "P2") if "reducing elbow" in n]
    assert any(f.code == "AB302" and "reducing elbow" in f.message for f in check_model(model))


def test_a_pair_b16_9_does_not_make_is_not_standard():
    """NPS 6 x 2: NPS 6 reducing elbows reduce to 5, 4, 3 1/2 or 3 only."""
    model = merge_model(report_of(_bend(90, 0.229, OD["6"], OD["2"]), links=[("P1", "P2")]))
    elbow = _elbow(model)
    assert elbow.snap["standard"] is False
    assert elbow.snap["dimensions"] == "asme-b16.9 radius; no such reducing elbow (non-standard)"
    assert not [n for n in _notes(model, "P1") if "cut to" in n or "no ASME B16.9 elbow" in n]
    said = [n for n in _notes(model, "P1") if "reducing elbow" in n]
    assert len(said) == 1 and "6 x 2" in said[0] and "5, 4, 3 1/2, 3 only" in said[0]


def test_a_large_end_the_list_does_not_cover_gets_no_verdict_on_its_sizes():
    """NPS 3 x 2: the source lists no large end below NPS 4, so no verdict (as before)."""
    model = merge_model(report_of(_bend(90, 0.114, OD["3"], OD["2"]), links=[("P1", "P2")]))
    assert _elbow(model).snap["standard"] is True


def test_short_radius_asked_a_reducing_elbow_is_the_long_radius_one():
    """B16.9 has no short-radius reducing elbow: with elbow_radius="short" the 6 x 4 was built
    on the NPS 6 short radius (152 mm) and called a B16.9 fitting; the B16.9 one has A 229 mm."""
    pipes = _bend(90, 0.229, OD["6"], OD["4"])
    model = merge_model(report_of(pipes, links=[("P1", "P2")]), elbow_radius="short")
    elbow = _elbow(model)
    g = elbow.geometry
    assert np.linalg.norm(g.start - CORNER) == pytest.approx(0.229, abs=1e-6)
    assert elbow.snap["standard"] is True
    assert any("no short-radius reducing elbow" in n for n in elbow.snap["notes"])
