"""A pipe whose shots lie on two raster lines along it (asbuilt.fit._cylinder_two_lines).

Two raster columns along a vertical pipe fit circles of any radius above half their distance:
the fit must not report the smallest one to a millimetre (an independent review: 38.9 +-1.3 mm
for a 57.1 mm pipe). Scans are ray cast here: a pan-tilt raster from a station at the origin
onto a vertical pipe, range noise along the beams.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit import fit_points
from asbuilt.fit._cylinder_two_lines import on_two_lines, on_two_raster_lines

SIGMA = 0.002  # metres


def pipe_scan(radius, distance, columns, seed, length=2.5):
    """Shots (n, 3) metres on a vertical pipe (axis through (distance, 0), z from -1 to
    length - 1 m) from a raster whose pan step puts ``columns`` raster columns on it."""
    rng = np.random.default_rng(seed)
    half_width = math.asin(radius / distance)
    step = 2.0 * half_width / columns
    pans = -half_width + step * (rng.uniform(0.15, 0.85) + np.arange(columns))
    tilts = np.radians(np.arange(-8.0, 12.0, 0.6))
    pan, tilt = (a.ravel() for a in np.meshgrid(pans, tilts))
    beams = np.column_stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)])
    # Ray against the infinite vertical cylinder (x - d)^2 + y^2 = r^2, nearest root.
    a = beams[:, 0] ** 2 + beams[:, 1] ** 2
    b = -2.0 * distance * beams[:, 0]
    c = distance**2 - radius**2
    disc = b * b - 4 * a * c
    t = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2 * a)
    z = t * beams[:, 2]
    hit = (disc > 0) & (z > -1.0) & (z < length - 1.0)
    ranges = t[hit] + rng.normal(0.0, SIGMA, hit.sum())
    return beams[hit] * ranges[:, None]


# Two scans from the review's own ray caster (pointing noise 0.01 degree, range noise 2 mm):
# two pan columns along a vertical pipe, two tilt rows along a horizontal one.
REVIEW_SCANS = json.loads((Path(__file__).parent / "two_line_pipes.json").read_text())


@pytest.mark.parametrize("scan", REVIEW_SCANS, ids=[scan["name"] for scan in REVIEW_SCANS])
def test_two_raster_lines_are_refused_with_the_radii_they_allow(scan):
    with pytest.raises(FitError, match="two lines along it") as caught:
        fit_points(
            "cylinder", np.array(scan["points"]), sigma=SIGMA, viewpoint=np.array(scan["station"])
        )
    # The radii it names reach past the true one.
    reach_mm = float(str(caught.value).split("radii up to ")[1].split(" mm")[0])
    assert reach_mm > 1000.0 * scan["radius"]


@pytest.mark.parametrize(("radius", "seed"), [(0.0571, 0), (0.0571, 1), (0.0842, 2), (0.1095, 3)])
def test_two_raster_columns_do_not_give_a_radius_to_the_millimetre(radius, seed):
    points = pipe_scan(radius, 6.5, 2, seed)
    try:
        result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=np.zeros(3))
    except FitError:
        return  # refused: honest
    # Fitted: the truth must lie within its error.
    assert abs(result.primitive.radius - radius) <= 3.0 * result.stderr["radius"], (
        result.primitive.radius,
        result.stderr,
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_pipe_over_several_raster_columns_is_untouched(seed):
    points = pipe_scan(0.0571, 6.5, 5, seed)
    result = fit_points("cylinder", points, sigma=SIGMA, viewpoint=np.zeros(3))
    assert "radius_reach" not in result.diagnostics
    assert not any("two lines" in note for note in result.notes)
    assert abs(result.primitive.radius - 0.0571) < 4.0 * result.stderr["radius"] + 1e-4


def _lines(count, rng, radius=0.06):
    """Shots on ``count`` straight lines along a z-axis cylinder, and their axis and centre."""
    angles = np.linspace(-1.2, 1.2, count)
    z = rng.uniform(-1.0, 1.0, (count, 8))
    points = np.concatenate(
        [
            np.column_stack(
                [np.full(8, radius * math.cos(a)), np.full(8, radius * math.sin(a)), z[i]]
            )
            for i, a in enumerate(angles)
        ]
    )
    return points + rng.normal(0.0, 0.0005, points.shape), np.array([0.0, 0.0, 1.0]), np.zeros(3)


@pytest.mark.parametrize(("count", "expected"), [(2, True), (3, False), (5, False)])
def test_two_lines_are_told_from_more(count, expected):
    points, axis, centre = _lines(count, np.random.default_rng(count))
    assert on_two_lines(points, axis, centre, 0.006) is expected


def _slanted_lines(count, rng, radius=0.057, sweep_deg=50.0):
    """Shots on ``count`` raster lines slanted across a z-axis cylinder: each runs 0.8 m along
    it while turning ``sweep_deg`` about it (a window turned to the pipe), 64 degrees apart."""
    z = np.linspace(-0.4, 0.4, 13)
    turn = np.radians(sweep_deg) * (z - z.mean()) / np.ptp(z)
    points = np.concatenate(
        [
            np.column_stack([radius * np.cos(a), radius * np.sin(a), z])
            for a in [turn + np.radians(64.0) * (i - (count - 1) / 2) for i in range(count)]
        ]
    )
    return points + rng.normal(0.0, SIGMA / 2, points.shape), np.array([0.0, 0.0, 1.0]), np.zeros(3)


@pytest.mark.parametrize(("count", "expected"), [(2, True), (3, False), (4, False)])
def test_two_slanted_lines_are_told_from_more(count, expected):
    """Slanted lines' directions about the axis run into each other, so no gap parts them; two
    of them are still straight within the noise, three or more are not."""
    points, axis, centre = _slanted_lines(count, np.random.default_rng(count))
    assert on_two_lines(points, axis, centre, 3 * SIGMA) is expected


def test_a_review_pipe_on_two_slanted_lines_is_refused():
    """The stop-48 review's plumb NPS 4 pipe through a floor: its 26 shots on two raster lines
    3 degrees apart gave r 30.1 +-1.8 mm for 57.15 mm."""
    path = Path(__file__).with_name("background_plane_scenes.json")
    scene = json.loads(path.read_text())["scenes"]["two_slanted_lines"]
    points = np.array(scene["points"])
    with pytest.raises(FitError, match="two lines along it"):
        fit_points("cylinder", points[scene["on_target"]], sigma=SIGMA, viewpoint=scene["station"])
    with pytest.raises(FitError):  # with the floor's 307 shots too
        fit_points("cylinder", points, sigma=SIGMA, viewpoint=scene["station"])


def _raster_rows(rows: int, rng) -> np.ndarray:
    """Shots (n, 3) metres 6 m from the origin on ``rows`` raster rows (tilt steps of 0.5
    degree), 15 pans 0.2 degree apart, the beams' lengths varying by a few centimetres."""
    pans = np.radians(0.2 * np.arange(15))
    tilts = np.radians(0.5 * np.arange(rows))
    pan, tilt = (a.ravel() for a in np.meshgrid(pans, tilts))
    beams = np.column_stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)])
    return (6.0 + rng.uniform(-0.05, 0.05, pan.size))[:, None] * beams


@pytest.mark.parametrize(("rows", "expected"), [(2, True), (3, False), (5, False)])
def test_two_raster_rows_are_told_from_more(rows, expected):
    points = _raster_rows(rows, np.random.default_rng(rows))
    assert on_two_raster_lines(points, np.zeros(3)) is expected
    # Turned a quarter about the beam's mean: two columns instead of two rows.
    assert on_two_raster_lines(points[:, [0, 2, 1]], np.zeros(3)) is expected


def test_shots_aimed_by_hand_are_not_on_raster_lines():
    rng = np.random.default_rng(5)
    points = _raster_rows(2, rng)
    points += rng.normal(0.0, 0.01, points.shape)  # a centimetre off any line at 6 m
    assert not on_two_raster_lines(points, np.zeros(3))


@pytest.mark.parametrize("name", ["through_wall_two_rows", "on_floor_two_rows"])
def test_two_raster_rows_over_a_pipe_widen_its_radius_error(name):
    """Two raster rows slanted over a pipe (a black-box review's ray caster): the fit's radius
    was 37% and 28% low at one or two millimetres; the radii the rows accept now widen its
    standard error to take in the true one, and a note says why."""
    path = Path(__file__).with_name("two_raster_rows_scenes.json")
    scene = json.loads(path.read_text())["scenes"][name]
    result = fit_points("cylinder", scene["points"], sigma=SIGMA, viewpoint=scene["station"])
    error = abs(result.primitive.radius - scene["truth"]["radius"])
    assert error > 0.2 * scene["truth"]["radius"]  # the likeliest radius is still the low one
    assert error < 2.0 * result.stderr["radius"]
    assert result.diagnostics["radius_reach"] > scene["truth"]["radius"]
    assert any("two raster lines" in note for note in result.notes)


def test_a_line_grazing_the_silhouette_is_a_line_however_its_shots_scatter():
    # A vertical pipe (r 1.5 m, axis through (10, 0)): a raster column on its front and one
    # grazing its silhouette, whose shots (mixed returns between the pipe and the wall behind
    # among them) scatter 40 mm along their beams. The grazing column is no straight line to
    # the cutoff, but over its 1.4 degrees of arc it bows by a tenth of a millimetre: as far as
    # the radius goes, a line.
    rng = np.random.default_rng(4)
    radius, center, axis = 1.5, np.array([10.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    heights = np.linspace(0.0, 3.0, 10)
    front = np.column_stack([np.full(10, 10.0 - radius), np.zeros(10), heights])
    angles = np.radians(90.0 + rng.uniform(-0.7, 0.7, 10))
    grazing = np.column_stack(
        [10.0 + radius * np.cos(angles), radius * np.sin(angles), heights]
    ) + np.outer(rng.uniform(-0.02, 0.02, 10), [1.0, 0.0, 0.0])
    kept = np.vstack([front, grazing])
    assert on_two_lines(kept, axis, center, 0.006)
    # A scattered band over 40 degrees of arc is no line.
    band = np.radians(90.0 + rng.uniform(-20.0, 20.0, 10))
    wide = np.column_stack([10.0 + radius * np.cos(band), radius * np.sin(band), heights])
    assert not on_two_lines(np.vstack([front, wide]), axis, center, 0.006)
