"""Cuboid fit time alone, on the trials of ``benchmarks/fit_accuracy.py``.

The accuracy benchmark times every fit inside a long run that also simulates the scans; this
script generates the same cuboid trials first (same seed, same cells: every section, two and
three seen faces) and then times only the fit calls (through :func:`asbuilt.fit.fit_points`,
as the pipeline calls them, with the range sigma), with and without the viewpoint, clean and
with 20% edge outliers, repeated, so the figure can be checked on its own.

Run: ``python benchmarks/cuboid_speed.py [--points 40] [--trials 50] [--repeat 3]``; the
medians printed are those of ``cylinder_speed.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import cylinder_speed  # noqa: E402
import fit_accuracy  # noqa: E402

#: Seen faces of the accuracy benchmark's cuboid cells (a column side-on, a pier from above).
FACES = (2, 3)


def trials(points: int, count: int, seed: int) -> list:
    """The accuracy benchmark's cuboid trials with ``points`` shots, every section and face
    count."""
    out = []
    for section in fit_accuracy.SECTIONS:
        for faces in FACES:
            key = (section, faces, points)
            rng = np.random.default_rng([seed, fit_accuracy.hash_key("cuboid", key)])
            out.extend(fit_accuracy.cuboid_trial(rng, *key) for _ in range(count))
    return out


def main(argv=None) -> int:
    return cylinder_speed.run("cuboid", trials, __doc__, argv)


if __name__ == "__main__":
    raise SystemExit(main())
