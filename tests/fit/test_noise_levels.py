"""The residual noise level of a fit made without the sensor's sigma (asbuilt.fit._noise_levels)."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit._noise_levels import _residual_noise
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Plane
from asbuilt.tolerances import DEFAULT_TOLERANCES


def _fit(residuals, parameters: int = 5) -> FitResult:
    residuals = np.asarray(residuals, dtype=np.float64)
    return FitResult(
        primitive=Plane(normal=[0.0, 0.0, 1.0], point=[0.0, 0.0, 0.0]),
        residuals=residuals,
        inliers=np.ones(residuals.size, dtype=bool),
        stderr={},
        sigma=0.002,
        sigma_source="residuals",
        method="test",
        covariance=np.eye(parameters),
    )


def _points(n: int) -> np.ndarray:
    return np.column_stack([np.arange(n, dtype=float), np.zeros(n), np.zeros(n)])


@pytest.mark.parametrize(
    ("residual_mm", "n", "expected_mm"),
    [
        # Enough degrees of freedom: the RMS with the fit's 5 parameters taken off.
        (1.0, 20, np.sqrt(20 / 15)),
        # 9 shots, 4 degrees of freedom: the missing one counts as a 2 mm prior residual
        # (noise_level's rule), where the RMS alone had claimed 1.5 mm.
        (1.0, 9, np.sqrt((9 * 1.0 + 4.0) / 5)),
        # As many shots as parameters: five prior residuals join theirs.
        (1.0, 5, np.sqrt((5 * 1.0 + 5 * 4.0) / 5)),
    ],
)
def test_few_degrees_of_freedom_are_pooled_with_the_prior(residual_mm, n, expected_mm):
    result = _fit(np.full(n, residual_mm / 1000))
    noise = _residual_noise(result, _points(n), DEFAULT_TOLERANCES)
    assert noise == pytest.approx(expected_mm / 1000)
