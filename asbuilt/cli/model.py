"""``asbuilt model SCAN --out FILE [--out FILE ...]``: scan to as-built CAD in one run.

Fits every object, merges pipes into spools with fittings, checks the compliance rules, then
writes every ``--out`` (format by suffix, :data:`asbuilt.export.SUFFIXES`), all or nothing. Progress goes to standard error; one summary line per file and the findings
counts go to standard output.

An object whose fit is refused is left out of the outputs and said on standard error (one line
each, also with ``--quiet``); the outputs are written and the exit code is 1. When no object can
be fitted nothing is written (exit 2).

``SCAN`` may be ``-``: the scan is read from standard input (:mod:`asbuilt.cli._input`); its
errors name ``<stdin>`` where a file's name the file.
"""

from __future__ import annotations

import argparse

from asbuilt.cli._args import positive_number
from asbuilt.cli._input import SCAN_HELP
from asbuilt.cli._text import plural
from asbuilt.export import SUFFIXES

__all__ = ["register", "run"]

#: The registry's suffixes (importing asbuilt.export does not load CadQuery).
_SUFFIXES = " ".join(SUFFIXES)


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``model`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "model",
        help="fit, merge and check a scan, then write CAD and piping files (STEP, glTF, DXF, ...)",
        description="Turn an asbuilt-scan file into an as-built model: fit every object, merge "
        "pipes into spools with standard fittings, check the compliance rules, and write each "
        f"--out file in the format its suffix names ({_SUFFIXES}). Either every file is "
        "written or none is.",
        epilog="Example: asbuilt model samples/spool.json --out spool.step --out spool.glb "
        "--out spool.dxf --out spool.json",
    )
    parser.add_argument("scan", metavar="SCAN", help=f"the asbuilt-scan JSON file ({SCAN_HELP})")
    parser.add_argument(
        "--out",
        "-o",
        metavar="FILE",
        action="append",
        required=True,
        help=f"an output file; give --out several times for several formats ({_SUFFIXES})",
    )
    parser.add_argument(
        "--plate-thickness",
        metavar="MM",
        type=positive_number("thickness in mm"),
        default=None,
        help="thickness of the plates made from fitted planes, in millimetres (default 10)",
    )
    parser.add_argument(
        "--catalog",
        metavar="NAME|FILE",
        default=None,
        help="pipe catalog for snapping sizes (default asme-b36.10m; see 'asbuilt catalog')",
    )
    parser.add_argument(
        "--schedule",
        metavar="S",
        default=None,
        help="pipe wall schedule, e.g. STD, 40, 10S: pipes become hollow (default: the "
        "catalog's default schedule)",
    )
    parser.add_argument(
        "--elbow-radius",
        choices=("long", "short"),
        default="long",
        help="ASME B16.9 elbow radius for the fittings joining pipes (default long)",
    )
    parser.add_argument(
        "--rules", metavar="FILE", default=None, help="compliance rules file (TOML)"
    )
    parser.add_argument(
        "--design", metavar="FILE", default=None, help="design file to compare the model with"
    )
    parser.add_argument(
        "--no-merge",
        action="store_true",
        help="keep one component per fitted object (no pipe snapping, spools or fittings)",
    )
    parser.add_argument("--no-check", action="store_true", help="skip the compliance rules")
    parser.add_argument(
        "--step-schema",
        choices=("AP214", "AP242"),
        default="AP214",
        help="STEP application protocol (default AP214)",
    )
    parser.add_argument(
        "--report",
        metavar="FILE",
        action="append",
        default=None,
        help="also write a QA report (.html, .csv or .json by suffix), published with the --out "
        "files (all or nothing); give --report several times for several reports",
    )
    parser.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")
    parser.set_defaults(handler=run)
    return parser


def _size(n: int) -> str:
    for unit in ("B", "kB", "MB", "GB"):
        if n < 1000 or unit == "GB":
            return f"{n} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n} B"


def run(args: argparse.Namespace) -> int:
    """Build the model and write the outputs; return 0, or 1 when an object's fit was refused
    (left out of the outputs). Bad input raises AsbuiltError (exit 2)."""
    import sys
    from pathlib import Path

    from rich.console import Console

    from asbuilt.atomic import AtomicBatch, check_target
    from asbuilt.cli._args import refuse_standard_output
    from asbuilt.cli._input import input_files, scan_input
    from asbuilt.cli._models import say_refused
    from asbuilt.cli._progress import stage_progress
    from asbuilt.errors import ExportError
    from asbuilt.export import export_models, exporter_for
    from asbuilt.pipeline import build_model

    inputs = input_files(args.scan, args.rules, args.design, args.catalog)
    outputs = [Path(p) for p in args.out]
    reports = [Path(p) for p in args.report or ()]
    for name in args.out:
        # The name as typed first: a directory or a trailing slash is said as such (Path drops
        # the slash and the suffix test would call it a file without a suffix), then an unknown
        # suffix; all before any work.
        refuse_standard_output(name, "--out", "a CAD model", "model.step")
        check_target(name, "--out", inputs=inputs)
        exporter_for(name)
    seen = {path.resolve() for path in outputs}
    for name, report_path in zip(args.report or (), reports):
        from asbuilt.report import report_format_for

        refuse_standard_output(name, "--report", "a report", "report.html")
        check_target(
            name, "--report", inputs=inputs, example=f"report{report_path.suffix or '.html'}"
        )
        report_format_for(name)  # an unknown report suffix fails before any work too
        if report_path.resolve() in seen:
            raise ExportError(
                "this report is also an --out file or another --report; name them apart",
                source=str(report_path),
            )
        seen.add(report_path.resolve())

    source = scan_input(args.scan)
    scan = source.load_scan()
    err = Console(file=sys.stderr, markup=False)
    with stage_progress(err, quiet=args.quiet) as bar:
        task = bar.add_task("", total=len(scan.objects), stage="fitting")
        model = build_model(
            scan,
            catalog=args.catalog,
            schedule=args.schedule,
            elbow_radius=args.elbow_radius,
            rules=args.rules,
            design=args.design,
            merge=not args.no_merge,
            check=not args.no_check,
            progress=lambda done, total, oid: bar.update(task, completed=done, description=oid),
        )
        bar.update(
            task,
            completed=0,
            total=len(model.components),
            description="loading the CAD kernel",
            stage="solids",
        )

        def progress(stage: str, done: int, total: int) -> None:
            label = "solids" if stage == "solids" else "writing"
            bar.update(task, completed=done, total=total, stage=label, description="")

        thickness = None if args.plate_thickness is None else args.plate_thickness / 1000.0
        # The model files and the reports are published together, or none of them: a report
        # that fails (a full disk) or a SIGTERM before the end leaves no new file.
        with AtomicBatch() as batch:
            results = export_models(
                model,
                outputs,
                plate_thickness=thickness,
                step_schema=args.step_schema,
                progress=progress,
                batch=batch,
            )
            if reports:
                from asbuilt.report import write_reports
                from asbuilt.report.html import StagedGltf

                # An HTML report can embed a 3-D view from a glTF written in this run.
                views = [r.path for r in results if r.path.suffix.lower() in (".glb", ".gltf")]
                view = {}
                if views:
                    view["gltf"] = StagedGltf(batch.staged_for(views[0]), views[0])
                write_reports(model, reports, batch=batch, **view)

    status = 1 if say_refused(err, model, source.name) else 0  # written, but without them
    if args.quiet:
        return status
    out = Console(file=sys.stdout, highlight=False, soft_wrap=True, markup=False)
    for result in results:
        out.print(
            f"wrote {result.path} ({result.name}, {_size(result.size)}, "
            f"{plural(result.objects, 'object')})"
        )
    for report_path in reports:
        out.print(f"wrote {report_path} (report)")
    counts = {severity: 0 for severity in ("error", "warning", "info")}
    for finding in model.findings:
        counts[finding.severity] += 1
    spools = f", {plural(len(model.spools), 'spool')}"
    out.print(
        f"{plural(len(model.components), 'component')}{spools if model.spools else ''}; "
        f"findings: {plural(counts['error'], 'error')}, {plural(counts['warning'], 'warning')}, "
        f"{counts['info']} info"
    )
    return status
