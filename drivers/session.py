"""Scan sessions: raster and edge-seeking shots per object, a journal per shot, resume, scan file.

Per object (:func:`scan_target`, deterministic given the measured ranges):

1. **Raster.** A cell-centred grid over the window with at least the points the kind needs
   (:meth:`Target.wanted`), columns and rows in proportion to the window's width and height,
   shot row by row in serpentine order (short head moves); never fewer than 3 rows and 3
   columns (5 for cuboids: two lines on each of two seen faces), so a thin object (a pipe
   seen side-on) cannot fall between two rows of a loose window. Along a window at least
   twice as long as wide (a column's, a beam's) 3 lines suffice for cuboids too: the seen
   faces lie side by side across it (:func:`min_lines`), and with a small point budget the
   shots saved go to the edges.
2. **Foreground.** Valid returns are split at the largest gap in sorted range when it exceeds
   ``max(0.1 m, 5 %)``: the nearer cluster is the object the operator aimed at, the farther one
   the background behind it. Misses (no return, device errors) are background too.
3. **Fill.** If fewer than the wanted points landed on the object, a denser raster over the
   object's angular extent (its foreground cells, widened by half a cell) adds them
   (``fill_rounds`` times at most).
4. **Edges.** Neighbouring cells of which one is on the object and the other not bracket the
   object's silhouette (an object cell on the raster's border pairs with the cell beyond it,
   shot first: if that is on the object too, the object runs on beyond the window and the
   pair is dropped); each pair belongs to the side its outside cell is on (left, right,
   bottom, top: lower or higher pan or tilt). A side takes the pairs whose inside cell is on
   its outermost line of object cells (they bracket the object's extreme there, which bounds
   its unseen edges; a pair on an inner line brackets a stretch of silhouette cut short, such
   as a row through a column's top seen from below), from the finest raster that has any; on
   the sides along an elongated object (:func:`long_sides`) those with object cells on both
   sides along the edge first (a row through a column's end can be cut short by it). Of
   the pairs of a side that bracket the same two lines (a straight edge), only the middle
   one is kept. ``edge_pairs`` pairs are dealt to the sides in turn (every side gets some),
   each side's share at evenly spaced quantiles of its pairs (its middle pair for one); the
   foreground split is re-measured with every edge shot. A pair is bisected (shoot the
   midpoint, keep the half that still brackets the edge) until the bracket, as an angle times
   the range of its inside shot, is at most ``edge_tolerance`` metres, ``edge_depth`` steps
   at most, ``edge_shots`` shots per object at most. Cylinders and spheres take
   ``curved_depth`` steps (2) instead: their fits use surface points only, and shots pressed
   against a curved silhouette graze it (mixed returns). The last hit of a pair then lies
   within ``edge_tolerance`` (across the beam) of the silhouette edge, or within one head
   position when the head cannot aim finer (its steps are whole positions: the bracket is
   recorded as the head reached it, ``ObjectScan.brackets``, ``acquisition.edge_brackets``
   in the scan file), which bounds the
   object's unseen edges (a face's far edge, a column's top) far better than the raster (up
   to one raster step short). When that last hit shares its bisected angle with other hits
   (every step missed, so it is the raster shot the pair started from; or a step fell on a
   fill raster's column), a shot a bracket inside it (then two, then four brackets, until one
   hits: that last hit may be a pointing error's) gives the points a hit off the raster's
   lines a few brackets from the edge. On a face seen at incidence ``theta`` the
   bracket along the face is ``edge_tolerance / cos(theta)``.

Every shot is appended to a JSON-lines journal beside the output (``<out>.journal``) and
flushed to disk (fsync) before the next one, so nothing measured is lost; after each object the
scan file is rewritten atomically with every finished object. ``--resume`` replays the journal:
finished objects come back as they were and the interrupted object's algorithm is re-run with
its recorded shots served from the journal until it needs new ones.

Shots with device errors are retried ``retries`` times, then skipped and counted; a move the
pan-tilt unit refuses (``! <message>``) skips its shot. A range finder that times out, answers
unreadably (wrong line settings) or with an error that is not a miss (a refused command, an
interface or temperature error, a code of unknown meaning: anything but signal too weak, too
strong or too much background light), or a unit that refuses, on ``lost_after`` consecutive
shots, or a port that fails, ends the session with a :class:`~asbuilt.errors.DeviceError`
naming the device's code and its meaning (the journal keeps everything up to that shot).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from asbuilt.atomic import atomic_write, check_target
from asbuilt.errors import ScanError
from asbuilt.scan.insulation import MAX_INSULATION
from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS, Tolerances
from asbuilt.units import unit_factor

from . import plan as plans
from ._shots import DeviceShooter, Shot
from .edges import (
    BACK_STEPS,
    SIDES,
    boundary_pairs,
    bracket,
    deal_pairs,
    distinct_brackets,
    edge_turns,
    is_extreme,
    is_interior,
    long_sides,
    min_lines,
    on_a_line_shot,
    same_position,
)
from .journal import Journal, journal_path_for, read_journal
from .journal import Replay as _Replay
from .kinematics import Calibration, beam, forward
from .plan import DEFAULT_SETTINGS, SessionSettings, Target, Window
from .raster import _cell_index, foreground_threshold, grid

__all__ = [
    "Shot",
    "ObjectScan",
    "DeviceShooter",
    "grid",
    "min_lines",
    "foreground_threshold",
    "scan_target",
    "Journal",
    "read_journal",
    "ScanSession",
    "journal_path_for",
]

Shoot = Callable[[float, float, str], "Shot"]


@dataclass(frozen=True, eq=False)
class ObjectScan:
    """The shots of one object and which of them lie on it.

    Attributes
    ----------
    target : Target
    shots : tuple of Shot
        Every shot, in order.
    on_object : ndarray of bool, shape (len(shots),)
        Shots kept as the object's points.
    brackets : tuple of (int, int)
        Each bisected pair's last hit and the first miss beyond it (indices into ``shots``):
        the edge lies between the two beams, whatever the bracket the requested angles
        narrowed to (a head aims in whole positions).
    """

    target: Target
    shots: tuple[Shot, ...]
    on_object: np.ndarray
    brackets: tuple[tuple[int, int], ...] = ()

    @property
    def skipped(self) -> int:
        """Shots without a valid return after their retries (misses and device errors)."""
        return sum(1 for s in self.shots if s.range is None)

    def measurements(self) -> np.ndarray:
        """Unit pan (rad), tilt (rad) and raw range (m) of the object's points, shape (n, 3)."""
        kept = [s for s, k in zip(self.shots, self.on_object) if k]
        if not kept:
            return np.zeros((0, 3))
        return np.array([[s.pan, s.tilt, s.range] for s in kept], dtype=float)

    def points(self, calibration: Calibration) -> np.ndarray:
        """The object's points in the scan frame, shape (n, 3), metres."""
        m = self.measurements()
        if not len(m):
            return np.zeros((0, 3))
        return forward(calibration, m[:, 0], m[:, 1], m[:, 2])


def scan_target(
    target: Target,
    shoot: Shoot,
    settings: SessionSettings = DEFAULT_SETTINGS,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
) -> ObjectScan:
    """Shoot one object: raster, fill, edge bisection (see the module docstring).

    Parameters
    ----------
    target : Target
    shoot : callable ``(pan_rad, tilt_rad, phase) -> Shot``
        Moves, measures (with retries) and journals one shot.
    settings : SessionSettings
    tolerances : Tolerances
        Source of the paper's minimum point counts.

    Returns
    -------
    ObjectScan
    """
    wanted = target.wanted(tolerances)
    shots: list[Shot] = []

    def on_object(threshold: float) -> np.ndarray:
        return np.array(
            [
                s.range is not None and (settings.keep_background or s.range < threshold)
                for s in shots
            ],
            dtype=bool,
        )

    pan, tilt, (rows, cols) = grid(target.window, wanted, min_lines(target.kind, target.window))
    shots.extend(shoot(p, t, "raster") for p, t in zip(pan, tilt))
    grids = [(0, rows, cols, target.window)]
    for _ in range(settings.fill_rounds):
        threshold = foreground_threshold(s.range for s in shots)
        fg = on_object(threshold)
        if fg.sum() >= wanted:
            break
        start, r0, c0, win0 = grids[-1]
        cells = fg[start : start + r0 * c0][_cell_index(r0, c0)]
        if not cells.any():
            break
        rr, cc = np.nonzero(cells)
        dp, dt = win0.width / c0, win0.height / r0
        box = Window(
            win0.pan_min + (cc.min() - 0.5) * dp,
            win0.pan_min + (cc.max() + 1.5) * dp,
            win0.tilt_min + (rr.min() - 0.5) * dt,
            win0.tilt_min + (rr.max() + 1.5) * dt,
        )
        density = max(cells.mean() * (r0 * c0) * dp * dt / (box.width * box.height), 0.25)
        need = wanted - int(fg.sum())
        pan, tilt, (r1, c1) = grid(box, max(4, math.ceil(need / density)), min_cells=2)
        grids.append((len(shots), r1, c1, box))
        shots.extend(shoot(p, t, "fill") for p, t in zip(pan, tilt))

    threshold = foreground_threshold(s.range for s in shots)
    fg = on_object(threshold)
    sides: dict[str, list] = {side: [] for side in SIDES}
    # A side keeps the pairs on its outermost line of object cells (they bracket the object's
    # extreme on that side, which bounds its unseen edges), from the finest grid that has any.
    # Along an elongated object (:func:`long_sides`) those away from its ends come first
    # (:func:`is_interior`): a row through a column's end can be cut short by the end.
    along = long_sides(target.window)
    for interior in (True, False):
        for start, r0, c0, win0 in reversed(grids):  # finest grid first
            cells = fg[start : start + r0 * c0][_cell_index(r0, c0)]
            index = _cell_index(r0, c0) + start
            dp, dt = win0.width / c0, win0.height / r0
            found = boundary_pairs(cells)
            for side in SIDES:
                chosen = [
                    p
                    for p in found[side]
                    if is_extreme(p, cells, side)
                    and not (interior and side in along and not is_interior(p, cells, side))
                ]
                if sides[side] or not chosen:
                    continue
                sides[side] = [
                    (
                        np.array([win0.pan_min + (c + 0.5) * dp, win0.tilt_min + (r + 0.5) * dt]),
                        np.array([win0.pan_min + (c2 + 0.5) * dp, win0.tilt_min + (r2 + 0.5) * dt]),
                        float(shots[index[r, c]].range),
                        not (0 <= r2 < r0 and 0 <= c2 < c0),
                        int(index[r, c]),
                        int(index[r2, c2]) if 0 <= r2 < r0 and 0 <= c2 < c0 else -1,
                    )
                    for (r, c), (r2, c2) in chosen
                ]
                sides[side] = distinct_brackets(sides[side], 0 if side in ("left", "right") else 1)
    budget = settings.edge_budget()
    curved = target.kind in ("cylinder", "sphere")
    depth = min(settings.edge_depth, settings.curved_depth) if curved else settings.edge_depth

    def is_hit(shot: Shot) -> bool:
        # The split is re-measured with every edge shot: a raster that fell wholly on the object
        # saw no background yet, and the first shot beyond its border may be the first to.
        nonlocal threshold
        threshold = foreground_threshold(s.range for s in shots)
        return shot.range is not None and (settings.keep_background or shot.range < threshold)

    brackets = []  # (last hit, first miss beyond it), indices into shots
    for inside, outside, reach, beyond, hit_at, miss_at in deal_pairs(sides, settings.edge_pairs):
        if beyond:
            # The object reaches the raster's border here: the cell beyond it was not shot.
            if budget <= 0:
                break
            shot = shoot(float(outside[0]), float(outside[1]), "edge")
            shots.append(shot)
            budget -= 1
            if is_hit(shot):
                continue  # the object runs on beyond the window: no edge to pin here
            miss_at = len(shots) - 1
        for _ in range(depth):
            if budget <= 0:
                break
            if not curved and bracket(inside, outside) * reach <= settings.edge_tolerance:
                break
            mid = 0.5 * (inside + outside)
            shot = shoot(float(mid[0]), float(mid[1]), "edge")
            shots.append(shot)
            budget -= 1
            # A head that aims in whole positions reached one end of the bracket again: the
            # bracket is one position across and cannot narrow; another step would only repeat
            # this shot (and count its point twice).
            repeated = any(at >= 0 and same_position(shots[at], shot) for at in (hit_at, miss_at))
            if is_hit(shot):
                inside, reach, hit_at = mid, float(shot.range), len(shots) - 1
            else:
                outside, miss_at = mid, len(shots) - 1
            if repeated:
                break
        if not curved and miss_at >= 0:
            brackets.append((hit_at, miss_at))
        if (
            not curved
            and budget > 0
            and bracket(inside, outside) * reach <= settings.edge_tolerance
            and on_a_line_shot(
                inside,
                outside,
                shots[hit_at],
                shots,
                lambda s: s.range is not None and (settings.keep_background or s.range < threshold),
            )
        ):
            # The last hit lies within the tolerance of the edge, but on a line of other hits
            # (the raster shot the pair started from, when every step missed, or a step that
            # fell on a fill raster's column): the points alone cannot tell it from a raster
            # shot. A shot a bracket inside it lands on the object off those lines, within two
            # brackets of the edge, and marks the edge there; should it miss (the last hit
            # was a pointing error's, the edge lies inside that line), two and then four
            # brackets inside.
            for back_by in BACK_STEPS:
                if budget <= 0:
                    break
                back = inside - back_by * (outside - inside)
                shot = shoot(float(back[0]), float(back[1]), "edge")
                shots.append(shot)
                budget -= 1
                if is_hit(shot):
                    break
    return ObjectScan(target, tuple(shots), on_object(threshold), tuple(brackets))


# -- session --------------------------------------------------------------------------------------
@dataclass
class _Resumed:
    done: dict = field(default_factory=dict)  # id -> ObjectScan
    order: list = field(default_factory=list)  # ids in journal order (done or failed)
    pending: Target | None = None
    pending_shots: list = field(default_factory=list)
    failed: dict = field(default_factory=dict)  # id -> reason


def _file_thickness(metres: float, k: float) -> float:
    """An insulation thickness in the file's units (``k`` metres each), to 9 decimals (50 mm
    stays ``50``, not ``50.00000000000001``) unless the rounding would take it past the scan
    loader's :data:`~asbuilt.scan.insulation.MAX_INSULATION` once converted back."""
    value = round(metres / k, 9)
    return value if value * k <= MAX_INSULATION else metres / k


class ScanSession:
    """An acquisition session writing one scan file.

    Parameters
    ----------
    shooter : callable ``(pan, tilt, phase) -> Shot``
        Usually a :class:`DeviceShooter`.
    calibration : Calibration
        Turns the measurements into points.
    out : str or Path
        The scan file (rewritten atomically after each object); the journal goes beside it.
    units : str
        Length unit of the scan file.
    settings : SessionSettings
    resume : bool
        Continue from an existing journal (else refuse to overwrite one).
    on_shot : callable ``(target, shot, taken, planned)``, optional
        Progress callback after every shot (``planned`` is an estimate for the object).
    name : str, optional
        The scan's name.
    tolerances : Tolerances
    plan, plan_file : Plan and str, optional
        The targets' plan and its file (None: prompts), journaled; a resume must give the same.

    Raises
    ------
    ScanError
        A journal exists and ``resume`` is False, or ``resume`` without a journal or with
        another plan than the session's (:func:`~asbuilt.drivers.plan.resume_plan_mismatch`).
    """

    def __init__(
        self,
        shooter: Shoot,
        calibration: Calibration,
        out,
        *,
        units: str = "m",
        settings: SessionSettings = DEFAULT_SETTINGS,
        resume: bool = False,
        on_shot=None,
        name: str | None = None,
        tolerances: Tolerances = DEFAULT_TOLERANCES,
        plan: plans.Plan | None = None,
        plan_file: str | None = None,
    ):
        from .calibration import calibration_to_dict

        unit_factor(units)
        self.shooter = shooter
        self.calibration = calibration
        self.out = Path(out)
        self.units = units
        self.settings = settings
        self.on_shot = on_shot
        self.name = name
        self.tolerances = tolerances
        self.journal_path = journal_path_for(self.out)
        self.objects: dict[str, ObjectScan] = {}
        self.failed: dict[str, str] = {}
        self._resumed = _Resumed()
        # Check all before touching the journal (Journal() modifies nothing until an append).
        check_target(self.out, "--out", example="scan.json")
        exists = self.journal_path.exists() and self.journal_path.stat().st_size > 0
        if resume:
            if not exists:
                raise ScanError(
                    "no journal to resume from; start without --resume",
                    source=str(self.journal_path),
                )
            self._load_journal(plan, plan_file)
        elif exists:
            raise ScanError(
                "a journal of an earlier session is here; continue it with --resume or choose "
                "another --out",
                source=str(self.journal_path),
            )
        self.journal = Journal(self.journal_path)
        self.objects.update(self._resumed.done)
        self.failed.update(self._resumed.failed)
        if self.objects:  # the finished objects, before the journal is appended to
            try:
                self.write_scan()
            except BaseException:
                self.journal.close()
                raise
        if not resume:
            self.journal.append(
                {
                    "type": "session",
                    "version": 1,
                    "units": units,
                    "name": name,
                    "started": datetime.now(timezone.utc).isoformat(timespec="seconds"),
                    "calibration": calibration_to_dict(calibration),
                    "settings": dataclasses.asdict(settings),
                    "plan": plans.plan_record(plan, plan_file and Path(plan_file).name),
                }
            )
        else:
            self.journal.append(
                {"type": "resume", "at": datetime.now(timezone.utc).isoformat(timespec="seconds")}
            )

    # -- resume ----------------------------------------------------------------------------
    def _load_journal(self, plan=None, plan_file: str | None = None) -> None:
        recs = read_journal(self.journal_path)
        source = str(self.journal_path)
        if not recs or recs[0].get("type") != "session":
            raise ScanError(
                "does not start with a session record; not a scan journal", source=source
            )
        mismatch = plans.resume_plan_mismatch(recs, plan, plan_file and Path(plan_file).name)
        if mismatch:
            raise ScanError(mismatch, source=source)
        try:
            self.settings = SessionSettings(**recs[0].get("settings", {}))
        except (TypeError, ValueError) as exc:
            raise ScanError(
                f"bad session settings ({exc})", source=source, where="line 1"
            ) from None
        if recs[0].get("units", self.units) != self.units:
            raise ScanError(
                f"the session wrote {recs[0].get('units')!r}; resume with --units "
                f"{recs[0].get('units')}",
                source=source,
            )
        targets: dict[str, Target] = {}
        shots: dict[str, list[Shot]] = {}
        current = begun = None  # the object begun last and not ended, its record's line
        r = self._resumed
        for i, rec in enumerate(recs):
            kind = rec.get("type")
            try:
                if kind == "object":
                    target = Target.from_dict(rec["target"], source=source, where=f"line {i + 1}")
                    targets[target.id] = target
                    shots[target.id] = []
                    current, begun = target.id, i + 1
                elif kind == "shot":
                    shots[rec["object"]].append(Shot.from_record(rec))
                elif kind in ("done", "failed"):
                    oid = rec["id"]
                    if kind == "done":
                        r.done[oid] = self._finish(targets[oid], shots[oid])
                        r.failed.pop(oid, None)
                    else:
                        r.failed[oid] = rec.get("reason", "")
                    r.order.append(oid)
                    current = None
            except (KeyError, TypeError, ValueError, IndexError, OverflowError) as exc:
                raise ScanError(
                    f"unreadable record ({exc})", source=source, where=f"line {i + 1}"
                ) from None
        if current is not None:
            if current in r.done:  # scan() refuses a finished id before journaling its object
                why = f"object {current!r} is begun again after it was finished; the journal"
                where = f"line {begun}"
                raise ScanError(f"{why} was edited, cannot resume", source=source, where=where)
            r.pending = targets[current]
            r.pending_shots = shots[current]

    def _finish(self, target: Target, shots: list[Shot]) -> ObjectScan:
        """Re-run the planner over recorded shots (no device) to rebuild a finished object."""
        replay = _Replay(shots, None)
        return scan_target(target, replay, self.settings, self.tolerances)

    @property
    def pending(self) -> Target | None:
        """The object a resumed journal was in the middle of (scan it first), or None."""
        return self._resumed.pending

    def is_done(self, object_id: str) -> bool:
        """Whether an object with this id is already in the scan."""
        return object_id in self.objects

    # -- scanning --------------------------------------------------------------------------
    def scan(self, target: Target) -> ObjectScan | None:
        """Shoot ``target``, journal every shot, add it to the scan file.

        Returns
        -------
        ObjectScan or None
            None when too few shots landed on the object (recorded in :attr:`failed`; the
            shots stay in the journal).
        """
        if target.id in self.objects:
            raise ScanError(
                f"object id {target.id!r} is already in the scan; choose another id",
                source=str(self.out),
            )
        recorded: list[Shot] = []
        if self._resumed.pending is not None and self._resumed.pending.id == target.id:
            recorded = self._resumed.pending_shots
            target = self._resumed.pending
            self._resumed.pending = None
        else:
            self.journal.append({"type": "object", "target": target.to_dict()})
        seq = len(recorded)
        planned = target.wanted(self.tolerances) + self.settings.edge_budget()
        taken = 0

        def live(pan: float, tilt: float, phase: str) -> Shot:
            nonlocal seq
            shot = self.shooter(pan, tilt, phase)
            self._note_unsolicited()
            self.journal.append(shot.to_record(target.id, seq))
            seq += 1
            return shot

        replay = _Replay(recorded, live)

        def counted(pan: float, tilt: float, phase: str) -> Shot:
            nonlocal taken, planned
            shot = replay(pan, tilt, phase)
            taken += 1
            planned = max(planned, taken)
            if self.on_shot is not None:
                self.on_shot(target, shot, taken, planned)
            return shot

        result = scan_target(target, counted, self.settings, self.tolerances)
        n = int(result.on_object.sum())
        minimum = MIN_POINTS.get(target.kind, 7)
        if n < minimum:
            reason = self._too_few(result.shots, n, minimum)
            self.journal.append({"type": "failed", "id": target.id, "reason": reason})
            self.failed[target.id] = reason
            return None
        self.journal.append({"type": "done", "id": target.id, "points": n})
        self.objects[target.id] = result
        self.failed.pop(target.id, None)
        self.write_scan()
        return result

    def _note_unsolicited(self) -> None:
        """Journal the lines the pan-tilt unit sent on its own (a power-up banner...), which
        its driver skipped, and its driver's notes (a Pelco-D head's tilt encoding), as ``note``
        records (a resume ignores them)."""
        ptu = getattr(self.shooter, "ptu", None)
        for key in ("unsolicited", "notes"):  # notes: what a driver found out (Pelco-D)
            lines = getattr(ptu, key, None)
            if isinstance(lines, list) and lines:
                self.journal.append({"type": "note", "device": "ptu", key: list(lines)})
                lines.clear()

    def _too_few(self, shots: list[Shot], n: int, minimum: int) -> str:
        """Why an object with ``n`` shots on it is not in the scan: aim, or the unit's reach."""
        short = f"{n} shots on the object, {minimum} needed at least"
        beyond = [(s.pan_req, s.tilt_req) for s in shots if s.error == "limit"]
        if not beyond or 2 * len(beyond) < len(shots):  # mostly shot: the aim was off
            return f"{short}; re-aim the window"
        limits = getattr(getattr(self.shooter, "ptu", None), "limits", None)  # DeviceShooter's
        ranges = limits.ranges_missed(beyond) if limits is not None else ""
        return (
            f"{len(beyond)} of {len(shots)} shots were beyond the pan-tilt unit's "
            f"{ranges or 'limits'} ({short}); put the window within reach or move the station"
        )

    def close(self) -> None:
        """Close the journal."""
        self.journal.close()

    def __enter__(self) -> ScanSession:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- output ----------------------------------------------------------------------------
    def beam_origin(self) -> np.ndarray:
        """Where the beams start, shape (3,), metres, scan frame: the scan's sensor position.

        The fits read the shots' raster (rows, columns, bisection shots) from their directions
        as seen from the sensor position. The beams start on the tilt axis, not at the base: a
        PTU-D46's 47 mm above it, seen from the base, turns each shot's tilt by a parallax that
        changes with its range, enough to break a row apart (the column of the docs' site lost
        a measured size in 5 of 8 scans). With the laser on the tilt axis the beams all start at
        one point; with a laser offset, the mean of the object shots' origins (a few
        millimetres from each).
        """
        angles = [r.measurements()[:, :2] for r in self.objects.values()]
        angles = np.concatenate(angles) if angles else np.zeros((0, 2))
        if not len(angles):
            angles = np.zeros((1, 2))
        origins, _ = beam(self.calibration, angles[:, 0], angles[:, 1])
        return origins.mean(axis=0)

    def document(self) -> dict:
        """The ``asbuilt-scan`` document of every finished object (file units)."""
        k = unit_factor(self.units)
        objects = []
        for result in self.objects.values():
            t = result.target
            m = result.measurements()
            pts = result.points(self.calibration) / k
            obj = {
                "id": t.id,
                "kind": t.kind,
                "points": np.round(pts, 9).tolist(),
                "measurements": [
                    [math.degrees(p), math.degrees(q), r / k] for p, q, r in m.tolist()
                ],
            }
            for key in ("group", "label", "nominal"):
                if getattr(t, key) is not None:
                    obj[key] = getattr(t, key)
            if t.insulation is not None:
                obj["insulation"] = _file_thickness(t.insulation, k)
            obj["acquisition"] = {
                "window_deg": t.window.degrees(),
                "shots": len(result.shots),
                "skipped": result.skipped,
                "background": int(
                    sum(
                        1
                        for s, on in zip(result.shots, result.on_object)
                        if s.range is not None and not on
                    )
                ),
            }
            turns = edge_turns(result, self.calibration)
            if turns:
                obj["acquisition"]["edge_brackets"] = turns
            objects.append(obj)
        doc = {"format": "asbuilt-scan", "version": 1, "units": self.units}
        if self.name:
            doc["name"] = self.name
        doc["sensor"] = {"position": [v / k for v in self.beam_origin()]}
        doc["objects"] = objects
        from .calibration import calibration_to_dict

        doc["acquisition"] = {
            "journal": self.journal_path.name,
            "calibration": calibration_to_dict(self.calibration),
            "failed": dict(self.failed),
        }
        return doc

    def write_scan(self) -> None:
        """Rewrite the scan file atomically with every finished object."""
        with atomic_write(self.out, "w") as f:
            json.dump(self.document(), f, indent=1)
            f.write("\n")
