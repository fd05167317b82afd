"""Reading JSON integers no float can hold: one hook for every JSON reader of the package.

Python's ``json`` turns an integer literal into an ``int`` of any size: one past the float range
(over 308 digits) then overflows wherever a field converts it, far from the field, and one past
4,300 digits raises while parsing (Python's integer-string limit). Read with :func:`parse_int`,
such an integer becomes an infinite float, which every number check refuses by the field's name
as not finite.
"""

from __future__ import annotations

__all__ = ["LONGEST_INTEGER", "parse_int"]

#: Digits of the longest integer a float holds (``sys.float_info.max`` is about 1.8e308).
LONGEST_INTEGER = 308


def parse_int(literal: str) -> int | float:
    """``json.loads`` integer hook: an ``int``, or +-inf for an integer of more than
    ``LONGEST_INTEGER`` digits (``float()`` of a decimal string does not raise)."""
    if len(literal) - literal.startswith("-") > LONGEST_INTEGER:
        return float(literal)
    return int(literal)
