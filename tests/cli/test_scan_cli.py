"""``asbuilt scan`` and ``asbuilt simulate-device`` end to end over the simulated devices."""

from __future__ import annotations

import io
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from asbuilt.cli import main

ROOT = Path(__file__).resolve().parents[2]

PIPE_OD = 0.3239  # NPS 12
SCENE = {
    "format": "asbuilt-scene",
    "version": 1,
    "units": "m",
    "seed": 1,
    "stations": [
        {"id": "S1", "position": [0.0, 0.0, 1.5], "range_sigma": 0.001, "angular_sigma_deg": 0.005}
    ],
    "objects": [
        {
            "id": "P1",
            "kind": "cylinder",
            "geometry": {
                "type": "cylinder",
                "start": [-1.0, 4.0, 1.2],
                "end": [1.0, 4.0, 1.2],
                "od": PIPE_OD,
            },
        },
        {
            "id": "C1",
            "kind": "cuboid",
            "geometry": {
                "type": "member",
                "start": [2.0, 5.0, 0.0],
                "end": [2.0, 5.0, 3.0],
                "section": [0.4, 0.4],
            },
        },
        {
            "id": "wall",
            "scan": False,
            "geometry": {
                "type": "plate",
                "center": [0.0, 8.0, 2.0],
                "normal": [0, -1, 0],
                "size": [14.0, 5.0],
                "thickness": 0.2,
            },
        },
        {"id": "floor", "scan": False, "geometry": {"type": "ground"}},
    ],
}
PLAN = {
    "format": "asbuilt-scan-plan",
    "version": 1,
    "targets": [
        {"id": "P1", "kind": "cylinder", "window_deg": [72, -6.5, 108, -1.5], "nominal": '12"'},
        {"id": "C1", "kind": "cuboid", "window_deg": [63.5, -8, 73, 10]},
    ],
}


#: No random noise: a resumed session must reproduce an uninterrupted one exactly.
EXACT = "&range_sigma=0&angle_sigma=0"


@pytest.fixture
def site(tmp_path):
    """Scene, plan and calibration (an ideal chain at the scene's station) files."""
    (tmp_path / "scene.json").write_text(json.dumps(SCENE))
    (tmp_path / "plan.json").write_text(json.dumps(PLAN))
    (tmp_path / "cal.json").write_text(
        json.dumps(
            {"format": "asbuilt-calibration", "version": 1, "base": {"position_m": [0, 0, 1.5]}}
        )
    )
    return tmp_path


def _args(site, rig, out="scan.json", extra_ptu="", extra_lrf="", more=()):
    return [
        "scan",
        "--ptu",
        f"sim-ptu://{rig}?scene={site / 'scene.json'}{extra_ptu}",
        "--lrf",
        f"sim-lrf://{rig}{extra_lrf}",
        "--calibration",
        str(site / "cal.json"),
        "--out",
        str(site / out),
        *more,
    ]


def test_full_simulated_session_fits_the_true_dimensions(site, capsys):
    from asbuilt.fit import fit_points
    from asbuilt.scan import load_scan

    assert main(_args(site, "full", more=["--plan", str(site / "plan.json")])) == 0
    err = capsys.readouterr().err
    assert "P1" in err and "C1" in err
    scan = load_scan(site / "scan.json")
    pipe = scan.object("P1")
    assert pipe.nominal == '12"'
    assert 20 <= len(pipe.points) <= 60  # sparse: the paper's 20-40 points, not a dense cloud
    assert pipe.measurements.shape == pipe.points.shape
    cyl = fit_points("cylinder", pipe.points).primitive
    assert cyl.radius == pytest.approx(PIPE_OD / 2, rel=0.03)
    assert abs(cyl.axis[0]) == pytest.approx(1.0, abs=1e-3)
    assert cyl.center[1:] == pytest.approx([4.0, 1.2], abs=0.01)
    column = scan.object("C1")
    assert len(column.points) >= 30
    box = fit_points("cuboid", column.points).primitive
    assert box.center[:2] == pytest.approx([2.0, 5.0], abs=0.05)
    assert max(sorted(box.size)[:2]) == pytest.approx(0.4, rel=0.05)


def test_interactive_session_with_typed_and_aimed_windows(site, monkeypatch, capsys):
    answers = (
        "\n".join(
            [
                "P1",
                "cylinder",
                "72 -6.5 108 -1.5",
                '12"',
                "",  # insulation thickness: a bare pipe
                "C1",
                "cuboid",
                "aim",
                "63.5 -8",
                "ok",
                "73 10",
                "ok",
                "",
                "",
            ]
        )
        + "\n"
    )
    monkeypatch.setattr(sys, "stdin", io.StringIO(answers))
    assert main(_args(site, "typed")) == 0
    doc = json.loads((site / "scan.json").read_text())
    assert [o["id"] for o in doc["objects"]] == ["P1", "C1"]
    assert doc["objects"][0]["nominal"] == '12"'
    assert "insulation" not in doc["objects"][0]  # empty answer: bare
    window = doc["objects"][1]["acquisition"]["window_deg"]
    assert window == pytest.approx([63.5, -8, 73, 10], abs=0.06)  # whole counts of 0.0514 deg
    err = capsys.readouterr().err
    assert "object id" in err and "corner 1" in err
    assert err.count("  insulation thickness (optional, mm): ") == 1  # the cylinder's only


def test_a_plans_insulated_cylinder_is_written_in_the_scan_units(site, capsys):
    """The plan gives the thickness in metres; the scan file carries it in its --units and
    reads back in metres."""
    from asbuilt.scan import load_scan

    plan = {**PLAN, "targets": [{**PLAN["targets"][0], "insulation": 0.05}, PLAN["targets"][1]]}
    (site / "lagged.plan.json").write_text(json.dumps(plan))
    more = ["--plan", str(site / "lagged.plan.json"), "--units", "mm"]
    assert main(_args(site, "lagplan", more=more)) == 0
    doc = json.loads((site / "scan.json").read_text())
    assert doc["units"] == "mm"
    assert doc["objects"][0]["insulation"] == 50 and "insulation" not in doc["objects"][1]
    scan = load_scan(site / "scan.json")
    assert scan.object("P1").insulation == pytest.approx(0.05)
    assert scan.object("P1").nominal == '12"' and scan.object("C1").insulation == 0


def test_an_operators_insulation_is_asked_for_cylinders_and_asked_again_when_bad(
    site, monkeypatch, capsys
):
    """In millimetres (said in the prompt) for a metric scan; empty is a bare pipe; an answer
    that is not a thickness the scan could carry asks for the object again, as the nominal
    size does."""
    from asbuilt.scan import load_scan

    p1 = ["P1", "cylinder", "72 -6.5 108 -1.5", '12"']
    answers = [*p1, "2 in", *p1, "-5", *p1, "600", *p1, "38", "C1", "cuboid", "63.5 -8 73 10", ""]
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n".join([*answers, ""]) + "\n"))
    assert main(_args(site, "lagtyped", more=["--units", "cm"])) == 0
    err = capsys.readouterr().err
    assert err.count("  insulation thickness (optional, mm): ") == 4
    assert "  insulation thickness must be a number >= 0 in mm, not '2 in'; give the object " in err
    assert "must be a number >= 0 in mm, not '-5'; give the object again" in err
    assert "600 mm is thicker than any pipe insulation (at most 500 mm); give the object" in err
    doc = json.loads((site / "scan.json").read_text())
    assert [o["id"] for o in doc["objects"]] == ["P1", "C1"]
    assert doc["objects"][0]["insulation"] == 3.8  # cm, the scan's units
    assert "insulation" not in doc["objects"][1]
    assert load_scan(site / "scan.json").object("P1").insulation == pytest.approx(0.038)


@pytest.mark.parametrize(
    "units, text, expected",
    [
        ("m", "", (None, None)),
        ("mm", "50", (None, 0.05)),
        ("in", "1.5", (None, 0.0381)),
        ("ft", "2", (None, 0.0508)),
        ("ft", "20", ("20 in is thicker than any pipe insulation (at most 19.685 in)", None)),
        ("m", "nan", ("must be a number >= 0 in mm, not 'nan'", None)),
        ("m", "-0", (None, 0.0)),
    ],
)
def test_the_typed_thickness_is_in_mm_or_in_inches_for_an_imperial_scan(units, text, expected):
    from asbuilt.cli.scan import _thickness_unit, _typed_thickness

    problem, metres = _typed_thickness(text, _thickness_unit(units))
    assert problem == expected[0]
    assert metres == (pytest.approx(expected[1]) if expected[1] is not None else None)


def test_ctrl_c_stops_cleanly_and_resume_finishes(site, monkeypatch, capsys):
    from asbuilt.drivers import session as session_module

    plan = ["--plan", str(site / "plan.json")]
    assert main(_args(site, "ref", out="ref.json", extra_ptu=EXACT, more=plan)) == 0

    real_call = session_module.DeviceShooter.__call__
    count = {"n": 0}

    def interrupted(self, pan, tilt, phase):
        count["n"] += 1
        if count["n"] > 50:
            raise KeyboardInterrupt
        return real_call(self, pan, tilt, phase)

    monkeypatch.setattr(session_module.DeviceShooter, "__call__", interrupted)
    assert main(_args(site, "c1", extra_ptu=EXACT, more=plan)) == 130
    assert "--resume" in capsys.readouterr().err
    journal = (site / "scan.json.journal").read_text().splitlines()
    assert sum('"type":"shot"' in line for line in journal) == 50
    monkeypatch.setattr(session_module.DeviceShooter, "__call__", real_call)
    assert main(_args(site, "c2", extra_ptu=EXACT, more=[*plan, "--resume"])) == 0
    done = json.loads((site / "scan.json").read_text())["objects"]
    assert done == json.loads((site / "ref.json").read_text())["objects"]


def test_unplugged_cable_is_one_line_and_resumable(site, capsys):
    plan = ["--plan", str(site / "plan.json")]
    code = main(_args(site, "u1", extra_lrf="?unplug_after=30", more=plan))
    err = capsys.readouterr().err
    assert code == 2
    last = err.strip().splitlines()[-1]  # after the progress lines
    assert last.startswith("asbuilt: error:") and "unplugged" in last and "--resume" in last
    assert "Traceback" not in err
    assert main(_args(site, "u2", more=[*plan, "--resume"])) == 0
    assert len(json.loads((site / "scan.json").read_text())["objects"]) == 2


def test_silent_unit_fails_within_the_timeout(site, capsys):
    start = time.monotonic()
    code = main(
        _args(
            site,
            "quiet",
            extra_ptu="&silent=1",
            more=["--plan", str(site / "plan.json"), "--timeout", "0.3"],
        )
    )
    assert code == 2
    assert time.monotonic() - start < 10  # generous: it must not hang
    assert "no reply to 'PR' within 0.3 s" in capsys.readouterr().err


@pytest.mark.parametrize(
    "more, message",
    [
        (["--plan", "missing-plan.json"], "cannot read the plan"),
        (["--units", "furlong"], "unknown unit"),
        (["--retries", "-1"], "--retries must be >= 0"),
    ],
)
def test_bad_input_is_one_line(site, capsys, more, message):
    assert main(_args(site, "bad", more=more)) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "plan, message",
    [
        (
            "other.json",
            "the journal's session ran another plan, plan.json (2 targets), not other.json (1 "
            "target); resume with the session's own --plan, or choose another --out for this one",
        ),
        (None, "the journal's session ran the plan plan.json (2 targets); resume with that --plan"),
    ],
)
def test_resume_with_another_plan_is_refused_before_the_devices_open(site, capsys, plan, message):
    """A resumed session took another plan's targets and appended them to its scan."""
    from asbuilt.drivers.plan import load_plan, plan_record
    from asbuilt.drivers.simrig import _RIGS

    (site / "other.json").write_text(json.dumps({**PLAN, "targets": PLAN["targets"][1:]}))
    record = {"type": "session", "version": 1, "units": "m", "settings": {}}
    record["plan"] = plan_record(load_plan(site / "plan.json"), "plan.json")
    journal = site / "scan.json.journal"
    journal.write_text(json.dumps(record) + "\n")
    before = journal.read_bytes()
    more = ["--plan", str(site / plan)] if plan else []
    assert main(_args(site, "rp", more=[*more, "--resume"])) == 2
    err = capsys.readouterr().err
    assert err == f"asbuilt: error: {journal}: {message}\n"
    assert journal.read_bytes() == before and not (site / "scan.json").exists()
    assert "rp" not in _RIGS  # refused before any device opened


def test_resume_of_an_older_journal_with_another_plan_is_refused(site, capsys):
    """A journal from before sessions recorded their plan: its begun targets must be the plan's."""
    (site / "other.json").write_text(json.dumps({**PLAN, "targets": PLAN["targets"][1:]}))
    target = {"id": "P1", "kind": "cylinder", "window_deg": [72, -6.5, 108, -1.5], "nominal": '12"'}
    lines = [{"type": "session", "version": 1, "units": "m"}, {"type": "object", "target": target}]
    (site / "scan.json.journal").write_text("".join(json.dumps(r) + "\n" for r in lines))
    more = ["--plan", str(site / "other.json"), "--resume"]
    assert main(_args(site, "ro", more=more)) == 2
    assert "scanned target 'P1', which other.json does not have" in capsys.readouterr().err


def test_existing_journal_needs_resume(site, capsys):
    (site / "scan.json.journal").write_text('{"type":"session","version":1}\n')
    assert main(_args(site, "j", more=["--plan", str(site / "plan.json")])) == 2
    assert "--resume" in capsys.readouterr().err


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")
def test_simulate_device_serves_ptys_that_asbuilt_scan_uses(site):
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "asbuilt",
            "simulate-device",
            "--scene",
            str(site / "scene.json"),
            "--range-sigma",
            "0.001",
        ],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        paths = dict(server.stdout.readline().split() for _ in range(2))
        assert set(paths) == {"ptu", "lrf"}
        scan = subprocess.run(
            [
                sys.executable,
                "-m",
                "asbuilt",
                "scan",
                "--ptu",
                paths["ptu"],
                "--lrf",
                paths["lrf"],
                "--lrf-8n1",
                "--calibration",
                str(site / "cal.json"),
                "--plan",
                str(site / "plan.json"),
                "--out",
                str(site / "tty.json"),
            ],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert scan.returncode == 0, scan.stderr
    finally:
        server.send_signal(signal.SIGINT)
        server.wait(timeout=10)
    assert server.returncode == 0
    doc = json.loads((site / "tty.json").read_text())
    pipe = np.array(doc["objects"][0]["points"])
    radius = np.linalg.norm(pipe[:, 1:] - [4.0, 1.2], axis=1)
    assert radius.mean() == pytest.approx(PIPE_OD / 2, abs=0.003)
    assert math.isfinite(radius.std())


def test_units_apply_to_points_and_raw_ranges(site):
    from asbuilt.scan import load_scan

    plan = ["--plan", str(site / "plan.json")]
    assert main(_args(site, "m", out="m.json", extra_ptu=EXACT, more=plan)) == 0
    assert (
        main(_args(site, "mm", out="mm.json", extra_ptu=EXACT, more=[*plan, "--units", "mm"])) == 0
    )
    in_m, in_mm = load_scan(site / "m.json"), load_scan(site / "mm.json")
    assert in_mm.units == "mm"
    for a, b in zip(in_m.objects, in_mm.objects):
        assert b.points == pytest.approx(a.points, abs=1e-9)
        assert b.measurements == pytest.approx(a.measurements, abs=1e-9)
    raw = json.loads((site / "mm.json").read_text())["objects"][0]["measurements"][0][2]
    assert 3000 < raw < 5000  # millimetres in the file


@pytest.mark.parametrize(
    "units, value, metres", [("m", 0.003, 0.003), ("mm", 3.0, 0.003), ("in", 0.1, 0.00254)]
)
def test_edge_tolerance_is_given_in_the_scan_units(units, value, metres):
    import argparse

    from asbuilt.cli.scan import _settings

    args = argparse.Namespace(
        retries=None,
        edge_pairs=None,
        edge_depth=12,
        edge_tolerance=value,
        keep_background=False,
        units=units,
    )
    settings = _settings(args, None)
    assert settings.edge_tolerance == pytest.approx(metres)
    assert settings.edge_depth == 12


@pytest.mark.parametrize("value", [0.0, -1.0, float("nan")])
def test_a_bad_edge_tolerance_is_one_clear_error(value):
    import argparse

    from asbuilt.cli.scan import _settings
    from asbuilt.errors import ScanError

    args = argparse.Namespace(
        retries=None,
        edge_pairs=None,
        edge_depth=None,
        edge_tolerance=value,
        keep_background=False,
        units="mm",
    )
    with pytest.raises(ScanError, match="--edge-tolerance must be a length > 0"):
        _settings(args, None)


P1_ANSWERS = ["P1", "cylinder", "72 -6.5 108 -1.5", '12"', ""]


def test_bad_typed_angles_are_re_prompted_in_the_operators_terms(site, monkeypatch, capsys):
    """Three numbers for a window, 'inf'/'nan' or one number while aiming: a plain line saying
    what to type and the prompt again, no Python exception text; the object is then scanned."""
    answers = [
        *("C1", "cuboid", "63.5 -8 73"),  # three numbers: asked again from the id
        *("C1", "cuboid", "63.5 -8 inf 10"),
        *("C1", "cuboid", "aim", "inf 0", "nan 0", "63.5", "63.5 -8", "ok", "73 10", "ok", ""),
        "",
    ]
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n".join(answers) + "\n"))
    assert main(_args(site, "badangles")) == 0
    err = capsys.readouterr().err
    assert err.count("give four numbers PAN1 TILT1 PAN2 TILT2 (degrees), or 'aim'") == 2
    assert err.count("give two numbers PAN TILT (degrees), or 'ok' to take this corner") == 3
    for python in ("from_corners", "positional argument", "convert float", "Traceback"):
        assert python not in err
    doc = json.loads((site / "scan.json").read_text())
    window = doc["objects"][0]["acquisition"]["window_deg"]
    assert window == pytest.approx([63.5, -8, 73, 10], abs=0.06)  # whole counts of 0.0514 deg


def test_a_plan_window_beyond_the_tilt_limit_is_reported_with_the_range(site, capsys):
    """The simulated unit tilts up to +31.063 deg: a window at 35-45 deg is out of reach, and the
    operator is told so (with the range), not to re-aim; the object in reach is scanned."""
    plan = {**PLAN, "targets": [PLAN["targets"][0], {"id": "high", "kind": "plane"}]}
    plan["targets"][1]["window_deg"] = [80, 35, 100, 45]
    (site / "high.plan.json").write_text(json.dumps(plan))
    assert main(_args(site, "high", more=["--plan", str(site / "high.plan.json")])) == 1
    err = " ".join(capsys.readouterr().err.split())  # rich wraps the line on a narrow terminal
    assert "high: not in the scan: " in err and "re-aim" not in err
    assert "beyond the pan-tilt unit's tilt range [-46.646, 31.063] deg" in err
    assert [o["id"] for o in json.loads((site / "scan.json").read_text())["objects"]] == ["P1"]


C1_ANSWERS = ["C1", "cuboid", "63.5 -8 73 10", ""]


def test_end_of_input_keeps_the_scan_and_says_how_to_resume(site, monkeypatch, capsys):
    """A piped script that ends after one object (no empty id): the object is in the scan file,
    the last line says so and how to go on, and --resume adds the next object to it."""
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n".join(P1_ANSWERS) + "\n"))
    assert main(_args(site, "eof1")) == 0
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.startswith("end of input: 1 finished object(s) saved in ")
    assert str(site / "scan.json.journal") in last and "asbuilt scan --resume" in last
    assert [o["id"] for o in json.loads((site / "scan.json").read_text())["objects"]] == ["P1"]
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n".join([*C1_ANSWERS, ""]) + "\n"))
    assert main(_args(site, "eof2", more=["--resume"])) == 0
    assert "end of input" not in capsys.readouterr().err  # ended by the empty id
    doc = json.loads((site / "scan.json").read_text())
    assert [o["id"] for o in doc["objects"]] == ["P1", "C1"]


def test_a_closed_stdin_is_the_end_of_input_not_a_traceback(site, monkeypatch, capsys):
    monkeypatch.setattr(sys, "stdin", None)  # started with 0<&-
    assert main(_args(site, "closed")) == 0
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert last.startswith("end of input: no finished object, so no ")
    assert not (site / "scan.json").exists()


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")
def test_a_hung_up_terminal_is_the_end_of_input(site, monkeypatch, capsys):
    """Reading a terminal whose other end closed fails with EIO (when SIGHUP is ignored, e.g.
    under nohup): that is the end of the input, not a traceback."""
    master, slave = os.openpty()
    with os.fdopen(slave, "r", encoding="utf-8") as terminal:
        os.close(master)  # the terminal window closes
        monkeypatch.setattr(sys, "stdin", terminal)
        assert main(_args(site, "hup")) == 0
    err = capsys.readouterr().err
    assert err.strip().splitlines()[-1].startswith("end of input: no finished object")
    assert "Traceback" not in err


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="needs SIGHUP")
def test_sighup_stops_cleanly_and_keeps_the_scan(site):
    """The operator's terminal closes (SIGHUP) at the next prompt: exit 130, the finished object
    in the scan file, one line saying so; --resume continues."""
    scan = subprocess.Popen(
        [sys.executable, "-m", "asbuilt", *_args(site, "sighup")],
        cwd=ROOT,
        stdin=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        scan.stdin.write("\n".join(P1_ANSWERS) + "\n")
        scan.stdin.flush()
        # wait (bounded) for the object to be written, then hang up at the next prompt
        deadline = time.monotonic() + 60
        while not (site / "scan.json").exists() and scan.poll() is None:
            assert time.monotonic() < deadline, "the scan never wrote its first object"
            time.sleep(0.05)
        scan.send_signal(signal.SIGHUP)
        _, err = scan.communicate(timeout=60)
    finally:
        scan.kill()
    assert scan.returncode == 130, err
    last = err.strip().splitlines()[-1]
    assert last.startswith("hang-up: 1 finished object(s) saved in ") and "--resume" in last
    assert "Traceback" not in err
    assert [o["id"] for o in json.loads((site / "scan.json").read_text())["objects"]] == ["P1"]


def _object_begun_again(site):
    # an edited journal begins P1 again after its 'done' (its torn last line stays last)
    journal = site / "scan.json.journal"
    data = journal.read_bytes()
    torn = data.rindex(b"\n") + 1
    target = json.dumps({"id": "P1", "kind": "cylinder", "window_deg": [72, -6.5, 108, -1.5]})
    journal.write_bytes(
        data[:torn] + b'{"type":"object","target":' + target.encode() + b"}\n" + data[torn:]
    )
    return "begun again after it was finished; the journal was edited, cannot resume"


def _out_made_a_directory(site):
    (site / "scan.json").unlink()
    (site / "scan.json").mkdir()
    return "is a directory"


@pytest.mark.parametrize(
    "edit", [_object_begun_again, _out_made_a_directory], ids=["object-again", "out-dir"]
)
def test_a_refused_resume_is_one_line_and_leaves_the_journal_byte_for_byte(site, capsys, edit):
    plan = ["--plan", str(site / "plan.json")]
    assert main(_args(site, "r1", extra_lrf="?unplug_after=70", more=plan)) == 2
    with open(site / "scan.json.journal", "ab") as f:
        f.write(b'{"type":"shot","object":"C1","seq":40,"req":[1.1')  # the crash hit mid-write
    message = edit(site)
    capsys.readouterr()
    before = (site / "scan.json.journal").read_bytes()
    listing = sorted(p.name for p in site.iterdir())
    assert main(_args(site, "r2", more=[*plan, "--resume"])) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert (site / "scan.json.journal").read_bytes() == before
    assert sorted(p.name for p in site.iterdir()) == listing
