"""The simulated LightWare LW20 at the byte level."""

from __future__ import annotations

from asbuilt.drivers.sim_lw20 import LW20Simulator
from driver_helpers import wall_rig


def _out(chunks) -> bytes:
    return b"".join(chunk for _, chunk in chunks)


def test_ld_answers_only_in_serial_mode():
    sim = LW20Simulator(wall_rig(4.996))
    assert _out(sim.startup()) == b""
    assert _out(sim.feed(b"LD\r\n")) == b""  # not selected yet
    assert _out(sim.feed(b"www\r\n")) == b""
    assert _out(sim.feed(b"LD\r\n")) == b"5.00\r\n"
    assert _out(sim.feed(b"L")) == b""
    assert _out(sim.feed(b"D\r")) == b"5.00\r\n"  # byte by byte, a bare CR
    assert _out(sim.feed(b"XX\r\n")) == b""


def test_no_target_and_prefix():
    sim = LW20Simulator(wall_rig(dropout=1.0))
    sim.feed(b"www\r\n")
    assert _out(sim.feed(b"LD\r\n")) == b"-1.00\r\n"
    sim = LW20Simulator(wall_rig(2.5), prefix="ld:")
    sim.feed(b"www\r\n")
    assert _out(sim.feed(b"LD\r\n")) == b"ld:2.50\r\n"
