"""Reading an ``asbuilt-model`` document back: recognise it, parse and check it, rebuild a Model.

The reading side of :mod:`asbuilt.export.model_json` (which re-exports every public name here,
and writes the document): the format's name and version the reader accepts, the error a
malformed document raises, and the field-by-field rebuild of components (with their fits),
findings, spools and the stored scan, each bad field named by its place in the document.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping

import numpy as np

from asbuilt._json_numbers import parse_int as _parse_int
from asbuilt.errors import ExportError, ScanError
from asbuilt.export._model_fields import (
    check_component_fields,
    check_diagnostics,
    faces_field,
    insulation_field,
    number_field,
    point_field,
    points_field,
    positive_field,
    wall_field,
)
from asbuilt.export.stored_fit import (
    StoredFit,
    SummaryFieldError,
    stored_fit_from_summary,
    summary_float,
)
from asbuilt.export.stored_fit import describe_value as _describe
from asbuilt.export.stored_scan import scan_from_section
from asbuilt.findings import Finding, Suggestion, Waived
from asbuilt.model import (
    Bend,
    Component,
    Correction,
    Cross,
    Model,
    Reducer,
    Spool,
    Straight,
    Tee,
)
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.scan.model import Scan
from asbuilt.units import UNITS

__all__ = [
    "FORMAT",
    "VERSION",
    "ModelDocumentError",
    "is_model_document",
    "model_document_in",
    "load_model_document",
    "loads_model_document",
    "model_from_document",
    "load_model",
]

FORMAT = "asbuilt-model"
VERSION = 1


class ModelDocumentError(ExportError):
    """An ``asbuilt-model`` document is malformed (not JSON, wrong format, bad field)."""


def is_model_document(path) -> bool:
    """Whether ``path`` holds an ``asbuilt-model`` document (rather than a scan).

    False for anything unreadable or not JSON: the scan loader then reports the problem.
    """
    try:
        with open(path, "rb") as handle:
            head = handle.read(4096)
            if b'"asbuilt-model"' not in head:
                return False
            return model_document_in(head + handle.read()) is not None
    except OSError:
        return False


def model_document_in(data: bytes) -> dict | None:
    """The JSON object in ``data`` when it is an ``asbuilt-model`` document, else None (not
    UTF-8, not JSON, nested too deeply, another format: the scan loader then says what is wrong).
    A byte order mark is allowed, as every reader allows it."""
    if b'"asbuilt-model"' not in data[:4096]:
        return None
    try:
        # The integer hook the reader uses: a 400-digit integer reads as infinite and is refused
        # by its field's name, instead of overflowing float() in a check.
        document = json.loads(data.decode("utf-8-sig"), parse_int=_parse_int)
    except (ValueError, RecursionError):
        return None
    if isinstance(document, dict) and document.get("format") == FORMAT:
        return document
    return None


def load_model_document(path) -> dict:
    """Read and check an ``asbuilt-model`` JSON document; return it as plain data.

    Raises
    ------
    ModelDocumentError
        When the file is unreadable, not JSON, or not an ``asbuilt-model`` version 1 document.
    """
    from .._text import read_text

    source = str(path)
    text = read_text(
        path,
        ModelDocumentError,
        what="model document",
        missing="cannot read the file (No such file or directory); check the path",
    )
    return loads_model_document(text, source=source)


def loads_model_document(text: str, *, source: str | None = None) -> dict:
    """:func:`load_model_document` of JSON text; ``source`` names it in errors."""
    from .._text import loads_json

    try:
        document = loads_json(text, ModelDocumentError, source=source)
    except json.JSONDecodeError as exc:
        raise ModelDocumentError(
            f"line {exc.lineno} column {exc.colno}: invalid JSON ({exc.msg}); fix the syntax there",
            source=source,
        ) from None
    except RecursionError:
        raise ModelDocumentError(
            "invalid JSON (nested too deeply); fix or re-export the model document",
            source=source,
        ) from None
    _check_document(document, source)
    return document


def _check_document(document, source: str | None) -> None:
    if not isinstance(document, dict):
        raise ModelDocumentError("the document must be a JSON object", source=source)
    if document.get("format") != FORMAT:
        raise ModelDocumentError(
            f"format is {document.get('format')!r}, expected {FORMAT!r}; is this a model file?",
            source=source,
            where="format",
        )
    if document.get("version") != VERSION:
        raise ModelDocumentError(
            f"version {document.get('version')!r} is not supported; this asbuilt reads "
            f"version {VERSION}",
            source=source,
            where="version",
        )
    if document.get("units", "m") != "m":
        raise ModelDocumentError(
            "units must be 'm' (documents store metres)", source=source, where="units"
        )
    if "components" not in document:
        hint = (
            'it has "objects", so it looks like a scan: a scan\'s format is "asbuilt-scan"'
            if "objects" in document
            else 'add "components": [...] (an asbuilt-model document lists its components)'
        )
        raise ModelDocumentError(f"missing; {hint}", source=source, where="components")
    for key in ("components", "spools", "findings"):
        if not isinstance(document.get(key, []), list):
            raise ModelDocumentError("must be a list", source=source, where=key)


#: A component field with the wrong type or shape (``key``, and what it must be): the same
#: error a fit summary's field raises, so one handler locates both.
_BadField = SummaryFieldError


def _require_object(entry, where: str, what: str, source: str | None) -> None:
    if not isinstance(entry, dict):
        raise ModelDocumentError(
            f"must be a JSON object ({what}), not {_describe(entry)}", source=source, where=where
        )


def _geometry(entry: dict):
    shape = entry.get("shape")
    if shape == "straight":
        return Straight(
            point_field(entry, "start"),
            point_field(entry, "end"),
            positive_field(entry, "od") / 2,
            wall_field(entry),
        )
    if shape == "bend":
        start, end = points_field(entry, "ends", 2)
        od = positive_field(
            entry, "od"
        )  # od_end, wall_start, wall_end: absent before per-end sizes
        od_end = positive_field(entry, "od_end") if entry.get("od_end") is not None else od
        walls = wall_field(entry, "wall_start"), wall_field(entry, "wall_end")
        return Bend(
            start, end, point_field(entry, "center"), od / 2, walls[0], od_end / 2, walls[1]
        )
    if shape == "reducer":
        return Reducer(
            point_field(entry, "start"),
            point_field(entry, "end"),
            number_field(entry, "od_start") / 2,
            number_field(entry, "od_end") / 2,
            wall_field(entry, "wall_start"),
            point_field(entry, "offset") if entry.get("offset") is not None else np.zeros(3),
            wall_field(entry, "wall_end"),
        )
    if shape == "tee":
        run_start, run_end = points_field(entry, "run", 2)
        return Tee(
            point_field(entry, "center"),
            run_start,
            run_end,
            point_field(entry, "branch_end"),
            positive_field(entry, "od") / 2,
            number_field(entry, "branch_od") / 2,
            wall_field(entry),
            wall_field(entry, "branch_wall"),
        )
    if shape == "cross":
        run_start, run_end = points_field(entry, "run", 2)
        branch_start, branch_end = points_field(entry, "outlets", 2)
        return Cross(
            point_field(entry, "center"),
            run_start,
            run_end,
            branch_start,
            branch_end,
            positive_field(entry, "od") / 2,
            number_field(entry, "branch_od") / 2,
            wall_field(entry),
            wall_field(entry, "branch_wall"),
        )
    if shape == "cylinder":
        return Cylinder(
            point_field(entry, "center"),
            point_field(entry, "axis"),
            number_field(entry, "radius"),
            number_field(entry, "length"),
        )
    if shape == "cuboid":
        return Cuboid(
            point_field(entry, "center"), points_field(entry, "axes", 3), point_field(entry, "size")
        )
    if shape == "sphere":
        return Sphere(point_field(entry, "center"), number_field(entry, "radius"))
    if shape == "plane":
        outline = points_field(entry, "outline") if entry.get("outline") else np.zeros((0, 3))
        return Plane(point_field(entry, "point"), point_field(entry, "normal"), outline)
    if shape == "hull":
        return Hull(points_field(entry, "vertices"), faces_field(entry))
    raise _BadField(
        "shape",
        f"unknown shape {_describe(shape)}; use one of straight, bend, reducer, tee, cross, "
        "cylinder, "
        "cuboid, sphere, plane, hull",
    )


def _document_text(document: dict, key: str, source: str | None) -> str | None:
    """An optional top-level text field (absent in older documents)."""
    value = document.get(key)
    if value is not None and not isinstance(value, str):
        raise ModelDocumentError(
            f"must be text or null, not {_describe(value)}", source=source, where=key
        )
    return value


def _optional_float(value):
    return None if value is None else float(value)


#: The kinds a fit summary may name, and the document shapes of their primitives.
_FIT_SHAPES = {
    "cylinder": Cylinder,
    "cuboid": Cuboid,
    "sphere": Sphere,
    "plane": Plane,
    "hull": Hull,
}


def _fit_primitive(summary: dict, geometry):
    """The fitted primitive: the summary's ``primitive``, or (older documents, written without
    it) the component's own geometry when it is of the fitted kind (a pipe's straight as a
    cylinder of the fitted radius); None when neither gives one."""
    kind = summary["kind"]
    if kind not in _FIT_SHAPES:
        raise _BadField("kind", f"must be one of {', '.join(_FIT_SHAPES)}, not {_describe(kind)}")
    stored = summary.get("primitive")
    if stored is not None:
        if not isinstance(stored, dict):
            raise _BadField("primitive", f"must be an object, not {_describe(stored)}")
        try:
            primitive = _geometry(stored)
        except KeyError as exc:
            raise _BadField(f"primitive.{exc.args[0]}", "missing") from None
        except _BadField as exc:
            raise _BadField(f"primitive.{exc.key}", str(exc)) from None
        if not isinstance(primitive, _FIT_SHAPES[kind]):
            raise _BadField("primitive.shape", f"must be {kind!r} (the fitted kind)")
        return primitive
    if isinstance(geometry, _FIT_SHAPES[kind]):
        return geometry
    if kind == "cylinder" and isinstance(geometry, Straight):
        radius = summary_float(summary, "radius", geometry.outer_radius)
        middle = 0.5 * (geometry.start + geometry.end)
        return Cylinder(middle, geometry.direction, radius, geometry.length)
    return None


def _stored_fit(entry: dict, geometry) -> StoredFit | None:
    """The fit a component comes from, rebuilt from its ``fitted`` summary (None if null)."""
    summary = entry.get("fitted")
    if summary is None:
        return None
    if not isinstance(summary, dict):
        raise _BadField("fitted", f"must be an object or null, not {_describe(summary)}")
    try:
        if isinstance(summary.get("diagnostics"), dict):
            check_diagnostics(summary["diagnostics"])
        primitive = _fit_primitive(summary, geometry)
        return None if primitive is None else stored_fit_from_summary(summary, primitive)
    except KeyError as exc:
        raise _BadField(f"fitted.{exc.args[0]}", "missing") from None
    except _BadField as exc:
        raise _BadField(f"fitted.{exc.key}", str(exc)) from None


def _shared_fit(entry: dict, geometry, fits: dict) -> StoredFit | None:
    """:func:`_stored_fit`, one object per fit: merging cuts one scanned pipe into pieces at a
    tee that share its fit, and the rules judge each fit once (by identity)."""
    summary = entry.get("fitted")
    if not isinstance(summary, dict):
        return _stored_fit(entry, geometry)
    key = (json.dumps(entry.get("sources")), json.dumps(summary, sort_keys=True))
    if key not in fits:
        fits[key] = _stored_fit(entry, geometry)
    return fits[key]


def _waived(entry) -> Waived | None:
    """A finding's ``waived`` entry (null, or ``{"reason", "severity"}``) read back."""
    if entry is None:
        return None
    if not isinstance(entry, Mapping):
        raise ValueError(f"waived must be null or an object, not {entry!r}")
    return Waived(str(entry["reason"]), str(entry["severity"]))


def model_from_document(document: dict, *, source: str | None = None) -> Model:
    """Rebuild a :class:`Model` from an ``asbuilt-model`` document.

    Each component's fit is restored from its ``fitted`` summary as a
    :class:`~asbuilt.export.stored_fit.StoredFit` (components cut from one fit share one), so
    that :func:`asbuilt.rules.check_model` and the reports see the fits' uncertainty. The
    ``scan`` section becomes ``model.scan`` (points, sensor, links, size hints: what the rules
    and the report read of the scan); a document without it (older, or a model made without
    a scan) has ``model.scan`` None, as before.

    Raises
    ------
    ModelDocumentError
        Naming the component or finding and field that is wrong.
    """
    _check_document(document, source)
    display_units = document.get("display_units")
    if display_units is not None and not (
        isinstance(display_units, str) and display_units in UNITS
    ):
        # The unit STL and OBJ are written in: an unknown one failed there (ValueError).
        raise ModelDocumentError(
            f"must be one of {', '.join(UNITS)} or null, not {_describe(display_units)}",
            source=source,
            where="display_units",
        )
    name = _document_text(document, "name", source)  # IFC, glTF and STEP name things by it
    components = []
    fits: dict = {}
    first_of: dict = {}
    for index, entry in enumerate(document.get("components", [])):
        _require_object(entry, f"components[{index}]", "a component", source)
        where = f"components[{index}] ({entry.get('id')})"
        if isinstance(entry.get("id"), str) and entry["id"] in first_of:
            # Findings, spools and CAD names refer to components by id: two of one id would
            # pass for one (and only writing CAD caught it).
            raise ModelDocumentError(
                f"duplicate id {entry['id']!r} (also components[{first_of[entry['id']]}]); give "
                "every component its own id",
                source=source,
                where=f"{where}.id",
            )
        if isinstance(entry.get("id"), str):
            first_of.setdefault(entry["id"], index)
        try:
            check_component_fields(entry)
            sources = tuple(
                entry.get("sources") or ([entry["source"]] if entry.get("source") else [])
            )
            geometry = _geometry(entry)
            components.append(
                Component(
                    id=entry["id"],
                    type=entry["type"],
                    geometry=geometry,
                    sources=sources,
                    spool=entry.get("spool"),
                    group=entry.get("group"),
                    label=entry.get("label"),
                    nominal=entry.get("nominal"),
                    schedule=entry.get("schedule"),
                    insulation=insulation_field(entry),
                    snap=entry.get("snap") or {},
                    fit=_shared_fit(entry, geometry, fits),
                    corrections=tuple(
                        Correction(
                            c["what"],
                            c.get("before"),
                            c.get("after"),
                            float(c["size"]),
                            c.get("unit", ""),
                        )
                        for c in entry.get("corrections") or ()
                    ),
                )
            )
        except KeyError as exc:
            raise ModelDocumentError(
                f"missing field {exc.args[0]!r}", source=source, where=where
            ) from None
        except _BadField as exc:
            raise ModelDocumentError(str(exc), source=source, where=f"{where}.{exc.key}") from None
        except (TypeError, ValueError, AttributeError) as exc:
            raise ModelDocumentError(str(exc), source=source, where=where) from None
    findings = []
    for index, entry in enumerate(document.get("findings", [])):
        _require_object(entry, f"findings[{index}]", "a finding", source)
        try:
            findings.append(
                Finding(
                    code=entry["code"],
                    slug=entry["slug"],
                    severity=entry["severity"],
                    objects=tuple(entry.get("objects") or ()),
                    message=entry["message"],
                    location=entry.get("location"),
                    measured=_optional_float(entry.get("measured")),
                    allowed=_optional_float(entry.get("allowed")),
                    stderr=_optional_float(entry.get("stderr")),
                    unit=entry.get("unit", ""),
                    suggestions=tuple(
                        Suggestion(
                            s["description"],
                            s.get("change") or {},
                            bool(s.get("unambiguous", False)),
                        )
                        for s in entry.get("suggestions") or ()
                    ),
                    unverifiable=bool(entry.get("unverifiable", False)),
                    waived=_waived(entry.get("waived")),
                )
            )
        except KeyError as exc:
            raise ModelDocumentError(
                f"missing field {exc.args[0]!r}", source=source, where=f"findings[{index}]"
            ) from None
        except (TypeError, ValueError, AttributeError) as exc:
            raise ModelDocumentError(str(exc), source=source, where=f"findings[{index}]") from None
    spools = []
    for index, entry in enumerate(document.get("spools", [])):
        _require_object(entry, f"spools[{index}]", "a spool", source)
        try:
            spools.append(
                Spool(
                    str(entry["id"]),
                    tuple(entry.get("components") or ()),
                    float(entry.get("pipe_length") or 0.0),
                )
            )
        except KeyError as exc:
            raise ModelDocumentError(
                f"missing field {exc.args[0]!r}", source=source, where=f"spools[{index}]"
            ) from None
        except (TypeError, ValueError, AttributeError) as exc:
            raise ModelDocumentError(str(exc), source=source, where=f"spools[{index}]") from None

    scan = _stored_scan(document, source)
    _check_finite(document, source)
    return Model(
        components=tuple(components),
        scan=scan,
        units=display_units or "m",
        name=name,
        catalog=document.get("catalog"),
        spools=tuple(spools),
        findings=tuple(findings),
        catalog_file=_document_text(document, "catalog_file", source),
        source=_document_text(document, "source", source),
    )


def _first_non_finite(value) -> tuple | None:
    """The keys and indices leading to the first number in ``value`` that is not finite (a JSON
    ``NaN``, ``Infinity``, ``1e999`` or an integer beyond any float), ``()`` when ``value`` is
    one, or None."""
    if isinstance(value, float):
        return None if math.isfinite(value) else ()
    if isinstance(value, dict):
        items = value.items()
    elif isinstance(value, list):
        try:  # a point or another list of numbers, the bulk of a document: at C speed
            if all(map(math.isfinite, value)):
                return None
        except (TypeError, OverflowError):  # not all numbers (or an int beyond any float)
            pass
        items = enumerate(value)
    else:
        return None
    for key, item in items:
        if isinstance(item, (float, dict, list)):
            found = _first_non_finite(item)
            if found is not None:
                return (key, *found)
    return None


def _check_finite(document: dict, source: str | None) -> None:
    """Refuse a number anywhere in the document that is not finite (the writer writes those as
    null), naming its place; the fields checked one by one have already said theirs."""
    try:
        path = _first_non_finite(document)
    except RecursionError:
        raise ModelDocumentError(
            "nested too deeply; fix or re-export the model document", source=source
        ) from None
    if path is None:
        return
    value = document
    place = ""
    for depth, key in enumerate(path):
        value = value[key]
        if isinstance(key, int):
            place += f"[{key}]"
            if depth == 1 and path[0] == "components" and isinstance(value, dict):
                place += f" ({value.get('id')})"
        else:
            place += f".{key}" if place else str(key)
    raise ModelDocumentError(
        f"must be a finite number or null, not {_describe(value)}", source=source, where=place
    )


def _stored_scan(document: dict, source: str | None) -> Scan | None:
    """The scan of the document's ``scan`` section; None when it is absent or null."""
    section = document.get("scan")
    if section is None:
        return None
    if not isinstance(section, dict):
        raise ModelDocumentError(
            f"must be an asbuilt-scan object or null, not {_describe(section)}",
            source=source,
            where="scan",
        )
    try:
        return scan_from_section(section, _document_text(document, "source", source))
    except ScanError as exc:
        where = f"scan.{exc.where}" if exc.where else "scan"
        raise ModelDocumentError(exc.message, source=source, where=where) from None


def load_model(path) -> Model:
    """Read an ``asbuilt-model`` file and rebuild the :class:`Model` (see
    :func:`model_from_document`)."""
    return model_from_document(load_model_document(path), source=str(path))
