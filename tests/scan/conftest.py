"""Fixtures for the scan tests: a fresh valid document and a writer into ``tmp_path``."""

from __future__ import annotations

import copy
import json
import sys
from pathlib import Path

import pytest

# scan_cases.py (beside this file) is shared with tests/cli; make it importable by name whatever
# pytest's import mode or package layout.
if str(Path(__file__).parent) not in sys.path:
    sys.path.insert(0, str(Path(__file__).parent))

from scan_cases import make_doc  # noqa: E402


@pytest.fixture
def doc() -> dict:
    """A fresh valid document (metres) the test may modify."""
    return copy.deepcopy(make_doc())


@pytest.fixture
def write(tmp_path):
    """Write a document (dict or raw text) to ``tmp_path/scan.json``; return the path."""

    def _write(document, name: str = "scan.json"):
        path = tmp_path / name
        text = document if isinstance(document, str) else json.dumps(document)
        path.write_text(text, encoding="utf-8")
        return path

    return _write
