"""Tests for asbuilt.fit._faces: neighbours, local normals, noise level, rectangles, segmentation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from asbuilt.fit import _faces


def _plane_points(rng, normal, n=60, noise=0.0):
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    basis = _faces._perpendicular_basis(normal)
    uv = rng.uniform(-0.5, 0.5, size=(n, 2))
    return uv @ basis.T + rng.normal(0.0, noise, n)[:, None] * normal, normal


def test_knn_matches_brute_force_for_small_and_large_sets():
    rng = np.random.default_rng(1)
    for n in (30, 300):
        pts = rng.normal(size=(n, 3))
        got = _faces.knn(pts, 5)
        d = np.linalg.norm(pts[:, None] - pts[None], axis=2)
        np.fill_diagonal(d, np.inf)
        want = np.argsort(d, axis=1)[:, :5]
        assert np.array_equal(np.sort(got, axis=1), np.sort(want, axis=1))


def test_local_normals_of_a_plane_are_its_normal():
    pts, normal = _plane_points(np.random.default_rng(2), [1.0, 2.0, 0.5])
    normals, rms, index = _faces.local_normals(pts, 6)
    assert index.shape == (len(pts), 6)
    assert np.allclose(np.abs(normals @ normal), 1.0, atol=1e-9)
    assert rms.max() < 1e-7


@pytest.mark.parametrize("noise", [0.001, 0.003])
def test_noise_scale_is_recovered_on_two_faces(noise):
    rng = np.random.default_rng(3)
    a, na = _plane_points(rng, [1.0, 0.0, 0.0], noise=noise)
    b, nb = _plane_points(rng, [0.0, 1.0, 0.0], noise=noise)
    pts = np.vstack([a, b + [0.0, 0.5, 0.0]])
    normals, rms, _ = _faces.local_normals(pts, 6)
    est = _faces.noise_scale(pts, normals, rms, 1e-4)
    assert est == pytest.approx(noise, rel=0.35)


@pytest.mark.parametrize("angle", [0.0, 17.0, 45.0, 71.0])
def test_min_area_rectangle_finds_a_rotated_rectangle(angle):
    rng = np.random.default_rng(4)
    local = rng.uniform([-0.6, -0.2], [0.6, 0.2], size=(200, 2))
    local[:4] = [[-0.6, -0.2], [0.6, -0.2], [0.6, 0.2], [-0.6, 0.2]]
    c, s = math.cos(math.radians(angle)), math.sin(math.radians(angle))
    rot = np.array([[c, -s], [s, c]])
    sides = _faces.min_area_rectangle(local @ rot.T)
    assert np.allclose(sides @ sides.T, np.eye(2), atol=1e-12)
    assert (
        abs(abs(sides[0] @ rot[:, 0]) - 1.0) < 1e-9 or abs(abs(sides[0] @ rot[:, 1]) - 1.0) < 1e-9
    )


def test_segment_finds_two_perpendicular_faces_of_a_corner():
    rng = np.random.default_rng(5)
    # Two faces of a box corner: x = 0 (y in [0, 0.4]) and y = 0 (x in [0, 0.3]), z in [0, 1].
    ys, zs = np.meshgrid(np.linspace(0.02, 0.38, 4), np.linspace(0.05, 0.95, 5))
    xs, zs2 = np.meshgrid(np.linspace(0.02, 0.28, 3), np.linspace(0.05, 0.95, 5))
    face_a = np.column_stack([np.zeros(ys.size), ys.ravel(), zs.ravel()])
    face_b = np.column_stack([xs.ravel(), np.zeros(xs.size), zs2.ravel()])
    pts = np.vstack([face_a, face_b]) + rng.normal(0.0, 0.0005, (ys.size + xs.size, 3))
    pts = pts - pts.mean(axis=0)
    normals, _, _ = _faces.local_normals(pts, 6)
    frame = _faces.segment(pts, normals, 0.002, 0.3, 20.0)
    assert frame.n_faces == 2
    normals_seen = frame.face_sign[:, None] * frame.axes[frame.face_axis]
    # Outward normals point away from the box body (toward -x and -y).
    assert sorted(np.round(normals_seen @ [1.0, 0.0, 0.0]).tolist()) == [-1.0, 0.0]
    assert sorted(np.round(normals_seen @ [0.0, 1.0, 0.0]).tolist()) == [-1.0, 0.0]
    assert np.all(frame.labels >= 0)


def test_segment_returns_none_when_no_face_spans_two_dimensions():
    """Points on one line lie in every plane through it: no face."""
    pts = np.outer(np.linspace(-1.0, 1.0, 8), [1.0, 2.0, 3.0])
    pts[:, 0] += np.random.default_rng(6).normal(0.0, 1e-6, 8)
    normals, _, _ = _faces.local_normals(pts, 4)
    assert _faces.segment(pts, normals, 0.001, 0.1, 20.0) is None


def test_dense_paths_give_what_the_dense_matrices_give(monkeypatch):
    # Above _DENSE_LIMIT points the pair counts are sorted, not a dense matrix: same counts
    # (but for a pair exactly the threshold apart, where rounding may go either way).
    rng = np.random.default_rng(5)
    values = rng.uniform(0, 1, 900)
    sorted_counts = _faces._within(values, 0.01)
    dense = (np.abs(values[:, None] - values[None, :]) < 0.01).sum(axis=1)
    np.testing.assert_array_equal(sorted_counts, dense)


def test_spread_subset_with_a_tree_matches_the_dense_one(monkeypatch):
    from asbuilt.fit import cuboid

    rng = np.random.default_rng(11)
    x = rng.uniform(0, 1, (300, 3))
    base = rng.uniform(size=300) < 0.8
    dense = cuboid._spread_subset(x, base)
    monkeypatch.setattr(_faces, "_DENSE_LIMIT", 10)
    np.testing.assert_array_equal(cuboid._spread_subset(x, base), dense)
