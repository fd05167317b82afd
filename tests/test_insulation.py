"""asbuilt.insulation: the jacket and envelope geometry of insulated components."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from asbuilt.insulation import JACKET_ROOM, envelope, jacket, jacket_thickness
from asbuilt.model import Bend, Component, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder

R = 0.05715  # NPS 4 outside radius, ASME B36.10M


def comp(geometry, kind="pipe", insulation=0.05):
    return Component("X", kind, geometry, insulation=insulation)


def test_a_straight_jacket_is_hollow_with_the_pipe_as_its_bore():
    pipe = Straight([0, 0, 0], [2, 0, 0], R, 0.006)
    found = jacket(comp(pipe))
    assert isinstance(found, Straight)
    assert found.outer_radius == pytest.approx(R + 0.05)
    assert found.outer_radius - found.wall == pytest.approx(R)
    np.testing.assert_array_equal(found.start, pipe.start)
    outer = envelope(comp(pipe))
    assert (outer.outer_radius, outer.wall) == (pytest.approx(R + 0.05), 0.0)


def test_a_bare_component_has_no_jacket_and_is_its_own_envelope():
    pipe = Straight([0, 0, 0], [2, 0, 0], R)
    assert jacket(comp(pipe, insulation=0.0)) is None
    assert envelope(comp(pipe, insulation=0.0)) is pipe


def test_a_fitted_cylinder_jacket_is_a_straight_along_its_axis():
    tank = Cylinder([0, 0, 2], [0, 0, 1], 1.0, 4.0)
    found = jacket(comp(tank, "cylinder", 0.1))
    np.testing.assert_allclose([found.start, found.end], [[0, 0, 0], [0, 0, 4]])
    assert (found.outer_radius, found.wall) == (pytest.approx(1.1), pytest.approx(0.1))


def test_shapes_insulation_does_not_wrap_have_none():
    box = Cuboid([0, 0, 0], np.eye(3), [1, 1, 1])
    assert jacket(comp(box, "cuboid")) is None
    assert envelope(comp(box, "cuboid")) is box


def test_a_tight_elbow_gets_a_thinner_jacket():
    # a short-radius NPS 4 elbow (bend radius 1 D = 0.1143 m) under 100 mm of lagging
    bend = Bend([0.1143, 0, 0], [0, 0.1143, 0], [0, 0, 0], R)
    c = comp(bend, "elbow", 0.1)
    assert jacket_thickness(c) == pytest.approx(JACKET_ROOM * 0.1143 - R)
    found = jacket(c)
    assert max(found.radii) < found.bend_radius
    # a long-radius elbow under 50 mm has room for all of it
    long = dataclasses.replace(bend, start=[0.1524, 0, 0], end=[0, 0.1524, 0])
    assert jacket_thickness(comp(long, "elbow", 0.05)) == 0.05


def test_a_tee_jacket_keeps_its_outlet_beyond_the_run_jacket():
    tee = Tee([0, 0, 0], [-0.105, 0, 0], [0.105, 0, 0], [0, 0, 0.105], R, R)
    c = comp(tee, "tee", 0.1)
    t = jacket_thickness(c)
    assert t == pytest.approx(JACKET_ROOM * 0.105 - R)
    found = jacket(c)
    assert found.outer_radius < 0.105  # the outlet still ends outside the run's cladding
