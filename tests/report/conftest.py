"""Fixtures for the report tests; the helpers they use live in report_helpers.py."""

from __future__ import annotations

import pytest
from report_helpers import ROOT, Browser, _chromium, _ci


@pytest.fixture(scope="session")
def plant_model():
    """The plant sample fitted, merged and checked (cuboids, pipes, elbows, tank, plane, hull)."""
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    return build_model(load_scan(ROOT / "samples" / "plant.json"))


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium; skipped with the reason where it is missing, but under CI
    (``CI=true``) a missing browser fails the test."""
    executable = _chromium()
    if executable is None:
        message = (
            "chromium not found: install it (apt-get install chromium chromium-driver) "
            "to render the HTML report in a real browser"
        )
        if _ci():
            pytest.fail(message)
        pytest.skip(message)
    instance = Browser(executable)
    try:
        yield instance
    finally:
        instance.close()
