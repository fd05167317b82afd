"""Pipe ends left loose at a fitting or another pipe: found after the fittings are built.

Merging joins each pipe end to at most one other (:mod:`.contiguity`): a fourth pipe at a tee
that does not meet it as a cross (:mod:`.crosses`: outlets off one line or of two sizes), a pipe
ending on another's side at an angle no tee makes, or near a pipe end another joint already
took, is left unjoined. A linked pair gets a note from contiguity; an unlinked one was silent.

:func:`loose_ends` finds every open pipe end (no other component's port within
:data:`PORT_TOUCH`) whose pipe, continued straight on by ``reach`` (``joint_distance``) plus its
shot spacing (the last shot may be that far short of the real end, as contiguity allows), would
run into another pipe or fitting: the swept pipe and the other component's body (capsules around
their centrelines: a tee's run and outlet, an elbow's arc in chords, a reducer at its larger
radius) come within the sum of their outer radii. A pipe that passes above or beside the other,
or runs alongside it, does not: nor one lying side by side with it, touching it or fitted into
it along its length (within :data:`IN_LINE_DEG`, off its line, still within the sum of their
radii ``reach`` back from the end: the clash rule's, not a branch). Pipes merging joined (a
lateral's three pipes, a fitting it could not build) are not loose to each other; a pair
contiguity's notes already name (a link it could not make) is recorded with ``noted`` true, so
the rules report it once.

An open end that runs into nothing within that reach may still point at another pipe's open end
further on: the two axes meet ahead of both ends (an elbow the scan did not reach: one pipe's
shots stopped short where the station could not see it), or the other pipe continues its line
(an unscanned stretch or a valve). Merging does not join such ends (beyond ``reach`` a meeting
is as likely a coincidence as a joint, and a scan link joins them), but the pair is recorded,
with the ``corner`` where the axes meet, so the rule can ask. Both ends must be open, their axes
meet within the larger pipe's outer radius, and the meeting lie at most :data:`FACING_REACH`
past either end.

Each loose end becomes a record on its pipe's ``snap["loose_ends"]`` (docs/merging.md), read by
the rule ``unjoined-end`` (AB304).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np
from scipy.spatial import cKDTree

from asbuilt.model import Bend, Component, Cross, Reducer, Straight, Tee
from asbuilt.tolerances import DEFAULT_TOLERANCES

from .contiguity import ELBOW_MAX_DEG, best_for_link, line_closest_points, segment_distance
from .ports import ports

__all__ = ["FACING_REACH", "IN_LINE_DEG", "PORT_TOUCH", "loose_ends", "bodies"]

#: Farthest (m) past an open end that another open end's axis may meet it and be recorded: an
#: operator's missed stretch of a pipe (a riser's hidden foot, a run behind a column) is
#: seldom longer; two unrelated lines meeting within a pipe's radius are rarer the nearer.
FACING_REACH = 2.0

#: Bends (degrees) below this are in line (the other pipe continues this one's line).
IN_LINE_DEG = 10.0

#: Two ports closer than this (metres) are joined (merging makes them equal to rounding).
PORT_TOUCH = 1e-3

#: Chords an elbow's arc is split into for the distance test (a 90 degree bend: 11.25 degrees
#: each, within 0.2% of its bend radius of the arc).
_ARC_CHORDS = 8

#: Spacing (m) of the points sampled along components to find those near an end.
_SAMPLE_STEP = 0.25

_PIPING = ("pipe", "coupling", "elbow", "tee", "cross", "reducer")


def bodies(component: Component) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """Capsules ``(a, b, radius)`` (metres) around a piping component's centreline."""
    g = component.geometry
    if isinstance(g, Tee | Cross):
        return [
            (g.run_start, g.run_end, float(g.outer_radius)),
            *((g.center, end, float(g.branch_outer_radius)) for end in g.outlets),
        ]
    if isinstance(g, Reducer):
        return [(g.start, g.end, float(max(g.outer_radius_start, g.outer_radius_end)))]
    if isinstance(g, Bend):
        radius = float(max(g.outer_radius, g.outer_radius_end or 0.0))
        u, w = g.start - g.center, g.end - g.center
        bend = float(np.linalg.norm(u))
        u = u / bend
        v = w - (w @ u) * u
        v = v / np.linalg.norm(v)
        angle = float(np.arctan2(w @ v, w @ u))
        t = np.linspace(0.0, angle, _ARC_CHORDS + 1)
        arc = g.center + bend * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * v)
        return [(arc[k], arc[k + 1], radius) for k in range(_ARC_CHORDS)]
    if isinstance(g, Straight):
        return [(g.start, g.end, float(g.outer_radius))]
    return []


def _point_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance (m) from ``point`` to the segment ``a b``."""
    d = b - a
    t = float(np.clip((point - a) @ d / max(float(d @ d), 1e-24), 0.0, 1.0))
    return float(np.linalg.norm(point - a - t * d))


def _surface_gap(point: np.ndarray, capsules) -> float:
    """Distance (m) from ``point`` to the nearest capsule's surface, 0 inside."""
    return max(0.0, min(_point_distance(point, a, b) - radius for a, b, radius in capsules))


def _angle_deg(u: np.ndarray, capsules, point: np.ndarray) -> float:
    """Angle (degrees, 0-90) between direction ``u`` and the axis of the capsule nearest
    ``point``."""
    a, b, _ = min(capsules, key=lambda c: _point_distance(point, c[0], c[1]))
    axis = (b - a) / max(float(np.linalg.norm(b - a)), 1e-12)
    return float(np.degrees(np.arccos(min(1.0, abs(float(u @ axis))))))


def _alongside(pipe: Straight, point, out, reach: float, capsule) -> bool:
    """Whether ``capsule`` ``(a, b, radius)`` runs beside the pipe ``pipe`` at its open end
    ``point`` (3,) m (``out`` its outward unit direction) rather than ahead of it: within
    :data:`IN_LINE_DEG` of its axis, off its line (axes farther apart than the smaller radius),
    and still within the sum of their radii ``reach`` metres back along the pipe. Such pipes lie
    side by side, touching or fitted into each other along their length (the clash rule's
    business), not one ending on the other; a pipe converging on another's side and ending
    there leaves it within that reach."""
    a, b, rad = capsule
    axis = b - a
    length = float(np.linalg.norm(axis))
    if length == 0:
        return False
    axis = axis / length
    if abs(float(axis @ out)) < np.cos(np.radians(IN_LINE_DEG)):
        return False
    rel = point - a
    lateral = float(np.linalg.norm(rel - (rel @ axis) * axis))
    if lateral <= min(float(pipe.outer_radius), rad):
        return False  # on one line: a pipe ending in line with (or into) the other
    back = min(reach, float(np.linalg.norm(pipe.end - pipe.start)))
    return _point_distance(point - back * out, a, b) <= float(pipe.outer_radius) + rad


def loose_ends(
    components: Sequence[Component],
    *,
    reach: float,
    slack: Mapping[str, float] | None = None,
    joined: Iterable[frozenset] = (),
    noted: Iterable[frozenset] = (),
    bend_limit_deg: float = ELBOW_MAX_DEG + 10.0,
    tolerances=None,
) -> dict[str, list[dict]]:
    """Open pipe ends that run into another pipe or fitting within ``reach`` (+ slack).

    Parameters
    ----------
    components : sequence of Component
        Merged pipes and fittings (others are ignored).
    reach : float
        How far (m) each open end is continued straight on (``Tolerances.joint_distance``).
    slack : mapping, optional
        Scan object id to how far (m) its fitted ends may fall short of the real ones.
    joined, noted : iterables of frozenset of scan object ids
        Pairs merging joined (never loose to each other) and pairs contiguity's notes name.
    bend_limit_deg : float
        Largest bend (degrees) of an elbow between two ends that face each other from afar
        (contiguity's ``elbow_bend_limit``; the default is its value at the default
        ``intended_angle_deg``, 10).
    tolerances : Tolerances, optional
        Merging's tolerances, for whether a link would join two facing ends (default
        :data:`asbuilt.tolerances.DEFAULT_TOLERANCES`).

    Returns
    -------
    dict
        Pipe component id to its records: ``end`` (``"start"`` or ``"end"``), ``at`` (the end,
        [x, y, z] m), ``touches`` (the component's id), ``touches_type``, ``touches_pipes``
        (the scan pipes it is or joins), ``gap`` (m from the end to its surface, 0 touching or
        inside), ``angle_deg`` (between the pipe and the nearest axis of it, 0-90) and
        ``noted``. An end meeting another open end beyond the reach (see the module) has
        ``gap`` the distance (m) from the end to where the axes meet, ``corner`` that point
        ([x, y, z] m), ``beyond`` how far (m) past the other pipe's end it lies, and
        ``bend_deg`` (0: the other pipe continues this one's line) and ``linkable`` (whether
        merging would join the two if the scan linked them: :func:`link_would_join`).
    """
    slack = dict(slack or {})
    joined, noted = set(joined), set(noted)
    piping = [c for c in components if c.type in _PIPING]
    source_of = {c.id: (c.sources[0] if c.sources else c.id) for c in piping if c.type == "pipe"}

    def scan_pipes(comp: Component) -> list[str]:
        if comp.type == "pipe":
            return [source_of[comp.id]]
        connects = (comp.snap or {}).get("connects") or ()
        return list(dict.fromkeys(source_of.get(str(k), str(k)) for k in connects))

    port_points = [np.asarray(p, float) for c in piping for p, _ in ports(c)]
    port_owner = [c.id for c in piping for _ in ports(c)]
    port_tree = cKDTree(np.array(port_points).reshape(-1, 3))
    capsules = {c.id: bodies(c) for c in piping}
    # points every _SAMPLE_STEP along every body: a k-d tree of them finds the components near
    # an end whatever their length
    samples, owners, widest = [], [], 0.0
    for n, comp in enumerate(piping):
        for a, b, rad in capsules[comp.id]:
            count = max(2, int(np.ceil(float(np.linalg.norm(b - a)) / _SAMPLE_STEP)) + 1)
            t = np.linspace(0.0, 1.0, count)[:, None]
            samples.append(a + t * (b - a))
            owners += [n] * count
            widest = max(widest, rad)
    sample_tree = cKDTree(np.concatenate(samples))
    # open pipe ends (no other component's port at them): (pipe, which end, point, outward)
    open_ends = [
        (comp, k, np.asarray(point, float), np.asarray(out, float))
        for comp in piping
        if comp.type == "pipe"
        for k, (point, out) in enumerate(ports(comp))
        if not any(port_owner[q] != comp.id for q in port_tree.query_ball_point(point, PORT_TOUCH))
    ]
    open_tree = cKDTree(np.array([end[2] for end in open_ends]).reshape(-1, 3))
    found: dict[str, list[dict]] = {}
    for comp, k, point, out in open_ends:
        own = source_of[comp.id]
        radius = float(comp.geometry.outer_radius)
        length = reach + float(slack.get(own, 0.0))
        tip = point + length * out
        near = sample_tree.query_ball_point(
            0.5 * (point + tip), 0.5 * length + radius + widest + _SAMPLE_STEP
        )
        best = None
        for other in (piping[n] for n in sorted({owners[q] for q in near})):
            if other.id == comp.id:
                continue
            theirs = scan_pipes(other)
            if own in theirs or any(frozenset((own, q)) in joined for q in theirs):
                continue  # a piece of the same pipe, or joined to this pipe by merging
            hits = [
                (a, b, rad)
                for a, b, rad in capsules[other.id]
                if segment_distance(point, tip, a, b) <= radius + rad
            ]
            if not hits or all(
                _alongside(comp.geometry, point, out, length, capsule) for capsule in hits
            ):
                continue  # nothing ahead, or a pipe it runs beside (side by side, overlapping)
            gap = _surface_gap(point, capsules[other.id])
            rank = (gap, other.type == "pipe")  # a fitting before the pipe it joins
            if best is None or rank < best[0]:
                best = (rank, other, theirs)
        if best is None:
            record = _facing_end(
                comp,
                own,
                point,
                out,
                open_ends,
                open_tree,
                scan_pipes,
                joined,
                reach,
                bend_limit_deg,
            )
            if record is not None:
                record["end"] = ("start", "end")[k]
                record["noted"] = any(frozenset((own, q)) in noted for q in record["touches_pipes"])
                # as far apart as a scan link may bridge (contiguity's rule): linking them in
                # the scan would have merging join them
                other = next(c for c in piping if c.id == record["touches"])
                record["linkable"] = link_would_join(
                    comp,
                    other,
                    (slack.get(own, 0.0), slack.get(source_of.get(other.id, ""), 0.0)),
                    tolerances,
                )
                found.setdefault(comp.id, []).append(record)
            continue
        (gap, _), other, theirs = best
        found.setdefault(comp.id, []).append(
            {
                "end": ("start", "end")[k],
                "at": [float(x) for x in point],
                "touches": other.id,
                "touches_type": other.type,
                "touches_pipes": theirs,
                "gap": float(gap),
                "angle_deg": _angle_deg(out, capsules[other.id], point),
                "noted": any(frozenset((own, q)) in noted for q in theirs),
            }
        )
    return found


def _facing_end(comp, own, point, out, open_ends, open_tree, scan_pipes, joined, reach, limit):
    """The record of the open end (of another pipe, not joined to this one) whose axis meets
    this open end's ``point`` (3,) m, ``out`` (3,) unit, ahead of both ends within
    :data:`FACING_REACH`, or that continues its line: the nearest such meeting, or None."""
    radius = float(comp.geometry.outer_radius)
    best = None
    for q in open_tree.query_ball_point(point, 2.0 * FACING_REACH):
        other, _, there, their_out = open_ends[q]
        if other.id == comp.id:
            continue
        theirs = scan_pipes(other)
        if own in theirs or any(frozenset((own, p)) in joined for p in theirs):
            continue
        within = max(radius, float(other.geometry.outer_radius))
        bend = float(np.degrees(np.arccos(np.clip(-float(out @ their_out), -1.0, 1.0))))
        if bend < IN_LINE_DEG:
            rel = there - point
            ahead = float(rel @ out)
            lateral = float(np.linalg.norm(rel - ahead * out))
            if not (reach < ahead <= FACING_REACH and lateral <= within):
                continue
            distance, beyond, corner = ahead, 0.0, there
        elif bend <= limit:
            s, t, qa, qb = line_closest_points(point, out, there, their_out)
            if float(np.linalg.norm(qa - qb)) > within:
                continue
            if not (-reach <= s <= FACING_REACH and -reach <= t <= FACING_REACH):
                continue
            if max(s, t) <= reach:
                continue  # within contiguity's reach: its joint, or its note
            distance, beyond, corner = s, t, 0.5 * (qa + qb)
        else:
            continue
        if best is None or max(distance, beyond) < best[0]:
            best = (max(distance, beyond), other, theirs, distance, beyond, corner, bend)
    if best is None:
        return None
    _, other, theirs, distance, beyond, corner, bend = best
    return {
        "at": [float(x) for x in point],
        "touches": other.id,
        "touches_type": other.type,
        "touches_pipes": theirs,
        "gap": float(max(distance, 0.0)),
        "angle_deg": float(min(bend, 180.0 - bend)),
        "corner": [float(x) for x in corner],
        "beyond": float(max(beyond, 0.0)),
        "bend_deg": float(bend),
    }


def link_would_join(a: Component, b: Component, slack, tolerances=None) -> bool:
    """Whether merging would join the straight pipes ``a`` and ``b`` if the scan linked them:
    contiguity's joint search for a linked pair (:func:`asbuilt.merge.contiguity.best_for_link`,
    its limits widened by ``LINK_MARGIN``) finds an inline or elbow joint between their ends.

    ``slack`` is the two pipes' slack (metres, as merging computes it from their shots).
    """
    tol = DEFAULT_TOLERANCES if tolerances is None else tolerances
    pts = np.array([[a.geometry.start, a.geometry.end], [b.geometry.start, b.geometry.end]], float)
    axes = pts[:, 1] - pts[:, 0]
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    out = np.stack([-axes, axes], axis=1)
    ods = 2.0 * np.array([a.geometry.outer_radius, b.geometry.outer_radius], float)
    found = best_for_link(0, 1, pts, out, axes, ods, tol, np.asarray(slack, float))
    return found is not None and found.kind != "oblique"
