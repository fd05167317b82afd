"""``asbuilt calibrate``: scan a room of known planes with a rig that has injected calibration
errors (over the simulator URLs), estimate, and check the estimate predicts the true points."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from asbuilt.drivers.calibration import calibration_to_dict, load_calibration
from asbuilt.drivers.kinematics import Calibration, aim, forward

from asbuilt.cli import main

STATION = (0.0, 0.0, 1.2)
NOMINAL = Calibration(base_position=STATION)
TRUE = Calibration(
    pan_zero=math.radians(0.8),
    tilt_zero=math.radians(-0.5),
    tilt_axis_offset=(0.0, 0.0, 0.047),
    laser_offset=(0.0, 0.025, 0.035),
    range_offset=0.015,
    range_scale=1.003,
    base_position=STATION,
)
# id: (plate centre, normal, surface plane normal . x = offset, corner points to aim at)
ROOM = {
    "floor": ([2.5, 0, -0.005], [0, 0, 1], 0.0, [[1.6, -1.2, 0], [3.6, 1.2, 0]]),
    "front": ([4.005, 0, 1.5], [1, 0, 0], 4.0, [[4, -1.5, 0.4], [4, 1.5, 2.6]]),
    "left": ([2.0, 3.005, 1.5], [0, 1, 0], 3.0, [[0.8, 3, 0.4], [3.2, 3, 2.6]]),
    "right": ([2.0, -2.505, 1.5], [0, -1, 0], 2.5, [[0.8, -2.5, 0.4], [3.2, -2.5, 2.6]]),
    "ceiling": ([2.5, 0, 3.005], [0, 0, 1], 3.0, [[1.6, -1.2, 3], [3.6, 1.2, 3]]),
}


@pytest.fixture
def room(tmp_path):
    objects = [
        {
            "id": name,
            "kind": "plane",
            "geometry": {
                "type": "plate",
                "center": centre,
                "normal": normal,
                "size": [8, 8],
                "thickness": 0.01,
            },
        }
        for name, (centre, normal, _, _) in ROOM.items()
    ]
    scene = {
        "format": "asbuilt-scene",
        "version": 1,
        "units": "m",
        "stations": [
            {"id": "S", "position": list(STATION), "range_sigma": 0.0005, "angular_sigma_deg": 0.0}
        ],
        "objects": objects,
    }
    targets = []
    for name, (_, _, _, corners) in ROOM.items():
        pan, tilt = aim(NOMINAL, np.array(corners, float))
        targets.append(
            {
                "id": name,
                "kind": "plane",
                "points": 30,
                "window_deg": [
                    math.degrees(pan[0]),
                    math.degrees(tilt[0]),
                    math.degrees(pan[1]),
                    math.degrees(tilt[1]),
                ],
            }
        )
    plan = {
        "format": "asbuilt-scan-plan",
        "version": 1,
        "targets": targets,
        "settings": {"edge_pairs": 0},
    }
    known = {
        "format": "asbuilt-targets",
        "version": 1,
        "targets": {
            name: {"type": "plane", "normal": normal, "offset": offset}
            for name, (_, normal, offset, _) in ROOM.items()
        },
    }
    files = {
        "scene": scene,
        "plan": plan,
        "targets": known,
        "nominal": calibration_to_dict(NOMINAL),
        "true": calibration_to_dict(TRUE),
    }
    for key, doc in files.items():
        (tmp_path / f"{key}.json").write_text(json.dumps(doc))
    return tmp_path


def test_calibrate_recovers_the_injected_errors(room, capsys):
    scan_args = [
        "scan",
        "--ptu",
        f"sim-ptu://room?scene={room / 'scene.json'}&calibration={room / 'true.json'}",
        "--lrf",
        "sim-lrf://room",
        "--calibration",
        str(room / "nominal.json"),
        "--plan",
        str(room / "plan.json"),
        "--out",
        str(room / "room.json"),
    ]
    assert main(scan_args) == 0
    capsys.readouterr()
    assert (
        main(
            [
                "calibrate",
                str(room / "room.json"),
                "--targets",
                str(room / "targets.json"),
                "--initial",
                str(room / "nominal.json"),
                "--out",
                str(room / "est.json"),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "residual RMS" in out and "held fixed" in out
    estimate = load_calibration(room / "est.json")
    doc = json.loads((room / "est.json").read_text())
    assert doc["estimate"]["residual_rms_m"] < 0.001
    assert doc["estimate"]["initial_rms_m"] > 0.01
    # fresh directions all around the room: the estimate predicts the true points
    rng = np.random.default_rng(0)
    pan = rng.uniform(-1.2, 1.2, 200)
    tilt = rng.uniform(-0.6, 0.6, 200)
    raw = rng.uniform(1.0, 5.0, 200)
    truth = forward(TRUE, pan, tilt, raw)
    assert np.abs(forward(NOMINAL, pan, tilt, raw) - truth).max() > 0.03
    assert np.abs(forward(estimate, pan, tilt, raw) - truth).max() < 0.004
    assert estimate.get("tilt_axis_offset.z") == pytest.approx(0.047, abs=0.003)


def test_calibrate_needs_measurements_and_known_ids(room, capsys):
    scan = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "objects": [
            {
                "id": "front",
                "kind": "plane",
                "points": [[4, 0, 0], [4, 1, 0], [4, 0, 1], [4, 1, 1.5]],
            }
        ],
    }
    (room / "bare.json").write_text(json.dumps(scan))
    code = main(
        [
            "calibrate",
            str(room / "bare.json"),
            "--targets",
            str(room / "targets.json"),
            "--out",
            str(room / "x.json"),
        ]
    )
    assert code == 2
    err = capsys.readouterr().err
    assert "no object with this id" in err and "targets.floor" in err
    assert not (room / "x.json").exists()


def test_calibrate_refuses_objects_without_raw_measurements(room, capsys):
    scan = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "objects": [
            {
                "id": "front",
                "kind": "plane",
                "points": [[4, 0, 0], [4, 1, 0], [4, 0, 1], [4, 1, 1.5]],
            }
        ],
    }
    (room / "bare.json").write_text(json.dumps(scan))
    (room / "one.json").write_text(
        json.dumps({"targets": {"front": {"type": "plane", "normal": [1, 0, 0], "offset": 4.0}}})
    )
    code = main(
        [
            "calibrate",
            str(room / "bare.json"),
            "--targets",
            str(room / "one.json"),
            "--out",
            str(room / "x.json"),
        ]
    )
    assert code == 2
    assert "objects[0] (front): has no raw measurements" in capsys.readouterr().err


@pytest.mark.parametrize(
    "more, message",
    [
        (
            ["--free", "pan_zero", "--fix", "pan_zero"],
            "--fix: 'pan_zero' is given to both --free and --fix; estimate it or hold it, not both",
        ),
        (["--free", "pan_zero,bogus"], "--free: unknown parameter 'bogus'; use names from: "),
        (["--fix", "bogus"], "--fix: unknown parameter 'bogus'; use names from: "),
        (["--free", ","], "--free: give parameter names, comma separated"),
    ],
)
def test_calibrate_parameter_choices_are_checked_first_and_named(tmp_path, capsys, more, message):
    """A name given to both --free and --fix was reported as 'no calibration parameter is
    observable from these targets' after the work; a misspelt one did not name its option."""
    argv = ["calibrate", str(tmp_path / "no-scan.json"), "--targets", str(tmp_path / "t.json")]
    assert main([*argv, "--out", str(tmp_path / "c.json"), *more]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"asbuilt: error: {message}") and err.count("\n") == 1, err
    assert list(tmp_path.iterdir()) == []
