"""Tests for asbuilt.fit._faces: neighbours, local normals, noise level, rectangles, segmentation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from asbuilt.fit import _faces
from asbuilt.fit._neighbours import local_normals
from asbuilt.fit._vectors import perpendicular_basis


def _plane_points(rng, normal, n=60, noise=0.0):
    normal = np.asarray(normal, float) / np.linalg.norm(normal)
    basis = perpendicular_basis(normal)
    uv = rng.uniform(-0.5, 0.5, size=(n, 2))
    return uv @ basis.T + rng.normal(0.0, noise, n)[:, None] * normal, normal


@pytest.mark.parametrize("noise", [0.001, 0.003])
def test_noise_scale_is_recovered_on_two_faces(noise):
    rng = np.random.default_rng(3)
    a, na = _plane_points(rng, [1.0, 0.0, 0.0], noise=noise)
    b, nb = _plane_points(rng, [0.0, 1.0, 0.0], noise=noise)
    pts = np.vstack([a, b + [0.0, 0.5, 0.0]])
    normals, rms, _ = local_normals(pts, 6)
    est = _faces.noise_scale(pts, normals, rms, 1e-4)
    assert est == pytest.approx(noise, rel=0.35)


def test_segment_finds_two_perpendicular_faces_of_a_corner():
    rng = np.random.default_rng(5)
    # Two faces of a box corner: x = 0 (y in [0, 0.4]) and y = 0 (x in [0, 0.3]), z in [0, 1].
    ys, zs = np.meshgrid(np.linspace(0.02, 0.38, 4), np.linspace(0.05, 0.95, 5))
    xs, zs2 = np.meshgrid(np.linspace(0.02, 0.28, 3), np.linspace(0.05, 0.95, 5))
    face_a = np.column_stack([np.zeros(ys.size), ys.ravel(), zs.ravel()])
    face_b = np.column_stack([xs.ravel(), np.zeros(xs.size), zs2.ravel()])
    pts = np.vstack([face_a, face_b]) + rng.normal(0.0, 0.0005, (ys.size + xs.size, 3))
    pts = pts - pts.mean(axis=0)
    normals, _, _ = local_normals(pts, 6)
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
    normals, _, _ = local_normals(pts, 4)
    assert _faces.segment(pts, normals, 0.001, 0.1, 20.0) is None


def test_dense_paths_give_what_the_dense_matrices_give(monkeypatch):
    # Above _DENSE_LIMIT points the pair counts are sorted, not a dense matrix: same counts
    # (but for a pair exactly the threshold apart, where rounding may go either way).
    rng = np.random.default_rng(5)
    values = rng.uniform(0, 1, 900)
    sorted_counts = _faces._within(values, 0.01)
    dense = (np.abs(values[:, None] - values[None, :]) < 0.01).sum(axis=1)
    np.testing.assert_array_equal(sorted_counts, dense)


# The hot-path helpers below replace numpy conveniences by cheaper calls; each must give the
# convenience's answer bit for bit (the fit's decisions must not change).


@pytest.mark.parametrize("r", [2, 3, 4, 17, 18, 35, 60])
def test_pairs_by_position_are_triu_indices(r):
    i, j = np.triu_indices(r, 1)
    every = np.arange(i.size)
    got_i, got_j = _faces._pairs(r, every)
    np.testing.assert_array_equal(got_i, i)
    np.testing.assert_array_equal(got_j, j)
    some = np.random.default_rng(r).choice(i.size, min(i.size, 7), replace=False)
    got_i, got_j = _faces._pairs(r, some)
    np.testing.assert_array_equal(got_i, i[some])
    np.testing.assert_array_equal(got_j, j[some])


def test_distinct_is_the_greedy_suppression_in_order():
    # Reference: take planes in order, skipping any the same as one already taken (direction
    # within cos_face and offset within twice the threshold).
    rng = np.random.default_rng(9)
    normals = rng.normal(size=(60, 3))
    normals[20:40] = normals[:20] + rng.normal(0.0, 0.01, (20, 3))  # near-duplicates
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    offsets = rng.choice([0.0, 0.5, 1.0], 60) + rng.normal(0.0, 0.001, 60)
    order = rng.permutation(60)
    cos_face, threshold = math.cos(math.radians(10.0)), 0.01
    for limit in (1, 3, 8, 60):
        expected: list[int] = []
        for c in order[: 8 * limit]:
            same = [
                abs(normals[c] @ normals[e]) > cos_face
                and abs(offsets[c] - offsets[e]) < 2 * threshold
                for e in expected
            ]
            if not any(same) and len(expected) < limit:
                expected.append(int(c))
        assert _faces._distinct(normals, offsets, order, cos_face, threshold, limit) == expected


def test_frame_score_counts_points_near_a_face():
    # Two faces of a unit cube corner: points on them, one point off both.
    pts = np.array([[0.5, 0.1, 0.2], [0.5, -0.3, 0.0], [0.1, 0.5, 0.3], [-0.2, 0.5, 0.1]])
    pts = np.vstack([pts, [[0.0, 0.0, 0.0]]])
    axes = np.eye(3)
    faces = [(0, 0.5, np.array([1, 1, 0, 0, 0], bool)), (1, 0.5, np.array([0, 0, 1, 1, 0], bool))]
    frame, dist = _faces._frame_and_distances(pts, axes, faces, 0.01, None)
    np.testing.assert_array_equal(frame.labels, [0, 0, 1, 1, -1])
    assert dist.shape == (5, 2)
    count, minus_ss = _faces._score(dist, 0.01)
    assert count == 4 and minus_ss == 0.0


def test_a_new_face_needs_a_seen_face_to_bound_it():
    """Faces whose masks hold no shot explain nothing: a candidate face then has no box to lie
    inside or touch, and is refused (it had raised numpy's "zero-size array" error)."""
    from asbuilt.fit._faces import _acceptable

    proj = np.random.default_rng(1).uniform(-0.2, 0.2, (12, 3))
    nothing = np.zeros(12, bool)
    mask = np.zeros(12, bool)
    mask[:5] = True
    faces = [(0, 0.2, nothing)]
    assert _acceptable(proj, nothing, faces, 1, 0.2, mask, 0.004, 0.05) is False
