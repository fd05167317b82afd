"""Laterals (wyes) fuse into one valid solid, in the kernel and read back from STEP.

Before merging built laterals, a 30-75 degree branch on an inline pair left three disjoint
pipes (the run's gap and the branch's stand-off unfilled): their spool fused into 3 solids.
Each case here merges synthetic fits of a run (two pipes with a gap) and an oblique branch,
fuses the spool, and compares its volume with the union computed independently of the kernel:
the run's wall over its whole length, plus the branch's wall outside the run's outside, less
the run's wall where the branch's bore opens into it (tees are hollow that way), the branch
region integrated by Monte Carlo with numpy.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from asbuilt.cad import prepare
from asbuilt.export.step import read_step, write_step

#: ASME B36.10M outside diameters (metres) by NPS.
OD = {"2": 0.0603, "4": 0.1143, "6": 0.1683}
ANGLES = (30, 45, 60, 75)
#: (run NPS, branch NPS): equal and reduced branches.
SIZES = (("4", "4"), ("6", "4"), ("6", "2"))
ORIENTATIONS = ("horizontal", "vertical", "tilted")


def _frame(orientation: str) -> tuple[np.ndarray, np.ndarray]:
    """The run's direction and a unit vector across it the branch leans towards."""
    if orientation == "horizontal":
        return np.array([1.0, 0, 0]), np.array([0, 1.0, 0])  # a branch in the horizontal plane
    if orientation == "vertical":
        return np.array([0, 0, 1.0]), np.array([1.0, 0, 0])
    run = np.array([1.0, 0.5, 0.7]) / np.linalg.norm([1.0, 0.5, 0.7])
    across = np.cross(run, [0.3, -1.0, 0.2])
    return run, across / np.linalg.norm(across)


def _lateral_model(synthetic, angle: float, run_nps: str, branch_nps: str, orientation: str):
    """Run P1 | P2 with a 0.4 m gap centred on J, branch P3 from 0.3 m off J (SCH 40)."""
    run, across = _frame(orientation)
    theta = math.radians(angle)
    branch = math.cos(theta) * run + math.sin(theta) * across
    junction = np.array([2.0, -1.0, 1.5])
    pipes = [
        synthetic.Pipe("P1", tuple(junction - 1.6 * run), tuple(junction - 0.2 * run), OD[run_nps]),
        synthetic.Pipe("P2", tuple(junction + 0.2 * run), tuple(junction + 1.6 * run), OD[run_nps]),
        synthetic.Pipe(
            "P3", tuple(junction + 0.3 * branch), tuple(junction + 1.5 * branch), OD[branch_nps]
        ),
    ]
    from asbuilt.merge import merge_model

    return merge_model(synthetic.report_of(pipes), schedule="40")


def expected_volume(model, samples: int = 400_000, seed: int = 7) -> float:
    """The spool's volume (m^3) without the CAD kernel: a continuous hollow run from P1's start
    to P2's end, and a hollow branch from the lateral's centre to P3's end, outside the run's
    outside, its bore open into the run's."""
    parts = {c.id: c for c in model.components}
    (lateral,) = [c for c in model.components if c.type == "tee"]
    g = lateral.geometry
    start, end = parts["P1"].geometry.start, parts["P2"].geometry.end
    big, bore = g.outer_radius, g.outer_radius - g.wall
    small, small_bore = g.branch_outer_radius, g.branch_outer_radius - g.branch_wall
    axis = (end - start) / np.linalg.norm(end - start)
    branch_far = parts["P3"].geometry.end
    length_b = float(np.linalg.norm(branch_far - g.center))
    b = (branch_far - g.center) / length_b
    run_wall = math.pi * (big**2 - bore**2) * float(np.linalg.norm(end - start))
    # Near the run (the branch cylinder up to where its outside is clear of the run's outside,
    # with room to spare) points are classified; beyond, the branch is its plain wall.
    sin = math.sqrt(max(0.0, 1.0 - float(b @ axis) ** 2))
    near = min(length_b, (big + small) / sin + 0.05)
    rng = np.random.default_rng(seed)
    s = rng.uniform(0.0, near, samples)
    r = small * np.sqrt(rng.uniform(0.0, 1.0, samples))
    phi = rng.uniform(0.0, 2 * math.pi, samples)
    u = np.cross(b, [0.0, 0.0, 1.0] if abs(b[2]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    w = np.cross(b, u)
    points = (
        g.center
        + s[:, None] * b
        + r[:, None] * (np.cos(phi)[:, None] * u + np.sin(phi)[:, None] * w)
    )
    rel = points - start
    rho = np.linalg.norm(rel - (rel @ axis)[:, None] * axis, axis=1)
    in_run_wall = (rho >= bore) & (rho <= big)
    solid_here = (r >= small_bore) & (rho >= bore)  # branch wall, less the run's bore
    cylinder = math.pi * small**2 * near
    correction = cylinder * float(np.mean(solid_here.astype(float) - in_run_wall))
    far = math.pi * (small**2 - small_bore**2) * (length_b - near)
    return run_wall + correction + far


def _step_solids(path: Path) -> list[bool]:
    """Validity of each solid in a STEP file as OCP's plain reader rebuilds it."""
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer

    reader = STEPControl_Reader()
    assert reader.ReadFile(str(path)) == 1  # IFSelect_RetDone
    reader.TransferRoots()
    explorer = TopExp_Explorer(reader.OneShape(), TopAbs_SOLID)
    found = []
    while explorer.More():
        found.append(BRepCheck_Analyzer(explorer.Current()).IsValid())
        explorer.Next()
    return found


@pytest.mark.parametrize("orientation", ORIENTATIONS)
@pytest.mark.parametrize("sizes", SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
@pytest.mark.parametrize("angle", ANGLES)
def test_a_lateral_fuses_into_one_valid_solid_of_the_union_volume(
    tmp_path, synthetic_pipes, angle, sizes, orientation
):
    model = _lateral_model(synthetic_pipes, angle, *sizes, orientation)
    assert sorted(c.type for c in model.components) == ["pipe", "pipe", "pipe", "tee"]
    (spool,) = model.spools
    (lateral,) = [c for c in model.components if c.type == "tee"]
    assert lateral.snap["standard"] is False
    assert lateral.snap["angle_deg"] == pytest.approx(angle, abs=0.5)
    assert lateral.geometry.wall > 0 and lateral.geometry.branch_wall > 0  # hollow, SCH 40
    cad = prepare(model)
    fused = cad.fused_spool(spool.id)
    assert len(fused.Solids()) == 1 and fused.isValid()
    assert fused.Volume() == pytest.approx(expected_volume(model), rel=0.005)
    # the fused body, written to STEP and read back by OCP's reader: still one valid solid
    path = tmp_path / "lateral.step"
    fused.exportStep(str(path))
    assert _step_solids(path) == [True]
    # the model's own STEP (one solid per object, closed faces split): every solid valid
    model_path = tmp_path / "model.step"
    write_step(cad, model_path)
    read = read_step(model_path)
    assert sorted(s.name for s in read) == sorted(spool.components)
    assert [s.name for s in read if not s.valid] == []
