"""The sphere fit with the sensor's position: range noise along the beams does not bias it."""

import numpy as np
import pytest

from asbuilt.fit import fit_points

#: Range noise of the benchmark's sensor, metres.
SIGMA = 0.002
#: A 0.2 m sphere 5 m away: its radius is 50 noise sigmas, where orthogonal distances shrink it.
RADIUS = 0.1
CENTRE = np.array([5.0, 0.0, 0.0])


def _scans(count, seed):
    """``count`` scans of 29 shots whose beams meet the sphere at sin(incidence) up to 0.9,
    each range the exact ray-sphere distance plus N(0, SIGMA) (no pointing noise)."""
    rng = np.random.default_rng(seed)
    offsets = np.linspace(-0.9, 0.9, 7) * RADIUS / np.linalg.norm(CENTRE)
    pan, tilt = (a.ravel() for a in np.meshgrid(offsets, offsets))
    inside = pan**2 + tilt**2 <= (0.9 * RADIUS / np.linalg.norm(CENTRE)) ** 2
    beams = np.column_stack([np.ones(inside.sum()), pan[inside], tilt[inside]])
    beams /= np.linalg.norm(beams, axis=1)[:, None]
    ahead = beams @ CENTRE
    true_range = ahead - np.sqrt(ahead**2 - CENTRE @ CENTRE + RADIUS**2)
    for _ in range(count):
        ranges = true_range + rng.normal(0.0, SIGMA, len(beams))
        yield ranges[:, None] * beams


def test_range_noise_along_the_beams_leaves_the_radius_unbiased():
    with_station, without = [], []
    for points in _scans(400, 11):
        with_station.append(fit_points("sphere", points, sigma=SIGMA, viewpoint=np.zeros(3)))
        without.append(fit_points("sphere", points, sigma=SIGMA))
    errors = np.array([f.primitive.radius for f in with_station]) - RADIUS
    orthogonal = np.array([f.primitive.radius for f in without]) - RADIUS
    standard_error = errors.std(ddof=1) / np.sqrt(len(errors))
    # Orthogonal distances shrink the radius by several standard errors of the mean here ...
    assert orthogonal.mean() < -4 * standard_error
    # ... measuring along the beams does not (within 3 standard errors of the mean).
    assert abs(errors.mean()) < 3 * standard_error
    # Same precision: the correction is of second order.
    assert np.sqrt(np.mean(errors**2)) < 1.05 * np.sqrt(np.mean(orthogonal**2))


@pytest.mark.parametrize(
    "viewpoint",
    [
        2.0 * CENTRE,  # behind the sphere: every beam would pass through it first
        np.array([0.0, 100.0, 0.0]),  # a station in another frame: no beam meets the sphere
    ],
)
def test_a_station_the_shots_cannot_come_from_leaves_the_orthogonal_fit(viewpoint):
    # The beams from a wrong station meet the sphere nowhere near the shots (or not at all):
    # the refit along them is dropped and the fit is the one without a station.
    for points in _scans(20, 5):
        wrong = fit_points("sphere", points, sigma=SIGMA, viewpoint=viewpoint)
        none = fit_points("sphere", points, sigma=SIGMA)
        assert wrong.primitive.radius == none.primitive.radius
        np.testing.assert_array_equal(wrong.primitive.center, none.primitive.center)
