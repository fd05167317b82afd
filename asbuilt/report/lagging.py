"""Insulation quantities of a model: what insulation contractors and QA count, by thickness and
pipe size (numpy only).

A component's :attr:`~asbuilt.model.Component.insulation` is the thickness ``t`` of lagging and
cladding around its geometry (the bare pipe, fitting or vessel of outer radius ``r``); the
cladding's outer radius is ``r + t``. The full thickness is counted everywhere, also where
:func:`asbuilt.insulation.jacket_thickness` draws the jacket thinner at a tight fitting (the
insulator trims it there, but buys and fits that thickness). Per insulated component:

* **Insulated length** (metres, along the centreline): a straight or a cylinder its length; an
  elbow its bend radius times its angle (radians); a reducer its run length; a tee or a cross its
  run length plus each outlet's length beyond the run's cladding (from the centre to the
  outlet's end, less ``(r_run + t) / sin(angle)``, the angle between outlet and run: 90 degrees
  but for a lateral; none when the outlet ends inside the cladding).
* **Cladding area** (m2, the jacketing sheet's outer surface, its lateral surface only) and
  **insulation volume** (m3, between the bare outside and the cladding), by Pappus' theorems
  (the surface and the volume swept by a generating line or area are its length or area times
  the distance its centroid travels):

  - straight and cylinder: ``2 pi (r + t) L`` and ``pi ((r + t)^2 - r^2) L``; exact. A cylinder
    kept as an object (a tank, a vessel) is counted the same way: its heads are not modelled,
    so their insulation is not in the take-off.
  - elbow of bend radius ``R`` and angle ``a`` (radians): ``2 pi (r + t) R a`` and
    ``pi ((r + t)^2 - r^2) R a``; exact while the cladding clears the bend's axis
    (``r + t < R``; beyond, the lagging is mitred and these overstate it). A reducing elbow's
    radius changes in proportion to the angle, so its mean radius gives the volume exactly;
    the area leaves out the slope of its taper (``sqrt(1 + slope^2)``: 0.3 % for an NPS 6 x 4
    long-radius elbow).
  - reducer of run length ``H``: the cladding is the cone frustum of end radii ``r1 + t`` and
    ``r2 + t`` (both ends' radii grown by ``t``, as :func:`asbuilt.insulation.jacket` draws it;
    normal to the cone its thickness is ``t cos(half angle)``, 1.8 % less for a B16.9 NPS 6 x 4),
    area ``pi (R1 + R2) sqrt(H^2 + (R1 - R2)^2)``, volume the frustum ``pi H (R1^2 + R1 R2 +
    R2^2) / 3`` less the reducer's. Exact for that frustum when concentric; an eccentric
    (oblique) one has the same volume (Cavalieri) and a slightly larger area than counted.
  - tee and cross: the run as a straight of the run's radius and length, each outlet as a
    straight of the outlet's radius and its length beyond the run's cladding. An approximation:
    the saddle where they meet is left out (the hole the outlet cuts in the run's cladding is
    not subtracted, the outlet's curved edge not added), and the outlet pipe inside the run's
    lagging is counted as lagging. Per outlet these overstate the area by up to about the
    hole's ``pi (rb + t)^2`` (0.036 m2 for an NPS 4 outlet under 50 mm) and the volume by up to
    about ``pi rb^2 t``.

Components are grouped by (thickness, size label); the take-off passes its own labels (a
fitting as it is counted, ``NPS 6 x 4`` for a reducer), so insulated NPS 4 pipe and NPS 4 elbows
share a row and a reducer has its own.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cylinder

__all__ = [
    "FITTING_TYPES",
    "LaggedPart",
    "InsulationQuantity",
    "InsulationSummary",
    "insulated_part",
    "summarise_insulation",
]

#: Component types counted as insulated fittings (the take-off's fitting types).
FITTING_TYPES = ("elbow", "tee", "cross", "reducer", "coupling")

#: Thicknesses are grouped rounded to micrometres (a model document's rounding).
_THICKNESS_DECIMALS = 6


@dataclass(frozen=True)
class LaggedPart:
    """The insulation of one component: ``thickness`` metres, insulated centreline ``length``
    metres, cladding ``area`` m2 and insulation ``volume`` m3 (see the module docstring)."""

    thickness: float
    length: float
    area: float
    volume: float


@dataclass(frozen=True)
class InsulationQuantity:
    """Insulation of one ``thickness`` (metres) and ``size`` (display label, as the take-off
    labels the components): insulated centreline ``length`` metres, cladding ``area`` m2,
    insulation ``volume`` m3, the number of insulated ``fittings`` and the ``components``'
    ids (model order)."""

    thickness: float
    size: str
    length: float
    area: float
    volume: float
    fittings: int
    components: tuple[str, ...]


@dataclass(frozen=True)
class InsulationSummary:
    """All insulation of a model: ``by_size`` (thinnest first, then largest pipe first), totals
    ``length`` metres, ``area`` m2, ``volume`` m3 and ``fittings``, and per spool id its
    insulated length ``spool_length`` metres (0 for a bare spool)."""

    by_size: tuple[InsulationQuantity, ...]
    length: float
    area: float
    volume: float
    fittings: int
    spool_length: Mapping[str, float]


def _straight(r: float, t: float, length: float) -> tuple[float, float, float]:
    """(length, area, volume) of lagging ``t`` on a straight of outer radius ``r``."""
    return length, 2.0 * np.pi * (r + t) * length, np.pi * ((r + t) ** 2 - r * r) * length


def _frustum(r1: float, r2: float, height: float) -> float:
    return np.pi * height * (r1 * r1 + r1 * r2 + r2 * r2) / 3.0


def _junction(g: Tee | Cross, t: float) -> tuple[float, float, float]:
    run = g.run_end - g.run_start
    run_length = float(np.linalg.norm(run))
    length, area, volume = _straight(float(g.outer_radius), t, run_length)
    for end in g.outlets:
        outlet = end - g.center
        reach = float(np.linalg.norm(outlet))
        if reach <= 0 or run_length <= 0:
            continue
        sine = float(np.linalg.norm(np.cross(outlet / reach, run / run_length)))
        beyond = reach - (float(g.outer_radius) + t) / max(sine, 1e-9)
        if beyond > 0:
            more = _straight(float(g.branch_outer_radius), t, beyond)
            length, area, volume = length + more[0], area + more[1], volume + more[2]
    return length, area, volume


def insulated_part(component: Component) -> LaggedPart | None:
    """The insulation quantities of one component (see the module docstring), or None when it
    is bare or of a shape insulation does not wrap (a box, a sphere, a plane, a hull)."""
    t = float(component.insulation)
    g = component.geometry
    if t <= 0:
        return None
    if isinstance(g, Cylinder):
        quantities = _straight(float(g.radius), t, float(g.length))
    elif isinstance(g, Straight):
        quantities = _straight(float(g.outer_radius), t, g.length)
    elif isinstance(g, Bend):
        sweep = g.bend_radius * np.radians(g.angle_deg)
        quantities = _straight(0.5 * sum(g.radii), t, sweep)
    elif isinstance(g, Reducer):
        r1, r2, h = float(g.outer_radius_start), float(g.outer_radius_end), g.length
        big1, big2 = r1 + t, r2 + t
        area = np.pi * (big1 + big2) * np.hypot(h, big1 - big2)
        quantities = (h, area, _frustum(big1, big2, h) - _frustum(r1, r2, h))
    elif isinstance(g, Tee | Cross):
        quantities = _junction(g, t)
    else:
        return None
    length, area, volume = (float(q) for q in quantities)
    return LaggedPart(thickness=t, length=length, area=area, volume=volume)


def _default_size(component: Component) -> str:
    """``NPS <nominal>``, else the largest outside diameter in mm."""
    if component.nominal:
        return f"NPS {component.nominal}"
    od = _largest_od(component.geometry)
    return f"OD {od * 1000:.1f} mm"


def _largest_od(g) -> float:
    if isinstance(g, Cylinder):
        return 2.0 * float(g.radius)
    if isinstance(g, Bend):
        return 2.0 * float(max(g.radii))
    if isinstance(g, Reducer):
        return 2.0 * float(max(g.outer_radius_start, g.outer_radius_end))
    return 2.0 * float(getattr(g, "outer_radius", 0.0))


def summarise_insulation(
    model: Model, size: Callable[[Component], str | None] | None = None
) -> InsulationSummary:
    """Sum a model's insulation by thickness and size, and per spool.

    Parameters
    ----------
    model : Model
        Geometry and thicknesses metres.
    size : callable, optional
        ``size(component) -> str`` the display label a component is grouped under (the
        take-off passes its own; default ``NPS <nominal>`` or the OD in mm; a None label falls
        back to the default).

    Returns
    -------
    InsulationSummary
    """
    groups: dict[tuple, dict] = {}
    spool_length: dict[str, float] = {spool.id: 0.0 for spool in model.spools}
    for comp in model.components:
        part = insulated_part(comp)
        if part is None:
            continue
        label = (size(comp) if size is not None else None) or _default_size(comp)
        entry = groups.setdefault(
            (round(part.thickness, _THICKNESS_DECIMALS), label),
            {"od": 0.0, "length": 0.0, "area": 0.0, "volume": 0.0, "fittings": 0, "ids": []},
        )
        entry["od"] = max(entry["od"], _largest_od(comp.geometry))
        entry["length"] += part.length
        entry["area"] += part.area
        entry["volume"] += part.volume
        entry["fittings"] += comp.type in FITTING_TYPES
        entry["ids"].append(comp.id)
        if comp.spool:
            spool_length[comp.spool] = spool_length.get(comp.spool, 0.0) + part.length
    by_size = tuple(
        InsulationQuantity(
            thickness=float(thickness),
            size=label,
            length=float(e["length"]),
            area=float(e["area"]),
            volume=float(e["volume"]),
            fittings=int(e["fittings"]),
            components=tuple(e["ids"]),
        )
        for (thickness, label), e in sorted(
            groups.items(), key=lambda kv: (kv[0][0], -kv[1]["od"], kv[0][1])
        )
    )
    return InsulationSummary(
        by_size=by_size,
        length=float(sum(q.length for q in by_size)),
        area=float(sum(q.area for q in by_size)),
        volume=float(sum(q.volume for q in by_size)),
        fittings=sum(q.fittings for q in by_size),
        spool_length=spool_length,
    )
