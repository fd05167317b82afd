"""Sizes an acquisition session saw run on beyond the operator's window are lower bounds."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from asbuilt.fit import fit, fit_object
from asbuilt.fit._window import beyond_window
from asbuilt.scan.model import ScanObject

EXAMPLES = Path(__file__).resolve().parents[2] / "drivers" / "examples"


def _object(pan_deg, tilt_deg, window):
    n = len(pan_deg)
    measurements = np.column_stack([np.radians(pan_deg), np.radians(tilt_deg), np.full(n, 5.0)])
    return ScanObject(
        id="C1",
        kind="cuboid",
        points=np.zeros((n, 3)),
        measurements=measurements,
        extra={"acquisition": {"window_deg": window}},
    )


def test_beyond_window_is_outside_the_recorded_corners():
    obj = _object([64.0, 72.9, 73.2, 68.0, 68.0], [0.0, 9.9, 0.0, -8.4, 10.1], [63.5, -8, 73, 10])
    assert beyond_window(obj).tolist() == [False, False, True, True, True]


@pytest.mark.parametrize(
    "extra",
    [{}, {"acquisition": {"window_deg": [1, 2, 3]}}, {"acquisition": 5}, {"acquisition": {}}],
)
def test_beyond_window_needs_a_window(extra):
    obj = _object([0.0, 1.0], [0.0, 1.0], [0, 0, 2, 2])
    assert beyond_window(obj) is not None
    obj = ScanObject(
        id="C1", kind="cuboid", points=obj.points, measurements=obj.measurements, extra=extra
    )
    assert beyond_window(obj) is None


def test_beyond_window_needs_the_measurements():
    extra = {"acquisition": {"window_deg": [0, 0, 2, 2]}}
    assert (
        beyond_window(ScanObject(id="C1", kind="cuboid", points=np.zeros((2, 3)), extra=extra))
        is None
    )


@pytest.fixture(scope="module")
def site_scan(tmp_path_factory):
    """The docs' example session ("Trying it without hardware"): the simulated site, scanned
    with its plan; the column's window (tilt -8 to 10 degrees) covers its middle only."""
    from asbuilt.drivers.calibration import load_calibration
    from asbuilt.drivers.plan import load_plan
    from asbuilt.drivers.ptu import PanTiltUnit
    from asbuilt.drivers.rangefinder import open_range_finder
    from asbuilt.drivers.session import DeviceShooter, ScanSession

    from asbuilt.scan import load_scan

    out = tmp_path_factory.mktemp("site") / "site.json"
    plan = load_plan(EXAMPLES / "site.plan.json")
    cal = load_calibration(EXAMPLES / "ptu-d46.cal.json")
    ptu = PanTiltUnit.open(f"sim-ptu://example?scene={EXAMPLES / 'site.scene.json'}")
    lrf = open_range_finder("sim-lrf://example")
    with ScanSession(DeviceShooter(ptu, lrf), cal, out) as session:
        for target in plan.targets:
            session.scan(target)
    ptu.close()
    lrf.close()
    return load_scan(out)


def test_a_column_running_on_past_its_window_has_a_lower_bound_height(site_scan):
    # The scene's column is 3.0 m tall; the window saw 2.3 m of it and the shots beyond the
    # window's top and bottom rows hit it too. Its height was reported +-52 mm.
    report = fit(site_scan)
    column = report.get("C1").result
    height = int(np.argmax(column.primitive.size))
    assert column.primitive.size[height] < 3.0
    assert math.isinf(column.stderr["size"][height])
    assert math.isinf(column.stderr["center"])
    assert any("beyond the operator's window at both ends" in note for note in column.notes)
    assert column.diagnostics["open_sizes"] == 1.0
    # The other sizes and the pipe (whose window holds its ends) keep their errors.
    assert all(math.isfinite(se) for k, se in enumerate(column.stderr["size"]) if k != height)
    pipe = report.get("P1").result
    assert math.isfinite(pipe.stderr["length"])
    assert not any("beyond the operator's window" in note for note in pipe.notes)


def test_a_pipe_running_on_past_its_window_has_a_lower_bound_length(site_scan):
    # The same column's shots read as a cylinder's would give a length; with its outermost
    # shots beyond the window, that length is a lower bound too.
    column = next(obj for obj in site_scan.objects if obj.id == "C1")
    as_pipe = ScanObject(
        id="C1",
        kind="cylinder",
        points=column.points,
        measurements=column.measurements,
        extra=column.extra,
    )
    result = fit_object(as_pipe, sigma=0.002, viewpoint=site_scan.sensor.position).result
    assert math.isinf(result.stderr["length"])
