"""The count of a fit's rejected shots that lie behind it seen from the station."""

from __future__ import annotations

import numpy as np
import pytest
from test_cylinder_background import _pipe_before_wall, _plumb_pipe_before_wall

from asbuilt.fit import fit_points
from asbuilt.fit._background_count import behind_fit, with_background_count
from asbuilt.fit.result import BACKGROUND_KEYS, BACKGROUND_SHOTS
from asbuilt.primitives import Cuboid, Cylinder, Plane, Sphere
from asbuilt.tolerances import DEFAULT_TOLERANCES

STATION = np.zeros(3)
#: A 4 in pipe (r 57.15 mm) 5 m in front of the station along +y, its axis along x.
PIPE = Cylinder(np.array([0.0, 5.0, 0.0]), np.array([1.0, 0.0, 0.0]), 0.05715, 2.0)
CUTOFF = 0.006


def _counted(result) -> float:
    return sum(result.diagnostics.get(key, 0.0) for key in BACKGROUND_KEYS)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("scene", [_pipe_before_wall, _plumb_pipe_before_wall])
def test_every_rejected_wall_shot_and_no_pipe_shot_is_counted(scene, seed):
    points, on_pipe, _ = scene(np.random.default_rng(seed))
    result = fit_points("cylinder", points, sigma=0.002, viewpoint=STATION)
    assert _counted(result) == np.count_nonzero(~result.inliers & ~on_pipe)
    assert not behind_fit(result.primitive, points[on_pipe], STATION, CUTOFF).any()


@pytest.mark.parametrize(
    "point, expected",
    [
        ([0.3, 7.0, 0.0], True),  # the wall 2 m behind, the beam through the pipe's side
        ([0.3, 7.0, 0.4], True),  # the wall, the beam clear above the pipe
        ([0.3, 4.5, 0.3], False),  # something in front of the pipe, off it
        ([0.3, 5.2, 0.01], False),  # past the pipe's axis, the beam through its middle
        ([1.6, 7.0, 0.0], True),  # past the pipe's end (1 m from its centre)
    ],
)
def test_behind_a_cylinder(point, expected):
    point = np.asarray(point, dtype=np.float64)
    if np.isclose(point[2], 0.0) and point[1] > 6:
        # aimed at the wall through the pipe's top edge, the beam 1 mm inside its radius:
        # a 21 mm chord, but background (pointing noise, a radius fitted a little wide)
        beam = np.array([0.3, 5.0, PIPE.radius - 0.001])
        point = beam / np.linalg.norm(beam) * 7.0
    assert behind_fit(PIPE, point[None, :], STATION, CUTOFF)[0] == expected


def test_a_beam_through_the_pipe_is_not_background():
    # aimed at the pipe's axis, recorded 2 m past it: no beam reaches a wall through a pipe
    beam = np.array([0.3, 5.0, 0.0])
    point = beam / np.linalg.norm(beam) * 7.0
    assert not behind_fit(PIPE, point[None, :], STATION, CUTOFF)[0]


def test_spheres_and_boxes_use_their_own_tests_and_planes_have_none():
    sphere = Sphere(np.array([0.0, 5.0, 0.0]), 0.5)
    box = Cuboid(np.array([0.0, 5.0, 0.0]), np.eye(3), np.array([1.0, 1.0, 1.0]))
    wall = np.array([[1.2, 8.0, 0.0], [0.0, 4.0, 0.0]])  # beside it, 3 m behind; in front
    assert behind_fit(sphere, wall, STATION, CUTOFF).tolist() == [True, False]
    assert behind_fit(box, wall, STATION, CUTOFF).tolist() == [True, False]
    plane = Plane(np.array([0.0, 5.0, 0.0]), np.array([0.0, 1.0, 0.0]))
    assert not behind_fit(plane, wall, STATION, CUTOFF).any()


def test_without_a_station_nothing_is_counted():
    points, on_pipe, _ = _pipe_before_wall(np.random.default_rng(1))
    result = fit_points("cylinder", points, sigma=0.002)
    assert BACKGROUND_SHOTS not in result.diagnostics or _counted(result) <= np.count_nonzero(
        ~result.inliers & ~on_pipe
    )
    assert with_background_count(result, points, None, 0.002, DEFAULT_TOLERANCES) is result


def test_the_count_only_adds_to_the_diagnostics():
    points, _, _ = _pipe_before_wall(np.random.default_rng(2))
    plain = fit_points("cylinder", points, sigma=0.002)  # nothing to count without a station
    counted = with_background_count(plain, points, STATION, 0.002, DEFAULT_TOLERANCES)
    assert counted.diagnostics[BACKGROUND_SHOTS] > 0
    assert repr(counted.primitive) == repr(plain.primitive)
    assert (counted.inliers == plain.inliers).all() and counted.notes == plain.notes
