"""Laterals (wyes): a branch joining an inline pair of run pipes at an oblique angle.

Private helper of :mod:`asbuilt.merge.spool`. No catalog has butt-weld laterals (ASME B16.9
makes square tees only), so a lateral is built from the measured pipe ends as a tee-shaped
fitting (component type ``"tee"``, :class:`~asbuilt.model.Tee` geometry with its branch at the
lateral's angle, ``standard`` False): the run fills the gap between the two run pipes' ends and
the branch runs from the centre ``J`` (where the branch axis meets the run axis) to the branch
pipe's end.

Each fitting end must lie beyond the saddle (where the branch's outside meets the run's) by
:data:`LATERAL_CLEARANCE`, or the pipe welded there would overlap the branch or the run and
the spool would not fuse into one body whose bore is open. For a branch of outer radius ``r``
at angle ``theta`` to a run of outer radius ``R`` (distances from ``J``):

* the branch's outside leaves the run's at ``(R + r cos theta) / sin theta`` along the branch;
* the saddle reaches ``R cot theta + r / sin theta`` along the run on the branch's side
  (the crotch), and the branch cylinder's end disk at ``J`` reaches ``r sin theta`` the other
  way (the saddle's heel, at ``R cot theta - r / sin theta``, lies within that).

A pipe whose measured end lies closer to ``J`` is cut back to that (noted as any trim is);
farther, the fitting fills up to it (the pipes keep their measured ends). Numpy only; metres.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ._fitting_shapes import size_text, tee_solid
from .contiguity import Joint, line_closest_points

if TYPE_CHECKING:
    from .spool import _Builder

__all__ = ["LATERAL_CLEARANCE", "lateral_reach", "build_lateral"]

#: Length (metres) of plain cylinder a lateral keeps between its saddle and each weld.
LATERAL_CLEARANCE = 0.025


def lateral_reach(run_radius: float, branch_radius: float, angle_deg: float):
    """``(crotch, heel, branch)``: how far (metres) from the centre a lateral's shape reaches
    along the run on the branch's side, along the run on the other side, and along the branch
    before its outside leaves the run's (no clearance added); ``angle_deg`` in (0, 90]."""
    theta = np.radians(angle_deg)
    sin, cos = float(np.sin(theta)), float(np.cos(theta))
    crotch = run_radius * cos / sin + branch_radius / sin
    heel = max(branch_radius * sin, branch_radius / sin - run_radius * cos / sin)
    branch = (run_radius + branch_radius * cos) / sin
    return crotch, heel, branch


def build_lateral(b: _Builder, joint: Joint):
    """The lateral at ``joint`` (kind ``"lateral"``: two run ends, then the branch end) as the
    spool builder's items: ``[("tee", name, Tee, run PipeSpec, snap)]``; the pipes' ends are
    moved to the fitting's."""
    (i, ki), (j, kj), (bi, bk) = joint.ends
    pi, pj, pb = b.pipes[i], b.pipes[j], b.pipes[bi]
    run_dir = b.out[i, ki]  # from pipe i's end towards pipe j
    ob = b.out[bi, bk]  # the branch end's outward direction: towards the run
    anchor = b.base[i, ki]
    _, t, _, _ = line_closest_points(b.base[bi, bk], ob, anchor, run_dir)
    center = anchor + t * run_dir
    branch_dir = -ob
    cos = float(branch_dir @ run_dir)
    angle = float(np.degrees(np.arccos(min(1.0, abs(cos)))))
    run = pi if pi.od >= pj.od else pj
    crotch, heel, reach = lateral_reach(0.5 * run.od, 0.5 * pb.od, angle)
    ahead, behind = (crotch, heel) if cos >= 0 else (heel, crotch)
    # run ends: the measured ends, or farther out to clear the saddle
    at_i = min(float((b.base[i, ki] - center) @ run_dir), -(behind + LATERAL_CLEARANCE))
    at_j = max(float((b.base[j, kj] - center) @ run_dir), ahead + LATERAL_CLEARANCE)
    at_b = max(float((b.base[bi, bk] - center) @ branch_dir), reach + LATERAL_CLEARANCE)
    geometry = tee_solid(
        center,
        center + at_i * run_dir,
        center + at_j * run_dir,
        center + at_b * branch_dir,
        run,
        pb,
    )
    name = f"{pi.id}-{pj.id}-{pb.id}"
    b.ends[i, ki], b.ends[j, kj] = geometry.run_start, geometry.run_end
    b.ends[bi, bk] = geometry.branch_end
    for end in ((i, ki), (j, kj), (bi, bk)):
        b.fitting_at[end] = f"lateral {name}"
        b.allowance[end] = 0.0
    # (the pipes' own note, from finding the joint, says the same: contiguity._laterals)
    notes = [
        f"{pb.id} joins the run of {pi.id} and {pj.id} at {angle:.0f} degrees: a lateral (wye), "
        "which no catalog here has; built as a tee-shaped fitting with its branch at that "
        "angle, from the measured pipe ends (non-standard)"
    ]
    if abs(pi.od - pj.od) > 1e-9 and pi.run != pj.run:
        small = pj if run is pi else pi
        notes.append(
            f"the run changes from {size_text(run)} to {size_text(small)} here: built with the "
            "larger run's size throughout (no reducing lateral)"
        )
    snap = {
        "status": "fitting",
        "dimensions": "measured pipe ends (no catalog lateral; non-standard)",
        "standard": False,
        "angle_deg": angle,
        "connects": [pi.id, pj.id, pb.id],
        "notes": notes,
    }
    return [("tee", name, geometry, run, snap)]
