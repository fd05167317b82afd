"""Apply suggestions: every unambiguous one (a spell checker's "accept all"), or those chosen.

A suggestion's ``change`` is data; two kinds are understood:

- ``{"object": id | "objects": [ids], "field": "nominal", "value": "4", "od": 0.1143}``: set the
  nominal size and the outside diameter (metres) of components (``reject_hint: true`` records
  that the operator's hint was overridden); a pipe or bend whose diameter changes takes the
  catalog's wall of its new size in its schedule, or none (solid, as merging builds a size
  without a listed wall) when the catalog lists none or is not at hand;
- ``{"object": id, "field": "rotation", "value": 3x3 matrix, "about": [x, y, z]}``: rotate a
  component's geometry about a point (metres).

Each applied change is recorded on the component as a :class:`~asbuilt.model.Correction`.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from asbuilt.model import Bend, Component, Correction, Cross, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

__all__ = [
    "APPLIED_FIELDS",
    "LINK_FIELD",
    "acceptable_change",
    "applicable",
    "is_link",
    "apply_fixes",
    "apply_suggestions",
    "rotate_geometry",
    "resize_geometry",
]

#: The ``change`` fields :func:`apply_suggestions` can make to a model. Other changes are data
#: for a person or another step: ``units`` means reading the scan again in other units, and a
#: refused fit's suggestion keeps the measured points to rescan.
APPLIED_FIELDS = ("nominal", "rotation")

#: A change to the scan that merging then realises: ``{"objects": [a, b], "field": "link"}``
#: adds the scan link ``[a, b]`` (scan object ids), and the model is merged again
#: (:func:`asbuilt.pipeline.relink`); it can be accepted (``--accept``), never by ``--fix``
#: alone, and :func:`apply_suggestions` leaves it to that step.
LINK_FIELD = "link"


def applicable(suggestion) -> bool:
    """Whether ``suggestion`` is a change to a model's components that can be applied."""
    change = suggestion.change
    targets = change.get("objects") or change.get("object")
    return bool(targets) and change.get("field") in APPLIED_FIELDS


def is_link(suggestion) -> bool:
    """Whether ``suggestion`` adds a scan link between two objects (see :data:`LINK_FIELD`)."""
    change = suggestion.change
    objects = change.get("objects") or ()
    return change.get("field") == LINK_FIELD and len(objects) == 2


def acceptable_change(suggestion) -> bool:
    """Whether ``suggestion`` is a change a person can accept: one :func:`apply_suggestions`
    makes, or a scan link merging then realises (:func:`is_link`)."""
    return applicable(suggestion) or is_link(suggestion)


def rotate_geometry(geometry, rotation, about):
    """``geometry`` rotated by ``rotation`` (3, 3) about the point ``about`` (3,) metres."""
    r = np.asarray(rotation, dtype=np.float64)
    p = np.asarray(about, dtype=np.float64)

    def point(x):
        return p + r @ (np.asarray(x) - p)

    def vector(v):
        v = r @ np.asarray(v)
        return v / np.linalg.norm(v)

    g = geometry
    if isinstance(g, Reducer):
        return dataclasses.replace(
            g, start=point(g.start), end=point(g.end), offset=r @ np.asarray(g.offset)
        )
    if isinstance(g, Straight):
        return dataclasses.replace(g, start=point(g.start), end=point(g.end))
    if isinstance(g, Bend):
        return dataclasses.replace(
            g, start=point(g.start), end=point(g.end), center=point(g.center)
        )
    if isinstance(g, (Tee, Cross)):
        return dataclasses.replace(g, **{name: point(getattr(g, name)) for name in g.point_fields})
    if isinstance(g, Cylinder):
        return dataclasses.replace(g, center=point(g.center), axis=vector(g.axis))
    if isinstance(g, Cuboid):
        axes = (r @ np.asarray(g.axes).T).T
        u, _, vt = np.linalg.svd(axes)  # re-orthonormalise against rounding
        return dataclasses.replace(g, center=point(g.center), axes=u @ vt)
    if isinstance(g, Sphere):
        return dataclasses.replace(g, center=point(g.center))
    if isinstance(g, Plane):
        outline = np.array([point(x) for x in g.outline]).reshape(-1, 3)
        return dataclasses.replace(
            g, point=point(g.point), normal=vector(g.normal), outline=outline
        )
    if isinstance(g, Hull):
        return dataclasses.replace(g, vertices=np.array([point(x) for x in g.vertices]))
    raise TypeError(f"cannot rotate {type(g).__name__}")


def resize_geometry(geometry, od: float, wall: float | None = None):
    """``geometry`` with outside diameter ``od`` (metres) and, for a pipe or bend, wall ``wall``
    (metres; None keeps its own); a wall too thick for it becomes 0."""
    radius = 0.5 * float(od)
    g = geometry
    if isinstance(g, (Straight, Bend)):
        wall = g.wall if wall is None else float(wall)
        wall = wall if wall < radius else 0.0
        return dataclasses.replace(g, outer_radius=radius, wall=wall)
    if isinstance(g, Cylinder):
        return dataclasses.replace(g, radius=radius)
    return g


def _od(geometry) -> float | None:
    if hasattr(geometry, "outer_radius"):
        return 2 * geometry.outer_radius
    if isinstance(geometry, Cylinder):
        return 2 * geometry.radius
    return None


def _axis(geometry):
    if isinstance(geometry, Reducer):
        return geometry.direction
    if isinstance(geometry, Straight):
        d = geometry.end - geometry.start
        return d / np.linalg.norm(d)
    if isinstance(geometry, Cylinder):
        return np.array(geometry.axis)
    if isinstance(geometry, Cuboid):
        return np.array(geometry.axes[int(np.argmax(geometry.size))])
    return None


def model_schedule(model: Model, catalog) -> str | None:
    """The schedule the model's pipes were built to (merging gives every snapped pipe one
    schedule: ``--schedule``, else the catalog's default, else STD), for a pipe that has none
    (left unsnapped) and is given a size: the most common among the model's pipes, else the
    catalog's default; None when neither is known."""
    from asbuilt.merge import resolve_schedule

    schedules = [c.schedule for c in model.components if c.type == "pipe" and c.schedule]
    if schedules:
        return max(sorted(set(schedules)), key=schedules.count)
    return None if catalog is None else resolve_schedule(catalog, None)


def _new_wall(component: Component, change, catalog, schedule) -> float | None:
    """The wall (metres) a component re-sized by ``change`` takes: the catalog's wall of the new
    size in ``schedule``, 0 (solid) when the catalog lists none or there is no catalog; None
    (keep its own) when its diameter does not change and the catalog cannot say."""
    od, before = change.get("od"), _od(component.geometry)
    wall = None
    if catalog is not None and schedule:
        try:
            wall = catalog.wall(str(change["value"]), schedule)
        except KeyError:  # a size the catalog does not have
            wall = None
    if wall is not None:
        return float(wall)
    if od is None or (before is not None and abs(float(od) - before) < 1e-9):
        return None
    return 0.0


def _apply(component: Component, change, catalog=None, schedule=None) -> Component:
    """``component`` with ``change`` made; a re-sized pipe without a schedule of its own takes
    ``schedule`` (:func:`model_schedule`) when the catalog has its wall there."""
    field = change.get("field")
    if field == "nominal":
        od = change.get("od")
        before_od = _od(component.geometry)
        schedule = component.schedule or (schedule if component.type == "pipe" else None)
        wall = None if od is None else _new_wall(component, change, catalog, schedule)
        geometry = (
            component.geometry if od is None else resize_geometry(component.geometry, od, wall)
        )
        snap = dict(component.snap or {})
        snap.update(status="snapped", reason="accepted with asbuilt check --fix")
        if od is not None:
            snap["od_catalog"] = float(od)
        if change.get("reject_hint"):
            snap["hint_rejected"] = True
        size = abs(float(od) - before_od) if od is not None and before_od is not None else 0.0
        fix = Correction(
            "size set by check --fix", component.nominal, str(change["value"]), size, "m"
        )
        if not component.schedule and schedule and wall:
            component = dataclasses.replace(component, schedule=schedule)
        return dataclasses.replace(
            component,
            geometry=geometry,
            nominal=str(change["value"]),
            snap=snap,
            corrections=(*component.corrections, fix),
        )
    if field == "rotation":
        before = _axis(component.geometry)
        geometry = rotate_geometry(component.geometry, change["value"], change["about"])
        after = _axis(geometry)
        angle = 0.0
        if before is not None and after is not None:
            angle = float(np.degrees(np.arccos(np.clip(np.dot(before, after), -1, 1))))
        fix = Correction(
            "axis regularised by check --fix",
            None if before is None else [float(x) for x in before],
            None if after is None else [float(x) for x in after],
            angle,
            "deg",
        )
        return dataclasses.replace(
            component, geometry=geometry, corrections=(*component.corrections, fix)
        )
    raise ValueError(f"unknown change field {field!r}")


def apply_fixes(model: Model, findings, *, catalog=None) -> tuple[Model, list[str]]:
    """Apply the first unambiguous suggestion of every finding (a spell checker's "accept all").

    Parameters
    ----------
    model : Model
    findings : iterable of Finding
    catalog : Catalog, str or Path, optional
        The pipe catalog whose walls a re-sized pipe takes; default the one the model was built
        with (:func:`asbuilt.catalog.model_catalog`). Without one a re-sized pipe is solid.

    Returns
    -------
    (Model, list of str)
        The corrected model (its findings cleared: run :func:`check_model` again) and one line
        per applied change, e.g. ``"P3: make P3's axis vertical (rotate it 3.1 deg ...)"``.
    """
    chosen = []
    for finding in findings:
        suggestion = next((s for s in finding.suggestions if s.unambiguous and applicable(s)), None)
        if suggestion is not None:
            chosen.append((finding, suggestion))
    return apply_suggestions(model, chosen, catalog=catalog)


def apply_suggestions(model: Model, chosen, *, catalog=None) -> tuple[Model, list[str]]:
    """Apply the given suggestions, ambiguous or not (a spell checker's "accept this one").

    Parameters
    ----------
    model : Model
    chosen : iterable of (Finding, Suggestion)
        E.g. from :func:`asbuilt.rules.accept.choose_suggestions`; a suggestion without a
        ``change`` it can make (advice, see :func:`applicable`) changes nothing.
    catalog : Catalog, str or Path, optional
        As for :func:`apply_fixes`.

    Returns
    -------
    (Model, list of str)
        As :func:`apply_fixes`.
    """
    from asbuilt.catalog import Catalog, model_catalog

    if catalog is None or isinstance(catalog, (Catalog, str, Path)):
        catalog = model_catalog(model, catalog)[0]
    else:  # e.g. the rules' SizeTable, which has no walls
        catalog = None
    schedule = model_schedule(model, catalog)
    components = {c.id: c for c in model.components}
    changes: list[str] = []
    for finding, suggestion in chosen:
        if not applicable(suggestion):
            continue
        change = dict(suggestion.change)
        targets = change.get("objects") or [change.get("object")]
        applied = [t for t in targets if t in components]
        for target in applied:
            components[target] = _apply(components[target], change, catalog, schedule)
        if applied:
            changes.append(f"{', '.join(applied)}: {suggestion.description} ({finding.slug})")
    fixed = tuple(components[c.id] for c in model.components)
    return model.replace(components=fixed, findings=()), changes
