"""``asbuilt scan --ptu-protocol pelco-d --lrf-protocol lw20`` and ``simulate-device`` with the
Pelco-D head and the LW20 simulators, over real pseudo-terminals; bad options and device errors
are one line with exit status 2."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from asbuilt.drivers.pty_sim import PtyServer
from asbuilt.drivers.simrig import SimulatedRig, load_world, station_defaults

from asbuilt.cli import main

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")

ROOT = Path(__file__).resolve().parents[2]


def _server(site, address=1, **ptu_options):
    world = load_world(site / "scene.json")
    calibration, _ = station_defaults(world, None)
    rig = SimulatedRig(world, calibration, speed=20000.0)  # moves take a moment: polled
    return PtyServer(
        rig, "lw20", ptu_protocol="pelco-d", ptu_address=address, ptu_options=ptu_options
    )


def _scan(site, ptu, lrf, *more):
    return main(
        [
            "scan",
            "--ptu-protocol",
            "pelco-d",
            "--lrf-protocol",
            "lw20",
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


def test_a_scan_with_a_pelco_head_and_an_lw20(site, capsys):
    with _server(site, address=5) as server:
        assert _scan(site, server.ptu_path, server.lrf_path, "--ptu-address", "5") == 0
        assert server.error is None
    doc = json.loads((site / "scan.json").read_text())
    wall = doc["objects"][0]
    assert wall["id"] == "W1" and len(wall["points"]) >= 9
    assert all(abs(y - 6.0 + 0.1) < 0.01 for _, y, _ in wall["points"])  # the wall's near face


def test_a_scan_with_a_head_whose_tilt_is_signed_16_bit(site, capsys):
    # tilts below zero go on the wire as two's complement (FC 18 for -10 deg)
    with _server(site, tilt_encoding="signed") as server:
        more = ("--ptu-tilt-encoding", "signed")
        assert _scan(site, server.ptu_path, server.lrf_path, *more) == 0
        assert server.error is None
    wall = json.loads((site / "scan.json").read_text())["objects"][0]
    assert len(wall["points"]) >= 9
    assert min(z for _, _, z in wall["points"]) < 0  # shots below the horizon reached
    assert all(abs(y - 6.0 + 0.1) < 0.01 for _, y, _ in wall["points"])


def test_a_head_at_another_address_is_one_line_before_anything_is_shot(site, capsys):
    with _server(site, address=5) as server:
        assert _scan(site, server.ptu_path, server.lrf_path) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("asbuilt: error: Pelco-D head on") and "address 1" in err[-1]
    assert "Traceback" not in "\n".join(err)
    assert not (site / "scan.json.journal").exists()


def test_an_lw20_answering_garbage_is_one_line_before_the_head_moves(site, capsys):
    master, slave = os.openpty()
    stop = threading.Event()

    def serve():  # not an LW20 (or the wrong baud rate): every line answered with noise
        while not stop.is_set():
            try:
                data = os.read(master, 1024)
            except OSError:
                return
            if b"LD" in data:
                os.write(master, b"#?x\r\n")

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        with _server(site) as server:
            code = _scan(site, server.ptu_path, os.ttyname(slave))
    finally:
        stop.set()
        os.close(slave)
        os.close(master)
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("asbuilt: error: LW20 range finder") and "baud rate" in err[-1]
    assert not (site / "scan.json.journal").exists()


@pytest.mark.parametrize(
    "more, message",
    [
        (["--ptu-address", "3"], "--ptu-address is a Pelco-D option"),
        (["--ptu-tilt-sign", "1"], "--ptu-tilt-sign is a Pelco-D option"),
        (["--ptu-tilt-encoding", "signed"], "--ptu-tilt-encoding is a Pelco-D option"),
        (["--ptu-protocol", "pelco-d", "--ptu-address", "0"], "Pelco-D address 1-255, not 0"),
        (["--ptu-protocol", "pelco-d", "--ptu-address", "256"], "Pelco-D address 1-255"),
        (["--ptu-protocol", "pelco-d", "--ptu-tilt-zero", "nan"], "--ptu-tilt-zero must be"),
        (["--lrf-protocol", "lw20", "--lrf-id", "1"], "the LW20 has none"),
    ],
)
def test_bad_head_options_are_one_line(site, capsys, more, message):
    args = ["scan", "--ptu", "sim-ptu://x", "--lrf", "sim-lrf://x", "--out", "o.json"]
    assert main([*args, "--plan", str(site / "missing.json"), *more]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1


def test_simulate_device_serves_a_pelco_head_and_an_lw20_that_scan_uses(site):
    server = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "asbuilt",
            "simulate-device",
            "--scene",
            str(site / "scene.json"),
            "--ptu-protocol",
            "pelco-d",
            "--ptu-address",
            "9",
            "--lrf-protocol",
            "lw20",
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
                "--ptu-protocol",
                "pelco-d",
                "--ptu-address",
                "9",
                "--ptu",
                paths["ptu"],
                "--lrf-protocol",
                "lw20",
                "--lrf",
                paths["lrf"],
                "--plan",
                str(site / "plan.json"),
                "--out",
                str(site / "tty.json"),
            ],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert scan.returncode == 0, scan.stderr
    finally:
        server.send_signal(signal.SIGINT)
        server.wait(timeout=10)
    assert server.returncode == 0
    assert json.loads((site / "tty.json").read_text())["objects"][0]["id"] == "W1"


def test_simulate_device_refuses_an_address_outside_1_to_255(site):
    args = ["simulate-device", "--scene", str(site / "scene.json"), "--ptu-address", "0"]
    run = subprocess.run(
        [sys.executable, "-m", "asbuilt", *args, "--ptu-protocol", "pelco-d"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2 and run.stdout == ""
    assert "--ptu-address must be a Pelco-D address 1-255" in run.stderr
    assert len(run.stderr.strip().splitlines()) == 1
