"""Two raster lines on a column and one shot beside them that turns the frame.

Two vertical raster columns on a column leave its frame free to turn about them; a single
floor or wall shot from the raster column beside it can lie on a face turned to reach it (a
plane through one line and a point), and the fit then turned the column by it: on the clutter
benchmark 23-34 degrees at +-0.16 degree, 1.3-1.6 m wide for 0.25-0.55. Such a fit must
report the turn the two lines leave (:mod:`asbuilt.fit._cuboid_lone`). Scans ray cast as in
``test_cuboid_raster_line_frames``, plus the floor shot where the next raster column's beam
meets the floor on a plane through the last line turned ``turn`` degrees from across the
beams.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from test_cuboid_raster_line_frames import assert_turn_covered, column_scan

from asbuilt.fit import fit_points
from asbuilt.fit._cuboid_inside import ShotsInside
from asbuilt.fit._cuboid_lone import (
    OneLineFace,
    face_through_station,
    lone_shot_lines,
    one_line_and_lone_shot,
)
from asbuilt.fit.cuboid import _fit_box, fit_cuboid
from asbuilt.primitives import Cuboid
from asbuilt.tolerances import DEFAULT_TOLERANCES


def lone_shot_scan(yaw_deg: float, seed: int, turn_deg: float):
    """A column's two raster columns and one floor shot of the next raster column, on the plane
    through the last line turned ``turn_deg`` from across the beams toward the range.

    Returns the shots (n, 3) metres (the floor shot last), the true axes (3, 3) and size (3,),
    or None when the raster does not put exactly two columns on the box.
    """
    points, truth, hit, size = column_scan((0.3, 0.5, 2.6), 7.0, 10.0, yaw_deg, 2, seed)
    pan = np.arctan2(points[:, 1], points[:, 0])
    lines = np.unique(np.round(pan, 5))
    if hit != 2 or lines.size != 2:
        return None
    foot = points[np.abs(pan - lines[1]) < 1e-4, :2].mean(axis=0)
    beyond = 2.0 * lines[1] - lines[0]  # the next raster column's pan
    beam = np.array([math.cos(beyond), math.sin(beyond)])
    turn = math.radians(turn_deg)
    across = np.array([-math.sin(lines[1]), math.cos(lines[1])])
    radial = np.array([math.cos(lines[1]), math.sin(lines[1])])
    in_plane = math.cos(turn) * across + math.sin(turn) * radial
    normal = np.array([-in_plane[1], in_plane[0]])
    reach = float(normal @ foot) / float(normal @ beam)
    shot = np.array([reach * beam[0], reach * beam[1], -1.5])  # the floor, 1.5 m down
    return np.vstack([points, shot]), truth, size


@pytest.mark.parametrize("yaw", [70.0, 75.0, 80.0])
@pytest.mark.parametrize("turn", [40.0, 50.0, 65.0])
def test_a_lone_floor_shot_does_not_set_the_turn_of_two_raster_lines(yaw, turn):
    """Kept or not, the floor shot must not leave the fit claiming a turn the lines cannot
    fix (on the code before this check 17 of these 27 fits were 19-44 degrees off at
    +-0.2-9 degrees)."""
    for seed in range(3):
        scan = lone_shot_scan(yaw, seed, turn)
        if scan is None:
            continue
        points, truth, _ = scan
        assert_turn_covered(points, truth, seed)


def _trial(face_axis, x, label):
    """A fit tuple (model, label, residual, inliers) of a frame along the world axes, with
    every shot kept (what :func:`lone_shot_lines` reads of it)."""
    model = SimpleNamespace(
        axes=np.eye(3), face_axis=np.array(face_axis), offset=np.zeros(len(face_axis))
    )
    n = x.shape[0]
    return model, np.asarray(label), np.zeros(n), np.ones(n, dtype=bool)


def _line(u, v, n=8):
    return np.column_stack([np.full(n, u), np.full(n, v), np.linspace(0.0, 2.0, n)])


def assert_vertical_lines_and_lone_shot(found):
    """``found`` (:func:`lone_shot_lines`) holds shots 0-7 and 8-15 as the two lines, along
    z, and shot 16 as the lone one."""
    assert found is not None
    first, second, direction, lone = found
    assert np.flatnonzero(lone).tolist() == [16]
    assert sorted([np.flatnonzero(first).tolist(), np.flatnonzero(second).tolist()]) == [
        list(range(8)),
        list(range(8, 16)),
    ]
    assert abs(direction[2]) == pytest.approx(1.0)


def test_lone_shot_lines_finds_two_lines_and_a_lone_shot():
    width = 0.006
    # One line on each face (x = 0 and y = 0) and a shot on the first face beside its line.
    x = np.vstack([_line(0.0, 0.1), _line(0.1, 0.0), [[0.0, 0.9, 0.0]]])
    label = np.r_[np.zeros(8, int), np.ones(8, int), 0]
    found = lone_shot_lines(_trial([0, 1], x, label), x, width)
    assert_vertical_lines_and_lone_shot(found)


def test_lone_shot_lines_leaves_a_shot_that_tests_the_frame():
    width = 0.006
    # Both lines on one face (x = 0): a third shot on it tests their plane; it sets nothing.
    x = np.vstack([_line(0.0, 0.1), _line(0.0, 0.4), [[0.0, 0.9, 0.0]], [[0.2, 0.0, 0.0]]])
    label = np.r_[np.zeros(17, int), 1]
    trial = _trial([0, 1], x, label)
    # Two shots beside the lines are more than one.
    assert lone_shot_lines(trial, x, width) is None
    x, label = x[:17], label[:17]
    trial = _trial([0, 1], x, label)
    assert lone_shot_lines(trial, x, width) is None
    # Three lines are not two.
    x = np.vstack([_line(0.0, 0.1), _line(0.0, 0.4), _line(0.2, 0.0), [[0.0, 0.9, 0.0]]])
    label = np.r_[np.zeros(16, int), np.ones(8, int), 0]
    assert lone_shot_lines(_trial([0, 1], x, label), x, width) is None


def _one_face_trial(x):
    """A fit tuple of one face, x = 0 (normal along x), every shot kept."""
    model = SimpleNamespace(
        axes=np.eye(3),
        face_axis=np.array([0]),
        offset=np.zeros(1),
        normals=lambda: np.array([[1.0, 0.0, 0.0]]),
    )
    n = x.shape[0]
    return model, np.zeros(n, dtype=int), np.zeros(n), np.ones(n, dtype=bool)


def test_lone_shot_lines_on_one_face_finds_a_shot_beyond_its_two_lines():
    width = 0.006
    # Two lines on the face x = 0 and a floor shot on its plane beyond them across.
    x = np.vstack([_line(0.0, 0.1), _line(0.0, 0.4), [[0.0, 0.9, 0.0]]])
    found = lone_shot_lines(_one_face_trial(x), x, width)
    assert_vertical_lines_and_lone_shot(found)
    # No shot beyond the lines, a shot between them (inside any corner's box: it tests the
    # frame), two beyond them, or three lines: none of them.
    for extra in ([], [[0.0, 0.25, 1.0]], [[0.0, 0.9, 0.0], [0.0, -0.5, 0.0]]):
        y = np.vstack([_line(0.0, 0.1), _line(0.0, 0.4), np.reshape(extra, (-1, 3))])
        assert lone_shot_lines(_one_face_trial(y), y, width) is None, extra
    y = np.vstack([_line(0.0, 0.1), _line(0.0, 0.4), _line(0.0, 0.7), [[0.0, 0.9, 0.0]]])
    assert lone_shot_lines(_one_face_trial(y), y, width) is None


def test_a_lone_floor_shot_on_a_two_line_face_leaves_the_turn_open():
    """Clutter benchmark: a column on a floor whose one fitted face held its two raster
    columns (one on each of two faces) and a floor shot of the next raster column on that
    face's plane, turned 16 degrees at a stated +-6 and 0.53 m wide for 0.26 at +-0.009. The
    corners between the lines fit as well with the floor shot seen past their box: the turn
    is unknown (+-52 degrees) and the width as far as those corners' boxes say. That box then
    holds 6 of the 39 shots inside it (the second face's line), so the fit is refused
    (asbuilt.fit._cuboid_inside); the comparison is checked on the fit before that test."""
    data = json.loads(Path(__file__).with_name("two_lines_floor_shot_column.json").read_text())
    points, station = np.array(data["points"]), np.array(data["station"])
    with pytest.raises(ShotsInside, match="6 of the 39 shots"):
        fit_cuboid(points, sigma=data["sigma"], viewpoint=station)
    options = {"edge_pad": 0.5, "silhouette": True}
    result = _fit_box(points, data["sigma"], DEFAULT_TOLERANCES, station, options)
    axes, truth = np.asarray(result.primitive.axes), np.asarray(data["axes"])
    cosines = np.abs(axes @ truth.T)
    error = np.degrees(np.arccos(np.clip(cosines.max(axis=1), 0.0, 1.0)))
    assert np.all(error <= 5.0 * np.asarray(result.stderr["axes_deg"])), error
    true_size = np.asarray(data["size"])[cosines.argmax(axis=1)]
    size_error = np.abs(np.asarray(result.primitive.size) - true_size)
    assert np.all(size_error <= 5.0 * np.asarray(result.stderr["size"])), size_error


def _raster_column(count: int) -> np.ndarray:
    """A vertical raster column's shots on a face (count, 3) metres, 2 mm scatter across."""
    rng = np.random.default_rng(count)
    points = np.zeros((count, 3))
    points[:, 2] = np.linspace(0.2, 3.0, count)
    points[:, :2] += rng.normal(0.0, 0.002, (count, 2))
    return points + [7.0, 1.0, 0.0]


@pytest.mark.parametrize(
    ("beside", "expected"),
    [
        ([], True),  # one line: any plane through it holds it
        ([[7.3, 1.2, 0.0]], True),  # one shot beside it fixes the plane exactly
        ([[7.3, 1.2, 0.0], [7.3, 1.2, 0.5]], False),  # a second tests it (a line on the floor)
        ([[7.0, 1.3, 1.0], [7.3, 1.2, 0.0]], False),  # or lies on the face elsewhere
    ],
)
def test_one_line_and_lone_shot(beside, expected):
    points = np.vstack([_raster_column(12), np.array(beside, dtype=float).reshape(-1, 3)])
    assert one_line_and_lone_shot(points, 0.006) is expected
    # Whatever the order of the shots.
    assert one_line_and_lone_shot(points[::-1], 0.006) is expected


def test_two_raster_lines_on_a_face_are_not_one_line():
    second = _raster_column(12) + [0.0, 0.2, 0.0]
    assert not one_line_and_lone_shot(np.vstack([_raster_column(12), second]), 0.006)


def test_a_column_fitted_as_one_line_and_a_floor_shot_is_refused():
    """Clutter benchmark: a column before a wall whose one fitted face held its one raster
    column and a floor shot of the next (turned 27 degrees, 0.53 m wide for 0.24-0.33 at
    stated +-0.25 degree). That face measures nothing: refused, and not refitted at another
    noise level by the dispatcher."""
    data = json.loads(Path(__file__).with_name("one_line_column.json").read_text())
    points, station = np.array(data["points"]), data["station"]
    with pytest.raises(OneLineFace, match="one raster line"):
        fit_cuboid(points, sigma=data["sigma"], viewpoint=station)
    with pytest.raises(OneLineFace):
        fit_points("cuboid", points, sigma=data["sigma"], viewpoint=station)


@pytest.mark.parametrize(
    ("station_x", "expected"),
    [
        (-0.15, True),  # in the -x face's plane
        (-0.155, True),  # 5 mm off it: within the width
        (-0.157, False),  # 7 mm off it
        (-0.65, False),  # 0.5 m off: a face seen at 86 degrees
        (0.15, True),  # in the +x face's plane (the face nearer the station)
        (2.85, False),  # before the +x face
    ],
)
def test_a_face_through_the_station_is_a_raster_sweep(station_x, expected):
    # A 0.3 x 0.4 x 3 m column's faces across x lie at x = -0.15 and 0.15; the station 8 m
    # along y, where a beam in the nearer face's plane only grazes it.
    column = Cuboid(np.array([0.0, 0.0, 1.5]), np.eye(3), np.array([0.3, 0.4, 3.0]))
    view = np.array([station_x, -8.0, 1.5])
    assert face_through_station(column, 0, view, 0.006) is expected


@pytest.mark.parametrize("name", ["sweep_plane_column.json", "wall_face_column.json"])
def test_a_raster_column_and_what_lies_beyond_fitted_as_a_face_are_refused(name):
    """Clutter benchmark, 1 m of window around a column: fitted faces in the plane of one
    raster column's sweep through the station, holding the column's shots and the floor shots
    below its base (1.23 m wide for 0.29, turned 30-36 degrees) or the wall's beside it (1.37
    m wide for 0.30, 14 of the 105 shots inside its box). Refused, in either shot order."""
    data = json.loads(Path(__file__).with_name(name).read_text())
    points, station = np.array(data["points"]), data["station"]
    for order in (slice(None), slice(None, None, -1)):
        with pytest.raises(OneLineFace, match="sweep through the station"):
            fit_points("cuboid", points[order], sigma=data["sigma"], viewpoint=station)
