"""Insulated pipes: how often the pipe inside the cladding snaps to its true size.

Single lagged pipes of NPS 2 to 12 (ASME B36.10M ODs from the shipped catalog) under 25, 50,
75 and 100 mm of insulation are scanned by the simulator (``asbuilt.sim``: a scene of one pipe
clad in ``insulation``, the beams hit the cladding) from one station 3 to 10 m away (range
sigma 2 mm, pointing sigma 0.01 degree, 2% dropouts, mixed returns at the silhouette edges),
with 20, 30 or 40 shots wanted on the pipe. Each pipe is 2 m long (at least 8 cladding
diameters, up to 4.2 m), horizontal, 0.5 to 3 m above the floor, turned within 45 degrees of
square to the line of sight. The real fit (``asbuilt.fit.fit``) runs once per trial, then
``asbuilt.merge.merge_model`` three times, with the scan object's insulation:

* given right (the scene's thickness): the share snapped to the true NPS (``right``), to
  another size (``wrong``), or left open between two sizes (``ambiguous``) or with none near
  (``no size``); an open size is flagged, a wrong one is not;
* given 3 mm too thick: the shares right and wrong (an error ``e`` in the thickness moves the
  pipe's OD by ``2e``, here 6 mm smaller);
* not given (the cladding taken for the pipe, the contrast): the shares right and wrong, and
  what it most often came out as (a size, or ``open``);

and the OD error of the pipe before snapping (the fitted cladding OD less twice the given
thickness, less the true OD): mean and standard deviation, mm.

Run: ``python benchmarks/insulated_pipes.py [--trials 100] [--seed 1]`` (about 3.5 minutes of
one core at the default 100 trials a cell, 8,400 pipes; ``--sizes 4 6``, ``--thicknesses 50``
or ``--points 30`` for part of the grid); it prints Markdown for benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from asbuilt.catalog import load_catalog  # noqa: E402
from asbuilt.errors import AsbuiltError  # noqa: E402
from asbuilt.fit import fit  # noqa: E402
from asbuilt.fit.result import FitReport, ObjectFit  # noqa: E402
from asbuilt.merge import merge_model  # noqa: E402
from asbuilt.scan import loads_scan  # noqa: E402
from asbuilt.sim.scene import scene_from_dict  # noqa: E402
from asbuilt.sim.simulate import simulate_scan  # noqa: E402

SIZES = ("2", "3", "4", "6", "8", "10", "12")
THICKNESSES_MM = (25, 50, 75, 100)
POINTS = (20, 30, 40)
SIGMA = 0.002
OFF = 0.003  # the thickness error of the contrast column, metres
STATION = np.array([0.0, 0.0, 1.5])


def scene_doc(od: float, thickness: float, n_points: int, rng) -> dict:
    """A scene of one insulated pipe (metres) at a random place 3-10 m from the station."""
    distance = rng.uniform(3.0, 10.0)
    bearing = rng.uniform(-np.pi / 3, np.pi / 3)  # within the instrument's usual sweep
    centre = np.array([distance * np.sin(bearing), distance * np.cos(bearing), 0.0])
    centre[2] = rng.uniform(0.5, 3.0)
    square = np.array([np.cos(bearing), -np.sin(bearing), 0.0])  # square to the sight line
    turn = rng.uniform(-np.pi / 4, np.pi / 4)
    c, s = np.cos(turn), np.sin(turn)
    axis = np.array([c * square[0] - s * square[1], s * square[0] + c * square[1], 0.0])
    length = max(2.0, 8 * (od + 2 * thickness))
    return {
        "format": "asbuilt-scene",
        "units": "m",
        "stations": [
            {
                "id": "S1",
                "position": STATION.tolist(),
                "range_sigma": SIGMA,
                "angular_sigma_deg": 0.01,
                "dropout": 0.02,
                "mixed_return": 0.5,
            }
        ],
        "objects": [
            {
                "id": "P1",
                "kind": "cylinder",
                "insulation": thickness,
                "points": n_points,
                "geometry": {
                    "type": "cylinder",
                    "start": (centre - 0.5 * length * axis).tolist(),
                    "end": (centre + 0.5 * length * axis).tolist(),
                    "od": od,
                },
            },
            {"id": "floor", "scan": False, "geometry": {"type": "ground"}},
        ],
    }


def with_insulation(report: FitReport, thickness: float) -> FitReport:
    """The same fits with every scan object's insulation set to ``thickness`` (metres)."""
    objects = tuple(dataclasses.replace(o, insulation=thickness) for o in report.scan.objects)
    scan = dataclasses.replace(report.scan, objects=objects)
    fits = tuple(
        ObjectFit(objects[k], item.result, item.requested) for k, item in enumerate(report.fits)
    )
    return FitReport(scan=scan, fits=fits)


def snapped(report: FitReport):
    """The merged pipe's nominal size (None when left open), the snap's status and the pipe's
    OD before snapping (m)."""
    (pipe,) = [c for c in merge_model(report).components if c.type in ("pipe", "cylinder")]
    snap = pipe.snap or {}
    return pipe.nominal, snap.get("status"), snap.get("od_fit")


def run_trial(od, thickness, n_points, rng):
    """One trial's outcomes, or None when the fit was refused."""
    scene = scene_from_dict(scene_doc(od, thickness, n_points, rng))
    doc = simulate_scan(scene, seed=int(rng.integers(2**31)))  # each trial its own noise
    scan = loads_scan(json.dumps(doc))
    try:
        report = fit(scan, strict=True)
    except AsbuiltError:
        return None
    given = snapped(with_insulation(report, thickness))
    off = snapped(with_insulation(report, thickness + OFF))
    bare = snapped(with_insulation(report, 0.0))
    return given, off, bare


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=100, help="pipes per cell (default 100)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--sizes", nargs="+", default=list(SIZES), help="NPS sizes")
    parser.add_argument(
        "--thicknesses", nargs="+", type=float, default=list(THICKNESSES_MM), help="mm"
    )
    parser.add_argument("--points", nargs="+", type=int, default=list(POINTS))
    args = parser.parse_args(argv)
    catalog = load_catalog("asme-b36.10m")
    rng = np.random.default_rng(args.seed)
    rows = []
    started = time.perf_counter()
    totals = defaultdict(list)
    for nps in args.sizes:
        size = catalog.size(nps)
        for t_mm in args.thicknesses:
            t = t_mm / 1000.0
            for n in args.points:
                cell = defaultdict(list)
                instead = Counter()
                for _ in range(args.trials):
                    out = run_trial(size.od, t, n, rng)
                    if out is None:
                        cell["failed"].append(1)
                        continue
                    (got, status, od_fit), (off, _, _), (bare, _, _) = out
                    cell["right"].append(got == size.nominal)
                    cell["wrong"].append(got is not None and got != size.nominal)
                    cell["ambiguous"].append(got is None and status == "ambiguous")
                    cell["nosize"].append(got is None and status != "ambiguous")
                    cell["off_right"].append(off == size.nominal)
                    cell["off_wrong"].append(off is not None and off != size.nominal)
                    cell["bare_right"].append(bare == size.nominal)
                    cell["bare_wrong"].append(bare is not None and bare != size.nominal)
                    instead[bare if bare is not None else "open"] += 1
                    if od_fit is not None:
                        cell["od_err"].append((od_fit - size.od) * 1000)
                rows.append((nps, t_mm, n, cell, instead))
                for key in (
                    "right",
                    "wrong",
                    "ambiguous",
                    "nosize",
                    "off_right",
                    "off_wrong",
                    "bare_right",
                    "bare_wrong",
                ):
                    totals[key].extend(cell[key])
                totals["failed"].extend(cell["failed"])
    elapsed = time.perf_counter() - started

    def pct(values):
        return f"{100 * np.mean(values):.0f}%" if values else "-"

    print(
        f"Simulated single insulated pipes, sigma {SIGMA * 1000:.0f} mm, 3-10 m, "
        f"{args.trials} trials per cell, seed {args.seed}; {elapsed:.0f} s.\n"
    )
    print(
        "| NPS | insulation (mm) | shots | right | wrong | ambiguous | no size | "
        "3 mm off: right / wrong | not given: right / wrong (most often) | "
        "OD error mean / sd (mm) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for nps, t_mm, n, cell, instead in rows:
        errs = np.array(cell["od_err"])
        err = f"{errs.mean():+.1f} / {errs.std(ddof=1):.1f}" if errs.size > 1 else "-"
        usual = instead.most_common(1)[0][0] if instead else "-"
        usual = f"NPS {usual}" if usual not in ("-", "open") else "open"
        failed = f" ({len(cell['failed'])} fits refused)" if cell["failed"] else ""
        print(
            f"| {nps} | {t_mm:g} | {n} | {pct(cell['right'])}{failed} | {pct(cell['wrong'])} | "
            f"{pct(cell['ambiguous'])} | {pct(cell['nosize'])} | {pct(cell['off_right'])} / "
            f"{pct(cell['off_wrong'])} | {pct(cell['bare_right'])} / {pct(cell['bare_wrong'])} "
            f"({usual}) | {err} |"
        )
    print(
        f"\nAll cells: right {pct(totals['right'])}, wrong {pct(totals['wrong'])}, ambiguous "
        f"{pct(totals['ambiguous'])}, no size {pct(totals['nosize'])}; thickness 3 mm off: right "
        f"{pct(totals['off_right'])}, wrong {pct(totals['off_wrong'])}; not given: right "
        f"{pct(totals['bare_right'])}, wrong {pct(totals['bare_wrong'])}; fits refused: "
        f"{len(totals['failed'])}."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
