"""Fixtures shared by the CLI tests."""

from __future__ import annotations

import pytest
from asbuilt.drivers.simrig import forget_rigs


@pytest.fixture(autouse=True)
def _fresh_rigs():
    """Each test starts and ends with no simulated rig registered (``sim-ptu://NAME`` URLs)."""
    forget_rigs()
    yield
    forget_rigs()
