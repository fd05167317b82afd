"""Butt welds of a piped model: the unit piping fabrication and erection progress is counted in.

A butt weld is wherever the ends of two piping components meet: a pipe and the elbow, tee,
cross or reducer welded to it (ASME B16.9 fittings are butt-welding fittings), two fittings
welded close-coupled, or two pipes of one size welded in line. Merging places mating ends at
one point, so ends within :data:`WELD_GAP` of each other are one weld. An end that meets no
other piping end is an **open end**: a flange, a piece of equipment, a field weld to pipe that
was not scanned, or where the scan stopped; it is counted apart, never as a weld.

Each weld has the size of its smaller end (a reducer's large end is welded to the large pipe,
its small end to the small one). Progress is usually tracked in **diameter-inches** (inch-dia):
the sum over welds of the nominal pipe size in inches. A weld whose size is not a catalog size
with an NPS (a fitted OD that was not snapped, a DN catalog without an ``nps`` column) has no
diameter-inches and is counted in ``without_nps``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from asbuilt.merge.ports import ports
from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cylinder

__all__ = [
    "PIPING_TYPES",
    "WELD_GAP",
    "Weld",
    "WeldCount",
    "WeldSummary",
    "piping_ends",
    "welds_of",
    "summarise_welds",
]

#: Component types whose ends are welded.
PIPING_TYPES = ("pipe", "elbow", "tee", "cross", "reducer", "coupling")

#: Distance (metres) within which two piping ends are one joint: merging puts mating ends at
#: the same point, and a model document's coordinates are rounded to micrometres; 1 mm is the
#: compliance rules' touch distance (``clash.touch_distance``), so a weld here is a joint there.
WELD_GAP = 1e-3

#: Two ODs (metres) closer than this are one size (rounding of coordinates and radii).
_SAME_OD = 5e-4


@dataclass(frozen=True)
class Weld:
    """One butt weld: the two ``components`` (ids, sorted) it joins, its ``location`` (3,)
    metres, its ``od`` metres (the smaller end's), the catalog ``nominal`` of that OD and its
    ``nps`` in inches (None when not a catalog size with an NPS), and the ``spool``."""

    components: tuple[str, str]
    location: np.ndarray
    od: float
    nominal: str | None
    nps: float | None
    spool: str | None


@dataclass(frozen=True)
class WeldCount:
    """Butt welds of one size: display ``size`` (``"NPS 4"``; the OD in mm when not a catalog
    size), ``nominal``, ``od`` metres, ``nps`` inches or None, ``count``, ``diameter_inches``
    (``count * nps``, None without an NPS) and the ``joints`` (``"P1/P1-P2"``, sorted ids)."""

    size: str
    nominal: str | None
    od: float
    nps: float | None
    count: int
    diameter_inches: float | None
    joints: tuple[str, ...]


@dataclass(frozen=True)
class WeldSummary:
    """All welds of a model: ``by_size`` (largest first), ``count``, ``diameter_inches`` (the
    sum over welds with an NPS; None when none has one), ``without_nps`` (welds left out of
    it), and per spool id ``spool_welds``, ``spool_diameter_inches`` and ``spool_open_ends``
    (piping ends that meet no other piping end)."""

    welds: tuple[Weld, ...]
    by_size: tuple[WeldCount, ...]
    count: int
    diameter_inches: float | None
    without_nps: int
    spool_welds: Mapping[str, int]
    spool_diameter_inches: Mapping[str, float | None]
    spool_open_ends: Mapping[str, int]


def _end_diameters(geometry) -> list[float]:
    """The outside diameter (metres) at each end :func:`asbuilt.merge.ports.ports` gives, in
    its order: a reducer's and a reducing elbow's ends each their own, a tee's and a cross's
    outlets the branch's."""
    if isinstance(geometry, Reducer):
        return [2.0 * float(geometry.outer_radius_start), 2.0 * float(geometry.outer_radius_end)]
    if isinstance(geometry, Straight):
        return [2.0 * float(geometry.outer_radius)] * 2
    if isinstance(geometry, Bend):
        return [2.0 * float(r) for r in geometry.radii]
    if isinstance(geometry, Tee | Cross):
        run, branch = 2.0 * float(geometry.outer_radius), 2.0 * float(geometry.branch_outer_radius)
        return [run, run, *[branch] * len(geometry.outlets)]
    return []


def piping_ends(component: Component) -> list[tuple[np.ndarray, float]]:
    """Each welded end of a piping component: ``(point (3,) metres, outside diameter metres)``.

    The ends are its ports (:func:`asbuilt.merge.ports.ports`, as merging joins them); a pipe
    left as a fitted cylinder has its cylinder's two ends. Empty for components that are not
    piping (a cuboid, a sphere...).
    """
    geometry = component.geometry
    if isinstance(geometry, Cylinder):
        od = 2.0 * float(geometry.radius)
        return [(np.asarray(end), od) for end in geometry.ends]
    return [
        (np.asarray(point), od)
        for (point, _), od in zip(ports(component), _end_diameters(geometry), strict=True)
    ]


def _size_of(catalog, od: float) -> tuple[str | None, float | None]:
    """The catalog nominal and NPS (inches) of an OD in metres, (None, None) when no catalog
    pipe size has that OD."""
    if catalog is None or getattr(catalog, "kind", None) != "pipe" or not catalog.sizes:
        return None, None
    best = catalog.nearest(od, 1)[0]
    if abs(best.od - od) >= _SAME_OD:
        return None, None
    return best.nominal, best.nps


def welds_of(
    components: tuple[Component, ...], catalog=None
) -> tuple[tuple[Weld, ...], dict[str, int]]:
    """The butt welds between piping components and the open ends of each spool.

    Parameters
    ----------
    components : tuple of Component
        Geometry metres; components not of :data:`PIPING_TYPES` are ignored.
    catalog : Catalog, optional
        For each weld's nominal size and NPS (none: sizes by OD only).

    Returns
    -------
    welds : tuple of Weld
        In the order of the components' ends.
    open_ends : dict
        Spool id (components without a spool are left out) to its ends meeting no other end.
    """
    points, owners, ods = [], [], []
    for index, comp in enumerate(components):
        if comp.type not in PIPING_TYPES:
            continue
        for point, od in piping_ends(comp):
            points.append(point)
            owners.append(index)
            ods.append(od)
    open_ends: dict[str, int] = {}
    if not points:
        return (), open_ends
    points_array = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    joined = np.zeros(len(points), dtype=bool)
    welds = []
    pairs = sorted(cKDTree(points_array).query_pairs(WELD_GAP)) if len(points) > 1 else []
    for i, j in pairs:
        if owners[i] == owners[j]:
            continue  # a component's own ends (a zero-length piece): not a joint
        joined[i] = joined[j] = True
        a, b = components[owners[i]], components[owners[j]]
        od = min(ods[i], ods[j])
        nominal, nps = _size_of(catalog, od)
        welds.append(
            Weld(
                components=tuple(sorted((a.id, b.id))),
                location=0.5 * (points_array[i] + points_array[j]),
                od=float(od),
                nominal=nominal,
                nps=None if nps is None else float(nps),
                spool=a.spool or b.spool,
            )
        )
    for k, is_joined in enumerate(joined):
        spool = components[owners[k]].spool
        if spool:
            open_ends[spool] = open_ends.get(spool, 0) + (0 if is_joined else 1)
    return tuple(welds), open_ends


def summarise_welds(model: Model, catalog=None, label=None) -> WeldSummary:
    """Count a model's butt welds by size and per spool.

    Parameters
    ----------
    model : Model
        Geometry metres.
    catalog : Catalog, optional
        The pipe catalog for sizes and NPS (see :func:`welds_of`).
    label : callable, optional
        ``label(nominal, od) -> str`` for a size's display label (default ``NPS <nominal>``,
        or the OD in mm).

    Returns
    -------
    WeldSummary
    """
    if label is None:

        def label(nominal, od):
            return f"NPS {nominal}" if nominal else f"OD {od * 1000:.1f} mm"

    welds, open_ends = welds_of(model.components, catalog)
    groups: dict[tuple, list[Weld]] = {}
    for weld in welds:
        key = (weld.nominal, None if weld.nominal else round(weld.od, 4))
        groups.setdefault(key, []).append(weld)
    by_size = []
    for (nominal, _), group in sorted(groups.items(), key=lambda kv: -kv[1][0].od):
        nps = group[0].nps
        by_size.append(
            WeldCount(
                size=label(nominal, group[0].od),
                nominal=nominal,
                od=group[0].od,
                nps=nps,
                count=len(group),
                diameter_inches=None if nps is None else nps * len(group),
                joints=tuple("/".join(w.components) for w in group),
            )
        )
    known = [w.nps for w in welds if w.nps is not None]
    spool_welds: dict[str, int] = {}
    spool_inches: dict[str, float | None] = {}
    for spool in model.spools:
        spool_welds[spool.id] = 0
        spool_inches[spool.id] = None
    for weld in welds:
        if weld.spool is None:
            continue
        spool_welds[weld.spool] = spool_welds.get(weld.spool, 0) + 1
        if weld.nps is not None:
            spool_inches[weld.spool] = (spool_inches.get(weld.spool) or 0.0) + weld.nps
        else:
            spool_inches.setdefault(weld.spool, None)
    return WeldSummary(
        welds=welds,
        by_size=tuple(by_size),
        count=len(welds),
        diameter_inches=float(sum(known)) if known else None,
        without_nps=len(welds) - len(known),
        spool_welds=spool_welds,
        spool_diameter_inches=spool_inches,
        spool_open_ends=open_ends,
    )
