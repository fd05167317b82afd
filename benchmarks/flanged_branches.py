"""Flanged tee branches 1.5 radii long pointing at the station: the cylinder fit of the branch.

The scenes are the tests' own (``tests/fit/test_cylinder_others.py``, ``asbuilt.sim.raycast``):
a horizontal header 6 m away, a closed (flanged) branch off it toward the station tilted 40
degrees off the line of sight, a raster over the branch's silhouette window with about 30
shots on it, range noise 2 mm. Each scene is fitted twice: the branch's own shots (side and
flange face), and every shot in the window (the header's too). A fit is right when its radius
is within 10% of the branch's; the table also counts refusals and the wrong fits whose stated
radius error is under a tenth of their error (confidently wrong).

Run: ``python benchmarks/flanged_branches.py --seeds 8`` (about half a minute).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from asbuilt.errors import FitError
from asbuilt.fit import fit_points

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import _test_modules  # noqa: E402

#: (header radius, branch radius), metres: NPS 12/4, 8/4, 16/6, 12/2, 24/8.
PAIRS = [(0.1619, 0.05715), (0.1096, 0.0572), (0.2191, 0.0841), (0.1619, 0.0302), (0.3048, 0.1096)]


def _scenes_module():
    """The tests' tee and raster, loaded from the checkout (the tests are not installed)."""
    return _test_modules.load("fit/test_cylinder_others.py", "tee_scenes")


def _outcome(points, scenes, branch: float) -> str:
    try:
        fit = fit_points("cylinder", points, sigma=scenes.SIGMA, viewpoint=scenes.STATION)
    except FitError:
        return "refused"
    error = abs(fit.primitive.radius - branch)
    if error <= 0.1 * branch:
        return "right"
    return "confidently wrong" if fit.stderr["radius"] < 0.1 * error else "wrong"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8, help="scenes per size pair")
    args = parser.parse_args(argv)
    scenes = _scenes_module()
    kinds = ("right", "wrong", "confidently wrong", "refused")
    print("| header / branch OD mm | shots | " + " | ".join(kinds) + " |")
    print("|---|---|" + "---|" * len(kinds))
    for header, branch in PAIRS:
        for which in ("branch alone", "whole window"):
            counts = dict.fromkeys(kinds, 0)
            for seed in range(args.seeds):
                points, on = scenes._shoot(scenes._tee(header, branch, seed), seed)
                chosen = points[on] if which == "branch alone" else points
                counts[_outcome(chosen, scenes, branch)] += 1
            cells = " | ".join(str(counts[kind]) for kind in kinds)
            print(f"| {2000 * header:.1f} / {2000 * branch:.1f} | {which} | {cells} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
