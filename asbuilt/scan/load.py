"""Read and validate ``asbuilt-scan`` version 1 documents (JSON) into :class:`~asbuilt.scan.model.Scan`.

The file format is described in ``docs/scan-format.md`` and, as a JSON Schema, by
:func:`asbuilt.scan.schema.scan_schema`; both are built from the constants in this module.

Every problem a user can cause raises :class:`~asbuilt.errors.ScanError` (or
:class:`~asbuilt.errors.ScanReadError` when the file cannot be read at all) with one line that
names the file, the place in it and what to do, e.g.
``scan.json: objects[3] (P4).points[17]: coordinate is NaN``.

Points are converted with numpy in one go; only when that conversion finds something wrong does
a Python loop walk the offending array to name the first bad entry.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from asbuilt._text import REPEATED_KEY, decode_text
from asbuilt.errors import ScanError, ScanReadError, located
from asbuilt.scan._json_hooks import (
    MAX_INTEGER_DIGITS,
    _first_repeated,
    _line_column_of_integer,
    _LongInteger,
    _object_from,
    _parse_int,
)
from asbuilt.scan.insulation import insulation_in_metres
from asbuilt.scan.model import KINDS, Scan, ScanObject, Sensor, kind_phrase
from asbuilt.tolerances import MIN_POINTS
from asbuilt.units import UNITS

__all__ = [
    "FORMAT",
    "VERSION",
    "MAX_FILE_BYTES",
    "MAX_POINTS",
    "PLAUSIBLE_RANGE_SIGMA",
    "IDENTICAL_RTOL",
    "COLLINEAR_RTOL",
    "MAX_INTEGER_DIGITS",
    "MAX_ANGLE_DEGREES",
    "TOP_LEVEL_KEYS",
    "OBJECT_KEYS",
    "load_scan",
    "loads_scan",
    "check_object_id",
    "check_text",
]

#: The ``format`` value every scan file carries.
FORMAT = "asbuilt-scan"
#: The only ``version`` this code reads.
VERSION = 1
#: Largest scan file accepted (checked with ``stat`` before parsing): 64 MiB is ~1.5 million
#: points of JSON, far beyond a sparse scan of 20-40 shots per object.
MAX_FILE_BYTES = 64 * 1024 * 1024
#: Most points (all objects together) a scan may hold.
MAX_POINTS = 1_000_000
#: Points whose spread (largest singular value of the centred points) is below this fraction of
#: their coordinate magnitude (at least 1 m) are taken as all identical.
IDENTICAL_RTOL = 1e-9
#: Points whose second singular value is below this fraction of the first lie on a line.
COLLINEAR_RTOL = 1e-6

#: Range sigmas (metres) a range finder can have: a laser tracker's 10 micrometres to a cheap
#: distance meter's few centimetres at long range, with margin. Outside, the value is almost
#: surely in the wrong unit (a metre value in a millimetre file is 1000 times too small).
PLAUSIBLE_RANGE_SIGMA = (1e-5, 0.1)


#: Largest coordinate magnitude, metres, after the unit conversion: beyond any survey frame
#: (UTM northings reach 1e7 m, Earth-centred coordinates 6.4e6 m). A larger one is a unit slip
#: or a corrupted number, and its squares would overflow the fits' arithmetic.
MAX_COORDINATE_M = 1e8

#: Longest id accepted, in characters: DXF names (layers, blocks) hold at most 255.
MAX_ID_CHARACTERS = 255
#: Largest pan or tilt angle a measurement may hold, in degrees (a full turn either way): more
#: is a count of steps or a corrupted number, which would make a calibration's shot anywhere.
MAX_ANGLE_DEGREES = 360.0

#: Top-level keys the format defines; any other key is kept in ``Scan.extra`` and ignored.
TOP_LEVEL_KEYS = ("format", "version", "units", "name", "sensor", "objects", "links")
#: Object keys the format defines; any other key is kept in ``ScanObject.extra``.
OBJECT_KEYS = (
    "id",
    "kind",
    "points",
    "group",
    "label",
    "nominal",
    "measurements",
    "station",
    "insulation",
)

_UNITS_TEXT = ", ".join(UNITS)
_KINDS_TEXT = ", ".join(KINDS)


def _describe(value) -> str:
    """A short phrase for a JSON value in messages: ``a string ("abc")``, ``null``, ``an array``."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if value == "":
        return "an empty string"
    if isinstance(value, str):
        shown = value if len(value) <= 20 else value[:17] + "..."
        return f"a string ({json.dumps(shown)})"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, dict):
        return "an object"
    if isinstance(value, float) and math.isnan(value):
        return "NaN"
    if isinstance(value, float) and math.isinf(value):
        return "infinite"
    text = repr(value)
    return text if len(text) <= 20 else text[:17] + "..."


def _shown(value) -> str:
    """A value as it would appear in the file when it is text, else :func:`_describe`."""
    return json.dumps(value) if isinstance(value, str) else _describe(value)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _is_finite_number(value) -> bool:
    """A JSON number that is a finite float (False for huge integers, NaN, infinities)."""
    if not _is_number(value):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


class _Context:
    """What every check needs to raise a located error: the source and a fast-path flag."""

    def __init__(self, source: str | None, may_hold_bools: bool):
        self.source = source
        self.may_hold_bools = may_hold_bools

    def error(self, where: str | None, message: str) -> ScanError:
        return ScanError(message, source=self.source, where=where)


# --------------------------------------------------------------------------------------------
# Reading


def load_scan(path) -> Scan:
    """Read and validate an ``asbuilt-scan`` file.

    Parameters
    ----------
    path : str or os.PathLike
        The JSON scan file; messages name it as given.

    Returns
    -------
    Scan
        All lengths in metres (points shape (n, 3) per object); ``Scan.units`` is the file's unit.

    Raises
    ------
    ScanReadError
        The file does not exist, cannot be read, or is larger than :data:`MAX_FILE_BYTES`.
    ScanError
        The content is not a valid version-1 scan (one located line says where and why).
    """
    source = os.fspath(path)
    if not source:
        raise ScanReadError("'': the scan file name is empty; give the scan's JSON file")
    try:
        size = os.stat(source).st_size
    except FileNotFoundError:
        raise ScanReadError(
            located(source, None, "file does not exist; check the path and the current directory")
        ) from None
    except OSError as exc:
        raise ScanReadError(
            located(
                source, None, f"cannot be read ({exc.strerror}); check the path and permissions"
            )
        ) from None
    if os.path.isdir(source):
        raise ScanReadError(located(source, None, "is a directory; give the scan's JSON file"))
    if size > MAX_FILE_BYTES:
        raise ScanReadError(_too_large(source, size))
    try:
        with open(source, "rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise ScanReadError(
            located(source, None, f"cannot be read ({exc.strerror}); check the file's permissions")
        ) from None
    if len(data) > MAX_FILE_BYTES:
        raise ScanReadError(_too_large(source, len(data)))
    return loads_scan(data, source=source)


def _too_large(source: str | None, size: int) -> str:
    return located(
        source,
        None,
        f"is {size:,} bytes, too large to be a sparse scan (the limit is "
        f"{MAX_FILE_BYTES // (1024 * 1024)} MiB and {MAX_POINTS:,} points); "
        "split it into several scans",
    )


def loads_scan(text: str | bytes, source: str | None = None) -> Scan:
    """Validate an ``asbuilt-scan`` document given as JSON text.

    Parameters
    ----------
    text : str or bytes
        The JSON document (bytes are decoded as UTF-8).
    source : str, optional
        Name used in messages (a file path); ``Scan.source`` keeps it.

    Returns
    -------
    Scan
        All lengths converted to metres; points shape (n, 3) per object.

    Raises
    ------
    ScanReadError
        The text is larger than :data:`MAX_FILE_BYTES`.
    ScanError
        Malformed JSON (with line and column) or an invalid document (located, one line).
    """
    if len(text) > MAX_FILE_BYTES:
        raise ScanReadError(_too_large(source, len(text)))
    if isinstance(text, (bytes, bytearray)):
        text = decode_text(bytes(text), ScanError, source=source, what="scan")
    if not text.strip():
        raise ScanError(
            "the file is empty (or only white space); give an asbuilt-scan JSON document",
            source=source,
        )
    repeated: list[bool] = []
    try:
        document = json.loads(
            text,
            object_pairs_hook=lambda pairs: _object_from(pairs, repeated),
            parse_int=_parse_int,
        )
    except json.JSONDecodeError as exc:
        raise ScanError(
            f"invalid JSON ({exc.msg}); fix the syntax there",
            source=source,
            where=f"line {exc.lineno} column {exc.colno}",
        ) from None
    except _LongInteger as exc:
        raise ScanError(
            f"a number of {exc.digits:,} digits is too long to be a coordinate; fix the number there",
            source=source,
            where=_line_column_of_integer(text, exc.digits),
        ) from None
    except RecursionError:
        raise ScanError("invalid JSON (nested too deeply)", source=source) from None
    context = _Context(source, may_hold_bools="true" in text or "false" in text)
    if repeated:
        where, key = _first_repeated(document, None)
        raise context.error(
            f"{where}.{key}" if where else key,
            REPEATED_KEY,
        )
    return _scan_from_document(document, context)


# --------------------------------------------------------------------------------------------
# Validation


def _scan_from_document(document, ctx: _Context) -> Scan:
    if not isinstance(document, dict):
        raise ctx.error(
            None,
            f"the top level is {_describe(document)}; an asbuilt-scan file is a JSON object "
            f'starting {{"format": "{FORMAT}", "version": {VERSION}, ...}}',
        )
    _check_format(document, ctx)
    factor = _check_units(document, ctx)
    name = _optional_string(document, "name", "name", ctx)
    sensor = _sensor(document.get("sensor"), document["units"], ctx)
    objects = _objects(document, factor, ctx)
    links = _links(document.get("links"), objects, ctx)
    extra = {key: value for key, value in document.items() if key not in TOP_LEVEL_KEYS}
    return Scan(
        units=document["units"],
        objects=objects,
        links=links,
        name=name,
        sensor=sensor,
        source=ctx.source,
        extra=MappingProxyType(extra),
    )


def _check_format(document: dict, ctx: _Context) -> None:
    if "format" not in document:
        raise ctx.error(
            "format",
            f'missing; this is not an asbuilt scan (start the file with "format": "{FORMAT}", '
            f'"version": {VERSION})',
        )
    if document["format"] != FORMAT:
        model_hint = (
            " (a model document: re-export it with 'asbuilt check MODEL.json --fix OUT', or "
            "report on it with 'asbuilt report')"
            if document["format"] == "asbuilt-model"
            else ""
        )
        raise ctx.error(
            "format",
            f'is {_shown(document["format"])}, not "{FORMAT}"; this is not an asbuilt scan '
            f"file{model_hint}",
        )
    if "version" not in document:
        raise ctx.error("version", f'missing; add "version": {VERSION}')
    version = document["version"]
    if not _is_number(version):
        raise ctx.error("version", f"must be the number {VERSION}, not {_describe(version)}")
    if version != VERSION:
        raise ctx.error(
            "version",
            f"version {version} is not supported; this asbuilt reads version {VERSION} "
            "(upgrade asbuilt or convert the file)",
        )


def _check_units(document: dict, ctx: _Context) -> float:
    if "units" not in document:
        raise ctx.error("units", f'missing; add "units": one of {_UNITS_TEXT} (e.g. "units": "m")')
    units = document["units"]
    if not isinstance(units, str) or units not in UNITS:
        raise ctx.error("units", f"unknown unit {_shown(units)}; use one of {_UNITS_TEXT}")
    return UNITS[units]


def _optional_string(mapping: Mapping, key: str, where: str, ctx: _Context) -> str | None:
    value = mapping.get(key)
    if value is None:
        return value
    if isinstance(value, str):
        return _checked_text(value, where, ctx)
    raise ctx.error(where, f"must be text (a JSON string), not {_describe(value)}")


def _checked_text(value: str, where: str, ctx: _Context) -> str:
    """``value`` unless it holds a character no output can carry: an unpaired UTF-16 surrogate
    (JSON's ``\\ud800`` escape is legal syntax, but no UTF-8 file, terminal or CAD string can
    encode it) or a control character (a line break would split the one-line messages and the
    OBJ / DXF records; STEP truncates at NUL)."""
    for position, character in enumerate(value):
        code = ord(character)
        if 0xD800 <= code <= 0xDFFF:
            what = f"an unpaired surrogate (\\u{code:04x})"
        elif code < 0x20 or 0x7F <= code < 0xA0:
            what = f"a control character (\\u{code:04x})"
        else:
            continue
        raise ctx.error(
            where,
            f"holds {what} at character {position + 1}; use printable text",
        )
    return value


def _checked_id(object_id, where: str, ctx: _Context) -> str:
    """``object_id`` unless an object's ``id`` may not be it (see :func:`check_object_id`)."""
    if not isinstance(object_id, str) or not object_id:
        raise ctx.error(
            where,
            f'must be non-empty text, not {_describe(object_id)}; give the object an id such as "P1"',
        )
    _checked_text(object_id, where, ctx)
    if len(object_id) > MAX_ID_CHARACTERS:
        raise ctx.error(
            where,
            f"is {len(object_id):,} characters long; use at most {MAX_ID_CHARACTERS} (CAD names "
            "hold no more)",
        )
    if object_id != object_id.strip():
        # CAD files drop or keep the spaces differently (STEP trims them), so the object could
        # not be matched across formats by its id.
        raise ctx.error(
            where,
            f"{json.dumps(object_id, ensure_ascii=False)} starts or ends with white space (or is "
            "only white space); remove it",
        )
    return object_id


def check_object_id(object_id, where: str, source: str | None = None) -> str:
    """Return ``object_id`` if a scan may carry it as an object's ``id``, as the loader checks:
    non-empty text of at most :data:`MAX_ID_CHARACTERS` characters, without control characters
    or white space at either end. For the tools that write scans (``asbuilt scan`` checks its
    plan's and its operator's ids before the session, which must not end in a refused file).

    Raises
    ------
    ScanError
        One line naming ``source`` and ``where`` (e.g. ``targets[0].id``).
    """
    return _checked_id(object_id, where, _Context(source, may_hold_bools=False))


def check_text(value: str, where: str, source: str | None = None) -> str:
    """Return ``value`` if a scan may carry it as a name, group, label or nominal size, as the
    loader checks: no control character nor unpaired surrogate.

    Raises
    ------
    ScanError
        One line naming ``source`` and ``where`` (e.g. ``--name``).
    """
    return _checked_text(value, where, _Context(source, may_hold_bools=False))


def _position(raw, factor: float, where: str, ctx: _Context) -> np.ndarray | None:
    """An optional station position [x, y, z] in file units, as (3,) metres."""
    if raw is None:
        return None
    if not isinstance(raw, list) or len(raw) != 3 or not all(_is_finite_number(c) for c in raw):
        raise ctx.error(where, "must be 3 finite numbers [x, y, z] in the file's units")
    position = np.array(raw, dtype=np.float64) * factor
    if np.abs(position).max() > MAX_COORDINATE_M:
        raise ctx.error(where, _beyond_reach(float(np.abs(position).max())))
    position.setflags(write=False)
    return position


def _sensor(raw, units: str, ctx: _Context) -> Sensor:
    factor = UNITS[units]
    if raw is None:
        return Sensor()
    if not isinstance(raw, dict):
        raise ctx.error(
            "sensor",
            f'must be an object like {{"position": [x, y, z], "range_sigma": 0.002}}, '
            f"not {_describe(raw)}",
        )
    position = _position(raw.get("position"), factor, "sensor.position", ctx)
    sigma = raw.get("range_sigma")
    if sigma is not None:
        if not _is_finite_number(sigma) or sigma <= 0:
            raise ctx.error(
                "sensor.range_sigma",
                f"must be a positive number (the range noise in the file's units), "
                f"not {_describe(sigma)}",
            )
        low, high = PLAUSIBLE_RANGE_SIGMA
        if not low <= float(sigma) * factor <= high:
            raise ctx.error(
                "sensor.range_sigma",
                f"{float(sigma):g} {units} is not a range finder's noise (expected "
                f"{low / factor:g} to {high / factor:g} {units}); it is in the file's units "
                f"({units}): check the value and the units",
            )
        sigma = float(sigma) * factor
    return Sensor(position=position, range_sigma=sigma)


def _objects(document: dict, factor: float, ctx: _Context) -> tuple[ScanObject, ...]:
    if "objects" not in document:
        raise ctx.error(
            "objects", 'missing; add "objects": [{"id": ..., "kind": ..., "points": [...]}]'
        )
    raw_objects = document["objects"]
    if not isinstance(raw_objects, list):
        raise ctx.error("objects", f"must be an array of objects, not {_describe(raw_objects)}")
    objects = []
    first_index: dict[str, int] = {}
    total = 0
    for index, raw in enumerate(raw_objects):
        obj = _object(index, raw, factor, ctx)
        if obj.id in first_index:
            raise ctx.error(
                f"{obj.where}.id",
                f"duplicate id {json.dumps(obj.id)} (also objects[{first_index[obj.id]}]); "
                "give every object its own id",
            )
        first_index[obj.id] = index
        total += len(obj.points)
        if total > MAX_POINTS:
            raise ctx.error(
                obj.where,
                f"the scan holds more than {MAX_POINTS:,} points, too many for a sparse scan; "
                "split it into several scans",
            )
        objects.append(obj)
    return tuple(objects)


def _object(index: int, raw, factor: float, ctx: _Context) -> ScanObject:
    where = f"objects[{index}]"
    if not isinstance(raw, dict):
        raise ctx.error(
            where,
            f'must be an object like {{"id": "P1", "kind": "cylinder", "points": [...]}}, '
            f"not {_describe(raw)}",
        )
    object_id = raw.get("id")
    if "id" not in raw:
        raise ctx.error(f"{where}.id", 'missing; give the object an id such as "P1"')
    _checked_id(object_id, f"{where}.id", ctx)
    where = f"{where} ({object_id})"
    kind = raw.get("kind")
    if "kind" not in raw:
        raise ctx.error(f"{where}.kind", f"missing; use one of {_KINDS_TEXT}")
    if not isinstance(kind, str) or kind not in KINDS:
        raise ctx.error(f"{where}.kind", f"unknown kind {_shown(kind)}; use one of {_KINDS_TEXT}")
    if "points" not in raw:
        raise ctx.error(f"{where}.points", "missing; add the measured points [[x, y, z], ...]")
    points = _triples(raw["points"], f"{where}.points", "point", "[x, y, z]", ctx) * factor
    _check_magnitude(points, f"{where}.points", ctx)
    _check_spread(points, kind, f"{where}.points", ctx)
    points.setflags(write=False)
    measurements = None
    if raw.get("measurements") is not None:
        measurements = _measurements(raw["measurements"], len(points), factor, where, ctx)
    return ScanObject(
        id=object_id,
        kind=kind,
        points=points,
        index=index,
        group=_optional_string(raw, "group", f"{where}.group", ctx),
        label=_optional_string(raw, "label", f"{where}.label", ctx),
        nominal=_optional_string(raw, "nominal", f"{where}.nominal", ctx),
        measurements=measurements,
        station=_position(raw.get("station"), factor, f"{where}.station", ctx),
        insulation=_insulation(raw.get("insulation"), kind, factor, f"{where}.insulation", ctx),
        extra=MappingProxyType({k: v for k, v in raw.items() if k not in OBJECT_KEYS}),
    )


def _insulation(value, kind: str, factor: float, where: str, ctx: _Context) -> float:
    """The object's insulation thickness in metres (0 when absent or null), or a located error."""
    thickness, problem = insulation_in_metres(value, kind, factor, _describe)
    if problem:
        raise ctx.error(where, problem)
    return thickness


def _triples(raw, where: str, item: str, form: str, ctx: _Context) -> np.ndarray:
    """``raw`` (a JSON array of 3-number arrays) as a float64 array (n, 3), or a located error.

    numpy converts well-formed input in one call; anything it cannot convert cleanly (ragged rows,
    strings, nulls, booleans, NaN, infinities) is then located by :func:`_locate_bad_triple`.
    """
    if not isinstance(raw, list):
        raise ctx.error(where, f"must be an array of {item}s {form}, not {_describe(raw)}")
    if not raw:
        return np.zeros((0, 3))
    try:
        array = np.array(raw)
    except (ValueError, TypeError, OverflowError):
        array = None
    clean = (
        array is not None
        and array.ndim == 2
        and array.shape[1] == 3
        and array.dtype.kind in "iuf"
        and not (ctx.may_hold_bools and _holds_bool(raw))
    )
    if clean:
        array = array.astype(np.float64, copy=False)
        clean = bool(np.isfinite(array).all())
    if not clean:
        _locate_bad_triple(raw, where, item, form, ctx)
        # Every entry is a finite number, yet numpy kept objects: integers beyond 64 bits.
        array = np.array([[float(c) for c in row] for row in raw], dtype=np.float64)
    return np.array(array, dtype=np.float64)


def _holds_bool(raw: list) -> bool:
    return any(type(c) is bool for row in raw for c in row)


def _locate_bad_triple(raw: list, where: str, item: str, form: str, ctx: _Context) -> None:
    for i, row in enumerate(raw):
        here = f"{where}[{i}]"
        if not isinstance(row, list):
            raise ctx.error(
                here, f"a {item} must be an array of 3 numbers {form}, not {_describe(row)}"
            )
        if len(row) != 3:
            raise ctx.error(here, f"a {item} must be 3 numbers {form}, not {len(row)}")
        for value in row:
            if not _is_number(value):
                raise ctx.error(here, f"coordinate is {_describe(value)}, not a number")
            try:
                number = float(value)
            except OverflowError:
                raise ctx.error(here, "coordinate is too large to be a length") from None
            if math.isnan(number):
                raise ctx.error(here, "coordinate is NaN")
            if math.isinf(number):
                raise ctx.error(here, "coordinate is infinite")


def _check_magnitude(points: np.ndarray, where: str, ctx: _Context) -> None:
    """A located error for the first point with a coordinate beyond ``MAX_COORDINATE_M``."""
    if len(points) and np.abs(points).max() > MAX_COORDINATE_M:
        row = int(np.argmax(np.abs(points).max(axis=1) > MAX_COORDINATE_M))
        raise ctx.error(f"{where}[{row}]", _beyond_reach(float(np.abs(points[row]).max())))


def _beyond_reach(metres: float) -> str:
    return (
        f"a coordinate of {metres:.3g} m is beyond any site (at most {MAX_COORDINATE_M:.0e} m, "
        "after the file's units); check the units and the number"
    )


def _check_spread(points: np.ndarray, kind: str, where: str, ctx: _Context) -> None:
    """Too few points for the kind, or all identical, or collinear: a located error."""
    n = len(points)
    need = MIN_POINTS[kind]
    if n < need:
        raise ctx.error(
            where,
            f"has {n} point{'s' if n != 1 else ''}; {kind_phrase(kind)} needs at least {need}; "
            "scan more points on the object",
        )
    centred = points - points.mean(axis=0)
    singular = np.linalg.svd(centred, compute_uv=False)
    scale = max(1.0, float(np.abs(points).max()))
    if singular[0] <= IDENTICAL_RTOL * scale:
        spread = float(np.ptp(points, axis=0).max())
        if spread == 0.0:
            raise ctx.error(
                where,
                f"all {n} points are identical; {kind_phrase(kind)} needs points spread across "
                "its surface (re-aim and rescan)",
            )
        # Not identical, but closer together than coordinates this far from the origin are
        # trusted to resolve (a millimetre-sized object in a survey frame, or a unit slip).
        raise ctx.error(
            where,
            f"the {n} points span only {spread:.3g} m at coordinates of {scale:.3g} m, too "
            f"little to resolve there (under {IDENTICAL_RTOL:g} of the coordinates); check the "
            "units, or give the points relative to a site origin",
        )
    if singular[1] <= COLLINEAR_RTOL * singular[0]:
        # One point far from all the others (a survey-frame point pasted in, a unit slip) makes
        # any set look collinear: name it rather than blame the aim.
        middle = np.median(points, axis=0)
        offset = points - middle
        # hypot scales as it goes: squaring a coordinate of 1e200 would overflow to inf.
        distance = np.hypot(np.hypot(offset[:, 0], offset[:, 1]), offset[:, 2])
        far = int(np.argmax(distance))
        rest = np.delete(points, far, axis=0)
        rest_singular = np.linalg.svd(rest - rest.mean(axis=0), compute_uv=False)
        if rest_singular[1] > COLLINEAR_RTOL * rest_singular[0]:
            raise ctx.error(
                f"{where}[{far}]",
                f"this point lies {distance[far]:.4g} m from the others' median, which makes "
                "them look collinear; check its coordinates (units, a point from another frame)",
            )
        raise ctx.error(
            where,
            f"the points are collinear; {kind_phrase(kind)} needs points spread across its surface "
            "(re-aim and rescan)",
        )


def _measurements(raw, n_points: int, factor: float, where: str, ctx: _Context) -> np.ndarray:
    """Raw ``[pan_deg, tilt_deg, range]`` rows to (n, 3) pan rad, tilt rad, range m."""
    here = f"{where}.measurements"
    values = _triples(raw, here, "measurement", "[pan_deg, tilt_deg, range]", ctx)
    if len(values) != n_points:
        raise ctx.error(
            here,
            f"{len(values)} measurements for {n_points} points; give one "
            "[pan_deg, tilt_deg, range] per point, in the same order, or leave measurements out",
        )
    bad = np.flatnonzero(values[:, 2] <= 0)
    if bad.size:
        raise ctx.error(f"{here}[{bad[0]}]", "range must be positive (in the file's units)")
    beyond = np.flatnonzero(np.abs(values[:, :2]).max(axis=1) > MAX_ANGLE_DEGREES)
    if beyond.size:
        row = values[beyond[0]]
        axis = "pan" if abs(row[0]) > MAX_ANGLE_DEGREES else "tilt"
        raise ctx.error(
            f"{here}[{beyond[0]}]",
            f"a {axis} angle of {row[0 if axis == 'pan' else 1]:g} degrees is beyond a full turn "
            f"(at most {MAX_ANGLE_DEGREES:g}); give the pan-tilt unit's angles in degrees",
        )
    result = np.column_stack(
        [np.radians(values[:, 0]), np.radians(values[:, 1]), values[:, 2] * factor]
    )
    result.setflags(write=False)
    return result


def _links(raw, objects: tuple[ScanObject, ...], ctx: _Context) -> tuple[tuple[str, str], ...]:
    if raw is None:
        return ()
    if not isinstance(raw, list):
        raise ctx.error(
            "links", f'must be an array of id pairs like [["P1", "P2"]], not {_describe(raw)}'
        )
    known = {obj.id for obj in objects}
    links = []
    for i, pair in enumerate(raw):
        where = f"links[{i}]"
        if (
            not isinstance(pair, list)
            or len(pair) != 2
            or not all(isinstance(x, str) for x in pair)
        ):
            raise ctx.error(
                where, f'must be a pair of object ids like ["P1", "P2"], not {_describe_pair(pair)}'
            )
        for object_id in pair:
            if object_id not in known:
                raise ctx.error(
                    where,
                    f"unknown object id {json.dumps(object_id)}; link only ids listed in objects",
                )
        if pair[0] == pair[1]:
            raise ctx.error(
                where, f"links {json.dumps(pair[0])} to itself; link two different objects"
            )
        links.append((pair[0], pair[1]))
    return tuple(links)


def _describe_pair(value) -> str:
    if not isinstance(value, list):
        return _describe(value)
    if len(value) != 2:
        return f"an array of {len(value)} item{'s' if len(value) != 1 else ''}"
    return "[" + ", ".join(_describe(v) for v in value) + "]"
