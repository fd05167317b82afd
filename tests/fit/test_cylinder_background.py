"""The split of a pipe's shots from whole raster lines on the background behind it."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from asbuilt.fit import fit_points
from asbuilt.fit._cylinder_background import (
    behind_the_pipe,
    depth_segments,
    fit_without_background_plane,
    near_subsets,
    only_background_behind,
)
from asbuilt.fit.cylinder import _fit_cylinder, fit_cylinder
from asbuilt.primitives import Cylinder
from asbuilt.tolerances import DEFAULT_TOLERANCES


def _pipe_before_wall(rng, wall_behind=1.5):
    """A raster of 7 columns x 7 rows from the origin over a level pipe (r 0.1 m, 4 m away
    along y) with the wall ``wall_behind`` metres behind its axis: the outer rows miss it."""
    pipe = Cylinder(np.array([0.0, 4.0, 0.0]), np.array([1.0, 0.0, 0.0]), 0.1, 4.0)
    pan = np.radians(np.linspace(-6, 6, 7))
    tilt = np.radians(np.linspace(-2.1, 2.1, 7))
    p, t = np.meshgrid(pan, tilt)
    beams = np.column_stack([np.sin(p.ravel()), np.cos(p.ravel()), np.sin(t.ravel())])
    beams /= np.linalg.norm(beams, axis=1)[:, None]
    points, on_pipe = [], []
    for beam in beams:
        # Where the beam meets the pipe (x along the axis is free): solve in the y-z plane.
        a = beam[1] ** 2 + beam[2] ** 2
        b = -2 * 4.0 * beam[1]
        c = 16.0 - pipe.radius**2
        disc = b * b - 4 * a * c
        if disc > 0:
            r = (-b - np.sqrt(disc)) / (2 * a)
            on_pipe.append(True)
        else:
            r = (4.0 + wall_behind) / beam[1]
            on_pipe.append(False)
        points.append(beam * (r + rng.normal(0, 0.002)))
    return np.array(points), np.array(on_pipe), pipe


def test_the_pipe_and_the_wall_rows_behind_are_separate_surfaces():
    points, on_pipe, _ = _pipe_before_wall(np.random.default_rng(1))
    assert 0 < on_pipe.sum() < len(points) - 6
    segments = depth_segments(points, np.zeros(3), 0.002)
    assert set(segments[0]) == set(np.flatnonzero(on_pipe))  # nearest first
    assert all(not on_pipe[s].any() for s in segments[1:])
    masks = near_subsets(segments, len(points))
    assert masks and (masks[0] == on_pipe).all()


def test_one_surface_is_not_cut():
    # A wall alone, seen obliquely (its range changes along the raster, without jumps).
    rng = np.random.default_rng(2)
    pan, tilt = np.meshgrid(np.radians(np.linspace(-8, 8, 6)), np.radians(np.linspace(-4, 4, 6)))
    beams = np.column_stack([np.sin(pan.ravel()), np.cos(pan.ravel()), np.sin(tilt.ravel())])
    normal = np.array([0.5, 0.866, 0.0])
    ranges = 5.0 / (beams @ normal) + rng.normal(0, 0.002, len(beams))
    segments = depth_segments(beams * ranges[:, None], np.zeros(3), 0.002)
    assert len(segments) == 1
    assert near_subsets(segments, len(beams)) == []


def test_wall_shots_are_background_and_a_shot_in_front_is_not():
    points, on_pipe, pipe = _pipe_before_wall(np.random.default_rng(3))
    assert only_background_behind(pipe, points, np.zeros(3), ~on_pipe, 0.006)
    # A shot 0.5 m in front of the pipe, off it, hit something else first.
    front = np.vstack([points, [0.0, 3.5, 0.3]])
    left_out = np.append(~on_pipe, True)
    assert not only_background_behind(pipe, front, np.zeros(3), left_out, 0.006)
    # A wall shot whose beam ran through the pipe cannot be.
    through = np.vstack([points, [0.0, 5.5, 0.0]])
    assert not only_background_behind(pipe, through, np.zeros(3), np.append(~on_pipe, True), 0.006)


def test_without_a_viewpoint_the_wall_rows_are_left_out_by_their_plane():
    points, on_pipe, pipe = _pipe_before_wall(np.random.default_rng(4))
    result = fit_without_background_plane(_fit_cylinder, points, 0.002, DEFAULT_TOLERANCES)
    assert result is not None
    assert abs(result.primitive.radius - pipe.radius) < 3 * result.stderr["radius"]
    assert (result.inliers == on_pipe).all()
    # the plane's shots (the rest of the wall's the fit rejected), as the note says
    (said,) = [int(n.split()[0]) for n in result.notes if "left out as background" in n]
    assert 0 < result.diagnostics["background_shots"] == said <= np.count_nonzero(~on_pipe)


def test_a_shot_in_front_of_the_pipe_is_not_behind_it():
    points, on_pipe, pipe = _pipe_before_wall(np.random.default_rng(5))
    assert behind_the_pipe(pipe, points, on_pipe, ~on_pipe, 0.006)
    front = np.vstack([points, [0.0, 3.5, 0.0]])
    assert not behind_the_pipe(
        pipe, front, np.append(on_pipe, False), np.append(~on_pipe, True), 0.006
    )


def _plumb_pipe_before_wall(rng):
    """A raster of 5 columns x 12 rows from the origin over a plumb pipe (r 0.1 m, 1 m long, its
    axis 4 m away along x) with a wall 1.5 m behind its axis: the outer columns pass beside it
    and the top rows over its top, onto the wall."""
    pipe = Cylinder(np.array([4.0, 0.0, 0.2]), np.array([0.0, 0.0, 1.0]), 0.1, 1.0)
    pan, tilt = np.meshgrid(
        np.radians(np.linspace(-2.5, 2.5, 5)), np.radians(np.linspace(-3, 14, 12))
    )
    beams = np.column_stack(
        [
            np.cos(tilt.ravel()) * np.cos(pan.ravel()),
            np.cos(tilt.ravel()) * np.sin(pan.ravel()),
            np.sin(tilt.ravel()),
        ]
    )
    # The pipe's first crossing (x-y plane), kept where it lies within its length; else the wall.
    a = beams[:, 0] ** 2 + beams[:, 1] ** 2
    b = -2 * 4.0 * beams[:, 0]
    disc = b * b - 4 * a * (16.0 - pipe.radius**2)
    ranges = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2 * a)
    along = ranges * beams[:, 2] - pipe.center[2]
    on_pipe = (disc > 0) & (np.abs(along) <= 0.5 * pipe.length)
    ranges = np.where(on_pipe, ranges, 5.5 / beams[:, 0])
    points = beams * (ranges + rng.normal(0, 0.002, len(beams)))[:, None]
    return points, on_pipe, pipe


def test_wall_shots_above_a_plumb_pipe_passed_its_top():
    """Review (R1): the wall rows above a column's top passed over it; counted against the
    infinite cylinder they were "seen through" it, and the right fit of the pipe's shots was
    turned down."""
    points, on_pipe, pipe = _plumb_pipe_before_wall(np.random.default_rng(6))
    over = ~on_pipe & (points[:, 2] > 0.7)
    assert over.sum() >= 5 and on_pipe.sum() >= 0.4 * len(points)
    assert only_background_behind(pipe, points, np.zeros(3), ~on_pipe, 0.006)
    # Within its length a beam through the pipe still cannot reach the wall.
    through = np.vstack([points, [5.5, 0.0, 0.2]])
    assert not only_background_behind(pipe, through, np.zeros(3), np.append(~on_pipe, True), 0.006)


def test_a_plumb_pipe_before_wall_rows_is_fitted_from_its_own_shots():
    points, on_pipe, pipe = _plumb_pipe_before_wall(np.random.default_rng(7))
    result = fit_cylinder(points, sigma=0.002, viewpoint=np.zeros(3))
    assert abs(result.primitive.radius - pipe.radius) < 3 * result.stderr["radius"] + 0.001
    assert not any("viewpoint was ignored" in note for note in result.notes)
    assert (result.inliers == on_pipe).all()
    # The rules read the count (the outliers rule does not count them): as the note says.
    said = [int(n.split()[0]) for n in result.notes if "left out as background" in n]
    assert [
        result.diagnostics.get("background_shots", result.diagnostics.get("background_plane_shots"))
    ] == said


def test_the_rescue_keeps_the_viewpoint_it_cut_the_surfaces_by():
    """Independent review (batch c): a plumb NPS 4 pipe before a wall came out r 506 mm +-2.4
    (true 57.2) with the station ignored: the rescue, which takes the station as right to cut
    the shots at range jumps, returned a fit that had ignored it (at the 6.5 mm the shots
    scatter by, which :func:`fit_points` retries with). That fit stays refused; the wall is now
    left out as a background plane (:mod:`asbuilt.fit._cylinder_planes`) and the pipe's own
    shots give the pipe, with the station kept."""
    scan = json.loads(
        (Path(__file__).parent / "pipe_before_wall_subset_view_ignored.json").read_text()
    )
    result = fit_points(
        "cylinder",
        np.array(scan["points"]),
        sigma=scan["range_sigma"],
        viewpoint=scan["station"],
    )
    cylinder = result.primitive
    assert abs(cylinder.radius - scan["radius"]) < 3 * result.stderr["radius"] + 0.001
    assert abs(cylinder.axis @ np.array(scan["axis"])) > np.cos(np.radians(1.0))
    assert not any("viewpoint was ignored" in note for note in result.notes)
    # The wall's shots are left out, the pipe's kept.
    assert np.count_nonzero(result.inliers) <= scan["on_object"]
    assert result.diagnostics["background_plane_shots"] >= len(scan["points"]) - scan["on_object"]
