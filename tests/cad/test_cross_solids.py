"""Cross solids (asbuilt.cad.solids): a run cylinder fused with the outlet cylinder through both
sides, each bore of its own wall; valid for the kernel (``BRepCheck_Analyzer``) with the volume
of the formula: two cylinders less what they share (twice a tee's branch-in-run overlap)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from cad_zoo import R3, R4, W3, W4, tee_overlap
from OCP.BRepCheck import BRepCheck_Analyzer

from asbuilt.cad.solids import solid_for, split_closed_faces
from asbuilt.model import Component, Cross

R6, W6 = 0.1683 / 2, 0.00711  # NPS 6 STD


def _cross(run_r, run_w, out_r, out_w, c, m, turn_deg=0.0, tilt_deg=0.0):
    """A cross at (1, 2, 3): run along x turned ``turn_deg`` about z, outlets along y tilted
    ``tilt_deg`` about the run."""
    t = math.radians(turn_deg)
    run = np.array([math.cos(t), math.sin(t), 0.0])
    side = np.array([-math.sin(t), math.cos(t), 0.0])
    a = math.radians(tilt_deg)
    outlet = math.cos(a) * side + math.sin(a) * np.array([0.0, 0.0, 1.0])
    center = np.array([1.0, 2.0, 3.0])
    return Cross(
        center, center - c * run, center + c * run, center - m * outlet, center + m * outlet,
        run_r, out_r, run_w, out_w,
    )  # fmt: skip


def _volume(run_r, run_w, out_r, out_w, c, m):
    def body(r, q):
        return math.pi * (r * r * 2 * c + q * q * 2 * m) - 2 * tee_overlap(r, q)

    if run_w == 0:
        return body(run_r, out_r)
    return body(run_r, out_r) - body(run_r - run_w, out_r - out_w)


CASES = [
    pytest.param(R4, W4, R4, W4, 0.105, 0.105, id="nps4-straight"),
    pytest.param(R6, W6, R4, W4, 0.143, 0.130, id="nps6x4-reducing"),
    pytest.param(R4, W4, R3, W3, 0.105, 0.098, id="nps4x3-reducing"),
    pytest.param(R4, 0.0, R4, 0.0, 0.105, 0.105, id="solid"),
]


@pytest.mark.parametrize(("turn", "tilt"), [(0, 0), (33, 0), (90, 57), (-121, 90)])
@pytest.mark.parametrize(("run_r", "run_w", "out_r", "out_w", "c", "m"), CASES)
def test_a_cross_is_one_valid_solid_of_the_formula_volume(
    run_r, run_w, out_r, out_w, c, m, turn, tilt
):
    geometry = _cross(run_r, run_w, out_r, out_w, c, m, turn, tilt)
    solid = solid_for(Component("X1", "cross", geometry, spool="S1"))
    assert BRepCheck_Analyzer(solid.wrapped).IsValid()
    assert solid.Volume() == pytest.approx(_volume(run_r, run_w, out_r, out_w, c, m), rel=1e-3)
    # as written to files: closed faces split, still one valid solid
    assert BRepCheck_Analyzer(split_closed_faces(solid).wrapped).IsValid()


def test_a_cross_sits_between_its_four_ends():
    geometry = _cross(R6, W6, R4, W4, 0.143, 0.130)
    box = solid_for(Component("X1", "cross", geometry, spool="S1")).BoundingBox()
    assert (box.xmin, box.xmax) == pytest.approx((1 - 0.143, 1 + 0.143), abs=1e-6)
    assert (box.ymin, box.ymax) == pytest.approx((2 - 0.130, 2 + 0.130), abs=1e-6)
    assert (box.zmin, box.zmax) == pytest.approx((3 - R6, 3 + R6), abs=1e-6)


def test_outlets_parallel_to_the_run_are_refused():
    center = np.zeros(3)
    x = np.array([1.0, 0, 0])
    geometry = Cross(center, -x * 0.1, x * 0.1, -x * 0.1, x * 0.1, R4, R4, W4, W4)
    with pytest.raises(Exception, match="parallel"):
        solid_for(Component("X1", "cross", geometry, spool="S1"))
