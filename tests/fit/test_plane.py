"""Plane fits: total least squares on walls, floors and slopes; outline; outliers; errors."""

from __future__ import annotations

import numpy as np
import pytest
from fit_scans import angle_deg, raster_scan

from asbuilt.errors import FitError
from asbuilt.fit._common import orthonormal_basis
from asbuilt.fit.plane import fit_plane, plane_outline
from asbuilt.primitives import Plane


def _rectangle(center, normal, width, height):
    """A bounded plane: rectangle centred at ``center``, outline CCW about ``normal``."""
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    u, v = orthonormal_basis(normal)
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    outline = [np.asarray(center) + a * width / 2 * u + b * height / 2 * v for a, b in corners]
    return Plane(center, normal, outline)


SENSOR = np.array([0.0, 0.0, 1.6])

PLANES = [
    ("vertical wall facing the station", [6, 0, 1.5], [-1, 0, 0], 4, 3),
    ("oblique vertical wall", [5, 3, 1.5], [-1, -1.2, 0], 3, 2.5),
    ("floor slab", [4, 1, 0], [0, 0, 1], 3, 2),
    ("sloped roof", [5, -1, 3], [-0.3, 0.1, -1], 2, 2),
]


@pytest.mark.parametrize("name, center, normal, width, height", PLANES)
def test_recovers_a_simulated_plane(rng, name, center, normal, width, height):
    plane = _rectangle(center, normal, width, height)
    sample = raster_scan(plane, SENSOR, 30, rng)
    fit = fit_plane(sample.points)
    assert fit.kind == "plane"
    error = angle_deg(fit.primitive.normal, plane.normal)
    assert error <= 4.5 * fit.stderr["normal_deg"] + 1e-3 and error < 0.5
    offset = (fit.primitive.point - plane.point) @ plane.normal
    assert abs(offset) <= 4.5 * fit.stderr["offset"] + 1e-4
    # The normal points back towards the station at the origin's side.
    assert fit.primitive.normal @ (np.zeros(3) - fit.primitive.point) > 0
    assert fit.diagnostics["extent"] <= np.hypot(width, height) + 0.01
    assert fit.diagnostics["area"] <= width * height + 0.01


def test_total_least_squares_is_exact_for_a_vertical_wall():
    # z = A x + B y + C cannot represent this wall at all; orthogonal regression can.
    y, z = np.meshgrid(np.linspace(-1, 1, 5), np.linspace(0, 2, 4))
    points = np.column_stack([np.full(y.size, 3.0), y.ravel(), z.ravel()])
    fit = fit_plane(points)
    np.testing.assert_allclose(fit.primitive.normal, [-1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(fit.residuals, 0, atol=1e-12)
    assert fit.primitive.point == pytest.approx([3, 0, 1])


def test_outline_is_the_convex_hull_counter_clockwise_about_the_normal(rng):
    plane = _rectangle([5, 2, 1], [-1, -0.4, 0.2], 3, 2)
    sample = raster_scan(plane, SENSOR, 40, rng)
    fit = fit_plane(sample.points)
    outline = fit.primitive.outline
    normal = fit.primitive.normal
    point = fit.primitive.point
    np.testing.assert_allclose((outline - point) @ normal, 0, atol=1e-12)
    # Counter-clockwise: every turn has a positive component along the normal.
    edges = np.roll(outline, -1, axis=0) - outline
    turns = np.cross(edges, np.roll(edges, -1, axis=0)) @ normal
    assert np.all(turns > 0)
    # Every inlier projects inside (or on) the outline, and the corners are measured points.
    kept = sample.points[fit.inliers]
    projected = kept - np.outer((kept - point) @ normal, normal)
    side = np.einsum("kj,nkj->nk", np.cross(edges, normal), projected[:, None, :] - outline)
    assert np.all(side <= 1e-9)
    gaps = np.linalg.norm(projected[:, None, :] - outline[None, :, :], axis=2).min(axis=0)
    np.testing.assert_allclose(gaps, 0, atol=1e-12)


def test_plane_outline_of_collinear_points_raises():
    points = np.outer(np.arange(4.0), [1, 0, 0])
    with pytest.raises(FitError, match="collinear"):
        plane_outline(points, np.zeros(3), np.array([0.0, 0.0, 1.0]))


def test_three_points_define_a_plane_exactly():
    fit = fit_plane([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
    np.testing.assert_allclose(fit.primitive.normal, -np.ones(3) / np.sqrt(3))
    assert fit.n_inliers == 3 and fit.rms < 1e-12


def test_a_plane_through_the_origin_uses_the_sign_rule():
    x, y = np.meshgrid(np.linspace(-1, 1, 4), np.linspace(-1, 1, 4))
    points = np.column_stack([x.ravel(), y.ravel(), np.zeros(16)])
    fit = fit_plane(points)
    np.testing.assert_allclose(fit.primitive.normal, [0, 0, 1])


def test_twenty_percent_edge_outliers_are_rejected(rng):
    plane = _rectangle([6, 0, 1.5], [-1, 0.2, 0], 4, 3)
    sample = raster_scan(plane, SENSOR, 30, rng, outlier_fraction=0.2)
    fit = fit_plane(sample.points)
    np.testing.assert_array_equal(fit.inliers, ~sample.outliers)
    assert angle_deg(fit.primitive.normal, plane.normal) < 0.5
    assert any("6 outlier" in note for note in fit.notes)
    # The outline bounds the inliers only.
    assert fit.diagnostics["area"] <= 12.01


def test_covariance_and_standard_errors(rng):
    plane = _rectangle([6, 0, 1.5], [-1, 0, 0], 4, 3)
    points = raster_scan(plane, SENSOR, 30, rng).points
    fit = fit_plane(points)
    assert set(fit.stderr) == {"normal_deg", "offset"}
    cov = fit.covariance
    assert cov.shape == (3, 3) and np.all(np.linalg.eigvalsh(cov) > 0)
    # Independent check: the offset at the centroid has variance sigma^2 / n.
    assert fit.stderr["offset"] == pytest.approx(fit.sigma / np.sqrt(fit.n_inliers), rel=1e-6)
    sensor = fit_plane(points, sigma=0.002)
    assert sensor.sigma_source == "sensor"
    assert sensor.stderr["offset"] == pytest.approx(0.002 / np.sqrt(sensor.n_inliers), rel=1e-6)


def test_normal_error_matches_repeated_scans(rng):
    plane = _rectangle([6, 0, 1.5], [-1, 0.2, 0], 4, 3)
    errors, predicted = [], []
    for _ in range(80):
        fit = fit_plane(raster_scan(plane, SENSOR, 30, rng).points)
        errors.append(angle_deg(fit.primitive.normal, plane.normal))
        predicted.append(fit.stderr["normal_deg"])
    ratio = np.sqrt(np.mean(np.square(errors))) / np.sqrt(np.mean(np.square(predicted)))
    assert 0.75 < ratio < 1.3


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((2, 3)), "at least 3 points"),
        (np.ones((5, 3)), "identical"),
        (np.outer(np.arange(5.0), [0, 1, 1]), "collinear"),
    ],
)
def test_degenerate_points_raise(points, message):
    with pytest.raises(FitError, match=message):
        fit_plane(points)


def test_too_many_outliers_says_how_many_points_one_plane_holds():
    # A wall with a doorway: 16 shots on the wall, 12 through the door on a wall behind and 8
    # on the floor. No plane holds the 20 (55%) a plane fit needs; the error says how many the
    # best one holds, not the count of a compromise plane through two surfaces.
    y, z = np.meshgrid([-1.7, -0.56, 0.56, 1.7], [0.6, 1.2, 1.8, 2.4])
    wall = np.column_stack([np.full(16, 6.0), y.ravel(), z.ravel()])
    far = np.column_stack([np.full(12, 10.0), np.linspace(-5, 5, 12), np.linspace(1, 4, 12)])
    floor = np.column_stack([np.linspace(5.4, 9.0, 8), np.linspace(-2.7, 4.5, 8), np.zeros(8)])
    points = np.vstack([wall, far, floor])
    with pytest.raises(FitError, match=r"At most 16 of the 36 points lie on one plane") as raised:
        fit_plane(points, sigma=0.002)
    assert "needs 20" in str(raised.value) and '"hull"' in str(raised.value)


def _wall_and_floor(rng, wall_share: float, n: int) -> np.ndarray:
    """A wall at x = 5 m (n * wall_share shots) and the floor in front of it, 2 mm noise."""
    on_wall = int(round(wall_share * n))
    wall = np.column_stack(
        [np.full(on_wall, 5.0), rng.uniform(-2, 2, on_wall), rng.uniform(0, 3, on_wall)]
    )
    rest = n - on_wall
    floor = np.column_stack([rng.uniform(2, 5, rest), rng.uniform(-2, 2, rest), np.zeros(rest)])
    return np.vstack([wall, floor]) + rng.normal(0, 0.002, (n, 3))


@pytest.mark.parametrize("sigma", [0.002, None])
@pytest.mark.parametrize("wall_share, n", [(0.57, 1000), (0.6, 200), (0.57, 60), (0.65, 40)])
def test_a_surface_holding_most_points_is_fitted_beside_another_large_one(sigma, wall_share, n):
    # The trimmed start compromises between two large surfaces (a diagonal plane through wall
    # and floor); the plane holding the most points is settled instead, the floor rejected.
    rng = np.random.default_rng(n)
    fit = fit_plane(_wall_and_floor(rng, wall_share, n), sigma=sigma)
    assert angle_deg(fit.primitive.normal, [1.0, 0.0, 0.0]) < 0.5
    on_wall = int(round(wall_share * n))
    # Floor shots within a few millimetres of the corner also lie on the wall.
    assert np.count_nonzero(fit.inliers[on_wall:]) <= 3
    assert np.count_nonzero(fit.inliers[:on_wall]) >= on_wall - 2


@pytest.mark.parametrize("sigma", [0.002, None])
def test_two_equal_surfaces_are_refused_with_or_without_the_sensor_sigma(sigma):
    # Without the sigma the residuals would set the scale and a diagonal plane through both
    # explain every point at decimetres; one surface explains its half far better.
    points = _wall_and_floor(np.random.default_rng(5), 0.5, 400)
    with pytest.raises(FitError, match=r"At most 2\d\d of the 400 points lie on one plane"):
        fit_plane(points, sigma=sigma)


@pytest.mark.parametrize("roughness", [0.01, 0.05])
def test_a_rough_wall_without_the_sigma_keeps_its_points(roughness):
    rng = np.random.default_rng(9)
    points = np.column_stack([np.full(200, 5.0), rng.uniform(-2, 2, 200), rng.uniform(0, 3, 200)])
    points[:, 0] += rng.normal(0, roughness, 200)
    fit = fit_plane(points)
    assert fit.n_inliers >= 196
    assert fit.sigma == pytest.approx(roughness, rel=0.2)
