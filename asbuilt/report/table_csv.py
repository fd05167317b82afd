"""The CSV take-off: one row per component, ready for a spreadsheet or a quantity tracking system.

Columns (header row first, in this order): ``id``, ``type``, ``spool``, ``label``, ``nominal``
(the catalog's designation, e.g. ``4``), ``size`` (display label, e.g. ``NPS 4``; ``NPS 6 x 4``
for a reducer), ``schedule``, ``length_m`` and ``length_ft`` (straight length of pipes and
cylinders, longest edge of cuboids; empty for fittings), ``quantity_unit`` (``m``, ``ea``,
``m3`` or ``m2``), ``quantity``, ``weight_kg`` (pipes with a known wall), ``surface_area_m2``,
``findings`` (finding codes, worst first, separated by spaces) and ``severity`` (the worst).
Empty cells mean "not applicable or unknown". Decimal point, comma separated, UTF-8, CRLF line
ends (RFC 4180, Python's ``csv`` excel dialect).
"""

from __future__ import annotations

import csv as _csv
import io

from asbuilt.atomic import atomic_write

from .data import ReportData
from .takeoff import FOOT

__all__ = ["COLUMNS", "csv_text", "write_csv"]

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
)

_DECIMALS = {"m": 3, "m2": 3, "m3": 4, "ea": 0}


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
                row.id,
                row.type,
                row.spool or "",
                row.label or "",
                row.nominal or "",
                row.size or "",
                row.schedule or "",
                _number(row.length, 3),
                _number(None if row.length is None else row.length / FOOT, 3),
                row.quantity_unit,
                _number(row.quantity, _DECIMALS[row.quantity_unit]),
                _number(row.weight, 2),
                _number(row.area, 3),
                " ".join(row.findings),
                row.severity or "",
            ]
        )
    return buffer.getvalue()


def write_csv(data: ReportData, path) -> None:
    """Write the CSV take-off to ``path`` atomically."""
    text = csv_text(data)
    with atomic_write(path, "w", encoding="utf-8") as handle:
        handle.write(text)
