"""Quantity take-off of an as-built model as plain data (numpy only).

What project controls count: straight pipe length by nominal size and schedule (metres and
feet) with its weight where the wall is known, fittings counted by size and angle (never by
length), and volumes and surface areas of everything else (concrete or steel members, tanks and
vessels, spheres, plates, obstacles). Everything is computed in SI (metres, square metres,
cubic metres, kilograms) from the model's geometry; unit conversion happens in the writers.

Formulas
--------
* Pipe weight per metre (plain end) ``w = rho * pi * (OD - t) * t`` kg/m, the formula of
  ASME B36.10M-2004 (section 4, plain-end mass ``0.0246615 (D - t) t`` kg/m with D, t in mm,
  which is ``pi * 7850 kg/m3 * 1e-6``). NPS 4 STD (OD 114.3 mm, t 6.02 mm) gives 16.07 kg/m,
  the table value.
* Densities: carbon steel 7850 kg/m3 (the density behind the B36.10M formula; EN 10220 uses
  7.85 kg/dm3 too); austenitic stainless steel 7900 kg/m3 (EN 10088-1, grade 1.4301). Other
  materials get no weight unless a density is given.
* Cylinder (tank, vessel, chimney): volume ``pi r^2 h``, closed surface ``2 pi r h + 2 pi r^2``.
* Cuboid: volume ``a b c``, surface ``2 (ab + bc + ca)``. Sphere: ``4/3 pi r^3``, ``4 pi r^2``.
* Plane: area of its outline polygon (shoelace formula in the plane), no volume.
* Hull: volume by the divergence theorem over its outward triangles, surface the sum of the
  triangle areas.
* Insulation (lagging and cladding): insulated centreline length, cladding area and insulation
  volume by Pappus' theorems, grouped by thickness and size (:mod:`asbuilt.report.lagging`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from asbuilt.catalog import model_catalog
from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.units import UNITS

from .lagging import InsulationQuantity, InsulationSummary, summarise_insulation
from .welds import WeldCount, WeldSummary, summarise_welds

__all__ = [
    "DENSITIES",
    "FOOT",
    "PipeLine",
    "FittingCount",
    "FITTING_KINDS",
    "fitting_kind",
    "lateral_angle",
    "SolidQuantity",
    "ComponentRow",
    "SpoolQuantity",
    "TakeOff",
    "pipe_weight_per_metre",
    "take_off",
    "model_catalog",
    "severity_rank",
]

#: Density in kg/m3 by catalog material (see the module docstring for the sources).
DENSITIES: Mapping[str, float] = {
    "carbon steel": 7850.0,
    "steel": 7850.0,
    "stainless steel": 7900.0,
}

#: Metres per foot.
FOOT = UNITS["ft"]

#: Component types counted as fittings (by size and angle).
FITTING_TYPES = ("elbow", "tee", "cross", "reducer", "coupling")

#: The fitting kinds of the take-off, in its order: reducers are bought as concentric or
#: eccentric (ASME B16.9 makes both, of the same length H), so they are counted apart; a lateral
#: (wye) is built as a tee-shaped component but bought as a lateral, at its angle.
FITTING_KINDS = (
    "elbow",
    "tee",
    "cross",
    "lateral",
    "concentric reducer",
    "eccentric reducer",
    "coupling",
)


def lateral_angle(component: Component) -> float | None:
    """The branch angle in degrees of a lateral (a ``tee`` component merging built at the
    measured oblique angle, which its ``snap`` records as ``angle_deg``), else None."""
    if component.type != "tee":
        return None
    angle = (component.snap or {}).get("angle_deg")
    return None if angle is None else float(angle)


def fitting_kind(component: Component) -> str:
    """The take-off's kind of a fitting (one of :data:`FITTING_KINDS`): its type, with reducers
    told concentric or eccentric and laterals told from tees; a reducer without a reducer's
    geometry (a model document may give one a straight) has no offset, so it is counted
    concentric."""
    if component.type == "reducer":
        geometry = component.geometry
        eccentric = isinstance(geometry, Reducer) and geometry.eccentric
        return "eccentric reducer" if eccentric else "concentric reducer"
    if lateral_angle(component) is not None:
        return "lateral"
    return component.type


def severity_rank(severity: str | None) -> int:
    """0 for error, 1 warning, 2 info, 3 for none (sort key: the worst first)."""
    return {"error": 0, "warning": 1, "info": 2}.get(severity or "", 3)


def pipe_weight_per_metre(od: float, wall: float, density: float = DENSITIES["carbon steel"]):
    """Plain-end pipe weight per metre, ``density * pi * (od - wall) * wall``.

    Parameters
    ----------
    od, wall : float or ndarray, metres
        Outside diameter and wall thickness.
    density : float, kg/m3
        Default carbon steel, 7850 kg/m3 (ASME B36.10M-2004 plain-end mass formula).

    Returns
    -------
    float or ndarray, kg/m
    """
    od = np.asarray(od, dtype=np.float64)
    wall = np.asarray(wall, dtype=np.float64)
    value = density * np.pi * (od - wall) * wall
    return float(value) if value.ndim == 0 else value


@dataclass(frozen=True)
class PipeLine:
    """Straight pipe of one nominal size and schedule.

    ``size`` is the display label (``"NPS 4"``; the fitted OD in mm when not snapped);
    ``od``, ``wall`` metres (wall None when unknown); ``length`` metres; ``length_ft`` feet;
    ``weight_per_m`` kg/m and ``weight`` kg (None without a wall or a density); ``area`` m2 of
    outside surface; ``count`` pieces; ``components`` their ids.
    """

    nominal: str | None
    schedule: str | None
    size: str
    od: float
    wall: float | None
    length: float
    length_ft: float
    weight_per_m: float | None
    weight: float | None
    area: float
    count: int
    components: tuple[str, ...]


@dataclass(frozen=True)
class FittingCount:
    """Fittings of one type, size, schedule and angle: ``type`` one of :data:`FITTING_KINDS`
    (``"concentric reducer"`` and ``"eccentric reducer"`` apart), ``angle_deg`` (elbows and
    laterals, whole degrees, else None), ``bend_radius`` metres (elbows, else None), ``count``
    and the ids."""

    type: str
    size: str
    schedule: str | None
    angle_deg: int | None
    bend_radius: float | None
    count: int
    components: tuple[str, ...]


@dataclass(frozen=True)
class SolidQuantity:
    """One non-piping object: ``shape`` (cuboid, cylinder, sphere, plane, hull), ``dimensions``
    (metres: ``"0.400 x 0.400 x 3.000"``-style numbers as a tuple), ``volume`` m3 (None for a
    plane), ``area`` m2 (closed surface; one side for a plane), ``category`` (what it is counted
    as: ``"member"``, ``"tank/vessel"``, ``"sphere"``, ``"plate/wall"``, ``"obstacle"``)."""

    id: str
    type: str
    shape: str
    category: str
    label: str | None
    dimensions: tuple[float, ...]
    volume: float | None
    area: float


@dataclass(frozen=True)
class ComponentRow:
    """One CSV/JSON row per component.

    ``length`` metres (pipes, cylinders, the longest edge of a cuboid; None for fittings,
    spheres, planes and hulls); ``quantity_unit`` is ``"m"`` (pipe), ``"ea"`` (fittings),
    ``"m3"`` (solids) or ``"m2"`` (planes) and ``quantity`` the amount in it; ``weight`` kg or
    None; ``area`` m2 or None; ``findings`` the codes of the findings naming it, worst first;
    ``severity`` the worst of them or None; ``insulation`` metres, the thickness of lagging
    around it (0 when bare; :attr:`asbuilt.model.Component.insulation`).
    """

    id: str
    type: str
    spool: str | None
    label: str | None
    nominal: str | None
    size: str | None
    schedule: str | None
    length: float | None
    quantity_unit: str
    quantity: float
    weight: float | None
    area: float | None
    findings: tuple[str, ...]
    severity: str | None
    insulation: float = 0.0


@dataclass(frozen=True)
class SpoolQuantity:
    """One spool (the unit piping progress is tracked in): straight ``pipe_length`` metres and
    ``pipe_weight`` kg (None when no pipe of it has a weight; the sum of those that have one
    otherwise), the number of ``pipes``, how many of them have no weight
    (``pipes_without_weight``: no wall or no density known), the number of each fitting type
    (``fittings``: component type -> count, a lateral as ``"lateral"``, not ``"tee"``), its ``sizes`` (display labels) and ``findings`` (codes on its
    components, worst first); its butt ``welds``, their ``diameter_inches`` (None when no weld
    has an NPS size) and its ``open_ends`` (piping ends meeting nothing: flanges, equipment,
    where the scan stopped; :mod:`asbuilt.report.welds`); its ``insulated_length`` metres
    (centreline length of its insulated components, :mod:`asbuilt.report.lagging`; 0 when
    bare)."""

    id: str
    pipe_length: float
    pipe_weight: float | None
    pipes: int
    fittings: Mapping[str, int]
    sizes: tuple[str, ...]
    findings: tuple[str, ...]
    components: tuple[str, ...]
    pipes_without_weight: int = 0
    welds: int = 0
    diameter_inches: float | None = None
    open_ends: int = 0
    insulated_length: float = 0.0


@dataclass(frozen=True)
class TakeOff:
    """The whole take-off. Totals: ``pipe_length`` metres, ``pipe_weight`` kg (the sum over the
    pipes that have a weight; None when none has one), ``pipes_without_weight`` (pipe pieces
    left out of ``pipe_weight``: no wall or no density known), ``volumes`` m3 and ``areas`` m2 by solid category, ``density`` kg/m3 used
    (None: no weight) and ``material``; ``spools`` per spool in the model's order. Butt welds
    (:mod:`asbuilt.report.welds`): ``welds`` by size, largest first, ``weld_count``,
    ``diameter_inches`` (None when no weld has an NPS size) and ``welds_without_nps`` (welds
    left out of it). Insulation (:mod:`asbuilt.report.lagging`): ``insulation`` by thickness and
    size, thinnest first, ``insulated_length`` metres, ``insulation_area`` m2 of cladding,
    ``insulation_volume`` m3 and ``insulated_fittings`` (all 0 when nothing is insulated)."""

    pipes: tuple[PipeLine, ...]
    fittings: tuple[FittingCount, ...]
    solids: tuple[SolidQuantity, ...]
    rows: tuple[ComponentRow, ...]
    pipe_length: float
    pipe_weight: float | None
    volumes: Mapping[str, float] = field(default_factory=dict)
    areas: Mapping[str, float] = field(default_factory=dict)
    density: float | None = None
    material: str | None = None
    counts: Mapping[str, int] = field(default_factory=dict)
    spools: tuple[SpoolQuantity, ...] = ()
    pipes_without_weight: int = 0
    welds: tuple[WeldCount, ...] = ()
    weld_count: int = 0
    diameter_inches: float | None = None
    welds_without_nps: int = 0
    insulation: tuple[InsulationQuantity, ...] = ()
    insulated_length: float = 0.0
    insulation_area: float = 0.0
    insulation_volume: float = 0.0
    insulated_fittings: int = 0


# ----------------------------------------------------------------------------------------------
# geometry quantities


def _solid(component: Component) -> SolidQuantity | None:
    g = component.geometry
    if isinstance(g, Cuboid):
        a, b, c = (float(x) for x in g.size)
        shape, dims = "cuboid", (a, b, c)
        volume, area = a * b * c, 2.0 * (a * b + b * c + c * a)
        category = "member"
    elif isinstance(g, Cylinder):
        r, h = float(g.radius), float(g.length)
        shape, dims = "cylinder", (2.0 * r, h)
        volume, area = np.pi * r * r * h, 2.0 * np.pi * r * h + 2.0 * np.pi * r * r
        category = "tank/vessel"
    elif isinstance(g, Sphere):
        r = float(g.radius)
        shape, dims = "sphere", (2.0 * r,)
        volume, area = 4.0 / 3.0 * np.pi * r**3, 4.0 * np.pi * r * r
        category = "sphere"
    elif isinstance(g, Plane):
        shape, dims = "plane", ()
        volume, area = None, g.area
        category = "plate/wall"
    elif isinstance(g, Hull):
        shape = "hull"
        extent = g.vertices.max(axis=0) - g.vertices.min(axis=0)
        dims = tuple(float(x) for x in extent)
        volume, area = g.volume, g.area
        category = "obstacle"
    else:
        return None
    return SolidQuantity(
        id=component.id,
        type=component.type,
        shape=shape,
        category=category,
        label=component.label,
        dimensions=dims,
        volume=None if volume is None else float(volume),
        area=float(area),
    )


def _straight_length(g) -> float | None:
    if isinstance(g, (Straight, Cylinder)):
        return float(g.length)
    if isinstance(g, Reducer):
        return float(g.length)
    return None


def _outer_diameter(g) -> float | None:
    if isinstance(g, (Straight, Bend, Tee, Cross)):
        return 2.0 * float(g.outer_radius)
    if isinstance(g, Cylinder):
        return 2.0 * float(g.radius)
    if isinstance(g, Reducer):
        return 2.0 * float(max(g.outer_radius_start, g.outer_radius_end))
    return None


# ----------------------------------------------------------------------------------------------
# catalog look-ups (optional: a model may name a catalog file that is gone)


class _Sizes:
    """Labels and walls from the model's catalog (None: labels are the nominal sizes)."""

    def __init__(self, catalog):
        self.catalog = catalog

    @property
    def material(self) -> str | None:
        return (self.catalog.material or None) if self.catalog is not None else None

    def label(self, nominal: str | None, od: float | None) -> str:
        if nominal:
            return self.catalog.label(nominal) if self.catalog is not None else str(nominal)
        return f"OD {od * 1000:.1f} mm" if od is not None else "-"

    def nominal_for_od(self, od: float) -> str | None:
        if self.catalog is None or self.catalog.kind != "pipe" or not self.catalog.sizes:
            return None
        best = self.catalog.nearest(od, 1)[0]
        return best.nominal if abs(best.od - od) < 5e-4 else None

    def wall(self, nominal: str | None, schedule: str | None) -> float | None:
        if self.catalog is None or not nominal or not schedule or self.catalog.kind != "pipe":
            return None
        try:
            return self.catalog.wall(nominal, schedule)
        except KeyError:
            return None


def _fitting_size(component: Component, sizes: _Sizes) -> str:
    g = component.geometry
    if isinstance(g, Reducer):
        listed = component.snap.get("sizes") if isinstance(component.snap, Mapping) else None
        if listed and len(listed) == 2 and all(s is not None for s in listed):
            big, small = (str(s) for s in listed)
        else:  # an end whose pipe matched no catalog size is named by its OD
            ods = sorted((2 * g.outer_radius_start, 2 * g.outer_radius_end), reverse=True)
            big, small = (sizes.nominal_for_od(od) or f"{od * 1000:.1f} mm" for od in ods)
        return f"{sizes.label(big, None)} x {small}"
    if isinstance(g, Tee | Cross):
        run = sizes.label(component.nominal, 2 * g.outer_radius)
        if abs(g.branch_outer_radius - g.outer_radius) < 2.5e-4:
            return run
        branch = sizes.nominal_for_od(2 * g.branch_outer_radius)
        return f"{run} x {branch or f'{2000 * g.branch_outer_radius:.1f} mm'}"
    if isinstance(g, Bend) and abs(g.radii[0] - g.radii[1]) >= 2.5e-4:
        # a reducing elbow is bought by both sizes, large x small (as reducers are)
        ods = sorted((2 * r for r in g.radii), reverse=True)
        big = sizes.nominal_for_od(ods[0]) or (
            component.nominal if g.radii[0] >= g.radii[1] else None
        )
        small = sizes.nominal_for_od(ods[1]) or f"{ods[1] * 1000:.1f} mm"
        return f"{sizes.label(big, ods[0])} x {small}"
    return sizes.label(component.nominal, _outer_diameter(g))


# ----------------------------------------------------------------------------------------------
# the take-off


def _findings_by_object(model: Model) -> dict[str, list]:
    by_object: dict[str, list] = {}
    for finding in model.findings:
        for oid in finding.objects:
            by_object.setdefault(oid, []).append(finding)
    for found in by_object.values():
        found.sort(key=lambda f: (severity_rank(f.severity), f.code))
    return by_object


def _spools(
    model: Model, rows: list[ComponentRow], welds: WeldSummary, lagging: InsulationSummary
) -> tuple[SpoolQuantity, ...]:
    by_id = {row.id: row for row in rows}
    # bought as laterals, not tees (see FITTING_KINDS), so counted apart here too
    laterals = {c.id for c in model.components if lateral_angle(c) is not None}
    members: dict[str, list[ComponentRow]] = {}
    for spool in model.spools:
        members[spool.id] = [by_id[c] for c in spool.components if c in by_id]
    for row in rows:  # components naming a spool the model does not list
        if row.spool and row.spool not in members:
            members[row.spool] = []
        if row.spool and row not in members[row.spool]:
            members[row.spool].append(row)
    result = []
    for spool_id, parts in members.items():
        pipes = [r for r in parts if r.type == "pipe"]
        weights = [r.weight for r in pipes if r.weight is not None]
        fittings: dict[str, int] = {}
        for r in parts:
            if r.type in FITTING_TYPES:
                kind = "lateral" if r.id in laterals else r.type
                fittings[kind] = fittings.get(kind, 0) + 1
        codes = sorted({(severity_rank(r.severity), code) for r in parts for code in r.findings})
        result.append(
            SpoolQuantity(
                id=spool_id,
                pipe_length=float(sum(r.length or 0.0 for r in pipes)),
                pipe_weight=float(sum(weights)) if weights else None,
                pipes=len(pipes),
                fittings=fittings,
                sizes=tuple(dict.fromkeys(r.size for r in pipes if r.size)),
                findings=tuple(dict.fromkeys(code for _, code in codes)),
                components=tuple(r.id for r in parts),
                pipes_without_weight=len(pipes) - len(weights),
                welds=welds.spool_welds.get(spool_id, 0),
                diameter_inches=welds.spool_diameter_inches.get(spool_id),
                open_ends=welds.spool_open_ends.get(spool_id, 0),
                insulated_length=lagging.spool_length.get(spool_id, 0.0),
            )
        )
    return tuple(result)


def take_off(model: Model, *, density: float | None = None, catalog=None) -> TakeOff:
    """Count what was built.

    Parameters
    ----------
    model : Model
        Lengths metres.
    density : float, kg/m3, optional
        Pipe material density for weights; default from the catalog's material
        (:data:`DENSITIES`), none (no weights) for materials not listed there.
    catalog : Catalog, str or Path, optional
        The catalog for size labels, walls and the material; default the model's (see
        :func:`model_catalog`).

    Returns
    -------
    TakeOff
        Pipe lines sorted by outside diameter then schedule; fittings by type, size, angle;
        solids and rows in the model's order.
    """
    sizes = _Sizes(model_catalog(model, catalog)[0])
    welds = summarise_welds(model, sizes.catalog, sizes.label)
    material = sizes.material
    if density is None and material is not None:
        density = DENSITIES.get(material.lower())
    findings = _findings_by_object(model)

    lines: dict[tuple, dict] = {}
    fittings: dict[tuple, dict] = {}
    solids: list[SolidQuantity] = []
    rows: list[ComponentRow] = []
    counts: dict[str, int] = {}
    for comp in model.components:
        counts[comp.type] = counts.get(comp.type, 0) + 1
        g = comp.geometry
        od = _outer_diameter(g)
        weight = area = length = None
        if comp.type == "pipe":
            length = _straight_length(g)
            wall = getattr(g, "wall", 0.0) or sizes.wall(comp.nominal, comp.schedule)
            per_m = (
                pipe_weight_per_metre(od, wall, density) if wall and density is not None else None
            )
            weight = per_m * length if per_m is not None else None
            area = np.pi * od * length
            key = (comp.nominal, comp.schedule, None if comp.nominal else round(od, 4))
            entry = lines.setdefault(
                key, {"od": od, "wall": wall, "per_m": per_m, "length": 0.0, "area": 0.0, "ids": []}
            )
            entry["length"] += length
            entry["area"] += area
            entry["ids"].append(comp.id)
            size = sizes.label(comp.nominal, od)
            unit, quantity = "m", length
        elif comp.type in FITTING_TYPES:
            lateral = lateral_angle(comp)
            angle = round(g.angle_deg) if isinstance(g, Bend) else None
            angle = round(lateral) if lateral is not None else angle
            radius = round(g.bend_radius, 4) if isinstance(g, Bend) else None
            size = _fitting_size(comp, sizes)
            key = (fitting_kind(comp), size, comp.schedule, angle, radius)
            entry = fittings.setdefault(key, {"od": od or 0.0, "ids": []})
            entry["ids"].append(comp.id)
            unit, quantity = "ea", 1.0
        else:
            solid = _solid(comp)
            solids.append(solid)
            size = sizes.label(comp.nominal, None) if comp.nominal else None
            area = solid.area
            if solid.shape in ("cuboid", "cylinder"):
                length = max(solid.dimensions) if solid.shape == "cuboid" else solid.dimensions[1]
            if solid.volume is None:
                unit, quantity = "m2", solid.area
            else:
                unit, quantity = "m3", solid.volume
        found = findings.get(comp.id, [])
        rows.append(
            ComponentRow(
                id=comp.id,
                type=comp.type,
                spool=comp.spool,
                label=comp.label,
                nominal=comp.nominal,
                size=size,
                schedule=comp.schedule,
                length=None if length is None else float(length),
                quantity_unit=unit,
                quantity=float(quantity),
                weight=None if weight is None else float(weight),
                area=None if area is None else float(area),
                findings=tuple(dict.fromkeys(f.code for f in found)),
                severity=found[0].severity if found else None,
                insulation=float(comp.insulation),
            )
        )

    pipes = tuple(
        PipeLine(
            nominal=nominal,
            schedule=schedule,
            size=sizes.label(nominal, e["od"]),
            od=float(e["od"]),
            wall=None if not e["wall"] else float(e["wall"]),
            length=float(e["length"]),
            length_ft=float(e["length"] / FOOT),
            weight_per_m=None if e["per_m"] is None else float(e["per_m"]),
            weight=None if e["per_m"] is None else float(e["per_m"] * e["length"]),
            area=float(e["area"]),
            count=len(e["ids"]),
            components=tuple(e["ids"]),
        )
        for (nominal, schedule, _), e in sorted(
            lines.items(), key=lambda kv: (kv[1]["od"], kv[0][1] or "")
        )
    )
    fitting_rows = tuple(
        FittingCount(
            type=kind,
            size=size,
            schedule=schedule,
            angle_deg=angle,
            bend_radius=radius,
            count=len(e["ids"]),
            components=tuple(e["ids"]),
        )
        for (kind, size, schedule, angle, radius), e in sorted(
            fittings.items(),
            key=lambda kv: (FITTING_KINDS.index(kv[0][0]), -kv[1]["od"], kv[0][1], kv[0][3] or 0),
        )
    )
    # grouped under the take-off's own size labels (a tank, which has none, by its OD)
    labels = {row.id: row.size for row in rows}
    lagging = summarise_insulation(
        model, lambda c: labels.get(c.id) or sizes.label(None, _outer_diameter(c.geometry))
    )
    volumes: dict[str, float] = {}
    areas: dict[str, float] = {}
    for solid in solids:
        areas[solid.category] = areas.get(solid.category, 0.0) + solid.area
        if solid.volume is not None:
            volumes[solid.category] = volumes.get(solid.category, 0.0) + solid.volume
    return TakeOff(
        spools=_spools(model, rows, welds, lagging),
        pipes=pipes,
        fittings=fitting_rows,
        solids=tuple(solids),
        rows=tuple(rows),
        pipe_length=float(sum(p.length for p in pipes)),
        pipe_weight=(
            float(sum(p.weight for p in pipes if p.weight is not None))
            if any(p.weight is not None for p in pipes)
            else None
        ),
        pipes_without_weight=sum(p.count for p in pipes if p.weight is None),
        volumes=volumes,
        areas=areas,
        density=density,
        material=material,
        counts=counts,
        welds=welds.by_size,
        weld_count=welds.count,
        diameter_inches=welds.diameter_inches,
        welds_without_nps=welds.without_nps,
        insulation=lagging.by_size,
        insulated_length=lagging.length,
        insulation_area=lagging.area,
        insulation_volume=lagging.volume,
        insulated_fittings=lagging.fittings,
    )
