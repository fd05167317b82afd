"""The scan: the ``asbuilt-scan`` JSON file format, its validating loader and its JSON Schema.

>>> from asbuilt.scan import load_scan        # doctest: +SKIP
>>> scan = load_scan("samples/spool.json")    # every length in metres; scan.units is the file's

See ``docs/scan-format.md`` for the format and its error messages.
"""

from __future__ import annotations

from asbuilt.scan.load import MAX_FILE_BYTES, MAX_POINTS, load_scan, loads_scan
from asbuilt.scan.model import KINDS, Scan, ScanObject, Sensor

__all__ = [
    "KINDS",
    "MAX_FILE_BYTES",
    "MAX_POINTS",
    "Scan",
    "ScanObject",
    "Sensor",
    "load_scan",
    "loads_scan",
    "scan_schema",
]


def scan_schema() -> dict:
    """The Draft 2020-12 JSON Schema of an ``asbuilt-scan`` version 1 document.

    Built by :func:`asbuilt.scan.schema.scan_schema` (imported here on first use, so that
    ``python -m asbuilt.scan.schema`` runs that module only once).
    """
    from asbuilt.scan.schema import scan_schema as build

    return build()
