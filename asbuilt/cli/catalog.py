"""``asbuilt catalog list`` and ``asbuilt catalog show NAME``: the pipe and fitting catalogs.

``list`` prints every shipped catalog (name, kind, standard, sizes, title); ``show NAME``
prints one catalog's table in millimetres (a shipped name or a CSV path, the same format as
``--catalog FILE``), with ``--json`` for machines. The catalog file format is documented in
docs/catalogs.md.
"""

from __future__ import annotations

import argparse

__all__ = ["register", "run"]


def register(subparsers) -> argparse.ArgumentParser:
    """Add the ``catalog`` subcommand (with ``list`` and ``show``) to ``subparsers``."""
    parser = subparsers.add_parser(
        "catalog",
        help="list the pipe and fitting catalogs or show one",
        description="List the shipped pipe and fitting catalogs (ASME B36.10M, B36.19M, "
        "EN 10220, ASTM B88, ASTM D1785, ASME B16.9) or show one catalog's sizes in mm.",
        epilog="Examples: asbuilt catalog list; asbuilt catalog show asme-b36.10m; "
        "asbuilt catalog show my-pipes.csv --json",
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION")
    lister = actions.add_parser("list", help="list the shipped catalogs")
    lister.add_argument("--json", action="store_true", help="print JSON instead of a table")
    lister.set_defaults(handler=run)
    shower = actions.add_parser("show", help="show one catalog's sizes (mm)")
    shower.add_argument("name", metavar="NAME", help="a catalog name (see list) or a CSV path")
    shower.add_argument("--json", action="store_true", help="print JSON instead of a table")
    shower.set_defaults(handler=run)
    parser.set_defaults(handler=run)
    return parser


def _mm(value: float | None) -> str:
    return "" if value is None else f"{value * 1000:.3f}".rstrip("0").rstrip(".")


def _catalog_dict(cat) -> dict:
    out = {
        "name": cat.name,
        "title": cat.title,
        "standard": cat.standard,
        "kind": cat.kind,
        "material": cat.material,
        "designation": cat.designation,
        "file_units": cat.units,
        "units": "mm",
    }
    if cat.kind == "pipe":
        out["fittings"] = cat.fittings_name
        out["default_schedule"] = cat.default_schedule
        out["schedules"] = list(cat.schedules)
        out["sizes"] = [
            {
                "nominal": s.nominal,
                "nps": s.nps,
                "dn": s.dn,
                "od": round(s.od * 1000, 4),
                "walls": {k: round(v * 1000, 4) for k, v in s.walls.items()},
                "source": s.source,
            }
            for s in cat.sizes
        ]
    else:
        out["fittings"] = [
            {
                "nominal": f.nominal,
                "nps": f.nps,
                "dn": f.dn,
                **{k: round(v * 1000, 4) for k, v in f.dims.items()},
                "source": f.source,
            }
            for f in cat.fittings
        ]
    return out


def run(args: argparse.Namespace) -> int:
    """Print the list or one catalog; return 0. An unknown or malformed catalog raises a
    CatalogError (exit 2)."""
    import json
    import sys

    from rich.console import Console
    from rich.table import Table

    from asbuilt.catalog import FITTING_COLUMNS, catalog_names, load_catalog

    action = getattr(args, "action", None)
    console = Console(file=sys.stdout, width=160, markup=False)
    if action is None:
        print("usage: asbuilt catalog {list,show NAME}", file=sys.stderr)
        return 2
    if action == "list":
        cats = [load_catalog(name) for name in catalog_names()]
        if args.json:
            rows = [
                {
                    "name": c.name,
                    "kind": c.kind,
                    "standard": c.standard,
                    "title": c.title,
                    "sizes": len(c.sizes) if c.kind == "pipe" else len(c.fittings),
                }
                for c in cats
            ]
            print(json.dumps(rows, indent=2))
            return 0
        table = Table(title="asbuilt catalogs")
        for column in ("name", "kind", "standard", "sizes", "title"):
            table.add_column(column)
        for c in cats:
            count = len(c.sizes) if c.kind == "pipe" else len(c.fittings)
            table.add_row(c.name, c.kind, c.standard, str(count), c.title)
        console.print(table)
        return 0

    cat = load_catalog(args.name)
    if args.json:
        print(json.dumps(_catalog_dict(cat), indent=2))
        return 0
    console.print(f"{cat.name}: {cat.title} ({cat.standard}); lengths in mm")
    table = Table()
    if cat.kind == "pipe":
        table.add_column(cat.designation or "nominal")
        table.add_column("OD", justify="right")
        for schedule in cat.schedules:
            table.add_column(schedule, justify="right")
        for size in cat.sizes:
            table.add_row(
                size.nominal, _mm(size.od), *(_mm(size.walls.get(s)) for s in cat.schedules)
            )
    else:
        table.add_column(cat.designation or "nominal")
        for column in FITTING_COLUMNS:
            table.add_column(column, justify="right")
        for row in cat.fittings:
            table.add_row(row.nominal, *(_mm(row.dims.get(c)) for c in FITTING_COLUMNS))
    console.print(table)
    if cat.note:
        console.print(f"note: {cat.note}")
    console.print("sources: see each row's source column (asbuilt catalog show NAME --json)")
    return 0
