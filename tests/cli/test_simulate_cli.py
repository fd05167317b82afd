"""``asbuilt simulate``: in-process and as a subprocess; bad input is one line and exit 2."""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from asbuilt.cli import main
from asbuilt.scan import load_scan

ROOT = Path(__file__).resolve().parents[2]
SCENE = {
    "units": "mm",
    "seed": 3,
    "stations": [{"id": "S1", "position": [0, 0, 1500]}],
    "objects": [
        {
            "id": "P1",
            "kind": "cylinder",
            "points": 24,
            "nominal": '4"',
            "geometry": {
                "type": "cylinder",
                "start": [-1000, 5000, 1000],
                "end": [1000, 5000, 1000],
                "od": 114.3,
            },
        },
        {"id": "floor", "scan": False, "geometry": {"type": "ground"}},
    ],
}


@pytest.fixture
def scene_file(tmp_path):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(SCENE))
    return path


def test_in_process_writes_a_loadable_scan(scene_file, tmp_path, capsys):
    out = tmp_path / "scan.json"
    assert main(["simulate", str(scene_file), "--out", str(out), "--seed", "7"]) == 0
    scan = load_scan(out)
    assert scan.units == "mm" and [o.id for o in scan.objects] == ["P1"]
    assert 20 <= len(scan.objects[0].points) <= 32
    err = capsys.readouterr().err
    assert "simulated 1 object, " in err and " points (seed 7)" in err
    again = tmp_path / "again.json"
    main(["simulate", str(scene_file), "--out", str(again), "--seed", "7"])
    assert again.read_bytes() == out.read_bytes()


def test_points_and_exact_and_stdout(scene_file, capsys):
    assert main(["simulate", str(scene_file), "--out", "-", "--points", "33", "--exact"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert len(doc["objects"][0]["points"]) == 33
    assert doc["simulation"]["seed"] == 3


@pytest.mark.parametrize(
    "content, message",
    [
        ("{not json", "invalid JSON"),
        (json.dumps({**SCENE, "units": "yard"}), "units: unknown unit 'yard'"),
        (
            json.dumps(
                {
                    **SCENE,
                    "objects": [
                        {
                            "id": "X",
                            "kind": "cylinder",
                            "geometry": {
                                "type": "cylinder",
                                "start": [0, 0, 0],
                                "end": [0, 0, 0],
                                "od": 1,
                            },
                        }
                    ],
                }
            ),
            "objects[0] (X).geometry: 'start' and 'end' must differ",
        ),
    ],
)
def test_bad_scene_is_one_line_exit_2(tmp_path, capsys, content, message):
    bad = tmp_path / "bad.json"
    bad.write_text(content)
    out = tmp_path / "scan.json"
    assert main(["simulate", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and str(bad) in err
    assert not out.exists()


def test_missing_scene_and_bad_options(tmp_path, scene_file, capsys):
    assert main(["simulate", str(tmp_path / "nope.json"), "--out", str(tmp_path / "o")]) == 2
    assert "file not found" in capsys.readouterr().err
    assert main(["simulate", str(scene_file), "--out", str(tmp_path / "o"), "--points", "0"]) == 2
    assert "--points must be a positive integer" in capsys.readouterr().err


def test_points_beyond_a_scan_are_refused_before_any_work(tmp_path, scene_file, capsys):
    # found with the scene fuzzing: 10**30 shots overflowed the raster planner (a traceback)
    out = tmp_path / "o.json"
    assert main(["simulate", str(scene_file), "--out", str(out), "--points", "1" + "0" * 30]) == 2
    assert capsys.readouterr().err == (
        "asbuilt: error: --points must be at most 1,000,000 (the most a scan holds)\n"
    )
    assert not out.exists()


def test_subprocess(scene_file, tmp_path):
    out = tmp_path / "scan.json"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "simulate", str(scene_file), "--out", str(out)],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert load_scan(out).objects[0].id == "P1"
    bad = subprocess.run(
        [
            sys.executable,
            "-m",
            "asbuilt",
            "simulate",
            str(tmp_path / "nope.json"),
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
        timeout=120,
    )
    assert bad.returncode == 2
    assert "Traceback" not in bad.stderr and len(bad.stderr.strip().splitlines()) == 1
