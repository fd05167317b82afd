"""Tests for asbuilt.fit._silhouette: raster windows and edges placed on the silhouette."""

from __future__ import annotations

import numpy as np
import pytest

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
