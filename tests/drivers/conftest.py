"""Fixtures for the driver tests: scripted serial ports, small simulated worlds, a scene file."""

from __future__ import annotations

import json

import pytest
from asbuilt.drivers.simrig import forget_rigs, register_rig
from asbuilt.drivers.transport import LineChannel
from driver_helpers import SCENE, ScriptedPort, wall_rig


@pytest.fixture
def scripted():
    """Factory: ``scripted(script, timeout=0.3) -> (LineChannel, ScriptedPort)``."""

    def make(script, timeout: float = 0.3, **kwargs):
        port = ScriptedPort(script, **kwargs)
        return LineChannel(port, "test device", timeout), port

    return make


@pytest.fixture(autouse=True)
def _fresh_rigs():
    forget_rigs()
    yield
    forget_rigs()


@pytest.fixture
def wall():
    """A registered rig named 'wall' (5 m wall ahead): open sim-ptu://wall and sim-lrf://wall."""
    return register_rig("wall", wall_rig())


@pytest.fixture
def scene_file(tmp_path):
    """A scene with a 12" pipe and a 0.4 m column in front of a wall; returns its path."""
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(SCENE))
    return path
