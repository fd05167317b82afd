"""Tanks and drums scanned by :mod:`asbuilt.sim`, as an independent black-box review scanned them.

Each scene is drawn from its seed: a station at a height, a 2 mm range sigma, 0.01 degree
pointing noise and mixed returns at silhouette edges (the simulator's defaults), a raster over
a window, and every beam's return whatever it met (:func:`asbuilt.sim.sensor.fire`): shots
past the object land on what lies behind it, or return nothing. Each function returns the
points (n, 3) metres, the station (3,) metres and the truth (a dict). Lengths in metres.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.sim.raycast import CylinderShape, PlaneShape, direction_from_angles
from asbuilt.sim.scene import Scene, SceneObject, Station
from asbuilt.sim.sensor import angular_window, fire, operator_window, raster_angles

SIGMA = 0.002


def _station(height: float) -> Station:
    return Station(
        id="S",
        position=np.array([0.0, 0.0, height]),
        range_sigma=SIGMA,
        angular_sigma=math.radians(0.01),
        mixed_return=0.3,
    )


def _scene(station: Station, *shapes) -> Scene:
    objects = tuple(
        SceneObject(str(k), "cylinder" if k == 0 else None, shape, None, 30, k == 0, "S", k)
        for k, shape in enumerate(shapes)
    )
    return Scene(units="m", stations=(station,), objects=objects)


def _shots(scene: Scene, station: Station, pan, tilt, rng):
    """The points of every beam that came back, and which of them hit object 0."""
    got = fire(scene, station, pan, tilt, rng)
    ok = np.isfinite(got.range)
    points = station.position + got.range[ok, None] * direction_from_angles(pan[ok], tilt[ok])
    return points, got.object_index[ok] == 0


def _vertical_tank(rng, tall, heights):
    """A vertical tank drawn from ``rng``: radius 1-3 m, its axis 5-15 m beyond its radius
    from the station along a random bearing, ``tall`` (low, high) metres tall, the station
    ``heights`` (low, high) metres up. Returns the radius, the distance, the bearing (radians)
    and the unit line of sight (3,), the height, the :class:`Station` and the tank's
    :class:`CylinderShape` (the draws in the order the scenes always made them)."""
    radius = rng.uniform(1.0, 3.0)
    distance = rng.uniform(5.0, 15.0) + radius
    bearing = rng.uniform(-math.pi, math.pi)
    los = np.array([math.cos(bearing), math.sin(bearing), 0.0])
    height = rng.uniform(*tall)
    station = _station(rng.uniform(*heights))
    centre = distance * los
    tank = CylinderShape(start=centre, end=centre + [0.0, 0.0, height], radius=radius)
    return radius, distance, bearing, los, height, station, tank


def tank_before_wall(seed: int, margin: float = 0.5, heights=(1.0, 8.0)):
    """A vertical tank (radius 1-3 m, 3-10 m tall, its axis 5-15 m beyond its radius from the
    station) with a wall 0.5-3 m behind it, square to the view, scanned by a raster of 3
    columns and 8-15 rows over its silhouette window widened by ``margin`` times a uniform
    0-1 raster step on each side (the operator's window); the station ``heights`` (low, high)
    metres above the tank's foot (above its top, it sees the lid)."""
    rng = np.random.default_rng(seed)
    radius, distance, _, los, height, station, tank = _vertical_tank(rng, (3.0, 10.0), heights)
    centre = distance * los
    wall = PlaneShape(point=centre + (radius + rng.uniform(0.5, 3.0)) * los, normal=-los)
    rows = int(rng.integers(8, 16))
    margins = rng.uniform(0.0, margin, size=4)
    window = operator_window(angular_window(tank, station.position), 3, rows, margins)
    pan, tilt = raster_angles(window, 3, rows)
    points, hit = _shots(_scene(station, tank, wall), station, pan, tilt, rng)
    return points, station.position, {"radius": radius, "axis": np.array([0, 0, 1.0]), "hit": hit}


def partial_tank(seed: int):
    """A vertical tank (radius 1-3 m, 4-12 m tall, 5-15 m beyond its radius) with nothing
    around it, scanned by 3-8 columns and 4-12 rows over 15-50% of its silhouette's width and
    part of its height: every shot on the tank, over a narrow arc."""
    rng = np.random.default_rng(seed)
    radius, distance, bearing, _, height, station, tank = _vertical_tank(
        rng, (4.0, 12.0), (1.0, 3.0)
    )
    half = math.asin(radius / distance)
    width = 2.0 * half * rng.uniform(0.15, 0.5)
    pan0 = bearing + rng.uniform(-half, half - width) + 0.5 * width
    near = distance - radius
    low = math.atan2(0.3 - station.position[2], near)
    high = math.atan2(height - 0.3 - station.position[2], near)
    tall = (high - low) * rng.uniform(0.3, 1.0)
    tilt0 = rng.uniform(low + 0.5 * tall, high - 0.5 * tall)
    columns, rows = int(rng.integers(3, 9)), int(rng.integers(4, 13))
    pan, tilt = raster_angles((pan0, tilt0, width, tall), columns, rows)
    points, hit = _shots(_scene(station, tank), station, pan, tilt, rng)
    return points, station.position, {"radius": radius, "axis": np.array([0, 0, 1.0]), "hit": hit}


def end_on_drum(seed: int, floor: bool = True):
    """A horizontal drum (radius 0.75-1.5 m, 3-6 m long, flat ends) on saddles, its near end
    4-12 m from the station and its axis within 30 degrees of the line of sight, so that the
    station sees mostly its end; a floor under it when ``floor``. A raster of about 25-125
    beams (columns and rows in the window's proportion) over its silhouette window widened by
    0-1 raster step on each side."""
    rng = np.random.default_rng(seed)
    radius = rng.uniform(0.75, 1.5)
    length = rng.uniform(3.0, 6.0)
    bearing = rng.uniform(-math.pi, math.pi)
    los = np.array([math.cos(bearing), math.sin(bearing), 0.0])
    turn = bearing + math.radians(rng.uniform(-30.0, 30.0))
    axis = np.array([math.cos(turn), math.sin(turn), 0.0])
    station = _station(rng.uniform(1.0, 3.0))
    near = rng.uniform(4.0, 12.0) * los + [0.0, 0.0, radius + rng.uniform(0.0, 0.5)]
    drum = CylinderShape(start=near, end=near + length * axis, radius=radius)
    shapes = [drum]
    if floor:
        shapes.append(PlaneShape(point=np.zeros(3), normal=np.array([0.0, 0.0, 1.0])))
    window = angular_window(drum, station.position)
    shots = rng.uniform(20.0, 100.0) / 0.8
    aspect = window[2] * math.cos(window[1]) / window[3]
    rows = max(3, int(round(math.sqrt(shots / aspect))))
    columns = max(3, int(round(shots / rows)))
    window = operator_window(window, columns, rows, rng.uniform(0.0, 1.0, size=4))
    pan, tilt = raster_angles(window, columns, rows)
    points, hit = _shots(_scene(station, *shapes), station, pan, tilt, rng)
    return points, station.position, {"radius": radius, "axis": axis, "hit": hit}
