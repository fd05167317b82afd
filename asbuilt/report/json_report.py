"""The JSON report: the same data as the HTML and CSV reports, for programs.

Top level (``"format": "asbuilt-report"``, ``"version": 1``, ``"units": "m"``): ``title``,
``source``, ``scan_date``, ``generated``, ``catalog``, ``catalog_title``, ``display_units``,
``counts``, ``findings_summary`` (by severity), ``takeoff`` (``spools``, ``pipes``,
``fittings``, ``solids``, ``totals``), ``components`` (the CSV rows, same names without unit suffixes: lengths
m, areas m2, volumes m3, weights kg), ``quality`` (per fitted object; residuals in metres) and
``findings`` (as in the ``asbuilt-model`` document). Non-finite numbers are written as null. The JSON Schema is :func:`report_schema`.
"""

from __future__ import annotations

import dataclasses
import json

from asbuilt.atomic import atomic_write
from asbuilt.export.model_json import _finding, _json

from .data import ReportData
from .takeoff import FOOT

__all__ = ["FORMAT", "VERSION", "report_schema", "report_document", "dumps_report", "write_json"]

FORMAT = "asbuilt-report"
VERSION = 1


def report_schema() -> dict:
    """The JSON Schema (draft 2020-12) of the report, shipped as
    ``asbuilt/schemas/report.schema.json``."""
    from importlib import resources

    text = (resources.files("asbuilt") / "schemas" / "report.schema.json").read_text("utf-8")
    return json.loads(text)


def _plain(item) -> dict:
    return {f.name: getattr(item, f.name) for f in dataclasses.fields(item)}


def _quality(q) -> dict:
    entry = _plain(q)
    entry["residuals"] = q.residuals
    entry["inlier_mask"] = q.inlier_mask
    return entry


def report_document(data: ReportData) -> dict:
    """The report as plain JSON-ready data (see the module docstring)."""
    t = data.takeoff
    document = {
        "format": FORMAT,
        "version": VERSION,
        "units": "m",
        "title": data.title,
        "source": data.source,
        "scan_date": data.scan_date,
        "generated": data.generated,
        "catalog": data.catalog,
        "catalog_title": data.catalog_title,
        "display_units": data.units,
        "counts": dict(data.counts),
        "findings_summary": dict(data.severities),
        "takeoff": {
            "spools": [_plain(sp) for sp in t.spools],
            "pipes": [_plain(p) for p in t.pipes],
            "fittings": [_plain(f) for f in t.fittings],
            "solids": [_plain(s) for s in t.solids],
            "totals": {
                "pipe_length": t.pipe_length,
                "pipe_length_ft": t.pipe_length / FOOT,
                "pipe_weight": t.pipe_weight,
                "density": t.density,
                "material": t.material,
                "volumes": dict(t.volumes),
                "areas": dict(t.areas),
            },
        },
        "components": [_plain(row) for row in t.rows],
        "quality": [_quality(q) for q in data.quality],
        "findings": [_finding(f) for f in data.findings],
    }
    return _json(document)


def dumps_report(data: ReportData) -> str:
    """The JSON report as text (2-space indent)."""
    return json.dumps(report_document(data), indent=2, allow_nan=False) + "\n"


def write_json(data: ReportData, path) -> None:
    """Write the JSON report to ``path`` atomically."""
    text = dumps_report(data)
    with atomic_write(path, "w", encoding="utf-8") as handle:
        handle.write(text)
