"""The simulated pan-tilt unit at the byte level, checked against the manual's formats."""

from __future__ import annotations

import pytest
from asbuilt.drivers.sim_ptu import PTUSimulator
from driver_helpers import wall_rig


def _out(chunks) -> bytes:
    return b"".join(chunk for _, chunk in chunks)


def test_ptu_powers_up_with_echo_and_verbose_feedback():
    ptu = PTUSimulator(wall_rig())
    assert _out(ptu.feed(b"PP ")) == b"PP * Current Pan position is 0\r\n"
    assert _out(ptu.feed(b"ED ")) == b"ED *\r\n"  # the echo stops after ED
    assert _out(ptu.feed(b"FT ")) == b"*\r\n"
    assert _out(ptu.feed(b"pp ")) == b"* 0\r\n"  # case-insensitive, terse


@pytest.mark.parametrize(
    "command, reply",
    [
        (b"PP3091 ", b"! Maximum allowable Pan position is 3090\r\n"),
        (b"PP-3091 ", b"! Minimum allowable Pan position is -3090\r\n"),
        (b"TP605 ", b"! Maximum allowable Tilt position is 604\r\n"),
        (b"PR ", b"* 185.1428\r\n"),
        (b"TN ", b"* -907\r\n"),
        (b"PX ", b"* 3090\r\n"),
        (b"XYZ ", b"! Illegal Command\r\n"),
        (b"12 ", b"! Illegal Command\r\n"),
        (b"PS ", b"* 1000\r\n"),
        (b"PS-5 ", b"! Illegal PS argument -5\r\n"),
    ],
)
def test_ptu_terse_replies(command, reply):
    ptu = PTUSimulator(wall_rig())
    ptu.feed(b"ED FT ")
    assert _out(ptu.feed(command)) == reply


def test_ptu_several_commands_in_one_write_and_cr_delimiters():
    rig = wall_rig()
    ptu = PTUSimulator(rig)
    out = _out(ptu.feed(b"ED\rFT\r\rPP100 TP-50\rA\rPP\rTP "))
    assert out == b"ED\r*\r\n*\r\n*\r\n*\r\n*\r\n* 100\r\n* -50\r\n"  # ED itself is echoed
    assert rig.counts() == (100, -50)


def test_ptu_slaved_mode_waits_for_await():
    rig = wall_rig()
    ptu = PTUSimulator(rig)
    ptu.feed(b"ED FT S ")
    ptu.feed(b"PP200 ")
    assert rig.counts() == (0, 0)
    ptu.feed(b"A ")
    assert rig.counts() == (200, 0)


def test_ptu_relative_move_past_a_disabled_limit_sends_a_notice():
    rig = wall_rig()
    ptu = PTUSimulator(rig)
    ptu.feed(b"ED FT LD PP3000 ")
    out = _out(ptu.feed(b"PO200 "))
    assert out == b"*\r\n!P\r\n"
    assert rig.counts()[0] == 3090


def test_ptu_reset_sweep_reply():
    ptu = PTUSimulator(wall_rig())
    ptu.feed(b"ED ")
    assert _out(ptu.feed(b"R ")) == b"!T!T!P!P*\r\n"
