"""FreshGenerator and the small-matrix gufuncs give numpy's own results, bit for bit."""

import numpy as np
import pytest

from asbuilt.fit import _small_linalg
from asbuilt.fit._common import FreshGenerator, diagonal_extent


@pytest.mark.parametrize("seed", [20, 40, 41])
def test_fresh_generator_draws_what_default_rng_draws(seed):
    draws = [(0, seed, (24, 3)), (0, 17, 32), (0, seed, 32)]
    for _ in range(2):  # the second pass from the remembered draws
        fresh, rng = FreshGenerator(seed), np.random.default_rng(seed)
        for draw in draws:
            got = fresh.integers(*draw)
            assert np.array_equal(got, rng.integers(*draw))
            got[...] = -1  # a caller's copy: the remembered draw is untouched
    assert np.array_equal(
        FreshGenerator(seed).integers(*draws[0]), np.random.default_rng(seed).integers(*draws[0])
    )


def test_small_linalg_matches_numpy_linalg():
    rng = np.random.default_rng(3)
    shots = rng.normal(size=(23, 3))
    jacobian = rng.normal(size=(31, 5))
    normal = jacobian.T @ jacobian
    for full in (False, True):
        for ours, theirs in zip(
            _small_linalg.svd(shots, full_matrices=full), np.linalg.svd(shots, full_matrices=full)
        ):
            assert np.array_equal(ours, theirs)
    assert np.array_equal(
        _small_linalg.singular_values(shots), np.linalg.svd(shots, compute_uv=False)
    )
    assert np.array_equal(_small_linalg.eigvalsh(normal), np.linalg.eigvalsh(normal))
    assert np.array_equal(_small_linalg.inv(normal), np.linalg.inv(normal))
    assert diagonal_extent(shots) == float(np.linalg.norm(np.ptp(shots, axis=0)))
    with pytest.raises(np.linalg.LinAlgError):
        _small_linalg.inv(np.zeros((3, 3)))
