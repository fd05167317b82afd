"""``asbuilt scan`` device options over real pseudo-terminals: the Dimetix id, reply timeouts,
wrong line settings found before the head moves; ``simulate-device``'s id range."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading

import pytest
from asbuilt.drivers.pty_sim import PtyServer
from asbuilt.drivers.simrig import SimulatedRig, load_world, station_defaults

from asbuilt.cli import main

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")


def _server(site, device_id):
    world = load_world(site / "scene.json")
    calibration, noise = station_defaults(world, None)
    return PtyServer(SimulatedRig(world, calibration), "dimetix", device_id)


def _scan(site, ptu, lrf, *more):
    return main(
        [
            "scan",
            "--ptu",
            ptu,
            "--lrf",
            lrf,
            "--plan",
            str(site / "plan.json"),
            "--out",
            str(site / "scan.json"),
            "--timeout",
            "0.5",
            *more,
        ]
    )


def test_a_dimetix_with_another_id_is_reached_with_lrf_id(site, capsys):
    with _server(site, 3) as server:
        assert _scan(site, server.ptu_path, server.lrf_path, "--lrf-id", "3") == 0
    assert json.loads((site / "scan.json").read_text())["objects"][0]["id"] == "W1"


def test_a_wrong_id_is_one_line_naming_it_before_the_head_moves(site, capsys):
    with _server(site, 3) as server:
        assert _scan(site, server.ptu_path, server.lrf_path) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("asbuilt: error:") and "device id 0" in err[-1]
    assert not (site / "scan.json.journal").exists()  # no shot was taken


def _as_7e1(data: bytes) -> bytes:
    """What an 8N1 host receives from a 7E1 device: the even parity bit as bit 7."""
    return bytes(b | (0x80 if bin(b).count("1") % 2 else 0) for b in data)


def test_a_7e1_sensor_opened_8n1_is_one_line_before_the_head_moves(site, capsys):
    master, slave = os.openpty()
    stop = threading.Event()

    def serve():  # a Dimetix (protocols.md: 7E1): every command line answered 'g0?'
        while not stop.is_set():
            try:
                data = os.read(master, 1024)
            except OSError:
                return
            if b"\n" in data:
                os.write(master, _as_7e1(b"g0?\r\n"))

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        code = _scan(
            site,
            f"sim-ptu://r7?scene={site / 'scene.json'}",
            os.ttyname(slave),
            "--lrf-8n1",
        )
    finally:
        stop.set()
        os.close(slave)
        os.close(master)
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("asbuilt: error:") and "line settings" in err[-1]
    assert not (site / "scan.json.journal").exists()


@pytest.mark.parametrize(
    "more, message",
    [
        (["--timeout", "nan"], "--timeout must be a number of seconds > 0"),
        (["--timeout", "0"], "--timeout must be a number of seconds > 0"),
        (["--move-timeout", "nan"], "--move-timeout must be a number of seconds > 0"),
        (["--move-timeout", "inf"], "--move-timeout must be a number of seconds > 0"),
        (["--lrf-id", "12"], "--lrf-id must be a Dimetix device id 0-9"),
        (["--lrf-id", "1", "--lrf-protocol", "ldm"], "the LDM has none"),
    ],
)
def test_bad_device_options_are_one_line(site, capsys, more, message):
    # checked before anything is opened or read (the plan here does not even exist)
    args = ["scan", "--ptu", "sim-ptu://x", "--lrf", "sim-lrf://x", "--out", "o.json"]
    assert main([*args, "--plan", str(site / "missing.json"), *more]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_simulate_device_refuses_an_id_outside_0_to_9(site):
    # in a child process: a simulator that accepted the id would serve until killed
    args = ["simulate-device", "--scene", str(site / "scene.json"), "--device-id", "12"]
    run = subprocess.run(
        [sys.executable, "-m", "asbuilt", *args], capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 2 and run.stdout == ""
    assert "--device-id must be a Dimetix device id 0-9" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_resume_reopens_the_simulators_7e1_tty(site, monkeypatch, capsys):
    """Interrupted, then ``--resume`` against the same simulator, 7E1 as a factory Dimetix (no
    --lrf-8n1): the second open of the pty failed with EINVAL ("check the cable")."""
    from asbuilt.drivers import session as session_module

    real_call = session_module.DeviceShooter.__call__
    count = {"n": 0}

    def interrupted(self, pan, tilt, phase):
        count["n"] += 1
        if count["n"] > 10:
            raise KeyboardInterrupt
        return real_call(self, pan, tilt, phase)

    with _server(site, 0) as server:
        monkeypatch.setattr(session_module.DeviceShooter, "__call__", interrupted)
        assert _scan(site, server.ptu_path, server.lrf_path) == 130
        monkeypatch.setattr(session_module.DeviceShooter, "__call__", real_call)
        for _ in range(2):  # a second resume (nothing left to shoot) opens it a third time
            code = _scan(site, server.ptu_path, server.lrf_path, "--resume")
            assert code == 0, capsys.readouterr().err
            assert json.loads((site / "scan.json").read_text())["objects"][0]["id"] == "W1"
        assert server.error is None
