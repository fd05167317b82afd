"""FLIR/DP pan-tilt driver against scripted replies and against the simulator."""

from __future__ import annotations

import math

import pytest
from asbuilt.drivers.ptu import (
    MAX_UNSOLICITED,
    PanTiltUnit,
    PTUCommandError,
    PTULimitError,
    PTULimits,
)
from asbuilt.drivers.simrig import register_rig
from driver_helpers import wall_rig

from asbuilt.errors import DeviceProtocolError, DeviceTimeout

ARCSEC = math.pi / 180 / 3600

# An E-series-like unit: not the D46's resolution or limits, verbose feedback and echo on.
INIT_VERBOSE_ECHO = [
    ("PR", b" PR * 46.2857\r\n"),  # the resynchronising query after a lone delimiter
    ("FT", b"FT *\r\n"),  # echo on: the command comes back before the reply
    ("ED", b"ED *\r\n"),
    ("I", b"*\r\n"),
    ("PN", b"* -7000\r\n"),
    ("PX", b"* 7000\r\n"),
    ("TN", [b"* -3", b"000\r\n"]),  # a reply split in pieces
    ("TX", b"* 1500\r\n"),
    ("PR", b"* 46.2857\r\n"),
    ("TR", b"* 11.5714\r\n"),
    ("PS", b"* 1000\r\n"),
    ("TS", b"! Illegal Command\r\n"),  # a unit without the query keeps the reply timeout
]


def _unit(scripted, script, timeout=0.3):
    channel, port = scripted(script, timeout=timeout)
    return PanTiltUnit(channel, move_timeout=timeout), port


def test_initialize_reads_resolution_and_limits_from_the_unit(scripted):
    ptu, port = _unit(scripted, INIT_VERBOSE_ECHO)
    limits = ptu.initialize()
    assert limits == PTULimits(-7000, 7000, -3000, 1500, 46.2857, 11.5714)
    assert port.written[1:3] == ["FT", "ED"]  # terse feedback and echo off first


def test_verbose_replies_are_parsed(scripted):
    script = [
        ("PR", b"* 185.1428 seconds arc per Pan position\r\n"),
        ("FT", b"*\r\n"),
        ("ED", b"*\r\n"),
        ("I", b"*\r\n"),
        ("PN", b"* Minimum Pan position is -3090\r\n"),
        ("PX", b"* Maximum Pan position is 3090\r\n"),
        ("TN", b"* Minimum Tilt position is -907\r\n"),
        ("TX", b"* Maximum Tilt position is 604\r\n"),
        ("PR", b"* 185.1428 seconds arc per Pan position\r\n"),
        ("TR", b"* 185.1428 seconds arc per Tilt position\r\n"),
        ("PS", b"* Target Pan speed is 1000 positions/sec\r\n"),
        ("TS", b"* Target Tilt speed is 1000 positions/sec\r\n"),
        ("PP", b"* Current Pan position is 120\r\n"),
        ("TP", b"* Current Tilt position is -40\r\n"),
    ]
    ptu, _ = _unit(scripted, script)
    ptu.initialize()
    assert ptu.position_counts() == (120, -40)
    pan, tilt = ptu.to_angles(120, -40)
    assert pan == pytest.approx(120 * 185.1428 * ARCSEC)
    assert tilt == pytest.approx(-40 * 185.1428 * ARCSEC)


def test_move_sends_absolute_counts_and_awaits(scripted):
    script = INIT_VERBOSE_ECHO + [("PP2000", b"*\r\n"), ("TP-1000", b"*\r\n"), ("A", b"*\r\n")]
    ptu, port = _unit(scripted, script)
    ptu.initialize()
    pan, tilt = ptu.move_to(2000 * 46.2857 * ARCSEC, -1000 * 11.5714 * ARCSEC)
    assert port.written[-3:] == ["PP2000", "TP-1000", "A"]
    assert pan == pytest.approx(2000 * 46.2857 * ARCSEC)
    assert tilt == pytest.approx(-1000 * 11.5714 * ARCSEC)


@pytest.mark.parametrize("pan_counts, tilt_counts", [(7001, 0), (-7001, 0), (0, 1501), (0, -3001)])
def test_targets_outside_the_limits_are_refused_before_sending(scripted, pan_counts, tilt_counts):
    ptu, port = _unit(scripted, INIT_VERBOSE_ECHO)
    ptu.initialize()
    sent = len(port.written)
    with pytest.raises(PTULimitError, match="outside the unit's limits"):
        ptu.move_to(pan_counts * 46.2857 * ARCSEC, tilt_counts * 11.5714 * ARCSEC)
    assert len(port.written) == sent


@pytest.mark.parametrize(
    "pan, tilt, axis",
    [
        (math.inf, 0.0, "pan"),
        (0.0, -math.inf, "tilt"),
        (math.nan, 0.0, "pan"),
        (0.0, 1e308, "tilt"),
    ],
)
def test_non_finite_targets_are_limit_errors_before_sending(scripted, pan, tilt, axis):
    """``inf``/``nan`` (or an angle too large to count) is refused like any target outside the
    limits, not an OverflowError from the conversion to counts."""
    ptu, port = _unit(scripted, INIT_VERBOSE_ECHO)
    ptu.initialize()
    sent = len(port.written)
    with pytest.raises(PTULimitError, match=f"{axis} .* deg is not an angle inside the unit's"):
        ptu.move_to(pan, tilt)
    assert len(port.written) == sent


def test_error_reply_becomes_a_command_error(scripted):
    script = INIT_VERBOSE_ECHO + [("PP10", b"! Maximum allowable Pan position is 5\r\n")]
    ptu, _ = _unit(scripted, script)
    ptu.initialize()
    with pytest.raises(
        PTUCommandError, match="'PP10' refused: Maximum allowable Pan position is 5"
    ):
        ptu.command("PP10")


@pytest.mark.parametrize(
    "notice, axis", [(b"!P\r\n", "pan"), (b"!T\r\n", "tilt"), (b"!P!T\r\n", "pan and tilt")]
)
def test_asynchronous_limit_notice_becomes_a_limit_error(scripted, notice, axis):
    script = INIT_VERBOSE_ECHO + [("A", notice + b"*\r\n")]
    ptu, _ = _unit(scripted, script)
    ptu.initialize()
    with pytest.raises(PTULimitError, match=f"the {axis} axis hit its limit"):
        ptu.await_completion()


def test_reset_accepts_the_calibration_sweep_notices(scripted):
    ptu, port = _unit(scripted, [("R", b"!T!T!P!P*\r\n")])
    ptu.reset(timeout=1.0)
    assert port.written == ["R"]


@pytest.mark.parametrize("text", [b"hello", b"# 12"])
def test_text_that_is_no_reply_is_skipped_and_kept(scripted, text):
    # every reply starts with '*' or '!': other text (a power-up banner) is the unit's own
    ptu, _ = _unit(scripted, [("V", text + b"\r\n* 2.14\r\n")])
    assert ptu.command("V") == "2.14"
    assert ptu.unsolicited == [text.decode()]
    ptu, _ = _unit(scripted, [("V", text + b"\r\n")])
    with pytest.raises(DeviceTimeout):
        ptu.command("V")


def test_a_stream_of_text_that_is_no_reply_is_a_protocol_error(scripted):
    ptu, _ = _unit(scripted, [("V", b"hello\r\n" * (MAX_UNSOLICITED + 1))])
    with pytest.raises(DeviceProtocolError, match="neither"):
        ptu.command("V")


@pytest.mark.parametrize(
    "reply, value",
    [
        (b"* 46.2857\r\n", 46.2857),
        (b"* .5\r\n", 0.5),
        (b"* -.25 seconds\r\n", -0.25),
        (b"*12\r\n", 12),
    ],
)
def test_query_numbers_in_every_decimal_spelling(scripted, reply, value):
    ptu, _ = _unit(scripted, [("PR", reply)])
    assert ptu.query_number("PR") == pytest.approx(value)


def test_query_without_number_is_a_protocol_error(scripted):
    ptu, _ = _unit(scripted, [("PR", b"* lots\r\n")])
    with pytest.raises(DeviceProtocolError, match="holds no number"):
        ptu.query_number("PR")


def test_silent_unit_times_out(scripted):
    ptu, _ = _unit(scripted, [], timeout=0.2)
    with pytest.raises(DeviceTimeout, match="no reply to 'PR'"):
        ptu.initialize()


# -- against the simulator over the sim-ptu:// URL ----------------------------------------------
def test_driver_over_the_simulator_url(wall):
    with PanTiltUnit.open("sim-ptu://wall", timeout=1.0) as ptu:
        assert ptu.limits == PTULimits(-3090, 3090, -907, 604, 185.1428, 185.1428)
        pan, tilt = ptu.move_to(math.radians(10), math.radians(-5))
        assert ptu.position() == pytest.approx((pan, tilt))
        assert ptu.position_counts() == (
            round(math.radians(10) / (185.1428 * ARCSEC)),
            round(math.radians(-5) / (185.1428 * ARCSEC)),
        )
        assert "Pan-Tilt" in ptu.version()


def test_disabled_limits_let_the_unit_report_a_limit_hit(wall):
    with PanTiltUnit.open("sim-ptu://wall", timeout=1.0) as ptu:
        ptu.set_limit_enforcement(False)
        ptu.command("PP3000")
        with pytest.raises(PTULimitError, match="pan axis hit its limit"):
            ptu.command("PO500")
            ptu.await_completion()
        assert ptu.position_counts()[0] == 3090


def test_await_waits_for_a_finite_speed_move():
    rig = register_rig("slow", wall_rig())
    rig.speed = 20000.0  # positions per second: 0.1 s for 2000 positions
    with PanTiltUnit.open("sim-ptu://slow", timeout=1.0, move_timeout=5.0) as ptu:
        ptu.command("PP2000")
        ptu.await_completion()
        assert ptu.position_counts()[0] == 2000


def test_ranges_missed_names_the_axes_some_angles_fall_outside():
    limits = PTULimits(-7000, 7000, -3000, 1500, 46.2857, 11.5714)
    pan_hi, tilt_hi = 7000 * 46.2857 * ARCSEC, 1500 * 11.5714 * ARCSEC
    assert limits.ranges_missed([(0.0, 0.0), (pan_hi, tilt_hi)]) == ""
    assert limits.ranges_missed([(0.0, tilt_hi + 0.01)]) == "tilt range [-9.643, 4.821] deg"
    both = limits.ranges_missed([(math.nan, 0.0), (0.0, -1.0)])
    assert both == "pan range [-90.000, 90.000] deg and tilt range [-9.643, 4.821] deg"
