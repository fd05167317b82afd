"""Length units: converted once, at the edges (scan loading and output). Metres inside."""

from __future__ import annotations

import re

__all__ = [
    "UNITS",
    "IMPERIAL",
    "SMALL_SIZE_LIMIT",
    "to_metres",
    "from_metres",
    "unit_factor",
    "note_in_units",
]

#: Metres per unit, for every unit a scan or an output may use.
UNITS: dict[str, float] = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "ft": 0.3048}
#: Units that are imperial: text for people then gives lengths in inches and feet.
IMPERIAL = ("in", "ft")
#: Lengths below this (metres) are told in the small unit (mm, in), others in the large (m, ft).
SMALL_SIZE_LIMIT = 10.0


def unit_factor(unit: str) -> float:
    """Metres per ``unit``; ValueError naming the allowed units when unknown."""
    try:
        return UNITS[unit]
    except (KeyError, TypeError):
        allowed = ", ".join(UNITS)
        raise ValueError(f"unknown unit {unit!r}; use one of {allowed}") from None


def to_metres(value, unit: str):
    """``value`` (scalar or array) in ``unit`` converted to metres."""
    return value * unit_factor(unit)


def from_metres(value, unit: str):
    """``value`` (scalar or array) in metres converted to ``unit``."""
    return value / unit_factor(unit)


#: A length in a note: a number, a space, then mm or m as a word of its own.
_NOTE_LENGTH = re.compile(r"(?<![\w.])(\d+(?:\.\d+)?(?:e[+-]?\d+)?) (mm|m)\b(?![\^²])")


def note_in_units(note: str, units: str) -> str:
    """A note for people with its lengths (written in mm and m) in inches and feet when
    ``units`` is imperial: inches under :data:`SMALL_SIZE_LIMIT`, feet from it, three
    significant digits; unchanged for a metric unit. The one convention of every text that
    says lengths: the fits' notes (``asbuilt fit``), findings and merging's notes."""
    if units not in IMPERIAL:
        return note

    def imperial(match: re.Match) -> str:
        metres = float(match.group(1)) * (0.001 if match.group(2) == "mm" else 1.0)
        unit = "in" if abs(metres) < SMALL_SIZE_LIMIT else "ft"
        return f"{metres / unit_factor(unit):.3g} {unit}"  # as many digits as the note had

    return _NOTE_LENGTH.sub(imperial, note)
