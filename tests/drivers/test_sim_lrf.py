"""The simulated range finders (Dimetix, LDM) at the byte level."""

from __future__ import annotations

from asbuilt.drivers.sim_lrf import DimetixSimulator, LDMSimulator
from driver_helpers import wall_rig


def _out(chunks) -> bytes:
    return b"".join(chunk for _, chunk in chunks)


def test_dimetix_formats():
    rig = wall_rig(2.5)
    sim = DimetixSimulator(rig, device_id=2)
    assert _out(sim.startup()) == b"g2?\r\n"
    assert _out(sim.feed(b"s2g\r\n")) == b"g2g+00025000\r\n"
    assert _out(sim.feed(b"s1g\r\n")) == b""  # another device on the bus
    assert _out(sim.feed(b"s2uof+00000100\r\n")) == b"g2?\r\n"
    assert _out(sim.feed(b"s2g\r")) == b"g2g+00025100\r\n"
    assert _out(sim.feed(b"s2uof\r\n")) == b"g2uof+00000100\r\n"
    assert _out(sim.feed(b"s2zz\r\n")) == b"g2@E203\r\n"
    assert _out(sim.feed(b"s2c\r\n")) == b"g2?\r\n"


def test_ldm_formats():
    sim = LDMSimulator(wall_rig(4.996))
    assert _out(sim.feed(b"DM\r\n")) == b"004.996\r\n"
    sim.feed(b"SDs\r\n")
    assert _out(sim.feed(b"DM\r\n")) == b"004.996 001000\r\n"
    sim.feed(b"SDh\r\n")
    assert _out(sim.feed(b"DM\r\n")) == b"001384\r\n"  # 4996 mm
    assert _out(sim.feed(b"QQ\r\n")) == b""


def test_dropouts_answer_weak_signal():
    rig = wall_rig(dropout=1.0)
    assert _out(DimetixSimulator(rig).feed(b"s0g\r\n")) == b"g0@E255\r\n"
    assert _out(LDMSimulator(rig).feed(b"DM\r\n")) == b"E15\r\n"
