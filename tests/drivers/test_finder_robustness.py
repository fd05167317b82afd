"""Range finders and a pan-tilt unit that behave as the manuals allow but our defaults did not
expect, over real pseudo-terminals (the simulators' options, drivers/sim_lrf.py, sim_ptu.py):
an LDM that ends commands at CR and keeps the LF, unpadded format h, a device refusing every
measurement, 7E1 bytes on an 8N1 pty, a power-up banner mid-session, slow measurements."""

from __future__ import annotations

import math
import os

import pytest
from asbuilt.drivers.dimetix import DimetixDLS
from asbuilt.drivers.journal import journal_path_for, read_journal
from asbuilt.drivers.kinematics import Calibration
from asbuilt.drivers.ldm import LDM4x
from asbuilt.drivers.plan import SessionSettings, Target, Window
from asbuilt.drivers.ptu import PanTiltUnit
from asbuilt.drivers.pty_sim import PtyServer
from asbuilt.drivers.rangefinder import (
    RangeFinderCommandError,
    RangeFinderError,
    SignalTooWeak,
    TemperatureError,
)
from asbuilt.drivers.session import DeviceShooter, ScanSession
from driver_helpers import wall_rig

from asbuilt.errors import DeviceTimeout

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")

WALL = Target("W1", "plane", Window.from_degrees([-8, -4, 8, 4]))
STATION = Calibration()


def _lrf_sim(server: PtyServer):
    return server._endpoints[1].device


# -- 1. LDM command ending ----------------------------------------------------------------------
@pytest.mark.parametrize("unknown_reply", ["E12", None])
def test_an_ldm_that_keeps_the_lf_for_the_next_command_gets_cr_alone(unknown_reply):
    # CR ends a command, the LF of CR LF starts the next one ("\nDM"), which the meter refuses
    # (an error code, or silence): the probe's second DM finds it and switches to CR.
    options = {"command_end": "cr-keep-lf", "unknown_reply": unknown_reply}
    with PtyServer(wall_rig(4.0), "ldm", lrf_options=options) as server:
        with LDM4x.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()
            assert lrf.eol == "\r"
            assert [lrf.measure() for _ in range(4)] == pytest.approx([4.0] * 4, abs=1e-3)
        assert server.error is None


@pytest.mark.parametrize("unknown_reply", ["E12", None])
@pytest.mark.parametrize("output_format", ["d", "h"])
def test_an_ldm_that_keeps_the_cr_in_the_command_gets_lf_alone(unknown_reply, output_format):
    # LF ends a command and the CR of CR LF stays in it ("DM\r"), which the meter refuses (an
    # error code, or silence) from the first DM on: the probe tries LF alone and keeps it
    options = {
        "command_end": "lf-keep-cr",
        "unknown_reply": unknown_reply,
        "output_format": output_format,
    }
    with PtyServer(wall_rig(4.0), "ldm", lrf_options=options) as server:
        with LDM4x.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()
            assert lrf.eol == "\n"
            assert _lrf_sim(server).format == "d"  # SDd LF understood
            assert [lrf.measure() for _ in range(3)] == pytest.approx([4.0] * 3, abs=1e-3)
        assert server.error is None


def test_an_ldm_that_keeps_the_cr_and_misses_still_gets_lf_alone():
    rig = wall_rig(4.0)
    rig.move(pan_counts=150 * 3600 / rig.resolution[0])  # facing away from the wall: E15
    options = {"command_end": "lf-keep-cr", "unknown_reply": "E12"}
    with PtyServer(rig, "ldm", lrf_options=options) as server:
        with LDM4x.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()
            assert lrf.eol == "\n"
            with pytest.raises(SignalTooWeak):
                lrf.measure()


@pytest.mark.parametrize(
    "command_end, eol", [("any", "\r\n"), ("cr-keep-lf", "\r"), ("lf-keep-cr", "\n")]
)
def test_a_dimetix_gets_the_line_ending_it_takes(command_end, eol):
    # "cr-keep-lf": the probe's first stop is answered, the second ("\ns0c") is not;
    # "lf-keep-cr": not even the first ("s0c\r"); each is found and kept
    with PtyServer(wall_rig(4.0), "dimetix", lrf_options={"command_end": command_end}) as server:
        with DimetixDLS.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()
            assert lrf.eol == eol
            assert [lrf.measure() for _ in range(3)] == pytest.approx([4.0] * 3, abs=1e-3)
            lrf.laser(True)
            assert _lrf_sim(server).laser
        assert server.error is None


def test_a_silent_dimetix_is_still_a_timeout_with_cr_lf_kept():
    master, slave = os.openpty()
    try:
        with DimetixDLS.open(os.ttyname(slave), timeout=0.3) as lrf:
            with pytest.raises(DeviceTimeout, match="stop acknowledgement"):
                lrf.probe()
            assert lrf.eol == "\r\n"
    finally:
        os.close(slave)
        os.close(master)


def test_an_ldm_ending_commands_anywhere_keeps_cr_lf():
    with PtyServer(wall_rig(4.0), "ldm") as server:
        with LDM4x.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()
            assert lrf.eol == "\r\n"
            assert lrf.measure() == pytest.approx(4.0, abs=1e-3)


def test_a_scan_of_an_ldm_that_keeps_the_lf_has_its_points(tmp_path):
    options = {"command_end": "cr-keep-lf", "unknown_reply": "E12"}
    with PtyServer(wall_rig(4.0), "ldm", lrf_options=options) as server:
        with (
            PanTiltUnit.open(server.ptu_path, timeout=2.0) as ptu,
            LDM4x.open(server.lrf_path, timeout=1.0) as lrf,
        ):
            lrf.probe()
            with ScanSession(DeviceShooter(ptu, lrf), STATION, tmp_path / "s.json") as session:
                result = session.scan(WALL)
    assert result is not None
    assert all(s.range is not None for s in result.shots)


# -- 2. LDM format h ----------------------------------------------------------------------------
@pytest.mark.parametrize("metres", [3.6, 0.233 * 16])  # E10, E9 + "0": 0xE10, 0xE90
def test_unpadded_hex_that_looks_like_an_error_is_resolved_by_setting_format_d(metres):
    options = {"output_format": "h", "hex_digits": 0}
    with PtyServer(wall_rig(metres), "ldm", lrf_options=options) as server:
        with LDM4x.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()  # the reply E10 / E90 is not decimal: SDd
            assert _lrf_sim(server).format == "d"
            assert lrf.measure() == pytest.approx(metres, abs=1e-3)


def test_a_decimal_ldm_is_left_at_its_format():
    with PtyServer(wall_rig(4.0), "ldm", lrf_options={"output_format": "s"}) as server:
        with LDM4x.open(server.lrf_path, timeout=1.0) as lrf:
            lrf.probe()
            assert lrf.measure() == pytest.approx(4.0, abs=1e-3)
            assert lrf.last_quality == 1000
        assert _lrf_sim(server).format == "s"


@pytest.mark.parametrize(
    "reply, metres", [(b"E9\r\n", 0.233), (b"E99\r\n", None), (b"E100\r\n", 57.6)]
)
def test_only_e_and_two_digits_is_an_error(scripted, reply, metres):
    channel, _ = scripted([("DM", reply)], timeout=0.3, delimiters=b"\r\n")
    lrf = LDM4x(channel)
    if metres is None:
        with pytest.raises(RangeFinderError):
            lrf.measure()
    else:
        assert lrf.measure() == pytest.approx(metres)


# -- 3. a range finder that needs attention ends the session -----------------------------------
@pytest.mark.parametrize(
    "exc, lost",
    [
        (SignalTooWeak("E255", code="E255"), False),
        (RangeFinderCommandError("E203 wrong command or parameter", code="E203"), True),
        (TemperatureError("E252 temperature too high", code="E252"), True),
        (RangeFinderError("E16 device error", code="E16"), True),
    ],
)
def test_only_misses_are_not_counted_as_lost(exc, lost):
    class Head:
        def move_to(self, pan, tilt):
            return pan, tilt

    class Finder:
        def measure(self):
            raise exc

    shooter = DeviceShooter(Head(), Finder(), SessionSettings(retries=1, lost_after=2))
    assert shooter(0.0, 0.0, "raster").error == exc.code
    if lost:
        with pytest.raises(type(exc), match=f"{exc.code}.*2 shots in a row") as info:
            shooter(0.0, 0.0, "raster")
        assert info.value.code == exc.code
    else:
        assert shooter(0.0, 0.0, "raster").error == exc.code


def test_a_dimetix_refusing_every_command_stops_the_session_and_keeps_the_shots(tmp_path):
    out = tmp_path / "s.json"
    with PtyServer(wall_rig(4.0), "dimetix") as server:
        finder = _lrf_sim(server)

        def refuse_after_five(target, shot, taken, planned):
            if taken == 5:
                finder.refuse = 203

        with (
            PanTiltUnit.open(server.ptu_path, timeout=2.0) as ptu,
            DimetixDLS.open(server.lrf_path, timeout=1.0) as lrf,
        ):
            settings = SessionSettings(retries=1, lost_after=3)
            with ScanSession(
                DeviceShooter(ptu, lrf, settings),
                STATION,
                out,
                settings=settings,
                on_shot=refuse_after_five,
            ) as session:
                with pytest.raises(RangeFinderCommandError, match="E203 wrong command"):
                    session.scan(WALL)
    shots = [r for r in read_journal(journal_path_for(out)) if r["type"] == "shot"]
    assert [r["range"] is not None for r in shots] == [True] * 5 + [False] * 2
    assert [r["error"] for r in shots[5:]] == ["E203", "E203"]


# -- 4. 7E1 bytes on a pty ----------------------------------------------------------------------
def test_a_7e1_dimetix_on_a_pty_is_read_with_bit_7_cleared():
    with PtyServer(wall_rig(4.0), "dimetix", lrf_options={"parity_bit7": True}) as server:
        with DimetixDLS.open(server.lrf_path, timeout=1.0) as lrf:  # 7E1 asked, 8N1 on a pty
            lrf.probe()
            assert lrf.measure() == pytest.approx(4.0, abs=1e-3)


# -- 5. PTU text that is no reply ---------------------------------------------------------------
@pytest.mark.parametrize("after", [0, 8, 15])
def test_a_ptu_banner_is_skipped_and_journalled(tmp_path, after):
    banner = "Pan-Tilt Controller v2.14.0, (C)1988-2005 Directed Perception, Inc."
    options = {"banner": banner, "banner_after": after}
    out = tmp_path / "s.json"
    with PtyServer(wall_rig(4.0), "dimetix", ptu_options=options) as server:
        with (
            PanTiltUnit.open(server.ptu_path, timeout=2.0) as ptu,
            DimetixDLS.open(server.lrf_path, timeout=1.0) as lrf,
        ):
            with ScanSession(DeviceShooter(ptu, lrf), STATION, out) as session:
                assert session.scan(WALL) is not None
            skipped = list(ptu.unsolicited)
    notes = [r for r in read_journal(journal_path_for(out)) if r["type"] == "note"]
    noted = [n["unsolicited"] for n in notes]
    assert skipped == []  # each handed to the journal
    if after == 0:  # at power-up: cleared with the stale input at opening, or read and noted
        assert noted in ([], [[banner]])
    else:
        assert noted == [[banner]]


# -- measuring time -----------------------------------------------------------------------------
@pytest.mark.parametrize("protocol, seconds", [("ldm", 1.0), ("dimetix", 1.5), ("dimetix", 2.5)])
def test_a_finder_taking_seconds_per_measurement(protocol, seconds):
    with PtyServer(wall_rig(4.0), protocol, lrf_options={"measure_time": seconds}) as server:
        if protocol == "ldm":
            lrf = LDM4x.open(server.lrf_path, timeout=3.0)
        else:
            lrf = DimetixDLS.open(server.lrf_path, timeout=3.0)
        with lrf, PanTiltUnit.open(server.ptu_path, timeout=2.0) as ptu:
            lrf.probe()
            for pan_deg in (0, 10):
                pan, tilt = ptu.move_to(math.radians(pan_deg), 0.0)
                assert lrf.measure() == pytest.approx(4.0 / math.cos(pan), abs=1e-3)
        assert server.error is None


# -- 6. a unit that acknowledges a position command when the move ends --------------------------
def test_a_long_move_acknowledged_at_its_end_waits_for_the_travel_time():
    rig = wall_rig(4.0)
    rig.speed = 1000.0  # positions/s: 60 deg of pan (1167 counts) take over a second
    with PtyServer(rig, "dimetix", ptu_options={"ack_at_end": True}) as server:
        with PanTiltUnit.open(server.ptu_path, timeout=0.5, move_timeout=10.0) as ptu:
            assert ptu.speeds == (1000.0, 1000.0)
            for pan_deg in (30, -30, 0):
                pan, _ = ptu.move_to(math.radians(pan_deg), 0.0)
                assert ptu.position() == pytest.approx((pan, 0.0), abs=1e-3)
        assert server.error is None


# -- Pelco-D tilt encoding ----------------------------------------------------------------------
def test_a_signed_tilt_seen_by_the_pelco_driver_is_journalled_as_a_note(tmp_path):
    # the head reports tilts below zero in signed 16-bit, which the default "wrap" driver reads
    # and notes; the session hands the note to the journal
    from asbuilt.drivers.pelco import PelcoD

    out = tmp_path / "s.json"
    rig = wall_rig(4.0)
    rig.move(tilt_counts=5 * 3600 / rig.resolution[1])  # left tilted up: raw -500 (FE 0C)
    options = {"tilt_encoding": "signed"}
    with PtyServer(rig, "dimetix", ptu_protocol="pelco-d", ptu_options=options) as srv:
        with (
            PelcoD.open(srv.ptu_path, timeout=1.0, move_timeout=2.0) as ptu,
            DimetixDLS.open(srv.lrf_path, timeout=1.0) as lrf,
        ):
            assert len(ptu.notes) == 1  # the opening's query
            window = Window.from_degrees([-4, -4, 4, -1])  # down: raw 100-400 either way
            with ScanSession(DeviceShooter(ptu, lrf), STATION, out) as session:
                assert session.scan(Target("W2", "plane", window)) is not None
            assert ptu.notes == []
    notes = [r for r in read_journal(journal_path_for(out)) if r["type"] == "note"]
    assert len(notes) == 1 and "read as signed 16-bit" in notes[0]["notes"][0]
