"""Spools with real fittings: elbows, tees and reducers placed at the joints.

Input: pipes as lines already regularised and aligned (:mod:`asbuilt.merge.regularize`), their
sizes and fitting dimensions, and the joints (:mod:`asbuilt.merge.contiguity`). Output: the pipe
and fitting components, every neighbour sharing its end point and direction exactly.

Geometry at each joint (``o`` is a pipe end's outward direction, ``P`` the meeting point of the
axes):

* **elbow** of bend angle ``theta`` (between ``o_1`` and ``-o_2``) and bend radius ``R``
  (catalog long or short radius): centre-to-end ``R tan(theta/2)`` (within 2 degrees of 45 the
  catalog's 45 degree centre-to-end ``B`` instead, with ``R = B / tan(theta/2)``); ends
  ``T_k = P - R tan(theta/2) o_k``; the curvature centre is ``T_1 + R n`` with ``n`` the unit
  vector perpendicular to ``o_1`` towards ``-o_2``. Both pipes are trimmed (or extended) to
  ``T_k``. Between two sizes (a reducing elbow) a listed 90 degree pair takes its B16.9 A
  (:func:`.reducers.reducing_elbow_end`); another angle or pair is said to be non-standard.
* **inline**, one size: the ends meet at their midpoint (a butt weld); a gap is pipe the scan
  did not measure (both pipes extended to meet in its middle), with a note when longer than
  :func:`fitting_fill_limit`.
* **inline**, two sizes: a **reducer** of the catalog length (by its large end) centred on the
  gap; both pipes end at its ends. It is concentric when the aligned axes coincide, eccentric
  (``Reducer.offset`` the sideways step between them) when merging placed them apart
  (:mod:`asbuilt.merge.eccentric`); ASME B16.9 gives both the same length H.
* **lateral** (oblique branch; in no catalog): a tee-shaped fitting, :mod:`.laterals`.
* **cross** (:mod:`.crosses`): a tee with a second outlet opposite the first, both of the
  tee's ``M`` from ``J`` (ASME B16.9 tabulates crosses with tees); through a pipe, it splits it.
* **tee**: centre ``J`` where the branch axis meets the run axis; run ends ``J -+ C d``,
  branch end ``J + M b`` (``C``, ``M``: catalog centre-to-end of run and outlet; a reducing
  outlet's pair's own from ASME B16.9 Table 8 when listed, :func:`.reducers.reducing_tee_dims`).
  A tee in the middle of a pipe splits it into pieces ``<id>.1``, ``<id>.2``...

A fitting that would leave a pipe shorter than 1 mm is not built (the joint is reported in the
pipes' ``snap["merge_notes"]``) and the pipes keep their ends there.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

import numpy as np

from asbuilt.catalog import FittingDims
from asbuilt.model import (
    OFFSET_SLACK,
    Bend,
    Component,
    Correction,
    Spool,
    Straight,
)

from ._fitting_shapes import (
    ELBOW45_WINDOW_DEG,
    TRIM_SURFACE_TOLERANCE,
    flat_word,
    reducer_cone,
    reducing_elbow_source,
    same_size,
    size_text,
    tee_dims,
    tee_geometry,
)
from .contiguity import Joint, connected_groups, line_closest_points
from .crosses import build_cross
from .laterals import build_lateral
from .ports import connection_mismatches, ports
from .reducers import (
    nps_order,
    reducer_made,
    reducing_elbow_end,
    small_ends,
)

__all__ = [
    "PipeSpec",
    "build_spools",
    "ports",
    "connection_mismatches",
    "MIN_PIPE_LENGTH",
]

#: Shortest pipe piece left after trimming, metres.
MIN_PIPE_LENGTH = 0.001
#: Largest elbow bend built by default (degrees): ASME B16.9 elbows turn 45 or 90 degrees, plus
#: the default ``intended_angle_deg`` (10) of latitude; merge passes its own tolerance.
MAX_BEND_DEG = 100.0
#: A pipe cut back by more than this (metres) at a fitting gets a note: its fitted end is its
#: outermost shot, so the fitting then covers pipe the scan measured; 10 mm allows for shots
#: on the weld bead and bevel and for range noise along the axis.
TRIM_NOTE = 0.010
#: A pipe extended by more than this (metres) plus its shots' step along the axis at its ends
#: (the last shot is within a step of the end) gets a note: that much pipe was never
#: measured. It is Tolerances.joint_distance's default: sparse
#: scans stop short of fittings by a shot spacing or so, and operators keep the beam off the
#: fitting (the simulated perfect spool's pipes end 30-70 mm short of every fitting); farther
#: than that, the extension is the model's guess, not the scan's.
EXTEND_NOTE = 0.15


@dataclass(frozen=True, eq=False)
class PipeSpec:
    """One pipe ready for spool building.

    Attributes
    ----------
    id : str
    center : ndarray, shape (3,), metres
        A point of the (aligned) axis: the mid-point of the fitted extent.
    axis : ndarray, shape (3,)
        Unit axis (regularised).
    length : float
        Fitted length, metres.
    od : float
        Outside diameter to build with, metres.
    wall : float
        Wall thickness, metres (0 = solid).
    dims : FittingDims
        Fitting dimensions for this pipe's size.
    run : int
        Index of its run of one size.
    component : Component
        The pipe component so far (snap, corrections...); geometry is replaced here.
    nominal, schedule : str or None
    notes : list of str
        Sentences for ``snap["merge_notes"]`` (merging adds its own).
    slack : float
        Coarsest spacing of the pipe's shots along its axis, metres (for the notes).
    spacing : float
        Its shots' step along its axis at its ends (the larger), metres: an extension longer
        than this plus :data:`EXTEND_NOTE` gets a note.
    """

    id: str
    center: np.ndarray
    axis: np.ndarray
    length: float
    od: float
    wall: float
    dims: FittingDims
    run: int
    component: Component
    nominal: str | None = None
    schedule: str | None = None
    notes: list = field(default_factory=list)
    slack: float = 0.0
    spacing: float = 0.0


def _vec(x) -> tuple[float, float, float]:
    return tuple(float(v) for v in x)


def _unit(v):
    return v / np.linalg.norm(v)


def fitting_fill_limit(joint_distance: float, od: float) -> float:
    """Longest gap (metres) between collinear pipes of one size that a fitting could fill.

    ``2 joint_distance + 2 od``: the gap an inline joint takes without a link or shot slack
    (:mod:`.contiguity`: room for a reducer or a tee's run). A longer one was bridged only by a
    link's margin or sparse shots: the pipe filling it gets a note saying so.
    """
    return 2.0 * joint_distance + 2.0 * od


class _Builder:
    def __init__(self, pipes: Sequence[PipeSpec], reducer_notes=None, joint_distance=0.15):
        self.pipes = pipes
        self.joint_distance = joint_distance
        self.reducer_notes = dict(reducer_notes or {})
        n = len(pipes)
        self.base = np.zeros((n, 2, 3))
        self.out = np.zeros((n, 2, 3))
        for i, p in enumerate(pipes):
            half = 0.5 * p.length * p.axis
            self.base[i] = (p.center - half, p.center + half)
            self.out[i] = (-p.axis, p.axis)
        self.ends = self.base.copy()
        self.splits: dict[int, list[tuple[float, float]]] = {}
        self.fitting_at: dict[tuple[int, int], str] = {}
        # How far a pipe end may be cut back into its fitting with its shots still on the
        # fitting's surface (metres; set by _elbow, _inline and _tee).
        self.allowance: dict[tuple[int, int], float] = {}
        # Pipe ends extended to fill a gap longer than a fitting would: the note for them.
        self.filled: dict[tuple[int, int], str] = {}
        # Notes for pipes' merge_notes from the fittings built at them (non-standard ones).
        self.pipe_notes: dict[int, list[str]] = {}

    def reset(self):
        self.ends = self.base.copy()
        self.splits = {}
        self.fitting_at = {}
        self.allowance = {}
        self.filled = {}
        self.pipe_notes = {}

    def note(self, pipes: Iterable[int], text: str) -> None:
        """Put ``text`` in the merge notes of ``pipes`` (indices), once each."""
        for i in pipes:
            said = self.pipe_notes.setdefault(i, [])
            if text not in said:
                said.append(text)

    def param(self, i: int, point) -> float:
        """Position of ``point`` along pipe i's axis from its start end, metres."""
        return float((np.asarray(point) - self.base[i, 0]) @ self.pipes[i].axis)


def _elbow(b: _Builder, joint: Joint):
    (i, ki), (j, kj) = joint.ends
    pi, pj = b.pipes[i], b.pipes[j]
    oi, oj = b.out[i, ki], b.out[j, kj]
    _, _, qi, qj = line_closest_points(b.base[i, ki], oi, b.base[j, kj], oj)
    point = 0.5 * (qi + qj)
    cos = float(np.clip(-(oi @ oj), -1.0, 1.0))
    theta = float(np.arccos(cos))
    if np.degrees(theta) < 1e-6:
        return _inline(b, Joint("inline", joint.ends, explicit=joint.explicit))
    big = pi if pi.od >= pj.od else pj
    small = pj if big is pi else pi
    radius = max(pi.dims.bend_radius, pj.dims.bend_radius)
    reach = radius * np.tan(theta / 2)
    notes = list(big.dims.notes)
    degrees = float(np.degrees(theta))
    reducing = not same_size(pi, pj)
    # a listed B16.9 reducing elbow (90 degree long radius only): its centre-to-end A, or False
    # for a pair the list does not make, None for no verdict
    listed = reducing_elbow_end(big.dims.source, big.nominal, small.nominal) if reducing else None
    if listed and abs(degrees - 90.0) <= ELBOW45_WINDOW_DEG:
        if listed > reach + 1e-9:
            notes.append(
                "no short-radius reducing elbow in ASME B16.9: the long-radius reducing elbow used"
            )
        reach = listed
        radius = reach / np.tan(theta / 2)
    elif big.dims.elbow45_end is not None and abs(degrees - 45.0) <= ELBOW45_WINDOW_DEG:
        # a catalog 45 degree elbow: keep its centre-to-end, the radius follows
        reach = big.dims.elbow45_end
        radius = reach / np.tan(theta / 2)
        notes.extend(big.dims.elbow45_notes)
    ti = point - reach * oi
    tj = point - reach * oj
    inward = (-oj) - ((-oj) @ oi) * oi
    center = ti + radius * _unit(inward)
    # each end its pipe's size and wall (a B16.9 reducing elbow), the larger end first (as such
    # elbows are named; a reader of one size per elbow sees the larger, as built before)
    (s, ps), (e, pe) = sorted([(ti, pi), (tj, pj)], key=lambda end: -end[1].od)
    hollow = bool(pi.wall and pj.wall)
    walls = (ps.wall, pe.wall) if hollow else (0.0, 0.0)
    geometry = Bend(s, e, center, 0.5 * ps.od, walls[0], 0.5 * pe.od, walls[1])
    b.ends[i, ki] = ti
    b.ends[j, kj] = tj
    b.fitting_at[i, ki] = b.fitting_at[j, kj] = f"elbow {pi.id}-{pj.id}"
    # The bend leaves the pipe's cylinder by about s^2 / (2 R) at s along it.
    bent = float(np.sqrt(2.0 * radius * TRIM_SURFACE_TOLERANCE))
    b.allowance[i, ki] = b.allowance[j, kj] = min(bent, float(reach))
    if reducing:
        notes.append(
            "pipes of different sizes meet here: a reducing elbow, each end its pipe's size and wall"
        )
    source = big.dims.source
    # a B16.9 angle; a reducing elbow may still be non-standard at it (a 45, a pair not made),
    # which reducing_elbow_source says: only an angle B16.9 has no elbow for is cut or bent
    b16_9_angle = min(abs(degrees - 45.0), abs(degrees - 90.0)) <= ELBOW45_WINDOW_DEG
    standard = b16_9_angle
    if reducing:
        source, standard = reducing_elbow_source(
            b, f"{pi.id}-{pj.id}", big, small, degrees, listed, source, standard, (i, j), notes
        )
    if not b16_9_angle:
        # B16.9 makes 45 and 90 degree elbows only: say what was built instead of labelling it
        if degrees < 90.0:
            made = f"a 90 degree elbow of that radius cut to {degrees:.0f} degrees"
            source = f"{source}, cut from a 90 degree elbow (non-standard)"
        else:
            made = f"a {degrees:.0f} degree bend of the 90 degree elbow's radius"
            source = f"{source} radius, {degrees:.0f} degree bend (non-standard)"
        text = (
            f"the elbow {pi.id}-{pj.id} turns {degrees:.0f} degrees, which no ASME B16.9 elbow "
            f"does (45 or 90): built as {made}"
        )
        notes.append(text)
        b.note((i, j), text)
    snap = {
        "status": "fitting",
        "dimensions": source,
        "standard": _verdict(standard, big.dims),
        "bend_radius": radius,
        "angle_deg": float(np.degrees(theta)),
        "connects": [pi.id, pj.id],
        "notes": notes,
    }
    return [("elbow", f"{pi.id}-{pj.id}", geometry, big, snap)]


def _verdict(standard: bool, dims: FittingDims) -> bool | None:
    """A fitting's ``standard`` record: None (no verdict) for one built from a rule of thumb
    (no fittings row for its size: an unsized pipe's elbow is no catalog fitting), unless its
    form is non-standard whatever its size."""
    return None if standard and dims.source == "rule" else standard


#: A reducer whose place along the line is uncertain by more than this (m, either way) gets a
#: note saying so: beyond the 10 mm a fit-up survey tolerates, the take-off's lengths of the two
#: sizes move with it.
POSITION_NOTE = 0.010


def _inline(b: _Builder, joint: Joint):
    (i, ki), (j, kj) = joint.ends
    pi, pj = b.pipes[i], b.pipes[j]
    ei, ej = b.base[i, ki], b.base[j, kj]
    oi = b.out[i, ki]
    gap = float(oi @ (ej - ei))
    if same_size(pi, pj):
        # One size in line: a butt weld, the two pipes meeting at the gap's middle. A gap is
        # pipe the scan did not measure (operators keep the beam off welds, so the shots stop
        # short of one on both sides); before, gaps up to fitting_fill_limit were filled by a
        # "coupling" no butt-welded line has, which the take-off counted as a fitting.
        mid = 0.5 * (ei + ej)
        b.ends[i, ki] = b.ends[j, kj] = mid
        b.fitting_at[i, ki] = f"butt weld with {pj.id}"
        b.fitting_at[j, kj] = f"butt weld with {pi.id}"
        longest = fitting_fill_limit(b.joint_distance, max(pi.od, pj.od))
        if gap > longest:
            # more than a fitting would fill: a link or sparse shots made the joint; said, as
            # the extensions' own notes would not name the pair
            size = f"NPS {pi.nominal}" if pi.nominal else f"OD {pi.od * 1000:.1f} mm"
            b.filled[i, ki] = b.filled[j, kj] = (
                f"{pi.id} and {pj.id} are {gap * 1000:.0f} mm apart in line, longer than a "
                f"fitting fills ({longest * 1000:.0f} mm): the gap is modelled as {size} pipe "
                "the scan did not measure (both pipes extended to meet in its middle); scan "
                "the hidden section or check the link"
            )
        return []
    large = pi if pi.od > pj.od else pj
    length = large.dims.reducer_length
    mid = 0.5 * (ei + ej)
    # sideways step from pipe i's axis to pipe j's: zero when aligned coaxial
    offset = (ej - ei) - float((ej - ei) @ oi) * oi
    if np.linalg.norm(offset) <= OFFSET_SLACK:
        offset = np.zeros(3)
    start = mid - 0.5 * length * oi - 0.5 * offset
    end = mid + 0.5 * length * oi + 0.5 * offset
    b.ends[i, ki] = start
    b.ends[j, kj] = end
    b.fitting_at[i, ki] = b.fitting_at[j, kj] = f"reducer {pi.id}-{pj.id}"
    geometry, allowance = reducer_cone(start, end, pi, pj, float(length), offset)
    b.allowance[i, ki] = b.allowance[j, kj] = allowance
    notes = list(large.dims.notes)
    note = b.reducer_notes.get((min(i, j), max(i, j)))
    if geometry.eccentric and note:
        notes.insert(0, note)
    small = pj if large is pi else pi
    source, standard = _reducer_source(b, large, small, (i, j))
    # The shots bound the pipes' ends from inside only: a reducer shorter than the gap between
    # them may lie anywhere in it; built in the middle, it is within half the spare either way.
    spare = max(gap - float(length), 0.0)
    if 0.5 * spare > POSITION_NOTE:
        notes.append(
            f"the reducer fills {float(length) * 1000:.0f} of the {gap * 1000:.0f} mm between "
            f"{pi.id}'s and {pj.id}'s shots: built in the middle, it may lie up to "
            f"{0.5 * spare * 1000:.0f} mm either way along the line; scan up to it to place it"
        )
    snap = {
        "status": "fitting",
        "dimensions": source,
        "standard": _verdict(standard, large.dims),
        "length": length,
        "sizes": [pi.nominal, pj.nominal],
        "connects": [pi.id, pj.id],
        "notes": notes,
        "position_range": 0.5 * spare,
    }
    if geometry.eccentric:
        snap["eccentric"] = {
            "flat": flat_word(geometry.flat_side),
            "offset": float(np.linalg.norm(offset)),
        }
    return [("reducer", f"{pi.id}-{pj.id}", geometry, large, snap)]


def _reducer_source(b: _Builder, large: PipeSpec, small: PipeSpec, pipes) -> tuple[str, bool]:
    """(``dimensions`` record, standard?) of a reducer from ``large`` to ``small``: a pair the
    fittings table does not make (:func:`.reducers.reducer_made`) keeps the large end's H but
    is said to be non-standard, with a note on ``pipes``."""
    source = large.dims.source
    if reducer_made(source, large.nominal, small.nominal) is not False:
        return source, True
    ends = sorted(small_ends(source).get(large.nominal, ()), key=nps_order, reverse=True)
    text = (
        f"no NPS {large.nominal} x {small.nominal} reducer in {source} ("
        + (f"NPS {large.nominal} reduces to {', '.join(ends)} only" if ends else "none from it")
        + f"): built with the NPS {large.nominal} reducer's length, a fitting the standard "
        "does not make; two reducers in series, or check the sizes"
    )
    b.note(pipes, text)
    return f"{source} H of the large end; no such reducer (non-standard)", False


def _tee(b: _Builder, joint: Joint):
    branch_i, branch_k = joint.ends[-1]
    pb = b.pipes[branch_i]
    ob = b.out[branch_i, branch_k]
    small = None
    if joint.through is None:
        (i, ki), (j, kj) = joint.ends[:2]
        pi, pj = b.pipes[i], b.pipes[j]
        run_dir = b.out[i, ki]
        anchor = b.base[i, ki]
        if not same_size(pi, pj):
            # B16.9 tees reduce on the outlet only: a run that changes size at the tee is a
            # tee of the larger run and a reducer on the smaller side
            small = pj if pi.od > pj.od else pi
    else:
        i = joint.through
        pi = pj = b.pipes[i]
        run_dir = pi.axis
        anchor = b.base[i, 0]
    run = pj if small is pi else pi
    _, t, _, center = line_closest_points(b.base[branch_i, branch_k], ob, anchor, run_dir)
    center = anchor + t * run_dir
    geometry = tee_geometry(center, run_dir, -ob, run, pb)
    c_run, c_out, paired = tee_dims(run, pb)
    b.ends[branch_i, branch_k] = geometry.branch_end
    b.fitting_at[branch_i, branch_k] = "a tee"
    # A tee's run and outlet are the pipes' own cylinders up to its centre-to-end dimensions.
    b.allowance[branch_i, branch_k] = float(c_out)

    notes = list(run.dims.notes)
    source = run.dims.source
    standard = True
    if pb.od > run.od + 1e-9:
        # no "reducing outlet": the rules report the size mismatch (contiguous-diameter)
        standard = False
        source = f"{source}, outlet larger than the run (non-standard)"
        notes.append(
            f"the outlet ({size_text(pb)}) is larger than the run ({size_text(run)}): no ASME B16.9 "
            "tee has one (tees reduce on the outlet only); built with the run's dimensions"
        )
    elif paired:
        notes.append(
            f"reducing outlet: NPS {run.nominal} x {pb.nominal} tee of {source} (C "
            f"{c_run * 1000:.0f} mm, M {c_out * 1000:.0f} mm)"
        )
    elif not same_size(run, pb):
        notes.append("reducing outlet: built with the equal tee's dimensions of the run size")
    square = float(np.degrees(np.arccos(min(1.0, abs(float(ob @ run_dir))))))
    if abs(square - 90.0) > ELBOW45_WINDOW_DEG:
        # B16.9 tees are square; an oblique branch is a non-standard fitting (or a lateral)
        standard = False
        source = f"{source}, outlet at {square:.0f} degrees (non-standard)"
        text = (
            f"{pb.id} meets the run of {pi.id} at {square:.0f} degrees: ASME B16.9 tees are "
            "square (90 degrees); built as a tee of its dimensions with the outlet at that "
            "angle, which is not a B16.9 fitting"
        )
        notes.append(text)
        b.note({i, branch_i} | ({j} if joint.through is None else set()), text)
    items = []
    if joint.through is None:
        b.ends[i, ki] = geometry.run_start
        b.ends[j, kj] = geometry.run_end
        name = f"{pi.id}-{pj.id}-{pb.id}"
        b.fitting_at[i, ki] = b.fitting_at[j, kj] = f"tee {name}"
        b.fitting_at[branch_i, branch_k] = f"tee {name}"
        b.allowance[i, ki] = b.allowance[j, kj] = float(c_run)
        connects = [pi.id, pj.id, pb.id]
        if small is not None:
            end = (j, kj) if small is pj else (i, ki)
            port = geometry.run_end if small is pj else geometry.run_start
            items = _run_reducer(b, name, run, small, end, port, (i, j, branch_i))
            notes.append(
                f"the run changes from {size_text(run)} to {size_text(small)} here: tee of the larger "
                + ("run, followed by a reducer" if items else "run, and no reducer can follow")
            )
    else:
        at = b.param(i, center)
        b.splits.setdefault(i, []).append((at, float(c_run)))
        name = None  # named after the pieces are known
        connects = [pi.id, pb.id]
    snap = {
        "status": "fitting",
        "dimensions": source,
        "standard": _verdict(standard, run.dims),
        "connects": connects,
        "notes": notes,
    }
    at_param = b.param(i, center) if joint.through is not None else None
    return [("tee", name, geometry, run, snap, joint.through, at_param), *items]


def _run_reducer(b: _Builder, tee: str, run: PipeSpec, small: PipeSpec, end, port, pipes):
    """The reducer after the tee ``tee`` on the smaller run pipe's side: from the tee's run
    ``port`` ((3,) m) outwards by the large end's H, the smaller pipe's ``end`` moved to its
    small end. None is built when the fittings table does not make that pair (the pipe then
    meets the tee's port, and the rules report the size change); returns the fitting items."""
    if reducer_made(run.dims.source, run.nominal, small.nominal) is False:
        b.note(
            pipes,
            f"the run changes from {size_text(run)} to {size_text(small)} at the tee {tee}, but ASME "
            f"B16.9 tees reduce on the outlet only and {run.dims.source} has no "
            f"{run.nominal} x {small.nominal} reducer to follow it: {small.id} meets the tee's "
            f"{size_text(run)} run end with nothing between",
        )
        return []
    length = float(run.dims.reducer_length)
    direction = -b.out[end]  # out of the tee along the run, into the smaller pipe
    start = np.asarray(port, float)
    stop = start + length * direction
    b.ends[end] = stop
    name = f"reducer after tee {tee}"
    b.fitting_at[end] = name
    geometry, b.allowance[end] = reducer_cone(start, stop, run, small, length)
    snap = {
        "status": "fitting",
        "dimensions": run.dims.source,
        "standard": _verdict(True, run.dims),
        "length": length,
        "sizes": [run.nominal, small.nominal],
        "connects": [tee, small.id],
        "notes": [*run.dims.notes, "the run reduces after the tee (tees reduce on the outlet)"],
    }
    return [("reducer", f"{tee}-{small.id}", geometry, run, snap)]


def _pieces(b: _Builder, i: int):
    """The (start, end) point pairs of pipe i after trimming and splitting."""
    p = b.pipes[i]
    start, end = b.ends[i, 0], b.ends[i, 1]
    cuts = sorted(b.splits.get(i, []))
    if not cuts:
        return [(start, end)]
    pieces = []
    prev = start
    for at, half in cuts:
        pieces.append((prev, b.base[i, 0] + (at - half) * p.axis))
        prev = b.base[i, 0] + (at + half) * p.axis
    pieces.append((prev, end))
    return pieces


def _piece_ok(b: _Builder, i: int) -> bool:
    for start, end in _pieces(b, i):
        if b.param(i, end) - b.param(i, start) < MIN_PIPE_LENGTH:
            return False
    return True


def build_spools(
    pipes: Sequence[PipeSpec],
    joints: Sequence[Joint],
    group_of: Sequence[str | None],
    *,
    max_bend_deg: float = MAX_BEND_DEG,
    reducer_notes=None,
    taken_ids: Iterable[str] = (),
    joint_distance: float = 0.15,
) -> tuple[list[Component], list[Spool]]:
    """Place fittings at the joints, trim pipes and group everything into spools.

    Parameters
    ----------
    pipes : sequence of PipeSpec
    joints : sequence of Joint
        Indices refer to ``pipes``.
    group_of : sequence of str or None
        Each pipe's scan group (a spool takes the group's name when all its pipes share it).
    max_bend_deg : float
        An elbow joint bending more than this (degrees) is not built (the pipes get a note).
    reducer_notes : mapping of (int, int) to str, optional
        A note for the eccentric reducer between pipes (i, j), ``i < j`` (why it is eccentric).
    taken_ids : iterable of str, optional
        Ids a spool must not take besides the pipes' (every scan object's id): a generated
        ``S<n>`` or a group's name already used by an object is skipped, so that a spool is
        never mistaken for an object (a column "S1" and spool "S1").
    joint_distance : float
        ``Tolerances.joint_distance`` (metres): a gap between collinear pipes of one size
        longer than :func:`fitting_fill_limit` gets a note (pipe the scan did not measure).

    Returns
    -------
    components : list of Component
        Pipes (or their pieces) and fittings, in pipe order with each fitting after the first
        pipe it joins.
    spools : list of Spool
    """
    b = _Builder(pipes, reducer_notes, joint_distance)
    active = []
    for jt in joints:
        if jt.kind in ("contact", "link"):
            continue
        if jt.kind == "elbow":
            (i, ki), (j, kj) = jt.ends
            bend = float(np.degrees(np.arccos(np.clip(-(b.out[i, ki] @ b.out[j, kj]), -1, 1))))
            if bend > max_bend_deg:
                names = f"{pipes[i].id}, {pipes[j].id}"
                for k in (i, j):
                    pipes[k].notes.append(
                        f"no elbow built between {names}: their {bend:.0f} degree bend is beyond "
                        f"an elbow's {max_bend_deg:.0f} (ASME B16.9 elbows turn 45 or 90 degrees)"
                    )
                continue
        active.append(jt)
    failed: list[Joint] = []
    for _ in range(len(active) + 1):
        b.reset()
        built = []
        for joint in active:
            if joint.kind == "elbow":
                built.extend((joint, item) for item in _elbow(b, joint))
            elif joint.kind == "inline":
                built.extend((joint, item) for item in _inline(b, joint))
            elif joint.kind == "tee":
                built.extend((joint, item) for item in _tee(b, joint))
            elif joint.kind == "lateral":
                built.extend((joint, item) for item in build_lateral(b, joint))
            elif joint.kind == "cross":
                built.extend((joint, item) for item in build_cross(b, joint))
        bad = [i for i in range(len(pipes)) if not _piece_ok(b, i)]
        if not bad:
            break
        worst = bad[0]
        # drop the joints at that pipe, one at a time, largest fitting first
        culprit = next(jt for jt in reversed(active) if worst in jt.pipes)
        active.remove(culprit)
        failed.append(culprit)
    for joint in failed:
        names = ", ".join(pipes[k].id for k in joint.pipes)
        for k in joint.pipes:
            pipes[k].notes.append(
                f"no {joint.kind} built between {names}: the fitting would not fit on the pipe"
            )

    # pipe components (with pieces)
    components: list[Component] = []
    piece_ids: dict[int, list[str]] = {}
    by_pipe: dict[int, list[Component]] = {}
    for i, p in enumerate(pipes):
        pieces = _pieces(b, i)
        ids = [p.id] if len(pieces) == 1 else [f"{p.id}.{k + 1}" for k in range(len(pieces))]
        piece_ids[i] = ids
        comps = []
        for (start, end), pid in zip(pieces, ids):
            comps.append((pid, start, end))
        by_pipe[i] = comps

    fittings_after: dict[int, list[tuple[str, str, object, PipeSpec, dict, float]]] = {}
    for joint, item in built:
        kind, name, geometry, size_of, snap = item[:5]
        if kind in ("tee", "cross") and joint.through is not None:
            i = joint.through
            at = item[6]
            cuts = sorted(b.splits[i])
            k = next(n for n, (pos, _) in enumerate(cuts) if abs(pos - at) < 1e-9)
            outlets = [pipes[end[0]].id for end in joint.ends]  # a tee's branch, or two
            name = "-".join([piece_ids[i][k], piece_ids[i][k + 1], *outlets])
            snap = {**snap, "connects": [piece_ids[i][k], piece_ids[i][k + 1], *outlets]}
        first = min(joint.pipes)
        # lagging runs on over the fittings of insulated pipes: the thickest of theirs
        insulation = max(pipes[k].component.insulation for k in joint.pipes)
        fittings_after.setdefault(first, []).append(
            (kind, name, geometry, size_of, snap, insulation)
        )

    # spools: pipes joined by any joint (including contacts and failed ones)
    roots = {group[0]: group for group in connected_groups(len(pipes), joints)}
    spool_of: dict[int, str] = {}
    reserved = {p.id for p in pipes} | set(taken_ids)  # every object's id
    used_names: set[str] = set(reserved)
    groups_count: dict[str, int] = {}
    for members in roots.values():
        names = {group_of[m] for m in members}
        if len(names) == 1 and None not in names:
            groups_count[next(iter(names))] = groups_count.get(next(iter(names)), 0) + 1
    counter = 0
    spool_names: dict[int, str] = {}
    for root, members in sorted(roots.items()):
        names = {group_of[m] for m in members}
        name = None
        if len(names) == 1 and None not in names:
            candidate = next(iter(names))
            if groups_count[candidate] == 1 and candidate not in used_names:
                name = candidate
        if name is None:
            counter += 1
            while f"S{counter}" in used_names:
                counter += 1
            name = f"S{counter}"
        used_names.add(name)
        spool_names[root] = name
        for m in members:
            spool_of[m] = name

    # An object keeps its own id; a generated name (a fitting "P2-P3", a piece "P1.2") gives
    # way to every object's, whichever comes first: a user matching CAD back to the scan by id
    # must find the object, not an elbow.
    seen_ids: set[str] = set()

    def unique(name: str, own: bool = False) -> str:
        out, k = name, 2
        while out in seen_ids or (not own and out in reserved):
            out = f"{name}~{k}"
            k += 1
            own = False
        seen_ids.add(out)
        return out

    spool_members: dict[str, list[str]] = {name: [] for name in spool_names.values()}
    pipe_length: dict[str, float] = {name: 0.0 for name in spool_names.values()}
    for i, p in enumerate(pipes):
        spool = spool_of[i]
        base = p.component
        corrections = list(base.corrections)
        end_notes = []
        for k, label in ((0, "start"), (1, "end")):
            moved = float((b.ends[i, k] - b.base[i, k]) @ b.out[i, k])
            at = b.fitting_at.get((i, k), "the joint")
            if (i, k) in b.filled:
                if b.filled[i, k] not in end_notes:
                    end_notes.append(b.filled[i, k])
            elif -moved > max(TRIM_NOTE, b.allowance.get((i, k), 0.0)):
                end_notes.append(
                    f"cut back {-moved * 1000:.0f} mm at its {label} for {at}: the fitting covers "
                    "pipe the scan measured there"
                )
            elif moved > EXTEND_NOTE + p.spacing:
                end_notes.append(
                    f"extended {moved * 1000:.0f} mm at its {label} to {at}, beyond its last shot "
                    f"(its shots' step along it at its ends: {p.spacing * 1000:.0f} mm): that pipe was not "
                    "measured"
                )
            if abs(moved) > 1e-7:
                corrections.append(
                    Correction(
                        what=f"{'extended' if moved > 0 else 'trimmed'} at {label}",
                        before=_vec(b.base[i, k]),
                        after=_vec(b.ends[i, k]),
                        size=abs(moved) * 1000.0,
                        unit="mm",
                    )
                )
        snap = dict(base.snap)
        said = list(p.notes) + b.pipe_notes.get(i, []) + end_notes
        if said:
            snap["merge_notes"] = said
        for pid, start, end in by_pipe[i]:
            geometry = Straight(start=start, end=end, outer_radius=0.5 * p.od, wall=p.wall)
            comp = Component(
                id=unique(pid, own=pid == p.id),
                type="pipe",
                geometry=geometry,
                sources=base.sources,
                spool=spool,
                group=base.group,
                label=base.label,
                nominal=p.nominal,
                schedule=p.schedule,
                fit=base.fit,
                snap=snap,
                corrections=tuple(corrections),
                insulation=base.insulation,
            )
            components.append(comp)
            spool_members[spool].append(comp.id)
            pipe_length[spool] += geometry.length
        for kind, name, geometry, size_of, snap, insulation in fittings_after.get(i, []):
            comp = Component(
                id=unique(name),
                type=kind,
                geometry=geometry,
                sources=(),
                spool=spool,
                group=base.group,
                nominal=size_of.nominal,
                schedule=size_of.schedule,
                snap=snap,
                insulation=insulation,
            )
            components.append(comp)
            spool_members[spool].append(comp.id)
    spools = [
        Spool(id=name, components=tuple(spool_members[name]), pipe_length=pipe_length[name])
        for name in spool_names.values()
    ]
    return components, spools
