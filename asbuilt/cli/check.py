"""``asbuilt check SCAN``: the compliance checker, a spell checker for as-built models.

Fits and merges the scan (as ``asbuilt model`` does), runs the rules and prints the findings like
a linter, one per line, sorted by severity then position, then a summary line. Exit code 0 when
no finding is an error, 1 when one is, 2 for bad input, so it runs in a QA pipeline.
Each finding's suggestions are numbered beneath it, with the ``--accept`` choice that accepts
one (:mod:`asbuilt.rules.accept`). ``--fix OUT`` accepts every unambiguous suggestion, or with
``--accept`` only the chosen ones (ambiguous ones too), writes the corrected model (any export
format) and lists what it changed; the findings printed are then those left after the fixes.
An object whose fit was refused is an error finding ``AB001 fit-refused`` that no selection
drops and re-checks keep. A model document takes ``--catalog`` only where it decides something
(unmerged, or its own catalog unreadable) and refuses ``--no-merge``, one line each.
``SCAN`` may be ``-``: the scan or model document is read from standard input
(:mod:`asbuilt.cli._input`), and findings and errors name it ``<stdin>``.
"""

from __future__ import annotations

import argparse

from asbuilt.cli._input import SCAN_HELP
from asbuilt.cli._text import plural
from asbuilt.export import SUFFIXES

__all__ = ["register", "run"]


def _selectors(text: str) -> list[str]:
    items = [item.strip() for item in text.split(",") if item.strip()]
    if not items:
        raise argparse.ArgumentTypeError("give rule codes or slugs, e.g. AB202,too-few-points")
    return items


def suggestion_lines(finding) -> list[str]:
    """The numbered suggestions of ``finding``, one indented line each; a change names the
    ``--accept`` choice that accepts it (and ``--fix`` where ``--fix`` alone accepts it)."""
    from asbuilt.rules.accept import accept_choice

    lines = []
    for number, suggestion in enumerate(finding.suggestions, 1):
        line = f"    {number}. {suggestion.description}"
        choice = accept_choice(finding, number)
        if choice is not None:
            line += f"  [{'--fix, or ' if suggestion.unambiguous else ''}--accept {choice}]"
        lines.append(line)
    return lines


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``check`` subcommand to ``subparsers``."""
    parser = subparsers.add_parser(
        "check",
        help="check a scan's as-built model against the compliance rules (exit 1 on errors)",
        description="Fit and merge a scan (or read an asbuilt-model JSON document), check it "
        "against the compliance rules and print one finding per line, errors first. Exit code "
        "0: no errors; 1: at least one error; 2: bad input.",
        epilog="Example: asbuilt check samples/spool.json --design spool-design.json "
        "--rules project-rules.toml --fix spool-fixed.step",
    )
    parser.add_argument(
        "scan",
        metavar="SCAN",
        nargs="?",
        help=f"an asbuilt-scan JSON file (or an asbuilt-model document; {SCAN_HELP})",
    )
    parser.add_argument(
        "--list-rules",
        action="store_true",
        help="print every rule (code, slug, severity from --rules, whether it runs with "
        "--rules, --select and --ignore, source) and exit",
    )
    parser.add_argument(
        "--design",
        metavar="FILE",
        default=None,
        help="design file (asbuilt-design JSON) to compare with: deviations, missing, extra",
    )
    parser.add_argument(
        "--rules",
        metavar="FILE",
        default=None,
        help="rules file (TOML) overriding the shipped defaults per key (see docs/rules.md)",
    )
    parser.add_argument(
        "--select",
        metavar="RULES",
        type=_selectors,
        action="append",
        default=None,
        help="only these rules: codes, code prefixes or slugs, comma separated (AB2,clash)",
    )
    parser.add_argument(
        "--ignore",
        metavar="RULES",
        type=_selectors,
        action="append",
        default=None,
        help="skip these rules (same forms as --select)",
    )
    parser.add_argument(
        "--format",
        choices=("text", "concise", "json"),
        default="text",
        help="text: one finding per line, its numbered suggestions beneath, and a summary "
        "(default); concise: the finding lines and the summary only; json: the list of findings",
    )
    parser.add_argument(
        "--fix",
        metavar="OUT",
        default=None,
        help="accept every unambiguous suggestion (or only those --accept names) and write the "
        "corrected model to OUT (" + ", ".join(SUFFIXES) + ")",
    )
    parser.add_argument(
        "--accept",
        metavar="RULE@OBJECTS[:N]",
        action="append",
        default=None,
        help="with --fix: accept this suggestion instead of every unambiguous one, as the text "
        "output names it, e.g. AB101@P5:2 (rule code or slug, the finding's objects, the "
        "suggestion's number); repeat for several",
    )
    parser.add_argument(
        "--catalog",
        metavar="NAME|FILE",
        default=None,
        help="pipe catalog for sizes (default asme-b36.10m; see 'asbuilt catalog')",
    )
    parser.add_argument(
        "--no-merge",
        action="store_true",
        help="check the fitted objects as they are, without merging pipes into spools "
        "(scans only: a model document is already built)",
    )
    parser.set_defaults(handler=run)
    return parser


def _load(args, source, config, design, progress=None):
    """The checked model of ``source`` (a :class:`~asbuilt.cli._input.ScanInput`)."""
    from asbuilt.errors import CatalogError
    from asbuilt.pipeline import recheck

    if source.is_model():
        from asbuilt.cli._models import refuse_build_options

        refuse_build_options(source.name, ["--no-merge"] if args.no_merge else [])
        model = source.load_model()
        if args.catalog:
            _refuse_resizing(args, source.name, model)
        try:
            findings = recheck(model, config, design, catalog=args.catalog or None)
        except CatalogError as exc:
            if exc.source is not None:
                raise
            raise CatalogError(exc.message, source=source.name) from None
        return model.replace(findings=findings)
    from asbuilt.pipeline import build_model

    scan = source.load_scan()
    return build_model(
        scan,
        catalog=args.catalog,
        tolerances=config.tolerances,
        rules=config,
        design=design,
        merge=not args.no_merge,
        check=True,
        progress=progress,
    )


def _accept(model, choices, config, design):
    """Apply ``--accept``'s choices: scan links first (the model merged again with them,
    :func:`asbuilt.pipeline.relink`), then the chosen changes, found again among the merged
    model's findings. Returns ``(the model they apply to, the fixed model, the changes)``."""
    from asbuilt.errors import SuggestionError
    from asbuilt.rules import apply_suggestions, choose_suggestions
    from asbuilt.rules.fixes import is_link

    chosen = choose_suggestions(model.findings, choices)  # every choice checked first
    links = [(finding, s) for finding, s in chosen if is_link(s)]
    if not links:
        return (model, *apply_suggestions(model, chosen))
    from asbuilt.pipeline import relink

    pairs = [tuple(s.change["objects"]) for _, s in links]
    rest = [c for c in choices if not is_link(choose_suggestions(model.findings, [c])[0][1])]
    model = relink(model, pairs, tolerances=config.tolerances, rules=config, design=design)
    linked = [
        f"{', '.join(s.change['objects'])}: {s.description} ({finding.slug})"
        for finding, s in links
    ]
    try:
        chosen = choose_suggestions(model.findings, rest)
    except SuggestionError as exc:
        names = " and ".join(" and ".join(pair) for pair in pairs)
        raise SuggestionError(f"after linking {names}: {exc.message}") from None
    fixed, changes = apply_suggestions(model, chosen)
    return model, fixed, linked + changes


def _refuse_resizing(args, name: str, model) -> None:
    """Refuse ``--catalog`` for a model document whose pipe sizes were chosen when it was built
    (their snap records decide the size rules, so another catalog would change nothing) and
    whose own catalog can be read; it is taken when it names that same catalog, when the
    model is unmerged (the size rules snap against it) or when its own catalog is unreadable
    (``--catalog FILE`` is then the remedy)."""
    from asbuilt.catalog import load_catalog, model_catalog
    from asbuilt.export.model_json import ModelDocumentError

    own, problem = model_catalog(model)
    if own is None or problem is not None:
        return
    if not any((c.snap or {}).get("status") for c in model.components):
        return
    given = load_catalog(args.catalog)
    if given is own or (given.name == own.name and _same_path(given.path, own.path)):
        return
    raise ModelDocumentError(
        f"--catalog {args.catalog} cannot re-size this model's pipes: their sizes were chosen "
        f"from {own.name} when it was built; give the scan instead to size them against "
        "another catalog, or leave --catalog out",
        source=name,
    )


def _same_path(one, two) -> bool:
    """Whether two catalog paths (None for a shipped catalog) name one file: a model stores
    the absolute path, the command line may give it relative."""
    import os

    if one is None or two is None:
        return one == two
    try:
        return os.path.samefile(one, two)
    except OSError:
        return os.path.abspath(one) == os.path.abspath(two)


def _list_rules(config) -> None:
    """The registry as a table on stdout, with the severities the rules file gives and whether
    each rule runs under the rules file's and the command line's selection."""
    import sys

    from rich.console import Console
    from rich.table import Table

    from asbuilt.findings import FIT_REFUSED_CODE, FIT_REFUSED_SLUG
    from asbuilt.rules import RULES
    from asbuilt.rules.waivers import UNUSED_WAIVER_CODE, UNUSED_WAIVER_SLUG

    table = Table("code", "slug", "severity", "runs", "source or reason", show_lines=False)
    # Not a rule of the registry (no rules-file options): the pipeline's own finding for an
    # object the fit refused, which no selection drops.
    table.add_row(
        FIT_REFUSED_CODE,
        FIT_REFUSED_SLUG,
        "error",
        "always",
        "The fit: a scan object whose fit was refused is missing from the model; rescan it "
        "(docs/rules.md). Not configurable.",
    )
    table.add_row(
        UNUSED_WAIVER_CODE,
        UNUSED_WAIVER_SLUG,
        "info",
        "with waivers",
        "The rules file: a [[waive]] entry that matches no finding of a rule that ran; remove it "
        "(docs/rules.md). Not configurable.",
    )
    for r in RULES:
        table.add_row(
            r.code,
            r.slug,
            config.severity(r.slug),
            "yes" if config.is_active(r.slug) else "no",
            r.source,
        )
    Console(file=sys.stdout, soft_wrap=False, width=160, markup=False).print(table)


def run(args: argparse.Namespace) -> int:
    """Check the scan; print the findings; return 1 if any is an error, else 0."""
    import json
    import sys
    from pathlib import Path

    from rich.console import Console
    from rich.markup import escape

    from asbuilt.cli._input import input_files, scan_input
    from asbuilt.cli._progress import stage_progress
    from asbuilt.pipeline import recheck, refused_findings
    from asbuilt.rules import apply_fixes, load_rules

    config = load_rules(args.rules)
    select = [s for group in args.select or () for s in group]
    ignore = [s for group in args.ignore or () for s in group]
    if select or ignore:
        config = config.with_selection(select=select or None, ignore=ignore)
    if args.list_rules:
        _list_rules(config)  # runs: what a check with these options would run
        return 0
    if not args.scan:
        from asbuilt.errors import ScanReadError

        raise ScanReadError("check: give a SCAN file ('-': standard input), or --list-rules")
    design = None
    if args.design:
        from asbuilt.design import load_design

        design = load_design(args.design)
    if args.accept and args.fix is None:
        from asbuilt.errors import SuggestionError

        raise SuggestionError("--accept needs --fix OUT: the file to write the corrected model to")
    if args.accept:
        from asbuilt.rules.accept import parse_choice

        choices = [parse_choice(text) for text in args.accept]  # malformed: before any work
    if args.fix is not None:
        from asbuilt.atomic import check_target
        from asbuilt.cli._args import refuse_standard_output
        from asbuilt.export import exporter_for

        # All before any work, as typed: '-', a directory or a trailing slash is said as such
        # (the suffix test would call it a file without a suffix), then an unknown suffix.
        refuse_standard_output(args.fix, "--fix", "a CAD model", "fixed.step")
        check_target(
            args.fix,
            "--fix",
            inputs=input_files(args.scan, args.rules, args.design, args.catalog),
            example="fixed.step",
        )
        exporter_for(args.fix)

    source = scan_input(args.scan)
    err = Console(file=sys.stderr, highlight=False, soft_wrap=True)
    with stage_progress(err) as bar:
        task = bar.add_task("", total=None, stage="fitting")
        model = _load(
            args,
            source,
            config,
            design,
            lambda done, total, oid: bar.update(task, completed=done, total=total, description=oid),
        )
    findings = model.findings
    changes: list[str] = []
    if args.fix:
        from asbuilt.export import export_model

        if args.accept:
            model, fixed, changes = _accept(model, choices, config, design)
        else:
            fixed, changes = apply_fixes(model, findings)
        fixed = fixed.replace(findings=refused_findings(model))  # objects still not in it
        findings = recheck(fixed, config, design, catalog=args.catalog or None)
        export_model(fixed.replace(findings=findings), Path(args.fix))

    out = Console(file=sys.stdout, highlight=False, soft_wrap=True)
    if args.format == "json":
        from asbuilt.export.model_json import finding_to_dict

        text = json.dumps([finding_to_dict(f) for f in findings], indent=2, allow_nan=False)
        sys.stdout.write(text + "\n")
        for change in changes:
            err.print(f"fixed: {escape(change)}")
        if args.fix:
            err.print(f"wrote {escape(str(args.fix))} ({plural(len(changes), 'fix')})")
    else:
        colours = {"error": "red", "warning": "yellow", "info": "blue"}
        for f in findings:
            where = ",".join(f.objects) or "-"
            out.print(
                f"{escape(source.name)}: {escape(where)}: [{colours[f.severity]}]{f.severity}"
                f"[/] {f.slug}: {escape(f.message)}"
            )
            if args.format == "text":
                for line in suggestion_lines(f):
                    out.print(escape(line))
        for change in changes:
            out.print(f"fixed: {escape(change)}")
        counts = {s: sum(1 for f in findings if f.severity == s) for s in colours}
        unverifiable = sum(1 for f in findings if f.unverifiable)
        summary = (
            f"{plural(counts['error'], 'error')}, {plural(counts['warning'], 'warning')}"
            f" ({unverifiable} unverifiable), {counts['info']} info in "
            f"{plural(len(model.components), 'component')}"
        )
        if args.fix:
            summary += f"; {plural(len(changes), 'fix')} written to {args.fix}"
        out.print(escape(summary))
    return 1 if any(f.severity == "error" for f in findings) else 0
