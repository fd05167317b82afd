"""Fixtures for the fit tests; the synthetic scan helpers live in fit_scans.py."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20260521)
