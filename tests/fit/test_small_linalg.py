"""The cylinder fit's small solve and eigh against numpy.linalg's public functions.

They call numpy's private generalised ufuncs; these tests catch a numpy whose private module
changed its behaviour (the values, or the error on a singular matrix).
"""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit import _small_linalg


@pytest.fixture(params=["private ufuncs", "public fallback"])
def linalg(request, monkeypatch):
    if request.param == "public fallback":
        monkeypatch.setattr(_small_linalg, "_umath_linalg", None)
    return _small_linalg


@pytest.mark.parametrize("shape", [(3, 3), (7, 3, 3), (2, 5, 4, 4)])
def test_solve_is_numpys_bit_for_bit(linalg, shape):
    rng = np.random.default_rng(len(shape))
    normal = rng.normal(size=shape)
    right = rng.normal(size=shape[:-1] + (2,))
    assert np.array_equal(linalg.solve(normal, right), np.linalg.solve(normal, right))


def test_solve_raises_linalgerror_on_a_singular_matrix(linalg):
    normal = np.stack([np.eye(3), np.zeros((3, 3))])
    with pytest.raises(np.linalg.LinAlgError):
        linalg.solve(normal, np.ones((2, 3, 1)))


@pytest.mark.parametrize("shape", [(3, 3), (6, 3, 3)])
def test_eigh_is_numpys_bit_for_bit(linalg, shape):
    rng = np.random.default_rng(len(shape) + 10)
    half = rng.normal(size=shape)
    matrix = half @ np.swapaxes(half, -1, -2)
    values, vectors = linalg.eigh(matrix)
    expected_values, expected_vectors = np.linalg.eigh(matrix)
    assert np.array_equal(values, expected_values)
    assert np.array_equal(vectors, expected_vectors)
