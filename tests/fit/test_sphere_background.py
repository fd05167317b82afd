"""The split of a sphere's shots from the background a raster window reached past it."""

from __future__ import annotations

import re

import numpy as np
import pytest
from fit_scans import cast, cell_centres, directions

from asbuilt.errors import FitError
from asbuilt.fit import fit_points
from asbuilt.fit._sphere_background import behind, in_front
from asbuilt.fit.sphere import _fit_shots, fit_sphere
from asbuilt.pipeline import build_model
from asbuilt.primitives import Cylinder, Sphere
from asbuilt.scan.model import Scan, ScanObject, Sensor
from asbuilt.tolerances import DEFAULT_TOLERANCES

SIGMA = 0.002
STATION = np.zeros(3)
#: A 2.5 m tank 12 m away, a little above the station.
TANK = Sphere(np.array([11.0, 4.0, 1.0]), 1.25)


def _window(sphere, margin, count):
    """Nominal pan and tilt (count * count,) radians of a cell-centred raster over the sphere's
    silhouette widened by ``margin`` of its width on each side."""
    distance = float(np.linalg.norm(sphere.center))
    half = np.arcsin(sphere.radius / distance) * (1.0 + 2.0 * margin)
    pan0 = np.arctan2(sphere.center[1], sphere.center[0])
    tilt0 = np.arcsin(sphere.center[2] / distance)
    pan, tilt = np.meshgrid(
        cell_centres(pan0 - half, pan0 + half, count),
        cell_centres(tilt0 - half, tilt0 + half, count),
    )
    return pan.ravel(), tilt.ravel()


def _scan(rng, shapes, gap, margin=0.2, count=6, sphere=TANK):
    """Shots from the origin over ``sphere`` with ``margin`` and a wall ``gap`` metres behind
    it (square to the line of sight), the first of ``shapes`` (primitives) or the wall each
    beam meets: points (n, 3) metres and the index (n,) of what each hit (``len(shapes)`` for
    the wall). Pointing noise 0.01 degree (the shot recorded at its nominal angles), range
    noise ``SIGMA``."""
    pan, tilt = _window(sphere, margin, count)
    pointing = np.radians(0.01)
    true = directions(
        pan + rng.normal(0, pointing, pan.size), tilt + rng.normal(0, pointing, tilt.size)
    )
    toward = sphere.center / np.linalg.norm(sphere.center)
    wall = (np.linalg.norm(sphere.center) + sphere.radius + gap) / (true @ toward)
    ranges = np.column_stack([cast(shape, STATION, true) for shape in shapes] + [wall])
    ranges = np.where(np.isfinite(ranges), ranges, np.inf)
    hit = ranges.argmin(axis=1)
    reach = ranges.min(axis=1) + rng.normal(0, SIGMA, pan.size)
    return directions(pan, tilt) * reach[:, None], hit


def _left_out(result) -> int:
    """The count of shots a fit's note says were left out as background (0 without one)."""
    for note in result.notes:
        found = re.match(r"(\d+) shot\(s\) lie behind the sphere", note)
        if found:
            return int(found.group(1))
    return 0


@pytest.mark.parametrize("gap", [1.0, 3.0, 10.0])
@pytest.mark.parametrize("margin", [0.1, 0.2])
def test_a_sphere_before_a_wall_fits_its_own_shots(gap, margin):
    """A 6 x 6 raster over a window 20-40% wider than the tank: 16 shots on it, 20 on the wall
    (an independent review's sweep, every one refused: "36 of 36 points are outliers", or the
    wall fitted as a sphere kilometres wide). The wall's shots lie behind the tank along their
    beams, which clear it: left out as background, and the tank fitted from its own shots."""
    points, hit = _scan(np.random.default_rng(int(gap * 10 + margin * 100)), [TANK], gap, margin)
    on = hit == 0
    assert 12 <= on.sum() <= 0.6 * len(points)
    result = fit_points("sphere", points, sigma=SIGMA, viewpoint=STATION)
    assert abs(result.primitive.radius - TANK.radius) < 4 * result.stderr["radius"]
    offset = np.linalg.norm(result.primitive.center - TANK.center)
    assert offset < 4 * result.stderr["center"]
    assert (result.inliers == on).all()
    assert _left_out(result) == np.count_nonzero(~on)
    assert result.diagnostics["background_shots"] == np.count_nonzero(~on)


def test_the_wall_behind_a_spherical_tank_is_not_reported_as_outliers():
    """The shots the fit told apart as the wall behind are explained: the ``outliers`` rule
    (AB404) does not warn of them (it did on every such tank of an independent review)."""
    points, hit = _scan(np.random.default_rng(12), [TANK], 3.0, 0.2)
    assert np.count_nonzero(hit != 0) > 0.3 * len(points)
    scan = Scan(
        units="m",
        objects=(ScanObject("TK-1", "sphere", points, label="spherical tank TK-1"),),
        sensor=Sensor(position=STATION, range_sigma=SIGMA),
    )
    model = build_model(scan)
    assert [c.id for c in model.components] == ["TK-1"]
    assert not [f for f in model.findings if f.slug == "outliers"]


def test_without_the_station_no_shot_is_taken_for_background():
    """The split needs the beams: without a viewpoint the fit is what it was (here refused, the
    wall holding over half the shots)."""
    points, _ = _scan(np.random.default_rng(4), [TANK], 3.0)
    try:
        result = fit_sphere(points, sigma=SIGMA)
    except FitError:
        return
    assert _left_out(result) == 0


def test_a_clean_scan_is_fitted_as_before():
    """A fit neither refused nor contradicted from the station is returned as it is."""
    points, hit = _scan(np.random.default_rng(5), [TANK], 3.0, margin=-0.25)
    assert (hit == 0).all()
    result = fit_sphere(points, sigma=SIGMA, viewpoint=STATION)
    plain = _fit_shots(points, SIGMA, DEFAULT_TOLERANCES, STATION)
    assert repr(result) == repr(plain)


def test_behind_is_past_the_sphere_with_the_beam_clear_of_it():
    cutoff = 6 * SIGMA
    distance = float(np.linalg.norm(TANK.center))
    toward = TANK.center / distance
    side = np.cross(toward, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)

    def shot(lateral, depth):
        """On the beam that passes ``lateral`` metres beside the centre, ``depth`` metres from
        the station along the line of sight."""
        return (toward * distance + side * lateral) * depth / distance

    radius = TANK.radius
    shots = np.array(
        [
            shot(2.0, distance + 3.0),  # the wall, beside the tank
            shot(radius + 0.004, distance + 3.0),  # the wall, past a beam that grazed the edge
            shot(0.0, distance - radius - 0.5),  # in front of the tank
            shot(0.3, distance),  # inside it
            shot(0.5, distance + 3.0),  # the wall, its beam through the tank
            shot(2.0, distance - 0.8),  # beside the tank, nearer than its centre (a floor)
        ]
    )
    assert behind(TANK, shots, STATION, cutoff).tolist() == [True, True, False, False, False, False]
    # Seen from inside a vessel there is no behind.
    assert not behind(TANK, shots, TANK.center, cutoff).any()


def test_a_wall_fitted_as_a_sphere_is_contradicted_by_the_tank_in_front():
    points, hit = _scan(np.random.default_rng(6), [TANK], 3.0)
    toward = TANK.center / np.linalg.norm(TANK.center)
    # A sphere 40 m wide through the wall, its centre far behind it: the tank's shots are
    # between the station and the wall, in front of the sphere along their beams.
    plane = np.linalg.norm(TANK.center) + TANK.radius + 3.0
    wide = Sphere(toward * (plane + 20.0), 20.0)
    assert in_front(wide, points, STATION, 6 * SIGMA)[hit == 0].all()
    assert not in_front(TANK, points, STATION, 6 * SIGMA).any()


def test_a_stray_return_kilometres_off_before_a_wall():
    """The review's SP_02 in short: a far stray among a sphere's and a wall's shots."""
    points, hit = _scan(np.random.default_rng(7), [TANK], 3.0, margin=0.1)
    stray = points[0] / np.linalg.norm(points[0]) * 7400.0
    result = fit_points("sphere", np.vstack([points, stray]), sigma=SIGMA, viewpoint=STATION)
    assert abs(result.primitive.radius - TANK.radius) < 4 * result.stderr["radius"]
    assert result.inliers[:-1].tolist() == (hit == 0).tolist() and not result.inliers[-1]


def _post(radius):
    """A vertical post between the station and the tank, over part of its left side."""
    toward = TANK.center / np.linalg.norm(TANK.center)
    side = np.cross(toward, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    foot = toward * 7.0 + side * 0.3
    return Cylinder(np.array([foot[0], foot[1], 1.0]), np.array([0.0, 0.0, 1.0]), radius, 6.0)


def test_shots_in_front_of_the_sphere_are_fitted_not_left_out():
    """A post in front of the tank: its shots are nearer than the tank's, so they are fitted
    with them and rejected by the fit (outliers of the sphere), never left out as
    background; only the wall's shots are."""
    post = _post(0.2)
    points, hit = _scan(np.random.default_rng(8), [TANK, post], 3.0)
    on, front, wall = hit == 0, hit == 1, hit == 2
    assert front.sum() >= 3 and wall.sum() >= 3
    result = fit_points("sphere", points, sigma=SIGMA, viewpoint=STATION)
    assert abs(result.primitive.radius - TANK.radius) < 4 * result.stderr["radius"]
    assert (result.inliers == on).all()
    assert _left_out(result) == np.count_nonzero(wall)
    # Rejected by the fit, and no background of it.
    assert not behind(result.primitive, points[front], STATION, 6 * SIGMA).any()


def test_a_post_holding_most_of_the_near_shots_is_not_thrown_away():
    """A post wide enough to hide most of the tank: the shots in front outnumber the tank's,
    and leaving them out is not allowed (they are not behind it): the fit is refused, or made
    with the post's shots among those it judged, never with them discarded."""
    post = _post(0.45)
    points, hit = _scan(np.random.default_rng(9), [TANK, post], 3.0)
    assert (hit == 1).sum() > (hit == 0).sum()
    try:
        result = fit_points("sphere", points, sigma=SIGMA, viewpoint=STATION)
    except FitError:
        return
    assert _left_out(result) == np.count_nonzero(hit == 2), "the post's shots left out"


def test_shots_seen_through_the_sphere_are_judged_by_the_fit():
    """Mixed returns on beams that crossed the tank's edge (part tank, part wall) lie past the
    tank on beams through it: no background by the rule, so they are fitted with the tank's
    shots and rejected, and only the wall's shots are left out."""
    points, hit = _scan(np.random.default_rng(10), [TANK], 3.0)
    on = np.flatnonzero(hit == 0)
    ranges = np.linalg.norm(points, axis=1)
    directions_ = points / ranges[:, None]
    toward = TANK.center / np.linalg.norm(TANK.center)
    wall = (np.linalg.norm(TANK.center) + TANK.radius + 3.0) / (directions_ @ toward)
    # The three tank shots nearest its silhouette (farthest from the beam to the centre).
    edge = on[np.argsort(directions_[on] @ toward)[:3]]
    mixed = points.copy()
    mixed[edge] = directions_[edge] * (0.5 * (ranges[edge] + wall[edge]))[:, None]
    result = fit_points("sphere", mixed, sigma=SIGMA, viewpoint=STATION)
    assert abs(result.primitive.radius - TANK.radius) < 4 * result.stderr["radius"]
    assert not result.inliers[edge].any()
    assert _left_out(result) == np.count_nonzero(hit != 0)
