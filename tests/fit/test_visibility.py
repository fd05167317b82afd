"""Free-space evidence: beam excess through a cylinder, and the MSAC score that uses it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq, minimize_scalar

from asbuilt.fit._visibility import (
    beam_entries,
    beyond_first_surface,
    cylinder_beam_excess,
    edge_on_degrees,
    excess_and_beyond,
    one_side_could_see,
    visible_score,
)

AXIS = np.array([0.0, 0.0, 1.0])
CENTER = np.zeros(3)


def _marched_excess(axis, center, radius, point, viewpoint, steps=200_001):
    """Independent truth: march along the beam and measure the length inside the cylinder
    from the entry point up to the shot's point, capped at the chord (as documented)."""
    t = np.linspace(0.0, 1.0, steps)
    beam = viewpoint + t[:, None] * (point - viewpoint)
    rel = beam - center
    across = rel - np.outer(rel @ axis, axis)
    inside = np.linalg.norm(across, axis=1) < radius
    if not inside.any():
        return 0.0
    length = np.linalg.norm(point - viewpoint)
    first = t[np.argmax(inside)] * length
    # Far end of the chord along the (infinite) beam line.
    line = viewpoint + np.linspace(0.0, 4.0, 4 * steps)[:, None] * (point - viewpoint)
    rel = line - center
    across = rel - np.outer(rel @ axis, axis)
    inside_line = np.linalg.norm(across, axis=1) < radius
    last = np.linspace(0.0, 4.0, 4 * steps)[np.flatnonzero(inside_line)[-1]] * length
    chord = last - first
    middle = 0.5 * (first + last)
    return float(np.clip(2.0 * (length - middle), 0.0, chord))


@pytest.mark.parametrize(
    "point, viewpoint, expected",
    [
        ([1.0, 0.0, 0.0], [10.0, 0.0, 0.0], 0.0),  # near side, square on
        ([-1.0, 0.0, 0.0], [10.0, 0.0, 0.0], 2.0),  # far side: the whole chord
        ([-5.0, 0.0, 0.0], [10.0, 0.0, 0.0], 2.0),  # behind the pipe
        ([0.0, 0.0, 0.0], [10.0, 0.0, 0.0], 0.0),  # the chord's middle
        ([-0.5, 0.0, 0.0], [10.0, 0.0, 0.0], 1.0),  # half-way to the far side
        ([5.0, 3.0, 0.0], [10.0, 0.0, 0.0], 0.0),  # the beam misses the pipe
        ([0.0, 1.0, 0.0], [10.0, 1.0, 0.0], 0.0),  # grazing: a zero-length chord
    ],
)
def test_beam_excess_on_a_unit_pipe(point, viewpoint, expected):
    got = cylinder_beam_excess(AXIS, CENTER, 1.0, np.array([point]), np.array(viewpoint))
    assert got[0] == pytest.approx(expected, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-1.5, 1.5),
    st.floats(-1.5, 1.5),
    st.floats(-2.0, 2.0),
    st.floats(-1.0, 1.0),
    st.floats(2.0, 8.0),
)
def test_beam_excess_matches_marching_along_an_oblique_beam(x, y, z, lift, distance):
    viewpoint = np.array([distance, 0.3 * distance, lift * distance])
    point = np.array([x, y, z])
    got = cylinder_beam_excess(AXIS, CENTER, 1.0, point[None], viewpoint)[0]
    assert got == pytest.approx(_marched_excess(AXIS, CENTER, 1.0, point, viewpoint), abs=2e-3)


def test_beam_excess_does_not_depend_on_the_frame(rng):
    points = rng.normal(size=(30, 3))
    viewpoint = np.array([6.0, 2.0, 1.0])
    axis = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
    before = cylinder_beam_excess(axis, CENTER, 0.8, points, viewpoint)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    shift = rng.normal(size=3)
    after = cylinder_beam_excess(
        q @ axis, q @ CENTER + shift, 0.8, points @ q.T + shift, q @ viewpoint + shift
    )
    np.testing.assert_allclose(after, before, atol=1e-12)


@pytest.mark.parametrize(
    "residuals, excess, expected",
    [
        ([0.0, 0.002, -0.002], [0.0, 0.0, 0.0], 2.0),
        ([0.0, 0.0], [0.004, 0.0], 4.0),  # a beam through the pipe costs like a residual
        ([1.0, 0.0], [0.0, 0.0], 9.0),  # an outlier pays the cap, no more
        ([0.0], [1.0], 9.0),
    ],
)
def test_visible_score_is_truncated_at_the_cutoff(residuals, excess, expected):
    score = visible_score(np.array(residuals), np.array(excess), 0.002, 3.0)
    assert score == pytest.approx(expected)


@pytest.mark.parametrize(
    "point, viewpoint, expected",
    [
        ([1.0, 0.0, 0.0], [10.0, 0.0, 0.0], 0.0),  # the front, square on
        ([0.0, 1.0, 0.0], [10.0, 1.0, 0.0], 90.0),  # the silhouette, grazing
        ([np.sqrt(0.5), np.sqrt(0.5), 0.0], [10.0, np.sqrt(0.5), 0.0], 45.0),
        # Seen obliquely along the axis (beam 20 degrees off it): the front is still square on
        # across the axis, though the 3-D incidence is 70 degrees.
        ([1.0, 0.0, 0.0], [1.0 + 10.0 * np.sin(0.349), 0.0, 10.0 * np.cos(0.349)], 0.0),
        ([1.0, 0.0, 0.0], [1.0, 0.0, 10.0], np.nan),  # beam along the axis: not defined
    ],
)
def test_incidence_across_the_axis(point, viewpoint, expected):
    got = edge_on_degrees(AXIS, CENTER, np.array([point]), np.array(viewpoint))[0]
    if np.isnan(expected):
        assert np.isnan(got)
    else:
        assert got == pytest.approx(expected, abs=1e-6)


def test_one_station_sees_an_arc_but_not_two_opposite_clusters():
    # A raster over a pipe's visible side: lateral offsets even across the silhouette.
    arc = np.arcsin(np.linspace(-0.98, 0.98, 21)) + 1.0
    assert one_side_could_see(arc, 2.0 / 3.0, 60.0)
    # A thin pipe's front shots and the wall shots behind it, fitted as one big "pipe": two
    # clusters 165 degrees apart on its circle.
    clusters = np.concatenate([np.full(10, -0.16), np.full(12, -3.04)])
    clusters += np.linspace(-0.02, 0.02, 22)
    assert not one_side_could_see(clusters, 2.0 / 3.0, 60.0)
    assert not one_side_could_see(np.array([]), 2.0 / 3.0, 60.0)


def _first_surface_range(axis, center, radius, direction, viewpoint):
    """Independent truth: where a beam (unit ``direction`` from ``viewpoint``) first meets an
    infinite cylinder, by root finding on the distance from the axis, or where it passes
    closest to the axis (numerical minimisation) when it misses."""

    def from_axis(t):
        rel = viewpoint + t * direction - center
        return float(np.linalg.norm(rel - (rel @ axis) * axis))

    closest = minimize_scalar(
        from_axis, bounds=(0.0, 100.0), method="bounded", options={"xatol": 1e-12}
    ).x
    if from_axis(closest) >= radius:
        return closest
    return brentq(lambda t: from_axis(t) - radius, 0.0, closest, xtol=1e-13)


@pytest.mark.parametrize(
    "point, viewpoint, expected",
    [
        ([1.0, 0.0, 0.0], [10.0, 0.0, 0.0], 0.0),  # on the front, square on
        ([1.5, 0.0, 0.0], [10.0, 0.0, 0.0], -0.5),  # in front of it
        ([-1.0, 0.0, 0.0], [10.0, 0.0, 0.0], 2.0),  # the back: through the whole pipe
        ([-3.0, 0.0, 0.0], [10.0, 0.0, 0.0], 4.0),  # the wall behind it
        ([0.0, 1.0, 0.0], [10.0, 1.0, 0.0], 0.0),  # the silhouette, grazing
        ([-2.0, 1.5, 0.0], [10.0, 1.5, 0.0], 2.0),  # a beam that missed: from its closest
        ([1.0, 1.5, 0.0], [10.0, 1.5, 0.0], -1.0),  # approach to the axis
    ],
)
def test_beyond_the_first_surface_of_a_unit_pipe(point, viewpoint, expected):
    got = beyond_first_surface(AXIS, CENTER, 1.0, np.array([point]), np.array(viewpoint))
    assert got[0] == pytest.approx(expected, abs=1e-12)


@settings(max_examples=40, deadline=None)
@given(
    st.floats(-3.0, 3.0),
    st.floats(-3.0, 3.0),
    st.floats(-2.0, 2.0),
    st.floats(-0.9, 0.9),
    st.floats(-8.0, 8.0),
)
def test_beyond_the_first_surface_matches_root_finding_on_oblique_beams(x, y, z, lift, along):
    axis = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
    center = np.array([0.2, 0.1, -0.3])
    viewpoint = np.array([9.0, 2.0, 1.0 + along])
    point = np.array([x, y, z + lift * along])
    direction = (point - viewpoint) / np.linalg.norm(point - viewpoint)
    truth = np.linalg.norm(point - viewpoint) - _first_surface_range(
        axis, center, 0.7, direction, viewpoint
    )
    got = beyond_first_surface(axis, center, 0.7, point[None, :], viewpoint)[0]
    assert got == pytest.approx(truth, abs=1e-6)


def test_excess_and_beyond_are_the_two_functions_from_one_computation():
    rng = np.random.default_rng(21)
    axis = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
    center, viewpoint = np.array([0.2, 0.1, -0.3]), np.array([9.0, 2.0, 1.0])
    points = rng.uniform(-2.0, 2.0, (50, 3))
    excess, beyond = excess_and_beyond(axis, center, 0.7, points, viewpoint)
    np.testing.assert_array_equal(
        excess, cylinder_beam_excess(axis, center, 0.7, points, viewpoint)
    )
    np.testing.assert_array_equal(
        beyond, beyond_first_surface(axis, center, 0.7, points, viewpoint)
    )


def test_a_beam_past_the_pipes_end_met_no_pipe():
    """With the pipe's span along its axis, a beam over its top met nothing (excess 0, beyond
    inf); one through it within the span is judged as against the infinite cylinder."""
    view = np.array([-5.0, 0.0, 0.0])
    over = np.array([[2.0, 0.0, 1.4]])  # crosses the unit pipe at z 0.8-1.2
    below = np.array([[2.0, 0.0, 0.7]])  # at z 0.4-0.6
    excess, beyond = excess_and_beyond(AXIS, np.zeros(3), 1.0, over, view)
    assert excess[0] > 1.0 and np.isfinite(beyond[0])  # the infinite cylinder's answer
    excess, beyond = excess_and_beyond(
        AXIS, np.zeros(3), 1.0, over, view, (-1.0, 0.5)
    )  # top at 0.5
    assert excess[0] == 0.0 and beyond[0] == np.inf
    both = excess_and_beyond(AXIS, np.zeros(3), 1.0, below, view)
    spanned = excess_and_beyond(AXIS, np.zeros(3), 1.0, below, view, (-1.0, 1.0))
    assert np.allclose(both, spanned)


def test_where_beams_enter_a_unit_pipe():
    """Along the z axis, radius 1: a beam from (5, 0, 0) to the axis enters at (1, 0, 0); one
    from (5, 0, 3) enters where x = 1 on its line, (1, 0, 0.6); one that misses (toward
    (0, 2, 0)) is given where it passes nearest the axis, the foot of the perpendicular from
    the axis to its line: (20, 50, 0) / 29."""
    view = np.array([5.0, 0.0, 0.0])
    entries = beam_entries(AXIS, np.zeros(3), 1.0, np.array([[0.0, 0, 0], [0, 2, 0]]), view)
    np.testing.assert_allclose(entries, [[1.0, 0, 0], [20 / 29, 50 / 29, 0]], atol=1e-12)
    tilted = beam_entries(AXIS, np.zeros(3), 1.0, np.zeros((1, 3)), np.array([5.0, 0, 3]))
    np.testing.assert_allclose(tilted, [[1.0, 0, 0.6]], atol=1e-12)
