"""Crosses: four pipe ends meeting at one point, two opposite pairs each on one line.

Private helper of :mod:`asbuilt.merge.contiguity` (finding them), :mod:`asbuilt.merge`
(settling their sizes) and :mod:`asbuilt.merge.spool` (building them). Numpy only; metres.

ASME B16.9 tabulates straight tees and crosses in one table ("Dimensions of Straight Tees and
Crosses": C centre-to-end of run, M of outlet) and reducing outlet tees and crosses in another
(Table 8, run x outlet, C and M); manufacturers print them the same way (CCTF "Seamless welding
fittings": "Straight Tees and Crosses", pages 14-15; pipingengineer.org "Butt weld reducing tees
and crosses ... as per ASME B16.9", the page ``catalogs/asme-b16.9-tees.toml`` cites). So a
cross of a run and outlet size has the tee's C and M of that pair (:func:`._fitting_shapes.tee_dims`):
no numbers of its own.

Finding (:func:`find_crosses`, after the tee search): a tee with a pipe end left free on the
side opposite its outlet is a cross when that end and the tee's outlet end are an inline pair
(:func:`.contiguity._evaluate_pair`: parallel within ``intended_angle_deg``, on one line within
the skew tolerance, facing each other within the inline gap; the link's margin when the scan
links the end to one of the tee's pipes) and the end meets the tee's centre square-on as a
branch (:func:`.contiguity._branch_cost`, the tee branch's own test). So both outlets are on
one line, square to the run. An end facing the outlet from the other side whose line misses
it (outlets, or the run pair taken as outlets, offset by more than the skew tolerance) stays
free, with a note saying why; the tee is kept (the behaviour before crosses were built).

Sizes (:func:`settle_crosses`, once the pipes' sizes are snapped): the run is the pair with the
largest pipe (of equal pairs, the one with the first pipe in scan order); the outlets must be
of one size, no larger than the run's. Otherwise the cross falls back to a tee of the run and the
larger outlet, and the other outlet stays free with a note: ASME B16.9 crosses have two outlets
of one size.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from .contiguity import Joint
    from .spool import _Builder

__all__ = ["find_crosses", "settle_crosses", "build_cross", "CROSS_SOURCE_NOTE"]

#: The note every cross gets on where its dimensions come from.
CROSS_SOURCE_NOTE = (
    "cross: ASME B16.9 tabulates crosses with tees (straight tees and crosses, reducing outlet "
    "tees and crosses), so it has the tee's C and M for its run and outlet sizes"
)


def _tee_center(jt, pts, out, centers, axes):
    """``(centre (3,) m, run axis (3,), run OD index)`` of a tee joint."""
    from .contiguity import line_closest_points

    branch = jt.ends[-1]
    if jt.through is None:
        first = jt.ends[0]
        anchor, run_axis = pts[first], axes[first[0]]
    else:
        anchor, run_axis = centers[jt.through], axes[jt.through]
    _, t, _, _ = line_closest_points(pts[branch], out[branch], anchor, run_axis)
    return anchor + t * run_axis, run_axis


def find_crosses(
    joints: Sequence[Joint],
    used: set,
    pts: np.ndarray,
    out: np.ndarray,
    centers: np.ndarray,
    axes: np.ndarray,
    ods: np.ndarray,
    tol,
    slack: np.ndarray,
    linked_pairs: set,
    notes: list,
    names: Sequence[str],
    noted: set | None = None,
) -> list[Joint]:
    """The joints with each tee that has a free end opposite its outlet made a cross.

    Parameters
    ----------
    joints : sequence of contiguity.Joint
        The joints after the tee search.
    used : set of End
        The pipe ends joined so far; a cross's fourth end is added.
    pts, out : ndarray, shape (n, 2, 3)
        Pipe end points (metres) and outward unit directions.
    centers, axes : ndarray, shape (n, 3)
        Pipe centres (metres) and unit axes.
    ods : ndarray, shape (n,), metres
        Outside diameters.
    tol : Tolerances
    slack : ndarray, shape (n,), metres
        Each pipe's shot slack.
    linked_pairs : set of (int, int)
        The scan's links (pipe indices, smaller first).
    notes : list
        Receives ``(pipe indices, sentence)`` for an end facing a tee's outlet off its line.
    names : sequence of str
        Pipe ids.
    noted : set, optional
        Receives ``frozenset((a, b))`` of the pipe pairs those notes name (a link between them
        needs no second note).

    Returns
    -------
    list of contiguity.Joint
        A cross is kind ``"cross"``: its ends the two run ends then the two outlet ends (the
        tee's outlet first), or with ``through`` set (a pipe running through) the two outlet
        ends.
    """
    from .contiguity import Joint, _branch_cost, _evaluate_pair, skew_tolerance

    joints = list(joints)
    free = [(i, k) for i in range(len(pts)) for k in (0, 1) if (i, k) not in used]
    if not free:
        return joints
    for index, jt in enumerate(joints):
        if jt.kind != "tee" or len(jt.ends) not in (1, 3):
            continue
        branch = jt.ends[-1]
        center, run_axis = _tee_center(jt, pts, out, centers, axes)
        run_od = float(max(ods[p] for p in jt.pipes if p != branch[0]))
        best = near = None
        for end in free:
            if end in used or end[0] in jt.pipes:
                continue
            if float(out[end] @ out[branch]) > -np.cos(np.radians(tol.intended_angle_deg)):
                continue  # not facing the outlet from the run's other side
            linked = any((min(end[0], p), max(end[0], p)) in linked_pairs for p in jt.pipes)
            reach = 2 * run_od + tol.joint_distance + float(slack[end[0]])
            if float(np.linalg.norm(pts[end] - center)) > reach + (0.5 if linked else 0.0):
                continue
            if float(out[end] @ (center - pts[end])) <= 0:
                continue  # pointing away from the tee
            pair = _evaluate_pair(
                *branch, *end, pts, out, axes, ods, tol, relaxed=linked, slack=slack
            )
            meets = _branch_cost(
                end, center, run_axis, run_od, pts, out, axes, ods, tol, slack,
                extra=0.5 if linked else 0.0,
            )  # fmt: skip
            if pair is not None and pair.kind == "inline" and meets is not None:
                if best is None or pair.cost + meets < best[0]:
                    best = (pair.cost + meets, end)
            elif near is None:
                near = end
        if best is not None:
            end = best[1]
            used.add(end)
            joints[index] = Joint("cross", jt.ends + (end,), jt.through, jt.explicit or linked)
        elif near is not None:
            rel = pts[near] - pts[branch]
            apart = max(
                float(np.linalg.norm(rel - (rel @ axes[q]) * axes[q])) for q in (branch[0], near[0])
            )
            allowed = skew_tolerance(0.5 * ods[branch[0]], 0.5 * ods[near[0]])
            others = [p for p in jt.pipes if p != branch[0]]
            run = " and ".join(names[p] for p in others)
            why = (
                f"their axes are {apart * 1000:.0f} mm apart (a cross's opposite outlets must be "
                f"on one line within {allowed * 1000:.0f} mm)"
                if apart > allowed
                else "it does not meet the tee's centre square-on"
            )
            if noted is not None:
                noted.update(frozenset((near[0], p)) for p in jt.pipes)
            notes.append(
                (
                    (near[0], branch[0], *others),
                    f"{names[near[0]]} faces {names[branch[0]]} across the run of {run} as a "
                    f"cross's fourth pipe would, but {why}: no cross is built; the tee "
                    f"{'-'.join(names[p] for p in jt.pipes)} is kept and {names[near[0]]} is not "
                    "joined there",
                )
            )
    return joints


def settle_crosses(joints: Sequence[Joint], od: Sequence[float], names: Sequence[str], notes):
    """The crosses with the run pair first, or made tees where the outlets differ in size.

    Parameters
    ----------
    joints : sequence of contiguity.Joint
    od : sequence of float, metres
        Each pipe's built (snapped) outside diameter.
    names : sequence of str
        Pipe ids.
    notes : list
        Receives ``(pipe indices, sentence)`` for each cross made a tee.

    Returns
    -------
    list of contiguity.Joint
        The run is the pair with the largest pipe (of equal pairs, the one with the first
        pipe); a cross whose
        outlets differ in size, or (through a pipe) are larger than the pipe running through, is
        a tee of the run and the larger outlet.
    """
    from .contiguity import Joint

    result = []
    for jt in joints:
        if jt.kind != "cross":
            result.append(jt)
            continue
        if jt.through is None:
            # the larger pair is the run; of equal pairs, the one with the first pipe (scan
            # order), so that an equal cross is named the same whichever tee was found first
            pairs = sorted(
                [jt.ends[:2], jt.ends[2:]],
                key=lambda pair: (-round(max(od[e[0]] for e in pair), 9), min(e[0] for e in pair)),
            )
            run, outlets = pairs
            run_od = max(od[e[0]] for e in run)
        else:
            run, outlets = (), jt.ends
            run_od = od[jt.through]
        a, b = (e[0] for e in outlets)
        larger = max(od[a], od[b])
        if abs(od[a] - od[b]) <= 1e-9 and larger <= run_od + 1e-9:
            result.append(Joint("cross", (*run, *outlets), jt.through, jt.explicit))
            continue
        keep, drop = (outlets[0], outlets[1]) if od[a] >= od[b] else (outlets[1], outlets[0])
        run_pipes = (jt.through,) if jt.through is not None else tuple(e[0] for e in run)
        run_ids = " and ".join(names[p] for p in run_pipes)
        why = (
            f"its outlets {names[a]} and {names[b]} are of different sizes (OD "
            f"{od[a] * 1000:.1f} and {od[b] * 1000:.1f} mm; ASME B16.9 crosses have two outlets "
            "of one size)"
            if abs(od[a] - od[b]) > 1e-9
            else f"its outlets are larger than {run_ids}, which runs through"
        )
        notes.append(
            (
                (*run_pipes, a, b),
                f"{', '.join(names[p] for p in run_pipes)}, {names[a]} and {names[b]} meet as "
                f"a cross, but {why}: the tee {'-'.join(names[p] for p in (*run_pipes, keep[0]))} "
                f"is built and {names[drop[0]]} is not joined there (a tee and a reducer, or "
                "check the sizes)",
            )
        )
        result.append(Joint("tee", (*run, keep), jt.through, jt.explicit))
    return result


def build_cross(b: _Builder, joint: Joint):
    """The cross at ``joint`` as the spool builder's items (the tee builder's pattern):
    ``[("cross", name, Cross, run PipeSpec, snap, through, at), *reducer items]``; the pipes'
    ends are moved to the fitting's (a pipe running through is split)."""
    from asbuilt.model import Cross

    from ._fitting_shapes import ELBOW45_WINDOW_DEG, same_size, size_text, tee_dims
    from .contiguity import line_closest_points
    from .spool import _run_reducer, _verdict

    (c, kc), (d, kd) = joint.ends[-2:]
    pc, pd = b.pipes[c], b.pipes[d]
    oc = b.out[c, kc]  # out of pipe c, towards the centre
    small = None
    if joint.through is None:
        (i, ki), (j, kj) = joint.ends[:2]
        pi, pj = b.pipes[i], b.pipes[j]
        run_dir, anchor = b.out[i, ki], b.base[i, ki]
        if not same_size(pi, pj):
            small = pj if pi.od > pj.od else pi  # a reducer follows on the smaller side
    else:
        i = joint.through
        pi = pj = b.pipes[i]
        run_dir, anchor = pi.axis, b.base[i, 0]
    run = pj if small is pi else pi
    _, t, _, _ = line_closest_points(b.base[c, kc], oc, anchor, run_dir)
    center = anchor + t * run_dir
    c_run, c_out, paired = tee_dims(run, pc)
    hollow = bool(run.wall and pc.wall and pd.wall)
    geometry = Cross(
        center=center,
        run_start=center - c_run * run_dir,
        run_end=center + c_run * run_dir,
        branch_start=center - c_out * oc,
        branch_end=center + c_out * oc,
        outer_radius=0.5 * run.od,
        branch_outer_radius=0.5 * pc.od,
        wall=run.wall if hollow else 0.0,
        branch_wall=pc.wall if hollow else 0.0,
    )
    b.ends[c, kc], b.ends[d, kd] = geometry.branch_start, geometry.branch_end
    b.allowance[c, kc] = b.allowance[d, kd] = float(c_out)
    notes = [*run.dims.notes, CROSS_SOURCE_NOTE]
    source, standard = run.dims.source, True
    if paired:
        notes.append(
            f"reducing outlet: NPS {run.nominal} x {pc.nominal} cross of {source} (C "
            f"{c_run * 1000:.0f} mm, M {c_out * 1000:.0f} mm, the reducing tee's)"
        )
    elif not same_size(run, pc):
        notes.append("reducing outlet: built with the straight cross's dimensions of the run size")
    square = float(np.degrees(np.arccos(min(1.0, abs(float(oc @ run_dir))))))
    pipes = {i, j, c, d} if joint.through is None else {i, c, d}
    if abs(square - 90.0) > ELBOW45_WINDOW_DEG:
        standard = False
        source = f"{source}, outlets at {square:.0f} degrees (non-standard)"
        text = (
            f"{pc.id} and {pd.id} meet the run of {pi.id} at {square:.0f} degrees: ASME B16.9 "
            "crosses are square (90 degrees); built as a cross of its dimensions with the "
            "outlets at that angle, which is not a B16.9 fitting"
        )
        notes.append(text)
        b.note(pipes, text)
    items = []
    if joint.through is None:
        b.ends[i, ki], b.ends[j, kj] = geometry.run_start, geometry.run_end
        b.allowance[i, ki] = b.allowance[j, kj] = float(c_run)
        name = f"{pi.id}-{pj.id}-{pc.id}-{pd.id}"
        for end in ((i, ki), (j, kj), (c, kc), (d, kd)):
            b.fitting_at[end] = f"cross {name}"
        connects = [pi.id, pj.id, pc.id, pd.id]
        if small is not None:
            end = (j, kj) if small is pj else (i, ki)
            port = geometry.run_end if small is pj else geometry.run_start
            items = _run_reducer(b, name, run, small, end, port, tuple(pipes))
            notes.append(
                f"the run changes from {size_text(run)} to {size_text(small)} here: cross of the "
                + (
                    "larger run, followed by a reducer"
                    if items
                    else "larger run; no reducer follows"
                )
            )
        at = None
    else:
        at = b.param(i, center)
        b.splits.setdefault(i, []).append((at, float(c_run)))
        b.fitting_at[c, kc] = b.fitting_at[d, kd] = "a cross"
        name = None  # named after the pieces are known
        connects = [pi.id, pc.id, pd.id]
    snap = {
        "status": "fitting",
        "dimensions": source,
        "standard": _verdict(standard, run.dims),
        "connects": connects,
        "notes": notes,
    }
    return [("cross", name, geometry, run, snap, joint.through, at), *items]
