"""Compliant objects scanned with the paper's point counts and 2 mm noise raise no error.

A small fixed-seed version of benchmarks/false_alarms.py (which runs 200 scans per scene and
reports the rate in benchmarks/RESULTS.md): the whole pipeline (simulated scan, fit, merge,
shipped rules) must find no error on plumb columns, straight standard pipes and a perfect spool.
"""

import json
import sys
from pathlib import Path

import pytest

from asbuilt.pipeline import build_model
from asbuilt.scan import loads_scan
from asbuilt.sim.simulate import simulate_scan

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from false_alarms import faulty_scenes, scenes  # noqa: E402

SCENES = scenes()
FAULTY = faulty_scenes()


@pytest.mark.parametrize("name", list(SCENES))
@pytest.mark.parametrize("seed", [11, 12, 13, 14])
def test_compliant_scene_has_no_error(name, seed):
    model = build_model(loads_scan(json.dumps(simulate_scan(SCENES[name], seed=seed))))
    errors = [f"{f.slug}: {f.message}" for f in model.findings if f.severity == "error"]
    assert errors == []


def test_plumb_column_from_a_sparse_scan_is_unverifiable_not_an_error():
    model = build_model(
        loads_scan(json.dumps(simulate_scan(SCENES["plumb columns (2 x 36 pts)"], seed=21)))
    )
    plumb = [f for f in model.findings if f.slug == "out-of-plumb"]
    assert plumb and all(f.severity == "warning" and f.unverifiable for f in plumb)
    assert all("second face" in f.suggestions[0].description for f in plumb)


@pytest.mark.parametrize(
    "name", ["column leaning 1:100 (40 mm over 4 m)", "NPS 4 pipes crossing 50 mm apart"]
)
def test_faulty_scene_is_an_error(name):
    scene, slug = FAULTY[name]
    model = build_model(loads_scan(json.dumps(simulate_scan(scene, seed=31))))
    assert any(f.slug == slug and f.severity == "error" for f in model.findings)
