"""Simulated shots -> the real cylinder fit (asbuilt.fit.fit_points) -> merge_model."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from synthetic_pipes import raster_points

from asbuilt.fit import fit_points
from asbuilt.fit.result import FitReport, ObjectFit
from asbuilt.merge import merge_model, shot_spacing
from asbuilt.merge.spool import connection_mismatches
from asbuilt.scan.model import Scan, ScanObject, Sensor

OD6 = 0.1683
R6 = 0.229  # ASME B16.9 NPS 6 long-radius elbow


def scanned_spool(rng, n_points=30):
    corners = np.array([[0, 0, 0], [3.0, 0, 0], [3.0, 2.5, 0], [3.0, 2.5, 2.0]]) + [1, 2, 0.5]
    station = corners.mean(axis=0) + [4, -4, 1.5]
    truth, objects, fits = [], [], []
    for k in range(3):
        a, b = corners[k], corners[k + 1]
        d = (b - a) / np.linalg.norm(b - a)
        start = a + (R6 * d if k else 0)
        end = b - (R6 * d if k < 2 else 0)
        truth.append((start, end))
        pts = raster_points(start, end, OD6, n_points, station, rng)
        obj = ScanObject(id=f"P{k + 1}", kind="cylinder", points=pts, index=k, group="line-1")
        objects.append(obj)
        fits.append(ObjectFit(obj, fit_points("cylinder", pts, sigma=0.002), "cylinder"))
    scan = Scan(units="m", objects=tuple(objects), sensor=Sensor(range_sigma=0.002))
    return FitReport(scan=scan, fits=tuple(fits)), truth


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_simulated_spool_merges_to_standard_parts(seed):
    report, truth = scanned_spool(np.random.default_rng(seed))
    model = merge_model(report)
    assert [c.type for c in model.components] == ["pipe", "elbow", "pipe", "elbow", "pipe"]
    assert [s.id for s in model.spools] == ["line-1"]
    pipes = [c for c in model.components if c.type == "pipe"]
    assert {c.nominal for c in pipes} == {"6"}
    found, bad = connection_mismatches(model.components, tolerance=1e-4)
    assert (found, bad) == (4, [])
    for comp, (start, end) in zip(pipes, truth):
        g = comp.geometry
        ends = (g.start, g.end)
        for point, at_elbow in ((start, comp.id != "P1"), (end, comp.id != "P3")):
            if at_elbow:
                error = min(np.linalg.norm(e - point) for e in ends)
                assert error < 0.005, (comp.id, error)


def test_shot_spacing_is_the_largest_gap_along_the_axis():
    pts = np.array([[0, 0, 0], [0.1, 0, 0], [0.5, 0, 0], [0.6, 1, 0], [5, 0, 0]], float)
    inliers = np.array([True, True, True, True, False])
    assert shot_spacing(pts, inliers, np.zeros(3), np.array([1.0, 0, 0])) == pytest.approx(0.4)
    assert shot_spacing(pts[:1], inliers[:1], np.zeros(3), np.array([1.0, 0, 0])) == 0.0


SAMPLES = Path(__file__).resolve().parents[2] / "samples"


@pytest.mark.skipif(not (SAMPLES / "spool.json").exists(), reason="samples not present")
def test_the_simulated_sample_spool_merges_to_its_true_sizes():
    """samples/spool.json comes from the full simulator (dropouts, mixed edge returns)."""
    from asbuilt.fit import fit
    from asbuilt.scan import load_scan

    model = merge_model(fit(load_scan(SAMPLES / "spool.json")))
    comps = {c.id: c for c in model.components}
    truth = {"P1": "6", "P2": "6", "P3": "6", "P6": "6", "P4": "4", "P5": "4"}
    assert {k: comps[k].nominal for k in truth} == truth
    assert {c.type for c in model.components} == {"pipe", "tee", "elbow", "reducer"}
    assert connection_mismatches(model.components, tolerance=1e-4) == (9, [])
    assert [s.id for s in model.spools] == ["SP-101"]
