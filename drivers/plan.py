"""Scan targets and plan files (the scripted mode of ``asbuilt scan --plan``).

A target is what the operator says and points at: an id, a kind and a window of unit angles
(two corner directions). A plan file lists targets for repeatable runs::

    {"format": "asbuilt-scan-plan", "version": 1,
     "settings": {"retries": 2, "edge_pairs": 4, "edge_tolerance": 0.002},
     "targets": [
       {"id": "P1", "kind": "cylinder", "window_deg": [-10, -3, 12, 4],
        "points": 24, "group": "line-1", "nominal": "4\\"", "insulation": 0.05}]}

``window_deg`` is ``[pan1, tilt1, pan2, tilt2]``: two opposite corners in the pan-tilt unit's
own degrees (as its position readout shows them); ``points`` is optional (default: the paper's
minimum for the kind). Settings are optional and override the command-line defaults; they are
the fields of :class:`SessionSettings` (``edge_tolerance`` in metres, the others counts or
true/false). A cylinder's optional ``insulation`` is the thickness of its lagging and cladding in
metres, like every length in a plan (whatever the scan's ``--units``); the session writes it to
the scan object in the scan file's units.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from asbuilt._text import loads_json, read_text
from asbuilt.errors import ScanError
from asbuilt.scan.insulation import INSULATED_KINDS, MAX_INSULATION
from asbuilt.scan.load import MAX_POINTS
from asbuilt.scan.model import KINDS
from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS, Tolerances

__all__ = [
    "Window",
    "Target",
    "Plan",
    "SessionSettings",
    "DEFAULT_SETTINGS",
    "TARGET_KEYS",
    "PLAN_KEYS",
    "required_points",
    "check_insulation",
    "load_plan",
    "plan_to_dict",
    "plan_digest",
    "plan_record",
    "resume_plan_mismatch",
]


@dataclass(frozen=True)
class Window:
    """A rectangle of unit angles, radians (``pan_min < pan_max``, ``tilt_min < tilt_max``)."""

    pan_min: float
    pan_max: float
    tilt_min: float
    tilt_max: float

    def __post_init__(self) -> None:
        values = (self.pan_min, self.pan_max, self.tilt_min, self.tilt_max)
        if not all(math.isfinite(v) for v in values):
            raise ValueError("window angles must be finite")
        if self.pan_max <= self.pan_min or self.tilt_max <= self.tilt_min:
            raise ValueError("a window needs two different pan and two different tilt angles")

    @classmethod
    def from_corners(cls, pan1: float, tilt1: float, pan2: float, tilt2: float) -> Window:
        """The window spanned by two corner directions (radians, any order)."""
        return cls(min(pan1, pan2), max(pan1, pan2), min(tilt1, tilt2), max(tilt1, tilt2))

    @classmethod
    def from_degrees(cls, corners) -> Window:
        """From ``[pan1, tilt1, pan2, tilt2]`` in degrees."""
        return cls.from_corners(*(math.radians(float(v)) for v in corners))

    def degrees(self) -> list[float]:
        """``[pan_min, tilt_min, pan_max, tilt_max]`` in degrees."""
        return [math.degrees(v) for v in (self.pan_min, self.tilt_min, self.pan_max, self.tilt_max)]

    @property
    def width(self) -> float:
        """Pan extent, radians."""
        return self.pan_max - self.pan_min

    @property
    def height(self) -> float:
        """Tilt extent, radians."""
        return self.tilt_max - self.tilt_min


#: Largest window angle, degrees: a turn either way (a larger one overflows the raster planner).
_MAX_DEGREES = 360.0


def required_points(kind: str, tolerances: Tolerances = DEFAULT_TOLERANCES) -> int:
    """Points an object of ``kind`` needs on its surface (at least the paper's minimums).

    Cylinders 20 and cuboids 30 (Kwon et al.: ``Tolerances.recommended_points_*``); spheres
    like cylinders; planes 12; hulls and "auto" like cuboids.
    """
    paper = {
        "cylinder": tolerances.recommended_points_cylinder,
        "sphere": tolerances.recommended_points_cylinder,
        "cuboid": tolerances.recommended_points_cuboid,
        "hull": tolerances.recommended_points_cuboid,
        "auto": tolerances.recommended_points_cuboid,
        "plane": 12,
    }
    return max(paper.get(kind, tolerances.recommended_points_cuboid), MIN_POINTS.get(kind, 7))


#: The keys a plan target may have (anything else is refused: a typo would drop the field).
TARGET_KEYS = ("id", "kind", "window_deg", "points", "group", "label", "nominal", "insulation")

#: The top-level keys of a plan file (``comment``: free text, as in the example files).
PLAN_KEYS = ("format", "version", "comment", "settings", "targets")


@dataclass(frozen=True)
class Target:
    """One object to scan.

    Attributes
    ----------
    id : str
    kind : str
        One of :data:`asbuilt.scan.KINDS`.
    window : Window
        Unit angles to cover.
    points : int or None
        Points wanted on the object (None: :func:`required_points`).
    group, label, nominal : str or None
        Copied to the scan object.
    insulation : float or None
        Metres: the thickness of the insulation (lagging and cladding) a cylinder's points are
        measured on (see :func:`check_insulation`); written to the scan object in the file's
        units. None: not given (a bare pipe).
    """

    id: str
    kind: str
    window: Window
    points: int | None = None
    group: str | None = None
    label: str | None = None
    nominal: str | None = None
    insulation: float | None = None

    def __post_init__(self) -> None:
        check_insulation(self.insulation, self.kind, where=f"{self.id}.insulation")

    def wanted(self, tolerances: Tolerances = DEFAULT_TOLERANCES) -> int:
        """Points to collect: ``points`` but never fewer than :func:`required_points`."""
        return max(self.points or 0, required_points(self.kind, tolerances))

    def to_dict(self) -> dict:
        """JSON form (as in a plan file)."""
        d = {"id": self.id, "kind": self.kind, "window_deg": self.window.degrees()}
        for key in ("points", "group", "label", "nominal", "insulation"):
            if getattr(self, key) is not None:
                d[key] = getattr(self, key)
        return d

    @classmethod
    def from_dict(cls, raw, *, source: str | None = None, where: str = "target") -> Target:
        """Parse the JSON form; ScanError naming the field on any problem."""
        if not isinstance(raw, dict):
            raise ScanError("must be an object", source=source, where=where)
        tid = raw.get("id")
        if not isinstance(tid, str) or not tid.strip():
            raise ScanError("needs a non-empty string id", source=source, where=f"{where}.id")
        where = f"{where} ({tid})"
        for key in raw:  # a typo ("insualtion") would silently drop what it says
            if key not in TARGET_KEYS:
                raise ScanError(
                    f"unknown key; use {', '.join(TARGET_KEYS)}",
                    source=source,
                    where=f"{where}.{key}",
                )
        kind = raw.get("kind")
        if kind not in KINDS:
            raise ScanError(
                f"kind {kind!r} is not one of {', '.join(KINDS)}",
                source=source,
                where=f"{where}.kind",
            )
        corners = raw.get("window_deg")
        if (
            not isinstance(corners, list)
            or len(corners) != 4
            or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in corners)
        ):
            raise ScanError(
                "must be [pan1, tilt1, pan2, tilt2] in degrees",
                source=source,
                where=f"{where}.window_deg",
            )
        if not all(abs(v) <= _MAX_DEGREES for v in corners):  # NaN and infinities fail too
            raise ScanError(
                f"angles must be finite and within +-{_MAX_DEGREES:g} degrees (a turn)",
                source=source,
                where=f"{where}.window_deg",
            )
        try:
            window = Window.from_degrees(corners)
        except ValueError as exc:
            raise ScanError(str(exc), source=source, where=f"{where}.window_deg") from None
        points = raw.get("points")
        if points is not None and (
            not isinstance(points, int) or isinstance(points, bool) or points < 1
        ):
            raise ScanError("must be a positive integer", source=source, where=f"{where}.points")
        if points is not None and points > MAX_POINTS:
            raise ScanError(
                f"must be at most {MAX_POINTS:,} (the most a scan holds)",
                source=source,
                where=f"{where}.points",
            )
        extra = {}
        for key in ("group", "label", "nominal"):
            value = raw.get(key)
            if value is not None and not isinstance(value, str):
                raise ScanError("must be a string", source=source, where=f"{where}.{key}")
            extra[key] = value
        extra["insulation"] = check_insulation(
            raw.get("insulation"), kind, source=source, where=f"{where}.insulation"
        )
        return cls(tid, kind, window, points, **extra)


def _shown(value) -> str:
    """A short phrase for a JSON value in messages (as the scan loader words them)."""
    if value is None or isinstance(value, bool):
        return json.dumps(value)
    if isinstance(value, str):
        return f"a string ({json.dumps(value if len(value) <= 20 else value[:17] + '...')})"
    if isinstance(value, (list, dict)):
        return "an array" if isinstance(value, list) else "an object"
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else "infinite"
    text = repr(value)
    return text if len(text) <= 20 else text[:17] + "..."


def check_insulation(value, kind: str, *, source: str | None = None, where: str = "insulation"):
    """A target's insulation thickness in metres (None when absent or null), or ScanError.

    The scan loader's rules (:data:`~asbuilt.scan.insulation.MAX_INSULATION`,
    :data:`~asbuilt.scan.insulation.INSULATED_KINDS`) in the plan's metres: a number >= 0, at most
    0.5 m (more is a unit slip: ``50`` meaning millimetres), and above 0 only on a cylinder.
    """
    if value is None:
        return None
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not number or (isinstance(value, float) and not math.isfinite(value)) or value < 0:
        raise ScanError(
            f"must be a number >= 0 (the insulation's thickness in metres), not {_shown(value)}",
            source=source,
            where=where,
        )
    if value > MAX_INSULATION:  # an integer of any length compares without overflow
        raise ScanError(
            f"{_shown(value)} m is thicker than any pipe insulation (at most "
            f"{MAX_INSULATION:g} m); a plan's lengths are in metres (50 mm is 0.05): check the "
            "value",
            source=source,
            where=where,
        )
    if value > 0 and kind not in INSULATED_KINDS:
        raise ScanError(
            f'insulation is a radial thickness on a cylinder, not on kind "{kind}"; give the '
            'target "kind": "cylinder" or remove its insulation',
            source=source,
            where=where,
        )
    return abs(float(value))  # -0.0 is 0


@dataclass(frozen=True)
class SessionSettings:
    """How a session shoots.

    Attributes
    ----------
    retries : int
        Extra attempts for a shot that fails with a device error, before it is skipped.
    edge_pairs : int
        Hit/miss neighbour pairs refined per object by bisection, dealt in turn to the
        silhouette's four sides (left, right, bottom, top) so that every side gets some.
    edge_depth : int
        Most bisection steps per pair (each halves the angular bracket of the boundary).
    edge_tolerance : float
        Metres: a pair is bisected until its bracket, as an angle times the range of its
        inside shot (the width across the beam at the object), is at most this (or
        ``edge_depth`` steps are taken). 2 mm is about the range noise and the pointing noise
        at 10 m, below which bisection gains nothing.
    edge_shots : int
        Most edge shots per object, all pairs together (the default leaves room for four
        pairs of ten steps: a bracket of 2 m down to 2 mm).
    curved_depth : int
        Bisection steps per pair for cylinders and spheres instead of ``edge_tolerance``: their
        fits use the surface points only, and shots pressed against a curved silhouette graze
        it (mixed returns, outliers), so two steps (a quarter cell) are enough there.
    fill_rounds : int
        Denser rasters over the object's angular extent when the first raster put too few
        points on it.
    lost_after : int
        Consecutive shots that time out before the device is declared lost.
    keep_background : bool
        Also put returns judged to be background (beyond the range gap) into the object.
    """

    retries: int = 2
    edge_pairs: int = 4
    edge_depth: int = 10
    edge_tolerance: float = 0.002
    edge_shots: int = 40
    curved_depth: int = 2
    fill_rounds: int = 2
    lost_after: int = 3
    keep_background: bool = False

    def __post_init__(self) -> None:
        names = ("retries", "edge_pairs", "edge_depth", "edge_shots", "curved_depth", "fill_rounds")
        for name in names:
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be >= 0")
        if not (math.isfinite(self.edge_tolerance) and self.edge_tolerance > 0):
            raise ValueError("edge_tolerance must be a length > 0 (metres)")
        if self.lost_after < 1:
            raise ValueError("lost_after must be >= 1")

    def edge_budget(self) -> int:
        """Most edge shots one object can take: ``edge_shots``, or fewer when the pairs cannot
        use them (pairs x (depth + 1): the bisection steps and a check of the cell beyond the
        raster's border)."""
        return min(self.edge_shots, self.edge_pairs * (self.edge_depth + 1))


#: The default settings (module-level so functions can default to it).
DEFAULT_SETTINGS = SessionSettings()


@dataclass(frozen=True)
class Plan:
    """A plan file: targets in order and optional settings overrides."""

    targets: tuple[Target, ...]
    settings: dict = field(default_factory=dict)


_SETTING_TYPES = {
    "retries": int,
    "edge_pairs": int,
    "edge_depth": int,
    "edge_tolerance": float,
    "edge_shots": int,
    "curved_depth": int,
    "fill_rounds": int,
    "lost_after": int,
    "keep_background": bool,
}


def load_plan(path) -> Plan:
    """Read a plan file; ScanError (one located line) on any problem."""
    path = Path(path)
    source = str(path)
    text = read_text(
        path,
        ScanError,
        what="plan",
        missing="cannot read the plan (No such file or directory); check the path",
    )
    try:
        doc = loads_json(text, ScanError, source=source)
    except json.JSONDecodeError as exc:
        raise ScanError(f"not valid JSON (line {exc.lineno}: {exc.msg})", source=source) from None
    except RecursionError:
        raise ScanError("not valid JSON (nested too deeply)", source=source) from None
    if not isinstance(doc, dict) or doc.get("format") != "asbuilt-scan-plan":
        raise ScanError(
            'not a plan file; start it with {"format": "asbuilt-scan-plan", "version": 1}',
            source=source,
        )
    if doc.get("version") != 1:
        raise ScanError("version must be 1", source=source, where="version")
    for key in doc:
        if key not in PLAN_KEYS:
            raise ScanError(f"unknown key; use {', '.join(PLAN_KEYS)}", source=source, where=key)
    if "comment" in doc and not isinstance(doc["comment"], str):
        raise ScanError("must be a string", source=source, where="comment")
    raw_targets = doc.get("targets")
    if not isinstance(raw_targets, list) or not raw_targets:
        raise ScanError("needs a non-empty array of targets", source=source, where="targets")
    targets = tuple(
        Target.from_dict(t, source=source, where=f"targets[{i}]") for i, t in enumerate(raw_targets)
    )
    seen: set[str] = set()
    for i, t in enumerate(targets):
        if t.id in seen:
            raise ScanError(
                "duplicate id; ids must be unique", source=source, where=f"targets[{i}] ({t.id})"
            )
        seen.add(t.id)
    settings = doc.get("settings", {})
    if not isinstance(settings, dict):
        raise ScanError("must be an object", source=source, where="settings")
    for key, value in settings.items():
        kind = _SETTING_TYPES.get(key)
        if kind is None:
            raise ScanError(
                f"unknown setting; use {', '.join(_SETTING_TYPES)}",
                source=source,
                where=f"settings.{key}",
            )
        if kind is float:
            ok = (
                isinstance(value, (int, float))
                and not isinstance(value, bool)
                and math.isfinite(value)
                and value > 0
            )
            expected = "a length in metres > 0"
        elif kind is int:
            least = 1 if key == "lost_after" else 0
            ok = isinstance(value, int) and not isinstance(value, bool) and value >= least
            expected = f"an integer >= {least}"
        else:
            ok = isinstance(value, bool)
            expected = "true or false"
        if not ok:
            raise ScanError(f"must be {expected}", source=source, where=f"settings.{key}")
    return Plan(targets, dict(settings))


def plan_to_dict(plan: Plan) -> dict:
    """The JSON document of ``plan``."""
    doc = {
        "format": "asbuilt-scan-plan",
        "version": 1,
        "targets": [t.to_dict() for t in plan.targets],
    }
    if plan.settings:
        doc["settings"] = dict(plan.settings)
    return doc


def plan_digest(plan: Plan) -> str:
    """SHA-256 (hex) of the plan's targets in their JSON form (order, ids, kinds, windows...).

    The settings are left out: a session keeps its own (the journal records them).
    """
    text = json.dumps([t.to_dict() for t in plan.targets], sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def plan_record(plan: Plan | None, name: str | None = None) -> dict | None:
    """The journal's session ``plan`` field: the plan file's name, its target count and
    :func:`plan_digest`; None for a session without a plan (the targets come from prompts)."""
    if plan is None:
        return None
    return {"file": name, "targets": len(plan.targets), "sha256": plan_digest(plan)}


def _targets(n) -> str:
    return f"{n} target" if n == 1 else f"{n} targets"


def resume_plan_mismatch(records: list, plan: Plan | None, name: str | None = None) -> str | None:
    """Why ``plan`` (None: the prompts) cannot continue the journaled session, or None.

    A journal whose session record has a ``plan`` field must be resumed with the same plan
    (same targets: :func:`plan_digest`), or without one if it had none. An older journal,
    without the field, is checked by its objects: each target it began must be in the plan as
    it was journaled.
    """
    head = records[0] if records else {}
    if "plan" in head:
        recorded = head["plan"] if isinstance(head["plan"], dict) else None
        if recorded is None:
            if plan is None:
                return None
            return "the journal's session took its targets from the prompts; resume without --plan"
        was = f"{recorded.get('file') or 'a plan'} ({_targets(recorded.get('targets'))})"
        if plan is None:
            return f"the journal's session ran the plan {was}; resume with that --plan"
        if recorded.get("sha256") != plan_digest(plan):
            now = f"{name} ({_targets(len(plan.targets))})" if name else "this plan"
            return (
                f"the journal's session ran another plan, {was}, not {now}; resume with the "
                "session's own --plan, or choose another --out for this one"
            )
        return None
    if plan is None:
        return None
    mine = {t.id: t.to_dict() for t in plan.targets}
    for rec in records:
        target = rec.get("target") if rec.get("type") == "object" else None
        if isinstance(target, dict) and mine.get(target.get("id")) != target:
            how = "gives otherwise" if target.get("id") in mine else "does not have"
            return (
                f"the journal's session scanned target {target.get('id')!r}, which "
                f"{name or 'this plan'} {how}; resume with the session's own --plan, or choose "
                "another --out for this one"
            )
    return None
