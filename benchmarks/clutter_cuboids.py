"""Cuboids among a floor, a wall or a ceiling, shot over windows wider than the box.

A field operator frames a column, a pier or a beam with a pan-tilt window a little wider than
it; the beams that pass the box hit the floor, the wall behind or the ceiling, and a file from
another acquisition tool keeps those shots with the box's. This script ray-casts such scenes
(:mod:`asbuilt.sim.raycast`, 2 mm range noise, ideal pointing), fits each object as the
pipeline does (``fit_points("cuboid", ..., sigma, viewpoint)``) and counts, per scene and
window:

- *gross*: a fit with a size more than 5 standard errors off, or an axis more than 2 degrees
  and 5 of its standard errors off (a fit that claims what it does not know);
- *off 25%*: a size more than 25% off (whatever its standard error);
- *refused*: the fit raised a ``FitError`` (a clear message instead of a box).

Scenes: a pier (0.2-0.6 m across, 0.8-1.3 m tall) on a floor seen from 0.4-1.2 m above its
top; a column (0.2-0.6 m, 2-4 m tall) on a floor, with or without a wall 0.5-2 m behind, from
a station 1.5 m high; a beam (0.2-0.6 m, 3-4 m long, 25-65 degrees to the line of sight)
0.3 m under a ceiling, seen from below. Objects 4-12 m away. The raster steps are equal in pan
and tilt, chosen to put about ``--shots`` shots on the box; the window is the box's angular
silhouette widened on every side by ``margin`` times its smaller angular extent (0: the
silhouette, cell-centred; 0.5: twice as wide).

Run: ``python benchmarks/clutter_cuboids.py --trials 30`` (about a minute).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from asbuilt.errors import FitError  # noqa: E402
from asbuilt.fit import fit_points  # noqa: E402
from asbuilt.sim.raycast import (  # noqa: E402
    BoxShape,
    PlaneShape,
    angles_from_direction,
    direction_from_angles,
    raycast,
)

SIGMA = 0.002  # metres
SCENES = ("pier+floor", "column+floor", "column+wall+floor", "beam+ceiling")
MARGINS = (0.0, 0.25, 0.5, 1.0)


def _frame(yaw: float) -> np.ndarray:
    return np.array(
        [[math.cos(yaw), math.sin(yaw), 0.0], [-math.sin(yaw), math.cos(yaw), 0.0], [0, 0, 1.0]]
    )


def scene(name: str, rng):
    """``(box, station, background shapes)`` of one random scene."""
    distance = rng.uniform(4.0, 12.0)
    pan = rng.uniform(-math.pi, math.pi)
    toward = np.array([math.cos(pan), math.sin(pan), 0.0])
    across = rng.uniform(0.2, 0.6, size=2)
    yaw = pan + math.radians(rng.uniform(25.0, 65.0)) * rng.choice([-1.0, 1.0])
    floor = PlaneShape(np.zeros(3), np.array([0.0, 0.0, 1.0]))
    if name == "pier+floor":
        height = rng.uniform(0.8, 1.3)
        station = np.array([0.0, 0.0, height + rng.uniform(0.4, 1.2)])
        centre = distance * toward + [0.0, 0.0, 0.5 * height]
        return BoxShape(centre, _frame(yaw), np.array([*across, height])), station, [floor]
    if name.startswith("column"):
        height = rng.uniform(2.0, 4.0)
        station = np.array([0.0, 0.0, 1.5])
        centre = distance * toward + [0.0, 0.0, 0.5 * height]
        others = [floor]
        if "wall" in name:
            gap = rng.uniform(0.5, 2.0) + 0.5 * float(np.hypot(*across))
            others.append(PlaneShape(centre + gap * toward, -toward))
        return BoxShape(centre, _frame(yaw), np.array([*across, height])), station, others
    length = rng.uniform(3.0, 4.0)
    depth = across[1]
    station = np.array([0.0, 0.0, 1.5])
    top = rng.uniform(3.5, 4.5)
    centre = distance * toward + [0.0, 0.0, top - 0.5 * depth]
    frame = _frame(yaw)
    axes = np.array([frame[1], frame[2], frame[0]])  # length along the yawed x axis
    ceiling = PlaneShape(np.array([0.0, 0.0, top + 0.3]), np.array([0.0, 0.0, -1.0]))
    return BoxShape(centre, axes, np.array([across[0], depth, length])), station, [ceiling]


def shots(box, station, others, margin: float, wanted: int, rng):
    """Raster shots (n, 3) metres over the box's silhouette window widened by ``margin``."""
    pan, tilt = angles_from_direction(box.corners() - station)
    span = np.array([np.ptp(pan), np.ptp(tilt)])
    # A step that puts about ``wanted`` shots on the silhouette's bounding window (the box
    # fills most of it), equal in pan and tilt.
    step = math.sqrt(span[0] * span[1] / wanted)
    extra = margin * span.min()

    def lines(low, high):
        count = max(int(round((high - low + 2 * extra) / step)), 1)
        width = (high - low + 2 * extra) / count
        return low - extra + width * (np.arange(count) + 0.5)

    p, t = np.meshgrid(lines(pan.min(), pan.max()), lines(tilt.min(), tilt.max()))
    directions = direction_from_angles(p.ravel(), t.ravel())
    hits = raycast([box, *others], station, directions)
    ranges = hits.range[hits.hit] + rng.normal(0.0, SIGMA, int(hits.hit.sum()))
    return station + ranges[:, None] * directions[hits.hit]


def judge(box, result) -> tuple[bool, bool]:
    """``(gross, off)`` of a fit against the true box."""
    fitted = result.primitive
    truth_axes = np.asarray(box.axes, dtype=float)
    gross = off = False
    for axis, size, size_se, axis_se in zip(
        fitted.axes, fitted.size, result.stderr["size"], result.stderr["axes_deg"], strict=True
    ):
        k = int(np.argmax(np.abs(truth_axes @ axis)))
        true = float(box.size[k])
        error = abs(float(size) - true)
        angle = math.degrees(math.acos(min(1.0, abs(float(truth_axes[k] @ axis)))))
        if math.isfinite(size_se) and error > 5.0 * size_se:
            gross = True
        if angle > 2.0 and angle > 5.0 * axis_se:
            gross = True
        off |= error > 0.25 * true
    return gross, off


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30, help="scenes per cell (default 30)")
    parser.add_argument("--shots", type=int, default=30, help="shots wanted on the box")
    parser.add_argument("--seed", type=int, default=47)
    args = parser.parse_args(argv)
    started = time.perf_counter()
    print(
        f"Command: `python benchmarks/clutter_cuboids.py --trials {args.trials} --shots {args.shots}`"
    )
    print()
    print("| scene | window margin | fits | gross | off > 25% | refused | median shots (on box) |")
    print("|---|---|---|---|---|---|---|")
    totals = np.zeros(4, dtype=int)
    for name in SCENES:
        for margin in MARGINS:
            rng = np.random.default_rng([args.seed, SCENES.index(name), MARGINS.index(margin)])
            counts = np.zeros(4, dtype=int)
            sizes = []
            for _ in range(args.trials):
                box, station, others = scene(name, rng)
                points = shots(box, station, others, margin, args.shots, rng)
                on_box = np.abs(box_distance(box, points)) < 0.01
                sizes.append((len(points), int(on_box.sum())))
                counts[0] += 1
                try:
                    result = fit_points("cuboid", points, sigma=SIGMA, viewpoint=station)
                except FitError:
                    counts[3] += 1
                    continue
                gross, off = judge(box, result)
                counts[1] += gross
                counts[2] += off
            totals += counts
            n, on = np.median(np.array(sizes), axis=0)
            print(
                f"| {name} | {margin:g} | {counts[0]} | {counts[1]} | {counts[2]} | {counts[3]}"
                f" | {n:.0f} ({on:.0f}) |"
            )
    print(f"| all | | {totals[0]} | {totals[1]} | {totals[2]} | {totals[3]} | |")
    print()
    print(f"({time.perf_counter() - started:.0f} s)")
    return 0


def box_distance(box, points: np.ndarray) -> np.ndarray:
    """Signed distance (n,) metres from ``points`` (n, 3) to ``box``'s surface."""
    local = np.abs((points - box.center) @ np.asarray(box.axes).T) - 0.5 * np.asarray(box.size)
    outside = np.linalg.norm(np.maximum(local, 0.0), axis=1)
    return outside + np.minimum(local.max(axis=1), 0.0)


if __name__ == "__main__":
    raise SystemExit(main())
