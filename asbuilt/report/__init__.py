"""QA reports of an as-built model: HTML (with pictures), CSV and JSON, chosen by suffix.

``write_report(model, path)`` gathers the report's content once (:func:`report_data`: header,
quantity take-off, fit quality, findings) and writes it atomically in the format the suffix
names (:data:`SUFFIXES`). ``write_reports(model, paths)`` writes several, all or nothing.
Importing this package is light: matplotlib is imported only to draw the HTML pictures.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterable
from dataclasses import dataclass
from importlib import import_module
from pathlib import Path

from asbuilt.atomic import AtomicBatch
from asbuilt.errors import ExportError, UnknownFormatError

from .data import FitQuality, ReportData, fit_quality, report_data
from .takeoff import TakeOff, pipe_weight_per_metre, take_off

__all__ = [
    "SUFFIXES",
    "ReportFormat",
    "report_format_for",
    "write_report",
    "write_reports",
    "report_data",
    "ReportData",
    "FitQuality",
    "fit_quality",
    "take_off",
    "TakeOff",
    "pipe_weight_per_metre",
]


@dataclass(frozen=True)
class ReportFormat:
    """One report format: ``suffix``, ``name``, ``description`` and its writer
    (``module.function(data, path, **options)``), and the options it accepts."""

    suffix: str
    name: str
    description: str
    module: str
    function: str
    options: tuple[str, ...] = ()

    def write(self, data: ReportData, path, **options) -> None:
        writer = getattr(import_module(f"{__name__}.{self.module}"), self.function)
        writer(data, path, **{k: v for k, v in options.items() if k in self.options})


_FORMATS = (
    ReportFormat(
        ".html",
        "HTML",
        "self-contained QA report with pictures, take-off, fit quality and findings",
        "html",
        "write_html",
        ("figure_format", "label_limit", "gltf"),
    ),
    ReportFormat(
        ".htm",
        "HTML",
        "self-contained QA report with pictures, take-off, fit quality and findings",
        "html",
        "write_html",
        ("figure_format", "label_limit", "gltf"),
    ),
    ReportFormat(
        ".csv",
        "CSV",
        "one row per component (quantities, sizes, findings)",
        "table_csv",
        "write_csv",
    ),
    ReportFormat(
        ".json",
        "JSON",
        "the report's data (asbuilt-report document, metres)",
        "json_report",
        "write_json",
    ),
)

#: Report suffixes mapped to their format.
SUFFIXES: dict[str, ReportFormat] = {f.suffix: f for f in _FORMATS}

_OPTIONS = {"density", "figure_format", "label_limit", "gltf", "generated", "catalog"}


def report_format_for(path) -> ReportFormat:
    """The report format for ``path``'s suffix (case-insensitive).

    Raises
    ------
    UnknownFormatError
        Naming the file and the known suffixes.
    """
    suffix = Path(path).suffix.lower()
    try:
        return SUFFIXES[suffix]
    except KeyError:
        what = f"unknown report format {suffix!r}" if suffix else "the report has no suffix"
        raise UnknownFormatError(
            f"{what}; use one of {', '.join(SUFFIXES)}", source=str(path)
        ) from None


def _file_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _check_options(options: dict) -> None:
    unknown = set(options) - _OPTIONS
    if unknown:
        raise TypeError(f"unknown report option(s): {', '.join(sorted(unknown))}")


def write_reports(model, paths: Iterable, *, batch: AtomicBatch | None = None, **options):
    """Write one report per path (format by suffix), all or nothing.

    Parameters
    ----------
    model : asbuilt.model.Model
        Metres; its findings as the rules left them.
    paths : iterable of str or Path
        ``.html``/``.htm``, ``.csv`` or ``.json``.
    batch : asbuilt.atomic.AtomicBatch, optional
        Stage the reports in this batch and leave publishing them to its owner (with the model
        files of the same run: all or nothing together).
    **options
        ``density`` (kg/m3, pipe weights; default from the catalog's material),
        ``figure_format`` (``"svg"`` or ``"png"``, HTML), ``label_limit`` (HTML pictures),
        ``gltf`` (a glTF/GLB file of the model for the HTML's optional 3-D view, or a
        :class:`~asbuilt.report.html.StagedGltf` for one staged in the same batch),
        ``generated`` (datetime stamp, default now), ``catalog`` (the Catalog the model was
        built with; default the model's ``catalog_file``, else the shipped catalog it names).

    Returns
    -------
    list of Path
        The files written, in order.

    Raises
    ------
    UnknownFormatError, ExportError
        Before any file is created or replaced.
    """
    _check_options(options)
    targets = [Path(p) for p in paths]
    formats = [report_format_for(p) for p in targets]
    seen: set[Path] = set()
    for target in targets:
        if target.resolve() in seen:
            raise ExportError(
                "this report is given twice; name each output once", source=str(target)
            )
        seen.add(target.resolve())
    data = report_data(
        model,
        density=options.get("density"),
        generated=options.get("generated"),
        catalog=options.get("catalog"),
    )
    with contextlib.nullcontext(batch) if batch is not None else AtomicBatch() as batch:
        for fmt, target in zip(formats, targets):
            temp = batch.stage(target)
            try:
                fmt.write(data, temp, **options)
            except OSError as exc:
                raise ExportError(
                    f"cannot write the report ({exc.strerror or exc})", source=str(target)
                ) from None
            os.chmod(temp, _file_mode())
    return targets


def write_report(model, path, **options) -> Path:
    """Write one report to ``path``, format by suffix (``.html``, ``.csv``, ``.json``),
    atomically. See :func:`write_reports` for the options."""
    return write_reports(model, [path], **options)[0]
