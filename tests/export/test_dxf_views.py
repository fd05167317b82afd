"""DXF views of nearly vertical objects: what a 2D CAD reader (LibreCAD) shows in plan."""

from __future__ import annotations

import ezdxf
import numpy as np
import pytest

from asbuilt.cad import prepare
from asbuilt.export.dxf import write_dxf
from asbuilt.model import Component, Model, Straight
from asbuilt.primitives import Cylinder


def _tilted(degrees: float, azimuth: float = 0.6) -> np.ndarray:
    t = np.radians(degrees)
    return np.array([np.sin(t) * np.cos(azimuth), np.sin(t) * np.sin(azimuth), np.cos(t)])


@pytest.fixture(scope="module")
def plan(tmp_path_factory):
    components = (
        # a fitted vertical tank, 3 m across, 5.6 m tall, its axis 0.02 degrees off vertical
        # (2 mm in plan), as the plant sample's TK1
        Component("TK1", "cylinder", Cylinder([6, 9, 3.05], _tilted(0.02), 1.5, 5.6)),
        # a riser 1 degree off vertical: its 35 mm plan centreline lies inside its circle
        Component(
            "P1",
            "pipe",
            Straight([0, 0, 0], 2.0 * _tilted(1.0), 0.1095, 0.008),
        ),
        # a line sloping 5 degrees keeps its plan centreline
        Component(
            "P2",
            "pipe",
            Straight([0, 2, 1], [2.0, 2, 1 + 2.0 * np.tan(np.radians(5))], 0.1095, 0.008),
        ),
    )
    model = Model(components=components, units="m", name="tilted")
    path = tmp_path_factory.mktemp("dxf_views") / "tilted.dxf"
    write_dxf(prepare(model, solids=False), path)
    return ezdxf.readfile(path).modelspace()


def _near(entities, xy_mm, tolerance_mm):
    return [
        e
        for e in entities
        if np.linalg.norm(np.mean([p[:2] for p in e.get_points()], axis=0) - xy_mm) < tolerance_mm
    ]


def test_a_nearly_vertical_tank_is_its_circle_in_plan_not_a_dash(plan):
    outlines = _near(plan.query('LWPOLYLINE[layer=="PLAN-OUTLINE"]'), [6000, 9000], 50)
    centrelines = _near(plan.query('LWPOLYLINE[layer=="PLAN-CENTRELINE"]'), [6000, 9000], 50)
    assert centrelines == []
    assert len(outlines) == 1 and outlines[0].closed
    points = np.array([p[:2] for p in outlines[0].get_points()])
    assert np.ptp(points, axis=0) == pytest.approx([3000, 3000], rel=0.01)


def test_a_riser_a_degree_off_vertical_is_its_outline_in_plan(plan):
    assert _near(plan.query('LWPOLYLINE[layer=="PLAN-CENTRELINE"]'), [17, 12], 60) == []
    assert len(_near(plan.query('LWPOLYLINE[layer=="PLAN-OUTLINE"]'), [17, 12], 60)) == 1


def test_a_sloping_line_keeps_its_centreline_in_plan(plan):
    lines = _near(plan.query('LWPOLYLINE[layer=="PLAN-CENTRELINE"]'), [1000, 2000], 10)
    assert len(lines) == 1
    assert _near(plan.query('LWPOLYLINE[layer=="PLAN-OUTLINE"]'), [1000, 2000], 10) == []
