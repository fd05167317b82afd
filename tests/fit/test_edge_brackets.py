"""A cuboid edge pinned by edge bisection lies within the bracket the session ended on.

The docs' simulated site, scanned without noise: the PTU-D46 aims in whole positions
(0.0514 degree), so the bisection of the column's silhouette cannot narrow below one
position, 5 mm across the beam at 5.5 m and 15 mm along the side seen at 71 degrees. The fit
took the last hit for the edge: 395.9 x 388.9 mm (truth 400 x 400) +- 0.1 micrometre.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from asbuilt.fit import fit, fit_object
from asbuilt.fit._edge_brackets import edge_brackets
from asbuilt.scan.model import ScanObject

EXAMPLES = Path(__file__).resolve().parents[2] / "drivers" / "examples"


def _scan_site(out: Path, options: str):
    from asbuilt.drivers.kinematics import Calibration
    from asbuilt.drivers.plan import load_plan
    from asbuilt.drivers.ptu import PanTiltUnit
    from asbuilt.drivers.rangefinder import open_range_finder
    from asbuilt.drivers.session import DeviceShooter, ScanSession
    from asbuilt.drivers.simrig import forget_rigs

    forget_rigs()
    plan = load_plan(EXAMPLES / "site.plan.json")
    ptu = PanTiltUnit.open(f"sim-ptu://brackets?scene={EXAMPLES / 'site.scene.json'}&{options}")
    lrf = open_range_finder("sim-lrf://brackets")
    try:
        with ScanSession(DeviceShooter(ptu, lrf), Calibration(), out) as session:
            for target in plan.targets:
                session.scan(target)
    finally:
        ptu.close()
        lrf.close()
        forget_rigs()
    return out


@pytest.fixture(scope="module")
def noiseless_site(tmp_path_factory):
    out = tmp_path_factory.mktemp("brackets") / "site.json"
    return _scan_site(out, "range_sigma=0&angle_sigma=0")


def test_the_session_records_each_bisections_last_bracket(noiseless_site):
    doc = json.loads(noiseless_site.read_text())
    column = next(obj for obj in doc["objects"] if obj["id"] == "C1")
    rows = column["acquisition"]["edge_brackets"]
    # The column's left and right silhouette (its top and bottom run on past the window).
    assert len(rows) == 2
    for row in rows:
        assert len(row) == 7 and 0 <= row[0] < len(column["points"])
        turn, heading = np.array(row[1:4]), np.array(row[4:])
        assert math.isclose(np.linalg.norm(heading), 1.0, rel_tol=1e-9)
        # At least one head position (0.0514 degree) between the hit and the miss: the
        # angles the head reached, not the bisection's requests (a few millidegrees apart).
        assert np.linalg.norm(turn) >= math.radians(0.05)


def test_the_column_section_is_measured_within_its_standard_error(noiseless_site):
    from asbuilt.scan import load_scan

    report = fit(load_scan(noiseless_site))
    column = report.get("C1").result
    size = np.asarray(column.primitive.size)
    section = [k for k in range(3) if size[k] < 1.0]
    assert len(section) == 2
    for k in section:
        se = column.stderr["size"][k]
        error = size[k] - 0.4
        # Was -4.1 and -11.1 mm at 0.1 micrometre (z -40000 and -100000).
        assert abs(error) < 0.005
        assert abs(error) <= 3.0 * se
        assert se >= 0.001  # the bracket, not the (zero) noise
    assert column.diagnostics["bracketed"] == 2.0


def test_noisy_sessions_stay_within_three_standard_errors(tmp_path):
    from asbuilt.scan import load_scan

    out = _scan_site(tmp_path / "site.json", "seed=1")
    column = fit(load_scan(out)).get("C1").result
    size = np.asarray(column.primitive.size)
    for k in (k for k in range(3) if size[k] < 1.0):
        # Was 395.8 +- 0.8 and 390.2 +- 0.7 mm (z -5.5 and -13.5).
        assert abs(size[k] - 0.4) <= 3.0 * column.stderr["size"][k]


def test_without_brackets_the_fit_is_unchanged(noiseless_site):
    from asbuilt.scan import load_scan

    column = load_scan(noiseless_site).object("C1")
    plain = ScanObject(
        id="C1",
        kind="cuboid",
        points=column.points,
        measurements=column.measurements,
        extra={"acquisition": {"window_deg": column.extra["acquisition"]["window_deg"]}},
    )
    viewpoint = np.zeros(3)
    with_brackets = fit_object(column, viewpoint=viewpoint).result
    without = fit_object(plain, viewpoint=viewpoint).result
    assert "bracketed" not in without.diagnostics
    assert with_brackets.diagnostics["bracketed"] == 2.0
    assert np.all(np.asarray(with_brackets.primitive.size[:2]) > without.primitive.size[:2])


@pytest.mark.parametrize(
    "rows",
    [
        None,
        5,
        [],
        [[0, 0, 0, 0]],  # the wrong width
        [[0.5, 0, 0, 0, 1, 0, 0]],  # not an index
        [[3, 0, 0, 0, 1, 0, 0]],  # past the points
        [[0, 0, 0, float("nan"), 1, 0, 0]],
        [["a", 0, 0, 0, 1, 0, 0]],
    ],
)
def test_malformed_brackets_are_ignored(rows):
    obj = ScanObject(
        id="C1",
        kind="cuboid",
        points=np.zeros((3, 3)),
        extra={"acquisition": {"edge_brackets": rows}},
    )
    assert edge_brackets(obj) is None
