"""The ``asbuilt-model`` JSON document: write it, read it back, rebuild a Model from it.

The document (documented field by field in ``docs/model-format.md``) is plain data built
first (:func:`model_document`) and then written atomically. Lengths are metres, angles
degrees, in the scan frame (z up). Reading back (:func:`load_model_document`,
:func:`model_from_document`) restores ids, types, geometry, sizes, spools, corrections,
findings and each component's fit as a :class:`~asbuilt.export.stored_fit.StoredFit` (from its
``fitted`` summary: the fitted primitive, standard errors, counts, RMS, per-point residuals and
inlier flags), so the rules and the report judge a document as they judge the scan it came
from.

This module writes the document; the reading side (with :data:`FORMAT`, :data:`VERSION` and
:class:`ModelDocumentError`) lives in :mod:`asbuilt.export._model_json_read` and is
re-exported here, so every name imports from this module as before.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from asbuilt.atomic import atomic_write
from asbuilt.export._model_json_read import (
    FORMAT,
    VERSION,
    ModelDocumentError,
    is_model_document,
    load_model,
    load_model_document,
    model_from_document,
)
from asbuilt.export._model_json_read import loads_model_document as loads_model_document
from asbuilt.export._model_json_read import model_document_in as model_document_in
from asbuilt.export.stored_scan import scan_section
from asbuilt.findings import Finding
from asbuilt.model import (
    Bend,
    Component,
    Cross,
    Model,
    Reducer,
    Straight,
    Tee,
)
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

__all__ = [
    "FORMAT",
    "VERSION",
    "ModelDocumentError",
    "model_document",
    "dumps_model",
    "write_model_json",
    "load_model_document",
    "model_from_document",
    "load_model",
    "SCHEMA_PATH",
    "model_schema",
    "finding_to_dict",
    "json_ready",
    "is_model_document",
]

#: The JSON Schema of the document (package data).
SCHEMA_PATH = Path(__file__).resolve().parents[1] / "schemas" / "model.schema.json"


def model_schema() -> dict:
    """The document's JSON Schema (draft 2020-12), as shipped in ``asbuilt/schemas``."""
    return json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))


def json_ready(value):
    """Plain JSON data from numpy arrays, tuples, mappings and non-finite floats (-> None)."""
    if isinstance(value, Mapping):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        number = float(value)
        return number if math.isfinite(number) else None
    if value is None or isinstance(value, str):
        return value
    return str(value)


def _geometry_fields(geometry) -> dict:
    if isinstance(geometry, Straight):
        return {
            "shape": "straight",
            "start": geometry.start,
            "end": geometry.end,
            "od": 2 * geometry.outer_radius,
            "wall": geometry.wall,
            "length": geometry.length,
        }
    if isinstance(geometry, Bend):
        return {
            "shape": "bend",
            "center": geometry.center,
            "ends": [geometry.start, geometry.end],
            # od and wall as readers of one size per elbow built it: the start's OD, thinner wall
            "od": 2 * geometry.radii[0],
            "wall": min(geometry.walls),
            "od_end": 2 * geometry.radii[1],
            "wall_start": geometry.walls[0],
            "wall_end": geometry.walls[1],
            "bend_radius": geometry.bend_radius,
            "angle_deg": geometry.angle_deg,
        }
    if isinstance(geometry, Reducer):
        return {
            "shape": "reducer",
            "start": geometry.start,
            "end": geometry.end,
            "od_start": 2 * geometry.outer_radius_start,
            "od_end": 2 * geometry.outer_radius_end,
            # for readers that know one wall (before per-end walls): the thinner, as they wrote
            "wall": min(geometry.wall_start, geometry.wall_end),
            "wall_start": geometry.wall_start,
            "wall_end": geometry.wall_end,
            "offset": geometry.offset,
            "eccentric": geometry.eccentric,
        }
    if isinstance(geometry, Tee):
        return {
            "shape": "tee",
            "center": geometry.center,
            "run": [geometry.run_start, geometry.run_end],
            "branch_end": geometry.branch_end,
            "od": 2 * geometry.outer_radius,
            "branch_od": 2 * geometry.branch_outer_radius,
            "wall": geometry.wall,
            "branch_wall": geometry.branch_wall,
        }
    if isinstance(geometry, Cross):
        return {
            "shape": "cross",
            "center": geometry.center,
            "run": [geometry.run_start, geometry.run_end],
            "outlets": [geometry.branch_start, geometry.branch_end],
            "od": 2 * geometry.outer_radius,
            "branch_od": 2 * geometry.branch_outer_radius,
            "wall": geometry.wall,
            "branch_wall": geometry.branch_wall,
        }
    if isinstance(geometry, Cylinder):
        start, end = geometry.ends
        return {
            "shape": "cylinder",
            "center": geometry.center,
            "axis": geometry.axis,
            "radius": geometry.radius,
            "length": geometry.length,
            "od": 2 * geometry.radius,
            "start": start,
            "end": end,
        }
    if isinstance(geometry, Cuboid):
        return {
            "shape": "cuboid",
            "center": geometry.center,
            "axes": geometry.axes,
            "size": geometry.size,
        }
    if isinstance(geometry, Sphere):
        return {"shape": "sphere", "center": geometry.center, "radius": geometry.radius}
    if isinstance(geometry, Plane):
        return {
            "shape": "plane",
            "point": geometry.point,
            "normal": geometry.normal,
            "outline": geometry.outline,
        }
    if isinstance(geometry, Hull):
        return {"shape": "hull", "vertices": geometry.vertices, "faces": geometry.faces}
    raise TypeError(f"no document form for geometry {type(geometry).__name__}")


def _fitted(fit) -> dict | None:
    if fit is None:
        return None
    primitive = fit.primitive
    summary = {
        "kind": fit.kind,
        "method": fit.method,
        "points": fit.n_points,
        "inliers": fit.n_inliers,
        "rms": fit.rms,
        "max_residual": fit.max_residual,
        "sigma": fit.sigma,
        "sigma_source": fit.sigma_source,
    }
    if hasattr(primitive, "radius"):
        summary["radius"] = primitive.radius
    if isinstance(primitive, Cuboid):
        summary["size"] = primitive.size
    summary["stderr"] = dict(fit.stderr)
    summary["observed"] = list(fit.observed) if fit.observed is not None else None
    summary["diagnostics"] = dict(fit.diagnostics)
    summary["notes"] = list(fit.notes)
    summary["primitive"] = _geometry_fields(primitive)
    residuals, inliers = np.asarray(fit.residuals), np.asarray(fit.inliers)
    # One per given point, or none: a fit read from an older document has no per-point data
    # (empty arrays) and writes none, rather than lists its reader would refuse.
    if residuals.shape == (fit.n_points,) and inliers.shape == (fit.n_points,):
        summary["residuals"] = residuals.astype(np.float64)
        summary["inlier_mask"] = inliers.astype(bool)
    return summary


def _component(component: Component) -> dict:
    entry = {
        "id": component.id,
        "type": component.type,
        "nominal": component.nominal,
        "schedule": component.schedule,
        "insulation": component.insulation,
        **_geometry_fields(component.geometry),
        "spool": component.spool,
        "group": component.group,
        "label": component.label,
        "source": component.sources[0] if len(component.sources) == 1 else None,
        "sources": list(component.sources),
        "fitted": _fitted(component.fit),
        "snap": dict(component.snap),
        "corrections": [
            {"what": c.what, "before": c.before, "after": c.after, "size": c.size, "unit": c.unit}
            for c in component.corrections
        ],
    }
    return entry


def finding_to_dict(finding: Finding) -> dict:
    """A finding as JSON-ready data (the shape of the model document's ``findings``)."""
    return json_ready(
        {
            "code": finding.code,
            "slug": finding.slug,
            "severity": finding.severity,
            "objects": list(finding.objects),
            "location": finding.location,
            "message": finding.message,
            "measured": finding.measured,
            "allowed": finding.allowed,
            "stderr": finding.stderr,
            "unit": finding.unit,
            "suggestions": [
                {
                    "description": s.description,
                    "change": dict(s.change),
                    "unambiguous": s.unambiguous,
                }
                for s in finding.suggestions
            ],
            "unverifiable": finding.unverifiable,
            "waived": (
                None
                if finding.waived is None
                else {"reason": finding.waived.reason, "severity": finding.waived.severity}
            ),
        }
    )


def model_document(model: Model) -> dict:
    """The ``asbuilt-model`` document of a model, as plain JSON-ready data.

    Parameters
    ----------
    model : Model
        Lengths metres; the document keeps metres (``"units": "m"``) and records the model's
        output unit as ``display_units``. Its scan, when attached, is stored whole as the
        ``scan`` section (:func:`asbuilt.export.stored_scan.scan_section`; null without one).
    """
    document = {
        "format": FORMAT,
        "version": VERSION,
        "units": "m",
        "display_units": model.units,
        "name": model.name,
        "source": model.scan.source if model.scan is not None else model.source,
        "catalog": model.catalog,
        "catalog_file": model.catalog_file,
        "components": [_component(c) for c in model.components],
        "spools": [
            {"id": s.id, "components": list(s.components), "pipe_length": s.pipe_length}
            for s in model.spools
        ],
        "findings": [finding_to_dict(f) for f in model.findings],
        "scan": scan_section(model.scan),
    }
    return json_ready(document)


def dumps_model(model: Model) -> str:
    """The model document as JSON text (2-space indent, keys in the documented order; a list
    of numbers, such as a point, on one line)."""
    return _dumps(model_document(model), "") + "\n"


def _dumps(value, indent: str) -> str:
    """``json.dumps(value, indent=2)``, but a list holding no list or object on one line: the
    scan section's thousands of points take a line each, not four."""
    inner = indent + "  "
    if isinstance(value, dict) and value:
        items = (f"{inner}{json.dumps(k)}: {_dumps(v, inner)}" for k, v in value.items())
        return "{\n" + ",\n".join(items) + f"\n{indent}}}"
    if isinstance(value, list) and any(isinstance(v, (dict, list)) for v in value):
        return "[\n" + ",\n".join(inner + _dumps(v, inner) for v in value) + f"\n{indent}]"
    return json.dumps(value, allow_nan=False)


def write_model_json(model: Model, path) -> None:
    """Write the model document to ``path`` atomically (temporary file, then rename)."""
    text = dumps_model(model)
    with atomic_write(path, "w") as handle:
        handle.write(text)


def _write_document(model: Model, path) -> None:
    """Registry entry point: write the document to ``path`` directly (the caller stages it)."""
    Path(path).write_text(dumps_model(model), encoding="utf-8")
