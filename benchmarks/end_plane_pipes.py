"""Pipes at a flange face or entering a wall: the cylinder fit with and without the rescue
that leaves out a plane across the pipe's end (``asbuilt/fit/_cylinder_end_plane.py``).

The scenes are the tests' own ray-cast ones (``tests/fit/test_cylinder_end_plane.py``, not
``asbuilt.sim``): a pipe ending at a flange twice its radius or entering a square or 30-degree
wall, 5-7 m from the station, 32 hand-aimed shots over its last half metre and its end, range
noise 2 mm along the beams, pointing noise 0.01 degree. A fit is right when its radius is within
4 standard errors (or 2 mm) of the truth and its axis within 4 standard errors (or 1 degree).

Run: ``python benchmarks/end_plane_pipes.py --seeds 60`` (about a minute).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import asbuilt.fit.cylinder as cylinder_module

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import _test_modules  # noqa: E402


def _scenes_module():
    """The tests' scene generator, loaded from the checkout (the tests are not installed)."""
    return _test_modules.load("fit/test_cylinder_end_plane.py", "end_plane_scenes")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=60, help="scenes per configuration")
    args = parser.parse_args(argv)
    scenes = _scenes_module()
    rescue = cylinder_module.fit_without_end_plane
    rows = []
    for radius, surface, slant in scenes.CONFIGURATIONS:
        counts = {"scenes": 0, "before": 0, "after": 0, "spoiled": 0, "over half": 0}
        for seed in range(args.seeds):
            points, station, axis, labels = scenes._scene(seed, radius, surface, slant)
            share = float(np.mean(labels == "end"))
            if share < 0.25:
                continue
            counts["scenes"] += 1
            counts["over half"] += share > 0.5
            cylinder_module.fit_without_end_plane = lambda *a: None
            before = scenes._outcome(points, station, radius, axis)
            cylinder_module.fit_without_end_plane = rescue
            after = scenes._outcome(points, station, radius, axis)
            counts["before"] += before
            counts["after"] += after
            counts["spoiled"] += before and not after
        rows.append((radius, surface, slant, counts))
    print(
        "| pipe OD | surface | slant | scenes (25%+ on it) | of them over half | right before | right now | spoiled |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for radius, surface, slant, c in rows:
        print(
            f"| {2e3 * radius:.1f} mm | {surface} | {slant:.0f} deg | {c['scenes']} | {c['over half']}"
            f" | {c['before']} | {c['after']} | {c['spoiled']} |"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
