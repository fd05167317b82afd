"""The edge-bisection shots' helpers of the cuboid fit (asbuilt.fit._cuboid_bisection)."""

from __future__ import annotations

import numpy as np

from asbuilt.fit import _faces
from asbuilt.fit._cuboid_bisection import spread_subset


def test_spread_subset_with_a_tree_matches_the_dense_one(monkeypatch):
    rng = np.random.default_rng(11)
    x = rng.uniform(0, 1, (300, 3))
    base = rng.uniform(size=300) < 0.8
    dense = spread_subset(x, base)
    monkeypatch.setattr(_faces, "_DENSE_LIMIT", 10)
    np.testing.assert_array_equal(spread_subset(x, base), dense)
