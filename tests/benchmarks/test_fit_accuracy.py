"""benchmarks/fit_accuracy.py runs end to end (a smoke run) and its error measures are right."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import fit_accuracy  # noqa: E402

from asbuilt.primitives import Cuboid  # noqa: E402
from asbuilt.sim.geometry import rotation_zyx  # noqa: E402


def test_quick_run_writes_tables(tmp_path):
    out = tmp_path / "fit.md"
    assert (
        fit_accuracy.main(["--quick", "--only", "sphere", "--only", "plane", "--out", str(out)])
        == 0
    )
    text = out.read_text()
    assert "#### Targets" in text
    assert "#### Spheres, clean" in text and "#### Planes (walls, plates), with 20% edge" in text
    assert "| 0.5 | 30 | 5 | " in text  # sphere cell: diameter, points, trials


@pytest.mark.parametrize("yaw", [0.0, 30.0, 90.0])
def test_cuboid_errors_are_permutation_and_sign_free(yaw):
    axes = rotation_zyx(yaw, 0, 0)
    truth = {"axes": axes, "size": np.array([0.3, 0.4, 3.0])}
    # the same box described with permuted, flipped axes and sizes
    fitted = Cuboid(
        center=np.zeros(3),
        axes=np.array([axes[2], -axes[0], -axes[1]]),
        size=np.array([3.03, 0.3, 0.4]),
    )
    err = fit_accuracy.cuboid_errors(fitted, truth)
    np.testing.assert_allclose(err["size_rel"], [0.0, 0.0, 0.01], atol=1e-12)
    assert err["orientation"] == pytest.approx(0.0, abs=1e-6)
    turned = Cuboid(center=np.zeros(3), axes=rotation_zyx(yaw + 2.0, 0, 0), size=truth["size"])
    assert fit_accuracy.cuboid_errors(turned, truth)["orientation"] == pytest.approx(2.0)


def test_trials_are_exact_and_on_the_surface():
    rng = np.random.default_rng(0)
    trial = fit_accuracy.cylinder_trial(rng, 114.3, 3, 30)
    assert trial.clean.shape == trial.dirty.shape == (30, 3)
    changed = np.any(trial.clean != trial.dirty, axis=1)
    assert changed.sum() == 6  # 20% edge outliers
    assert trial.bound["radius"] > 0 and trial.bound["axis"] > 0
