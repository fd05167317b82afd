"""Another cylinder among a pipe's shots (a tee's header, a rack neighbour) is said, not
guessed (:mod:`asbuilt.fit._cylinder_others`).

Two sources of scenes: the black-box review's generator (its own ray caster, saved in
``other_cylinder_scenes.json``) and :mod:`asbuilt.sim.raycast` (a lone pipe with edge
outliers, a flanged tee branch), shot by a raster over the aimed pipe's silhouette window.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit import fit_points
from asbuilt.fit._cylinder_others import (
    OTHER_ANGLE,
    OTHER_RADIUS,
    OTHER_SHOTS,
    apart,
    cylinders_named,
)
from asbuilt.fit.cylinder import _fit_seen_from
from asbuilt.primitives import Cylinder
from asbuilt.sim.raycast import (
    CylinderShape,
    PlaneShape,
    angles_from_direction,
    direction_from_angles,
    raycast,
)
from asbuilt.tolerances import DEFAULT_TOLERANCES

SIGMA = 0.002  # metres
STATION = np.array([0.0, 0.0, 1.5])
SCENES = json.loads((Path(__file__).parent / "other_cylinder_scenes.json").read_text())["scenes"]


def _fixture(name):
    scene = SCENES[name]
    return scene, np.array(scene["points"]), np.array(scene["station"])


def _other_radius(result) -> float:
    return result.diagnostics[OTHER_RADIUS]


def test_a_branch_fitted_as_its_header_names_the_branch():
    """The review's tee: 50 of 70 shots on the header, so the fit is the header's; its 20
    rejected shots fit the branch, which the fit names in a note and its diagnostics."""
    scene, points, station = _fixture("branch_fitted_as_header")
    result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=station)
    assert result.primitive.radius == pytest.approx(scene["header_radius"], rel=0.05)
    assert _other_radius(result) == pytest.approx(scene["truth"]["radius"], rel=0.05)
    assert result.diagnostics[OTHER_SHOTS] >= 0.8 * sum(scene["on_target"])
    assert result.diagnostics[OTHER_ANGLE] > 60  # a branch leaves its header square
    (note,) = [n for n in result.notes if "fit another cylinder" in n]
    assert note.startswith("20 of the 70 shots, left out of this fit, fit another cylinder (r 110")


def test_a_rack_neighbour_fitted_names_the_pipe():
    scene, points, station = _fixture("rack_neighbour_fitted")
    result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=station)
    assert _other_radius(result) == pytest.approx(scene["truth"]["radius"], rel=0.1)
    assert result.diagnostics[OTHER_ANGLE] < 5  # a rack's pipes run side by side


def test_a_refused_rack_names_its_cylinders():
    """No cylinder has most of the shots: the refusal lists those the surfaces fit."""
    scene, points, station = _fixture("rack_refused")
    with pytest.raises(FitError) as caught:
        fit_points("cylinder", points, sigma=SIGMA, viewpoint=station)
    message = str(caught.value)
    assert message.startswith("No cylinder explains most of these points")
    radii = [float(r) / 1000 for r in re.findall(r"r (\d+) mm over \d+ shots", message)]
    assert len(radii) == 2
    assert min(abs(r - scene["truth"]["radius"]) for r in radii) < 0.05 * scene["truth"]["radius"]
    assert "Give the object only its own pipe's shots." in message


def test_a_wall_bent_into_a_wide_cylinder_is_no_other_cylinder():
    """A pipe through a wall: the wall's 43 shots fit a cylinder of r 115 m over 1.3 degrees
    of arc, which is a plane, not another pipe."""
    _, points, station = _fixture("pipe_through_wall")
    result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=station)
    assert OTHER_SHOTS not in result.diagnostics
    assert not any("another cylinder" in n for n in result.notes)


def _shoot(shapes, seed: int, on_target: int = 30, window: float = 1.0):
    """Shots (n, 3) metres of a raster over ``shapes[0]``'s silhouette window enlarged
    ``window`` times about its centre, its steps giving about ``on_target`` shots on it, and
    which hit it (n,) bool."""
    target = shapes[0]
    axis = target.end - target.start
    length = float(np.linalg.norm(axis))
    axis /= length
    u = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    along, around = np.meshgrid(np.linspace(0, length, 30), np.linspace(0, 2 * np.pi, 36))
    surface = (
        target.start
        + along.reshape(-1, 1) * axis
        + target.radius * (np.cos(around).reshape(-1, 1) * u + np.sin(around).reshape(-1, 1) * v)
    )
    pan, tilt = angles_from_direction(surface - STATION)
    rng = np.random.default_rng(seed)
    # Lines in each direction in the window's proportion, at least six across its narrow side.
    spans = np.array([np.ptp(pan), np.ptp(tilt)])
    lines = np.maximum(np.sqrt(on_target * spans / spans[::-1]), 6.0)
    steps = spans / lines
    low = (
        0.5 * (pan.min() + pan.max() - window * spans[0]),
        0.5 * (tilt.min() + tilt.max() - window * spans[1]),
    )
    p, t = np.meshgrid(
        np.arange(low[0] + rng.random() * steps[0], low[0] + window * spans[0], steps[0]),
        np.arange(low[1] + rng.random() * steps[1], low[1] + window * spans[1], steps[1]),
    )
    directions = direction_from_angles(p.ravel(), t.ravel())
    hits = raycast(shapes, STATION, directions)
    ranges = hits.range[hits.hit] + rng.normal(0.0, SIGMA, int(hits.hit.sum()))
    return STATION + ranges[:, None] * directions[hits.hit], hits.object_index[hits.hit] == 0


def _tee(header_radius, branch_radius, seed):
    """A horizontal header 6 m away and a flanged branch 1.5 radii long off it toward the
    station, tilted 40 degrees off the line of sight (branch first: the raster's target)."""
    rng = np.random.default_rng(seed)
    yaw = rng.uniform(-np.pi, np.pi)
    centre = STATION + 6.0 * np.array([np.cos(yaw), np.sin(yaw), 0.0])
    header_axis = np.array([-np.sin(yaw), np.cos(yaw), 0.0])
    toward = (STATION - centre) / np.linalg.norm(STATION - centre)
    branch_axis = np.cos(np.radians(40)) * toward + np.sin(np.radians(40)) * np.array([0, 0, 1.0])
    header = CylinderShape(centre - 1.5 * header_axis, centre + 1.5 * header_axis, header_radius)
    end = centre + (header_radius + 1.5 * branch_radius) * branch_axis
    return [CylinderShape(centre, end, branch_radius), header]


def test_flanged_branches_alone_are_fitted_past_their_face():
    """The branches' own shots, 9-14 on the side and 12-16 on the flange face: the first fit
    lay across the face (axis 89 degrees off, radius 12-46% off at a stated 1-2%) in 11 of
    these 16 scenes before a plane holding most of a fit's inliers was tried whatever that
    fit's axis said; now 15 are within 10% with the axis within 10 degrees."""
    right = 0
    for header, branch in [(0.1619, 0.05715), (0.2191, 0.0841)]:
        for seed in range(8):
            shapes = _tee(header, branch, seed)
            points, on = _shoot(shapes, seed)
            result = fit_points("cylinder", points[on], sigma=SIGMA, viewpoint=STATION)
            axis = shapes[0].end - shapes[0].start
            cosine = abs(result.primitive.axis @ axis) / np.linalg.norm(axis)
            right += result.primitive.radius == pytest.approx(branch, rel=0.1) and (
                np.degrees(np.arccos(min(cosine, 1.0))) < 10.0
            )
    assert right >= 14


def test_thin_flanged_branches_alone_are_fitted_past_their_face():
    """NPS 2 branches (9-14 side shots, 10-14 on a face two diameters across): a fit lying
    along the face bends to a few of its shots' noise and explains them better than their
    plane does, but leaves the rest of the face off, on that plane. Before that was a reason
    to look, 4 of these 8 were r 31-35% low at a stated 2-3%; now 7 are within 10%."""
    right = 0
    for seed in range(8):
        shapes = _tee(0.1619, 0.0302, seed)
        points, on = _shoot(shapes, seed)
        result = fit_points("cylinder", points[on], sigma=SIGMA, viewpoint=STATION)
        right += result.primitive.radius == pytest.approx(0.0302, rel=0.1)
    assert right >= 6


def test_a_thin_branch_fitted_as_its_header_names_the_branch():
    """An NPS 2 branch's shots, refitted among those its header's fit left out, leave the
    branch's face out as the surface across its end and keep only its 8 side shots; with the
    face's shots counted (10 or more in all) the branch is named."""
    points, _ = _shoot(_tee(0.1619, 0.0302, 0), 0)
    result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=STATION)
    assert result.primitive.radius > 3 * 0.0302  # the header's shots, not the branch's
    assert _other_radius(result) == pytest.approx(0.0302, rel=0.2)


def test_flanged_branches_with_their_header_in_the_window():
    """With the header in the window too (14-23 shots on it), a background plane through the
    header is left out and the branch fitted past its face: 13 of these 16 tees within 10%
    (5 at stop 50); the rest wrong or refused (the plane takes some side shots with it)."""
    right = 0
    for header, branch in [(0.2191, 0.0841), (0.3048, 0.1096)]:
        for seed in range(8):
            points, _ = _shoot(_tee(header, branch, seed), seed)
            try:
                result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=STATION)
            except FitError:
                continue
            right += result.primitive.radius == pytest.approx(branch, rel=0.1)
    assert right >= 10


@pytest.mark.xfail(
    strict=True,
    reason="open: a flanged branch 1.5 radii long pointing at the station, the header in its"
    " window, has 9-12 side shots against 14-16 on its flange face and 14-22 on the header;"
    " the background plane through the header takes 4 of the 9 side shots with it, and the"
    " fit of the rest lies across the face (r 31.8 +-0.8 mm for 57.15 mm here). Of 40 such"
    " tees 22 within 10% (8 at stop 50), 1 refused, 17 wrong (8 of them a 30 mm branch fitted"
    " as its header, with a note naming the branch)",
)
def test_a_flanged_branch_with_its_header_in_the_window():
    points, _ = _shoot(_tee(0.1619, 0.05715, 4), 4)
    result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=STATION)
    assert result.primitive.radius == pytest.approx(0.05715, rel=0.1)


@pytest.mark.parametrize("seed", range(6))
def test_a_lone_pipe_names_no_other_cylinder(seed):
    """A pipe alone, a fifth of its shots edge outliers on a wall 0.5 m behind it: no
    cylinder among them."""
    rng = np.random.default_rng(seed)
    yaw = rng.uniform(-np.pi, np.pi)
    centre = STATION + rng.uniform(3, 8) * np.array([np.cos(yaw), np.sin(yaw), 0.0])
    axis = np.array([-np.sin(yaw), np.cos(yaw), rng.uniform(-0.1, 0.1)])
    axis /= np.linalg.norm(axis)
    pipe = CylinderShape(centre - axis, centre + axis, rng.choice([0.0302, 0.0572, 0.1096]))
    points, _ = _shoot([pipe], seed, on_target=40)
    toward = (STATION - centre) / np.linalg.norm(STATION - centre)
    wall = PlaneShape(centre - 0.5 * toward, toward)
    out = rng.choice(len(points), len(points) // 5, replace=False)
    beams = (points[out] - STATION) / np.linalg.norm(points[out] - STATION, axis=1)[:, None]
    behind = raycast([wall], STATION, beams)
    points[out] = STATION + behind.range[:, None] * beams
    result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=STATION)
    assert OTHER_SHOTS not in result.diagnostics


def test_one_pipe_found_twice_is_not_apart():
    one = Cylinder(center=[0, 0, 0], axis=[0, 0, 1], radius=0.1, length=2.0)
    tilted = np.array([0, 0.1, 1]) / np.linalg.norm([0, 0.1, 1])  # 5.7 degrees
    assert not apart(one, Cylinder(center=[0.01, 0, 0.5], axis=tilted, radius=0.11, length=1))
    assert apart(one, Cylinder(center=[0.3, 0, 0], axis=[0, 0, 1], radius=0.1, length=2.0))
    assert apart(one, Cylinder(center=[0, 0, 0], axis=[0, 0, 1], radius=0.06, length=2.0))
    assert apart(
        one,
        Cylinder(center=[0, 0, 0], axis=np.array([1, 0, 1]) / np.sqrt(2), radius=0.1, length=2.0),
    )


def test_without_a_station_no_surfaces_are_named():
    _, points, _ = _fixture("rack_refused")
    assert cylinders_named(_fit_seen_from, points, None, SIGMA, DEFAULT_TOLERANCES) == ""
