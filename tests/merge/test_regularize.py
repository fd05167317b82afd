"""Orientation regularisation (GlobFit-style relations made exact) and line alignment."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.merge.contiguity import line_closest_points
from asbuilt.merge.regularize import align_lines, perpendicular_basis, regularize_directions
from asbuilt.rules import check_model
from asbuilt.tolerances import Tolerances


def tilted(base, towards, degrees):
    """Unit vector ``base`` rotated by ``degrees`` towards ``towards`` (both unit, orthogonal)."""
    a = np.radians(degrees)
    return np.cos(a) * np.asarray(base, float) + np.sin(a) * np.asarray(towards, float)


X, Y, Z = np.eye(3)


@pytest.mark.parametrize(
    ("axis", "expected", "relation", "angle"),
    [
        (tilted(Z, X, 1.5), Z, "vertical", 1.5),
        (tilted(X, Z, 1.0), X, "horizontal", 1.0),
        (tilted(X, Z, -1.9), X, "horizontal", 1.9),
        (tilted(Z, X, 3.0), tilted(Z, X, 3.0), None, 0.0),  # beyond 2 degrees: left alone
        (tilted(X, Z, 5.0), tilted(X, Z, 5.0), None, 0.0),
    ],
)
def test_single_axis(axis, expected, relation, angle):
    result = regularize_directions([axis], [1.0], tol_deg=2.0, names=["P1"])
    assert result.axes[0] == pytest.approx(expected, abs=1e-12)
    assert result.angles_deg[0] == pytest.approx(angle, abs=1e-9)
    assert (relation in result.relations[0]) if relation else not result.relations[0]


def test_tolerance_is_configurable():
    axis = tilted(Z, X, 3.0)
    result = regularize_directions([axis], [1.0], tol_deg=5.0)
    assert result.axes[0] == pytest.approx(Z)


def test_near_parallel_axes_become_exactly_parallel():
    a = tilted(tilted(X, Y, 30), Z, 5)
    b = tilted(tilted(X, Y, 31), Z, 5)
    result = regularize_directions([a, b], [2.0, 1.0], tol_deg=2.0, names=["P1", "P2"])
    assert abs(result.axes[0] @ result.axes[1]) == pytest.approx(1.0, abs=1e-12)
    assert "parallel to P1" in result.relations[1]
    # the longer pipe moves less
    assert result.angles_deg[0] < result.angles_deg[1]


def test_opposite_senses_are_parallel_and_keep_their_sense():
    result = regularize_directions([X, -tilted(X, Y, 1)], [1, 1], tol_deg=2.0)
    assert result.axes[0] @ result.axes[1] == pytest.approx(-1.0)
    assert result.axes[1] @ -X > 0.999
    assert result.angles_deg == pytest.approx([0.5, 0.5])


def test_near_perpendicular_horizontal_axes_become_exactly_perpendicular():
    a = tilted(X, Y, 10)
    b = tilted(X, Y, 98.5)  # 88.5 degrees from a
    result = regularize_directions([a, b], [3.0, 1.0], tol_deg=2.0, names=["P1", "P2"])
    assert result.axes[0] @ result.axes[1] == pytest.approx(0.0, abs=1e-12)
    assert result.axes[1][2] == pytest.approx(0.0)
    assert result.axes[0] == pytest.approx(a)  # the heavier one is the reference
    assert "perpendicular to P1" in result.relations[1]


def test_relations_are_found_between_measured_axes_so_snaps_do_not_chain():
    # P2 is 0.63 degrees off horizontal, P1 is 17 degrees off it and 2.1 degrees off square to
    # P2. P2 becomes horizontal, which brings the pair within 2 degrees of square, but the pair
    # was not measured square and must stay 2 degrees off (less the horizontal snap's share).
    p1 = np.array([0.95533649, 0.0, -0.29552021])
    p2 = np.array([0.03542363, 0.99931231, -0.01095781])
    assert 87.8 < np.degrees(np.arccos(p1 @ p2)) < 87.9
    result = regularize_directions([p1, p2], [1.0, 1.1], tol_deg=2.0, names=["P1", "P2"])
    assert result.relations == ((), ("horizontal",))
    assert result.axes[0] == pytest.approx(p1)
    angle = np.degrees(np.arccos(abs(result.axes[0] @ result.axes[1])))
    assert 87.9 < angle < 88.2


def test_parallel_groups_are_forced_together_beyond_the_tolerance():
    a, b = X, tilted(X, Y, 6.0)
    loose = regularize_directions([a, b], [1, 1], tol_deg=2.0)
    assert loose.axes[1] == pytest.approx(b)
    forced = regularize_directions([a, b], [1, 1], tol_deg=2.0, parallel_groups=[[0, 1]])
    assert forced.axes[0] @ forced.axes[1] == pytest.approx(1.0)
    assert forced.cluster[0] == forced.cluster[1]


@pytest.mark.parametrize(
    ("stderr", "expected_vertical"),
    [
        (0.2, False),  # 3 x 0.2 = 0.6 degree: a 2.2 degree lean is measured, kept
        (0.9, False),  # 2.7 degrees allowed by the errors, but no more than the 2 degree tolerance
        (3.0, True),  # a stub known to 3 degrees: 2.2 is noise, built vertical (up to 10)
    ],
)
def test_a_poorly_measured_axis_is_regularised_beyond_the_tolerance(stderr, expected_vertical):
    axis = tilted(Z, X, 2.2)
    capped = regularize_directions([axis], [0.1], tol_deg=2.0, stderr_deg=[stderr])
    assert capped.axes[0] == pytest.approx(axis)  # without max_deg the tolerance caps it
    result = regularize_directions(
        [axis], [0.1], tol_deg=2.0, stderr_deg=[stderr], max_deg=10.0 if stderr > 1 else 2.0
    )
    assert (result.axes[0] == pytest.approx(Z)) is expected_vertical


def test_no_relation_beyond_max_deg_whatever_the_errors():
    axis = tilted(Z, X, 12.0)
    result = regularize_directions([axis], [0.1], tol_deg=2.0, stderr_deg=[8.0], max_deg=10.0)
    assert result.axes[0] == pytest.approx(axis)
    assert not result.relations[0]


@pytest.mark.parametrize("measured", [41.0, 45.0, 47.7, 49.5])
def test_a_stub_at_about_45_degrees_to_its_elbow_partner_is_made_45(measured):
    # a jog: P1 and P3 level along x, the stub P2 between them turned ~45 degrees in plan and
    # 1 degree off level, its axis known to 3.5 degrees (a 60 mm stub)
    p1, p3 = X, tilted(X, Y, 0.1)
    stub = tilted(tilted(X, Y, measured), Z, 1.0)
    result = regularize_directions(
        [p1, stub, p3],
        [2.0, 0.06, 1.5],
        tol_deg=2.0,
        names=["P1", "P2", "P3"],
        stderr_deg=[0.05, 3.5, 0.05],
        max_deg=10.0,
        elbow_pairs=[(0, 1), (1, 2)],
    )
    p1_new, stub_new, p3_new = result.axes
    assert np.degrees(np.arccos(stub_new @ p1_new)) == pytest.approx(45.0, abs=1e-9)
    assert np.degrees(np.arccos(stub_new @ p3_new)) == pytest.approx(45.0, abs=1e-9)
    assert stub_new[2] == pytest.approx(0.0, abs=1e-12)  # still level
    assert any("45 degrees to" in r for r in result.relations[1])
    assert "horizontal" in result.relations[1]


def test_45_degrees_only_between_elbow_partners_and_within_the_errors():
    p1, stub = X, tilted(X, Y, 47.7)
    common = dict(tol_deg=2.0, names=["P1", "P2"], max_deg=10.0)
    unjoined = regularize_directions([p1, stub], [2, 0.06], stderr_deg=[0.05, 3.5], **common)
    assert unjoined.axes[1] == pytest.approx(stub)
    precise = regularize_directions(
        [p1, stub], [2, 0.06], stderr_deg=[0.05, 0.3], elbow_pairs=[(0, 1)], **common
    )
    assert precise.axes[1] == pytest.approx(stub)  # 2.7 degrees off 45 at 0.3: measured
    joined = regularize_directions(
        [p1, stub], [2, 0.06], stderr_deg=[0.05, 3.5], elbow_pairs=[(0, 1)], **common
    )
    assert np.degrees(np.arccos(joined.axes[1] @ X)) == pytest.approx(45.0)
    assert joined.angles_deg[1] == pytest.approx(2.7)


def test_a_riser_offset_is_made_45_degrees_to_the_vertical_riser():
    riser, offset = Z, tilted(tilted(Z, X, 43.0), Y, 1.5)
    result = regularize_directions(
        [riser, offset],
        [3.0, 0.3],
        tol_deg=2.0,
        names=["R1", "R2"],
        stderr_deg=[0.05, 1.5],
        max_deg=10.0,
        elbow_pairs=[(0, 1)],
    )
    assert np.degrees(np.arccos(result.axes[1] @ Z)) == pytest.approx(45.0)
    assert "45 degrees to R1" in result.relations[1]


@pytest.mark.parametrize("turn", [-2.7, 2.7])
def test_a_jog_with_a_short_stub_is_built_with_two_standard_45_degree_elbows(turn):
    # an NPS 4 jog (ASME B16.9 45 degree elbows, 63.5 mm centre to end, corners at x = 2 m and
    # one elbow's diagonal on): the 60 mm stub's axis fitted 2.7 degrees off, known to 3.5
    corner = np.array([2.0, 0.0, 1.3])
    diagonal = tilted(X, Y, 45.0)
    stub_mid = corner + (0.0635 + 0.03) * diagonal
    stub_axis = tilted(diagonal, tilted(Y, X, 45.0) * [-1, 1, 1], turn)
    second = corner + 2 * (0.0635 + 0.03) * diagonal
    pipes = [
        Pipe("P1", (0.0, 0.0, 1.3), tuple(corner - [0.0635, 0, 0]), 0.1143, se_axis_deg=0.05),
        Pipe(
            "P2",
            tuple(stub_mid - 0.03 * stub_axis),
            tuple(stub_mid + 0.03 * stub_axis),
            0.1143,
            se_axis_deg=3.5,
        ),
        Pipe(
            "P3",
            tuple(second + [0.0635, 0, 0]),
            tuple(second + [2.0, 0, 0]),
            0.1143,
            se_axis_deg=0.05,
        ),
    ]
    capped = merge_model(report_of(pipes), tolerances=Tolerances(angle_snap_max_deg=2.0))
    assert {round(c.snap["angle_deg"], 6) for c in capped.components if c.type == "elbow"} == {
        round(45.0 + turn, 6)
    }
    model = merge_model(report_of(pipes))
    elbows = [c for c in model.components if c.type == "elbow"]
    assert len(elbows) == 2
    for elbow in elbows:
        assert elbow.snap["angle_deg"] == pytest.approx(45.0, abs=1e-6)
        assert elbow.snap["standard"] is True
    stub = next(c for c in model.components if c.id == "P2")
    assert any("45 degrees to" in c.what for c in stub.corrections)
    assert not [f for f in check_model(model) if f.code == "AB302"]


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)), min_size=1, max_size=12
    )
)
def test_regularised_axes_stay_unit_and_move_little(raw):
    axes = np.array([v for v in raw if np.linalg.norm(v) > 0.1], float)
    if len(axes) == 0:
        return
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    result = regularize_directions(axes, np.ones(len(axes)), tol_deg=2.0)
    assert np.allclose(np.linalg.norm(result.axes, axis=1), 1.0)
    assert np.all(np.einsum("ij,ij->i", result.axes, axes) > 0)  # same sense
    # clusters chain at most a few tolerances; nothing turns by a large angle
    assert result.angles_deg.max() < 10.0


def test_perpendicular_basis():
    for axis in (X, Y, Z, np.array([1, 1, 1]) / np.sqrt(3)):
        u, v = perpendicular_basis(axis)
        assert np.allclose([u @ axis, v @ axis, u @ v], 0)
        assert np.allclose([u @ u, v @ v], 1)


def test_align_lines_makes_skew_lines_meet_and_moves_sideways_only():
    centers = np.array([[0, 0, 0.0], [2, 1, 0.004]])
    axes = np.array([X, Y])
    new = align_lines(centers, axes, meets=[(0, 1)], coaxial=[])
    _, _, q1, q2 = line_closest_points(new[0], axes[0], new[1], axes[1])
    assert np.linalg.norm(q1 - q2) < 1e-9
    for k in range(2):
        assert (new[k] - centers[k]) @ axes[k] == pytest.approx(0.0, abs=1e-12)
    # equal weights share the 4 mm
    assert np.linalg.norm(new[0] - centers[0]) == pytest.approx(0.002, abs=1e-6)


def test_align_lines_makes_parallel_lines_coaxial_weighted():
    centers = np.array([[0, 0, 0.0], [3, 0.003, 0.0]])
    new = align_lines(centers, np.array([X, X]), meets=[], coaxial=[(0, 1)], weights=[3.0, 1.0])
    assert new[0][1] == pytest.approx(new[1][1], abs=1e-9)
    assert new[0][1] == pytest.approx(0.00075, abs=1e-7)  # the heavier line moves a quarter


def test_align_lines_without_constraints_changes_nothing():
    centers = np.array([[1.0, 2, 3]])
    assert np.array_equal(align_lines(centers, np.array([Z]), [], []), centers)


def test_align_lines_keeps_an_eccentric_pair_at_its_offset():
    """Two parallel lines 24 mm apart asked to sit 27 mm apart (eccentric NPS 6 x 4) move
    sideways only, sharing the 3 mm change in inverse proportion to their weights."""
    centers = np.array([[-1.25, 0.0, 1.0], [1.39, 0.002, 1.024]])
    axes = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    new = align_lines(
        centers, axes, [], [(0, 1)], weights=[1.0, 2.0], offsets=[np.array([0, 0, 0.027])]
    )
    step = new[1] - new[0]
    assert step[1:] == pytest.approx([0.0, 0.027], abs=1e-9)
    assert new[:, 0] == pytest.approx(centers[:, 0])
    # the weight-2 line moves half as far as the weight-1 line: 1 mm up, 2 mm down
    assert new[1, 2] - centers[1, 2] == pytest.approx(0.001, abs=1e-9)
    assert new[0, 2] - centers[0, 2] == pytest.approx(-0.002, abs=1e-9)
    coaxial = align_lines(centers, axes, [], [(0, 1)], offsets=[None])
    assert coaxial[1, 1:] == pytest.approx(coaxial[0, 1:], abs=1e-9)


# --- fit-up: joined axes that miss each other beyond the fits' uncertainty ---------------------
# An NPS 6 (OD 168.3 mm) 90 degree elbow, B16.9 long radius 229 mm, its second leg lifted out of
# plane by ``lift``. The synthetic fits' centre standard error is 1 mm and axis 0.2 degrees; each
# 1.5 m leg's centre is 0.229 + 0.75 = 0.979 m from the corner, so each axis is placed there to
# hypot(1 mm, 0.979 m x 0.2 deg) = 3.561 mm, the two together to 5.036 mm: the allowance is
# max(3 x 5.036, 6) = 15.11 mm.
FIT_UP_ALLOWED = 3 * np.hypot(*[np.hypot(0.001, 0.979 * np.radians(0.2))] * 2)


@pytest.mark.parametrize(
    ("lift", "reported"),
    [(0.0, False), (0.010, False), (0.014, False), (0.017, True), (0.030, True)],
)
def test_an_elbow_offset_beyond_the_fits_is_a_fit_up_finding(lift, reported):
    """A 30 mm offset at an elbow was absorbed silently ("axis shifted to meet P2 15.3 mm",
    no finding) although the fits place the axes to a few millimetres."""
    od, c2e = 0.1683, 0.229
    pipes = [
        Pipe("P1", (-c2e - 1.5, 0, 1), (-c2e, 0, 1), od),
        Pipe("P2", (0, c2e, 1 + lift), (0, c2e + 1.5, 1 + lift), od),
    ]
    model = merge_model(report_of(pipes, links=[("P1", "P2")]))
    assert [c.type for c in model.components] == ["pipe", "elbow", "pipe"]
    found = [f for f in check_model(model) if f.slug == "fit-up"]
    if not reported:
        assert found == []
        return
    (f,) = found
    assert f.code == "AB303" and f.severity == "warning" and f.objects == ("P1", "P2")
    assert f.measured == pytest.approx(lift, abs=1e-6)
    assert f.allowed == pytest.approx(FIT_UP_ALLOWED, rel=1e-3)
    assert f.stderr == pytest.approx(FIT_UP_ALLOWED / 3, rel=1e-3)
