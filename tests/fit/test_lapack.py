"""numpy's LAPACK gufuncs called directly (:mod:`asbuilt.fit._lapack`): the public functions'
results bit for bit, and their errors."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit import _lapack as lapack


def _symmetric(rng, *shape):
    a = rng.normal(size=(*shape, 3))
    return a.swapaxes(-1, -2) @ a


@pytest.mark.parametrize("shape", [(3,), (40, 3), (5,)])
def test_results_are_numpys_bit_for_bit(shape):
    rng = np.random.default_rng(7)
    a = _symmetric(rng, *shape) if shape != (5,) else _symmetric(rng, 5, 5)[..., :3, :3]
    for mine, theirs in zip(lapack.eigh(a), np.linalg.eigh(a)):
        assert np.array_equal(mine, theirs)
    assert np.array_equal(lapack.eigvalsh(a), np.linalg.eigvalsh(a))
    assert np.array_equal(lapack.inv(a), np.linalg.inv(a))
    b = rng.normal(size=(*a.shape[:-1], 1))
    assert np.array_equal(lapack.solve(a, b), np.linalg.solve(a, b))
    points = rng.normal(size=(40, 3))
    for mine, theirs in zip(lapack.svd(points), np.linalg.svd(points, full_matrices=False)):
        assert np.array_equal(mine, theirs)


def test_failures_and_other_inputs_go_to_numpy():
    singular = np.zeros((2, 3, 3))
    singular[0] = np.eye(3)
    with pytest.raises(np.linalg.LinAlgError):
        lapack.solve(singular, np.ones((2, 3, 1)))
    with pytest.raises(np.linalg.LinAlgError):
        lapack.inv(np.zeros((3, 3)))
    nan = np.full((3, 3), np.nan)
    with pytest.raises(np.linalg.LinAlgError):
        lapack.eigh(nan)
    single = np.eye(3, dtype=np.float32)
    assert lapack.eigvalsh(single).dtype == np.float32


def test_a_numpy_without_these_gufuncs_is_not_used():
    """The import-time check: gufuncs missing, or giving other bits, mean the public functions."""

    class Renamed:  # a numpy whose private module lacks the names
        pass

    class Off:  # one that answers, but not as the public function does
        def __getattr__(self, name):
            def gufunc(*arrays, signature):
                outputs = signature.split("->")[1]
                return (
                    tuple(np.zeros_like(arrays[0]) for _ in outputs)[: len(outputs)]
                    if len(outputs) > 1
                    else np.zeros_like(arrays[0])
                )

            return gufunc

    assert not lapack._same_as_public(Renamed())
    assert not lapack._same_as_public(Off())
    from numpy.linalg import _umath_linalg

    assert lapack._same_as_public(_umath_linalg)
