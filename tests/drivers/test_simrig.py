"""The simulated rig: sensor effects (noise, dropouts, grazing, mixed edge returns), worlds."""

from __future__ import annotations

import math

import numpy as np
import pytest
from asbuilt.drivers.kinematics import Calibration
from asbuilt.drivers.simrig import ShapesWorld, SimNoise, SimulatedRig
from driver_helpers import wall_rig

from asbuilt.sim.raycast import PlaneShape


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
