"""A rough surface declared with an optimistic sigma must not settle in a rival basin.

Shots of an NPS 6 pipe (r 84.1 mm) 5 m away, a random subset of a fine raster over its
visible side, with 6 mm range scatter while the scan declares 2 mm: a fit at the declared
sigma can hold 25 of 31 shots to 1.7 mm with a radius 16% too large and reject the rest a few
sigmas off (a black-box review's scan; seeds 46, 68 and 121 here). The rejected shots lie near,
so the fit at the wider noise level that keeps them is compared as a mixture and wins
(:func:`asbuilt.fit._noise_levels._rough_rival`).
"""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit import fit_points

RADIUS = 0.0841
DISTANCE = 5.0


def _shots(rng, scatter: float, count: int = 30, background: int = 0) -> np.ndarray:
    """``count`` shots (n, 3) metres from the origin at a vertical pipe of radius ``RADIUS``,
    2 m long, ``DISTANCE`` away along x: a random subset of a 12 x 40 raster over its
    silhouette, each range with Gaussian ``scatter`` (metres); ``background`` more shots on a
    wall 1 m behind the pipe, as edge-grazing beams record."""
    half = np.arcsin(RADIUS / DISTANCE)
    pan = np.linspace(-half, half, 14)[1:-1]
    top = np.arctan(1.0 / DISTANCE)
    tilt = np.linspace(-top, top, 42)[1:-1]
    pans, tilts = np.meshgrid(pan, tilt)
    beams = np.stack(
        [np.cos(tilts) * np.cos(pans), np.cos(tilts) * np.sin(pans), np.sin(tilts)], axis=-1
    ).reshape(-1, 3)
    # First crossing of each beam with the infinite vertical cylinder at (DISTANCE, 0).
    a = beams[:, 0] ** 2 + beams[:, 1] ** 2
    b = -2.0 * DISTANCE * beams[:, 0]
    disc = b * b - 4.0 * a * (DISTANCE**2 - RADIUS**2)
    hit = disc > 0
    ranges = (-b[hit] - np.sqrt(disc[hit])) / (2.0 * a[hit])
    beams = beams[hit]
    pick = rng.choice(ranges.size, count, replace=False)
    points = (ranges[pick] + rng.normal(0.0, scatter, count))[:, None] * beams[pick]
    if background:
        wall = beams[rng.choice(beams.shape[0], background, replace=False)]
        depth = (DISTANCE + 1.0) / wall[:, 0] + rng.normal(0.0, 0.002, background)
        points = np.vstack([points, depth[:, None] * wall])
    return points


@pytest.mark.parametrize("seed", [46, 68, 121])
def test_a_rough_pipe_with_an_optimistic_sigma_keeps_its_radius(seed):
    # Before: radius 167.4, 74.6 and 76.1 mm (z 10.2, -5.5, -4.9) at the declared 2 mm.
    points = _shots(np.random.default_rng(seed), scatter=0.006)
    result = fit_points("cylinder", points, sigma=0.002, viewpoint=np.zeros(3))
    error = result.primitive.radius - RADIUS
    assert abs(error) < 3.0 * result.stderr["radius"]
    assert result.sigma_source == "residuals" and result.sigma > 0.003
    assert any("more than the sensor's range sigma" in note for note in result.notes)


@pytest.mark.parametrize("seed", range(6))
def test_the_declared_sigma_stands_on_a_smooth_pipe(seed):
    points = _shots(np.random.default_rng(seed), scatter=0.002)
    result = fit_points("cylinder", points, sigma=0.002, viewpoint=np.zeros(3))
    assert result.sigma_source == "sensor" and result.sigma == 0.002


@pytest.mark.parametrize("seed", range(6))
def test_background_shots_stay_outliers_at_the_declared_sigma(seed):
    # Shots of the wall a metre behind are background, not a rough surface's scatter.
    points = _shots(np.random.default_rng(seed), scatter=0.002, count=30, background=6)
    result = fit_points("cylinder", points, sigma=0.002, viewpoint=np.zeros(3))
    assert result.sigma_source == "sensor"
    assert not result.inliers[30:].any()
    assert abs(result.primitive.radius - RADIUS) < 3.0 * result.stderr["radius"]
