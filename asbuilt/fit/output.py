"""Fit results as data for people and programs: the ``asbuilt fit --json`` dict and table rows.

Inside, every length is metres; here they are converted once to the output unit (the scan's
unit unless asked otherwise). Standard errors whose key ends in ``_deg`` stay in degrees.

The JSON shape (one dict per object, in the scan's order)::

    {"units": "m", "objects": [
      {"id": "P1", "kind": "cylinder", "center": [..], "axis": [..], "radius": .., "length": ..,
       "rms": .., "max_residual": .., "n_points": .., "n_inliers": .., "stderr": {..},
       "outliers": [..], "method": "..", "sigma": .., "sigma_source": "..", "notes": [..]},
      {"id": "X1", "kind": "auto", "chosen": "cylinder", ...the chosen primitive's fields...}]}

Non-finite numbers (e.g. the RMS of a fit with no inliers) become ``null`` so the output is
strict JSON.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from asbuilt.fit.result import FitReport, FitResult, ObjectFit
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Primitive, Sphere
from asbuilt.units import IMPERIAL, SMALL_SIZE_LIMIT, note_in_units, unit_factor

__all__ = [
    "TABLE_COLUMNS",
    "fit_report_to_dict",
    "object_fit_to_dict",
    "primitive_to_dict",
    "display_units",
    "fit_table_rows",
    "fit_table_notes",
    "note_in_units",
]

#: Column headings of :func:`fit_table_rows`.
TABLE_COLUMNS = ("id", "kind", "dimensions", "center", "rms", "inliers", "standard errors")


def _number(value: float, factor: float = 1.0) -> float | None:
    """``value / factor`` as a float, or None when it is not finite (JSON has no NaN)."""
    number = float(value) / factor
    return number if math.isfinite(number) else None


def _vector(values: Iterable[float], factor: float = 1.0) -> list:
    return [_number(v, factor) for v in np.asarray(values, dtype=np.float64).ravel()]


def _rows(values, factor: float = 1.0) -> list[list]:
    return [_vector(row, factor) for row in np.asarray(values, dtype=np.float64)]


def primitive_to_dict(primitive: Primitive, units: str = "m") -> dict:
    """A primitive's defining fields, lengths in ``units``.

    Parameters
    ----------
    primitive : Primitive
        Cylinder, Cuboid, Sphere, Plane or Hull (metres).
    units : str
        Output length unit (one of :data:`asbuilt.units.UNITS`).

    Returns
    -------
    dict
        cylinder: ``center`` (3,), ``axis`` (3,), ``radius``, ``length``; cuboid: ``center``,
        ``axes`` (3, 3) rows, ``size`` (3,); sphere: ``center``, ``radius``; plane: ``normal``,
        ``point``, ``outline`` (k, 3); hull: ``vertices`` (n, 3), ``faces`` (m, 3) int.
    """
    f = unit_factor(units)
    if isinstance(primitive, Cylinder):
        return {
            "center": _vector(primitive.center, f),
            "axis": _vector(primitive.axis),
            "radius": _number(primitive.radius, f),
            "length": _number(primitive.length, f),
        }
    if isinstance(primitive, Cuboid):
        return {
            "center": _vector(primitive.center, f),
            "axes": _rows(primitive.axes),
            "size": _vector(primitive.size, f),
        }
    if isinstance(primitive, Sphere):
        return {"center": _vector(primitive.center, f), "radius": _number(primitive.radius, f)}
    if isinstance(primitive, Plane):
        return {
            "normal": _vector(primitive.normal),
            "point": _vector(primitive.point, f),
            "outline": _rows(primitive.outline, f),
        }
    if isinstance(primitive, Hull):
        return {
            "vertices": _rows(primitive.vertices, f),
            "faces": [[int(i) for i in face] for face in primitive.faces],
        }
    raise TypeError(f"not a primitive: {type(primitive).__name__}")


def _stderr(stderr, f: float) -> dict:
    out = {}
    for key, value in stderr.items():
        scale = 1.0 if key.endswith("_deg") else f
        if isinstance(value, (tuple, list, np.ndarray)):
            out[key] = _vector(value, scale)
        else:
            out[key] = _number(value, scale)
    return out


def _result_fields(result: FitResult, units: str) -> dict:
    f = unit_factor(units)
    fields = primitive_to_dict(result.primitive, units)
    if result.observed is not None:
        fields["observed"] = [bool(x) for x in result.observed]
    fields.update(
        {
            "rms": _number(result.rms, f),
            "max_residual": _number(result.max_residual, f),
            "n_points": result.n_points,
            "n_inliers": result.n_inliers,
            "stderr": _stderr(result.stderr, f),
            "outliers": [int(i) for i in np.flatnonzero(~np.asarray(result.inliers, bool))],
            "method": result.method,
            "sigma": _number(result.sigma, f),
            "sigma_source": result.sigma_source,
            "notes": [note_in_units(note, units) for note in result.notes],
        }
    )
    return fields


def object_fit_to_dict(item: ObjectFit, units: str = "m") -> dict:
    """One object's fit as the ``asbuilt fit --json`` dict, lengths in ``units``.

    Keys: ``id``, ``kind`` (the requested kind), ``chosen`` (only when it differs, e.g. for
    ``auto``), the primitive's fields (:func:`primitive_to_dict`), ``observed`` (cuboids),
    ``rms``, ``max_residual``, ``n_points``, ``n_inliers``, ``stderr``, ``outliers`` (indices
    of rejected points), ``method``, ``sigma``, ``sigma_source``, ``notes``.
    """
    head = {"id": item.object.id, "kind": item.requested}
    if item.result.kind != item.requested:
        head["chosen"] = item.result.kind
    fields = _result_fields(item.result, units)
    note = _insulation_note(item)
    if note is not None and note[1]:
        # only the refusal: the cylinder is the cladding's either way, but this one is not
        # modelled, and a program reading --json must see why
        fields["notes"].append(note_in_units(note[0], units))
    return {**head, **fields}


def _insulation_note(item: ObjectFit) -> tuple[str, bool] | None:
    """``(note, pipeless)`` for a cylinder fitted on its insulation (the scan's ``insulation``):
    the pipe inside, or that none is left (``pipeless``: the thickness is the fitted radius or
    more, and :func:`asbuilt.model.without_pipeless_insulation` keeps it out of the model);
    None for a bare object."""
    thickness = item.object.insulation
    if not thickness or item.result.kind != "cylinder":
        return None
    inside = item.result.primitive.radius - thickness
    head = f"fitted on its insulation: the cladding's radius; with {thickness * 1000:g} mm "
    if inside > 0:
        return (
            head + f"of insulation the pipe inside has radius {inside * 1000:.1f} mm (OD "
            f"{2 * inside * 1000:.1f} mm), which merging snaps",
            False,
        )
    return (
        head + "of insulation no pipe is left inside, so model, check and report leave it out "
        "(fit-refused): check the thickness and the file's units",
        True,
    )


def fit_report_to_dict(report: FitReport, units: str | None = None) -> dict:
    """The whole report as ``{"units": u, "objects": [...]}``.

    Parameters
    ----------
    report : FitReport
        Fits in metres.
    units : str, optional
        Output length unit; defaults to the scan file's unit (``report.scan.units``).

    Returns
    -------
    dict
        JSON-ready (only dicts, lists, str, int, float, bool, None).
    """
    units = report.scan.units if units is None else units
    unit_factor(units)  # ValueError naming the allowed units when unknown
    return {"units": units, "objects": [object_fit_to_dict(item, units) for item in report.fits]}


# --------------------------------------------------------------------------------------------
# Table


def display_units(units: str) -> tuple[str, str]:
    """(small, large) display units for a table: ``("mm", "m")``, or ``("in", "ft")`` when the
    output unit is imperial. Radii, sizes under 10 m and residuals use the small one; lengths
    and positions the large one."""
    return ("in", "ft") if units in IMPERIAL else ("mm", "m")


def _decimals(unit: str) -> int:
    return {"mm": 1, "cm": 2, "in": 2, "m": 3, "ft": 3}[unit]


def _fmt(value_m: float, unit: str) -> str:
    value = float(value_m) / unit_factor(unit)
    if not math.isfinite(value):
        return "-"
    return f"{value:.{_decimals(unit)}f}"


def _size(value_m: float, small: str, large: str) -> str:
    unit = small if abs(value_m) < SMALL_SIZE_LIMIT else large
    return f"{_fmt(value_m, unit)} {unit}"


def _dimensions(primitive: Primitive, small: str, large: str) -> str:
    if isinstance(primitive, Cylinder):
        return (
            f"r {_size(primitive.radius, small, large)}, L {_fmt(primitive.length, large)} {large}"
        )
    if isinstance(primitive, Sphere):
        return f"r {_size(primitive.radius, small, large)}"
    if isinstance(primitive, Cuboid):
        unit = small if primitive.size.max() < SMALL_SIZE_LIMIT else large
        return " × ".join(_fmt(s, unit) for s in primitive.size) + f" {unit}"
    if isinstance(primitive, Plane):
        area = primitive.area / unit_factor(large) ** 2
        n = ", ".join(f"{c:.2f}" for c in primitive.normal)
        return f"n ({n}), {area:.2f} {large}²"
    if isinstance(primitive, Hull):
        return f"{len(primitive.vertices)} vertices, {len(primitive.faces)} faces"
    raise TypeError(f"not a primitive: {type(primitive).__name__}")  # pragma: no cover


def _center(primitive: Primitive) -> np.ndarray:
    if isinstance(primitive, Plane):
        return primitive.point
    if isinstance(primitive, Hull):
        return primitive.vertices.mean(axis=0)
    return primitive.center


def _stderr_text(stderr, small: str) -> str:
    parts = []
    for key, value in stderr.items():
        values = np.atleast_1d(np.asarray(value, dtype=np.float64))
        if key.endswith("_deg"):
            shown = "/".join(f"{v:.2f}" for v in values) + "°"
            name = key[: -len("_deg")]
        else:
            shown = "/".join(_fmt(v, small) for v in values) + f" {small}"
            name = key
        parts.append(f"{name} ±{shown}")
    return ", ".join(parts)


def fit_table_rows(report: FitReport, units: str | None = None) -> list[tuple[str, ...]]:
    """One row of display strings per object, matching :data:`TABLE_COLUMNS`.

    Display units follow :func:`display_units` of ``units`` (default: the scan's unit): mm and m
    for metric files, inches and feet for imperial ones. A cuboid size only bounded by the
    points (not measured between two seen faces: estimated from their extent and the raster,
    which can put it beyond the points, see docs/fitting.md) is marked with ``≈``; the depth
    assumed behind a single seen face (no standard error) with ``~``.
    """
    units = report.scan.units if units is None else units
    small, large = display_units(units)
    rows = []
    for item in report.fits:
        result = item.result
        kind = result.kind if result.kind == item.requested else f"{item.requested}→{result.kind}"
        dimensions = _dimensions(result.primitive, small, large)
        if isinstance(result.primitive, Cuboid) and result.observed is not None:
            unit = dimensions.rsplit(" ", 1)[1]
            assumed = result.diagnostics.get("assumed_size")
            sizes = [
                ("~" if k == assumed else "" if seen else "≈") + _fmt(s, unit)
                for k, (s, seen) in enumerate(zip(result.primitive.size, result.observed))
            ]
            dimensions = " × ".join(sizes) + f" {unit}"
        center = "(" + ", ".join(_fmt(c, large) for c in _center(result.primitive)) + f") {large}"
        rows.append(
            (
                item.object.id,
                kind,
                dimensions,
                center,
                f"{_fmt(result.rms, small)} {small}",
                f"{result.n_inliers}/{result.n_points}",
                _stderr_text(result.stderr, small),
            )
        )
    return rows


def fit_table_notes(report: FitReport, units: str | None = None) -> list[tuple[str, str]]:
    """Every fit's notes as ``(object id, note)`` pairs in the scan's order, to show under the
    table: a fit's warnings (undetermined, viewpoint ignored, wider noise, an assumed size),
    auto's reason for its choice and the outliers it rejected are part of what it says; an
    insulated cylinder's (the scan's ``insulation``) says the pipe inside it. Their
    lengths are in inches and feet when ``units`` (default: the scan's) is imperial
    (:func:`note_in_units`)."""
    units = report.scan.units if units is None else units
    notes = []
    for item in report.fits:
        said = list(item.result.notes)
        note = _insulation_note(item)
        if note is not None:
            said.append(note[0])
        notes.extend((item.object.id, note_in_units(note, units)) for note in said)
    return notes
