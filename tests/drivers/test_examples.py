"""The example files in drivers/examples load, and the example plan scans the example scene."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from asbuilt.drivers.calibration import PlaneTarget, SphereTarget, load_calibration, load_targets
from asbuilt.drivers.plan import load_plan
from asbuilt.drivers.ptu import PanTiltUnit
from asbuilt.drivers.rangefinder import open_range_finder
from asbuilt.drivers.session import DeviceShooter, ScanSession

EXAMPLES = Path(__file__).resolve().parents[2] / "drivers" / "examples"


def test_example_calibration():
    cal = load_calibration(EXAMPLES / "ptu-d46.cal.json")
    assert cal.tilt_axis_offset == (0.0, 0.0, 0.047)


def test_example_targets():
    targets = load_targets(EXAMPLES / "room.targets.json")
    assert targets["front"] == PlaneTarget((1.0, 0.0, 0.0), 4.0)
    assert targets["ball"] == SphereTarget(0.15)


def test_example_plan_scans_the_example_scene(tmp_path):
    plan = load_plan(EXAMPLES / "site.plan.json")
    cal = load_calibration(EXAMPLES / "ptu-d46.cal.json")
    scene = EXAMPLES / "site.scene.json"
    ptu = PanTiltUnit.open(f"sim-ptu://example?scene={scene}")
    lrf = open_range_finder("sim-lrf://example")
    with ScanSession(DeviceShooter(ptu, lrf), cal, tmp_path / "site.json") as session:
        for target in plan.targets:
            assert session.scan(target) is not None
    ptu.close()
    lrf.close()
    assert set(session.objects) == {"P1", "C1"}
    assert all(r.on_object.sum() >= 20 for r in session.objects.values())


def test_example_room_scan_calibrates(tmp_path, capsys):
    # docs/calibration.md, "Trying it without hardware": the room example scanned by the
    # simulated rig with its true (erroneous) calibration, then calibrated from the nominal one.
    from asbuilt.cli import main

    scene, truth = EXAMPLES / "room.scene.json", EXAMPLES / "room.true.cal.json"
    scan = tmp_path / "room-scan.json"
    assert (
        main(
            [
                "scan",
                "--ptu",
                f"sim-ptu://room?scene={scene}&calibration={truth}",
                "--lrf",
                "sim-lrf://room",
                "--calibration",
                str(EXAMPLES / "ptu-d46.cal.json"),
                "--plan",
                str(EXAMPLES / "room.plan.json"),
                "--out",
                str(scan),
            ]
        )
        == 0
    )
    capsys.readouterr()
    out = tmp_path / "cal.json"
    argv = ["calibrate", str(scan), "--targets", str(EXAMPLES / "room.targets.json")]
    argv += ["--initial", str(EXAMPLES / "ptu-d46.cal.json"), "--out", str(out)]
    assert main(argv) == 0
    text = capsys.readouterr().out
    before, after = (
        float(v) for v in re.findall(r"([\d.]+) mm", text.split("residual RMS:")[1])[:2]
    )
    assert before > 10.0 and after < 1.5
    estimate = load_calibration(out)
    assert estimate.range_offset == pytest.approx(0.015, abs=0.005)
    assert estimate.tilt_zero == pytest.approx(math.radians(-0.5), abs=math.radians(0.15))
    notes = {line.split(" (")[0]: line for line in text.splitlines()}
    assert notes["held fixed"].endswith("base_position.z, base_rotation.yaw")  # one line
