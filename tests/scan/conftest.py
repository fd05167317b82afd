"""Fixtures for the scan tests: a fresh valid document and a writer into ``tmp_path``."""

from __future__ import annotations

import copy
import json

import pytest
from scan_cases import make_doc


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
