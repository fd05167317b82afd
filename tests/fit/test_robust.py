"""The shared robust least-squares scheme: trimmed costs, Gauss-Newton, the robust loop."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit import _robust as robust
from asbuilt.fit import sphere as sphere_module
from asbuilt.tolerances import DEFAULT_TOLERANCES


def test_trimmed_cost_sums_the_smallest_squares():
    residuals = np.array([3.0, -1.0, 2.0, 10.0])
    assert robust.trimmed_cost(residuals, 2) == 5.0
    assert robust.trimmed_cost(residuals, 9) == 114.0


@pytest.mark.parametrize("n, keep", [(40, 30), (20, 15), (7, 6), (1, 1)])
def test_keep_count_trims_the_design_contamination(n, keep):
    assert robust.keep_count(n, DEFAULT_TOLERANCES) == keep


def test_robust_geometric_fit_rejects_background_points_and_refits_the_rest():
    rng = np.random.default_rng(6)
    directions = rng.normal(size=(40, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    points = 1.5 * directions + rng.normal(0, 0.001, (40, 3))
    points[:8] *= 1.5  # pushed 0.75 m outwards
    start = (np.zeros(3) + 0.1, 1.2)
    fit = robust.robust_geometric_fit(
        points, [start], sphere_module._MODEL, kind="sphere", tolerances=DEFAULT_TOLERANCES
    )
    assert fit.state[1] == pytest.approx(1.5, abs=0.002)
    np.testing.assert_array_equal(fit.inliers, np.arange(40) >= 8)
    assert fit.jacobian.shape == (32, 4)


def test_robust_geometric_fit_refuses_when_most_points_are_outliers():
    rng = np.random.default_rng(7)
    directions = rng.normal(size=(20, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    points = directions + rng.normal(0, 0.0005, (20, 3))
    points[:10] = rng.uniform(-3, 3, (10, 3))
    with pytest.raises(FitError, match=r"outliers to the best sphere"):
        robust.robust_geometric_fit(
            points, [(np.zeros(3), 1.0)], sphere_module._MODEL, kind="sphere", sigma=0.0005
        )


def test_robust_geometric_fit_needs_a_finite_start():
    with pytest.raises(FitError, match="No sphere fits"):
        robust.robust_geometric_fit(
            np.eye(4, 3), [(np.full(3, np.nan), 1.0)], sphere_module._MODEL, kind="sphere"
        )


def test_gauss_newton_steps_solve_singular_normal_equations_by_least_squares():
    # Positive definite: the Cholesky solve; singular: the minimum-norm least-squares step.
    normal = np.array([[4.0, 2.0], [2.0, 3.0]])
    np.testing.assert_allclose(
        robust._newton_step(normal, np.array([1.0, 2.0])), -np.linalg.solve(normal, [1.0, 2.0])
    )
    singular = np.array([[1.0, 0.0], [0.0, 0.0]])
    np.testing.assert_allclose(robust._newton_step(singular, np.array([2.0, 0.0])), [-2.0, 0.0])
