"""The device simulators at the byte level, checked against the manuals' formats."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
import serial
from asbuilt.drivers.kinematics import Calibration
from asbuilt.drivers.sim_lrf import DimetixSimulator, LDMSimulator
from asbuilt.drivers.sim_ptu import PTUSimulator
from asbuilt.drivers.simport import parse_sim_url
from asbuilt.drivers.simrig import ShapesWorld, SimNoise, SimulatedRig, register_rig
from driver_helpers import wall_rig

from asbuilt.sim.raycast import PlaneShape


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
    assert _out(sim.feed(b"QQ\r\n")) == b""


def test_dropouts_answer_weak_signal():
    rig = wall_rig(dropout=1.0)
    assert _out(DimetixSimulator(rig).feed(b"s0g\r\n")) == b"g0@E255\r\n"
    assert _out(LDMSimulator(rig).feed(b"DM\r\n")) == b"E15\r\n"


def test_range_noise_has_the_configured_spread():
    rig = wall_rig(5.0, range_sigma=0.002, seed=4)
    values = np.array([rig.measure() for _ in range(400)])
    assert values.mean() == pytest.approx(5.0, abs=0.0005)
    assert values.std() == pytest.approx(0.002, rel=0.15)


def test_true_calibration_drives_the_beam_and_the_raw_range():
    cal = Calibration(range_offset=0.02, range_scale=1.01, laser_offset=(0.0, 0.0, 0.1))
    rig = wall_rig(5.0)
    rig.calibration = cal
    raw = rig.measure()
    assert raw == pytest.approx((5.0 - 0.02) / 1.01)


def test_grazing_incidence_is_too_weak():
    world = ShapesWorld([PlaneShape(point=np.array([0, 0, -1.0]), normal=np.array([0, 0, 1.0]))])
    rig = SimulatedRig(world, noise=SimNoise(min_cos=0.05))
    rig.move(0, -10)  # 10 positions down: about 0.5 degree: cos(incidence) about 0.009
    assert rig.measure() is None
    rig.move(0, -900)  # about 46 degrees down
    assert rig.measure() == pytest.approx(1.0 / math.sin(900 * 185.1428 / 3600 * math.pi / 180))


def test_mixed_return_at_an_edge_lies_between_the_surfaces():
    # a near half-plane (y > 0 is blocked by a wall at x = 2) in front of a far wall at x = 6
    near = PlaneShape(point=np.array([2.0, 0, 0]), normal=np.array([1.0, 0, 0]))

    class HalfNear(ShapesWorld):
        def raycast(self, origins, directions):
            hits = super().raycast(origins, directions)
            far = PlaneShape(point=np.array([6.0, 0, 0]), normal=np.array([1.0, 0, 0]))
            t_far, _ = far.intersect(origins, directions)
            left = directions[:, 1] > 0
            rng = np.where(left, hits.range, t_far)
            return type(hits)(rng, hits.object_index, np.ones(len(rng)), hits.normal)

    rig = SimulatedRig(HalfNear([near]), noise=SimNoise(divergence=0.01))
    rig.move(0, 0)  # the beam centre sits exactly on the edge: half the footprint on each
    value = rig.measure()
    assert 2.0 < value < 6.0
    rig.move(500, 0)  # far inside the near surface
    assert rig.measure() == pytest.approx(
        2.0 / math.cos(500 * 185.1428 / 3600 * math.pi / 180), rel=1e-3
    )


@pytest.mark.parametrize(
    "url, scheme, name, options",
    [
        ("sim-ptu://lab?scene=a.json&seed=3", "sim-ptu", "lab", {"scene": "a.json", "seed": "3"}),
        ("SIM-LRF://lab?protocol=ldm", "sim-lrf", "lab", {"protocol": "ldm"}),
        ("sim-lrf://", "sim-lrf", "default", {}),
    ],
)
def test_parse_sim_url(url, scheme, name, options):
    assert parse_sim_url(url) == (scheme, name, options)


def test_ptu_and_lrf_urls_share_one_rig(scene_file):
    ptu = serial.serial_for_url(f"sim-ptu://shared?scene={scene_file}", timeout=0.5)
    lrf = serial.serial_for_url("sim-lrf://shared", timeout=0.5)
    ptu.write(b"ED PP1500 A ")
    lrf.write(b"s0g\r\n")
    assert lrf.read_until(b"g0g").endswith(b"g0g")  # power-up g0? first, then the distance
    ptu.close()
    lrf.close()


@pytest.mark.parametrize(
    "url, message",
    [
        ("sim-lrf://nowhere", "does not exist; give ?scene=PATH"),
        ("sim-lrf://wall?protocol=pelco", "unknown simulated range finder protocol"),
        ("sim-lrf://wall?scene=other.json", "already exists with scene=None"),
        ("sim-ptu://x?scene=/no/such/scene.json", "scene file not found"),
    ],
)
def test_bad_sim_urls_fail_to_open(wall, url, message):
    with pytest.raises(serial.SerialException, match=re.escape(message)):
        serial.serial_for_url(url)


def test_registered_rig_is_reused():
    rig = register_rig("mine", wall_rig())
    port = serial.serial_for_url("sim-ptu://mine", timeout=0.2)
    port.write(b"ED PP300 ")
    port.read(100)
    assert rig.counts()[0] == 300
    port.close()


def test_exported_model_is_a_world(tmp_path):
    import trimesh
    from asbuilt.drivers.simrig import load_world

    box = trimesh.creation.box(extents=[1.0, 1.0, 1.0])
    box.apply_translation([3.5, 0.0, 0.0])  # near face at x = 3
    path = tmp_path / "model.stl"
    box.export(path)
    rig = SimulatedRig(load_world(path))
    assert rig.measure() == pytest.approx(3.0, abs=1e-6)
    rig.move(3000, 0)  # about 154 degrees: looking away from the model
    assert rig.measure() is None


@pytest.mark.parametrize("content", [b"", b"solid x\nendsolid x\n"])
def test_empty_models_are_scene_errors(tmp_path, content):
    from asbuilt.drivers.simrig import load_world

    from asbuilt.errors import SceneError

    path = tmp_path / "empty.stl"
    path.write_bytes(content)
    with pytest.raises(SceneError) as info:
        load_world(path)
    assert str(info.value).startswith(str(path))
