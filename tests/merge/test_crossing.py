"""Four pipes meeting as a cross, or a pipe through another's joint: no fittings through each other.

With the scan linking the opposite pipes ([P1, P2], [P3, P4]) merging once built two couplings
through each other and no finding said so; with two pipes ending on either side of a third
running through, a coupling through that pipe. Then it built a tee and left the fourth pipe
unjoined; now both are one cross (merge.crosses; its own tests in test_crosses.py). Geometry
hand-drawn: NPS 4 (OD 114.3 mm) pipes ending 0.1-0.15 m from the crossing point.
"""

from __future__ import annotations

import itertools

import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.rules import check_model

OD = 0.1143
P1 = Pipe("P1", (0, 0, 0), (1.9, 0, 0), OD)
P2 = Pipe("P2", (2.1, 0, 0), (4, 0, 0), OD)
P3 = Pipe("P3", (2, 0.15, 0), (2, 2, 0), OD)
P4 = Pipe("P4", (2, -0.15, 0), (2, -2, 0), OD)
CROSS = [P1, P2, P3, P4]
THROUGH = Pipe("P1", (0, 0, 0), (4, 0, 0), OD)


def _fittings(model):
    return sorted(
        (c.type, tuple(c.snap.get("connects") or ())) for c in model.components if c.type != "pipe"
    )


def _joint_codes(found):
    return [f for f in found if f.code in ("AB302", "AB304", "AB501")]


@pytest.mark.parametrize(
    "links",
    [
        [("P1", "P2"), ("P3", "P4")],
        [("P3", "P4"), ("P1", "P2")],
        [("P1", "P2"), ("P3", "P4"), ("P1", "P3")],
        list(itertools.combinations(["P1", "P2", "P3", "P4"], 2)),
        [],
    ],
    ids=["opposite", "opposite-reversed", "opposite-and-branch", "all-pairs", "no-links"],
)
def test_a_cross_is_one_cross_whatever_the_links(links):
    model = merge_model(report_of(CROSS, links=links))
    # no two couplings through each other, no tee with a loose fourth pipe: one cross
    assert _fittings(model) == [("cross", ("P1", "P2", "P3", "P4"))]
    assert not [c for c in model.components if c.snap.get("loose_ends")]
    assert not _joint_codes(check_model(model))


def test_a_reducing_cross_has_the_larger_pair_as_its_run():
    big = 0.1683  # NPS 6 run, NPS 4 outlets; linked outlets first
    pipes = [Pipe("P1", (0, 0, 0), (1.85, 0, 0), big), Pipe("P2", (2.15, 0, 0), (4, 0, 0), big)]
    model = merge_model(report_of([*pipes, P3, P4], links=[("P3", "P4"), ("P1", "P2")]))
    assert _fittings(model) == [("cross", ("P1", "P2", "P3", "P4"))]
    assert not _joint_codes(check_model(model))


@pytest.mark.parametrize("links", [[], [("P3", "P4")]], ids=["unlinked", "linked"])
def test_no_coupling_through_a_pipe_running_through(links):
    model = merge_model(report_of([THROUGH, P3, P4], links=links))
    # a cross splitting P1 with both outlets; no coupling P3-P4 through P1
    (cross,) = [c for c in model.components if c.type != "pipe"]
    assert cross.type == "cross" and cross.snap["connects"] == ["P1.1", "P1.2", "P3", "P4"]
    assert not _joint_codes(check_model(model))


def test_linked_pipes_through_each_other_are_said_to_be():
    pipes = [THROUGH, Pipe("P2", (2, -2, 0), (2, 2, 0), OD)]
    model = merge_model(report_of(pipes, links=[("P1", "P2")]))
    (f,) = _joint_codes(check_model(model))
    assert f.code == "AB302" and f.objects == ("P1", "P2")
    assert "pass through each other" in f.message and " -" not in f.message


def test_a_pipe_through_a_tee_is_a_clash():
    model = merge_model(report_of([P1, P2, P3, Pipe("P5", (2, 0, -2), (2, 0, 2), OD)]))
    (f,) = [f for f in check_model(model) if f.code == "AB501"]
    assert set(f.objects) == {"P1-P2-P3", "P5"}
