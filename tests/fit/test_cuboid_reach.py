"""Sizes bounded by shots that no raster says reach the edges: lower bounds, not measurements.

An independent review's column (0.3 x 0.3 x 3 m, seen on two faces, 24 shots aimed by hand in
clusters away from the edges, ``box_hand_aimed.json``, the truth under ``truth``) came out
280.1 +- 7.6, 242.4 +- 6.9 and 2799 +- 149 mm: every size short, the width at z -8.4. The
standard error was half the spacing between the operator's clusters, which says nothing about
how far an edge lies beyond the last shot. Without a raster lattice from a trusted viewpoint
those sizes are lower bounds (``asbuilt.fit._cuboid_reach``): standard error infinite, a note
with what the shots span. A raster keeps its finite errors, and so does a dense cloud.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest
from fit_scans import cell_centres, corner_angles, shoot, sizes_in_true_order

from asbuilt.fit import fit, fit_points
from asbuilt.fit._cuboid_reach import DENSE_SHOTS, lower_bounds, note
from asbuilt.fit.cuboid import fit_cuboid
from asbuilt.primitives import Cuboid
from asbuilt.scan.load import load_scan

HERE = Path(__file__).parent
RANGE_SIGMA = 0.002  # metres
SPAN = re.compile(r"([\d.]+) m \(the shots span ([\d.]+) m of it\)")


def _column(yaw_deg: float = 40.0) -> Cuboid:
    """A 0.3 x 0.3 x 3 m column 6 m out along x from the station (the origin), its centre at
    the station's height, turned ``yaw_deg`` (two faces seen)."""
    yaw = np.radians(yaw_deg)
    axes = np.array(
        [[np.cos(yaw), np.sin(yaw), 0.0], [-np.sin(yaw), np.cos(yaw), 0.0], [0.0, 0.0, 1.0]]
    )
    return Cuboid(center=np.array([6.0, 0.0, 0.0]), axes=axes, size=np.array([0.3, 0.3, 3.0]))


def _raster(box: Cuboid, rng, columns: int = 7, rows: int = 8):
    """Hits (m, 3) of a cell-centred raster over the box's silhouette window widened by 10%."""
    pans, tilts = corner_angles(box)
    lines = []
    for values, count in ((pans, columns), (tilts, rows)):
        margin = 0.1 * np.ptp(values)
        lines.append(cell_centres(values.min() - margin, values.max() + margin, count))
    pan, tilt = np.meshgrid(*lines)
    points, hit = shoot(box, pan.ravel(), tilt.ravel(), rng, range_sigma=RANGE_SIGMA)
    return points[hit]


def _scattered(box: Cuboid, rng, count: int, inset: float):
    """Hits (count, 3) at random directions within the box's silhouette window shrunk by
    ``inset`` of its width a side (on no lattice: shots aimed one by one, or a cloud)."""
    pans, tilts = corner_angles(box)
    out = []
    while sum(len(p) for p in out) < count:
        pan = rng.uniform(
            pans.min() + inset * np.ptp(pans), pans.max() - inset * np.ptp(pans), count
        )
        tilt = rng.uniform(
            tilts.min() + inset * np.ptp(tilts), tilts.max() - inset * np.ptp(tilts), count
        )
        points, hit = shoot(box, pan, tilt, rng, range_sigma=RANGE_SIGMA)
        out.append(points[hit])
    return np.vstack(out)[:count]


def _spans(result) -> list[tuple[float, float]]:
    return [(float(a), float(b)) for note in result.notes for a, b in SPAN.findall(note)]


def test_hand_aimed_sizes_are_lower_bounds():
    path = HERE / "box_hand_aimed.json"
    truth = json.loads(path.read_text())["truth"]
    (item,) = fit(load_scan(path)).fits
    result = item.result
    assert not any(result.observed)
    # The sizes are as before (the extent padded by half the shots' spacing), the errors not.
    size, stderr, _ = sizes_in_true_order(result, np.asarray(truth["axes"]).T)
    assert size * 1000 == pytest.approx([242.4, 280.1, 2799.0], abs=0.1)
    assert np.all(np.isinf(stderr))  # were 6.9, 7.6 and 149 mm: z -8.4, -2.6 and -1.3
    assert math.isinf(result.stderr["center"])
    assert result.diagnostics["unreached_sizes"] == 3.0
    note = next(n for n in result.notes if "lower bound" in n)
    assert "not on a pan-tilt raster from the station" in note
    # Each lower bound, what the shots span, is below the truth.
    spans = _spans(result)
    assert len(spans) == 3
    for (fitted, span), true in zip(sorted(spans), sorted(truth["size"])):
        assert span <= fitted and span < true


@pytest.mark.parametrize("seed", range(3))
def test_a_raster_keeps_finite_standard_errors(seed):
    box = _column()
    points = _raster(box, np.random.default_rng(seed))
    # With the station, and without it when the scan frame is centred on it (then trusted).
    for viewpoint in (np.zeros(3), None):
        result = fit_cuboid(points, sigma=RANGE_SIGMA, viewpoint=viewpoint)
        size, stderr, observed = sizes_in_true_order(result, np.asarray(box.axes).T)
        assert not observed.any()
        assert np.all(np.isfinite(stderr)) and math.isfinite(result.stderr["center"])
        assert "unreached_sizes" not in result.diagnostics
        assert np.all(np.abs(size - box.size) <= 4.0 * stderr)


def test_shots_off_a_raster_are_lower_bounds_and_a_dense_cloud_is_not():
    box = _column()
    rng = np.random.default_rng(5)
    # Shots kept 10% of the window's width from its sides, at random directions: the edges
    # lie anywhere beyond them.
    few = _scattered(box, rng, 30, 0.1)
    for viewpoint in (np.zeros(3), None):
        result = fit_cuboid(few, sigma=RANGE_SIGMA, viewpoint=viewpoint)
        _, stderr, _ = sizes_in_true_order(result, np.asarray(box.axes).T)
        assert np.all(np.isinf(stderr))
        assert result.diagnostics["unreached_sizes"] == 3.0
        assert all(span <= size for size, span in _spans(result))
    note = next(n for n in result.notes if "lower bound" in n)
    assert "sensor position" in note  # without the station: give it
    # A scanner's cloud reaches its edges to its point spacing: finite errors that cover them.
    cloud = _scattered(box, rng, DENSE_SHOTS + 200, 0.0)
    result = fit_points("cuboid", cloud, sigma=RANGE_SIGMA)
    size, stderr, _ = sizes_in_true_order(result, np.asarray(box.axes).T)
    assert np.all(np.isfinite(stderr))
    assert np.all(np.abs(size - box.size) <= 4.0 * stderr + 0.01)


def test_lower_bounds_of_a_fit_without_its_station():
    # Two stations' views fitted together (no station): a view that found its sizes unreached
    # makes the joint fit's extent sizes lower bounds; observed sizes and the rest stay.
    box = _column()
    result = fit_cuboid(_raster(box, np.random.default_rng(1)), sigma=RANGE_SIGMA)
    bounded = lower_bounds(result)
    assert np.all(np.isinf(bounded.stderr["size"]))
    assert bounded.primitive is result.primitive
    assert bounded.stderr["axes_deg"] == result.stderr["axes_deg"]
    assert bounded.diagnostics["unreached_sizes"] == 3.0
    assert lower_bounds(bounded) is bounded  # nothing left to bound


def test_a_raster_with_occluded_columns_keeps_its_standard_errors():
    # The plant sample's beam B2 is a simulated raster whose pan columns have a gap (four
    # steps, something in front): no grid is read from it, but its tilts lie on evenly spaced
    # rows. Taken for hand-aimed shots, it got "aimed by hand?" and infinite errors.
    scan = load_scan(HERE.parents[1] / "samples" / "plant.json")
    beam = scan.object("B2")
    result = fit_points(
        "cuboid", beam.points, sigma=scan.sensor.range_sigma, viewpoint=scan.sensor.position
    )
    assert "unreached_sizes" not in result.diagnostics
    assert all(math.isfinite(se) for se in result.stderr["size"])


@pytest.mark.parametrize(
    ("trusted", "says"),
    [
        # A station given: the shots may be hand-aimed, or the station's position wrong (a
        # raster read from a point 0.5 m off is no raster).
        (True, ("aimed by hand, or is the station's position wrong?", "Check the scan's sensor")),
        (False, ("Without the station", "Give the scan's sensor position")),
    ],
)
def test_the_lower_bound_note_says_why_and_what_to_do(trusted, says):
    text = note([4.983, 0.289], [3.337, 0.248], trusted)
    assert all(part in text for part in says)
    assert "4.983 m (the shots span 3.337 m of it)" in text
