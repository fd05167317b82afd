"""Tests for asbuilt.fit._vectors: the cuboid fit's cross products, unit rows and bases."""

from __future__ import annotations

import numpy as np

from asbuilt.fit._vectors import cross3, cross_rows, perpendicular_basis, unit_rows


def test_perpendicular_basis_is_the_normalised_cross_products():
    rng = np.random.default_rng(8)
    for direction in rng.normal(size=(50, 3)):
        direction /= np.linalg.norm(direction)
        helper = np.eye(3)[int(np.argmin(np.abs(direction)))]
        first = np.cross(direction, helper)
        first /= np.linalg.norm(first)
        expected = np.stack([first, np.cross(direction, first)], axis=1)
        got = perpendicular_basis(direction)
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)
        np.testing.assert_allclose(got.T @ got, np.eye(2), atol=1e-12)
        np.testing.assert_allclose(got.T @ direction, 0.0, atol=1e-12)


def test_cross_products_match_numpy():
    rng = np.random.default_rng(9)
    a, b = rng.normal(size=(2, 20, 3))
    np.testing.assert_allclose(cross_rows(a, b), np.cross(a, b), rtol=0, atol=1e-15)
    np.testing.assert_allclose(cross_rows(a[0], b), np.cross(a[0], b), rtol=0, atol=1e-15)
    np.testing.assert_allclose(cross3(a[0], b[0]), np.cross(a[0], b[0]), rtol=0, atol=1e-15)


def test_unit_rows_leave_zero_rows_at_zero():
    vectors = np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -2.0]])
    unit, ok = unit_rows(vectors)
    np.testing.assert_allclose(unit, [[0.6, 0.8, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    assert ok.tolist() == [True, False, True]
