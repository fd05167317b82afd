"""Length units: converted once, at the edges (scan loading and output). Metres inside."""

from __future__ import annotations

__all__ = ["UNITS", "to_metres", "from_metres", "unit_factor"]

#: Metres per unit, for every unit a scan or an output may use.
UNITS: dict[str, float] = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "ft": 0.3048}


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
