"""The simulated Pelco-D head at the byte level (frames written by hand from protocols.md)."""

from __future__ import annotations

import math

import pytest
from asbuilt.drivers.sim_pelco import PelcoDSimulator
from driver_helpers import wall_rig


def _frame(addr, cmd2, value=0, cmd1=0):
    body = [addr, cmd1, cmd2, value >> 8, value & 0xFF]
    return bytes([0xFF, *body, sum(body) % 256])


def _out(chunks) -> bytes:
    return b"".join(chunk for _, chunk in chunks)


def test_set_commands_move_the_rig_and_get_no_reply():
    rig = wall_rig()
    sim = PelcoDSimulator(rig, address=1)
    assert _out(sim.feed(_frame(1, 0x4B, 9000))) == b""
    assert _out(sim.feed(_frame(1, 0x4D, 35000))) == b""  # raw grows downwards: 10 deg up
    pan, tilt = rig.unit_angles()
    assert math.degrees(pan) == pytest.approx(90) and math.degrees(tilt) == pytest.approx(10)
    assert _out(sim.feed(_frame(1, 0x51))) == _frame(1, 0x59, 9000)
    assert _out(sim.feed(_frame(1, 0x53))) == _frame(1, 0x5B, 35000)


def test_bytes_one_at_a_time_and_noise_before_the_sync():
    sim = PelcoDSimulator(wall_rig(), address=3)
    out = []
    for byte in b"\x00\x42" + _frame(3, 0x4B, 27000) + _frame(3, 0x51):
        out.extend(sim.feed(bytes([byte])))
    assert _out(out) == _frame(3, 0x59, 27000)


def test_bad_checksum_and_other_addresses_are_ignored():
    rig = wall_rig()
    sim = PelcoDSimulator(rig, address=1)
    bad = bytearray(_frame(1, 0x4B, 4500))
    bad[6] ^= 1
    assert _out(sim.feed(bytes(bad) + _frame(2, 0x4B, 4500) + _frame(2, 0x51))) == b""
    assert rig.unit_angles()[0] == 0.0
    # a frame that starts inside a bad one is found again (the receiver resyncs on FF)
    assert _out(sim.feed(b"\xff\x01\x00" + _frame(1, 0x51))) == _frame(1, 0x59, 0)


def test_tilt_beyond_the_mechanics_is_clamped_and_values_past_a_turn_ignored():
    rig = wall_rig()
    sim = PelcoDSimulator(rig)
    sim.feed(_frame(1, 0x4D, 18000))  # straight back: beyond straight down
    assert math.degrees(rig.unit_angles()[1]) == pytest.approx(-90)
    sim.feed(_frame(1, 0x4B, 36000))
    assert rig.unit_angles()[0] == 0.0


def test_stop_holds_the_head_where_it_is():
    rig = wall_rig()
    rig.speed = 1e-6  # practically still
    sim = PelcoDSimulator(rig)
    sim.feed(_frame(1, 0x4B, 9000))
    sim.feed(_frame(1, 0x00, 0))
    assert _out(sim.feed(_frame(1, 0x51))) == _frame(1, 0x59, 0)


def test_trickled_and_corrupted_replies():
    sim = PelcoDSimulator(wall_rig(), trickle=0.001, corrupt={1})
    chunks = sim.feed(_frame(1, 0x51))
    assert [len(c) for _, c in chunks] == [1] * 7
    assert [at for at, _ in chunks] == sorted(at for at, _ in chunks)
    reply = _out(chunks)
    assert reply[:6] == _frame(1, 0x59, 0)[:6] and reply[6] != _frame(1, 0x59, 0)[6]
    assert _out(sim.feed(_frame(1, 0x51))) == _frame(1, 0x59, 0)  # only the first was spoilt
