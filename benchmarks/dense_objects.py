"""Time and memory of each fit on dense objects (a scanner's cloud instead of 20-40 shots).

asbuilt is built for sparse scans, but a scan may hold up to 1,000,000 points and users do
load dense clouds of one object. This script fits a pipe (OD 200 mm, 1.5 m seen over 150
degrees), a column (0.4 x 0.3 m, two faces, 2 m tall), a tank head (half a 0.6 m sphere) and a
wall (3 x 2 m), with 1 mm noise, at growing point counts, with every kind, and reports the wall-clock time per fit and the process's peak memory
so far (``ru_maxrss``; it only grows, so read it as an upper bound for the rows above).

Run: ``python benchmarks/dense_objects.py [--counts 1000 10000] [--large]``
(``--large`` adds 100,000 points; about 1 minute).
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from asbuilt.errors import FitError  # noqa: E402
from asbuilt.fit import fit_points  # noqa: E402

SENSOR = np.array([0.0, 0.0, 1.0])
NOISE = 0.001


def pipe(n: int, rng) -> np.ndarray:
    """``n`` points (n, 3) metres on the 150 degrees of a pipe facing the sensor."""
    centre, axis, radius = np.array([1.0, 3.0, 1.0]), np.array([1.0, 0.0, 0.0]), 0.1
    toward = SENSOR - centre
    toward -= (toward @ axis) * axis
    toward /= np.linalg.norm(toward)
    side = np.cross(axis, toward)
    angle = np.radians(rng.uniform(-75.0, 75.0, n))
    along = rng.uniform(-0.75, 0.75, n)
    ring = np.cos(angle)[:, None] * toward + np.sin(angle)[:, None] * side
    points = centre + along[:, None] * axis + radius * ring
    return points + rng.normal(0.0, NOISE, points.shape)


def column(n: int, rng) -> np.ndarray:
    """``n`` points (n, 3) metres on the two faces of a 0.4 x 0.3 m column facing the sensor."""
    half = n // 2
    height = rng.uniform(-1.0, 1.0, n)
    front = np.column_stack([rng.uniform(-0.2, 0.2, half), np.full(half, -0.15), height[:half]])
    rest = n - half
    side = np.column_stack([np.full(rest, -0.2), rng.uniform(-0.15, 0.15, rest), height[half:]])
    points = np.vstack([front, side]) + np.array([1.0, 5.0, 1.0])
    return points + rng.normal(0.0, NOISE, points.shape)


def tank_head(n: int, rng) -> np.ndarray:
    """``n`` points (n, 3) metres on the half of a 0.6 m sphere facing the sensor."""
    centre = np.array([0.0, 4.0, 1.0])
    toward = (SENSOR - centre) / np.linalg.norm(SENSOR - centre)
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    direction *= np.where(direction @ toward < 0, -1.0, 1.0)[:, None]
    points = centre + 0.3 * direction
    return points + rng.normal(0.0, NOISE, points.shape)


def wall(n: int, rng) -> np.ndarray:
    """``n`` points (n, 3) metres on a 3 x 2 m wall 6 m away."""
    points = np.column_stack([rng.uniform(-1.5, 1.5, n), np.full(n, 6.0), rng.uniform(0.0, 2.0, n)])
    return points + rng.normal(0.0, NOISE, points.shape)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", type=int, nargs="+", default=[1000, 10000])
    parser.add_argument("--large", action="store_true", help="also 100,000 points")
    args = parser.parse_args(argv)
    counts = args.counts + ([100_000] if args.large else [])
    rng = np.random.default_rng(2026)
    print("| object | points | kind | result | seconds | peak MB so far |")
    print("|---|---|---|---|---|---|")
    for name, make, kinds in (
        ("pipe", pipe, ("cylinder", "auto")),
        ("column", column, ("cuboid", "auto")),
        ("tank head", tank_head, ("sphere", "auto")),
        ("wall", wall, ("plane", "auto")),
    ):
        for n in counts:
            points = make(n, rng)
            for kind in dict.fromkeys((*kinds, "plane", "sphere", "hull")):
                start = time.perf_counter()
                try:
                    result = fit_points(kind, points, sigma=NOISE, viewpoint=SENSOR)
                    outcome = result.kind
                except FitError:
                    outcome = "refused (FitError)"
                seconds = time.perf_counter() - start
                peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
                print(f"| {name} | {n:,} | {kind} | {outcome} | {seconds:.2f} | {peak:.0f} |")
                sys.stdout.flush()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
