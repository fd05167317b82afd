"""Cuboid fits from the fewest shots: 7 (the least a cuboid takes) to 15 points.

The accuracy benchmark starts at 20 points. An operator in a hurry takes fewer, and a fit must
then still be right or say it is unsure. This script fits the accuracy benchmark's cuboid
trials (``benchmarks/trials.py``: the same simulated pan-tilt range finder, sections 0.2, 0.4
and 0.6 m, two and three seen faces, the exact silhouette window or the operator's) at 7, 8,
10, 12 and 15 points, clean, with the sensor's sigma and the station, and reports per cell the
median and worst of each trial's worst relative size error (over the three sizes, each against
the true axis nearest it) and of its worst axis error, and the fits refused.

Run: ``python benchmarks/sparse_cuboids.py [--trials 40] [--operator-window] [--out F]``
(about a minute at 40 trials).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import fit_accuracy  # noqa: E402
import trials as trial_maker  # noqa: E402

from asbuilt.errors import AsbuiltError  # noqa: E402
from asbuilt.fit import fit_points  # noqa: E402

POINTS = (7, 8, 10, 12, 15)
SECTIONS = (0.2, 0.4, 0.6)
FACES = (2, 3)


def errors(result, truth) -> tuple[float, float]:
    """The worst relative size error (fraction) and the worst axis error (degrees)."""
    axes, size = result.primitive.axes, result.primitive.size
    size_errors, angles = [], []
    for k in range(3):
        cosines = np.abs(axes @ truth["axes"][k])
        j = int(cosines.argmax())
        size_errors.append(abs(size[j] - truth["size"][k]) / truth["size"][k])
        angles.append(float(np.degrees(np.arccos(min(1.0, cosines[j])))))
    return max(size_errors), max(angles)


def cell(section: float, faces: int, n: int, count: int, operator: bool) -> dict:
    sizes, angles, refused = [], [], 0
    for s in range(count):
        rng = np.random.default_rng([n, faces, int(section * 1000), s])
        trial = trial_maker.cuboid_trial(rng, section, faces, n, operator=operator)
        try:
            result = fit_points(
                "cuboid",
                trial.clean,
                sigma=fit_accuracy.SIGMA_R,
                viewpoint=fit_accuracy.STATION.position,
            )
        except AsbuiltError:
            refused += 1
            continue
        size_error, angle = errors(result, trial.truth)
        sizes.append(size_error)
        angles.append(angle)
    return {"sizes": np.array(sizes), "angles": np.array(angles), "refused": refused}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=40, help="trials per cell (40)")
    parser.add_argument("--operator-window", action="store_true")
    parser.add_argument("--out", type=Path, help="also write the table (Markdown) here")
    args = parser.parse_args(argv)
    window = "operator window" if args.operator_window else "exact silhouette window"
    lines = [
        f"Cuboids from 7-15 points, clean, {window}, {args.trials} trials a cell "
        "(worst size error of each trial, relative; worst axis error, degrees)",
        "",
        "| section m | faces | points | size median % | size worst % | axis median deg "
        "| axis worst deg | refused |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for section in SECTIONS:
        for faces in FACES:
            for n in POINTS:
                c = cell(section, faces, n, args.trials, args.operator_window)
                if c["sizes"].size:
                    figures = (
                        f"{100 * np.median(c['sizes']):.2f} | {100 * c['sizes'].max():.1f} | "
                        f"{np.median(c['angles']):.2f} | {c['angles'].max():.2f}"
                    )
                else:
                    figures = "- | - | - | -"
                lines.append(f"| {section} | {faces} | {n} | {figures} | {c['refused']} |")
    text = "\n".join(lines) + "\n"
    print(text, end="")
    if args.out is not None:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
