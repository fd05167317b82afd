"""The colour table: by kind, overridden by the worst finding; conversions."""

from __future__ import annotations

import pytest

from asbuilt.cad.colours import (
    KIND_COLOURS,
    STATUS_COLOURS,
    colour_for,
    component_status,
    hex_colour,
    rgb255,
)
from asbuilt.findings import Finding
from asbuilt.model import COMPONENT_TYPES


def test_every_component_type_has_a_colour():
    # and the insulation parts drawn around insulated components
    assert set(KIND_COLOURS) == set(COMPONENT_TYPES) | {"insulation"}
    for colour in KIND_COLOURS.values():
        assert len(colour) == 4 and all(0 <= c <= 1 for c in colour)


@pytest.mark.parametrize(
    ("kind", "status", "expected"),
    [
        ("pipe", None, KIND_COLOURS["pipe"]),
        ("pipe", "info", KIND_COLOURS["pipe"]),
        ("pipe", "warning", STATUS_COLOURS["warning"]),
        ("cuboid", "error", STATUS_COLOURS["error"]),
        ("unknown-kind", None, (0.5, 0.5, 0.5, 1.0)),
    ],
)
def test_colour_for(kind, status, expected):
    assert colour_for(kind, status) == expected


def test_worst_severity_wins_per_object():
    findings = [
        Finding("A1", "a", "info", ("P1", "P2"), "x"),
        Finding("A2", "b", "warning", ("P1",), "x"),
        Finding("A3", "c", "error", ("P2",), "x"),
        Finding("A4", "d", "warning", ("P2",), "x"),
    ]
    assert component_status(findings) == {"P1": "warning", "P2": "error"}


@pytest.mark.parametrize(
    ("colour", "rgb", "text"),
    [
        ((1, 0, 0, 1), (255, 0, 0), "#ff0000"),
        ((0.5, 0.25, 0, 0.3), (128, 64, 0), "#804000"),
        ((2, -1, 0, 1), (255, 0, 0), "#ff0000"),
    ],
)
def test_conversions(colour, rgb, text):
    assert rgb255(colour) == rgb
    assert hex_colour(colour) == text


def test_importing_the_colour_table_does_not_load_the_cad_kernel():
    import subprocess
    import sys

    code = "import sys, asbuilt.cad.colours; print('cadquery' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
