"""Tees whose run the scan's links do not name: the geometry decides, the links only join.

A straight run scanned as two pipes (0 and 1, collinear, butting or nearly so) and a branch (2)
square-on at their joint is a tee whichever of the three pairs the operator links: links say
which objects are contiguous, not that the others are not. Truth values are the hand-drawn
geometry below (NPS 4, OD 114.3 mm; ``joint_distance`` 0.15 m).
"""

from __future__ import annotations

import numpy as np
import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.merge.contiguity import find_joints
from asbuilt.merge.spool import connection_mismatches

OD = 0.1143

# a run along x split at x = 2 with a 0.2 m gap, the branch along +y stopping 0.15 m from the
# run axis (within the branch allowance OD + joint_distance = 0.264 m)
GAP_TEE = (((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)), ((2, 0.15, 0), (2, 2, 0)))
# the run pipes butt at x = 2, the branch stops 60 mm from the axis (on the run pipe's wall)
BUTT_TEE = (((0, 0, 0), (2, 0, 0)), ((2, 0, 0), (4, 0, 0)), ((2, 0.06, 0), (2, 2, 0)))
# a vertical branch dropping onto the joint, the run pipes 30 mm apart
DROP_TEE = (((0, 0, 0), (1.985, 0, 0)), ((2.015, 0, 0), (4, 0, 0)), ((2, 0, 0.1), (2, 0, 1.5)))


def segments(pairs):
    """centers (n, 3) m, unit axes (n, 3), lengths (n,) m of pipes given as (start, end)."""
    starts = np.array([p[0] for p in pairs], float)
    ends = np.array([p[1] for p in pairs], float)
    vec = ends - starts
    lengths = np.linalg.norm(vec, axis=1)
    return (starts + ends) / 2, vec / lengths[:, None], lengths


def joints_of(pairs, links):
    c, a, lengths = segments(pairs)
    return find_joints(c, a, lengths, np.full(len(c), OD), links=links)


TEE_LINKS = [
    pytest.param([(0, 2)], id="branch-linked-to-first-run-pipe"),
    pytest.param([(2, 0)], id="branch-linked-to-first-run-pipe-reversed"),
    pytest.param([(1, 2)], id="branch-linked-to-second-run-pipe"),
    pytest.param([(2, 1)], id="branch-linked-to-second-run-pipe-reversed"),
    pytest.param([(0, 2), (1, 2)], id="branch-linked-to-both-run-pipes"),
    pytest.param([(2, 1), (0, 2)], id="branch-linked-to-both-run-pipes-other-order"),
    pytest.param([(0, 1)], id="only-the-run-linked"),
    pytest.param([], id="nothing-linked"),
]


@pytest.mark.parametrize("pairs", [GAP_TEE, BUTT_TEE, DROP_TEE], ids=["gap", "butt", "drop"])
@pytest.mark.parametrize("links", TEE_LINKS)
def test_a_run_and_a_square_on_branch_are_a_tee_whatever_is_linked(pairs, links):
    joints = joints_of(pairs, links)
    assert [j.kind for j in joints] == ["tee"]
    tee = joints[0]
    assert tee.branch == (2, 0)
    # the run ends are the two facing ends of pipes 0 and 1
    assert set(tee.ends[:2]) == {(0, 1), (1, 0)} and tee.through is None


# the branch stops 0.4 m from the run axis (shots missed near the tee): beyond the branch
# allowance of 0.264 m by geometry alone, within it + LINK_MARGIN (0.764 m) when linked
FAR_TEE = (((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)), ((2, 0.4, 0), (2, 2, 0)))


@pytest.mark.parametrize(
    ("links", "expected"),
    [
        pytest.param([(0, 2)], ["tee"], id="branch-linked"),
        pytest.param([(2, 1)], ["tee"], id="branch-linked-to-second-run-pipe"),
        pytest.param([(0, 2), (0, 1)], ["tee"], id="branch-and-run-linked"),
        pytest.param([(0, 2), (1, 2)], ["tee"], id="branch-linked-to-both"),
        # unlinked, the branch is too far from the run to be a tee: the run alone is joined
        pytest.param([(0, 1)], ["inline"], id="only-the-run-linked"),
        pytest.param([], ["inline"], id="nothing-linked"),
    ],
)
def test_a_linked_branch_short_of_the_run_gets_the_link_margin(links, expected):
    """Links [P1, P2] made an elbow P1-P2 beside the collinear P3, and links [P1, P2], [P1, P3]
    an inline joint and a contact: no tee, although the link vouches for the branch as it does
    for every other joint's distances."""
    joints = joints_of(FAR_TEE, links)
    assert [j.kind for j in joints] == expected
    if expected == ["tee"]:
        assert joints[0].branch == (2, 0) and set(joints[0].ends[:2]) == {(0, 1), (1, 0)}


@pytest.mark.parametrize(
    ("pairs", "links", "expected"),
    [
        pytest.param(
            # P1 ends where P2 starts and nothing continues the run: a genuine elbow
            (((0, 0, 0), (1.9, 0, 0)), ((2, 0.15, 0), (2, 2, 0))),
            [(0, 1)],
            [("elbow", ((0, 1), (1, 0)))],
            id="elbow-pair-linked",
        ),
        pytest.param(
            (((0, 0, 0), (1.9, 0, 0)), ((2, 0.15, 0), (2, 2, 0))),
            [],
            [("elbow", ((0, 1), (1, 0)))],
            id="elbow-pair-unlinked",
        ),
        pytest.param(
            # a parallel pipe 0.3 m above the first one's line is not its run (axes 0.3 m apart,
            # the skew tolerance is 28.6 mm): the linked elbow stays
            (((0, 0, 0), (1.9, 0, 0)), ((2, 0.15, 0), (2, 2, 0)), ((2.1, 0, 0.3), (4, 0, 0.3))),
            [(0, 1)],
            [("elbow", ((0, 1), (1, 0)))],
            id="elbow-with-a-parallel-pipe-off-its-line",
        ),
        pytest.param(
            # the linked elbow's partner pipe continues 0.3 m below the run line: no run, elbow
            (((0, 0, 0), (1.9, 0, 0)), ((2, 0.15, 0), (2, 2, 0)), ((2.1, 0, -0.3), (4, 0, -0.3))),
            [(1, 0)],
            [("elbow", ((0, 1), (1, 0)))],
            id="elbow-with-a-parallel-pipe-below",
        ),
        pytest.param(
            # a four-way cross linked as two elbows (0-2 and 1-3): the run's second pipe is
            # linked to the opposite branch at that end, so the links keep both elbows
            (
                ((0, 0, 0), (1.9, 0, 0)),
                ((2.1, 0, 0), (4, 0, 0)),
                ((2, 0.15, 0), (2, 2, 0)),
                ((2, -0.15, 0), (2, -2, 0)),
            ),
            [(0, 2), (1, 3)],
            [("elbow", ((0, 1), (2, 0))), ("elbow", ((1, 0), (3, 0)))],
            id="cross-linked-as-two-elbows",
        ),
        pytest.param(
            # the branch crosses 0.2 m above the run's joint without touching it (its axis misses
            # the run axis by 0.2 m, beyond the 28.6 mm skew tolerance): the run is inline and
            # the link is not realised (kind "link", with a note), never a tee
            (((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)), ((2, -2, 0.2), (2, 2, 0.2))),
            [(0, 2)],
            [("inline", ((0, 1), (1, 0))), ("link", ((0, 0), (2, 0)))],
            id="branch-crossing-above-the-joint-linked",
        ),
        pytest.param(
            (((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)), ((2, -2, 0.2), (2, 2, 0.2))),
            [],
            [("inline", ((0, 1), (1, 0)))],
            id="branch-crossing-above-the-joint-unlinked",
        ),
        pytest.param(
            # the branch ends over the run but 0.25 m to the side of the joint, squarely on the
            # second run pipe: a tee through that pipe would need room, the linked elbow cannot
            # reach; never a tee at the joint (its axis misses the joint by 0.25 m)
            (((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)), ((2.35, 0.15, 0), (2.35, 2, 0))),
            [(0, 2)],
            None,
            id="branch-off-the-joint-linked",
        ),
    ],
)
def test_elbows_and_near_misses_stay_what_they_are(pairs, links, expected):
    joints = joints_of(pairs, links)
    if expected is None:
        assert not any(j.kind == "tee" and j.through is None for j in joints)
    else:
        assert [(j.kind, j.ends) for j in joints] == expected


@pytest.mark.parametrize("links", [[("P1", "P2")], [("P2", "P3")], [("P1", "P2"), ("P2", "P3")]])
def test_the_model_has_the_tee_and_the_whole_run(links):
    """End to end: the model holds a tee joining all three pipes in one spool, and the run's
    two pipes meet the tee's run ends (no loose pipe; before the fix P1-P2 was an elbow and P3
    a separate spool)."""
    pipes = [
        Pipe("P1", (0, 0, 0), (1.9, 0, 0), OD),
        Pipe("P2", (2, 0.15, 0), (2, 2, 0), OD),
        Pipe("P3", (2.1, 0, 0), (4, 0, 0), OD),
    ]
    model = merge_model(report_of(pipes, links=links))
    types = sorted(c.type for c in model.components)
    assert types == ["pipe", "pipe", "pipe", "tee"]
    assert {c.spool for c in model.components} == {"S1"}
    found, bad = connection_mismatches(model.components, tolerance=1e-4)
    assert bad == [] and found == 3
