"""Shared fitting numerics: validation, scales, bases, normals, noise levels and weights."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit import _common as common
from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((5, 2)), "shape (n, 3)"),
        (np.zeros(9), "shape (n, 3)"),
        ([[0, 0, 0], [1, 1, np.nan], [2, 0, 0], [0, 2, 0]], "finite"),
        ([["a", 0, 0]] * 4, "numbers"),
    ],
)
def test_validate_points_rejects_bad_arrays(points, message):
    with pytest.raises(FitError, match=message.replace("(", r"\(").replace(")", r"\)")):
        common.validate_points(points, "plane")


@pytest.mark.parametrize("kind", sorted(MIN_POINTS))
def test_validate_points_needs_the_kinds_minimum(kind):
    need = MIN_POINTS[kind]
    points = np.random.default_rng(1).normal(size=(need - 1, 3))
    with pytest.raises(FitError, match=f"at least {need} points, got {need - 1}"):
        common.validate_points(points, kind)
    assert common.validate_points(np.vstack([points, [0, 0, 0]]), kind).shape == (need, 3)


@pytest.mark.parametrize(
    "points, dimensions, message",
    [
        (np.ones((6, 3)), 1, "identical"),
        (np.outer(np.arange(6.0), [1, 2, 3]), 2, "collinear"),
        (np.column_stack([np.arange(6.0), np.arange(6.0) ** 2, np.zeros(6)]), 3, "coplanar"),
    ],
)
def test_require_spread_names_the_degeneracy(points, dimensions, message):
    with pytest.raises(FitError, match=message):
        common.require_spread(points, "cylinder", dimensions)


def test_require_spread_accepts_a_tetrahedron():
    spread = common.require_spread(np.vstack([np.zeros(3), np.eye(3)]), "sphere", 3)
    assert np.all(spread > 0) and np.all(np.diff(spread) <= 0)


@pytest.mark.parametrize(
    "axis", [[0, 0, 1], [1, 0, 0], [0, 1, 0], [1, 1, 1], [-0.3, 0.2, -0.9], [1e-12, 1, 0]]
)
def test_orthonormal_basis_is_a_right_handed_frame(axis):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    u, v = common.orthonormal_basis(axis)
    frame = np.array([u, v, axis])
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(frame) == pytest.approx(1.0)


def test_orthonormal_bases_match_orthonormal_basis_bit_for_bit():
    # Random axes and every tie between coordinate axes (where the branch choice matters).
    rng = np.random.default_rng(11)
    random = rng.normal(size=(500, 3))
    ties = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, 0, 1], [0, 1, 1], [1, 1, 1]])
    axes = np.vstack([random, ties, -ties, [[1e-12, 1, 0]]]).astype(float)
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    u, v = common.orthonormal_bases(axes)
    for k, axis in enumerate(axes):
        one_u, one_v = common.orthonormal_basis(axis)
        assert u[k].tolist() == one_u.tolist() and v[k].tolist() == one_v.tolist()


@pytest.mark.parametrize("count", [3, 7, 41])
def test_median_spacing_is_the_median_nearest_neighbour_distance(count):
    # Points on a line with known gaps: each point's nearest neighbour is its closer neighbour.
    # (Odd counts: there the median is one point's distance, whichever way it is averaged.)
    gaps = np.arange(1.0, count) / 100.0
    x = np.concatenate([[0.0], np.cumsum(gaps)])
    points = np.column_stack([x, np.zeros(count), np.zeros(count)])
    nearest = np.minimum(np.r_[np.inf, gaps], np.r_[gaps, np.inf])
    assert common.median_spacing(points) == pytest.approx(np.median(nearest), rel=1e-9)


@pytest.mark.parametrize(
    "direction, expected",
    [
        ([0.1, 0.2, -0.9], [-0.1, -0.2, 0.9]),
        ([-1, 0.5, 0.001], [1, -0.5, -0.001]),
        ([0.01, -1, 0], [-0.01, 1, 0]),
        ([0.5, -0.5, 0.5], [0.5, -0.5, 0.5]),
        ([-0.5, 0.5, 0], [0.5, -0.5, 0]),
    ],
)
def test_orient_makes_the_largest_component_positive(direction, expected):
    np.testing.assert_allclose(common.orient(np.array(direction, float)), expected)


def test_robust_scale_estimates_a_gaussian_sigma_and_ignores_gross_outliers():
    rng = np.random.default_rng(3)
    residuals = rng.normal(0, 0.002, 4000)
    residuals[:800] += 5.0
    assert common.robust_scale(residuals, 1e-4) == pytest.approx(0.002 * 1.35, rel=0.1)
    assert common.robust_scale(rng.normal(0, 0.002, 4001), 1e-4) == pytest.approx(0.002, rel=0.05)


@pytest.mark.parametrize("residuals", [np.zeros(10), np.zeros(0)])
def test_robust_scale_is_floored(residuals):
    assert common.robust_scale(residuals, 1e-4) == 1e-4


def test_tukey_weights_shape():
    weights = common.tukey_weights(np.array([0.0, 1.0, -4.685, 10.0]), 1.0)
    np.testing.assert_allclose(weights, [1.0, (1 - (1 / 4.685) ** 2) ** 2, 0.0, 0.0])


def test_noise_level_prefers_the_sensor_and_corrects_for_degrees_of_freedom():
    residuals = np.array([1.0, -1.0, 1.0, -1.0, 1.0, -1.0]) * 0.003
    assert common.noise_level(residuals, 2, 0.002, DEFAULT_TOLERANCES) == (0.002, "sensor")
    sigma, source = common.noise_level(residuals, 2, None, DEFAULT_TOLERANCES)
    assert source == "residuals"
    # 4 residual degrees of freedom, one short of min_noise_dof: the missing one counts as a
    # residual of the 2 mm prior (scaled inverse chi-square prior).
    assert sigma == pytest.approx(np.sqrt((6 * 0.003**2 + 0.002**2) / 5))
    many = np.tile(residuals, 3)  # 16 degrees of freedom: the residuals alone
    assert common.noise_level(many, 2, None, DEFAULT_TOLERANCES)[0] == pytest.approx(
        0.003 * np.sqrt(18 / 16)
    )
    # An exact fit (no degree of freedom) no longer claims the 0.1 mm floor: the prior's 2 mm.
    assert common.noise_level(residuals[:2] * 0, 2, None, DEFAULT_TOLERANCES)[0] == 0.002


def test_covariance_from_jacobian_matches_the_straight_line_textbook_formula():
    # y = a + b x with x = 0..4: Var(b) = sigma^2 / sum (x - mean)^2, Var(a) = sigma^2 (1/n + ...)
    x = np.arange(5.0)
    jacobian = np.column_stack([np.ones(5), x])
    covariance = common.covariance_from_jacobian(jacobian, 0.5)
    sxx = np.sum((x - x.mean()) ** 2)
    assert covariance[1, 1] == pytest.approx(0.25 / sxx)
    assert covariance[0, 0] == pytest.approx(0.25 * (1 / 5 + x.mean() ** 2 / sxx))


def test_covariance_from_a_rank_deficient_jacobian_is_finite_and_undetermined():
    # Two equal columns: a + b is determined, a - b not at all. A pseudo-inverse gave a - b
    # zero variance, as if it were known exactly.
    jacobian = np.column_stack([np.ones(4), np.ones(4)])
    covariance = common.covariance_from_jacobian(jacobian, 1.0)
    assert np.all(np.isfinite(covariance))
    assert covariance[0, 0] > 1e20 and covariance[1, 1] > 1e20


def test_covariance_of_a_nearly_singular_jacobian_keeps_its_large_variance():
    # Columns 1 and 1 + eps x: J^T J has condition ~1e20 (its inverse is rounding noise), J
    # itself 1e10. The exact covariance is that of the line y = a + b x with b scaled by eps.
    eps = 1e-10
    x = np.arange(5.0)
    jacobian = np.column_stack([np.ones(5), 1.0 + eps * x])
    covariance = common.covariance_from_jacobian(jacobian, 0.5)
    sxx = np.sum((x - x.mean()) ** 2)
    # a' = a + b, b' = eps b: Var(b) = Var(b') / eps^2.
    assert covariance[1, 1] == pytest.approx(0.25 / sxx / eps**2, rel=1e-4)


def test_covariance_with_fewer_residuals_than_parameters_is_undetermined_beyond_them():
    covariance = common.covariance_from_jacobian(np.array([[1.0, 0.0, 0.0]]), 1.0)
    assert covariance[0, 0] == pytest.approx(1.0)
    assert covariance[1, 1] > 1e20 and covariance[2, 2] > 1e20


@pytest.mark.parametrize("value, expected", [(4.0, 2.0), (-1e-30, np.inf), (np.nan, np.inf)])
def test_stderr_of(value, expected):
    assert common.stderr_of(value) == expected


def test_local_normals_on_a_plane_are_the_plane_normal():
    rng = np.random.default_rng(4)
    normal = np.array([1.0, 2.0, 2.0]) / 3.0
    u, v = common.orthonormal_basis(normal)
    points = rng.uniform(-1, 1, (30, 1)) * u + rng.uniform(-1, 1, (30, 1)) * v
    normals, flatness = common.local_normals(points, 6)
    np.testing.assert_allclose(np.abs(normals @ normal), 1.0, atol=1e-9)
    assert np.all(flatness < 1e-12)


def test_local_normals_on_many_points_use_the_tree():
    rng = np.random.default_rng(5)
    points = np.column_stack([rng.uniform(0, 1, (700, 2)), np.zeros(700)])
    normals, _ = common.local_normals(points, 6)
    np.testing.assert_allclose(np.abs(normals[:, 2]), 1.0, atol=1e-9)


@pytest.mark.parametrize(
    "angles_deg, expected",
    [([0, 45, 90], 90.0), ([350, 10], 20.0), (np.arange(0, 360, 30), 330.0), ([5], 0.0)],
)
def test_arc_coverage_deg(angles_deg, expected):
    assert common.arc_coverage_deg(np.radians(angles_deg)) == pytest.approx(expected)


@pytest.mark.parametrize(
    "points, dimensions, message",
    [
        (np.ones((6, 3)), 1, "identical"),
        (np.outer(np.arange(6.0), [1, 2, 3]), 2, "collinear"),
        (np.column_stack([np.arange(6.0), np.arange(6.0) ** 2, np.zeros(6)]), 3, "coplanar"),
    ],
)
def test_check_spread_judges_a_spread_as_require_spread_judges_points(points, dimensions, message):
    _, spread, _ = common.principal_axes(points)
    with pytest.raises(FitError, match=message):
        common.check_spread(spread, "cylinder", dimensions)
    # One dimension fewer is fine for both.
    if dimensions > 1:
        common.check_spread(spread, "cylinder", dimensions - 1)
        common.require_spread(points, "cylinder", dimensions - 1)


@pytest.mark.parametrize("slope", [0.0, 3e-6])
def test_incidence_variance_is_the_least_squares_line_of_squared_residuals(slope):
    rng = np.random.default_rng(4)
    square_on = rng.uniform(0.0, 1.0, 200)
    residuals = rng.normal(0.0, 1.0, 200) * np.sqrt(1e-7 + slope * square_on)
    mask = np.ones(200, bool)
    relative = common.incidence_variance(residuals, square_on, mask)
    if slope == 0.0:
        assert relative is None  # no evidence of a slope: even noise
        return
    level_slope = np.polyfit(square_on, residuals**2, 1)  # (slope, level), independent solver
    expected = (level_slope[1] + level_slope[0] * square_on) / level_slope.sum()
    np.testing.assert_allclose(
        relative, np.clip(expected, common.MIN_RELATIVE_VARIANCE, 1.0), rtol=1e-9
    )


def test_scoring_subset_keeps_sparse_scans_whole_and_scales_keep():
    from asbuilt.fit._common import SCORED_POINTS, scoring_subset

    rng = np.random.default_rng(0)
    sparse = rng.uniform(size=(40, 3))
    same, keep = scoring_subset(sparse, 30, rng)
    assert same is sparse and keep == 30
    dense = rng.uniform(size=(4 * SCORED_POINTS, 3))
    subset, keep = scoring_subset(dense, 3 * SCORED_POINTS, rng)
    assert subset.shape == (SCORED_POINTS, 3) and keep == 3 * SCORED_POINTS // 4
    assert len(np.unique(subset, axis=0)) == SCORED_POINTS  # drawn without replacement


@pytest.mark.parametrize(
    ("kind", "message"),
    [
        ("cylinder", "A cylinder needs at least 6 points, got 5; measure more points."),
        ("auto", 'An object of kind "auto" needs at least 7 points, got 5; measure more points.'),
    ],
)
def test_too_few_points_name_the_kind(kind, message):
    with pytest.raises(FitError) as err:
        common.validate_points(np.eye(5, 3), kind)
    assert str(err.value) == message


@pytest.mark.parametrize("columns", [2, 3])
def test_row_norms_are_numpys_norms_exactly(columns):
    v = np.random.default_rng(columns).normal(0.0, 3.0, (200, columns))
    v[0] = 0.0
    np.testing.assert_array_equal(common.row_norms(v), np.linalg.norm(v, axis=1))


def test_extent_across_an_axis_leaves_out_the_span_along_it():
    """A strip 40 m long and 2 m wide: 40 m across its points, 2 m across an axis along it
    (all a cylinder laid along the strip curves over), the full span again across an axis
    normal to the strip."""
    rng = np.random.default_rng(3)
    strip = np.column_stack([rng.uniform(-20, 20, 200), rng.uniform(-1, 1, 200), np.zeros(200)])
    strip[:2, :2] = [[-20, -1], [20, 1]]  # the corners: the extents are exact
    full = 2 * np.linalg.norm(strip - strip.mean(axis=0), axis=1).max()
    assert common.extent_of(strip) == pytest.approx(full)
    across = strip[:, 1] - strip[:, 1].mean()
    assert common.extent_of(strip, np.array([1.0, 0.0, 0.0])) == pytest.approx(
        2 * np.abs(across).max()
    )
    assert common.extent_of(strip, np.array([0.0, 0.0, 1.0])) == pytest.approx(full)


def test_the_extent_of_the_points_leaves_out_a_stray_kilometres_off():
    """The mixture scores' outlier range: one return 7.4 km off among 36 shots spread over
    20 m made it 370 times the scene's; it is the scene's without the stray, and any point
    set without one keeps its plain bounding-box diagonal."""
    from asbuilt.fit._common import diagonal_extent

    rng = np.random.default_rng(3)
    scene = rng.uniform([10.0, -5.0, 0.0], [25.0, 5.0, 6.0], (36, 3))
    plain = float(np.linalg.norm(np.ptp(scene, axis=0)))
    assert diagonal_extent(scene) == plain
    stray = np.vstack([scene, [7400.0, 0.0, 1.5]])
    assert diagonal_extent(stray) == plain
    # Two shots far apart with nothing between are the scene, not strays.
    pair = np.vstack([scene[:3], scene[:3] + [500.0, 0.0, 0.0]])
    assert diagonal_extent(pair) == float(np.linalg.norm(np.ptp(pair, axis=0)))
