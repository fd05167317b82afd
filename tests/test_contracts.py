"""Errors, tolerances, units, findings and model value objects."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from asbuilt.errors import AsbuiltError, DeviceTimeout, ScanError, ScanReadError
from asbuilt.findings import Finding
from asbuilt.model import Bend, Component, Straight
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances
from asbuilt.units import from_metres, to_metres, unit_factor


def test_located_error_message_and_builtin_bases():
    err = ScanError("coordinate is NaN", source="scan.json", where="objects[3] (P4).points[17]")
    assert str(err) == "scan.json: objects[3] (P4).points[17]: coordinate is NaN"
    assert isinstance(err, ValueError) and isinstance(err, AsbuiltError)
    assert issubclass(ScanReadError, OSError)
    assert issubclass(DeviceTimeout, TimeoutError)


def test_tolerances_are_frozen_and_every_field_has_a_reason():
    with pytest.raises(dataclasses.FrozenInstanceError):
        DEFAULT_TOLERANCES.angle_snap_deg = 5  # type: ignore[misc]
    assert all(len(reason) > 20 for reason in DEFAULT_TOLERANCES.reasons().values())
    assert dataclasses.replace(Tolerances(), angle_snap_deg=1.0).angle_snap_deg == 1.0


@pytest.mark.parametrize(
    ("unit", "metres"), [("m", 1), ("mm", 1e-3), ("cm", 1e-2), ("in", 0.0254), ("ft", 0.3048)]
)
def test_units_round_trip(unit, metres):
    assert unit_factor(unit) == metres
    assert from_metres(to_metres(12.5, unit), unit) == pytest.approx(12.5)


def test_unknown_unit_says_what_to_use():
    with pytest.raises(ValueError, match="use one of m, mm, cm, in, ft"):
        unit_factor("furlong")


def test_finding_validates_severity():
    with pytest.raises(ValueError):
        Finding(code="X", slug="x", severity="fatal", objects=(), message="m")


def test_bend_geometry_angle_and_radius():
    bend = Bend(start=[0.1524, 0, 0], end=[0, 0.1524, 0], center=[0, 0, 0], outer_radius=0.05715)
    assert bend.angle_deg == pytest.approx(90.0)
    assert bend.bend_radius == pytest.approx(0.1524)
    with pytest.raises(ValueError, match="equidistant"):
        Bend(start=[1, 0, 0], end=[0, 2, 0], center=[0, 0, 0], outer_radius=0.1)


def test_straight_and_component_validation():
    pipe = Straight(start=[0, 0, 0], end=[0, 0, 2], outer_radius=0.05715, wall=0.00602)
    assert pipe.length == 2.0
    np.testing.assert_allclose(pipe.direction, [0, 0, 1])
    with pytest.raises(ValueError, match="thinner than the outer radius"):
        Straight(start=[0, 0, 0], end=[0, 0, 1], outer_radius=0.01, wall=0.02)
    with pytest.raises(ValueError, match="component type"):
        Component(id="P1", type="valve", geometry=pipe)
