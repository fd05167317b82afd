"""Cylinder fit time alone, on the trials of ``benchmarks/fit_accuracy.py``.

The accuracy benchmark times every fit inside a long run that also simulates the scans; this
script generates the same trials first (same seed, same cells) and then times only the fit
calls (through :func:`asbuilt.fit.fit_points`, as the pipeline calls them), with and without
the viewpoint, clean and with 20% edge outliers, repeated, so the figure can be checked on its
own.

Two medians are printed: of every call (each scan ``--repeat`` times, pooled), and of each
scan's fastest call among its repeats. The second is :mod:`timeit`'s convention (its docs: the
lowest time is a lower bound on how fast the machine can run the code; higher ones come from
other processes interfering): on a shared machine whose speed wanders it measures the fit, not
the neighbours. The repeats run as whole passes over the scans, so a slow spell spoils one
pass, not every repeat of a scan.

Run: ``python benchmarks/cylinder_speed.py [--points 40] [--trials 50] [--repeat 3]``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import fit_accuracy  # noqa: E402

from asbuilt.fit import fit_points  # noqa: E402


def trials(points: int, count: int, seed: int) -> list:
    """The accuracy benchmark's cylinder trials with ``points`` shots, every OD and L/D."""
    out = []
    for od in fit_accuracy.ODS_MM:
        for ld in fit_accuracy.LDS:
            key = (od, ld, points)
            rng = np.random.default_rng([seed, fit_accuracy.hash_key("cylinder", key)])
            out.extend(fit_accuracy.cylinder_trial(rng, *key) for _ in range(count))
    return out


def timed(kind: str, data: list, viewpoint, repeat: int) -> np.ndarray:
    """Seconds per ``fit_points(kind, ...)`` call, shape (repeat, scans): whole passes over
    the scans, ``repeat`` of them."""
    times = np.empty((repeat, len(data)))
    for rep in range(repeat):
        for index, points in enumerate(data):
            start = time.perf_counter()
            try:
                fit_points(kind, points, sigma=fit_accuracy.SIGMA_R, viewpoint=viewpoint)
            except Exception:  # a failed fit is timed too, as in the accuracy benchmark
                pass
            times[rep, index] = time.perf_counter() - start
    return times


def run(kind: str, make_trials, doc: str, argv=None) -> int:
    """Parse the command line, make the trials with ``make_trials(points, count, seed)`` and
    print the markdown table of median and p90 ms per fit (shared with ``cuboid_speed.py``)."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--points", type=int, default=40)
    parser.add_argument("--trials", type=int, default=50, help="trials per cell (50)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--seed", type=int, default=2004)
    args = parser.parse_args(argv)
    data = make_trials(args.points, args.trials, args.seed)
    print(
        f"{len(data)} scans of {args.points} points, {args.repeat} passes; ms per fit: median"
        " and p90 of every call, and median of each scan's fastest call"
    )
    print("| data | viewpoint | median ms | p90 ms | median of fastest ms |")
    print("|---|---|---|---|---|")
    for name in ("clean", "dirty"):
        scans = [getattr(trial, name) for trial in data]
        for label, viewpoint in (("none", None), ("station", fit_accuracy.STATION.position)):
            ms = timed(kind, scans, viewpoint, args.repeat) * 1e3
            fastest = ms.min(axis=0)
            version = "clean" if name == "clean" else "20% edge outliers"
            print(
                f"| {version} | {label} | {statistics.median(ms.ravel()):.2f} | "
                f"{float(np.percentile(ms, 90)):.2f} | {statistics.median(fastest):.2f} |"
            )
    return 0


def main(argv=None) -> int:
    return run("cylinder", trials, __doc__, argv)


if __name__ == "__main__":
    raise SystemExit(main())
