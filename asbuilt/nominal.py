"""Nominal pipe sizes as people write them: an operator's hint (``4"``, ``DN100``, ``1½"``,
``4" sch 40``) parsed to a system and a number, and looked up in a catalog by that system.

The catalog (:mod:`asbuilt.catalog`, which re-exports these names) reads its ``nominal`` and
``nps`` cells with :func:`parse_number`; :meth:`asbuilt.catalog.Catalog.match_hint` finds the
size a hint names with :func:`size_by_system`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

__all__ = ["NominalHint", "parse_nominal", "parse_number", "size_by_system"]


@dataclass(frozen=True)
class NominalHint:
    """An operator's size hint parsed: ``system`` is ``"nps"``, ``"dn"`` or ``"number"``
    (a bare number, read in the catalog's designation first), ``value`` the number."""

    system: str
    value: float
    text: str


#: Unicode fraction glyphs operators may type (``1½"``; ``⅝"`` is a copper tube size).
_VULGAR = {
    "\u00bd": "1/2",
    "\u00bc": "1/4",
    "\u00be": "3/4",
    "\u215b": "1/8",
    "\u215c": "3/8",
    "\u215d": "5/8",
    "\u215e": "7/8",
}

#: Inch marks word processors and spreadsheets put in place of ``"``: right and left double
#: quotation marks, the double prime, and two single quotes or primes.
_INCH_MARKS = ("\u201d", "\u201c", "\u2033", "''", "\u2032\u2032", "\u2019\u2019")

_FRACTION = re.compile(r"^(?:(\d+)[\s-]+)?(\d+)/(\d+)$")


def parse_number(text: str) -> float | None:
    """A positive size number: ``4``, ``1.5``, ``3/4``, ``1 1/2``, ``1-1/2``; else None."""
    text = text.strip()
    match = _FRACTION.match(text)
    if match:
        whole = int(match.group(1) or 0)
        den = int(match.group(3))
        if den == 0:
            return None
        return whole + int(match.group(2)) / den
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) and value > 0 else None


#: A schedule, weight class or pressure rating written after a size (``4" sch 40``, ``4" STD``,
#: ``DN100 PN16``, ``4" 150#``): the size is read and the rest is left to the catalog.
_TRAILING_RATING = re.compile(
    r"\s*(?:,\s*)?(?:sch(?:edule)?\.?\s*\w+|std|xs|xxs|pn\s*\d+|class\s*\d+|\d+\s*#|"
    r"\d+\s*lbs?)$"
)


def size_by_system(hint: NominalHint, designation: str | None, by_nps, by_dn):
    """The size ``hint`` names, looked up by ``by_nps(value)`` or ``by_dn(value)`` (each the
    size or None): by its own system when it says one (``6"``, ``DN150``), else (a bare
    number) in the catalog's ``designation`` first, then the other."""
    if hint.system == "nps":
        return by_nps(hint.value)
    if hint.system == "dn":
        return by_dn(hint.value)
    dn_first = (designation or "").upper() == "DN"
    first, second = (by_dn, by_nps) if dn_first else (by_nps, by_dn)
    return first(hint.value) or second(hint.value)


def parse_nominal(text: str | None) -> NominalHint | None:
    """Parse an operator's nominal size hint.

    Understood forms: ``4"``, ``4 in``, ``4in``, ``4 in.``, ``4 inch``, ``4-inch``, ``NPS 4``,
    ``NPS-4``, ``NPS 4"``, ``1 1/2"``, ``1-1/2"``, ``1½"``, ``3/4``, ``DN100``, ``DN 100``,
    ``DN-100``, the JIS designations ``100A`` (millimetres, as DN) and ``4B`` (inches), and a
    bare number such as ``4`` or ``100`` (read as the catalog's own designation first: NPS for
    ASME catalogs, DN for EN 10220). Typographic inch marks (``4″``, ``4“``), the fraction slash
    (``1⁄2"``) and the fraction glyphs ``⅛ ¼ ⅜ ½ ⅝ ¾ ⅞`` are read as typed on a keyboard. A
    schedule, weight class or rating after the size (``4" sch 40``, ``4" STD``, ``DN100 PN16``,
    ``6" 150#``) is ignored. A size of zero (``DN 0``, ``0A``) and anything else give None.
    """
    if text is None:
        return None
    raw = str(text).strip()
    lowered = raw.lower().replace("\u2044", "/")  # the fraction slash of "1⁄2"
    for mark in _INCH_MARKS:
        lowered = lowered.replace(mark, '"')
    for glyph, text in _VULGAR.items():
        lowered = lowered.replace(glyph, f" {text}")
    lowered = " ".join(lowered.split())
    for _ in range(2):  # "4\" sch 40 150#": a schedule and a rating
        lowered = _TRAILING_RATING.sub("", lowered).strip()
    match = re.match(r"^dn\s*-?\s*(\d+(?:\.\d+)?)$", lowered) or re.match(r"^(\d+)\s*a$", lowered)
    if match:
        value = float(match.group(1))  # "DN 0" and "0A" name no size
        return NominalHint("dn", value, raw) if value > 0 else None
    # "NPS 4", and "NPS 4\"" or "NPS 1-1/2 in" with the inch unit said twice
    match = re.match(r'^nps\s*-?\s*(.+?)(?:\s*-?\s*(?:"|in\.?|inch|inches))?$', lowered)
    if match:
        value = parse_number(match.group(1))
        return NominalHint("nps", value, raw) if value else None
    match = re.match(r'^(.+?)\s*-?\s*(?:"|in\.?|inch|inches|b)$', lowered)
    if match:
        value = parse_number(match.group(1))
        return NominalHint("nps", value, raw) if value else None
    value = parse_number(lowered)
    return NominalHint("number", value, raw) if value else None
