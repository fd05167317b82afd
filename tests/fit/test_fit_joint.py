"""The joint face fit's frame choice: plausibility and the information criterion."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit._joint import FaceModel, _information, plausible


def _model(face_axis, face_sign, offsets) -> FaceModel:
    return FaceModel(np.eye(3), np.array(face_axis), np.array(face_sign, float), offsets, np.eye(3))


@pytest.mark.parametrize(
    "faces, signs, offsets, untrusted",
    [
        ([0, 1], [1, 1], [0.2, 0.2], True),  # two faces of a column
        ([0, 1, 2], [1, 1, 1], [0.2, 0.2, 0.6], True),  # a pier and its top
        ([0, 1, 0], [1, 1, -1], [0.2, 0.2, 0.2], False),  # opposite faces on axis 0
        ([0, 1, 0, 1], [1, 1, -1, -1], [0.2, 0.2, 0.2, 0.2], False),
    ],
)
def test_without_a_trusted_viewpoint_opposite_faces_are_implausible(
    faces, signs, offsets, untrusted
):
    model = _model(faces, signs, offsets)
    assert plausible(model, np.zeros(3), trusted=False) is untrusted


def test_with_a_trusted_viewpoint_the_faces_must_face_it():
    column = _model([0, 1], [1, 1], [0.2, 0.2])  # faces x = 0.2 and y = 0.2, outward +x, +y
    assert plausible(column, np.array([5.0, 5.0, 0.0]), trusted=True)
    assert not plausible(column, np.array([-5.0, 5.0, 0.0]), trusted=True)


def test_the_information_criterion_charges_faces_and_their_labels():
    # The same 40 residuals explained by two faces (30 + 10 points) or by four (10 each):
    # four faces pay two more offsets and the longer description of which face is which.
    rng = np.random.default_rng(1)
    residual = rng.normal(0.0, 0.002, 40)
    inliers = np.ones(40, bool)
    two = (_model([0, 1], [1, 1], [0.2, 0.2]), np.repeat([0, 1], [30, 10]), residual, inliers)
    four = (
        _model([0, 1, 0, 1], [1, 1, -1, -1], [0.2] * 4),
        np.repeat([0, 1, 2, 3], 10),
        residual,
        inliers,
    )
    assert _information(two, 0.002, 3.0) < _information(four, 0.002, 3.0)
    # Closer residuals win at equal faces; an outlier costs the cut-off and its label.
    tighter = (two[0], two[1], 0.5 * residual, inliers)
    assert _information(tighter, 0.002, 3.0) < _information(two, 0.002, 3.0)
    spoiled = residual.copy()
    spoiled[0] = 1.0
    outlier = (two[0], two[1], spoiled, inliers & (np.arange(40) != 0))
    assert _information(outlier, 0.002, 3.0) > _information(two, 0.002, 3.0) + 9.0 - 0.1


@pytest.mark.parametrize("rot_basis", [np.eye(3), np.eye(3)[:, 1:]])
def test_jacobian_matches_its_plain_construction(rot_basis):
    # Rotation columns (face normal x point, in the rotation basis), then -1 in each point's
    # face column: what the in-place fill must reproduce exactly.
    rng = np.random.default_rng(4)
    model = FaceModel(
        np.eye(3), np.array([0, 1, 2]), np.array([1.0, -1.0, 1.0]), [0.3, 0.2, 0.5], rot_basis
    )
    x = rng.normal(size=(25, 3))
    label = rng.integers(0, 3, 25)
    normal = model.normals()[label]
    onehot = (label[:, None] == np.arange(3)).astype(np.float64)
    expected = np.hstack([np.cross(normal, x) @ rot_basis, -onehot])
    np.testing.assert_array_equal(model.jacobian(x, label), expected)
