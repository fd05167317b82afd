"""Sphere fits: recovery from simulated scans, small caps, outliers, errors."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from fit_scans import raster_scan

from asbuilt.errors import FitError
from asbuilt.fit import fit_points
from asbuilt.fit import sphere as sphere_module
from asbuilt.fit._robust import RobustFit
from asbuilt.fit.sphere import algebraic_sphere, fit_sphere
from asbuilt.primitives import Sphere

SENSOR = np.zeros(3)


@pytest.mark.parametrize(
    "center, radius, n",
    [([3, 0.5, 0.5], 0.05, 20), ([5, -1, 1], 0.3, 30), ([8, 2, 0], 1.2, 40), ([10, 0, 2], 0.1, 40)],
)
def test_recovers_a_simulated_sphere(rng, center, radius, n):
    sphere = Sphere(center, radius)
    sample = raster_scan(sphere, SENSOR, n, rng)
    fit = fit_sphere(sample.points)
    assert fit.kind == "sphere"
    assert abs(fit.primitive.radius - radius) <= 4.5 * fit.stderr["radius"] + 1e-4
    distance = np.linalg.norm(fit.primitive.center - sphere.center)
    assert distance <= 4.5 * fit.stderr["center"] + 1e-4
    # One station sees at most a hemisphere.
    assert 60 < fit.diagnostics["cap_deg"] <= 181


def test_noise_free_cap_is_exact_where_the_algebraic_fit_is_not():
    rng = np.random.default_rng(2)
    directions = rng.normal(size=(25, 3))
    directions[:, 2] = np.abs(directions[:, 2]) * 4  # a cap around +z
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    points = np.array([1.0, 2.0, 3.0]) + 0.5 * directions
    fit = fit_sphere(points)
    assert fit.primitive.radius == pytest.approx(0.5, abs=1e-9)
    np.testing.assert_allclose(fit.primitive.center, [1, 2, 3], atol=1e-9)
    assert fit.rms < 1e-9
    center, radius = algebraic_sphere(points)
    assert radius == pytest.approx(0.5, abs=1e-9)  # exact data: the algebraic fit agrees
    noisy = points + rng.normal(0, 0.002, points.shape)
    assert abs(fit_sphere(noisy).primitive.radius - 0.5) < 0.01


def test_four_points_define_a_sphere_exactly():
    points = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [-1.0, 0, 0]]) * 2 + 5
    fit = fit_sphere(points)
    assert fit.primitive.radius == pytest.approx(2.0)
    np.testing.assert_allclose(fit.primitive.center, [5, 5, 5], atol=1e-9)
    assert fit.n_inliers == 4


def test_twenty_percent_edge_outliers_are_rejected(rng):
    sphere = Sphere([5, 1, 1], 0.4)
    sample = raster_scan(sphere, SENSOR, 30, rng, outlier_fraction=0.2)
    fit = fit_sphere(sample.points)
    far = sample.outliers & (np.abs(sphere.distance(sample.points)) > 0.02)
    assert not np.any(fit.inliers & far)
    assert abs(fit.primitive.radius - 0.4) <= 4.5 * fit.stderr["radius"] + 1e-4
    assert any("outlier" in note for note in fit.notes)


def test_covariance_and_standard_errors(rng):
    points = raster_scan(Sphere([5, 1, 1], 0.4), SENSOR, 30, rng).points
    fit = fit_sphere(points)
    assert set(fit.stderr) == {"radius", "center"}
    assert fit.covariance.shape == (4, 4)
    assert fit.stderr["radius"] == pytest.approx(np.sqrt(fit.covariance[3, 3]))
    assert fit.stderr["center"] == pytest.approx(np.sqrt(np.trace(fit.covariance[:3, :3])))
    one = fit_sphere(points, sigma=0.002)
    two = fit_sphere(points, sigma=0.004)
    assert two.sigma_source == "sensor"
    assert two.stderr["radius"] == pytest.approx(2 * one.stderr["radius"])


def test_radius_error_matches_repeated_scans_and_is_unbiased(rng):
    sphere = Sphere([6, 1, 1], 0.3)
    errors, predicted = [], []
    for _ in range(150):
        fit = fit_sphere(raster_scan(sphere, SENSOR, 30, rng).points)
        errors.append(fit.primitive.radius - 0.3)
        predicted.append(fit.stderr["radius"])
    rmse = np.sqrt(np.mean(np.square(errors)))
    assert 0.55 < rmse / np.sqrt(np.mean(np.square(predicted))) < 1.3
    # The product's bias target (a quarter of the scatter), allowing for the sampling error.
    assert abs(np.mean(errors)) < 0.25 * rmse + 2 * rmse / np.sqrt(len(errors))


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((3, 3)), "at least 4 points"),
        (np.ones((6, 3)), "identical"),
        (np.outer(np.arange(6.0), [1, 0, 1]), "collinear"),
        (np.column_stack([np.cos(np.arange(6.0)), np.sin(np.arange(6.0)), np.ones(6)]), "coplanar"),
    ],
)
def test_degenerate_points_raise(points, message):
    with pytest.raises(FitError, match=message):
        fit_sphere(points)


def test_a_shot_on_the_far_side_is_rejected(rng):
    sphere = Sphere([5, 1, 1], 0.3)
    sample = raster_scan(sphere, SENSOR, 30, rng)
    behind = sphere.center + 0.3 * sphere.center / np.linalg.norm(sphere.center)  # back pole
    fit = fit_sphere(np.vstack([sample.points, behind + 0.001]))
    assert not fit.inliers[-1] and fit.inliers[:-1].sum() >= 28
    assert any("far side" in note for note in fit.notes)


@pytest.mark.parametrize("radius, weighted", [(0.1, False), (0.5, True)])
def test_only_spheres_large_against_the_noise_are_weighted_by_incidence(radius, weighted):
    # Shots over a cap seen from one side, noisier square-on (3 mm) than grazing (1 mm): a
    # 0.5 m sphere's fit weights them; a 0.1 m one's (noise 2% of the radius, where the range
    # noise's sideways part biases the radius and weights make that worse) does not.
    rng = np.random.default_rng(7)
    polar = np.radians(rng.uniform(0.0, 70.0, 60))
    azimuth = rng.uniform(0.0, 2.0 * np.pi, 60)
    normals = np.column_stack(
        [np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), -np.cos(polar)]
    )
    noise = np.sqrt(0.001**2 + (0.003**2 - 0.001**2) * np.cos(polar) ** 2)
    points = (radius + rng.normal(0.0, 1.0, 60) * noise)[:, None] * normals + [0.0, 0.0, 5.0]
    state = (np.array([0.0, 0.0, 5.0]), radius)
    residuals, jacobian = sphere_module._MODEL.jacobian(state, points)
    robust = RobustFit(state, residuals, np.ones(60, bool), jacobian, float(np.std(residuals)))
    _, relative = sphere_module._incidence_weighted(robust, points)
    assert bool(np.ptp(relative) > 0.1) == weighted


_FLOOR_ROW = json.loads((Path(__file__).parent / "sphere_above_floor_row.json").read_text())


@pytest.mark.parametrize("station", [True, False])
def test_a_raster_row_on_the_floor_is_rejected_not_fitted(station):
    """A 1.3 m sphere at 8.5 m with its bottom raster row on the floor (8 of 30 shots;
    independent review's ray caster). The trimmed cost keeps three quarters of the shots, a
    floor shot among them, and its concentration steps wandered off: refused with the sensor's
    sigma, 30 of 30 outliers. The sphere from the four-point sample of least MSAC cost stands."""
    scan = _FLOOR_ROW
    viewpoint = scan["station"] if station else None
    result = fit_sphere(np.array(scan["points"]), sigma=scan["range_sigma"], viewpoint=viewpoint)
    assert abs(result.primitive.radius - scan["radius"]) < 3 * result.stderr["radius"]
    assert result.n_inliers == scan["on_sphere"]


def test_without_a_sigma_the_floor_row_is_background_by_likelihood():
    """The same scan without a sigma: every shot fitted a 3.3 m sphere at 226 mm, and the floor
    shots lie only a median 0.75 m from the sphere the others fit to 2 mm (under five of the
    wide fit's noise levels). By the mixture likelihood the 2 mm fit is far likelier."""
    result = fit_points("sphere", np.array(_FLOOR_ROW["points"]))
    assert abs(result.primitive.radius - _FLOOR_ROW["radius"]) < 3 * result.stderr["radius"]
    assert result.sigma < 0.003
    assert any("taken as background" in note for note in result.notes)


@pytest.mark.parametrize("far", [300.0, 1000.0, 3000.0, 7400.0])
def test_one_stray_return_kilometres_away_is_an_outlier_at_any_range(far):
    """A 2.5 m sphere's 6 x 6 raster and one stray return along a beam ``far`` metres away (a
    review's floor hit at 7.4 km). The four-point starts' degeneracy test was scaled by the
    extent of every point, so the stray ruled out every sample of the sphere: refused ("n of n
    points are outliers") at 3 km in 20 of 20 such scans and at 7.4 km in 5, fitted at 1 km.
    Each sample is now judged by its own size."""
    from fit_scans import cell_centres, shoot

    sphere = Sphere(np.array([7.0, 1.0, 0.5]), 1.25)
    distance = float(np.linalg.norm(sphere.center))
    half = np.arcsin(sphere.radius / distance)
    pan0 = np.arctan2(sphere.center[1], sphere.center[0])
    tilt0 = np.arcsin(sphere.center[2] / distance)
    pan, tilt = np.meshgrid(
        cell_centres(pan0 - half, pan0 + half, 6), cell_centres(tilt0 - half, tilt0 + half, 6)
    )
    points, hit = shoot(sphere, pan.ravel(), tilt.ravel(), np.random.default_rng(3))
    points = points[hit]
    stray = points[3] / np.linalg.norm(points[3]) * far
    result = fit_points("sphere", np.vstack([points, stray]), sigma=0.002, viewpoint=SENSOR)
    assert abs(result.primitive.radius - sphere.radius) < 4 * result.stderr["radius"]
    assert result.n_inliers == len(points)
    assert not result.inliers[-1]
