"""The as-built model: plain frozen data (components with geometry, spools, findings).

Fitting makes primitives; merging (:mod:`asbuilt.merge`) turns pipes into spools of standard
components; the rules add findings; the CAD layer and the exporters read this and nothing else.
All lengths are metres, in the scan frame (z up).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from .errors import FitError
from .findings import Finding
from .fit.result import FitFailure, FitReport, FitResult
from .primitives import Cuboid, Cylinder, Hull, Plane, Primitive, Sphere, as_vector
from .scan.model import Scan, ScanObject

__all__ = [
    "Straight",
    "Bend",
    "Reducer",
    "Tee",
    "Cross",
    "Geometry",
    "Correction",
    "Component",
    "Spool",
    "Model",
    "COMPONENT_TYPES",
    "model_from_fits",
    "bare_cylinder",
    "insulation_refused",
    "without_pipeless_insulation",
]

#: Component types: piping parts made by merging, then the plain fitted kinds.
COMPONENT_TYPES = (
    "pipe",
    "elbow",
    "tee",
    "cross",
    "reducer",
    "coupling",
    "cylinder",
    "cuboid",
    "sphere",
    "plane",
    "hull",
)


def _nonneg(value, name: str) -> float:
    number = float(value)
    if not np.isfinite(number) or number < 0:
        raise ValueError(f"The {name} must be a non-negative finite number, not {value!r}.")
    return number


def _wall(
    outer_radius: float, wall: float, name: str = "wall", radius_name: str = "outer radius"
) -> float:
    wall = _nonneg(wall, name)
    if wall >= outer_radius:
        raise ValueError(f"The {name} must be thinner than the {radius_name} (0 means solid).")
    return wall


def _hollow_or_solid(what: str, first: float, second: float) -> None:
    # a bore that closes to nothing at one end is no fitting (and no valid solid)
    if (first > 0) != (second > 0):
        raise ValueError(f"A {what}'s walls must be both 0 (solid) or both positive.")


@dataclass(frozen=True, eq=False)
class Straight:
    """A straight pipe (or coupling) from ``start`` to ``end`` (each (3,) metres).

    ``outer_radius`` metres; ``wall`` metres, 0 for a solid bar when the schedule is unknown.
    """

    kind: ClassVar[str] = "straight"
    start: np.ndarray
    end: np.ndarray
    outer_radius: float
    wall: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "start", as_vector(self.start, "start"))
        object.__setattr__(self, "end", as_vector(self.end, "end"))
        if np.linalg.norm(self.end - self.start) <= 0:
            raise ValueError("A straight needs distinct start and end points.")
        object.__setattr__(self, "outer_radius", _nonneg(self.outer_radius, "outer radius"))
        object.__setattr__(self, "wall", _wall(self.outer_radius, self.wall))

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.end - self.start))

    @property
    def direction(self) -> np.ndarray:
        """Unit vector from start to end, shape (3,)."""
        return (self.end - self.start) / self.length


@dataclass(frozen=True, eq=False)
class Bend:
    """An elbow: a torus section from ``start`` to ``end`` about the curvature centre ``center``.

    All points (3,) metres. The bend radius is ``|start - center|`` (= ``|end - center|``);
    the bend angle is the angle between them seen from ``center``.

    ``outer_radius`` and ``wall`` (metres, wall 0 = solid) are the start end's;
    ``outer_radius_end`` and ``wall_end`` the end end's, for a **reducing elbow** joining two
    pipe sizes (ASME B16.9 makes it to each end's pipe, so each end's outside and bore are the
    pipe's welded there; between the ends both change in proportion to the angle turned).
    ``None`` (the default) takes the start end's: one size throughout, as in
    ``Bend(s, e, c, r, wall)``. An end value equal to the start's is kept as ``None``, so a
    bend of one size stays one size when :func:`dataclasses.replace` changes its start's.
    Read :attr:`radii` and :attr:`walls` for both ends' values.

    Raises
    ------
    ValueError
        Ends not equidistant from the centre, a wall not thinner than its end's outer radius,
        or one end solid (0) and the other not.
    """

    kind: ClassVar[str] = "bend"
    start: np.ndarray
    end: np.ndarray
    center: np.ndarray
    outer_radius: float
    wall: float = 0.0
    outer_radius_end: float | None = None
    wall_end: float | None = None

    def __post_init__(self):
        for name in ("start", "end", "center"):
            object.__setattr__(self, name, as_vector(getattr(self, name), name))
        r1 = np.linalg.norm(self.start - self.center)
        r2 = np.linalg.norm(self.end - self.center)
        if r1 <= 0 or abs(r1 - r2) > 1e-6 * max(r1, 1.0):
            raise ValueError("A bend's ends must be equidistant from its centre.")
        object.__setattr__(self, "outer_radius", _nonneg(self.outer_radius, "outer radius"))
        object.__setattr__(self, "wall", _wall(self.outer_radius, self.wall))
        radius_end = self.outer_radius
        if self.outer_radius_end is not None:
            radius_end = _nonneg(self.outer_radius_end, "outer radius end")
        wall_end = self.wall if self.wall_end is None else self.wall_end
        wall_end = _wall(radius_end, wall_end, "wall end", "outer radius end")
        _hollow_or_solid("bend", self.wall, wall_end)
        object.__setattr__(
            self, "outer_radius_end", None if radius_end == self.outer_radius else radius_end
        )
        object.__setattr__(self, "wall_end", None if wall_end == self.wall else wall_end)

    @property
    def radii(self) -> tuple[float, float]:
        """Outer radius (metres) at the start end and at the end end."""
        end = self.outer_radius if self.outer_radius_end is None else self.outer_radius_end
        return self.outer_radius, end

    @property
    def walls(self) -> tuple[float, float]:
        """Wall (metres, 0 = solid) at the start end and at the end end."""
        return self.wall, self.wall if self.wall_end is None else self.wall_end

    @property
    def reducing(self) -> bool:
        """Whether the two ends differ in outer radius or wall."""
        return self.outer_radius_end is not None or self.wall_end is not None

    @property
    def bend_radius(self) -> float:
        return float(np.linalg.norm(self.start - self.center))

    @property
    def angle_deg(self) -> float:
        a = self.start - self.center
        b = self.end - self.center
        cos = np.dot(a, b) / (np.linalg.norm(a) * np.linalg.norm(b))
        return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))


#: Slack (metres) in a reducer's offset checks (beyond the difference of the end radii, along
#: the run) and the smallest offset that makes it eccentric: a micrometre is rounding of
#: coordinates written to a file, not geometry.
OFFSET_SLACK = 1e-6


@dataclass(frozen=True, eq=False)
class Reducer:
    """A reducer: a (possibly oblique) truncated cone between two pipe sizes.

    ``start`` and ``end`` (each (3,) metres) are the centres of its two end circles, of outer
    radius ``outer_radius_start`` and ``outer_radius_end`` (metres); both circles lie in planes
    perpendicular to the run direction :attr:`direction`. ``offset`` (3,) metres is the
    sideways step from the start end's axis to the end end's axis, perpendicular to the run:
    zero (the default) for a **concentric** reducer (the run is ``end - start``); for an
    **eccentric** reducer (ASME B16.9, flat on one side) its length is the difference of the
    radii, and the run is ``end - start - offset``.

    ``wall_start`` and ``wall_end`` metres are the wall thicknesses at the two ends, each that
    of the pipe welded there (a B16.9 reducer is made to the schedule of each connecting pipe,
    so its bore runs from one pipe's bore to the other's), 0 for solid. ``wall_end`` None (the
    default) takes ``wall_start``: one wall at both ends, as in ``Reducer(s, e, r1, r2, wall)``.

    Raises
    ------
    ValueError
        Coinciding ends, an offset not perpendicular to the run, or one longer than the
        difference of the radii (the small end would stick out of the large one's outline); a
        wall not thinner than its end's outer radius, or one end solid (0) and the other not.
    """

    kind: ClassVar[str] = "reducer"
    start: np.ndarray
    end: np.ndarray
    outer_radius_start: float
    outer_radius_end: float
    wall_start: float = 0.0
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3))
    wall_end: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "start", as_vector(self.start, "start"))
        object.__setattr__(self, "end", as_vector(self.end, "end"))
        object.__setattr__(self, "offset", as_vector(self.offset, "reducer offset"))
        for name in ("outer_radius_start", "outer_radius_end"):
            object.__setattr__(self, name, _nonneg(getattr(self, name), name.replace("_", " ")))
        wall_end = self.wall_start if self.wall_end is None else self.wall_end
        for name, radius, wall in (
            ("start", self.outer_radius_start, self.wall_start),
            ("end", self.outer_radius_end, wall_end),
        ):
            checked = _wall(radius, wall, f"wall {name}", f"outer radius {name}")
            object.__setattr__(self, f"wall_{name}", checked)
        _hollow_or_solid("reducer", self.wall_start, self.wall_end)
        run = self.end - self.start - self.offset
        length = float(np.linalg.norm(run))
        if length <= 0:
            raise ValueError("A reducer needs distinct start and end points along its run.")
        size = float(np.linalg.norm(self.offset))
        if abs(float(self.offset @ run)) / length > OFFSET_SLACK:
            raise ValueError(
                "The reducer offset must be perpendicular to the run (end - start - offset)."
            )
        step = abs(self.outer_radius_start - self.outer_radius_end)
        if size > step + OFFSET_SLACK:
            raise ValueError(
                f"The reducer offset ({size * 1000:.3f} mm) must not exceed the difference of "
                f"the end radii ({step * 1000:.3f} mm)."
            )

    @property
    def length(self) -> float:
        """Length along the run, metres (the B16.9 end-to-end length H)."""
        return float(np.linalg.norm(self.end - self.start - self.offset))

    @property
    def direction(self) -> np.ndarray:
        """Unit run direction from the start end to the end end, shape (3,)."""
        return (self.end - self.start - self.offset) / self.length

    @property
    def eccentric(self) -> bool:
        """True when the two axes are offset (more than a micrometre): an eccentric reducer."""
        return bool(np.linalg.norm(self.offset) > OFFSET_SLACK)

    @property
    def flat_side(self) -> np.ndarray | None:
        """Unit vector (3,) from the axes towards the flat side of an eccentric reducer (where
        both pipes' outsides are flush), perpendicular to the run; None when concentric."""
        if not self.eccentric:
            return None
        towards = self.offset / np.linalg.norm(self.offset)
        return towards if self.outer_radius_start >= self.outer_radius_end else -towards


def _check_junction(fitting) -> None:
    """Validate a tee's or cross's points (its ``point_fields``, each (3,) metres), radii and
    walls in place (``branch_wall`` None takes ``wall``)."""
    for name in fitting.point_fields:
        object.__setattr__(fitting, name, as_vector(getattr(fitting, name), name))
    outer = _nonneg(fitting.outer_radius, "outer radius")
    branch_outer = _nonneg(fitting.branch_outer_radius, "branch outer radius")
    branch_wall = fitting.wall if fitting.branch_wall is None else fitting.branch_wall
    object.__setattr__(fitting, "outer_radius", outer)
    object.__setattr__(fitting, "branch_outer_radius", branch_outer)
    object.__setattr__(fitting, "wall", _wall(outer, fitting.wall))
    object.__setattr__(
        fitting,
        "branch_wall",
        _wall(branch_outer, branch_wall, "branch wall", "branch outer radius"),
    )
    _hollow_or_solid(fitting.kind, fitting.wall, fitting.branch_wall)


@dataclass(frozen=True, eq=False)
class Tee:
    """An equal (or reducing-outlet) tee: a run from ``run_start`` to ``run_end`` through
    ``center`` and a branch from ``center`` to ``branch_end``; points (3,) metres.

    ``outer_radius`` and ``wall`` (metres) are the run's, ``branch_outer_radius`` and
    ``branch_wall`` the branch outlet's: a B16.9 reducing tee is made to the schedule of each
    connecting pipe, so each bore is its pipe's. ``branch_wall`` None (the default) takes
    ``wall``: one wall throughout. 0 for solid.

    Raises
    ------
    ValueError
        A wall not thinner than its own outer radius, or one of the two 0 (solid) and the
        other not.
    """

    kind: ClassVar[str] = "tee"
    #: Its points, each (3,) metres (validated, moved and turned together).
    point_fields: ClassVar[tuple[str, ...]] = ("center", "run_start", "run_end", "branch_end")
    center: np.ndarray
    run_start: np.ndarray
    run_end: np.ndarray
    branch_end: np.ndarray
    outer_radius: float
    branch_outer_radius: float
    wall: float = 0.0
    branch_wall: float | None = None

    def __post_init__(self):
        _check_junction(self)

    @property
    def outlets(self) -> tuple[np.ndarray, ...]:
        """The outlet ends, each (3,) metres: the branch end (a cross has two)."""
        return (self.branch_end,)

    @property
    def outlet_start(self) -> np.ndarray:
        """Where the outlet's cylinder starts, (3,) metres: the centre (it ends at
        ``branch_end``)."""
        return self.center


@dataclass(frozen=True, eq=False)
class Cross:
    """A straight (or reducing-outlet) cross: a run from ``run_start`` to ``run_end`` through
    ``center`` and an outlet line from ``branch_start`` through ``center`` to ``branch_end``
    (two outlets of one size on one line, square to the run); points (3,) metres.

    ASME B16.9 tabulates crosses with tees: a cross of a run and outlet size has the tee's
    centre-to-end C (run) and M (outlet) for that pair. ``outer_radius`` and ``wall`` (metres)
    are the run's, ``branch_outer_radius`` and ``branch_wall`` both outlets' (each bore its
    pipe's, as tees are made); ``branch_wall`` None takes ``wall``. 0 for solid.

    Raises
    ------
    ValueError
        A wall not thinner than its own outer radius, or one of the two 0 (solid) and the
        other not.
    """

    kind: ClassVar[str] = "cross"
    #: Its points, each (3,) metres (validated, moved and turned together).
    point_fields: ClassVar[tuple[str, ...]] = (
        "center",
        "run_start",
        "run_end",
        "branch_start",
        "branch_end",
    )
    center: np.ndarray
    run_start: np.ndarray
    run_end: np.ndarray
    branch_start: np.ndarray
    branch_end: np.ndarray
    outer_radius: float
    branch_outer_radius: float
    wall: float = 0.0
    branch_wall: float | None = None

    def __post_init__(self):
        _check_junction(self)

    @property
    def outlets(self) -> tuple[np.ndarray, ...]:
        """The two outlet ends, each (3,) metres: ``branch_start`` and ``branch_end``."""
        return (self.branch_start, self.branch_end)

    @property
    def outlet_start(self) -> np.ndarray:
        """Where the outlets' cylinder starts, (3,) metres: the far outlet end, ``branch_start``
        (it runs through the centre to ``branch_end``)."""
        return self.branch_start


Geometry = Straight | Bend | Reducer | Tee | Cross | Cylinder | Cuboid | Sphere | Plane | Hull


@dataclass(frozen=True)
class Correction:
    """A change merging made to a fitted value, recorded like a spell checker's correction.

    ``what`` names it (``"diameter snapped"``, ``"axis made vertical"``...), ``before`` and
    ``after`` are the values (lengths in metres, angles in degrees), ``size`` the magnitude of
    the change in ``unit``.
    """

    what: str
    before: object
    after: object
    size: float
    unit: str


@dataclass(frozen=True, eq=False)
class Component:
    """One part of the as-built model.

    Attributes
    ----------
    id : str
        Unique in the model (a scan object id, or e.g. ``"P1-P2"`` for the elbow joining them).
    type : str
        One of :data:`COMPONENT_TYPES`.
    geometry : Geometry
        Its shape, metres.
    sources : tuple of str
        Scan object ids it comes from (empty for fittings made by merging).
    spool, group, label : str or None
    nominal, schedule : str or None
        Catalog nominal size (e.g. ``"4"``) and schedule (e.g. ``"STD"``) when known.
    insulation : float, metres
        Thickness of the insulation around it, 0 when bare. ``geometry`` is the component
        itself (the pipe, not its cladding); the insulation is an envelope that much larger
        all round, which clashes and the take-off count.
    fit : FitResult or None
        The fit it comes from.
    snap : Mapping
        How the size was chosen: ``status`` ("snapped", "no-size", "ambiguous", "hint"),
        ``od_fit``, ``od_stderr``, ``od_catalog`` (metres), ``candidates`` and ``reason``.
    corrections : tuple of Correction
    """

    id: str
    type: str
    geometry: Geometry
    sources: tuple[str, ...] = ()
    spool: str | None = None
    group: str | None = None
    label: str | None = None
    nominal: str | None = None
    schedule: str | None = None
    fit: FitResult | None = None
    snap: Mapping = field(default_factory=dict)
    corrections: tuple[Correction, ...] = ()
    insulation: float = 0.0

    def __post_init__(self):
        if self.type not in COMPONENT_TYPES:
            raise ValueError(f"component type must be one of {COMPONENT_TYPES}, not {self.type!r}")
        _nonneg(self.insulation, "insulation")


@dataclass(frozen=True)
class Spool:
    """A connected group of piping components; ``pipe_length`` metres of straight pipe."""

    id: str
    components: tuple[str, ...]
    pipe_length: float = 0.0


@dataclass(frozen=True, eq=False)
class Model:
    """The as-built model of one scan.

    ``units`` is the unit outputs are written in (the scan's unless asked otherwise); the data
    stay in metres. ``catalog`` names the pipe catalog used for snapping, if any;
    ``catalog_file`` is the absolute path of that catalog's CSV file when it was a user's file
    rather than a shipped catalog (so that it can be read again: its name alone may name no
    shipped catalog, or a different one). ``source`` is the scan file a model read from a model
    document was built from (``scan.source`` when the scan is attached).
    """

    components: tuple[Component, ...]
    units: str = "m"
    name: str | None = None
    catalog: str | None = None
    spools: tuple[Spool, ...] = ()
    findings: tuple[Finding, ...] = ()
    scan: Scan | None = None
    fits: FitReport | None = None
    catalog_file: str | None = None
    source: str | None = None

    def component(self, component_id: str) -> Component:
        for comp in self.components:
            if comp.id == component_id:
                return comp
        raise KeyError(component_id)

    def replace(self, **changes) -> Model:
        """A copy with some fields changed (e.g. ``model.replace(findings=...)``)."""
        return dataclasses.replace(self, **changes)


def _pipeless(obj: ScanObject, cylinder: Cylinder, source: str | None) -> FitError | None:
    """The located error when ``obj``'s insulation is as thick as ``cylinder``'s radius (fitted
    to the cladding, metres) or thicker: no pipe would be left inside. None otherwise."""
    thickness = float(obj.insulation)
    if thickness <= 0 or thickness < cylinder.radius:
        return None
    return FitError(
        f"{thickness * 1000:g} mm of insulation is as thick as the fitted radius "
        f"({cylinder.radius * 1000:.1f} mm) or thicker, so no pipe is left inside; check "
        "the thickness and the file's units",
        source=source,
        where=f"{obj.where}.insulation",
    )


def bare_cylinder(obj: ScanObject, cylinder: Cylinder, source: str | None = None) -> Cylinder:
    """The cylinder inside an object's insulation: ``cylinder`` (fitted to the cladding, metres)
    with its radius less the object's ``insulation``; ``cylinder`` itself when bare.

    Raises
    ------
    FitError
        Located at the object's ``insulation``, when the insulation is as thick as the fitted
        radius or thicker (no pipe would be left inside). :func:`build_model
        <asbuilt.pipeline.build_model>` takes such objects out first
        (:func:`without_pipeless_insulation`), so this is met only by a caller that merges a
        fit report itself.
    """
    error = _pipeless(obj, cylinder, source)
    if error is not None:
        raise error
    thickness = float(obj.insulation)
    if thickness <= 0:
        return cylinder
    return dataclasses.replace(cylinder, radius=cylinder.radius - thickness)


def without_pipeless_insulation(report: FitReport) -> FitReport:
    """``report`` with each fitted cylinder whose ``insulation`` leaves no pipe inside moved to
    its failures, in the scan's order.

    The points fit the cladding well; it is the thickness given that leaves nothing to model
    (a unit slip or a typo), so the object is refused as a fit is, one object at a time: the
    others are modelled, and :func:`asbuilt.pipeline.fit_refused_finding` keeps its points.

    Parameters
    ----------
    report : FitReport
        As :func:`asbuilt.fit.fit` returns it (metres).

    Returns
    -------
    FitReport
        ``report`` itself when no object is refused so; else a copy whose ``failures`` hold the
        new :class:`~asbuilt.fit.result.FitFailure` s (located ``objects[i] (ID).insulation``,
        :func:`insulation_refused`). Its ``fits`` may be empty: the caller decides whether
        nothing fitted is bad input.
    """
    source = report.scan.source
    refused = {}
    for item in report.fits:
        if isinstance(item.result.primitive, Cylinder):
            error = _pipeless(item.object, item.result.primitive, source)
            if error is not None:
                refused[item.object.id] = FitFailure(object=item.object, error=error)
    if not refused:
        return report
    order = {obj.id: k for k, obj in enumerate(report.scan.objects)}
    failures = sorted(
        (*report.failures, *refused.values()), key=lambda f: order.get(f.object.id, len(order))
    )
    fits = tuple(item for item in report.fits if item.object.id not in refused)
    return dataclasses.replace(report, fits=fits, failures=tuple(failures))


def insulation_refused(failure: FitFailure) -> bool:
    """Whether ``failure`` is an object refused for its insulation
    (:func:`without_pipeless_insulation`) rather than for its points."""
    return (failure.error.where or "").endswith(".insulation")


def _component_from_fit(item, source: str | None = None) -> Component:
    obj, result = item.object, item.result
    geometry = result.primitive
    if isinstance(geometry, Cylinder):
        geometry = bare_cylinder(obj, geometry, source)
    return Component(
        id=obj.id,
        type=result.primitive.kind,
        geometry=geometry,
        insulation=float(obj.insulation) if isinstance(geometry, Cylinder) else 0.0,
        # an object fused with a second station's view of it (asbuilt.fit._stations) has both
        sources=(obj.id, *((obj.extra["fused_with"],) if "fused_with" in obj.extra else ())),
        group=obj.group,
        label=obj.label,
        fit=result,
    )


def model_from_fits(report: FitReport) -> Model:
    """The unmerged model: one component per fitted object, exactly as fitted."""
    scan = report.scan
    return Model(
        components=tuple(_component_from_fit(item, scan.source) for item in report.fits),
        units=scan.units,
        name=scan.name,
        scan=scan,
        fits=report,
    )


def fitted_primitive(component: Component) -> Primitive | None:
    """The primitive a component was fitted as, if it came from a fit."""
    return component.fit.primitive if component.fit is not None else None
