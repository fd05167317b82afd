"""Eccentric or concentric reducers, decided from simulated scans (real cylinder fits).

Truth: ASME B36.10M outside diameters and ASME B16.9 reducer lengths H
(/work/shared/reference/standards.md); an eccentric reducer's axes are offset by
``(OD_large - OD_small) / 2``.
"""

from __future__ import annotations

import numpy as np
import pytest
from synthetic_pipes import Pipe, raster_points, report_of

from asbuilt.fit import fit_points
from asbuilt.fit.result import FitReport, ObjectFit
from asbuilt.merge import merge_model
from asbuilt.merge.contiguity import Joint
from asbuilt.merge.eccentric import eccentric_joints
from asbuilt.merge.spool import connection_mismatches
from asbuilt.scan.model import Scan, ScanObject, Sensor

# (large OD, small OD, B16.9 reducer length H by the large end), metres
SIZES = {
    "6x4": (0.1683, 0.1143, 0.140),
    "8x4": (0.2191, 0.1143, 0.152),
    "8x6": (0.2191, 0.1683, 0.152),
    "10x6": (0.2730, 0.1683, 0.178),
    "4x3": (0.1143, 0.0889, 0.102),
}
NOMINALS = {"0.1683": "6", "0.1143": "4", "0.2191": "8", "0.273": "10", "0.0889": "3"}
SIGMA = 0.002  # range noise, metres


def _scan(sizes: str, flat: str | None, rng, direction=(1.0, 0.0, 0.0), shots=30, hint=True):
    """Two pipes (large then small) meeting at a reducer, scanned from one station.

    ``flat``: None for concentric, "top" or "bottom" for eccentric; ``hint``: give each pipe its
    nominal size (so a sparse fit's ambiguous diameter still snaps). Returns the report and the
    truth (each pipe's axis start and end, metres).
    """
    od_l, od_s, h = SIZES[sizes]
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    up = np.array([0.0, 0.0, 1.0]) - d[2] * d
    up /= np.linalg.norm(up)
    step = 0.5 * (od_l - od_s)
    shift = {None: 0.0, "top": step, "bottom": -step}[flat] * up
    origin = np.array([1.0, 2.0, 1.2])
    truth = [
        (origin - 2.5 * d, origin),
        (origin + h * d + shift, origin + (h + 2.5) * d + shift),
    ]
    station = origin + 0.5 * h * d + np.cross(d, up) * -5.0 + up * 0.8
    objects, fits = [], []
    for k, ((a, b), od) in enumerate(zip(truth, (od_l, od_s))):
        pts = raster_points(a, b, od, shots, station, rng, sigma=SIGMA)
        nominal = NOMINALS[str(od)] if hint else None
        obj = ScanObject(
            id=f"P{k + 1}", kind="cylinder", points=pts, index=k, label="pipe", nominal=nominal
        )
        objects.append(obj)
        fits.append(ObjectFit(obj, fit_points("cylinder", pts, sigma=SIGMA), "cylinder"))
    scan = Scan(units="m", objects=tuple(objects), sensor=Sensor(range_sigma=SIGMA))
    return FitReport(scan=scan, fits=tuple(fits)), truth


def _reducer(model):
    found = [c for c in model.components if c.type == "reducer"]
    assert len(found) == 1, [c.type for c in model.components]
    return found[0]


@pytest.mark.parametrize("sizes", sorted(SIZES))
@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("hint", [True, False])
def test_concentric_spools_never_get_an_eccentric_reducer(sizes, seed, hint):
    report, _ = _scan(sizes, None, np.random.default_rng(seed), hint=hint)
    model = merge_model(report)
    reducer = _reducer(model)
    assert not reducer.geometry.eccentric
    assert "eccentric" not in reducer.snap
    assert np.allclose(reducer.geometry.offset, 0.0)


@pytest.mark.parametrize("seed", range(6))
def test_sloped_concentric_spool_stays_concentric(seed):
    report, _ = _scan("8x6", None, np.random.default_rng(100 + seed), direction=(1, 0.5, 0.3))
    assert not _reducer(merge_model(report)).geometry.eccentric


@pytest.mark.parametrize("sizes", ["6x4", "8x4", "8x6", "10x6"])
@pytest.mark.parametrize("flat", ["top", "bottom"])
@pytest.mark.parametrize("seed", range(3))
def test_eccentric_reducer_is_found_and_pipes_stay_where_scanned(sizes, flat, seed):
    report, truth = _scan(sizes, flat, np.random.default_rng(seed))
    model = merge_model(report)
    reducer = _reducer(model)
    g = reducer.geometry
    od_l, od_s, h = SIZES[sizes]
    assert g.eccentric
    assert reducer.snap["eccentric"]["flat"] == flat
    assert any(f"eccentric reducer, flat on {flat}" in n for n in reducer.snap["notes"])
    # exactly the radii's difference, exactly vertical (snapped), B16.9 length
    assert np.linalg.norm(g.offset) == pytest.approx(0.5 * (od_l - od_s), abs=1e-9)
    assert g.flat_side == pytest.approx([0, 0, 1 if flat == "top" else -1], abs=1e-9)
    assert g.length == pytest.approx(h, abs=1e-9)
    # both pipes' axes where the scan put them, and the reducer's ends on them
    pipes = {c.id: c.geometry for c in model.components if c.type == "pipe"}
    for pid, (a, _) in zip(("P1", "P2"), truth):
        line = pipes[pid]
        d = line.direction
        for point in (line.start, line.end):
            rel = point - a
            lateral = rel - (rel @ d) * d
            assert np.linalg.norm(lateral) < 0.004, (pid, lateral)
    assert np.linalg.norm(g.start - truth[0][1]) < 0.006
    assert np.linalg.norm(g.end - truth[1][0]) < 0.006
    found, bad = connection_mismatches(model.components, tolerance=1e-6)
    assert (found, bad) == (2, [])
    corrections = [c.what for c in model.component("P1").corrections]
    assert f"axis placed eccentric to P2 (eccentric reducer, flat on {flat})" in corrections
    assert not any("coaxial" in text for text in corrections)


def test_eccentric_joints_needs_known_errors_and_a_size_change():
    """Pure decision: 27 mm apart is eccentric for NPS 6 x 4 only when errors are known."""
    joints = (Joint("inline", ((0, 1), (1, 0))),)
    centers = np.array([[-1.25, 0, 1.0], [1.39, 0, 1.027]])
    axes = np.array([[1.0, 0, 0], [1.0, 0, 0]])
    lengths = np.array([2.5, 2.5])
    ods = np.array([0.1683, 0.1143])
    args = (joints, centers, axes, lengths, axes, ods)
    found = eccentric_joints(*args, [0, 1], [0.002, 0.002], [0.05, 0.05])
    assert found[0].flat == "top"
    assert found[0].offset == pytest.approx([0, 0, 0.027])
    assert eccentric_joints(*args, [0, 1], [np.nan, 0.002], [0.05, 0.05]) == {}
    unknown = [0.0, np.nan]  # a diameter without a catalog size or an error: never eccentric
    assert eccentric_joints(*args, [0, 1], [0.002, 0.002], [0.05, 0.05], od_se=unknown) == {}
    # an unsized 110 mm pipe (+-3 mm): 29.15 mm expected, measured 15 mm: 14.15 mm off, beyond
    # the 12.8 mm window, within it widened by 3 x 1.5 mm (half the diameter's error)
    centers[1, 2] = 1.015
    wide = (joints, centers, axes, lengths, axes, np.array([0.1683, 0.110]))
    assert eccentric_joints(*wide, [0, 1], [0.002, 0.002], [0.05, 0.05]) == {}
    found = eccentric_joints(*wide, [0, 1], [0.002, 0.002], [0.05, 0.05], od_se=[0, 0.003])
    assert np.linalg.norm(found[0].offset) == pytest.approx(0.02915)
    assert eccentric_joints(*args, [0, 0], [0.002, 0.002], [0.05, 0.05]) == {}
    # 12 mm apart is neither clearly off-axis nor the radii's difference: the window is
    # 3 x hypot(2.28, 2.28) + 3 = 12.8 mm (2 mm centre and 0.05 deg x 1.25 m axis errors)
    centers[1, 2] = 1.012
    assert eccentric_joints(*args, [0, 1], [0.002, 0.002], [0.05, 0.05]) == {}


def test_coaxial_synthetic_reducer_unchanged():
    report = report_of(
        [Pipe("P1", (0, 0, 1), (2, 0, 1), 0.1683), Pipe("P2", (2.14, 0, 1), (4, 0, 1), 0.1143)]
    )
    reducer = _reducer(merge_model(report))
    assert not reducer.geometry.eccentric
    assert reducer.geometry.start == pytest.approx([2.0, 0, 1])
    assert reducer.geometry.end == pytest.approx([2.14, 0, 1])


def test_an_unsized_pipe_still_gets_its_eccentric_reducer():
    """Seed 1 without hints: the NPS 4 pipe's fitted 110.7 mm is ambiguous (NPS 4 or 3 1/2), so
    it is built at its estimate; the axes' 27 mm step is still an eccentric reducer whose
    offset is the built radii's difference, and the pipes stay where scanned."""
    report, truth = _scan("6x4", "top", np.random.default_rng(1), hint=False)
    model = merge_model(report)
    reducer = _reducer(model)
    assert model.component("P2").snap["status"] == "ambiguous"
    g = reducer.geometry
    assert g.eccentric and reducer.snap["eccentric"]["flat"] == "top"
    step = g.outer_radius_start - g.outer_radius_end
    assert np.linalg.norm(g.offset) == pytest.approx(step, abs=1e-9)
    small = model.component("P2").geometry
    assert small.start[1:] == pytest.approx(truth[1][0][1:], abs=0.004)
