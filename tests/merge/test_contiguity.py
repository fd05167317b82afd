"""Joints between pipes: inferred from geometry and taken from the scan's links."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.merge.contiguity import (
    connected_groups,
    find_joints,
    joint_pairs,
    line_closest_points,
    pipe_ends,
)

OD = 0.1143


def segments(*pairs):
    """centers, axes, lengths of pipes given as (start, end) pairs."""
    starts = np.array([p[0] for p in pairs], float)
    ends = np.array([p[1] for p in pairs], float)
    vec = ends - starts
    lengths = np.linalg.norm(vec, axis=1)
    return (starts + ends) / 2, vec / lengths[:, None], lengths


def joints_of(*pairs, links=(), ods=None, slack=None):
    c, a, l = segments(*pairs)  # noqa: E741
    ods = np.full(len(c), OD) if ods is None else np.asarray(ods)
    return find_joints(c, a, l, ods, links=links, slack=slack)


def test_pipe_ends():
    c, a, l = segments(((0, 0, 0), (2, 0, 0)))  # noqa: E741
    points, outward = pipe_ends(c, a, l)
    assert np.allclose(points[0], [[0, 0, 0], [2, 0, 0]])
    assert np.allclose(outward[0], [[-1, 0, 0], [1, 0, 0]])


def test_line_closest_points():
    s, t, q1, q2 = line_closest_points(
        np.zeros(3), np.array([1.0, 0, 0]), np.array([2.0, -1, 0.1]), np.array([0, 1.0, 0])
    )
    assert (s, t) == pytest.approx((2.0, 1.0))
    assert q1 == pytest.approx([2, 0, 0]) and q2 == pytest.approx([2, 0, 0.1])


def test_elbow_inferred_with_a_gap_before_the_fitting():
    joints = joints_of(((0, 0, 0), (1.8, 0, 0)), ((2, 0.2, 0), (2, 2, 0)))
    assert [(j.kind, j.ends) for j in joints] == [("elbow", ((0, 1), (1, 0)))]


@pytest.mark.parametrize(
    "pairs",
    [
        # too far from the meeting point (0.6 m each)
        (((0, 0, 0), (1.4, 0, 0)), ((2, 0.6, 0), (2, 2, 0))),
        # axes pass 0.1 m apart (skew), beyond half a radius
        (((0, 0, 0), (1.8, 0, 0)), ((2, 0.2, 0.1), (2, 2, 0.1))),
        # parallel pipes side by side in a rack
        (((0, 0, 0), (2, 0, 0)), ((0, 0.3, 0), (2, 0.3, 0))),
        # collinear but both ends point the same way (overlapping side by side)
        (((0, 0, 0), (2, 0, 0)), ((1, 0, 0), (3, 0, 0))),
    ],
)
def test_no_joint(pairs):
    assert joints_of(*pairs) == ()


def test_inline_joint_and_its_gap_limit():
    assert joints_of(((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)))[0].kind == "inline"
    assert joints_of(((0, 0, 0), (1.0, 0, 0)), ((2.1, 0, 0), (4, 0, 0))) == ()


def test_a_link_joins_pipes_beyond_the_distance_limits():
    pairs = (((0, 0, 0), (1.4, 0, 0)), ((2, 0.6, 0), (2, 2, 0)))
    joints = joints_of(*pairs, links=[(0, 1)])
    assert len(joints) == 1 and joints[0].kind == "elbow" and joints[0].explicit


def test_a_link_without_meeting_geometry_is_an_unrealised_link():
    # parallel pipes 0.3 m apart: the link still pools their size estimate (joint_pairs) but
    # joins them in no spool (connected_groups)
    pairs = (((0, 0, 0), (2, 0, 0)), ((0, 0.3, 0), (2, 0.3, 0)))
    joints = joints_of(*pairs, links=[(1, 0)])
    assert [j.kind for j in joints] == ["link"]
    assert joint_pairs(joints) == [(0, 1)]
    assert connected_groups(2, joints) == [[0], [1]]


def test_tee_at_an_inline_joint():
    joints = joints_of(
        ((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)), ((2, 0.15, 0), (2, 2, 0))
    )
    assert len(joints) == 1
    tee = joints[0]
    assert tee.kind == "tee" and tee.through is None
    assert tee.branch == (2, 0)
    assert set(tee.pipes) == {0, 1, 2}


@pytest.mark.parametrize(
    "links",
    [
        [(0, 1), (0, 2)],  # the run and the branch on its first pipe
        [(0, 2), (0, 1)],
        [(0, 1), (1, 2)],
        [(0, 1), (0, 2), (1, 2)],
    ],
)
def test_linked_tees_stay_tees(links):
    """Links P1-P3 (the run) and P1-P2 (the branch) made an elbow P1-P2 first, in id order,
    and left the run's link a contact: the tee and 0.44 m of run missing from the model
    (independent ray-cast plant, audit)."""
    joints = joints_of(
        ((0, 0, 0), (1.9, 0, 0)), ((2.1, 0, 0), (4, 0, 0)), ((2, 0.15, 0), (2, 2, 0)), links=links
    )
    assert [j.kind for j in joints] == ["tee"]
    assert joints[0].branch == (2, 0) and set(joints[0].pipes) == {0, 1, 2}


def test_tee_in_the_middle_of_a_pipe():
    joints = joints_of(((0, 0, 0), (4, 0, 0)), ((2, 0.15, 0), (2, 2, 0)))
    assert [(j.kind, j.through, j.ends) for j in joints] == [("tee", 0, ((1, 0),))]


def test_a_slanted_branch_is_not_a_tee():
    joints = joints_of(((0, 0, 0), (4, 0, 0)), ((2.1, 0.1, 0), (3.5, 1.5, 0)))
    assert all(j.kind != "tee" for j in joints)


def test_the_straight_pair_is_the_run_and_the_third_pipe_the_branch():
    # P2 ends where P1 and P3 meet: P1-P3 (straight on, nearest) is the run, P2 the branch
    joints = joints_of(
        ((0, 0, 0), (1.95, 0, 0)), ((2.0, -1.8, 0), (2.0, -0.2, 0)), ((2.05, 0, 0), (4, 0, 0))
    )
    assert [(j.kind, j.ends) for j in joints] == [("tee", ((0, 1), (2, 0), (1, 1)))]


def test_many_pipes_are_paired_locally():
    """A grid of 200 separate L-pairs: exactly 200 elbows and no cross-talk."""
    pairs = []
    for k in range(200):
        ox, oy = (k % 20) * 5.0, (k // 20) * 5.0
        pairs.append(((ox, oy, 0), (ox + 1.8, oy, 0)))
        pairs.append(((ox + 2, oy + 0.2, 0), (ox + 2, oy + 2, 0)))
    joints = joints_of(*pairs)
    assert len(joints) == 200
    assert all(j.kind == "elbow" and j.pipes[1] - j.pipes[0] == 1 for j in joints)


def test_an_end_past_another_pipe_s_corner_is_not_its_elbow():
    """An independent review's rack (fitted ends, metres): NPS 6 P1 and P2 turn at (3, 0),
    NPS 4 Q1 and Q2 at (2.6, 0.4); P1's shots run 40 mm past Q2's axis. Ranked by the ends'
    distance to the corner, P1-Q2 (0.63 m) came before Q1-Q2 (0.64 m) and P1-P2 (0.74 m): a
    6 x 4 reducing elbow cutting 270 mm of measured pipe off P1, and neither true elbow. Ranked
    by the distance to where each elbow would end (its centre-to-end from the corner), the two
    true elbows are the cheapest."""
    joints = joints_of(
        ((0.201, 0, 2), (2.64, 0, 2)),
        ((3.0, 0.375, 2), (3.0, 2.265, 2)),
        ((0.247, 0.398, 2), (2.153, 0.398, 2)),
        ((2.599, 0.59, 2), (2.6, 2.291, 2)),
        ods=[0.1685, 0.1678, 0.1122, 0.1127],
        slack=[0.25, 0.25, 0.25, 0.25],  # the shots' spacing along the pipes, about a raster row
    )
    assert sorted((j.kind, j.pipes) for j in joints) == [("elbow", (0, 1)), ("elbow", (2, 3))]


def test_a_tee_wins_over_an_elbow_when_the_branch_ends_nearer():
    # the branch stops 5 cm from the run axis, the run pipes 20 cm from the centre
    joints = joints_of(
        ((0, 0, 0), (1.8, 0, 0)), ((2.2, 0, 0), (4, 0, 0)), ((2, 0.05, 0), (2, 2, 0))
    )
    assert [(j.kind, j.ends) for j in joints] == [("tee", ((0, 1), (1, 0), (2, 0)))]


def test_a_four_way_cross_is_one_cross_joint_of_the_four_ends():
    """A tee with a fourth end opposite its outlet, on its line: a cross (merge.crosses)."""
    joints = joints_of(
        ((0, 0, 0), (1.8, 0, 0)),
        ((2.2, 0, 0), (4, 0, 0)),
        ((2, 0.2, 0), (2, 2, 0)),
        ((2, -0.2, 0), (2, -2, 0)),
    )
    assert [j.kind for j in joints] == ["cross"]
    assert sorted(joints[0].pipes) == [0, 1, 2, 3]


class _Link:
    def __init__(self, *pipes):
        self.pipes = pipes


@pytest.mark.parametrize(
    ("n", "links", "groups"),
    [
        (3, [], [[0], [1], [2]]),
        (4, [(2, 0), (1, 3)], [[0, 2], [1, 3]]),
        (5, [(4, 3), (3, 1, 2)], [[0], [1, 2, 3, 4]]),  # a tee joins three pipes
    ],
)
def test_connected_groups_are_the_spools(n, links, groups):
    assert connected_groups(n, [_Link(*pipes) for pipes in links]) == groups
