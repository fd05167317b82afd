"""benchmarks/tank_scenes.py: its outcome classes, and a sweep that leaves the shipped thresholds."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

import asbuilt.fit._cylinder_checks as checks
import asbuilt.fit._cylinder_far_side as far_side

SCRIPT = Path(__file__).resolve().parents[2] / "benchmarks" / "tank_scenes.py"


@pytest.fixture(scope="module")
def tank_scenes():
    spec = importlib.util.spec_from_file_location("tank_scenes", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_run_counts_every_seed_and_restores_the_thresholds(tank_scenes):
    shipped = far_side.FAR_FRACTION, checks.RASTER_SHARE
    counts = tank_scenes.run(1, 0.8, 0.95)
    assert (far_side.FAR_FRACTION, checks.RASTER_SHARE) == shipped
    assert set(counts) == {name for name, _ in tank_scenes.SCENES}
    for tally in counts.values():
        assert sum(tally.values()) == 1
        assert set(tally) <= {"right", "wrong", "refused"}


def test_outcome_judges_the_radius_by_its_error_and_standard_error(tank_scenes):
    points, station, truth = tank_scenes.sim_tanks.partial_tank(0)
    assert tank_scenes.outcome(points, station, truth) == "right"
    wrong = dict(truth, radius=truth["radius"] * 1.5)
    assert tank_scenes.outcome(points, station, wrong) == "wrong"
