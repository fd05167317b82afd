"""Tanks and drums from the tests' simulated scenes: right, wrong or refused, and how the
outcome moves with the two thresholds the tank checks rest on.

The scenes are ``tests/fit/sim_tanks.py``'s (:mod:`asbuilt.sim`, 2 mm range sigma, 0.01
degree pointing noise, mixed returns at silhouette edges, shots past the object landing on
what lies behind it), fitted as ``asbuilt fit`` fits them: kind ``cylinder``, the sensor's
sigma and the station. A fit is **wrong** when its radius is off by more than 3 standard
errors and 5%, else **right**; a refused fit is counted apart (docs/fitting.md, "Tanks and
drums").

The sensitivity sweep sets the module constants for the whole run:

- ``--far-fraction``: an inlier whose beam passed within this fraction of the radius of the
  fitted axis crossed its far half (``asbuilt.fit._cylinder_far_side.FAR_FRACTION``, 0.9);
- ``--raster-share``: the share of a fit's shots whose directions from the station must fall on
  a pan-tilt raster for the fit to be refused as shot from there
  (``asbuilt.fit._cylinder_checks.RASTER_SHARE``, 0.9).

Run: ``python benchmarks/tank_scenes.py --seeds 150`` (about 8 minutes a setting), and e.g.
``--far-fraction 0.8`` to see a threshold's effect. ``--sweep`` runs the defaults and each
threshold at two other values, and prints one table.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from _test_modules import load  # noqa: E402

import asbuilt.fit._cylinder_checks as checks  # noqa: E402
import asbuilt.fit._cylinder_far_side as far_side  # noqa: E402
from asbuilt.errors import FitError  # noqa: E402
from asbuilt.fit import fit_points  # noqa: E402

sim_tanks = load("fit/sim_tanks.py", "sim_tanks")

#: The scene families: (name, the generator of (points, station, truth) from a seed).
SCENES = (
    ("tank before a wall, station 1-8 m up", lambda seed: sim_tanks.tank_before_wall(seed)),
    (
        "tank before a wall, station 1-2 m up, wider window",
        lambda seed: sim_tanks.tank_before_wall(seed, margin=0.7, heights=(1.0, 2.0)),
    ),
    ("partial tank, nothing around", sim_tanks.partial_tank),
    ("horizontal drum seen end-on", sim_tanks.end_on_drum),
)

#: (far fraction, raster share) settings of ``--sweep``: the defaults, then each moved alone.
SWEEP = ((0.9, 0.9), (0.8, 0.9), (1.0, 0.9), (0.9, 0.8), (0.9, 0.95))


def outcome(points: np.ndarray, station: np.ndarray, truth: dict) -> str:
    """``"right"``, ``"wrong"`` or ``"refused"`` for one scene's fit (module docstring)."""
    try:
        result = fit_points("cylinder", points, sigma=sim_tanks.SIGMA, viewpoint=station)
    except FitError:
        return "refused"
    error = abs(result.primitive.radius - truth["radius"])
    wrong = error > 3.0 * result.stderr["radius"] and error > 0.05 * truth["radius"]
    return "wrong" if wrong else "right"


def run(seeds: int, far_fraction: float, raster_share: float) -> dict[str, Counter]:
    """Each scene family's outcome counts over seeds ``0..seeds-1`` at these thresholds (set
    for the run only: the shipped values are put back after it)."""
    shipped = far_side.FAR_FRACTION, checks.RASTER_SHARE
    far_side.FAR_FRACTION, checks.RASTER_SHARE = far_fraction, raster_share
    try:
        return {
            name: Counter(outcome(*scene(seed)) for seed in range(seeds)) for name, scene in SCENES
        }
    finally:
        far_side.FAR_FRACTION, checks.RASTER_SHARE = shipped


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=150)
    parser.add_argument("--far-fraction", type=float, default=far_side.FAR_FRACTION)
    parser.add_argument("--raster-share", type=float, default=checks.RASTER_SHARE)
    parser.add_argument("--sweep", action="store_true", help="the defaults and each moved alone")
    args = parser.parse_args(argv)
    settings = SWEEP if args.sweep else ((args.far_fraction, args.raster_share),)
    print(f"{args.seeds} seeds a scene family; right / wrong / refused\n")
    print("| far fraction | raster share | " + " | ".join(name for name, _ in SCENES) + " |")
    print("|---|---|" + "---|" * len(SCENES))
    for far_fraction, raster_share in settings:
        counts = run(args.seeds, far_fraction, raster_share)
        cells = (
            f"{c['right']} / {c['wrong']} / {c['refused']}"
            for c in (counts[name] for name, _ in SCENES)
        )
        print(f"| {far_fraction:g} | {raster_share:g} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
