"""How often ``kind: "auto"`` chooses the right primitive, on the fitting benchmark's scans.

The trials are those of ``benchmarks/fit_accuracy.py`` (same simulator, same cells, same seed,
so the same objects and shots): cylinders (every outside diameter and length/diameter), spheres,
planes (walls and plates) and cuboids (2 and 3 seen faces), each at 20 and 40 points, clean and
with 20% edge outliers. Every point set goes through :func:`asbuilt.fit.auto.fit_auto` twice:

* as ``asbuilt fit`` calls it for a scan that gives its sensor (range sigma and station), and
* without a sensor (no sigma, no viewpoint): the criterion then estimates the noise itself.

The table gives, per true kind and version, how many trials chose each kind (a failure in its
own column); below it, every cell with a wrong choice: another kind, or a failure. No trial
here has a cuboid seen on one face, which would rightly be a plane.

Run: ``python benchmarks/auto_choice.py [--trials 20] [--points 20 40] [--out F]``.
"""

from __future__ import annotations

import argparse
import collections
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import fit_accuracy as fa  # noqa: E402

from asbuilt.errors import FitError  # noqa: E402
from asbuilt.fit.auto import CANDIDATES, fit_auto  # noqa: E402

#: The sensor as a scan would give it: (label, sigma metres or None, viewpoint or None).
MODES = (
    ("sensor given", fa.SIGMA_R, fa.STATION.position),
    ("no sensor", None, None),
)


def cells(points: tuple[int, ...]) -> list[tuple[str, tuple, object]]:
    """(true kind, cell key, trial maker) for every cell at the given point counts."""
    out = []
    for n in points:
        out += [("cylinder", (od, ld, n), fa.cylinder_trial) for od in fa.ODS_MM for ld in fa.LDS]
        out += [("sphere", (d, n), fa.sphere_trial) for d in fa.SPHERE_D]
        out += [("plane", (w, n), fa.plane_trial) for w in fa.PLANE_W]
        out += [("cuboid", (s, f, n), fa.cuboid_trial) for s in fa.SECTIONS for f in (2, 3)]
    return out


def choose(points, sigma, viewpoint) -> tuple[str, float]:
    """The kind auto chooses (``"failed"`` when it raises) and the seconds it took."""
    start = time.perf_counter()
    try:
        result = fit_auto(points, sigma=sigma, viewpoint=viewpoint)
        chosen = result.primitive.kind
    except FitError:
        chosen = "failed"
    return chosen, time.perf_counter() - start


def run(trials: int, points: tuple[int, ...], seed: int, progress) -> tuple[dict, dict, list]:
    """Counts {(mode, version, true kind): Counter(chosen)}, wrong cells and fit times."""
    counts: dict = collections.defaultdict(collections.Counter)
    wrong: dict = collections.defaultdict(collections.Counter)
    times = []
    for kind, key, make in cells(points):
        # The accuracy benchmark's generator for this cell: the same objects and shots.
        rng = np.random.default_rng([seed, fa.hash_key(kind, key)])
        for _ in range(trials):
            trial = make(rng, *key)
            for version, data in (("clean", trial.clean), ("20% outliers", trial.dirty)):
                for mode, sigma, viewpoint in MODES:
                    chosen, elapsed = choose(data, sigma, viewpoint)
                    times.append(elapsed)
                    counts[(mode, version, kind)][chosen] += 1
                    if chosen != kind:
                        wrong[(mode, version, kind, key)][chosen] += 1
        progress(kind, key)
    return counts, wrong, times


def report(counts, wrong, times, command: str, elapsed: float, trials: int) -> str:
    """The Markdown tables."""
    columns = list(CANDIDATES) + ["failed"]
    lines = [
        f"Command: `{command}` ({elapsed:.0f} s on this machine; {trials} trials per cell; "
        f"median auto fit {np.median(times) * 1e3:.1f} ms, p90 "
        f"{np.percentile(times, 90) * 1e3:.1f} ms).",
        "",
        "| sensor | data | true kind | trials | right | " + " | ".join(columns) + " |",
        "|---|---|---|---|---|" + "---|" * len(columns),
    ]
    for (mode, version, kind), counter in counts.items():
        total = sum(counter.values())
        right = counter[kind] / total
        row = " | ".join(str(counter[c]) for c in columns)
        lines.append(f"| {mode} | {version} | {kind} | {total} | {right:.1%} | {row} |")
    lines += ["", "Cells with a wrong choice (cell key: cylinder (OD mm, L/D, n), sphere (D m, n),"]
    lines += ["plane (width m, n), cuboid (section m, faces, n)):", ""]
    if not wrong:
        lines.append("none")
    else:
        lines += ["| sensor | data | true kind | cell | wrong choices |", "|---|---|---|---|---|"]
        for (mode, version, kind, key), counter in wrong.items():
            text = ", ".join(f"{n} x {c}" for c, n in counter.most_common())
            lines.append(f"| {mode} | {version} | {kind} | {key} | {text} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=20, help="trials per cell (20)")
    parser.add_argument("--points", type=int, nargs="+", default=[20, 40])
    parser.add_argument("--seed", type=int, default=2004)
    parser.add_argument("--out", default=None, help="write the Markdown here, not to stdout")
    args = parser.parse_args(argv)
    started = time.perf_counter()

    def progress(kind, key):
        print(f"  {kind} {key} ({time.perf_counter() - started:.0f} s)", file=sys.stderr)

    counts, wrong, times = run(args.trials, tuple(args.points), args.seed, progress)
    given = argv if argv is not None else sys.argv[1:]
    command = "python benchmarks/auto_choice.py" + ("" if not given else " " + " ".join(given))
    text = report(counts, wrong, times, command, time.perf_counter() - started, args.trials)
    if args.out:
        Path(args.out).write_text(text)
    else:
        print(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
