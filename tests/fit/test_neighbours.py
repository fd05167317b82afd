"""Tests of asbuilt.fit._neighbours: nearest neighbours and local plane normals."""

from __future__ import annotations

import numpy as np

from asbuilt.fit._neighbours import knn, local_normals


def test_knn_matches_brute_force_for_small_and_large_sets():
    rng = np.random.default_rng(1)
    for n in (30, 300):
        pts = rng.normal(size=(n, 3))
        got = knn(pts, 5)
        d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
        np.fill_diagonal(d, np.inf)
        want = np.argsort(d, axis=1)[:, :5]
        assert np.array_equal(np.sort(got, axis=1), np.sort(want, axis=1))


def test_local_normals_of_a_plane_are_its_normal():
    rng = np.random.default_rng(2)
    normal = np.array([1.0, 2.0, 0.5]) / np.linalg.norm([1.0, 2.0, 0.5])
    helper = np.cross(normal, [1.0, 0.0, 0.0])
    basis = np.column_stack(
        [helper / np.linalg.norm(helper), np.cross(normal, helper / np.linalg.norm(helper))]
    )
    pts = rng.uniform(-0.5, 0.5, size=(40, 2)) @ basis.T
    normals, rms, index = local_normals(pts, 6)
    assert index.shape == (len(pts), 6)
    assert np.allclose(np.abs(normals @ normal), 1.0, atol=1e-9)
    assert rms.max() < 1e-7
