"""Four pipes meeting as a cross, or a pipe through another's joint: no fittings through each other.

Merging builds no cross (ASME B16.9 makes straight crosses, but the catalog has no cross
dimensions). With the scan linking the opposite pipes ([P1, P2], [P3, P4]) it built two
couplings through each other and no finding said so; with two pipes ending on either side of a
third running through, a coupling through that pipe. Now one straight run is a tee with one
branch, the fourth pipe is left unjoined, and one finding names the cross. Geometry hand-drawn:
NPS 4 (OD 114.3 mm) pipes ending 0.1-0.15 m from the crossing point.
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
def test_a_cross_is_one_tee_and_a_loose_fourth_pipe(links):
    model = merge_model(report_of(CROSS, links=links))
    # no two couplings through each other: one tee of the run P1-P2, the fourth pipe unjoined
    assert _fittings(model) == [("tee", ("P1", "P2", "P3"))]
    (loose,) = [c for c in model.components if c.snap.get("loose_ends")]
    assert loose.id == "P4"
    found = _joint_codes(check_model(model))
    assert found and not [f for f in found if f.code == "AB501"]
    # every finding names P4, the pipe merging left at the cross, and a cross
    assert all("P4" in f.objects and "cross" in f.message for f in found)


def test_the_opposite_links_say_why_they_are_not_joined():
    model = merge_model(report_of(CROSS, links=[("P1", "P2"), ("P3", "P4")]))
    (f,) = _joint_codes(check_model(model))
    assert (f.code, f.objects) == ("AB302", ("P3", "P4"))
    assert f.message.startswith(
        "the scan links P3 and P4, but a straight joint between them would pass through the "
        "joint of P1 and P2: the pipes meet there as a cross"
    )
    assert "P3 is joined to P1, P2 by a tee; P4 not joined there" in f.message
    assert "if P4 is welded there on site, the fitting is a cross: model it by hand" in f.message
    assert f.suggestions


def test_a_reducing_cross_keeps_the_run_and_a_reducing_tee():
    big = 0.1683  # NPS 6 run, NPS 4 branches
    pipes = [Pipe("P1", (0, 0, 0), (1.85, 0, 0), big), Pipe("P2", (2.15, 0, 0), (4, 0, 0), big)]
    model = merge_model(report_of([*pipes, P3, P4], links=[("P3", "P4"), ("P1", "P2")]))
    assert _fittings(model) == [("tee", ("P1", "P2", "P3"))]
    (f,) = _joint_codes(check_model(model))
    assert f.code == "AB302" and f.objects == ("P3", "P4") and "cross" in f.message


@pytest.mark.parametrize("links", [[], [("P3", "P4")]], ids=["unlinked", "linked"])
def test_no_coupling_through_a_pipe_running_through(links):
    model = merge_model(report_of([THROUGH, P3, P4], links=links))
    # a tee splitting P1 with one branch; no coupling P3-P4 through P1, no second tee there
    (tee,) = [c for c in model.components if c.type != "pipe"]
    assert tee.type == "tee" and "P3" in tee.snap["connects"]
    found = _joint_codes(check_model(model))
    assert not [f for f in found if f.code == "AB501"]
    (f,) = found
    assert "P4" in f.objects and "cross" in f.message
    assert f.code == ("AB302" if links else "AB304")


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
