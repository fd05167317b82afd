"""The example files in drivers/examples load, and the example plan scans the example scene."""

from __future__ import annotations

import json
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
    # The pan zero and the horizontal beam misalignment trade off on these targets: their sum
    # is the true 0.8 degree (room.true.cal.json), and the pair is reported as correlated.
    pan = estimate.pan_zero + estimate.beam_horizontal
    assert pan == pytest.approx(math.radians(0.8), abs=math.radians(0.05))
    notes = {line.split(" (")[0]: line for line in text.splitlines()}
    assert "pan_zero ~ beam_horizontal (-0.9" in notes["strongly correlated"]
    doc = json.loads(out.read_text())
    assert ["pan_zero", "beam_horizontal"] in [pair[:2] for pair in doc["estimate"]["correlated"]]
    # base_position.x rests on the front wall's offset alone
    assert "base_position.x by front (moved +0.00" in notes["set by one target's pose alone"]
    assert doc["estimate"]["one_target"] == {"base_position.x": "front"}
    assert notes["held fixed"].endswith("base_position.z, base_rotation.yaw")  # one line


def _targets_with_front_offset(tmp_path, offset):
    doc = json.loads((EXAMPLES / "room.targets.json").read_text())
    doc["targets"]["front"]["offset"] = offset
    path = tmp_path / f"front-{offset}.targets.json"
    path.write_text(json.dumps(doc))
    return path


def test_a_mis_surveyed_target_in_the_room_example(tmp_path, capsys):
    """A wall's offset typed 40 for 4 moved the instrument 36 m without a word; 0.3 m off is
    undetectable from the shots (only that wall fixes x), and the output says so."""
    from asbuilt.cli import main

    scene, truth = EXAMPLES / "room.scene.json", EXAMPLES / "room.true.cal.json"
    scan = tmp_path / "room-scan.json"
    argv = ["scan", "--ptu", f"sim-ptu://room2?scene={scene}&calibration={truth}"]
    argv += ["--lrf", "sim-lrf://room2", "--calibration", str(EXAMPLES / "ptu-d46.cal.json")]
    assert main([*argv, "--plan", str(EXAMPLES / "room.plan.json"), "--out", str(scan)]) == 0
    capsys.readouterr()
    initial = ["--initial", str(EXAMPLES / "ptu-d46.cal.json")]
    out = tmp_path / "cal.json"
    bad = _targets_with_front_offset(tmp_path, 40.0)
    assert main(["calibrate", str(scan), "--targets", str(bad), *initial, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and not out.exists(), err
    assert "the estimate moves base_position 36 m from the initial calibration" in err
    assert "the shots at 'front' lie 36 m (RMS) from it" in err
    off = _targets_with_front_offset(tmp_path, 4.3)
    assert main(["calibrate", str(scan), "--targets", str(off), *initial, "--out", str(out)]) == 0
    assert "base_position.x by front (moved +0.30" in capsys.readouterr().out
