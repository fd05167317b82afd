"""Straight joints that would pass through another pipe or another straight joint: a cross.

Contiguity builds an inline joint (a butt weld, a reducer) as the straight piece
between two facing pipe ends. Where four pipes meet at one point as a cross (P1 and P2 on one
line, P3 and P4 on a perpendicular one) and the scan links the opposite pairs, it built two
couplings through each other; where two pipes end on either side of a third that runs straight
through, it built a coupling through that pipe. Neither is a fitting anybody could weld: the
part there is a cross.

:func:`crossed_by` tells contiguity that the straight piece between two ends would pass through
another pipe or an accepted straight joint; contiguity then leaves the pair to the tee search
(one end becomes the branch of a tee at the other joint, or on the pipe it would cross), and
the cross search (:mod:`.crosses`) makes that tee a cross with the other end when the two lie
on one line. When it cannot (the ends off one line) and the scan linked the pair,
:func:`cross_note` words the note merging leaves on both pipes (reported as AB302
``merge-note``), unless the cross search's own note already names them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = [
    "End",
    "JOINED_BY",
    "crossed_by",
    "cross_note",
    "crossing_note",
    "branch_taken",
    "segment_closest",
]

#: A pipe end: (pipe index, 0 for the start end / 1 for the end end).
End = tuple[int, int]

#: How a note names the joint that took a pipe end (contiguity's notes too).
JOINED_BY = {
    "elbow": "an elbow",
    "tee": "a tee",
    "inline": "an inline joint",
    "contact": "a contact",
    "lateral": "a lateral",
    "cross": "a cross",
}


def segment_closest(p0, p1, q0, q1) -> tuple[float, float, float]:
    """Closest points of segments ``p0 p1`` and ``q0 q1`` (points (3,) m).

    Returns
    -------
    distance : float
        Between the closest points, metres.
    s, t : float
        Their parameters along each segment, 0 at ``p0`` (``q0``) to 1 at ``p1`` (``q1``).
    """
    d1, d2, r = p1 - p0, q1 - q0, p0 - q0
    a, e, f = float(d1 @ d1), float(d2 @ d2), float(d2 @ r)
    c, b = float(d1 @ r), float(d1 @ d2)
    denom = a * e - b * b
    s = float(np.clip((b * f - c * e) / denom, 0.0, 1.0)) if denom > 1e-12 * a * e else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t, s = 0.0, float(np.clip(-c / a, 0.0, 1.0))
    elif t > 1.0:
        t, s = 1.0, float(np.clip((b - c) / a, 0.0, 1.0))
    return float(np.linalg.norm(p0 + s * d1 - q0 - t * d2)), s, float(t)


def crossed_by(
    cand, joints: Sequence, pts: np.ndarray, ods: np.ndarray, min_angle_deg: float
) -> tuple[int, ...] | None:
    """What the straight piece of an inline candidate would pass through.

    The piece is the segment between the two ends with the larger pipe's radius. It passes
    through a pipe when their bodies interpenetrate (axes closer than the sum of the radii)
    with the closest point inside the piece and at least the piece's radius from either end
    of the pipe (the pipe continues on both sides: a branch ending at the joint is not
    crossing it); through another straight piece when their bodies interpenetrate inside both
    and their axes are more than ``min_angle_deg`` from parallel.

    Parameters
    ----------
    cand : contiguity candidate
        Its ``kind`` (only ``"inline"`` is a straight piece) and its two ends ``a``, ``b``
        (pipe index, 0 start / 1 end).
    joints : sequence of contiguity.Joint
        The joints accepted so far: the straight pieces are the inline joints' and the runs of
        tees and laterals at an inline joint (their first two ends).
    pts : ndarray, shape (n, 2, 3), metres
        Every pipe's end points.
    ods : ndarray, shape (n,), metres
        Outside diameters.
    min_angle_deg : float
        Smallest angle (degrees) between two pieces that cross (``intended_angle_deg``).

    Returns
    -------
    tuple of int or None
        The pipe it passes through (one index) or the two pipes of the piece it passes through;
        None when it passes through nothing (or the candidate is not inline).
    """
    if cand.kind != "inline":
        return None
    a, b = cand.a, cand.b
    bridges = [
        (jt.ends[0], jt.ends[1])
        for jt in joints
        if jt.kind == "inline" or (jt.kind in ("tee", "lateral") and len(jt.ends) == 3)
    ]
    p0, p1 = pts[a], pts[b]
    length = float(np.linalg.norm(p1 - p0))
    if length < 1e-9:
        return None
    radius = 0.5 * float(max(ods[a[0]], ods[b[0]]))
    # pipes near the piece: axis within the piece's half length + both radii of its middle
    starts, stops = pts[:, 0], pts[:, 1]
    d = stops - starts
    mid = 0.5 * (p0 + p1)
    t = np.clip(np.einsum("ij,ij->i", mid - starts, d) / np.maximum((d * d).sum(1), 1e-24), 0, 1)
    near = np.linalg.norm(starts + t[:, None] * d - mid, axis=1) <= (
        0.5 * length + radius + 0.5 * ods
    )
    for m in np.flatnonzero(near):
        m = int(m)
        if m in (a[0], b[0]):
            continue
        dist, s, t_m = segment_closest(p0, p1, starts[m], stops[m])
        long = float(np.linalg.norm(d[m]))
        if (
            dist < radius + 0.5 * float(ods[m])
            and 0.0 < s < 1.0
            and min(t_m, 1.0 - t_m) * long >= radius
        ):
            return (m,)
    cos_max = np.cos(np.radians(min_angle_deg))
    u = (p1 - p0) / length
    for e, f in bridges:
        if {e[0], f[0]} & {a[0], b[0]}:
            continue
        q0, q1 = pts[e], pts[f]
        span = float(np.linalg.norm(q1 - q0))
        if span < 1e-9 or abs(float(u @ (q1 - q0))) / span > cos_max:
            continue
        other = 0.5 * float(max(ods[e[0]], ods[f[0]]))
        dist, s, t_m = segment_closest(p0, p1, q0, q1)
        if dist < radius + other and 0.0 < s < 1.0 and 0.0 < t_m < 1.0:
            return (e[0], f[0])
    return None


def cross_note(
    names: Sequence[str],
    i: int,
    j: int,
    crossed: tuple[int, ...],
    taken: dict[int, tuple[str, tuple[int, ...]]],
) -> str:
    """The note on a linked pair whose straight joint would pass through ``crossed``.

    Parameters
    ----------
    names : sequence of str
        Pipe ids.
    i, j : int
        The linked pipes.
    crossed : tuple of int
        What the joint would pass through: one pipe, or the two pipes of a straight joint.
    taken : dict
        For each of ``i``, ``j`` joined at that end after all: the joint's kind and its other
        pipes.

    Returns
    -------
    str
        One sentence; it says ``not joined`` (the rules read that, docs/rules.md).
    """
    across = (
        names[crossed[0]]
        if len(crossed) == 1
        else f"the joint of {names[crossed[0]]} and {names[crossed[1]]}"
    )
    done = [
        f"{names[p]} is joined to {', '.join(names[q] for q in taken[p][1])} by "
        f"{JOINED_BY.get(taken[p][0], 'a joint')}"
        for p in (i, j)
        if p in taken
    ]
    loose = [names[p] for p in (i, j) if p not in taken]
    state = "; ".join(done + [f"{' and '.join(loose)} not joined there"] if loose else done)
    advice = " or ".join(loose) if loose else f"{names[i]} and {names[j]}"
    return (
        f"the scan links {names[i]} and {names[j]}, but a straight joint between them would "
        f"pass through {across}: the pipes meet there as a cross, but not as one merging "
        "builds (four pipe ends, two on each line, meeting at one point), so the "
        f"link is not joined ({state}); if {advice} is welded there on site, the fitting is a "
        "cross: check the pipes' positions or model it by hand; if not, check the link"
    )


def branch_taken(pipe: int, point: np.ndarray, joints: Sequence, pts, centers, axes, ods) -> bool:
    """Whether a tee through ``pipe`` already has its outlet within the pipe's OD of ``point``.

    A second branch there is a cross's fourth outlet (two pipes ending on either side of a
    pipe that runs through): no second tee is placed at the same place, the end stays loose.

    Parameters
    ----------
    pipe : int
        The run pipe's index.
    point : ndarray, shape (3,), metres
        Where the new branch's axis meets the run's axis.
    joints : sequence of contiguity.Joint
        The joints so far (a tee through a pipe has ``through`` set and its branch end last).
    pts : ndarray, shape (n, 2, 3), metres
        Every pipe's end points.
    centers, axes : ndarray, shape (n, 3)
        Pipe centres (metres) and unit axes.
    ods : ndarray, shape (n,), metres
        Outside diameters.
    """
    for jt in joints:
        if jt.kind != "tee" or jt.through != pipe:
            continue
        end = pts[jt.ends[-1]] - centers[pipe]
        at = centers[pipe] + float(end @ axes[pipe]) * axes[pipe]
        if float(np.linalg.norm(at - np.asarray(point, float))) < float(ods[pipe]):
            return True
    return False


def crossing_note(names: Sequence[str], i: int, j: int, axes_apart: float) -> str:
    """The note on a linked pair whose bodies pass through each other away from their ends.

    The clash rule never reports linked components, so this note (AB302 ``merge-note``) is
    what tells the user. ``axes_apart``: the closest distance between the two axis
    segments, metres.
    """
    return (
        f"the scan links {names[i]} and {names[j]}, but they pass through each other (their "
        f"axes {axes_apart * 1000:.0f} mm apart, inside both pipes) and no fitting joins them: "
        "not joined; if they meet at a cross, it joins four pipe ends (two pipes running "
        "through each other are no cross); if one passes the other, reroute it or check the link"
    )
