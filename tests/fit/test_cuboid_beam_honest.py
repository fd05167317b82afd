"""A receding beam's length the shots do not pin down says so.

Ray-cast beams of ``test_cuboid_receding_beam.py`` (0.2 x 0.4 m, 4-8 m long, 10-45 degrees off
the line of sight, their far part seen at 80-86 degrees, with and without a wall 1-3 m behind)
that the fit cut short. Whatever length it reports, the true one must lie within three
standard errors of it, or the standard error must be infinite (a lower bound): a raster's lone
corner shot taken for an edge-bisection shot had pinned the far end to 2 mm
(:mod:`asbuilt.fit._cuboid_edges`); the far part's shots, left out as background but lying on
a seen face's plane past the end, did not open it (:mod:`asbuilt.fit._cuboid_open`); and the
nearest surfaces' fit measured no raster gap at its far end (``SUBSET_GRAZING_DEG``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_cuboid_receding_beam import receding_beam_scan

from asbuilt.fit import fit_points
from asbuilt.fit._cuboid_edges import raster_corners
from asbuilt.fit._cuboid_open import open_past_faces
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Cuboid


@pytest.mark.parametrize(
    "wall, yaw_deg, pitch_deg, trial",
    [
        (False, 20, 0, 3),  # lone corner shot: 0.43 m short, +- 2 mm
        (False, 45, 0, 1),  # lone corner shot: 0.56 m short, +- 2 mm
        (True, 10, 0, 1),  # far part left out: 6.3 m short, +- 5 mm
        (True, 20, 10, 6),  # far part left out: 6.9 m short, +- 0.12 m
        (True, 10, 0, 3),  # far face's raster gap: 0.77 m short, +- 0.13 m
        (True, 20, 0, 7),  # far face's raster gap: 0.74 m short, +- 0.18 m
    ],
)
def test_a_short_beam_length_is_covered_by_its_standard_error(wall, yaw_deg, pitch_deg, trial):
    seed = 1000 * yaw_deg + 100 * pitch_deg + trial + 7 * wall
    points, _hit, beam = receding_beam_scan(seed, yaw_deg, pitch_deg, wall)
    fit = fit_points("cuboid", points, sigma=0.002, viewpoint=np.zeros(3))
    k = int(np.argmax(np.abs(np.asarray(fit.primitive.axes) @ beam.axes[0])))
    error = fit.primitive.size[k] - beam.size[0]
    stderr = fit.stderr["size"][k]
    assert not fit.observed[k]
    assert math.isinf(stderr) or abs(error) <= 3.0 * stderr


def test_a_lone_corner_shot_a_raster_step_away_is_a_raster_shot():
    # Shot 2 is alone on its row, a whole tilt step below its column's other shot: the
    # raster's corner. Shot 3 lies half a step from its partner: a bisection's.
    step = math.radians(1.0)
    angles = np.array([[0.0, 0.0], [step, 0.0], [step, -step], [0.0, 0.5 * step]])
    edges = (np.array([-1, -1, 1, 1]), np.array([-1, -1, 1, 0]))
    along, partner = raster_corners(edges, (None, angles, 0.0), np.array([step, step]))
    assert along.tolist() == [-1, -1, -1, 1]
    assert partner.tolist() == [-1, -1, -1, 0]


def _box_fit(points: np.ndarray, inliers: np.ndarray) -> FitResult:
    """A 2 x 0.2 x 0.4 m box along x fitted to ``inliers`` of ``points``, its length an extent."""
    box = Cuboid(center=np.zeros(3), axes=np.eye(3), size=np.array([2.0, 0.2, 0.4]))
    return FitResult(
        primitive=box,
        residuals=np.zeros(len(points)),
        inliers=inliers,
        stderr={"size": (0.05, 0.002, 0.002), "axes_deg": (0.1, 0.1, 0.1), "center": 0.03},
        sigma=0.002,
        sigma_source="sensor",
        method="test",
        observed=(False, True, False),
    )


def _side_shots(xs) -> np.ndarray:
    """Shots on the box's side face y = +0.1, at x (m,) metres, mid-height."""
    xs = np.asarray(xs, dtype=np.float64)
    return np.column_stack([xs, np.full(xs.size, 0.1), np.zeros(xs.size)])


def test_left_out_shots_on_a_seen_face_past_the_end_open_the_size():
    points = _side_shots([-0.9, -0.5, 0.0, 0.5, 0.9, 1.6, 2.4])
    inliers = np.array([True] * 5 + [False] * 2)
    opened = open_past_faces(_box_fit(points, inliers), points, 0.006)
    assert math.isinf(opened.stderr["size"][0])
    assert opened.stderr["size"][1:] == (0.002, 0.002)
    assert opened.diagnostics["open_sizes"] == 1.0


def test_left_out_shots_off_the_faces_leave_the_size_alone():
    # Past the end but a metre behind the side's plane (a wall), or a single stray shot on it.
    points = np.vstack([_side_shots([-0.9, -0.5, 0.0, 0.5, 0.9, 1.6]), [[2.0, 1.1, 0.0]]])
    inliers = np.array([True] * 5 + [False] * 2)
    fit = _box_fit(points, inliers)
    assert open_past_faces(fit, points, 0.006) is fit
