"""``asbuilt fit SCAN [--json] [--units U] [--output FILE]``: fit every object and show the result.

A table by default (id, kind, main dimensions, centre, RMS, inliers, standard errors) and each
fit's notes under it; ``--json``
prints the shape documented in :mod:`asbuilt.fit.output`, lengths in the scan's units unless
``--units`` says otherwise; ``--output FILE`` writes that JSON atomically to FILE instead of
standard output (``--output -``: standard output). ``SCAN`` may be ``-``: the scan is read from
standard input (``cat scan.json | asbuilt fit - --json``; :mod:`asbuilt.cli._input`). Progress goes to standard error.

An object whose fit is refused does not stop the others: the table is followed by one line per
refused object (its id, kind and the fit's reason), ``--json`` lists it among the objects, in
the scan's order, as ``{"id", "kind", "error"}``, and the exit code is 1. When no object can be
fitted, the error is bad input (exit 2), one line per object.
"""

from __future__ import annotations

import argparse

from asbuilt.cli._input import SCAN_HELP
from asbuilt.cli._text import plural
from asbuilt.units import UNITS

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``fit`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "fit",
        help="fit a primitive to every object of a scan and show the dimensions",
        description="Fit a cylinder, cuboid, sphere, plane or hull (or, for kind auto, the likeliest of "
        "them) to every object of an "
        "asbuilt-scan file (docs/scan-format.md) and show the result.",
        epilog="Example: asbuilt fit samples/spool.json --json --units mm",
    )
    parser.add_argument("scan", metavar="SCAN", help=f"the asbuilt-scan JSON file ({SCAN_HELP})")
    parser.add_argument(
        "--json", action="store_true", help="print the results as JSON instead of a table"
    )
    parser.add_argument(
        "--units",
        choices=tuple(UNITS),
        default=None,
        help="length unit of the output (default: the scan's own unit)",
    )
    parser.add_argument(
        "--output",
        "-o",
        metavar="FILE",
        default=None,
        help="write the JSON to FILE (atomically) instead of standard output ('-': standard "
        "output)",
    )
    parser.set_defaults(handler=run)
    return parser


def _report_dict(report, units: str) -> dict:
    """``fit_report_to_dict`` with the refused objects among the fitted ones, in the scan's
    order, each as ``{"id", "kind", "error"}`` (``error``: the fit's one-line reason), and each
    view fused into another object (:mod:`asbuilt.fit._stations`) as ``{"id", "kind",
    "fused_into"}``."""
    from asbuilt.fit.output import fit_report_to_dict

    data = fit_report_to_dict(report, units)
    fused = {
        item.object.extra["fused_with"]: item.object.id
        for item in report.fits
        if "fused_with" in item.object.extra
    }
    if not report.failures and not fused:
        return data
    entries = {item.object.id: entry for item, entry in zip(report.fits, data["objects"])}
    for failure in report.failures:
        obj = failure.object
        entries[obj.id] = {"id": obj.id, "kind": obj.kind, "error": failure.message}
    for obj in report.scan.objects:
        if obj.id in fused:  # a second station's view, fitted as part of another object
            entries[obj.id] = {"id": obj.id, "kind": obj.kind, "fused_into": fused[obj.id]}
    data["objects"] = [entries[obj.id] for obj in report.scan.objects if obj.id in entries]
    return data


def run(args: argparse.Namespace) -> int:
    """Load, fit, print; return the exit code: 0, or 1 when an object's fit was refused. Bad
    input (and a scan of which no object can be fitted) raises an AsbuiltError (exit 2)."""
    import json
    import os
    import sys

    from rich.console import Console
    from rich.table import Table

    from asbuilt.atomic import atomic_write, check_target
    from asbuilt.cli._input import input_files, scan_input
    from asbuilt.cli._progress import stage_progress
    from asbuilt.fit import fit
    from asbuilt.fit.output import TABLE_COLUMNS, fit_table_notes, fit_table_rows

    if args.output == "-":  # as elsewhere: '-' is standard output, not a file named '-'
        args.output, args.json = None, True
    if args.output is not None:
        # before any work; a directory is refused with a JSON file name to add
        check_target(args.output, "--output", inputs=input_files(args.scan), example="fit.json")
    source = scan_input(args.scan)
    scan = source.load_scan()
    err = Console(file=sys.stderr, markup=False)
    with stage_progress(err) as bar:
        task = bar.add_task("", total=len(scan.objects), stage="fitting")
        report = fit(
            scan,
            progress=lambda done, total, oid: bar.update(task, completed=done, description=oid),
        )

    status = 1 if report.failures else 0  # outputs are written, but objects are missing
    units = args.units or scan.units
    if args.json or args.output is not None:
        # To a file: UTF-8. To standard output: as it is when its encoding can write it, else
        # JSON's own \u escapes (a backslash escape of the stream would not be JSON beyond U+FFFF).
        text = json.dumps(_report_dict(report, units), indent=2, ensure_ascii=False) + "\n"
        if args.output is None and not _encodable(text, sys.stdout):
            text = json.dumps(_report_dict(report, units), indent=2) + "\n"
        if args.output is not None:
            with atomic_write(args.output, "w") as handle:
                handle.write(text)
            err.print(f"wrote {args.output}", highlight=False)
        else:
            sys.stdout.write(text)
        if args.json:
            return status

    title = scan.name or source.name
    heading = f"{title}: {plural(len(report), 'object')}"
    if report.failures:
        heading = f"{title}: {len(report)} fitted, {len(report.failures)} refused"
    table = Table(title=heading)
    for column in TABLE_COLUMNS:
        table.add_column(column, no_wrap=column in ("id", "kind", "inliers"))
    for row in fit_table_rows(report, units):
        table.add_row(*row)
    out = Console(file=sys.stdout, highlight=False, markup=False)
    if not out.is_terminal and "COLUMNS" not in os.environ:
        out.width = 160  # piped to a file or pager: room for one line per object
    out.print(table)
    notes = fit_table_notes(report, units)
    if notes:
        # A grid, so that a long note wraps under itself, not under the ids.
        grid = Table.grid(padding=(0, 2))
        grid.add_column(no_wrap=True)
        grid.add_column()
        for object_id, note in notes:
            grid.add_row(object_id, note)
        out.print("notes:")
        out.print(grid)
    if report.failures:
        grid = Table.grid(padding=(0, 2))
        grid.add_column(no_wrap=True)
        grid.add_column()
        for failure in report.failures:
            grid.add_row(f"{failure.object.id} ({failure.object.kind})", failure.message)
        out.print("refused (not fitted; rescan or check these objects):")
        out.print(grid)
    return status


def _encodable(text: str, stream) -> bool:
    """Whether ``stream``'s encoding can write every character of ``text``."""
    encoding = getattr(stream, "encoding", None) or "utf-8"
    try:
        text.encode(encoding)
    except (UnicodeEncodeError, LookupError):
        return False
    return True
