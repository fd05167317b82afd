"""A steel beam receding from the station: its sides' far part, seen past 80 degrees, is no fan.

Ray-cast with :mod:`asbuilt.sim` (a 0.2 x 0.4 m beam 4-8 m long starting 3-10 m from the
station, its axis 20-30 degrees off the line of sight, level or pitched 10 degrees, a raster
of 20-40 hits over an operator's window, 2 mm range and 0.01 degree pointing noise), with and
without a wall 1-3 m behind its far end whose shots the window also holds. Along a raster
line the sides' ranges step by more than ``tan(80 deg)`` times the spacing across the beams,
which the beam-fan rule took for background seen past the box (and the foreground rescue's
take-back reached only a few spacings on): these beams came out 1.5-7.5 m short with
decimetre standard errors. The beam-fan columns of ``test_cuboid_beam_fans.py`` are the case
the rule exists for.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from asbuilt.fit import fit_points
from asbuilt.fit._beam_fans import beam_fan_shots, neighbours, raster_lines
from asbuilt.primitives import Cuboid
from asbuilt.sim.raycast import BoxShape, PlaneShape, direction_from_angles
from asbuilt.sim.scene import Scene, SceneObject, Station
from asbuilt.sim.sensor import fire, operator_margins, plan_raster

STATION = Station(
    id="S",
    position=np.zeros(3),
    range_sigma=0.002,
    angular_sigma=math.radians(0.01),
    dropout=0.0,
    mixed_return=0.0,
)


def receding_beam_scan(seed: int, yaw_deg: float, pitch_deg: float, wall: bool):
    """Shots (n, 3) metres from the station (the origin), which hit the beam (n,) bool, and the
    true beam (its first axis along its length)."""
    rng = np.random.default_rng(seed)
    bearing = rng.uniform(-np.pi, np.pi)
    los = np.array([np.cos(bearing), np.sin(bearing), 0.0])
    near = rng.uniform(3.0, 10.0)
    length = rng.uniform(4.0, 8.0)
    height = rng.uniform(-1.0, 2.5)
    yaw = bearing + np.radians(yaw_deg) * rng.choice([-1, 1])
    pitch = np.radians(pitch_deg)
    along = np.array([np.cos(yaw) * np.cos(pitch), np.sin(yaw) * np.cos(pitch), np.sin(pitch)])
    side = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
    axes = np.vstack([along, side, np.cross(along, side)])
    section = [0.2, 0.4] if rng.random() < 0.5 else [0.4, 0.2]
    size = np.array([length, *section])
    centre = near * los + [0.0, 0.0, height] + 0.5 * length * along
    shape = BoxShape(center=centre, axes=axes, size=size)
    objects = [SceneObject("T", "cuboid", shape, Cuboid(centre, axes, size), 30, True, "S", 0)]
    if wall:
        far = max(float((shape.corners() @ los).max()), 0.0) + rng.uniform(1.0, 3.0)
        plane = PlaneShape(point=far * los, normal=los)
        objects.append(SceneObject("bg", None, plane, None, 30, False, "S", 1))
    scene = Scene(units="m", stations=(STATION,), objects=tuple(objects))
    wanted = int(rng.integers(20, 41))
    margins = operator_margins(rng)
    pan, tilt, _ = plan_raster(scene, 0, STATION, wanted, margins=margins)
    got = fire(scene, STATION, pan, tilt, rng)
    keep = np.isfinite(got.range)
    if not wall:
        keep &= got.object_index == 0
    points = direction_from_angles(pan[keep], tilt[keep]) * got.range[keep][:, None]
    return points, got.object_index[keep] == 0, Cuboid(centre, axes, size)


@pytest.mark.parametrize(
    "wall, yaw_deg, pitch_deg, trial",
    [
        (False, 20, 0, 9),
        (False, 20, 10, 0),
        (False, 20, 10, 5),
        (False, 30, 10, 3),
        (False, 30, 10, 6),
        (True, 20, 0, 5),
        (True, 20, 10, 7),
        (True, 20, 10, 0),
        (True, 20, 10, 4),
        (True, 30, 10, 5),
    ],
)
def test_a_receding_beam_keeps_its_far_part(wall, yaw_deg, pitch_deg, trial):
    seed = 1000 * yaw_deg + 100 * pitch_deg + trial + 7 * wall
    points, hit, beam = receding_beam_scan(seed, yaw_deg, pitch_deg, wall)
    fit = fit_points("cuboid", points, sigma=0.002, viewpoint=np.zeros(3))
    cuboid = fit.primitive
    k = int(np.argmax(np.abs(np.asarray(cuboid.axes) @ beam.axes[0])))
    # The far end lies somewhere in the raster step past the last hit on the beam (0.3-0.8 m
    # along it here): half a metre, not the 1.5-7.5 m the far part's shots were cut to.
    assert abs(cuboid.size[k] - beam.size[0]) < 0.5
    # The beam's shots are the fit's, the wall's are not.
    assert np.count_nonzero(hit & ~fit.inliers) <= 2
    assert not fit.inliers[~hit].any()


def _raster_face(pans_deg, tilts_deg, ranges):
    """Shots (n, 3) at the given pans and tilts (n,) degrees and ranges (n,) metres from the
    origin, and their raster-line neighbour pairs (every shot taken)."""
    pan, tilt = np.radians(pans_deg), np.radians(tilts_deg)
    points = direction_from_angles(pan, tilt) * np.asarray(ranges)[:, None]
    angles = np.column_stack([pan, tilt])
    lines = raster_lines(angles, np.radians([1.0, 1.0]))
    return points, neighbours(angles, lines, np.ones(len(pan), dtype=bool))


def test_a_bottom_face_seen_row_by_row_past_80_degrees_is_one_face():
    # A beam's bottom 1 m above the station's level seen by rows 1 degree of tilt apart, 4.1-8.2
    # m away (76-83 degrees): the far rows' ranges step past the 80 degree bound, yet every row
    # lies on the near rows' plane.
    tilts = np.repeat([14.0, 13.0, 12.0, 11.0, 10.0, 9.0, 8.0, 7.0], 3)
    pans = np.tile([-1.0, 0.0, 1.0], 8)
    ranges = 1.0 / np.sin(np.radians(tilts))
    points, pairs = _raster_face(pans, tilts, ranges)
    assert not beam_fan_shots(points, np.zeros(3), 0.006, pairs).any()


def test_a_wall_column_parted_by_the_box_stays_out():
    # A box's raster column 4.1-4.4 m away and the next column on the wall 3.5 m behind, the
    # wall's shots in two runs (the rows between them on the box's other face): the wall's
    # runs both lie on the plane through the two columns, but each steps off the box's column
    # itself, not one on from the other.
    box = np.arange(-15.0, 21.0, 5.0)
    wall = np.array([20.0, 15.0, 5.0, -10.0, -15.0])
    tilts = np.concatenate([box, wall])
    pans = np.concatenate([np.zeros(box.size), np.full(wall.size, 2.5)])
    ranges = np.concatenate([4.1 / np.cos(np.radians(box)), 7.6 / np.cos(np.radians(wall))])
    points, pairs = _raster_face(pans, tilts, ranges)
    fan = beam_fan_shots(points, np.zeros(3), 0.006, pairs)
    assert fan.tolist() == [False] * box.size + [True] * wall.size
