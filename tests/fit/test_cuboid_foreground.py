"""The cuboid fit's foreground rescue (asbuilt.fit._cuboid_foreground): a beam or column whose
raster window is mostly the wall behind it."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from asbuilt.fit import fit_points
from asbuilt.fit._cuboid_foreground import beam_box, behind, contradicting, measured_part
from asbuilt.fit.result import BACKGROUND_KEYS
from asbuilt.primitives import Cuboid

CUBE = Cuboid(np.zeros(3), np.eye(3), np.array([2.0, 2.0, 2.0]))
VIEW = np.array([-5.0, 0.0, 0.0])


def test_beam_box_enters_and_leaves_where_the_slabs_say():
    ranges, entry, leave = beam_box(CUBE, np.array([[-1.0, 0.0, 0.0], [3.0, 0.5, 0.0]]), VIEW)
    assert ranges[0] == pytest.approx(4.0)
    assert entry[0] == pytest.approx(4.0) and leave[0] == pytest.approx(6.0)
    # the second beam rises 0.5 m over 8 m: through the cube from x = -1 to x = 1
    assert entry[1] == pytest.approx(4.0 * np.hypot(1, 0.5 / 8)) and entry[1] < leave[1]


def test_a_beam_that_misses_or_runs_parallel_outside_enters_after_it_leaves():
    points = np.array([[-1.0, 3.0, 0.0], [3.0, 0.0, 1.5]])
    view = np.array([-5.0, 0.0, 1.5])  # the second beam runs parallel to the z slabs, above
    _, entry, leave = beam_box(CUBE, points, view)
    assert (entry > leave).all()


@pytest.mark.parametrize(
    "point, expected",
    [
        ([-1.0, 0.0, 0.0], False),  # on the near face
        ([-1.004, 0.0, 0.0], False),  # in front by less than the cutoff
        ([-2.0, 0.0, 0.0], True),  # in front: the beam meets the box farther away
        ([0.0, 0.0, 0.0], True),  # inside: the beam stops at the surface
        ([-0.995, 0.0, 0.0], False),  # just inside, within the cutoff
        ([3.0, 0.0, 0.0], False),  # behind (seen through: not this test's question)
        ([-2.0, 3.0, 0.0], False),  # beside the box
    ],
)
def test_contradicting_shots_are_in_front_of_the_box_or_inside_it(point, expected):
    assert contradicting(CUBE, np.array([point]), VIEW, 0.006)[0] == expected


@pytest.mark.parametrize(
    "point, expected",
    [
        ([3.0, 2.5, 0.0], True),  # the wall beside the box, past it
        ([3.0, 0.0, 0.0], False),  # its beam runs through the box
        ([-2.0, 0.0, 0.0], False),  # in front of it
        ([-3.0, 1.5, 0.0], False),  # beside it, nearer than any of it along its beam
    ],
)
def test_background_lies_past_the_box_with_its_beam_clear_of_it(point, expected):
    assert behind(CUBE, np.array([point]), VIEW, 0.006)[0] == expected


def _ray_cast_beam_before_wall(rng, yaw_deg: float):
    """A 3 m x 0.2 m x 0.4 m steel beam 3.5 m up, seen from 1.5 m up and 5 m away at a yaw, in
    front of a wall 1.5 m behind it; a rectangular pan-tilt window around the beam (a
    diagonal strip in it), range noise 2 mm. Returns the shots (n, 3), the station, the box."""
    yaw = np.radians(yaw_deg)
    along = np.array([np.cos(yaw), np.sin(yaw), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    axes = np.vstack([along, np.cross(up, along), up])
    box = Cuboid(np.array([5.0, 0.0, 3.5]), axes, np.array([3.0, 0.2, 0.4]))
    station = np.array([0.0, 0.0, 1.5])
    wall_x = 5.0 + 1.5 + 1.5 * abs(np.sin(yaw))
    corners = box.corners - station
    pan = np.arctan2(corners[:, 1], corners[:, 0])
    tilt = np.arctan2(corners[:, 2], np.hypot(corners[:, 0], corners[:, 1]))
    pans = np.linspace(pan.min(), pan.max(), 12)
    tilts = np.linspace(tilt.min(), tilt.max(), 6)
    shots = []
    for p in pans:
        for t in tilts:
            d = np.array([np.cos(t) * np.cos(p), np.cos(t) * np.sin(p), np.sin(t)])
            # the box: slabs in its own frame, written out here independently of beam_box
            start = (station - box.center) @ axes.T
            step = axes @ d
            with np.errstate(divide="ignore"):
                a = (-0.5 * box.size - start) / step
                b = (0.5 * box.size - start) / step
            near, far = np.minimum(a, b).max(), np.maximum(a, b).min()
            hit = near if near < far and near > 0 else (wall_x - station[0]) / d[0]
            shots.append(station + (hit + rng.normal(0.0, 0.002)) * d)
    return np.array(shots), station, box


@pytest.mark.parametrize("yaw_deg", [25.0, 40.0, 55.0, 70.0])
def test_a_beam_whose_window_is_mostly_wall_is_fitted_from_its_own_shots(yaw_deg):
    # Before the rescue these fits were boxes 2-4 m across through beam and wall.
    rng = np.random.default_rng(int(yaw_deg))
    points, station, box = _ray_cast_beam_before_wall(rng, yaw_deg)
    on_box = np.abs(box.distance(points)) < 0.01
    assert on_box.sum() < 0.5 * len(points)  # most of the window is wall
    fit = fit_points("cuboid", points, sigma=0.002, viewpoint=station)
    cuboid = fit.primitive
    # each fitted axis against the true one it is nearest
    for k in range(3):
        j = int(np.argmax(np.abs(box.axes @ cuboid.axes[k])))
        assert abs(cuboid.axes[k] @ box.axes[j]) > np.cos(np.radians(2.0))
        # across the beam to a few centimetres; along it the ends lie somewhere in the raster
        # step beyond the last hits (0.3-0.6 m along a beam seen at these yaws)
        tolerance = 0.06 if box.size[j] < 1 else 0.15 * box.size[j]
        assert cuboid.size[k] == pytest.approx(box.size[j], abs=tolerance)
    assert not fit.inliers[~on_box].any()
    # The note and the count the rules read (the wall's shots are not outliers to them)
    # agree, whichever rescue told the wall apart (a plane behind, or the nearest surface).
    said = [
        int(n.split()[0])
        for n in fit.notes
        if "left out as background" in n or "lie on a floor, ceiling or wall" in n
    ]
    counted = [fit.diagnostics[k] for k in BACKGROUND_KEYS if k in fit.diagnostics]
    assert len(said) == 1 and counted == said


@pytest.mark.parametrize("from_normal_deg", [0.0, 30.0, 60.0, 80.0])
def test_a_one_face_fit_is_plated_on_the_face_it_saw_however_obliquely(from_normal_deg):
    # A column 0.3 x 0.3 x 3 m whose -x face was seen (its x depth made up): the plate lies on
    # that face, ``4 cutoff`` deep behind it, over its shots' span, whether the station faces
    # it or looks along it from far down the wall (where y, not x, points most toward it).
    column = Cuboid(np.array([0.0, 0.0, 1.5]), np.eye(3), np.array([0.3, 0.3, 3.0]))
    found = SimpleNamespace(primitive=column, diagnostics={"faces": 1.0, "assumed_size": 0.0})
    rng = np.random.default_rng(3)
    shots = np.column_stack(
        [np.full(20, -0.15), rng.uniform(-0.1, 0.1, 20), rng.uniform(0.5, 2.5, 20)]
    )
    turn = np.radians(from_normal_deg)
    view = np.array([-0.15 - 6.0 * np.cos(turn), -6.0 * np.sin(turn), 1.5])
    cutoff = 0.006
    plate = measured_part(found, shots, view, cutoff)
    np.testing.assert_allclose(plate.axes, np.eye(3))
    np.testing.assert_allclose(plate.size[0], 4.0 * cutoff)
    np.testing.assert_allclose(plate.center[0], -0.15 + 2.0 * cutoff)
    np.testing.assert_allclose(plate.size[1:], np.ptp(shots[:, 1:], axis=0))
