"""Tests for asbuilt.fit._silhouette: raster windows and edges placed on the silhouette."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from asbuilt.fit import _silhouette


def _raster(viewpoint, pans, tilts, ranges):
    pan, tilt = np.meshgrid(pans, tilts)
    pan, tilt = pan.ravel(), tilt.ravel()
    d = np.column_stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)])
    return viewpoint + ranges[: pan.size, None] * d


def test_raster_window_is_the_extent_widened_by_half_a_step():
    rng = np.random.default_rng(1)
    view = np.array([1.0, -2.0, 0.5])
    pans = 0.3 + 0.01 * np.arange(5)
    tilts = -0.1 + 0.02 * np.arange(6)
    pts = _raster(view, pans, tilts, rng.uniform(4.0, 6.0, 30))
    pan0, window = _silhouette.raster_window(pts, view)
    assert window[0] + pan0 == pytest.approx(0.3 - 0.005)
    assert window[1] + pan0 == pytest.approx(0.34 + 0.005)
    assert window[2] == pytest.approx(-0.1 - 0.01)
    assert window[3] == pytest.approx(0.0 + 0.01)


def test_raster_with_missing_lines_still_counts_whole_steps():
    view = np.zeros(3)
    pans = 0.01 * np.array([0, 1, 3, 4])  # one column missed
    tilts = 0.02 * np.arange(4)
    pts = _raster(view, pans, tilts, np.full(16, 5.0))
    assert _silhouette.raster_window(pts, view) is not None


def test_points_not_from_a_raster_at_the_viewpoint_are_rejected():
    rng = np.random.default_rng(2)
    pts = rng.uniform(-1, 1, size=(30, 3)) + [5.0, 0.0, 0.0]
    assert _silhouette.raster_window(pts, np.zeros(3)) is None
    raster = _raster(np.zeros(3), 0.01 * np.arange(5), 0.02 * np.arange(6), np.full(30, 5.0))
    raster = raster + rng.uniform(0, 0.5, 30)[:, None] * [1.0, 0.0, 0.0]  # ranges vary
    assert _silhouette.raster_window(raster, np.array([0.0, 3.0, 1.0])) is None


def test_solve_bounds_puts_the_box_silhouette_on_the_window():
    axes = np.eye(3)
    origin = np.array([5.0, 0.0, 0.0])
    view = np.zeros(3)
    lo_true, hi_true = np.array([-0.2, -0.3, -1.0]), np.array([0.2, 0.3, 1.0])
    window = _silhouette._extent(lo_true, hi_true, axes, origin, view, 0.0)
    start_lo, start_hi = lo_true.copy(), hi_true.copy()
    start_lo[1] += 0.05
    start_hi[1] -= 0.04
    start_hi[2] -= 0.2
    free = [(1, 0), (1, 1), (2, 1)]
    lo, hi = _silhouette.solve_bounds(start_lo, start_hi, free, axes, origin, view, 0.0, window)
    assert np.allclose(lo, lo_true, atol=1e-6)
    assert np.allclose(hi, hi_true, atol=1e-6)


def test_the_simulator_raster_convention_is_the_one_assumed():
    """The silhouette window assumes shots at cell centres (half a step inside the window)."""
    sensor = pytest.importorskip("asbuilt.sim.sensor")
    assert sensor.EDGE_INSET == 0.5


# --------------------------------------------------------------------------- edge-bisection shots


def _grid_and_edges(step_p=0.01, step_t=0.02, cols=4, rows=5):
    """A raster plus bisection shots: one pan bisection right of row 2, one tilt bisection
    above column 1, each stepping 1/2, 3/4, 7/8 of a step (hits only)."""
    raster = [(0.3 + step_p * c, -0.1 + step_t * r) for r in range(rows) for c in range(cols)]
    right = 0.3 + step_p * (cols - 1)
    top = -0.1 + step_t * (rows - 1)
    pan_bisection = [(right + f * step_p, -0.1 + 2 * step_t) for f in (0.5, 0.75, 0.875)]
    tilt_bisection = [(0.3 + step_p, top + f * step_t) for f in (0.5, 0.625)]
    return raster, pan_bisection, tilt_bisection


def _points(view, angles):
    pan, tilt = np.asarray(angles, float).T
    d = np.column_stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)])
    ranges = np.random.default_rng(3).uniform(5.0, 6.0, len(pan))
    return view + ranges[:, None] * d


@pytest.mark.parametrize("view", [np.zeros(3), np.array([1.0, -2.0, 0.5])])
def test_bisection_shots_are_told_from_the_raster(view):
    raster, pan_b, tilt_b = _grid_and_edges()
    pts = _points(view, raster + pan_b + tilt_b)
    along, partner = _silhouette.edge_shots(pts, view)
    k = len(raster)
    assert np.all(along[:k] == -1) and np.all(partner[:k] == -1)
    assert np.all(along[k : k + 3] == 0)  # bisected along pan, on raster row 2
    assert np.all(along[k + 3 :] == 1)  # bisected along tilt, on raster column 1
    # each one's partner lies on its own row (column) at least a centimetre across the beam
    for i in range(k, len(pts)):
        j = 1 - along[i]
        assert np.asarray(raster + pan_b + tilt_b)[partner[i], j] == pytest.approx(
            np.asarray(raster + pan_b + tilt_b)[i, j]
        )


@pytest.mark.parametrize(
    "extra, flagged",
    [
        ([], 0),  # a plain raster
        ([(0.31, -0.1 + 0.02 * 5)], 0),  # a lone shot on a raster's next row (a box's corner)
        ([(0.335, 0.06 + 0.0137 * i) for i in range(3)], 0),  # a one-column fill raster
        ([(0.295, -0.04)], 1),  # half a step left of the raster, on a row
    ],
)
def test_raster_shots_off_the_main_lines_are_not_bisections(extra, flagged):
    raster, _, _ = _grid_and_edges()
    view = np.zeros(3)
    along, _ = _silhouette.edge_shots(_points(view, raster + extra), view)
    assert np.count_nonzero(along >= 0) == flagged


def test_raster_grid_pins_the_sides_that_bisection_shots_reach_beyond():
    raster, pan_b, tilt_b = _grid_and_edges()
    view = np.zeros(3)
    pts = _points(view, raster + pan_b + tilt_b)
    pan0, window, on_grid, pinned, steps = _silhouette.raster_grid(pts, view)
    assert on_grid.tolist() == [True] * len(raster) + [False] * 5
    assert steps == pytest.approx([0.01, 0.02])
    # pan high and tilt high at the outermost bisection shots; the others half a step out
    assert pinned.tolist() == [False, True, False, True]
    assert window[1] + pan0 == pytest.approx(0.33 + 0.875 * 0.01)
    assert window[3] == pytest.approx(-0.1 + 0.08 + 0.625 * 0.02)
    assert window[0] + pan0 == pytest.approx(0.3 - 0.005)
    assert window[2] == pytest.approx(-0.1 - 0.01)
    # and the plain raster's window is unchanged by the check
    plain = _silhouette.raster_window(_points(view, raster), view)
    assert plain[1][2] == pytest.approx(-0.11)


def _in_progression_reference(v, others, tol):
    """The definition, one value at a time."""
    for a in others:
        d = a - v
        if abs(d) <= tol:
            continue
        for target in (a + d, v - d):
            if np.any(np.abs(others - target) <= tol):
                return True
    return False


@settings(max_examples=200, deadline=None)
@given(
    st.lists(st.integers(-40, 40), min_size=0, max_size=12, unique=True),
    st.integers(-40, 40),
    st.sampled_from([0.0, 0.5, 1.5]),
)
def test_in_progression_matches_its_definition(values, v, tol):
    others = np.sort(np.array(values, dtype=float) * 0.37)
    v = v * 0.37
    assert _silhouette._in_progression(v, others, tol) == _in_progression_reference(v, others, tol)


# --------------------------------------------------------------------------- rounded or jittered angles


@pytest.mark.parametrize(
    "quantum, expected",
    [
        (0.001, 0.001),  # a file in millimetres, whole numbers
        (0.0001, 0.0001),  # metres to 4 decimals (the shipped samples)
        (0.01 * 0.0254, 0.01 * 0.0254),  # inches to 2 decimals
        (0.001 * 0.3048, 0.001 * 0.3048),  # feet to 3 decimals
        (0.0, 0.0),  # full precision
    ],
)
def test_coordinate_quantum_finds_the_files_rounding(quantum, expected):
    pts = np.random.default_rng(5).uniform(-12.0, 12.0, (30, 3))
    if quantum:
        pts = np.round(pts / quantum) * quantum
    assert _silhouette.coordinate_quantum(pts) == pytest.approx(expected, rel=1e-9)


def _raster_with_bisections(rng, jitter_deg=0.0):
    """A 4 x 5 raster with two bisection sequences (as _grid_and_edges), angles scattered by
    ``jitter_deg`` (recorded angles read back from a head's encoders)."""
    raster, pan_b, tilt_b = _grid_and_edges()
    angles = np.asarray(raster + pan_b + tilt_b, float)
    angles += rng.normal(0.0, np.radians(jitter_deg), angles.shape)
    return _points(np.zeros(3), angles), len(raster)


@pytest.mark.parametrize("quantum", [0.001, 0.0001])
def test_rounded_coordinates_take_no_raster_shot_for_a_bisection(quantum):
    """A file rounded to 1 mm moves a shot's angle at 5 m by up to 0.008 degree, more than a
    raster line's width for exact angles (0.02% of the spread): raster shots were taken for
    bisection shots and the box's unseen edges lost their half-step pad (a 1 m column came out
    0.65 m +- 3 mm). The rounding is now allowed for: no raster shot is flagged, and rounding
    to 0.1 mm (4 decimals in metres) still tells the bisection shots."""
    pts, k = _raster_with_bisections(np.random.default_rng(0))
    along, _ = _silhouette.edge_shots(np.round(pts / quantum) * quantum, np.zeros(3))
    assert np.all(along[:k] == -1)
    if quantum <= 0.0001:
        assert np.all(along[k:] >= 0)


@pytest.mark.parametrize("jitter_deg", [0.002, 0.005, 0.01, 0.03])
@pytest.mark.parametrize("seed", range(5))
def test_jittered_angles_take_no_raster_shot_for_a_bisection(jitter_deg, seed):
    pts, k = _raster_with_bisections(np.random.default_rng(seed), jitter_deg)
    along, _ = _silhouette.edge_shots(pts, np.zeros(3))
    assert np.all(along[:k] == -1)
