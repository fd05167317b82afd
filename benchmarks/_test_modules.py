"""The tests' own scene generators, loaded from the checkout for benchmarks (the tests are not
installed, nor a package)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

TESTS = Path(__file__).resolve().parent.parent / "tests"


def load(relative: str, name: str):
    """The module at ``tests/<relative>`` (e.g. ``fit/test_cylinder_others.py``), as ``name``."""
    spec = importlib.util.spec_from_file_location(name, TESTS / relative)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
