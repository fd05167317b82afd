"""The joint face fit's frame choice: plausibility and the information criterion."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit._joint import FaceModel, _information, _rejected_are_background, plausible


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


# A column's two seen faces, x = 0.2 (outward +x) and y = 0.2 (outward +y), seen from (5, 5, 0).
_NOISE, _CUTOFF = 0.002, 3.0  # an inlier cutoff of 6 mm


def _column_fit(rejected: np.ndarray, spread: float = 0.002):
    """A fit of 32 shots on the column's faces, residuals of RMS ``spread`` metres, that
    rejected ``rejected`` (r, 3) metres."""
    rng = np.random.default_rng(3)
    on_x = np.column_stack([np.full(16, 0.2), rng.uniform(-0.2, 0.2, 16), rng.uniform(-1, 1, 16)])
    on_y = np.column_stack([rng.uniform(-0.2, 0.2, 16), np.full(16, 0.2), rng.uniform(-1, 1, 16)])
    x = np.vstack([on_x, on_y, rejected])
    inliers = np.arange(len(x)) < 32
    label = np.repeat([0, 1, 0], [16, 16, len(rejected)])
    residual = np.where(inliers, spread * np.resize([1.0, -1.0], len(x)), 1.0)
    return (_model([0, 1], [1, 1], [0.2, 0.2]), label, residual, inliers), x


# Shots behind both faces, scattered over metres as mixed returns and the wall behind are
# (which of them can only be background is tested in test_cuboid_background.py).
_BEHIND = np.column_stack(
    [
        np.random.default_rng(11).uniform(-3.0, -0.3, 8),
        np.random.default_rng(12).uniform(-3.0, -0.3, 8),
        np.random.default_rng(13).uniform(-1.0, 1.0, 8),
    ]
)


def test_rejected_shots_behind_every_seen_face_are_background():
    assert _rejected_are_background(*_column_fit(_BEHIND), _NOISE, _CUTOFF)


def test_more_background_than_a_quarter_of_the_shots_is_left_to_the_other_frames():
    many = np.vstack([_BEHIND, _BEHIND[:3] + [-0.5, -0.7, 0.2]])  # 11 of 43
    assert _rejected_are_background(*_column_fit(many[:10]), _NOISE, _CUTOFF)  # 10 of 42
    assert not _rejected_are_background(*_column_fit(many), _NOISE, _CUTOFF)


def test_inliers_spread_wider_than_the_noise_leave_the_frame_to_the_others():
    # With the same inliers another frame can label them better: the inliers' residuals must
    # pass the chi-square test at the noise level (32 residuals of 2 mm pass; of 3 mm fail).
    assert _rejected_are_background(*_column_fit(_BEHIND, 0.002), _NOISE, _CUTOFF)
    assert not _rejected_are_background(*_column_fit(_BEHIND, 0.003), _NOISE, _CUTOFF)


def _box_raster(station, centre, axes, size, columns, rows, seed, sigma=0.002):
    """A pan-tilt raster of ``columns`` x ``rows`` beams from ``station`` (3,) metres over the
    angular window of a box (``centre`` (3,), ``axes`` (3, 3) rows, ``size`` (3,) metres), beams
    at the cells' centres: the first hit of each, ``sigma`` metres of range noise along it."""
    rng = np.random.default_rng(seed)
    station = np.asarray(station, dtype=np.float64)
    signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1])).T.reshape(-1, 3)
    corners = centre + (signs * size / 2) @ axes - station
    pan = np.arctan2(corners[:, 1], corners[:, 0])
    tilt = np.arctan2(corners[:, 2], np.hypot(corners[:, 0], corners[:, 1]))
    shots = []
    for i in range(columns):
        p = pan.min() + (i + 0.5) * np.ptp(pan) / columns
        for j in range(rows):
            t = tilt.min() + (j + 0.5) * np.ptp(tilt) / rows
            beam = np.array([np.cos(t) * np.cos(p), np.cos(t) * np.sin(p), np.sin(t)])
            start, along = axes @ (station - centre), axes @ beam
            with np.errstate(divide="ignore"):
                a, b = (-size / 2 - start) / along, (size / 2 - start) / along
            near, far = np.max(np.minimum(a, b)), np.min(np.maximum(a, b))
            if 0.0 < near <= far:
                shots.append(station + (near + rng.normal(0.0, sigma)) * beam)
    return np.array(shots)


@pytest.mark.parametrize("yaw_deg", [60.0, 70.0, 80.0, 90.0])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_narrow_side_seen_edge_on_by_one_raster_column_keeps_the_true_frame(yaw_deg, seed):
    # A 0.21 x 0.18 m column 3.6 m away, 4 x 5 raster shots: three raster columns on the wide
    # face, one on the narrow side seen at 80-85 degrees. That side is one line of shots in a
    # plane through the station, as a fan of beams is; the frame ranked first instead was
    # 25-37 degrees off (yaw 60 and 80), through two raster columns of different faces, with
    # a whole raster column of the wide face rejected and an axis standard error under 2
    # degrees.
    from asbuilt.fit import fit_points

    yaw = np.radians(yaw_deg)
    axes = np.array(
        [[np.cos(yaw), np.sin(yaw), 0.0], [-np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]]
    )
    station = np.array([1.2, 3.36, 1.7])
    points = _box_raster(
        station, np.array([0.0, 0.0, 1.5]), axes, np.array([0.21, 0.18, 3.0]), 4, 5, seed
    )
    fit = fit_points("cuboid", points, sigma=0.002, viewpoint=station)
    cosines = np.abs(axes @ fit.primitive.axes.T).max(axis=1)
    assert np.degrees(np.arccos(np.minimum(cosines, 1.0))).max() < 2.0
    assert fit.inliers.all()
