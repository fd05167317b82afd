"""The fields of a model document's components, checked by type on loading: numbers, points,
texts, ``snap`` records and fit diagnostics (:mod:`asbuilt.export._model_json_read` reads them).

Merging writes ``snap`` (how a component's size was chosen, what a fitting connects, the
notes merging left) and the rules, reports and CAD read it back from a document. A document
edited by hand can put any JSON value there; each field the program reads is checked here, by
name, so that a wrong one is one located error (``components[3] (P1).snap.od_fit: must be a
number or null, not [1, 2]``) instead of a failure deep in a rule. Keys the program does not
read are kept as they are (a later version's, or the user's own).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

from asbuilt.export.stored_fit import SummaryFieldError
from asbuilt.export.stored_fit import describe_value as _describe
from asbuilt.scan.load import MAX_COORDINATE_M

__all__ = [
    "check_component_fields",
    "check_diagnostics",
    "check_snap",
    "faces_field",
    "number_field",
    "optional_text_field",
    "point_field",
    "points_field",
    "positive_field",
    "wall_field",
]


def _number_problem(value) -> str | None:
    """None when ``value`` is a finite number or null (a non-finite number is written null);
    else what it must be."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return "must be a finite number or null"
    if abs(value) > MAX_COORDINATE_M:
        return f"must be at most {MAX_COORDINATE_M:g} in size (the scan's limit)"
    return None


def _text_problem(value) -> str | None:
    return None if value is None or isinstance(value, str) else "must be text or null"


def _flag_problem(value) -> str | None:
    return None if value is None or isinstance(value, bool) else "must be true, false or null"


def _texts_problem(value) -> str | None:
    if value is None or (isinstance(value, list) and all(isinstance(v, str) for v in value)):
        return None
    return "must be a list of text"


def _sizes_problem(value) -> str | None:
    """A fitting's end sizes: nominal sizes, null for an end whose pipe matched no size."""
    if value is None or (
        isinstance(value, list) and all(v is None or isinstance(v, str) for v in value)
    ):
        return None
    return "must be a list of nominal sizes (text, or null for no catalog size)"


def _point_problem(value) -> str | None:
    if (
        isinstance(value, list)
        and len(value) == 3
        and all(_number_problem(v) is None and v is not None for v in value)
    ):
        return None
    return "must be 3 finite numbers [x, y, z]"


def _object(fields: Mapping[str, Callable], required: tuple[str, ...] = ()):
    """A checker of an object whose listed fields have the given checkers."""

    def check(value, key: str) -> None:
        if value is None:
            return
        if not isinstance(value, dict):
            raise SummaryFieldError(key, f"must be an object or null, not {_describe(value)}")
        for name in required:
            if value.get(name) is None:
                raise SummaryFieldError(f"{key}.{name}", "missing")
        _check_fields(value, fields, key)

    return check


def _objects(fields: Mapping[str, Callable], required: tuple[str, ...] = ()):
    """A checker of a list of such objects."""
    one = _object(fields, required)

    def check(value, key: str) -> None:
        if value is None:
            return
        if not isinstance(value, list):
            raise SummaryFieldError(key, f"must be a list or null, not {_describe(value)}")
        for index, item in enumerate(value):
            if item is None:
                raise SummaryFieldError(f"{key}[{index}]", "must be an object, not null")
            one(item, f"{key}[{index}]")

    return check


def _candidates(value, key: str) -> None:
    """``candidates``: objects ``{nominal, od}``, or (older documents) ``[nominal, od]`` pairs
    or bare nominal sizes (text, which the rules skip: no diameter to compare)."""
    if value is None:
        return
    if not isinstance(value, list):
        raise SummaryFieldError(key, f"must be a list or null, not {_describe(value)}")
    for index, item in enumerate(value):
        where = f"{key}[{index}]"
        if isinstance(item, str):
            continue
        if isinstance(item, list):
            if len(item) != 2 or _text_problem(item[0]) or _number_problem(item[1]):
                raise SummaryFieldError(
                    where, f"must be a pair [nominal, od] or an object, not {_describe(item)}"
                )
            continue
        if item is None:
            raise SummaryFieldError(where, "must be an object, not null")
        _CANDIDATE(item, where)


def _check_fields(mapping: Mapping, fields: Mapping[str, Callable], key: str) -> None:
    for name, check in fields.items():
        if name not in mapping:
            continue
        value = mapping[name]
        where = f"{key}.{name}" if key else name
        if check in _SCALARS:
            problem = check(value)
            if problem:
                raise SummaryFieldError(where, f"{problem}, not {_describe(value)}")
        else:
            check(value, where)


_SCALARS = (
    _number_problem,
    _text_problem,
    _flag_problem,
    _texts_problem,
    _sizes_problem,
    _point_problem,
)

_CANDIDATE = _object(
    {"nominal": _text_problem, "od": _number_problem, "od_catalog": _number_problem}
)

#: The snap fields the program reads (merging writes them; docs/merging.md, docs/model-format.md).
SNAP_FIELDS: dict[str, Callable] = {
    "status": _text_problem,
    "reason": _text_problem,
    "nominal": _text_problem,
    "catalog": _text_problem,
    "dimensions": _text_problem,
    "od_fit": _number_problem,
    "od_stderr": _number_problem,
    "od_catalog": _number_problem,
    "od_joint": _number_problem,
    "od_joint_stderr": _number_problem,
    "angle_deg": _number_problem,
    "bend_radius": _number_problem,
    "length": _number_problem,
    "position_range": _number_problem,
    "window": _number_problem,
    "standard": _flag_problem,
    "hint_rejected": _flag_problem,
    "connects": _texts_problem,
    "run": _texts_problem,
    "sizes": _sizes_problem,
    "notes": _texts_problem,
    "merge_notes": _texts_problem,
    "candidates": _candidates,
    "hint": _object(
        {
            "nominal": _text_problem,
            "size": _text_problem,
            "od": _number_problem,
            "agrees": _flag_problem,
        }
    ),
    "eccentric": _object({"flat": _text_problem, "offset": _number_problem}),
    "fit_up": _objects(
        {
            "with": _text_problem,
            "miss": _number_problem,
            "stderr": _number_problem,
            "allowed": _number_problem,
            "at": _point_problem,
        },
        required=("with", "miss", "stderr", "allowed", "at"),
    ),
    "loose_ends": _objects(
        {
            "end": _text_problem,
            "at": _point_problem,
            "touches": _text_problem,
            "touches_type": _text_problem,
            "touches_pipes": _texts_problem,
            "gap": _number_problem,
            "angle_deg": _number_problem,
            "noted": _flag_problem,
            "corner": _point_problem,
            "beyond": _number_problem,
            "bend_deg": _number_problem,
        },
        required=("end", "at", "touches"),
    ),
}


def check_snap(snap: Mapping) -> None:
    """Check the fields of a component's ``snap`` record that the program reads.

    Raises
    ------
    SummaryFieldError
        Naming the field (``snap.<name>``, or deeper) and what it must be.
    """
    _check_fields(snap, SNAP_FIELDS, "snap")


def check_diagnostics(diagnostics: Mapping) -> None:
    """Check a fit summary's ``diagnostics``: every value a finite number or null (the fits'
    diagnostics are numbers, :class:`asbuilt.fit.result.FitResult`).

    Raises
    ------
    SummaryFieldError
        Naming ``diagnostics.<name>``.
    """
    for name, value in diagnostics.items():
        problem = _number_problem(value)
        if problem:
            raise SummaryFieldError(f"diagnostics.{name}", f"{problem}, not {_describe(value)}")


def number_field(entry: dict, key: str) -> float:
    """A finite number field (metres where it is a length)."""
    value = entry[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SummaryFieldError(key, f"must be a finite number, not {_describe(value)}")
    if abs(value) > MAX_COORDINATE_M:
        raise SummaryFieldError(key, _BEYOND_SITE.format(value=value))
    return float(value)


def positive_field(entry: dict, key: str) -> float:
    """A finite number field > 0 (a diameter, metres), named in its own terms when it is not."""
    value = number_field(entry, key)
    if value <= 0:
        raise SummaryFieldError(key, f"must be a positive length in metres, not {value:g}")
    return value


def point_field(entry: dict, key: str, value=None) -> list:
    """A field of 3 finite numbers [x, y, z]."""
    value = entry[key] if value is None else value
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(
            isinstance(c, (int, float)) and not isinstance(c, bool) and math.isfinite(c)
            for c in value
        )
    ):
        raise SummaryFieldError(key, f"must be 3 finite numbers [x, y, z], not {_describe(value)}")
    for c in value:
        if abs(c) > MAX_COORDINATE_M:
            raise SummaryFieldError(key, _BEYOND_SITE.format(value=c))
    return value


#: A number the document may not hold: lengths and coordinates are metres on a site, and
#: their squares must not overflow the rules' and exports' arithmetic (the scan's own limit).
_BEYOND_SITE = (
    "{value:g} is beyond any site (at most "
    + f"{MAX_COORDINATE_M:g}"
    + " m, the scan's limit); check the number"
)


def optional_text_field(entry: dict, key: str) -> None:
    value = entry.get(key)
    if value is not None and not isinstance(value, str):
        raise SummaryFieldError(key, f"must be text or null, not {_describe(value)}")


def check_component_fields(entry: dict) -> None:
    """The non-geometric fields a component is rebuilt from, by type (``SummaryFieldError`` if not)."""
    if not isinstance(entry["id"], str) or not entry["id"]:
        raise SummaryFieldError("id", f"must be non-empty text, not {_describe(entry['id'])}")
    for key in ("source", "spool", "group", "label", "nominal", "schedule"):
        optional_text_field(entry, key)
    sources = entry.get("sources")
    if sources is not None and (
        not isinstance(sources, list) or not all(isinstance(item, str) for item in sources)
    ):
        raise SummaryFieldError(
            "sources", f"must be a list of object ids, not {_describe(sources)}"
        )
    snap = entry.get("snap")
    if snap is not None and not isinstance(snap, dict):
        raise SummaryFieldError("snap", f"must be an object or null, not {_describe(snap)}")
    if snap is not None:
        check_snap(snap)
    corrections = entry.get("corrections")
    if corrections is None:
        return
    if not isinstance(corrections, list):
        raise SummaryFieldError("corrections", f"must be a list, not {_describe(corrections)}")
    for index, item in enumerate(corrections):
        key = f"corrections[{index}]"
        if not isinstance(item, dict):
            raise SummaryFieldError(key, f"must be an object, not {_describe(item)}")
        if not isinstance(item.get("what"), str):
            raise SummaryFieldError(
                f"{key}.what", f"must be text, not {_describe(item.get('what'))}"
            )
        if "size" not in item:
            raise SummaryFieldError(f"{key}.size", "missing; give the correction's size (a number)")
        try:
            number_field(item, "size")
        except SummaryFieldError as exc:
            raise SummaryFieldError(f"{key}.size", str(exc)) from None


def points_field(entry: dict, key: str, count: int | None = None) -> list:
    """A field holding a list of points (``count`` of them when given)."""
    value = entry[key]
    if not isinstance(value, list) or (count is not None and len(value) != count):
        what = {None: "a list of points [[x, y, z], ...]", 2: "two points [[x, y, z], [x, y, z]]"}
        shape = what.get(count, f"{count} points [[x, y, z], ...]")
        raise SummaryFieldError(key, f"must be {shape}, not {_describe(value)}")
    return [point_field(entry, key, item) for item in value]


def faces_field(entry: dict) -> list:
    value = entry["faces"]
    if not isinstance(value, list) or not all(
        isinstance(face, list)
        and len(face) == 3
        and all(isinstance(i, int) and not isinstance(i, bool) for i in face)
        for face in value
    ):
        raise SummaryFieldError(
            "faces", f"must be triangles [[i, j, k], ...], not {_describe(value)}"
        )
    return value


def insulation_field(entry: dict) -> float:
    """The component's insulation thickness, metres: 0 when null or absent (documents written
    before insulation was modelled), else a number >= 0 (``SummaryFieldError`` if not)."""
    if entry.get("insulation") is None:
        return 0.0
    value = number_field(entry, "insulation")
    if value < 0:
        raise SummaryFieldError("insulation", f"must be >= 0 (metres), not {value!r}")
    return value


def wall_field(entry: dict, key: str = "wall") -> float:
    """The wall ``key`` (metres); one without it (a reducer's, tee's or elbow's end, in
    documents written before fittings had a wall per end) has the one ``wall``, or 0 (solid)."""
    if entry.get(key) is not None:
        return number_field(entry, key)
    return number_field(entry, "wall") if entry.get("wall") is not None else 0.0
