"""Which shots a cuboid frame leaves out can only be background (asbuilt.fit._cuboid_background)."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit._cuboid_background import only_background

_WIDTH = 0.006  # the inlier cutoff: 3 sigmas of 2 mm


def _faces_seen(face_axis, n: int = 32) -> np.ndarray:
    """Shots on a 0.4 x 0.4 x 2 m column's faces x = 0.2 and (for two faces) y = 0.2."""
    rng = np.random.default_rng(3)
    on_x = np.column_stack([np.full(n, 0.2), rng.uniform(-0.2, 0.2, n), rng.uniform(-1, 1, n)])
    on_y = np.column_stack([rng.uniform(-0.2, 0.2, n), np.full(n, 0.2), rng.uniform(-1, 1, n)])
    return np.vstack([on_x[: n // 2], on_y[: n // 2]]) if len(face_axis) == 2 else on_x


def _background(face_axis, left_out: np.ndarray) -> bool:
    """``only_background`` for a column seen from (5, 5, 0), axes x, y, z, faces outward +x
    (and +y), at offsets 0.2."""
    face_axis = np.array(face_axis)
    normals = np.eye(3)[face_axis]
    signed = left_out @ normals.T - 0.2
    kept = _faces_seen(face_axis)
    n = len(kept) + len(left_out)
    return only_background(np.eye(3), face_axis, signed, kept, left_out, n, _WIDTH)


# Mixed returns and wall shots scattered over metres behind both faces.
_SCATTER = np.array(
    [
        [-1.7, -0.9, 0.3],
        [-2.4, 0.05, -0.6],
        [-0.8, -2.2, 0.8],
        [-1.1, -1.5, -0.2],
        [-3.0, -0.3, 0.55],
        [-0.35, -2.9, -0.9],
    ]
)
# One raster row's shots on the wall behind: one height, so one plane across the column's axis
# (which no seen face is normal to), metres off the box.
_WALL_ROW = np.array([[-1.6, -1.0, 0.3], [-1.3, -1.45, 0.301], [-0.9, -1.9, 0.299]])
# Three shots on the column's top (z = 1.05): a face the frame left out, behind both faces.
_TOP = np.array([[-0.1, -0.1, 1.05], [0.1, -0.15, 1.052], [-0.05, 0.1, 1.049]])


@pytest.mark.parametrize(
    "face_axis, left_out, background, why",
    [
        ([0, 1], _SCATTER, True, "scattered behind both faces"),
        ([0, 1], np.vstack([_SCATTER[:4], _WALL_ROW]), True, "a wall row, metres off the box"),
        ([0, 1], np.vstack([_SCATTER[:4], _TOP]), False, "the top: a face left out"),
        ([0, 1], np.vstack([_SCATTER[:4], _TOP[:2]]), True, "two shots make no face"),
        ([0, 1], np.vstack([_SCATTER[:5], [[0.5, -0.4, 0.0]]]), False, "one in front of x = 0.2"),
        ([0, 1], np.vstack([_SCATTER[:5], [[0.19, -1.0, 0.0]]]), False, "within twice the cutoff"),
        ([0, 1], np.vstack([_SCATTER[:5], [[-1.0, 0.21, 0.0]]]), False, "just in front of y = 0.2"),
        # One face spans nothing along its normal: a side at grazing incidence may lie any
        # depth behind it, so the wall row may be a face there.
        ([0], _SCATTER, True, "one face, scattered"),
        ([0], np.vstack([_SCATTER[:4], _WALL_ROW]), False, "one face, a wall row"),
    ],
)
def test_only_background(face_axis, left_out, background, why):
    assert _background(face_axis, left_out) is background, why
