"""Which pipes are joined, and how: from the scan's ``links`` and inferred from geometry.

Pipes are lines with two ends. Two pipe ends are a joint when

* their axes are nearly parallel (within ``Tolerances.intended_angle_deg``), nearly the same line
  (lateral offset within the skew tolerance of 0, or of the difference of the two fitted radii:
  an eccentric reducer's offset) and the ends face each other with a gap no larger
  than twice ``joint_distance`` plus twice the larger OD (room for a reducer or the run of a tee): an
  **inline** joint (butt weld, reducer or the run of a tee);
* or their axes are nearly coplanar (closest distance within the skew tolerance) and meet at a
  point that lies ahead of both ends by no more than the bend's centre-to-end plus
  ``joint_distance``: an **elbow** (the bend's centre-to-end is estimated with a long-radius bend,
  ``R = 1.5 x OD``, before sizes are known).

Each allowance grows by the pipe's ``slack``: how far its fitted end may fall short of the real
end because the scan's shots are sparse (merge passes the coarsest spacing of the pipe's inlier
shots along its axis: the last shot may be up to one spacing from the end).

The skew tolerance is ``max(0.5 x the smaller outer radius, 10 mm)``: sparse fits place an axis
to a few millimetres, and pipes that miss each other by more than half a radius do not meet.

Candidates come from a k-d tree on the end points (so 1,000 pipes merge in about a second),
best first (an inline pair by its gap, an elbow by its ends' distances from where the elbow
would end); each end joins at most one other end. An inline pair with a third end whose axis
meets it square-on is taken first, as a **tee** (stronger evidence than an elbow between two of
those ends); then the other pairs. A pipe end left over whose axis meets an inline joint
square-on becomes the branch of a **tee** there; one whose axis meets the inside
of another pipe square-on (within ``intended_angle_deg`` of 90 degrees) becomes the branch of a
tee that splits that pipe. ``links`` in the scan are honoured first, with distance limits
widened by :data:`LINK_MARGIN`: a linked run with a linked square-on branch is a tee, and so
is a linked elbow one of whose ends continues straight into an unlinked pipe (inline by the
unlinked limits) while the other meets that joint square-on (links say which pipes are
contiguous, not that the others are not); a linked run with an oblique third end is a lateral
as unlinked. A linked pair no fitting or butt joint realises (axes that do not meet, a bend
beyond an elbow, an end another joint took) gets a note saying why and is kept as kind
``link``: one size estimate, but no fitting and no spool together. A link whose ends form no
inline pair and no bend even within the widened limits, and whose pipes lie farther apart than
``joint_distance`` + :data:`LINK_MARGIN` (+ slack), is not modelled at all: no fitting is
invented over a gap nobody measured, and a note says why (a linked elbow within its reach is
built however far apart the pipes' segments are).

ASME B16.9 elbows turn 45 or 90 degrees: two ends whose bend would exceed 90 degrees plus
``intended_angle_deg`` are never an elbow. An inline pair with a third end meeting it at an
oblique angle (a **lateral** or wye, which the catalog does not have) becomes one ``lateral``
joint of the three ends (one spool; no butt weld across the lateral's gap), built from the
measured pipe ends (:mod:`.laterals`), with a note; no elbow may take one of their ends.

Last, a tee with a free end opposite its outlet, on the outlet's line and meeting the tee's
centre square-on, becomes a **cross** of the four ends (:mod:`.crosses`).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

from ._axes import line_closest_points, pipe_ends, segment_distance, skew_tolerance
from .crosses import find_crosses
from .crossing import JOINED_BY as _JOINED_BY
from .crossing import (
    End,
    branch_taken,
    cross_note,
    crossed_by,
    crossing_note,
)

__all__ = [
    "End",
    "Joint",
    "elbow_bend_limit",
    "find_joints",
    "line_closest_points",
    "pipe_ends",
    "segment_distance",
    "skew_tolerance",
]

#: Largest slack (metres) a pipe end may get: shots sparser than this cannot place a joint.
SLACK_CAP = 2.0

#: Spacing (metres) of the points sampled along each pipe to find tees in the middle of pipes.
SAMPLE_STEP = 0.5

#: How much farther (metres) than an inferred joint allows the ends of pipes the scan links may
#: lie: the operator vouches for contiguity the scan could not show (an end hidden behind a
#: support, a few missed shots). A longer gap holds a part nobody measured (a valve, a spool
#: piece); it is reported, never bridged by an invented fitting.
LINK_MARGIN = 0.5

#: Largest elbow bend (degrees) before ``intended_angle_deg`` is added: ASME B16.9 elbows turn 45
#: or 90 degrees (180 degree returns join parallel pipes, whose axes do not meet).
ELBOW_MAX_DEG = 90.0


@dataclass(frozen=True)
class Joint:
    """A connection found between pipes (indices into the pipe list).

    Attributes
    ----------
    kind : str
        ``"elbow"``, ``"inline"``, ``"tee"``, ``"cross"`` (a tee with a fourth end opposite its
        outlet, :mod:`.crosses`), ``"lateral"`` (an inline pair with a branch
        meeting it obliquely: a wye, built from the measured ends), ``"contact"`` (joined
        without a fitting) or ``"link"`` (the scan links the pair but nothing
        joins them: no fitting and no spool together, only one size estimate; a note says why).
    ends : tuple of End
        elbow/inline/contact: the two joined ends; tee: the run ends (two for a tee at an inline
        joint, none for a tee in the middle of a pipe) followed by the branch end; lateral: the
        two run ends followed by the branch end; cross: the run ends (none through a pipe)
        followed by the two outlet ends.
    through : int or None
        Tee in the middle of a pipe: that pipe's index.
    explicit : bool
        True when the scan's ``links`` named the pair.
    """

    kind: str
    ends: tuple[End, ...]
    through: int | None = None
    explicit: bool = False

    @property
    def pipes(self) -> tuple[int, ...]:
        """Indices of every pipe in the joint."""
        out = [pipe for pipe, _ in self.ends]
        if self.through is not None:
            out.insert(0, self.through)
        return tuple(out)

    @property
    def branch(self) -> End | None:
        """The branch end of a tee or a lateral."""
        return self.ends[-1] if self.kind in ("tee", "lateral") else None


@dataclass(frozen=True)
class _Candidate:
    cost: float
    kind: str
    a: End
    b: End
    explicit: bool


def elbow_bend_limit(tol: Tolerances) -> float:
    """Largest bend (degrees) an elbow joint may have: 90 + ``intended_angle_deg``."""
    return ELBOW_MAX_DEG + tol.intended_angle_deg


def _evaluate_pair(i, ki, j, kj, pts, out, axes, ods, tol: Tolerances, relaxed: bool, slack=None):
    """Classify the pair of ends; return a _Candidate or None.

    ``relaxed`` (a scan link): the distance limits grow by :data:`LINK_MARGIN`. A pair whose axes
    meet within reach but bend beyond :func:`elbow_bend_limit` is returned with kind
    ``"oblique"``: not a joint, only a fact to report.
    """
    ei, ej = pts[i, ki], pts[j, kj]
    oi, oj = out[i, ki], out[j, kj]
    ri, rj = 0.5 * ods[i], 0.5 * ods[j]
    skew_tol = skew_tolerance(ri, rj)
    jd = tol.joint_distance
    si = 0.0 if slack is None else float(slack[i])
    sj = 0.0 if slack is None else float(slack[j])
    cos = abs(float(axes[i] @ axes[j]))
    angle = float(np.degrees(np.arccos(min(1.0, cos))))
    if angle <= tol.intended_angle_deg:
        if float(oi @ oj) >= 0:  # both ends point the same way: not facing each other
            return None
        rel = ej - ei
        gap = float(oi @ rel)
        lateral = max(
            float(np.linalg.norm(rel - (rel @ axes[i]) * axes[i])),
            float(np.linalg.norm(rel - (rel @ axes[j]) * axes[j])),
        )
        # an eccentric reducer offsets the axes by the difference of the radii
        lateral = min(lateral, abs(lateral - abs(ri - rj)))
        if lateral > skew_tol:
            return None
        extra = LINK_MARGIN if relaxed else 0.0
        if not (-jd - extra <= gap <= 2 * jd + 2 * max(ods[i], ods[j]) + si + sj + extra):
            return None
        return _Candidate(abs(gap) + lateral, "inline", (i, ki), (j, kj), relaxed)
    s, t, qi, qj = line_closest_points(ei, oi, ej, oj)
    skew = float(np.linalg.norm(qi - qj))
    if skew > skew_tol:
        return None
    bend = float(np.degrees(np.arccos(np.clip(-(oi @ oj), -1.0, 1.0))))
    if bend >= 180.0 - tol.intended_angle_deg:
        return None
    reach = (
        1.5 * max(ods[i], ods[j]) * np.tan(np.radians(min(bend, elbow_bend_limit(tol))) / 2) + jd
    )
    extra = LINK_MARGIN if relaxed else 0.0
    if not (-jd - extra <= s <= reach + si + extra and -jd - extra <= t <= reach + sj + extra):
        return None
    kind = "elbow" if bend <= elbow_bend_limit(tol) else "oblique"
    # Each end's distance from where the elbow would end (its centre-to-end from the corner,
    # long radius ~ 1.5 OD): the pipe the fitting leaves unmeasured or cuts off, as an inline
    # pair's cost is its gap. Measured from the corner instead, an end that ran past the corner
    # (shots where the elbow would be) looked closest: an NPS 6 pipe's end 40 mm past another
    # spool's NPS 4 riser took it for a reducing elbow before its own elbow, 0.36 m short of its
    # corner (an independent review's rack, 3 of 21 scans).
    to_end = 1.5 * max(ods[i], ods[j]) * np.tan(np.radians(min(bend, ELBOW_MAX_DEG)) / 2)
    cost = abs(s - to_end) + abs(t - to_end) + skew
    return _Candidate(cost, kind, (i, ki), (j, kj), relaxed)


def best_for_link(i, j, pts, out, axes, ods, tol, slack):
    """The linked pair's best joint candidate, else its best ``"oblique"`` one (a bend beyond
    an elbow, returned so that the link's note can say so), else None."""
    best = oblique = None
    for ki in (0, 1):
        for kj in (0, 1):
            cand = _evaluate_pair(i, ki, j, kj, pts, out, axes, ods, tol, relaxed=True, slack=slack)
            if cand is None:
                continue
            # prefer the ends nearest each other among valid configurations
            cost = cand.cost + float(np.linalg.norm(pts[i, ki] - pts[j, kj]))
            if cand.kind == "oblique":
                if oblique is None or cost < oblique[0]:
                    oblique = (cost, cand)
            elif best is None or cost < best[0]:
                best = (cost, cand)
    best = best or oblique
    return None if best is None else best[1]


def _bend_deg(cand: _Candidate, out) -> float:
    """The bend (degrees) between the two ends of an elbow or oblique candidate."""
    oi, oj = out[cand.a], out[cand.b]
    return float(np.degrees(np.arccos(np.clip(-(oi @ oj), -1.0, 1.0))))


def _bend_note(names, i, j, bend, tol) -> str:
    return (
        f"the ends of {names[i]} and {names[j]} meet at a {bend:.0f} degree bend, beyond "
        f"an elbow's {elbow_bend_limit(tol):.0f} (ASME B16.9 elbows turn 45 or 90 degrees): "
        "not joined"
    )


def _tee_at_inline(joint: Joint, b: End, pts, out, axes, ods, tol, slack) -> float | None:
    (i, ki), (j, kj) = joint.ends
    point = 0.5 * (pts[i, ki] + pts[j, kj])
    return _branch_cost(b, point, axes[i], ods[i], pts, out, axes, ods, tol, slack)


def _branch_cost(
    b: End, point, run_axis, run_od, pts, out, axes, ods, tol, slack, oblique=False, extra=0.0
) -> float | None:
    """Cost of end ``b`` as a branch at ``point`` of a run, or None.

    A tee branch meets the run square-on (within ``intended_angle_deg`` of 90 degrees), its end
    up to the run's OD + ``joint_distance`` + its slack + ``extra`` (metres; :data:`LINK_MARGIN`
    for a branch the scan links to the run) from the run axis; with ``oblique`` the branch of a
    lateral instead: between ``intended_angle_deg`` and 90 degrees less it, its end up to the
    inline gap allowance (divided by the sine of the angle: an oblique branch must clear the
    run pipe) from the run axis. Its axis must pass the joint within the skew tolerance either
    way, however far its end.
    """
    pipe, k = b
    eb, ob = pts[pipe, k], out[pipe, k]
    cos = abs(float(axes[pipe] @ run_axis))
    angle = float(np.degrees(np.arccos(min(1.0, cos))))
    if oblique:
        if not tol.intended_angle_deg < angle < 90 - tol.intended_angle_deg:
            return None
        if float(ob @ (point - eb)) <= 0:
            return None  # the branch end points away from the run
    elif angle < 90 - tol.intended_angle_deg:
        return None
    s, _, q, _ = line_closest_points(eb, ob, point, run_axis)
    rel = q - point
    lateral_on_run = float(np.linalg.norm(rel - (rel @ run_axis) * run_axis))
    skew_tol = skew_tolerance(0.5 * run_od, 0.5 * ods[pipe])
    if lateral_on_run > skew_tol:
        return None
    along = abs(float(rel @ run_axis))
    if along > skew_tol + tol.joint_distance:
        return None
    if oblique:
        limit = 2 * tol.joint_distance + 2 * max(run_od, ods[pipe])
        limit = limit / np.sin(np.radians(angle)) + float(slack[pipe])
    else:
        limit = run_od + tol.joint_distance + float(slack[pipe]) + extra
    if not (-tol.joint_distance <= s <= limit):
        return None
    return abs(s) + along + lateral_on_run


def find_joints(
    centers,
    axes,
    lengths,
    ods,
    *,
    links: Iterable[tuple[int, int]] = (),
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    slack=None,
    notes: list | None = None,
    names: Sequence[str] | None = None,
) -> tuple[Joint, ...]:
    """Find the joints between pipes (see the module docstring for the rules).

    Parameters
    ----------
    centers : array_like, shape (n, 3), metres
    axes : array_like, shape (n, 3), unit vectors
    lengths : array_like, shape (n,), metres
    ods : array_like, shape (n,), metres
        Outside diameter estimates.
    links : iterable of (int, int)
        Pairs of pipe indices the scan says are contiguous.
    tolerances : Tolerances
    slack : array_like, shape (n,), metres, optional
        How far each pipe's fitted ends may fall short of its real ends beyond
        ``joint_distance`` (e.g. its coarsest shot spacing along the axis); default 0; at most
        :data:`SLACK_CAP`.
    notes : list, optional
        Receives ``(pipe indices, sentence)`` for what was found but not joined: a link too far
        apart to model, two ends bending beyond an elbow, the oblique branch of a lateral.
    names : sequence of str, optional
        Pipe ids for the sentences (default ``"#i"``).

    Returns
    -------
    tuple of Joint
    """
    centers = np.asarray(centers, float).reshape(-1, 3)
    axes = np.asarray(axes, float).reshape(-1, 3)
    lengths = np.asarray(lengths, float).reshape(-1)
    ods = np.asarray(ods, float).reshape(-1)
    n = len(centers)
    if n == 0:
        return ()
    pts, out = pipe_ends(centers, axes, lengths)
    tol = tolerances
    slack = np.zeros(n) if slack is None else np.asarray(slack, float).reshape(-1)
    slack = np.clip(slack, 0.0, SLACK_CAP)
    names = [f"#{i}" for i in range(n)] if names is None else list(names)
    notes = [] if notes is None else notes

    used: set[End] = set()
    joints: list[Joint] = []
    linked_pairs = set()
    for i, j in links:
        if i == j:
            continue
        key = (min(i, j), max(i, j))
        if key in linked_pairs:
            continue
        linked_pairs.add(key)

    # 1. explicit links first (distance limits widened by LINK_MARGIN)
    link_candidates = {
        key: best_for_link(*key, pts, out, axes, ods, tol, slack) for key in sorted(linked_pairs)
    }
    # 1a. a linked run (an inline pair) with a pipe linked to it as a square-on branch is a tee:
    # taking the links one by one in id order made the branch's link an elbow first and left
    # the run's own link a contact with the tee's length missing
    teed = set()
    for key, cand in link_candidates.items():
        if cand is None or cand.kind != "inline" or cand.a in used or cand.b in used:
            continue
        point = 0.5 * (pts[cand.a] + pts[cand.b])
        best = None
        for other in {q for pair in linked_pairs for q in pair if set(pair) & set(key)} - set(key):
            for k in (0, 1):
                if (other, k) in used:
                    continue
                cost = _branch_cost(
                    (other, k),
                    point,
                    axes[key[0]],
                    ods[key[0]],
                    *(pts, out, axes, ods, tol, slack),
                    extra=LINK_MARGIN,  # the branch is linked to the run
                )
                if cost is not None and (best is None or cost < best[0]):
                    best = (cost, (other, k))
        if best is None:
            continue
        used.update((cand.a, cand.b, best[1]))
        joints.append(Joint("tee", (cand.a, cand.b, best[1]), explicit=True))
        teed.update({key, *((min(q, best[1][0]), max(q, best[1][0])) for q in key)})
    # 1b. a linked elbow whose end continues straight into an unlinked pipe (an inline pair by
    # the geometry alone, without the link's margin) with the other end square-on at that joint
    # is a tee: links say which pipes are contiguous, not that the others are not, and an elbow
    # there would leave the run's other pipe loose where the fitting stands
    claimed: dict[End, set] = {}
    for key, c in link_candidates.items():
        for e in () if c is None else (c.a, c.b):
            claimed.setdefault(e, set()).add(key)
    flat = pts.reshape(-1, 3)
    base = 2 * tol.joint_distance + 1.5 * float(ods.max()) * 2.5 + float(ods.max())
    radius = base + 2 * float(slack.max())
    tree = cKDTree(flat)
    found = []
    for key, cand in link_candidates.items():
        if key in teed or cand is None or cand.kind != "elbow" or {cand.a, cand.b} & used:
            continue
        tee = _tee_around_elbow(cand, claimed, used, tree, radius, pts, out, axes, ods, tol, slack)
        if tee is not None:
            found.append(tee)
    for _, run_a, run_b, branch in sorted(found):
        if {run_a, run_b, branch} & used:
            continue
        used.update((run_a, run_b, branch))
        joints.append(Joint("tee", (run_a, run_b, branch), explicit=True))
        trio = (run_a[0], run_b[0], branch[0])
        teed.update((min(p, q), max(p, q)) for p in trio for q in trio if p != q)
    # 1c. a linked run with a third end meeting its joint obliquely is a lateral, as unlinked:
    # a straight joint across the wye's gap would be pipe nobody laid
    linked_inline = [
        c for key, c in link_candidates.items() if key not in teed and c and c.kind == "inline"
    ]
    lateral = _laterals(
        linked_inline, used, tree, radius, pts, out, axes, ods, tol, slack, notes, names
    )
    joints.extend(lateral)
    for found in lateral:
        trio = set(found.pipes)
        teed.update(key for key in linked_pairs if set(key) <= trio)
    # 1d. the other links, one by one; a link no fitting or butt joint realises gets a note
    # (decided after every joint is found: a tee through a pipe may still join the pair)
    unrealised: list[tuple[int, int, str]] = []
    # a straight joint through another pipe or straight joint (a cross's opposite outlets):
    # left to the tee search, then noted once the joints are known
    crossing: list[tuple[int, int, tuple[int, ...]]] = []
    for i, j in sorted(linked_pairs - teed):
        cand = link_candidates[i, j]
        if cand is None:
            apart = segment_distance(pts[i, 0], pts[i, 1], pts[j, 0], pts[j, 1])
            apart -= 0.5 * (ods[i] + ods[j])
            allowed = tol.joint_distance + LINK_MARGIN + float(slack[i] + slack[j])
            if apart > allowed:
                notes.append(
                    (
                        (i, j),
                        f"the scan links {names[i]} and {names[j]}, but they are "
                        f"{apart:.2f} m apart (a link may bridge {allowed:.2f} m): not joined "
                        "and no fitting invented; check the link or scan what lies between",
                    )
                )
                continue
            why = (
                f"the scan links {names[i]} and {names[j]}, but their axes do not meet (they "
                f"pass {apart * 1000:.0f} mm apart, outside to outside) and no fitting joins "
                "them: not joined; check the link or scan what lies between"
            )
            if apart < 0:  # the clash rule spares linked pipes: say they interpenetrate
                why = crossing_note(names, i, j, apart + 0.5 * (ods[i] + ods[j]))
        elif cand.kind == "oblique":
            why = _bend_note(names, i, j, _bend_deg(cand, out), tol)
        elif cand.a in used or cand.b in used:
            taken = next(jt for jt in joints if {cand.a, cand.b} & set(jt.ends))
            end = cand.a if cand.a in taken.ends else cand.b
            partners = ", ".join(names[p] for p in taken.pipes if p != end[0])
            why = (
                f"the scan links {names[i]} and {names[j]}, but that end of {names[end[0]]} is "
                f"already joined to {partners} by {_JOINED_BY[taken.kind]} (no fitting joins "
                "more pipes at one end): not joined"
            )
        else:
            across = crossed_by(cand, joints, pts, ods, tol.intended_angle_deg)
            if across is not None:
                crossing.append((i, j, across))
                continue
            used.update((cand.a, cand.b))
            joints.append(Joint(cand.kind, (cand.a, cand.b), explicit=True))
            continue
        unrealised.append((i, j, why))

    # 2. inferred end-to-end joints, best first
    # each end searches within the base reach plus twice its own slack: a pair is found by
    # whichever of its two ends has the larger slack
    radii = base + 2 * np.repeat(slack, 2)
    pairs = set()
    for a, near in enumerate(tree.query_ball_point(flat, radii)):
        for b in near:
            if b != a:
                pairs.add((min(a, b), max(a, b)))
    candidates: list[_Candidate] = []
    obliques: list[_Candidate] = []
    for a, b in sorted(pairs):
        i, ki = divmod(int(a), 2)
        j, kj = divmod(int(b), 2)
        if i == j or (min(i, j), max(i, j)) in linked_pairs:
            continue
        cand = _evaluate_pair(i, ki, j, kj, pts, out, axes, ods, tol, relaxed=False, slack=slack)
        if cand is not None:
            (obliques if cand.kind == "oblique" else candidates).append(cand)
    candidates.sort(key=lambda c: c.cost)

    # 2a. tees first: an inline pair with a third end meeting it square-on is stronger evidence
    # than any elbow between two of those ends
    tees = []
    for cand in candidates:
        if cand.kind != "inline":
            continue
        best = _best_branch(cand, tree, radius, pts, out, axes, ods, tol, slack)
        if best is not None:
            tees.append((cand.cost + best[0], cand, best[1]))
    tees.sort(key=lambda t: t[0])
    for _, cand, b in tees:
        if cand.a in used or cand.b in used or b in used:
            continue
        used.update((cand.a, cand.b, b))
        joints.append(Joint("tee", (cand.a, cand.b, b)))

    # 2b. laterals: an inline pair with a third end meeting it obliquely; one lateral joint of
    # the three (no lateral in the catalog: built from the measured ends), and no elbow may
    # take one of their ends
    joints.extend(
        _laterals(candidates, used, tree, radius, pts, out, axes, ods, tol, slack, notes, names)
    )

    for cand in candidates:
        if cand.a in used or cand.b in used:
            continue
        if crossed_by(cand, joints, pts, ods, tol.intended_angle_deg) is not None:
            continue  # a cross: one end may still be a tee's branch (step 3)
        used.update((cand.a, cand.b))
        joints.append(Joint(cand.kind, (cand.a, cand.b)))

    # 3. tees: leftover ends meeting an inline joint or the inside of a pipe
    free = [(i, k) for i in range(n) for k in (0, 1) if (i, k) not in used]
    if free:
        joints = _find_tees(joints, free, used, pts, out, centers, axes, lengths, ods, tol, slack)
    # 4. crosses: a tee with a free end opposite its outlet, on the outlet's line
    cross_noted: set = set()
    joints = find_crosses(
        *(joints, used, pts, out, centers, axes, ods, tol, slack, linked_pairs, notes, names),
        noted=cross_noted,
    )
    for i, j, across in crossing:
        taken = {}
        for end in (link_candidates[i, j].a, link_candidates[i, j].b):
            joint = next((jt for jt in joints if end in jt.ends), None)
            if joint is not None:
                taken[end[0]] = (joint.kind, tuple(p for p in joint.pipes if p != end[0]))
        unrealised.append((i, j, cross_note(names, i, j, across, taken)))
    for i, j, why in unrealised:
        if any(i in jt.pipes and j in jt.pipes for jt in joints):
            continue  # joined after all (a tee through one of them)
        if frozenset((i, j)) not in cross_noted:  # else the cross's note says it
            notes.append(((i, j), why))
        # kept for the joint size estimate (the scan says they are contiguous), but not
        # joined: no fitting, no spool together
        joints.append(Joint("link", ((i, 0), (j, 0)), explicit=True))
    noted = set()
    for cand in sorted(obliques, key=lambda c: c.cost):
        (i, ki), (j, kj) = cand.a, cand.b
        if cand.a in used or cand.b in used or (i, j) in noted:
            continue
        noted.add((i, j))
        notes.append(((i, j), _bend_note(names, i, j, _bend_deg(cand, out), tol)))
    return tuple(joints)


def _best_branch(cand, tree, radius, pts, out, axes, ods, tol, slack, skip=(), oblique=False):
    """The cheapest third end (not of the run's pipes, not in ``skip``) meeting the inline
    candidate ``cand`` as a branch (square-on, or ``oblique``): ``(cost, end)`` or None."""
    point = 0.5 * (pts[cand.a] + pts[cand.b])
    run_axis = axes[cand.a[0]]
    best = None
    for e in tree.query_ball_point(point, radius):
        b = divmod(int(e), 2)
        if b[0] in (cand.a[0], cand.b[0]) or b in skip:
            continue
        cost = _branch_cost(
            b, point, run_axis, ods[cand.a[0]], pts, out, axes, ods, tol, slack, oblique=oblique
        )
        if cost is not None and (best is None or cost < best[0]):
            best = (cost, b)
    return best


def _tee_around_elbow(cand, claimed, used, tree, radius, pts, out, axes, ods, tol, slack):
    """A tee hiding behind the linked elbow candidate ``cand``, or None.

    One of the elbow's ends must continue straight into a third pipe's end (an inline pair by
    :func:`_evaluate_pair`'s own limits: the link vouches for the elbow's pair, not for the
    run) and the elbow's other end must meet that joint square-on as a branch
    (:func:`_branch_cost`). A third end already ``used``, or that another link claims for a
    pipe outside the three, is not taken. Returns ``(cost, run end, run end, branch end)``
    (ends as :data:`End`, the run ends in pipe order), the cheapest of both ways round.
    """
    best = None
    for run_end, branch in ((cand.a, cand.b), (cand.b, cand.a)):
        for e in tree.query_ball_point(pts[run_end], radius):
            other = divmod(int(e), 2)
            if other[0] in (cand.a[0], cand.b[0]) or other in used:
                continue
            trio = {cand.a[0], cand.b[0], other[0]}
            if any(not set(key) <= trio for key in claimed.get(other, ())):
                continue  # the scan links that end to some other pipe
            run = _evaluate_pair(*run_end, *other, pts, out, axes, ods, tol, False, slack)
            if run is None or run.kind != "inline":
                continue
            point = 0.5 * (pts[run_end] + pts[other])
            cost = _branch_cost(
                branch,
                point,
                axes[run_end[0]],
                ods[run_end[0]],
                *(pts, out, axes, ods, tol, slack),
                extra=LINK_MARGIN,  # the branch is linked to the run
            )
            if cost is not None and (best is None or run.cost + cost < best[0]):
                # run ends in pipe order, as the other tees have them (the tee's id follows)
                best = (run.cost + cost, *sorted((run_end, other)), branch)
    return best


def _laterals(candidates, used, tree, radius, pts, out, axes, ods, tol, slack, notes, names):
    """Inline candidates with an oblique third end (a lateral): one ``"lateral"`` joint of the
    run ends and the branch end (the lateral fills the gap, so no butt weld is built); return
    the joints."""
    found = []
    for cand in candidates:
        if cand.kind != "inline" or cand.a in used or cand.b in used:
            continue
        best = _best_branch(
            cand, tree, radius, pts, out, axes, ods, tol, slack, skip=used, oblique=True
        )
        if best is not None:
            found.append((cand.cost + best[0], cand, best[1]))
    joints = []
    for _, cand, b in sorted(found, key=lambda t: t[0]):
        if cand.a in used or cand.b in used or b in used:
            continue
        used.update((cand.a, cand.b, b))
        # the lateral fills the gap between the run ends: no butt weld there
        joints.append(Joint("lateral", (cand.a, cand.b, b), explicit=cand.explicit))
        i, j, k = cand.a[0], cand.b[0], b[0]
        cos = abs(float(axes[k] @ axes[i]))
        angle = float(np.degrees(np.arccos(min(1.0, cos))))
        notes.append(
            (
                (k, i, j),
                f"{names[k]} meets the joint of {names[i]} and {names[j]} at {angle:.0f} "
                "degrees: a lateral (wye), which the catalog does not have; built from the "
                "measured pipe ends (non-standard)",
            )
        )
    return joints


def _find_tees(joints, free, used, pts, out, centers, axes, lengths, ods, tol, slack):
    joints = list(joints)
    inline_idx = [k for k, jt in enumerate(joints) if jt.kind == "inline"]
    inline_points = (
        np.array([0.5 * (pts[joints[k].ends[0]] + pts[joints[k].ends[1]]) for k in inline_idx])
        if inline_idx
        else np.zeros((0, 3))
    )
    inline_tree = cKDTree(inline_points) if len(inline_idx) else None
    # pipes sampled every SAMPLE_STEP metres along their axes: a k-d tree of the samples finds
    # the pipes passing near a free end whatever their length
    counts = np.maximum(np.ceil(lengths / SAMPLE_STEP).astype(int) + 1, 2)
    owner = np.repeat(np.arange(len(centers)), counts)
    fractions = np.concatenate([np.linspace(-0.5, 0.5, c) for c in counts])
    samples = centers[owner] + (fractions * lengths[owner])[:, None] * axes[owner]
    sample_tree = cKDTree(samples)
    reach = 0.5 * SAMPLE_STEP + 2 * tol.joint_distance + 2 * float(ods.max()) + float(slack.max())
    taken_inline: set[int] = set()
    for b in free:
        if b in used:
            continue
        pipe, k = b
        best = None
        if inline_tree is not None:
            near = inline_tree.query_ball_point(
                pts[pipe, k], 2 * float(ods.max()) + 2 * tol.joint_distance + float(slack[pipe])
            )
            for m in near:
                idx = inline_idx[m]
                if idx in taken_inline or pipe in joints[idx].pipes:
                    continue
                cost = _tee_at_inline(joints[idx], b, pts, out, axes, ods, tol, slack)
                if cost is not None and (best is None or cost < best[0]):
                    best = (cost, "inline", idx)
        for other in {int(owner[q]) for q in sample_tree.query_ball_point(pts[pipe, k], reach)}:
            if other == pipe:
                continue
            s, t, q_run, _ = line_closest_points(
                centers[other], axes[other], pts[pipe, k], out[pipe, k]
            )
            if abs(s) > 0.5 * lengths[other] - ods[other]:
                continue  # not inside the run pipe with room for the tee
            if branch_taken(other, q_run, joints, pts, centers, axes, ods):
                continue  # a cross's fourth outlet: left loose
            cost = _branch_cost(b, q_run, axes[other], ods[other], pts, out, axes, ods, tol, slack)
            if cost is not None and (best is None or cost < best[0]):
                best = (cost, "through", other)
        if best is None:
            continue
        _, how, ref = best
        used.add(b)
        if how == "inline":
            taken_inline.add(ref)
            run = joints[ref]
            joints[ref] = Joint("tee", run.ends + (b,), explicit=run.explicit)
        else:
            joints.append(Joint("tee", (b,), through=ref))
    return joints


def joint_pairs(joints: Sequence[Joint]) -> list[tuple[int, int]]:
    """Every pair of pipe indices joined directly (for runs and spools)."""
    pairs = []
    for joint in joints:
        pipes = joint.pipes
        for a in range(len(pipes)):
            for b in range(a + 1, len(pipes)):
                pairs.append((pipes[a], pipes[b]))
    return pairs


def connected_groups(n: int, joints) -> list[list[int]]:
    """Pipes ``0 .. n-1`` grouped by the joints that connect them (the spools).

    Each group is in ascending order and the groups are ordered by their first pipe; a pipe no
    joint touches is a group of its own. ``"link"`` joints (a scan link nothing realises) join
    nothing. Connected components by scipy's csgraph.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rows, cols = [], []
    for joint in joints:
        if getattr(joint, "kind", None) == "link":
            continue  # a link nothing realises joins no spool: it would be two pieces
        first, *others = joint.pipes
        rows += [first] * len(others)
        cols += list(others)
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    _, labels = connected_components(graph, directed=False)
    groups: dict[int, list[int]] = {}
    for index, label in enumerate(labels):
        groups.setdefault(int(label), []).append(index)
    return sorted(groups.values(), key=lambda group: group[0])
