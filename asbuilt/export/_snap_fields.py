"""The types of a model document's ``snap`` records and fit diagnostics, checked on loading.

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

__all__ = ["check_snap", "check_diagnostics"]


def _number(value) -> str | None:
    """None when ``value`` is a finite number or null (a non-finite number is written null);
    else what it must be."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return "must be a finite number or null"
    if abs(value) > MAX_COORDINATE_M:
        return f"must be at most {MAX_COORDINATE_M:g} in size (the scan's limit)"
    return None


def _text(value) -> str | None:
    return None if value is None or isinstance(value, str) else "must be text or null"


def _flag(value) -> str | None:
    return None if value is None or isinstance(value, bool) else "must be true, false or null"


def _texts(value) -> str | None:
    if value is None or (isinstance(value, list) and all(isinstance(v, str) for v in value)):
        return None
    return "must be a list of text"


def _point(value) -> str | None:
    if (
        isinstance(value, list)
        and len(value) == 3
        and all(_number(v) is None and v is not None for v in value)
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
            if len(item) != 2 or _text(item[0]) or _number(item[1]):
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


_SCALARS = (_number, _text, _flag, _texts, _point)

_CANDIDATE = _object({"nominal": _text, "od": _number, "od_catalog": _number})

#: The snap fields the program reads (merging writes them; docs/merging.md, docs/model-format.md).
SNAP_FIELDS: dict[str, Callable] = {
    "status": _text,
    "reason": _text,
    "nominal": _text,
    "catalog": _text,
    "dimensions": _text,
    "od_fit": _number,
    "od_stderr": _number,
    "od_catalog": _number,
    "od_joint": _number,
    "od_joint_stderr": _number,
    "angle_deg": _number,
    "bend_radius": _number,
    "length": _number,
    "window": _number,
    "standard": _flag,
    "hint_rejected": _flag,
    "connects": _texts,
    "run": _texts,
    "sizes": _texts,
    "notes": _texts,
    "merge_notes": _texts,
    "candidates": _candidates,
    "hint": _object({"nominal": _text, "size": _text, "od": _number, "agrees": _flag}),
    "eccentric": _object({"flat": _text, "offset": _number}),
    "fit_up": _objects(
        {"with": _text, "miss": _number, "stderr": _number, "allowed": _number, "at": _point},
        required=("with", "miss", "stderr", "allowed", "at"),
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
        problem = _number(value)
        if problem:
            raise SummaryFieldError(f"diagnostics.{name}", f"{problem}, not {_describe(value)}")
