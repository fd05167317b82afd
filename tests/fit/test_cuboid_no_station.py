"""Cuboids fitted without the station: the sizes' standard errors must cover the errors.

The scans are ray-cast here (``fit_scans.shoot``), independently of ``asbuilt.sim``: a pier
0.68 x 0.54 x 1.2 m whose top lies 3.6 m below a station 7 m away, so that two side faces and
the top are seen, turned so that one side face is seen obliquely; a cell-centred raster over
the pier's silhouette window. The station is not the scan frame's origin, so no viewpoint is
known.

Without a viewpoint nothing forbids two opposite faces, but no single station sees both. A
raster column on the oblique side face is a vertical line of shots; it lies in that face's
plane and just as well in the plane opposite the near face, and the segmentation's greedy
growth took the latter: the pier's width came out "observed" between the near face and that
column, 0.2-0.3 m short with a 1-2 mm standard error (z up to -380). A frame one station
can have seen is now offered and fitted too, and wins.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from fit_scans import cell_centres, corner_angles, shoot, sizes_in_true_order

from asbuilt.errors import FitError
from asbuilt.fit.cuboid import fit_cuboid
from asbuilt.primitives import Cuboid

HALF = np.array([0.34, 0.27, 0.6])  # the pier's half sizes, metres
DISTANCE = 7.0  # station to pier, horizontally, metres
DROP = 3.6  # the pier's top below the station, metres
STATION = np.array([3.5, -1.0, 1.5])  # the station in the scan frame, metres
RANGE_SIGMA = 0.002  # metres


def scan(turn_deg: float, seed: int, columns: int, rows: int):
    """Points (n, 3) in the scan frame and the pier's rotation (3, 3; columns its axes).

    A cell-centred raster of ``columns`` pan x ``rows`` tilt lines over the pier's exact
    silhouette window, seen from the station; ranges with 2 mm noise, directions with 0.01
    degree pointing noise, recorded at the nominal angles.
    """
    rng = np.random.default_rng(seed)
    a = np.radians(turn_deg)
    rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    centre = np.array([0.0, DISTANCE, -DROP - HALF[2]])  # from the station
    pier = Cuboid(centre, rot.T, 2.0 * HALF)
    pans, tilts = corner_angles(pier)
    pan, tilt = np.meshgrid(
        cell_centres(pans.min(), pans.max(), columns), cell_centres(tilts.min(), tilts.max(), rows)
    )
    points, hit = shoot(pier, pan.ravel(), tilt.ravel(), rng)
    return points[hit] + STATION, rot, centre


@pytest.mark.parametrize("turn_deg, columns, rows", [(21.0, 6, 6), (24.0, 6, 8), (160.0, 6, 6)])
@pytest.mark.parametrize("sigma", [RANGE_SIGMA, None])
def test_side_face_line_is_not_taken_for_an_opposite_face(turn_deg, columns, rows, sigma):
    for seed in range(4):
        points, rot, centre = scan(turn_deg, seed, columns, rows)
        local = (points - STATION - centre) @ rot
        # The scene is what the test is about: one raster column on a side face, vertical.
        on_side = np.abs(np.abs(local[:, :2]) - HALF[:2]).min(axis=1) < 0.01
        assert on_side.any()
        result = fit_cuboid(points, sigma=sigma)
        size, stderr, observed = sizes_in_true_order(result, rot)
        # One station sees no two opposite faces: every size is an extent bound.
        assert not observed.any()
        assert np.all(np.abs(size - 2.0 * HALF) <= 3.0 * stderr), (seed, size, stderr)


@pytest.mark.parametrize("turn_deg, columns, rows", [(65.0, 7, 4), (70.0, 7, 4), (160.0, 9, 4)])
@pytest.mark.parametrize("sigma", [RANGE_SIGMA, None])
def test_extent_bound_covers_its_own_faces_raster_step(turn_deg, columns, rows, sigma):
    # Four raster rows: the pier's top carries one or two of them, its side faces the rest,
    # and the lines are spaced differently on each face. An unseen edge lies within a step of
    # the lines of the face its extreme shot is on; the standard error took the finer step of
    # all faces (the median over them, or the shots just behind the extreme) and came out
    # 2-3 times too small (z up to 16).
    for seed in range(4):
        points, rot, _ = scan(turn_deg, seed, columns, rows)
        result = fit_cuboid(points, sigma=sigma)
        size, stderr, observed = sizes_in_true_order(result, rot)
        assert not observed.any()
        assert np.all(np.abs(size - 2.0 * HALF) <= 3.0 * stderr), (seed, size, stderr)


def test_a_wall_behind_is_no_back_face_without_the_station():
    # An independent review's ray-cast column with a wall 3.1 m behind it, no station given
    # (tests/fit/wall_as_back_face_no_station.json): the wall's shots, reaching far past the
    # column's outline, were fitted as its back face, and the column came out 5.51 x 1.22 m
    # with the 1.22 m "observed" to 0.8 mm. Two opposite faces must share one outline; a face
    # that reaches past its opposite is left out. Here the shots left are then not one box,
    # and the fit is refused rather than measured wrong.
    scan = json.loads((Path(__file__).parent / "wall_as_back_face_no_station.json").read_text())
    try:
        fit = fit_cuboid(np.array(scan["points"]), sigma=scan["range_sigma"])
    except FitError:
        return
    size, stderr, observed = sizes_in_true_order(fit, np.asarray(scan["axes"]))
    z = (size - np.asarray(scan["size"])) / stderr
    assert not np.any(observed & (np.abs(z) > 4.0)), (size, stderr, observed)
