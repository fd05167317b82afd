"""How long the QA reports take on a large scan (1,000 objects).

The scan is the plant sample (``samples/plant.json``: columns, beams, an NPS 8 spool with
elbows, a tank, a chimney, a wall and a pump skid; 13 objects, 464 points) tiled on a grid
with 40 m spacing, each copy's ids suffixed, until it holds at least ``--objects`` objects. The
model is built once with :func:`asbuilt.pipeline.build_model` (fit, merge, rules; timed for
reference), then every report is written ``--repeats`` times and the median wall time kept:
:func:`asbuilt.report.report_data` alone, the CSV, the JSON, the HTML with SVG pictures and
the HTML with PNG pictures, and the two matplotlib views on their own.

Run: ``python benchmarks/report_speed.py [--objects 1000] [--repeats 3] [--out FILE.md]``.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from asbuilt.pipeline import build_model  # noqa: E402
from asbuilt.report import report_data, write_report  # noqa: E402
from asbuilt.report.figures import render_view  # noqa: E402
from asbuilt.scan import load_scan  # noqa: E402


def tiled_scan(objects: int, spacing: float = 40.0):
    """The plant sample repeated on a grid until it has at least ``objects`` objects."""
    base = load_scan(ROOT / "samples" / "plant.json")
    copies = -(-objects // len(base.objects))
    side = int(np.ceil(np.sqrt(copies)))
    tiled, links = [], []
    for k in range(copies):
        offset = np.array([spacing * (k % side), spacing * (k // side), 0.0])
        for obj in base.objects:
            tiled.append(
                replace(
                    obj,
                    id=f"{obj.id}-{k}",
                    points=obj.points + offset,
                    index=len(tiled),
                    group=None if obj.group is None else f"{obj.group}-{k}",
                    measurements=None,
                )
            )
        links.extend((f"{a}-{k}", f"{b}-{k}") for a, b in base.links)
    return replace(base, objects=tuple(tiled), links=tuple(links), name=f"{base.name} x {copies}")


def median_time(function, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--objects", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None, help="also write the table here")
    args = parser.parse_args()

    scan = tiled_scan(args.objects)
    start = time.perf_counter()
    model = build_model(scan)
    build = time.perf_counter() - start
    points = sum(len(o.points) for o in scan.objects)

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        rows.append(
            (
                "report_data (take-off, fit quality)",
                median_time(lambda: report_data(model), args.repeats),
                None,
            )
        )
        rows.append(
            (
                "plan view, SVG (matplotlib)",
                median_time(lambda: render_view(model, "plan"), args.repeats),
                None,
            )
        )
        rows.append(
            (
                "elevation view, SVG (matplotlib)",
                median_time(lambda: render_view(model, "elevation"), args.repeats),
                None,
            )
        )
        for label, name, options in (
            ("CSV report", "qa.csv", {}),
            ("JSON report", "qa.json", {}),
            ("HTML report, SVG pictures", "qa.html", {}),
            ("HTML report, PNG pictures", "qa-png.html", {"figure_format": "png"}),
        ):
            path = tmp / name
            seconds = median_time(
                lambda path=path, options=options: write_report(model, path, **options),
                args.repeats,
            )
            rows.append((label, seconds, path.stat().st_size))

    lines = [
        f"Scan: {len(scan.objects)} objects ({points} points), the plant sample tiled; model: "
        f"{len(model.components)} components, {len(model.spools)} spools, "
        f"{len(model.findings)} findings. build_model (fit, merge, rules): {build:.1f} s.",
        "",
        "| step | median time (s) | file size |",
        "|---|---|---|",
    ]
    for label, seconds, size in rows:
        shown = "" if size is None else f"{size / 1e6:.2f} MB"
        lines.append(f"| {label} | {seconds:.2f} | {shown} |")
    lines.append("")
    lines.append(
        f"Median of {args.repeats} runs; Python {platform.python_version()}, "
        f"{platform.machine()}, {platform.system()}."
    )
    text = "\n".join(lines)
    print(text)
    if args.out is not None:
        args.out.write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
