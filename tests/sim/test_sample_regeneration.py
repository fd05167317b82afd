"""The committed samples regenerate byte for byte from their scenes, and they load."""

from pathlib import Path

import numpy as np
import pytest

from asbuilt.scan import load_scan
from asbuilt.sim.scene import load_scene
from asbuilt.sim.simulate import dumps_scan, simulate_scan

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
NAMES = ["spool", "structural-bay", "plant", "lagged-line"]


@pytest.mark.parametrize("name", NAMES)
def test_sample_regenerates_identically(name):
    scene = load_scene(SAMPLES / "scenes" / f"{name}.scene.json")
    text = dumps_scan(simulate_scan(scene))
    assert text == (SAMPLES / f"{name}.json").read_text(encoding="utf-8")


@pytest.mark.parametrize("name", NAMES)
def test_sample_loads_and_matches_truth(name):
    scan = load_scan(SAMPLES / f"{name}.json")
    scene = load_scene(SAMPLES / "scenes" / f"{name}.scene.json")
    assert (SAMPLES / f"{name}.json").stat().st_size < 200_000
    for obj in scan.objects:
        assert 20 <= len(obj.points) <= 50
        truth = scene.object(obj.id)
        assert obj.insulation == truth.insulation  # the points lie on the cladding
        d = truth.truth.distance(obj.points) - truth.insulation
        assert np.median(np.abs(d)) < 0.003


def test_spool_layout():
    scan = load_scan(SAMPLES / "spool.json")
    assert {o.id for o in scan.objects} == {"P1", "P2", "P3", "P4", "P5", "P6"}
    assert {o.nominal for o in scan.objects} == {'4"', '6"'}
    assert len(scan.links) == 5


def test_lagged_line_layout():
    scan = load_scan(SAMPLES / "lagged-line.json")
    assert [o.id for o in scan.objects] == ["P1", "P2", "P3", "P4"]
    assert {o.insulation for o in scan.objects} == {0.05}
    assert [o.nominal for o in scan.objects] == ['6"', '6"', '4"', '4"']
    assert len(scan.links) == 3
