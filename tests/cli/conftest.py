"""Fixtures shared by the CLI tests."""

from __future__ import annotations

import json

import pytest
from asbuilt.drivers.simrig import forget_rigs


@pytest.fixture(autouse=True)
def _fresh_rigs():
    """Each test starts and ends with no simulated rig registered (``sim-ptu://NAME`` URLs)."""
    forget_rigs()
    yield
    forget_rigs()


#: A scene of one wall 6 m in front of the station, and a plan that scans it.
WALL_SCENE = {
    "format": "asbuilt-scene",
    "version": 1,
    "units": "m",
    "stations": [{"id": "S1", "position": [0.0, 0.0, 1.5]}],
    "objects": [
        {
            "id": "wall",
            "scan": False,
            "geometry": {
                "type": "plate",
                "center": [0.0, 6.0, 1.5],
                "normal": [0, -1, 0],
                "size": [20.0, 6.0],
                "thickness": 0.2,
            },
        }
    ],
}
WALL_PLAN = {
    "format": "asbuilt-scan-plan",
    "version": 1,
    "settings": {"edge_pairs": 0},
    "targets": [{"id": "W1", "kind": "plane", "window_deg": [80, -5, 100, 5]}],
}


@pytest.fixture
def site(tmp_path):
    """A folder with a wall 6 m from the station (scene.json) and a plan of one window on it
    (plan.json): the device CLI tests scan it over pseudo-terminals."""
    (tmp_path / "scene.json").write_text(json.dumps(WALL_SCENE))
    (tmp_path / "plan.json").write_text(json.dumps(WALL_PLAN))
    return tmp_path
