"""The scan a model document was made from, stored in it (its ``scan`` section) and read back.

What the compliance rules, merging and the report read of a scan besides the fits is not in
the components: the sensor's range sigma (the poor-fit rule judges a fit's RMS against it), the
operator's ``links`` (linked objects are joined: no clash between them, contiguity follows the
links) and size hints (``nominal``: the hint-mismatch rule), and the measured points (the
report's object and point counts and its plan figures). A model document that dropped them
judged differently from the scan. The section is the scan itself, as an ``asbuilt-scan``
version-1 document in metres (every point, link, hint, station, raw measurement and unknown key
of the scan), so nothing measured or given by the operator is lost.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from asbuilt.errors import ScanError
from asbuilt.export.stored_fit import describe_value as _describe
from asbuilt.scan.load import FORMAT, OBJECT_KEYS, TOP_LEVEL_KEYS, VERSION
from asbuilt.scan.model import KINDS, Scan, ScanObject, Sensor

__all__ = ["scan_section", "scan_from_section"]


def _object_entry(obj: ScanObject) -> dict:
    """One scan object in the scan file's form (metres; raw measurements in degrees)."""
    entry = {
        "id": obj.id,
        "kind": obj.kind,
        "points": np.asarray(obj.points, dtype=np.float64),
        "group": obj.group,
        "label": obj.label,
        "nominal": obj.nominal,
    }
    if obj.measurements is not None:
        raw = np.asarray(obj.measurements, dtype=np.float64)
        entry["measurements"] = np.column_stack(
            [np.degrees(raw[:, 0]), np.degrees(raw[:, 1]), raw[:, 2]]
        )
    if obj.station is not None:
        entry["station"] = np.asarray(obj.station, dtype=np.float64)
    if obj.insulation:
        entry["insulation"] = float(obj.insulation)
    entry.update({k: v for k, v in _mapping(obj.extra).items() if k not in OBJECT_KEYS})
    return entry


def _mapping(value) -> Mapping:
    return value if isinstance(value, Mapping) else {}


def scan_section(scan: Scan | None) -> dict | None:
    """The model document's ``scan`` section: ``scan`` as an ``asbuilt-scan`` document.

    Parameters
    ----------
    scan : Scan or None
        Points (n, 3) metres; sensor position (3,) metres and range sigma metres.

    Returns
    -------
    dict or None
        ``{"format": "asbuilt-scan", "version": 1, "units": "m", "name", "sensor": {"position",
        "range_sigma"}, "objects": [...], "links": [[a, b], ...], ...}`` (numpy arrays left for
        the caller's JSON conversion; the scan's unknown top-level keys last, as they were);
        None for a model without its scan.
    """
    if scan is None:
        return None
    sensor = scan.sensor
    section = {
        "format": FORMAT,
        "version": VERSION,
        "units": "m",
        "name": scan.name,
        "sensor": {"position": sensor.position, "range_sigma": sensor.range_sigma},
        "objects": [_object_entry(obj) for obj in scan.objects],
        "links": [list(link) for link in scan.links],
    }
    section.update({k: v for k, v in _mapping(scan.extra).items() if k not in TOP_LEVEL_KEYS})
    return section


def _fail(where: str, message: str) -> ScanError:
    return ScanError(message, where=where)


def _text(raw: Mapping, key: str, where: str) -> str | None:
    value = raw.get(key)
    if value is not None and not isinstance(value, str):
        raise _fail(
            f"{where}.{key}" if where else key, f"must be text or null, not {_describe(value)}"
        )
    return value


def _rows(value, where: str, form: str) -> np.ndarray:
    """A list of finite number triples as a read-only float array (n, 3)."""
    if isinstance(value, list) and not value:
        array = np.zeros((0, 3))
    else:
        try:
            array = np.array(value, dtype=np.float64) if isinstance(value, list) else None
        except (TypeError, ValueError):
            array = None
        kinds = isinstance(value, list) and all(
            isinstance(row, list) and all(_is_number(c) for c in row) for row in value
        )
        if array is None or not kinds or array.ndim != 2 or array.shape[1] != 3:
            raise _fail(where, f"must be a list of {form}, not {_describe(value)}")
        if not np.isfinite(array).all():
            raise _fail(where, "must hold finite numbers only")
    array.setflags(write=False)
    return array


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _position(value, where: str) -> np.ndarray | None:
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != 3:
        raise _fail(where, f"must be [x, y, z] in metres or null, not {_describe(value)}")
    return _rows([value], where, "[x, y, z]")[0]


def _sensor(raw) -> Sensor:
    if raw is None:
        return Sensor()
    if not isinstance(raw, dict):
        raise _fail("sensor", f"must be an object or null, not {_describe(raw)}")
    sigma = raw.get("range_sigma")
    if sigma is not None and (not _is_number(sigma) or not math.isfinite(sigma) or sigma <= 0):
        raise _fail(
            "sensor.range_sigma", f"must be a positive number (m) or null, not {_describe(sigma)}"
        )
    position = _position(raw.get("position"), "sensor.position")
    return Sensor(position=position, range_sigma=None if sigma is None else float(sigma))


def _insulation(raw, where: str) -> float:
    if raw is None:
        return 0.0
    if not _is_number(raw) or not math.isfinite(raw) or raw < 0:
        raise _fail(where, f"must be a number >= 0 (m) or null, not {_describe(raw)}")
    return float(raw)


def _scan_object(index: int, raw, seen: set) -> ScanObject:
    where = f"objects[{index}]"
    if not isinstance(raw, dict):
        raise _fail(where, f"must be an object, not {_describe(raw)}")
    object_id = raw.get("id")
    if not isinstance(object_id, str) or not object_id:
        raise _fail(f"{where}.id", f"must be non-empty text, not {_describe(object_id)}")
    if object_id in seen:
        raise _fail(f"{where}.id", f"duplicate id {json.dumps(object_id)}")
    seen.add(object_id)
    where = f"{where} ({object_id})"
    kind = raw.get("kind")
    if kind not in KINDS:
        raise _fail(f"{where}.kind", f"must be one of {', '.join(KINDS)}, not {_describe(kind)}")
    if "points" not in raw:
        raise _fail(f"{where}.points", "missing")
    points = _rows(raw["points"], f"{where}.points", "points [x, y, z] in metres")
    measurements = None
    if raw.get("measurements") is not None:
        here = f"{where}.measurements"
        values = _rows(raw["measurements"], here, "[pan_deg, tilt_deg, range_m]")
        if len(values) != len(points):
            raise _fail(
                here, f"{len(values)} measurements for {len(points)} points; give one per point"
            )
        measurements = np.column_stack(
            [np.radians(values[:, 0]), np.radians(values[:, 1]), values[:, 2]]
        )
        measurements.setflags(write=False)
    return ScanObject(
        id=object_id,
        kind=kind,
        points=points,
        index=index,
        group=_text(raw, "group", where),
        label=_text(raw, "label", where),
        nominal=_text(raw, "nominal", where),
        measurements=measurements,
        station=_position(raw.get("station"), f"{where}.station"),
        insulation=_insulation(raw.get("insulation"), f"{where}.insulation"),
        extra=MappingProxyType({k: v for k, v in raw.items() if k not in OBJECT_KEYS}),
    )


def _links(raw, known: set) -> tuple[tuple[str, str], ...]:
    if raw is None:
        return ()
    if not isinstance(raw, list):
        raise _fail("links", f"must be a list of id pairs, not {_describe(raw)}")
    links = []
    for i, pair in enumerate(raw):
        if (
            not isinstance(pair, list)
            or len(pair) != 2
            or not all(isinstance(x, str) and x in known for x in pair)
        ):
            message = f"must be a pair of ids listed in objects, not {_describe(pair)}"
            raise _fail(f"links[{i}]", message)
        links.append((pair[0], pair[1]))
    return tuple(links)


def scan_from_section(section: Mapping, scan_source: str | None) -> Scan:
    """The :class:`Scan` of a model document's ``scan`` section.

    The section is checked for its structure (types, shapes, finite numbers, unique ids, links
    between listed ids), not for what a scan file must hold to be fitted (enough points, spread
    over a surface): the fits are made, and an object the fit refused is kept as it was
    measured.

    Parameters
    ----------
    section : Mapping
        The section as read from JSON: an ``asbuilt-scan`` document in metres.
    scan_source : str or None
        The scan file the model was made from (the document's ``source``): the Scan's
        ``source``.

    Returns
    -------
    Scan
        ``units`` ``"m"``; points (n, 3) metres; measurements (n, 3) pan, tilt radians and
        range metres.

    Raises
    ------
    ScanError
        Located inside the section (``where`` as in a scan file, e.g.
        ``objects[3] (P4).points``), with no ``source``: the caller names the document.
    """
    for key, value in (("format", FORMAT), ("version", VERSION), ("units", "m")):
        if section.get(key) != value:
            raise _fail(key, f"must be {json.dumps(value)}, not {_describe(section.get(key))}")
    if not isinstance(section.get("objects"), list):
        raise _fail("objects", f"must be a list, not {_describe(section.get('objects'))}")
    seen: set = set()
    objects = tuple(_scan_object(i, raw, seen) for i, raw in enumerate(section["objects"]))
    return Scan(
        units="m",
        objects=objects,
        links=_links(section.get("links"), seen),
        name=_text(section, "name", ""),
        sensor=_sensor(section.get("sensor")),
        source=scan_source,
        extra=MappingProxyType({k: v for k, v in section.items() if k not in TOP_LEVEL_KEYS}),
    )
