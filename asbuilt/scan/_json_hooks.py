"""The ``json.loads`` hooks of the scan loader: integers too long, keys given twice.

Private helper of :func:`asbuilt.scan.load.loads_scan`. An integer literal longer than
:data:`MAX_INTEGER_DIGITS` is refused while parsing (:func:`_parse_int`, located afterwards by
:func:`_line_column_of_integer`), and a JSON object whose key repeats is marked
(:func:`_object_from`) so that the first one can be reported with where it is
(:func:`_first_repeated`).
"""

from __future__ import annotations

import re

#: Most digits a JSON integer may have: 640 is the lowest limit Python's int parsing can be set
#: to (``sys.int_info.str_digits_check_threshold``), so a longer number is refused here with a
#: located message before Python's own ``ValueError`` can fire; any integer past 309 digits is
#: too large to be a length anyway.
MAX_INTEGER_DIGITS = 640


class _LongInteger(ValueError):
    """A JSON integer longer than :data:`MAX_INTEGER_DIGITS` (``digits``: how many it has)."""

    def __init__(self, digits: int):
        super().__init__(digits)
        self.digits = digits


def _parse_int(literal: str) -> int:
    """``json.loads`` integer hook: ``int``, refusing literals too long to convert."""
    digits = len(literal) - literal.startswith("-")
    if digits > MAX_INTEGER_DIGITS:
        raise _LongInteger(digits)
    return int(literal)


def _line_column_of_integer(text: str, digits: int) -> str | None:
    """``line L column C`` of the first JSON number of exactly ``digits`` integer digits (as
    :class:`json.JSONDecodeError` counts them), or None when it cannot be found."""
    found = re.search(rf"(?<![\w.\"])-?\d{{{digits}}}(?![\d.eE])", text)
    if found is None:
        return None
    start = found.start()
    line = text.count("\n", 0, start) + 1
    return f"line {line} column {start - text.rfind(chr(10), 0, start)}"


class _Repeated(dict):
    """A JSON object in which a key appeared more than once (``repeated``: the first such)."""

    repeated = ""


def _object_from(pairs: list, repeated: list) -> dict:
    """``json.loads`` object hook: a dict, marked (and ``repeated`` flagged) when a key repeats;
    the last value wins, as in a plain ``json.loads``, until the repeat is reported."""
    result = dict(pairs)
    if len(result) == len(pairs):
        return result
    marked = _Repeated(result)
    seen: set[str] = set()
    for key, _ in pairs:
        if key in seen:
            marked.repeated = key
            break
        seen.add(key)
    repeated.append(True)
    return marked


def _first_repeated(value, where: str | None):
    """``(where, key)`` of the first object (depth first, in file order) with a repeated key;
    ``where`` as in the error messages (``objects[3] (P4)``), None at the top level."""
    if isinstance(value, _Repeated):
        return where, value.repeated
    if isinstance(value, dict):
        for key, item in value.items():
            if isinstance(item, (dict, list)):
                found = _first_repeated(item, f"{where}.{key}" if where else key)
                if found:
                    return found
    elif isinstance(value, list):
        for index, item in enumerate(value):
            if isinstance(item, (dict, list)):
                label = f"{where or ''}[{index}]"
                if isinstance(item, dict) and isinstance(item.get("id"), str):
                    label += f" ({item['id']})"
                found = _first_repeated(item, label)
                if found:
                    return found
    return None
