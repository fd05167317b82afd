"""Regularisation keeps measured slopes: IPC table 704.1 drainage slopes (0.5-2%) are all below
the 2 degree (3.5%) snap angle, so only the axis standard error can tell a slope from noise."""

from __future__ import annotations

import math

import numpy as np
import pytest
from synthetic_pipes import Pipe, raster_points, report_of

from asbuilt.fit import fit_points
from asbuilt.fit.result import FitReport, ObjectFit
from asbuilt.merge import merge_model
from asbuilt.merge.regularize import regularize_directions
from asbuilt.scan.model import Scan, ScanObject, Sensor

NPS4 = 0.1143
ONE_PERCENT_DEG = math.degrees(math.atan(0.01))  # 0.573 degrees


def test_a_significant_deviation_is_kept_and_an_insignificant_one_snapped():
    tilt = np.radians(ONE_PERCENT_DEG)
    axis = np.array([math.cos(tilt), 0.0, -math.sin(tilt)])
    # known to 0.02 degrees (a 6 m, 40-shot fit): 0.57 degrees is 29 standard errors, kept
    kept = regularize_directions([axis], [6.0], tol_deg=2.0, stderr_deg=[0.02])
    assert kept.axes[0] == pytest.approx(axis) and kept.relations == ((),)
    # known to 0.5 degrees (a short, sparse fit): noise, made horizontal
    snapped = regularize_directions([axis], [0.8], tol_deg=2.0, stderr_deg=[0.5])
    assert snapped.axes[0] == pytest.approx([1, 0, 0]) and snapped.relations == (("horizontal",),)
    # without standard errors the tolerance alone decides (as before)
    assert regularize_directions([axis], [6.0], tol_deg=2.0).axes[0] == pytest.approx([1, 0, 0])


def test_a_well_measured_slope_is_not_made_parallel_to_a_level_pipe():
    tilt = np.radians(ONE_PERCENT_DEG)
    axes = [[math.cos(tilt), 0.0, -math.sin(tilt)], [1.0, 0.0, 0.0]]
    out = regularize_directions(axes, [6.0, 6.0], tol_deg=2.0, stderr_deg=[0.02, 0.02])
    assert out.axes[0][2] == pytest.approx(-math.sin(tilt))
    assert out.cluster[0] != out.cluster[1]


def test_merge_keeps_a_drain_slope_given_the_fits_axis_errors():
    drop = 6.0 * 0.01
    pipes = [Pipe("D1", (-3, 0, 1.0 + drop), (3, 0, 1.0), NPS4, se_axis_deg=0.02)]
    d1 = merge_model(report_of(pipes)).components[0]
    assert d1.geometry.start[2] - d1.geometry.end[2] == pytest.approx(drop, abs=1e-9)
    assert not any(c.what.startswith("axis regularised") for c in d1.corrections)


def _fitted(objects_truth, station, rng):
    objects, fits = [], []
    for k, (name, start, end, n) in enumerate(objects_truth):
        pts = raster_points(start, end, NPS4, n, station, rng)
        obj = ScanObject(id=name, kind="cylinder", points=pts, index=k, label="drain pipe")
        objects.append(obj)
        fits.append(ObjectFit(obj, fit_points("cylinder", pts, sigma=0.002), "cylinder"))
    scan = Scan(units="m", objects=tuple(objects), sensor=Sensor(range_sigma=0.002))
    return FitReport(scan=scan, fits=tuple(fits))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_scanned_one_percent_drain_keeps_its_slope_and_a_short_level_pipe_is_levelled(seed):
    """The audit's slope.json: a 1% drain over 6 m (z 1.06 -> 1.00), 40 shots with 2 mm range
    noise from (0, -6, 1.5), was modelled flat at z = 1.030 (each end 30 mm off). A short,
    sparsely scanned level pipe is still made exactly level."""
    station = np.array([0.0, -6.0, 1.5])
    report = _fitted(
        [
            ("D1", (-3.0, 0, 1.06), (3.0, 0, 1.00), 40),
            ("L1", (-1.0, -0.5, 2.5), (-1.0, 0.5, 2.5), 12),
        ],
        station,
        np.random.default_rng(seed),
    )
    comps = {c.id: c for c in merge_model(report).components}
    g = comps["D1"].geometry
    for point in (g.start, g.end):
        truth_z = 1.03 - 0.01 * point[0]  # the drain's centre line
        assert point[2] == pytest.approx(truth_z, abs=0.005)
    slope = (g.start[2] - g.end[2]) / abs(g.end[0] - g.start[0])
    assert slope == pytest.approx(0.01, abs=0.001)
    level = comps["L1"].geometry
    assert level.start[2] == pytest.approx(level.end[2], abs=1e-12)
    assert any(c.what.startswith("axis regularised") for c in comps["L1"].corrections)


def test_a_noisy_axis_does_not_turn_a_well_measured_one_it_is_parallel_to():
    """Clusters take the inverse-variance direction: a 6 m drain known to 0.02 degrees and a
    short pipe 0.4 degrees from it, known to 0.3, are parallel; the drain barely moves."""
    tilt = np.radians(ONE_PERCENT_DEG)
    other = np.radians(ONE_PERCENT_DEG - 0.4)
    axes = [[math.cos(tilt), 0.0, -math.sin(tilt)], [math.cos(other), 0.0, -math.sin(other)]]
    out = regularize_directions(axes, [6.0, 6.0], tol_deg=2.0, stderr_deg=[0.02, 0.3])
    assert out.cluster[0] == out.cluster[1]
    assert out.angles_deg[0] < 3 * 0.02 and out.angles_deg[1] == pytest.approx(0.4, abs=0.01)
