"""The CSV take-off: one row per component, ready for a spreadsheet or a quantity tracking system.

Columns (header row first, in this order): ``id``, ``type``, ``spool``, ``label``, ``nominal``
(the catalog's designation, e.g. ``4``), ``size`` (display label, e.g. ``NPS 4``; ``NPS 6 x 4``
for a reducer), ``schedule``, ``length_m`` and ``length_ft`` (straight length of pipes and
cylinders, longest edge of cuboids; empty for fittings), ``quantity_unit`` (``m``, ``ea``,
``m3`` or ``m2``), ``quantity``, ``weight_kg`` (pipes with a known wall), ``surface_area_m2``,
``findings`` (finding codes, worst first, separated by spaces), ``severity`` (the worst) and
``insulation_mm`` (the thickness of lagging around it in millimetres, 1 decimal; 0 when bare).
Empty cells mean "not applicable or unknown". Decimal point, comma separated, CRLF line ends
(RFC 4180, Python's ``csv`` excel dialect).

Spreadsheet safety: a text cell (id, label, spool, size...) that begins with ``=``, ``+``,
``-``, ``@``, a tab or a carriage return would be run as a formula by a spreadsheet (CSV
injection: ``=HYPERLINK(...)`` as a label), so it is written with a leading ``'`` (OWASP's
advice; spreadsheets show the text, not the quote). Numbers are written as they are. The file is
UTF-8 with a byte order mark, so that Excel shows non-ASCII labels (``Rohr-Ä1``) instead of
reading the file in the Windows code page; read it with ``encoding="utf-8-sig"``.
"""

from __future__ import annotations

import csv as _csv
import io

from asbuilt.atomic import atomic_write

from .data import ReportData
from .takeoff import FOOT

__all__ = ["COLUMNS", "FORMULA_STARTS", "csv_text", "text_cell", "write_csv"]

#: The CSV header, in order.
COLUMNS = (
    "id",
    "type",
    "spool",
    "label",
    "nominal",
    "size",
    "schedule",
    "length_m",
    "length_ft",
    "quantity_unit",
    "quantity",
    "weight_kg",
    "surface_area_m2",
    "findings",
    "severity",
    "insulation_mm",
)

_DECIMALS = {"m": 3, "m2": 3, "m3": 4, "ea": 0}

#: First characters that make a spreadsheet read a cell as a formula (OWASP, CSV injection).
FORMULA_STARTS = ("=", "+", "-", "@", "\t", "\r")


def text_cell(value: str | None) -> str:
    """A text cell safe to open in a spreadsheet: ``""`` for None, a leading ``'`` when it
    begins with one of :data:`FORMULA_STARTS`, else the text as it is."""
    if not value:
        return ""
    return "'" + value if value.startswith(FORMULA_STARTS) else value


def _number(value: float | None, decimals: int) -> str:
    if value is None:
        return ""
    return f"{value:.{decimals}f}"


def csv_text(data: ReportData) -> str:
    """The CSV document (see the module docstring for the columns and units)."""
    buffer = io.StringIO()
    writer = _csv.writer(buffer)
    writer.writerow(COLUMNS)
    for row in data.takeoff.rows:
        writer.writerow(
            [
                text_cell(row.id),
                text_cell(row.type),
                text_cell(row.spool),
                text_cell(row.label),
                text_cell(row.nominal),
                text_cell(row.size),
                text_cell(row.schedule),
                _number(row.length, 3),
                _number(None if row.length is None else row.length / FOOT, 3),
                row.quantity_unit,
                _number(row.quantity, _DECIMALS[row.quantity_unit]),
                _number(row.weight, 2),
                _number(row.area, 3),
                text_cell(" ".join(row.findings)),
                text_cell(row.severity),
                _number(row.insulation * 1000.0, 1),
            ]
        )
    return buffer.getvalue()


def write_csv(data: ReportData, path) -> None:
    """Write the CSV take-off to ``path`` atomically (UTF-8 with a byte order mark)."""
    text = csv_text(data)
    with atomic_write(path, "w", encoding="utf-8-sig") as handle:
        handle.write(text)
