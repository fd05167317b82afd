"""Merging accuracy on simulated spools: snap shares and centreline end-point error.

Spools of three pipes (along x, along y, then a vertical riser; two long-radius elbows) of
NPS 2 to 24, turned by a random angle about the vertical, are "scanned" from one station:
each pipe gets N points on its visible side (a raster of 4 columns within 52 degrees of the
side facing the station and N/4 rows evenly along the straight part, as the pan-tilt raster
does), each moved along its ray by Gaussian range noise of
sigma = 2 mm. The real fit (``asbuilt.fit.fit_points("cylinder", ...)``) and
``asbuilt.merge.merge_model`` then build the model, which is compared with the truth:

* right / wrong / ambiguous / no-size: share of pipes whose merged nominal size is the true
  one, another one, left open between two, or none (the target is 0% wrong);
* the same shares when each pipe is snapped alone (no joint estimate), for comparison;
* end-point error: distance from each merged pipe end at an elbow to the true elbow tangent
  point (mean and maximum, mm; the target is under 5 mm).

It also times ``merge_model`` on 1,000 synthetic pipes (250 four-pipe spools with three
elbows each, fits built directly), the median of three runs.

Run: ``python benchmarks/merge_accuracy.py [--trials 10] [--seed 1]`` (under a minute on two
cores); it prints Markdown for benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from asbuilt.catalog import load_catalog  # noqa: E402
from asbuilt.errors import FitError  # noqa: E402
from asbuilt.fit import fit_points  # noqa: E402
from asbuilt.fit.result import FitReport, ObjectFit  # noqa: E402
from asbuilt.merge import merge_model  # noqa: E402
from asbuilt.merge.snap import snap_diameter  # noqa: E402
from asbuilt.scan.model import Scan, ScanObject, Sensor  # noqa: E402
from asbuilt.tolerances import DEFAULT_TOLERANCES  # noqa: E402

SIZES = ("2", "3", "4", "6", "8", "10", "12", "16", "20", "24")
POINTS = (20, 30, 40)
SIGMA = 0.002


def spool_truth(nps: str, yaw: float):
    """Corner points (4, 3) m of a spool for NPS ``nps`` and its bend radius, turned by yaw."""
    catalog = load_catalog("asme-b36.10m")
    size = catalog.size(nps)
    radius = catalog.fitting(size).dims["elbow90_lr"]
    scale = max(1.0, 8 * size.od)  # keep pipes several diameters long
    corners = np.array([[0, 0, 0], [3.0, 0, 0], [3.0, 2.5, 0], [3.0, 2.5, 2.0]]) * scale
    c, s = np.cos(yaw), np.sin(yaw)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    return corners @ rot.T, size, radius


def straight_parts(corners, radius):
    """True pipe segments between elbow tangent points, list of (start, end)."""
    parts = []
    for k in range(3):
        a, b = corners[k], corners[k + 1]
        d = (b - a) / np.linalg.norm(b - a)
        start = a + (radius * d if k > 0 else 0)
        end = b - (radius * d if k < 2 else 0)
        parts.append((start, end))
    return parts


def sample_pipe(start, end, od, n, station, rng, margin=0.03):
    """n noisy points (n, 3) m on the side of a pipe facing ``station``.

    Like the pan-tilt raster: 4 columns across the visible side and rows evenly spread along
    the pipe from ``margin`` to ``length - margin`` (each shot jittered by a tenth of a row).
    """
    axis = (end - start) / np.linalg.norm(end - start)
    length = np.linalg.norm(end - start)
    rows = int(np.ceil(n / 4))
    row_t = np.linspace(margin, length - margin, rows)
    spacing = (length - 2 * margin) / max(rows - 1, 1)
    t = np.repeat(row_t, 4)[:n] + rng.normal(0, 0.1 * spacing, n)
    t = np.clip(t, margin, length - margin)
    centres = start + t[:, None] * axis
    to_station = station - centres
    facing = to_station - (to_station @ axis)[:, None] * axis
    facing /= np.linalg.norm(facing, axis=1)[:, None]
    side = np.cross(axis, facing)
    columns = np.radians(np.array([-52.5, -17.5, 17.5, 52.5]))
    phi = np.tile(columns, rows)[:n] + rng.normal(0, np.radians(3), n)
    normals = np.cos(phi)[:, None] * facing + np.sin(phi)[:, None] * side
    surface = centres + 0.5 * od * normals
    rays = surface - station
    rays /= np.linalg.norm(rays, axis=1)[:, None]
    return surface + rng.normal(0, SIGMA, n)[:, None] * rays


def run_trial(nps, n_points, rng):
    corners, size, radius = spool_truth(nps, rng.uniform(0, 2 * np.pi))
    centre = corners.mean(axis=0)
    away = np.array([1.0, -1.0, 0.3])
    station = centre + (5.0 + 6 * size.od) * away / np.linalg.norm(away)
    parts = straight_parts(corners, radius)
    objects, fits = [], []
    for k, (a, b) in enumerate(parts):
        pts = sample_pipe(a, b, size.od, n_points, station, rng)
        obj = ScanObject(id=f"P{k + 1}", kind="cylinder", points=pts, index=k)
        try:
            result = fit_points("cylinder", pts, sigma=SIGMA)
        except FitError:
            return None
        objects.append(obj)
        fits.append(ObjectFit(obj, result, "cylinder"))
    scan = Scan(units="m", objects=tuple(objects), sensor=Sensor(range_sigma=SIGMA))
    report = FitReport(scan=scan, fits=tuple(fits))
    model = merge_model(report)
    return report, model, parts, size


def time_thousand_pipes(rng) -> tuple[float, int]:
    """Median wall time (s) of merge_model on 1,000 pipes, and the number of elbows built."""
    from asbuilt.fit.result import FitResult
    from asbuilt.primitives import Cylinder

    objects, fits = [], []
    for s in range(250):
        origin = np.array([(s % 16) * 8.0, (s // 16) * 8.0, 0.0])
        corners = origin + np.array([[0, 0, 0], [3, 0, 0], [3, 3, 0], [3, 3, 2.5], [6, 3, 2.5]])
        for k in range(4):
            a, b = corners[k], corners[k + 1]
            d = (b - a) / np.linalg.norm(b - a)
            a = a + (0.19 * d if k else 0) + rng.normal(0, 0.002, 3)
            b = b - 0.19 * d + rng.normal(0, 0.002, 3)
            axis = (b - a) / np.linalg.norm(b - a)
            cyl = Cylinder(
                (a + b) / 2, axis, 0.05715 + rng.normal(0, 0.0005), float(np.linalg.norm(b - a))
            )
            obj = ScanObject(
                id=f"S{s}P{k}", kind="cylinder", points=np.zeros((4, 3)), index=len(objects)
            )
            res = FitResult(
                cyl, np.zeros(4), np.ones(4, bool), {"radius": 0.0005}, SIGMA, "sensor", "synthetic"
            )
            objects.append(obj)
            fits.append(ObjectFit(obj, res, "cylinder"))
    report = FitReport(Scan(units="m", objects=tuple(objects)), tuple(fits))
    times = []
    for _ in range(3):
        started = time.perf_counter()
        model = merge_model(report)
        times.append(time.perf_counter() - started)
    elbows = sum(c.type == "elbow" for c in model.components)
    return float(np.median(times)), elbows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=10, help="spools per size and count")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--sigma-mm",
        type=float,
        default=2.0,
        help="range noise in mm (default 2; the issue's targets are at 2)",
    )
    parser.add_argument("--no-timing", action="store_true", help="skip the 1,000-pipe timing")
    args = parser.parse_args(argv)
    global SIGMA
    SIGMA = args.sigma_mm / 1000.0
    rng = np.random.default_rng(args.seed)
    catalog = load_catalog("asme-b36.10m")
    stats = defaultdict(lambda: defaultdict(list))
    started = time.perf_counter()
    for nps in SIZES:
        for n in POINTS:
            cell = stats[(nps, n)]
            for _ in range(args.trials):
                out = run_trial(nps, n, rng)
                if out is None:
                    cell["fit_failed"].append(1)
                    continue
                report, model, parts, size = out
                pipes = {c.sources[0]: c for c in model.components if c.type == "pipe"}
                for k, item in enumerate(report.fits):
                    comp = pipes[item.object.id]
                    status = comp.snap["status"]
                    cell["right"].append(comp.nominal == size.nominal)
                    cell["wrong"].append(comp.nominal is not None and comp.nominal != size.nominal)
                    cell["ambiguous"].append(status == "ambiguous")
                    cell["nosize"].append(status == "no-size")
                    cyl = item.result.primitive
                    alone = snap_diameter(
                        2 * cyl.radius,
                        2 * item.result.stderr["radius"],
                        catalog,
                        tolerance=DEFAULT_TOLERANCES.diameter_tolerance,
                    )
                    got = alone.size.nominal if alone.size else None
                    cell["alone_right"].append(got == size.nominal)
                    cell["alone_wrong"].append(got is not None and got != size.nominal)
                    # end points at elbows against the true tangent points
                    start, end = parts[k]
                    g = comp.geometry
                    ends = (g.start, g.end)  # the fit's axis sense is arbitrary
                    for truth, wanted in ((start, k > 0), (end, k < 2)):
                        if wanted:
                            cell["end_err"].append(min(np.linalg.norm(e - truth) for e in ends))
    elapsed = time.perf_counter() - started

    def pct(values):
        return f"{100 * np.mean(values):.0f}%" if values else "-"

    print(
        f"Simulated spools: 3 pipes + 2 LR elbows, sigma {SIGMA * 1000:.0f} mm, "
        f"{args.trials} spools per cell, seed {args.seed}; {elapsed:.0f} s.\n"
    )
    print(
        "| NPS | points/pipe | right (joint) | wrong (joint) | ambiguous | no size | "
        "right (alone) | wrong (alone) | end error mean / max (mm) |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    totals = defaultdict(list)
    for nps in SIZES:
        for n in POINTS:
            c = stats[(nps, n)]
            errs = np.array(c["end_err"]) * 1000
            err = f"{errs.mean():.1f} / {errs.max():.1f}" if errs.size else "-"
            print(
                f"| {nps} | {n} | {pct(c['right'])} | {pct(c['wrong'])} | "
                f"{pct(c['ambiguous'])} | {pct(c['nosize'])} | {pct(c['alone_right'])} | "
                f"{pct(c['alone_wrong'])} | {err} |"
            )
            for key in ("right", "wrong", "alone_right", "alone_wrong", "end_err"):
                totals[
                    (key, n >= 20 and float(load_catalog("asme-b36.10m").size(nps).nps) >= 3)
                ].extend(c[key])
            totals[("fit_failed", True)].extend(c["fit_failed"])
    big = {k[0]: v for k, v in totals.items() if k[1]}
    errs = np.array(big["end_err"]) * 1000
    print(
        f"\nNPS 3 and up: right {pct(big['right'])} (alone {pct(big['alone_right'])}), "
        f"wrong {pct(big['wrong'])} (alone {pct(big['alone_wrong'])}), end error mean "
        f"{errs.mean():.1f} mm, 95th percentile {np.percentile(errs, 95):.1f} mm, max "
        f"{errs.max():.1f} mm; fits failed: {len(big.get('fit_failed', []))}."
    )
    if args.no_timing:
        return 0
    seconds, elbows = time_thousand_pipes(rng)
    print(
        f"\nmerge_model on 1,000 pipes (250 spools, {elbows} elbows built): "
        f"{seconds:.2f} s (median of 3)."
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
