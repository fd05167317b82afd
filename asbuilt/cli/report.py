"""``asbuilt report SCAN --out qa.html [--out qa.csv] [--out qa.json]``: QA reports.

Fits, merges and checks the scan as ``asbuilt model`` does (or reads an ``asbuilt-model`` JSON
document with the findings it records, checked again only when ``--rules`` or ``--design`` is
given), then writes every ``--out`` in the format its suffix names: a
self-contained HTML page with pictures, take-off, fit quality and findings; a CSV with one row
per component; or the same data as JSON. All or nothing. One summary line per file and the
findings counts go to standard output; the exit code is 0 (findings are in the report, not in
the exit code: use ``asbuilt check`` for a QA gate), except 1 when an object's fit was refused:
the reports are written without it, its finding says why, and standard error says so.
``SCAN`` may be ``-``: the scan or model document is read from standard input
(:mod:`asbuilt.cli._input`), named ``<stdin>`` in errors.
"""

from __future__ import annotations

import argparse

from asbuilt.cli._args import positive_number
from asbuilt.cli._input import SCAN_HELP
from asbuilt.cli._text import plural

__all__ = ["register", "run"]

_SUFFIXES = ".html .csv .json"


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError("must be 0 or more")
    return value


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``report`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "report",
        help="write QA reports: HTML with pictures, CSV take-off, JSON",
        description="Build the as-built model of a scan (fit, merge, check) or read an "
        "asbuilt-model JSON document, and write QA reports for quantity tracking: "
        "what was built, how much of it, and how sure the model is. The format follows each "
        f"--out suffix ({_SUFFIXES}); either every file is written or none is.",
        epilog="Example: asbuilt report samples/spool.json --out qa.html --out qa.csv",
    )
    parser.add_argument(
        "scan",
        metavar="SCAN",
        help=f"an asbuilt-scan JSON file (or an asbuilt-model document; {SCAN_HELP})",
    )
    parser.add_argument(
        "--out",
        "-o",
        metavar="FILE",
        action="append",
        required=True,
        help=f"a report file; give --out several times for several formats ({_SUFFIXES})",
    )
    parser.add_argument(
        "--catalog",
        metavar="NAME|FILE",
        default=None,
        help="pipe catalog for sizes (default asme-b36.10m; see 'asbuilt catalog')",
    )
    parser.add_argument(
        "--schedule",
        metavar="S",
        default=None,
        help="pipe wall schedule, e.g. STD, 40, 10S (default: the catalog's default); "
        "pipe weights need it",
    )
    parser.add_argument("--rules", metavar="FILE", default=None, help="compliance rules (TOML)")
    parser.add_argument(
        "--design", metavar="FILE", default=None, help="design file to compare the model with"
    )
    parser.add_argument(
        "--no-merge", action="store_true", help="one component per fitted object, no spools"
    )
    parser.add_argument("--no-check", action="store_true", help="skip the compliance rules")
    parser.add_argument(
        "--density",
        metavar="KG_M3",
        type=positive_number("density in kg/m3 (e.g. 7850)"),
        default=None,
        help="pipe material density for weights (default from the catalog's material: "
        "7850 carbon steel, 7900 stainless)",
    )
    parser.add_argument(
        "--figures",
        choices=("svg", "png"),
        default="svg",
        help="HTML pictures as inline SVG (default) or embedded PNG",
    )
    parser.add_argument(
        "--labels",
        metavar="N",
        type=_positive_int,
        default=200,
        help="label every object in the pictures up to N objects, else only those with "
        "findings (default 200)",
    )
    parser.add_argument(
        "--gltf",
        metavar="FILE",
        default=None,
        help="a glTF/GLB file of the same model (from 'asbuilt model --out'): the HTML offers "
        "an optional interactive 3-D view of it (the file is embedded up to 10 MB; the viewer "
        "needs network access when opened)",
    )
    parser.add_argument("--quiet", "-q", action="store_true", help="print nothing but errors")
    parser.set_defaults(handler=run)
    return parser


#: Options that shape how a scan is built; a model document is already built.
_BUILD_OPTIONS = (("schedule", "--schedule"), ("catalog", "--catalog"), ("no_merge", "--no-merge"))


def _model(args, source, progress):
    """The model of ``source`` (a :class:`~asbuilt.cli._input.ScanInput`) and the catalog it
    was built with (None: the report reads the model's)."""
    if source.is_model():
        from asbuilt.cli._models import refuse_build_options

        refuse_build_options(
            source.name, [flag for name, flag in _BUILD_OPTIONS if getattr(args, name)]
        )
        model = source.load_model()
        if args.no_check or (args.rules is None and args.design is None):
            return model, None  # the findings the document records
        from asbuilt.pipeline import recheck
        from asbuilt.report.takeoff import model_catalog
        from asbuilt.rules import load_rules

        catalog = model_catalog(model)[0]
        config = load_rules(args.rules) if args.rules else None
        findings = recheck(model, config, args.design, catalog=catalog)
        return model.replace(findings=findings), catalog
    from asbuilt.merge import resolve_catalog
    from asbuilt.pipeline import build_model

    catalog = resolve_catalog(args.catalog) if args.catalog is not None else None
    scan = source.load_scan()
    progress.total = len(scan.objects)
    model = build_model(
        scan,
        catalog=catalog,
        schedule=args.schedule,
        rules=args.rules,
        design=args.design,
        merge=not args.no_merge,
        check=not args.no_check,
        progress=progress,
    )
    return model, catalog


def _size(n: int) -> str:
    if n < 1000:
        return f"{n} B"
    for unit in ("kB", "MB", "GB"):
        n /= 1000
        if n < 1000 or unit == "GB":
            return f"{n:.1f} {unit}"
    return f"{n:.1f} GB"


def run(args: argparse.Namespace) -> int:
    """Build the model and write the reports; return 0, or 1 when an object's fit was refused
    (the reports are written without it). Bad input raises AsbuiltError (exit 2)."""
    import sys
    from pathlib import Path

    from rich.console import Console

    from asbuilt.atomic import check_target
    from asbuilt.cli._args import refuse_standard_output
    from asbuilt.cli._input import input_files, scan_input
    from asbuilt.cli._models import say_refused
    from asbuilt.cli._progress import stage_progress
    from asbuilt.errors import ExportError
    from asbuilt.report import SUFFIXES, report_format_for, write_reports

    inputs = input_files(args.scan, args.rules, args.design, args.catalog, args.gltf)
    outputs = [Path(p) for p in args.out]
    for name, path in zip(args.out, outputs):
        # As typed: a directory or a trailing slash is said as such before the suffix test.
        refuse_standard_output(name, "--out", "a report", "report.html")
        check_target(name, "--out", inputs=inputs, example=f"report{path.suffix or '.html'}")
        report_format_for(name)  # an unknown suffix fails before any work
    if args.gltf is not None:
        if Path(args.gltf).suffix.lower() not in (".glb", ".gltf"):
            raise ExportError("--gltf must name a .glb or .gltf file", source=str(args.gltf))
        if Path(args.gltf).is_dir():
            raise ExportError(
                "--gltf is a directory; give the .glb or .gltf file (asbuilt model SCAN --out "
                "model.glb)",
                source=str(args.gltf),
            )
        if not Path(args.gltf).is_file():
            raise ExportError(
                "--gltf file not found; write it first (asbuilt model SCAN --out model.glb)",
                source=str(args.gltf),
            )
        from asbuilt.export.gltf import gltf_problem

        problem = gltf_problem(Path(args.gltf))
        if problem:
            raise ExportError(
                f"--gltf {problem}; write it again (asbuilt model SCAN --out model.glb)",
                source=str(args.gltf),
            )

    source = scan_input(args.scan)
    err = Console(file=sys.stderr, markup=False)
    with stage_progress(err, quiet=args.quiet) as bar:
        task = bar.add_task("", total=None, stage="fitting")

        class _Progress:
            total = None

            def __call__(self, done, total, oid):
                bar.update(task, completed=done, total=total, description=oid)

        model, catalog = _model(args, source, _Progress())
        bar.update(task, completed=0, total=len(outputs), description="", stage="writing")
        options = {"figure_format": args.figures, "label_limit": args.labels}
        if args.density is not None:
            options["density"] = args.density
        if args.gltf is not None:
            options["gltf"] = args.gltf
        if catalog is not None:
            options["catalog"] = catalog
        written = write_reports(model, outputs, **options)

    status = 1 if say_refused(err, model, source.name) else 0  # written, but without them
    if args.quiet:
        return status
    out = Console(file=sys.stdout, highlight=False, soft_wrap=True, markup=False)
    for path in written:
        name = SUFFIXES[path.suffix.lower()].name
        out.print(f"wrote {path} ({name} report, {_size(path.stat().st_size)})")
    counts = {severity: 0 for severity in ("error", "warning", "info")}
    for finding in model.findings:
        counts[finding.severity] += 1
    out.print(
        f"{plural(len(model.components), 'component')}; findings: "
        f"{plural(counts['error'], 'error')}, {plural(counts['warning'], 'warning')}, "
        f"{counts['info']} info"
    )
    return status
