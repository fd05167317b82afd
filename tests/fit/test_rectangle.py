"""Tests for asbuilt.fit._rectangle (the minimum-area rectangle of one seen face)."""

import math

import numpy as np
import pytest

from asbuilt.fit._rectangle import min_area_rectangle


@pytest.mark.parametrize("angle", [0.0, 17.0, 45.0, 71.0])
def test_min_area_rectangle_finds_a_rotated_rectangle(angle):
    rng = np.random.default_rng(4)
    local = rng.uniform([-0.6, -0.2], [0.6, 0.2], size=(200, 2))
    local[:4] = [[-0.6, -0.2], [0.6, -0.2], [0.6, 0.2], [-0.6, 0.2]]
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    rot = np.array([[c, -s], [s, c]])
    sides = min_area_rectangle(local @ rot.T)
    assert np.allclose(sides @ sides.T, np.eye(2), atol=1e-12)
    assert (
        abs(abs(sides[0] @ rot[:, 0]) - 1.0) < 1e-9 or abs(abs(sides[0] @ rot[:, 1]) - 1.0) < 1e-9
    )
