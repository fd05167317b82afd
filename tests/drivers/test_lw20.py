"""LightWare LW20 / SF20 driver: reply parsing against scripted replies, serial mode selection,
no target, timeouts; over a pseudo-terminal against the simulator; a scan session with it."""

from __future__ import annotations

import json
import math
import os

import pytest
from asbuilt.drivers.lw20 import LW20, parse_distance
from asbuilt.drivers.rangefinder import RANGE_FINDER_PROTOCOLS, SignalTooWeak, open_range_finder
from driver_helpers import wall_rig

from asbuilt.errors import DeviceProtocolError, DeviceTimeout

LINE = b"\r\n"


def _lw20(scripted, script, timeout=0.3):
    channel, port = scripted([("www", b""), *script], timeout=timeout, delimiters=LINE)
    lrf = LW20(channel)
    lrf.select_serial_mode()
    return lrf, port


@pytest.mark.parametrize(
    "reply, metres",
    [
        (b"4.99\r\n", 4.99),
        (b"  12.34  \r\n", 12.34),
        (b"ld:4.99\r\n", 4.99),
        (b"LD 4.99\r\n", 4.99),
        (b"ldf,0:23.45\r\n", 23.45),
        (b"4.99 m\r\n", 4.99),
        (b"4.99m\r\n", 4.99),
        (b"+0.25\r\n", 0.25),
        (b"100\r\n", 100.0),
    ],
)
def test_distances_with_whitespace_label_or_unit(scripted, reply, metres):
    lrf, port = _lw20(scripted, [("LD", reply)])
    assert lrf.measure() == pytest.approx(metres)
    assert port.written == ["www", "LD"]


@pytest.mark.parametrize(
    "reply",
    [
        b"-1.00\r\n",
        b"0.00\r\n",
        b"ld:-1.00\r\n",
        b"0\r\n",
        # the reference does not say how the LW20 reports no return: the text forms are misses
        b"no target\r\n",
        b"No Target\r\n",
        b"NO-TARGET\r\n",
        b"notarget\r\n",
        b"--.--\r\n",
        b"-.--\r\n",
        b"----\r\n",
        b"ld:--.--\r\n",
        b"LD: --.-- m\r\n",
    ],
)
def test_zero_negative_or_said_in_text_is_no_target(scripted, reply):
    lrf, _ = _lw20(scripted, [("LD", reply)])
    with pytest.raises(SignalTooWeak, match="no target") as info:
        lrf.measure()
    assert info.value.code == "no-target"


@pytest.mark.parametrize(
    "reply",
    [
        b"-\r\n",
        b"no\r\n",
        b"target\r\n",
        b"no target 4.99\r\n",
        b"--.-- --.--\r\n",
        b"abc\r\n",
        b"4.9.9\r\n",
        b"1.00 2.00\r\n",
        b"nan\r\n",
        b"inf\r\n",
        b"4.99 km\r\n",
        b"ld:\r\n",
    ],
)
def test_anything_else_is_a_protocol_error(scripted, reply):
    lrf, _ = _lw20(scripted, [("LD", reply)])
    with pytest.raises(DeviceProtocolError, match="check the baud rate"):
        lrf.measure()


def test_an_echo_of_the_command_is_skipped(scripted):
    lrf, _ = _lw20(scripted, [("LD", [b"LD\r\n", b"3.2", b"1\r\n"])])
    assert lrf.measure() == pytest.approx(3.21)


def test_a_timeout_then_the_late_answer_is_dropped(scripted):
    # the first LD gets no answer in time; its late answer (1.11) must not become the next shot
    lrf, port = _lw20(scripted, [("LD", b""), ("LD", b"2.22\r\n")])
    with pytest.raises(DeviceTimeout, match="distance reply to LD"):
        lrf.measure(timeout=0.05)
    port._rx.extend(b"1.11\r\n")  # arrives late, before the next command
    assert lrf.measure() == pytest.approx(2.22)


def test_parse_distance_alone():
    assert parse_distance(" 7.5 ") == 7.5
    with pytest.raises(DeviceProtocolError):
        parse_distance("")


def test_registered_as_lw20():
    assert "lw20" in RANGE_FINDER_PROTOCOLS


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")
def test_over_a_pseudo_terminal_against_the_simulator():
    from asbuilt.drivers.ptu import PanTiltUnit
    from asbuilt.drivers.pty_sim import PtyServer

    with PtyServer(wall_rig(4.0), "lw20") as server:
        with PanTiltUnit.open(server.ptu_path, timeout=2.0) as ptu:
            with open_range_finder(server.lrf_path, "lw20", timeout=2.0) as lrf:
                assert isinstance(lrf, LW20)
                for pan_deg in (0, 15, -25):
                    pan, tilt = ptu.move_to(math.radians(pan_deg), math.radians(3))
                    expected = 4.0 / (math.cos(pan) * math.cos(tilt))
                    assert lrf.measure() == pytest.approx(expected, abs=0.006)  # centimetres
                ptu.move_to(math.radians(150), 0.0)  # facing away from the wall
                with pytest.raises(SignalTooWeak):
                    lrf.measure()
        assert server.error is None


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")
@pytest.mark.parametrize("no_target", ["no target", "--.--"])
def test_an_lw20_saying_no_target_in_text_misses_from_the_probe_on(no_target):
    from asbuilt.drivers.pty_sim import PtyServer

    rig = wall_rig(4.0)
    rig.move(pan_counts=150 * 3600 / rig.resolution[0])  # facing away from the wall
    with PtyServer(rig, "lw20", lrf_options={"no_target": no_target}) as server:
        with LW20.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()  # its LD is answered "no target": an answer all the same
            with pytest.raises(SignalTooWeak):
                lrf.measure()
            rig.move(pan_counts=0)
            assert lrf.measure() == pytest.approx(4.0, abs=0.006)
        assert server.error is None


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")
def test_without_www_the_simulator_stays_silent():
    from asbuilt.drivers.pty_sim import PtyServer

    with PtyServer(wall_rig(4.0), "lw20") as server:
        with LW20.open(server.lrf_path, timeout=0.3, select=False) as lrf:
            with pytest.raises(DeviceTimeout, match="LW20 range finder"):
                lrf.measure()


def test_a_scan_session_with_the_simulated_lw20(scene_file, tmp_path):
    from asbuilt.drivers.kinematics import Calibration
    from asbuilt.drivers.plan import Target, Window
    from asbuilt.drivers.ptu import PanTiltUnit
    from asbuilt.drivers.session import DeviceShooter, ScanSession

    station = Calibration(base_position=(0.0, 0.0, 1.5))
    pipe = Target("P1", "cylinder", Window.from_degrees([72, -6.5, 108, -1.5]))
    column = Target("C1", "cuboid", Window.from_degrees([63.5, -8, 73, 10]))
    sky = Target("X", "cylinder", Window.from_degrees([-100, 10, -90, 20]))  # nothing there
    out = tmp_path / "scan.json"
    with PanTiltUnit.open(f"sim-ptu://lw?scene={scene_file}&range_sigma=0", timeout=1.0) as ptu:
        with open_range_finder("sim-lrf://lw?protocol=lw20", "lw20", timeout=0.5) as lrf:
            with ScanSession(DeviceShooter(ptu, lrf), station, out) as session:
                for target in (pipe, column, sky):
                    session.scan(target)
    doc = json.loads(out.read_text())
    assert [o["id"] for o in doc["objects"]] == ["P1", "C1"]
    assert all(len(o["points"]) >= 20 for o in doc["objects"])
    assert "re-aim" in session.failed["X"]
    journal = [
        json.loads(line) for line in (tmp_path / "scan.json.journal").read_text().splitlines()
    ]
    errors = {r["error"] for r in journal if r["type"] == "shot" and r["object"] == "X"}
    assert errors == {"no-target"}  # misses, journaled with the driver's code


def _answering_www(banner_delay: float, reply_delay: float):
    """An LW20 on a pseudo-terminal that answers ``www`` with a line of its own after
    ``banner_delay`` (the reference gives no answer; an independent device may send one) and
    ``LD`` with 4.99 after ``reply_delay``."""
    from pty_fakes import PtyFake

    def respond(fake, command):
        if command == "www":
            fake.reply(b"LW20 ready, serial mode\r\n", banner_delay)
        elif command == "LD":
            fake.reply(b"4.99\r\n", reply_delay)

    return PtyFake(respond)


@pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")
@pytest.mark.parametrize(
    "banner_delay, reply_delay",
    [
        (0.02, 0.05),  # the answer to www comes after the input was cleared for the first LD
        (0.25, 0.3),  # ... after the settling time too: the probe's first reply, measured again
    ],
)
def test_an_answer_to_www_is_not_taken_for_a_distance(banner_delay, reply_delay):
    with _answering_www(banner_delay, reply_delay) as fake:
        with LW20.open(fake.path, timeout=2.0) as lrf:
            lrf.probe()  # before: "unexpected reply 'LW20 ready, serial mode' to LD"
            assert lrf.measure() == pytest.approx(4.99)
        assert fake.commands[0] == "www"
