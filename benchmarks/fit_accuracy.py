"""Fitting accuracy of sparse pan-tilt range finder scans, against Cramer-Rao bounds and skspatial.

Reproduces the paper's experiment (Kwon et al.: cylinders and cuboids of various sizes, 20-40
points) with a simulated pan-tilt laser range finder (:mod:`asbuilt.sim`): range noise sigma
2 mm, pointing noise 0.01 degree on pan and tilt, objects 3 to 10 m away, the points being the
returns of a raster over the object's visible side (the ideal kinematic chain), thinned evenly to
exactly n points.

Cells
-----
* cylinders: outside diameters 60.3, 114.3, 219.1, 323.8, 609.6 mm x length/diameter 1, 3, 10
  x 20, 30, 40 points; axis at 45-90 degrees to the line of sight; returns on the end caps
  are dropped (a pipe runs on into its fittings);
* spheres: diameters 0.2, 0.5, 1, 3 m x 20, 30, 40 points;
* planes (walls and plates): 0.5 and 3 m wide, incidence 0-60 degrees x 20, 30, 40 points;
* cuboids: sections about 0.2, 0.4, 0.6 m across (each side 0.8-1.2 x that), 2 seen faces (a
  3 m column yawed 25-65 degrees to the line of sight) or 3 seen faces (a 1.2 m pier whose top
  is 20-35 degrees below the sensor) x 20, 30, 40 points.

For each cell: median, 90th percentile and mean (bias) of the errors; for radius, axis, plane
normal and cuboid orientation also the Cramer-Rao bound from the Fisher information of the same
points at the true parameters (``benchmarks/crb.py`` derives it) and RMSE / bound. The bound of a
cell is the RMS of its trials' bounds (the trials' geometries differ). Errors: radius = fitted -
true; axis (normal) = angle between fitted and true axis, sign-free; cuboid orientation = the
rotation angle between the fitted and true frames after matching axes; cuboid sizes relative,
per side.

Raster window: by default the raster is cell-centred over the object's exact angular silhouette
window, so the outer shots fall exactly half a raster step inside the silhouette - the
convention the cuboid fit assumes when it places unseen edges half a step beyond the outermost
points, and therefore optimistic. ``--operator-window`` also fits every trial again with the
raster over an operator's window (:func:`asbuilt.sim.sensor.operator_margins`: each side of the
silhouette window moved out by an independent margin uniform between 0 and one raster step;
shots off the object dropped), where the edge falls anywhere between the last hit and the first
miss. The operator-window twin of a trial starts from the same generator state, so it has the
same object and pose (its noise differs); the exact-window trials are the same with or without
the flag.

Scan session (cuboids, ``--session``): the cuboid trials acquired once more, from the same
generator state (same object and pose), by the product's acquisition algorithm
(``asbuilt.drivers.session.scan_target``, default settings: a raster, fill rasters when too few
shots land, then one edge-bisection pair per silhouette side bisected to 2 mm) over an operator's
window (:func:`session_window`), each shot by the sensor model
(:func:`asbuilt.sim.sensor.fire`). n counts every point on the object, raster, fill and edge
hits alike: the session is asked for about n - 8 raster points and its edge hits make up the
rest (the coarsest edge hits dropped when over n; the raster is never thinned). Outliers as below
(the edge shots, nearest a miss, become them first).

The same trials are fitted again with 20% edge outliers: the fifth of the shots nearest the
silhouette (angular distance to the nearest raster shot that missed the object) become mixed
returns by the sensor model's rule (half land on the background surface 1.5-3 m behind, half
uniformly between object and background). scikit-spatial's ``best_fit`` (Cylinder, Sphere,
Plane; it has no cuboid) runs on the first ``--sk-trials`` trials of each cell, errors and time
per fit side by side.

Run: ``python benchmarks/fit_accuracy.py [--trials 50] [--sk-trials 20] [--operator-window]
[--session] [--quick] [--out F]``.
Times are single-process wall-clock per fit call (``time.perf_counter``).
"""

from __future__ import annotations

import argparse
import copy
import itertools
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from fit_report import (  # noqa: E402
    Cell,
    cuboid_table,
    cylinder_table,
    fmt,
    plane_table,
    summary,
    window_cells_table,
    window_table,
)
from trials import (  # noqa: E402
    LDS,
    NS,
    ODS_MM,
    OPERATOR,
    PLANE_W,
    SECTIONS,
    SESSION,
    SIGMA_R,
    SPHERE_D,
    STATION,
    cuboid_trial,
    cylinder_trial,
    hash_key,
    plane_trial,
    sphere_trial,
    unit,
)

# --------------------------------------------------------------------------- fits under test


def _ours(sensor: bool = True, viewpoint: bool = True):
    """Our fits by kind, called through :func:`asbuilt.fit.fit_points` exactly as the pipeline
    calls them (its checks included: points within the noise of a line, noise wider than the
    sensor's sigma, undetermined fits); ``sensor`` False calls them as for a scan without a
    ``sensor`` block (no sigma, no viewpoint), ``viewpoint`` False as for one whose sensor gives
    ``range_sigma`` but no ``position``."""
    from asbuilt.fit import fit_points

    options = {"sigma": SIGMA_R} if sensor else {}
    if sensor and viewpoint:
        # fit_points passes the viewpoint only to the fits that take one (cylinder, cuboid).
        options["viewpoint"] = STATION.position
    return {
        kind: (lambda points, k=kind: fit_points(k, points, **options))
        for kind in ("cylinder", "sphere", "plane", "cuboid")
    }


def _skspatial():
    try:
        from skspatial.objects import Cylinder, Plane, Sphere
    except ImportError:
        return {}
    return {"cylinder": Cylinder.best_fit, "sphere": Sphere.best_fit, "plane": Plane.best_fit}


def _angle_deg(a, b) -> float:
    c = abs(float(np.dot(unit(a), unit(b))))
    return math.degrees(math.acos(min(1.0, c)))


def _ours_params(kind, result):
    p = result.primitive
    if kind == "cylinder":
        return {"radius": p.radius, "axis": p.axis}
    if kind == "sphere":
        return {"radius": p.radius}
    if kind == "plane":
        return {"normal": p.normal}
    return {"cuboid": p}


def _sk_params(kind, obj):
    if kind == "cylinder":
        vector = np.asarray(obj.vector, float)
        return {"radius": float(obj.radius), "axis": vector}
    if kind == "sphere":
        return {"radius": float(obj.radius)}
    return {"normal": np.asarray(obj.normal, float)}


def cuboid_errors(fitted, truth) -> dict:
    """Relative size errors per true side and the frame rotation angle (degrees).

    Fitted axes are matched to the true ones by the permutation with the largest sum of
    absolute cosines (a fit turned near 45 degrees still gets its sizes compared, on the
    nearest assignment, rather than none).
    """
    dots = fitted.axes @ truth["axes"].T  # fitted rows x true rows
    match = max(
        (np.array(order) for order in itertools.permutations(range(3))),
        key=lambda order: float(np.abs(dots[order, np.arange(3)]).sum()),
    )
    signs = np.sign(dots[match, np.arange(3)])
    matched = signs[:, None] * fitted.axes[match]
    if np.linalg.det(matched) < 0:
        worst = int(np.argmin(np.abs(dots[match, np.arange(3)])))
        matched[worst] *= -1
    rot = matched @ truth["axes"].T
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(rot) - 1) / 2))))
    size_rel = (fitted.size[match] - truth["size"]) / truth["size"]
    return {"size_rel": size_rel, "orientation": angle}


def run_fit(function, kind, points, is_ours):
    start = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = function(points)
    except Exception as exc:  # every failure is counted, whatever raised it
        return None, time.perf_counter() - start, type(exc).__name__
    elapsed = time.perf_counter() - start
    params = _ours_params(kind, out) if is_ours else _sk_params(kind, out)
    return params, elapsed, None


def record(cell: Cell, kind, params, truth):
    if kind in ("cylinder", "sphere"):
        cell.add("radius", params["radius"] - truth["radius"])
    if kind == "cylinder":
        cell.add("axis", _angle_deg(params["axis"], truth["axis"]))
    if kind == "plane":
        cell.add("normal", _angle_deg(params["normal"], truth["normal"]))
    if kind == "cuboid":
        err = cuboid_errors(params["cuboid"], truth)
        for k, name in enumerate(("size_a", "size_b", "size_len")):
            cell.add(name, abs(err["size_rel"][k]))
        cell.add("orientation", err["orientation"])


def _twin(rng):
    """A generator in ``rng``'s current state (``rng`` itself is left untouched)."""
    twin = np.random.Generator(type(rng.bit_generator)())
    twin.bit_generator.state = copy.deepcopy(rng.bit_generator.state)
    return twin


def run_cells(
    kind, cells, make, trials, sk_trials, ours, sk, seed, progress, operator=False, session=False
):
    """Run every cell; return {cell key: {(estimator, version): Cell}}.

    Versions: ``"clean"`` and ``"outliers"`` (exact silhouette window) and, with ``operator``,
    the same trials shot over an operator's window, ``"clean@operator"`` and
    ``"outliers@operator"`` (ours only); with ``session`` (cuboids: ``make`` takes
    ``session=True``) the same objects acquired by the scan session's algorithm over an
    operator's window, ``"clean@session"`` and ``"outliers@session"`` (ours only). Each twin
    starts from the trial's generator state, so the plain versions do not depend on the flags.
    """
    results = {}
    for key in cells:
        rng = np.random.default_rng([seed, hash_key(kind, key)])
        per = {}
        for t in range(trials):
            twin = _twin(rng) if operator else None
            session_twin = _twin(rng) if session else None
            versions = []
            trial = make(rng, *key)
            versions.append((trial, ("clean", trial.clean), ("outliers", trial.dirty)))
            if operator:
                op = make(twin, *key, operator=True)
                versions.append(
                    (op, ("clean" + OPERATOR, op.clean), ("outliers" + OPERATOR, op.dirty))
                )
            if session:
                se = make(session_twin, *key, session=True)
                versions.append(
                    (se, ("clean" + SESSION, se.clean), ("outliers" + SESSION, se.dirty))
                )
            for trial, *data in versions:
                _fit_trial(per, kind, trial, data, t, ours, sk, sk_trials)
        results[key] = per
        progress(kind, key)
    return results


def _fit_trial(per, kind, trial, data, t, ours, sk, sk_trials):
    """Fit one trial's point sets (``data``: (version, points) pairs) into ``per``."""
    for version, pts in data:
        estimators = [("ours", ours, True)]
        if sk is not None and t < sk_trials and "@" not in version:
            estimators.append(("skspatial", sk, False))
        for name, function, is_ours in estimators:
            cell = per.setdefault((name, version), Cell())
            cell.trials += 1
            params, elapsed, failure = run_fit(function, kind, pts, is_ours)
            cell.times.append(elapsed)
            if failure:
                cell.failures += 1
                continue
            record(cell, kind, params, trial.truth)
            for bname, value in trial.bound.items():
                if bname != "faces":
                    cell.bound(bname, value)
            if version.startswith("outliers") and trial.retained_bound:
                for bname, value in trial.retained_bound.items():
                    if bname != "faces":
                        cell.bound("retained_" + bname, value)


# --------------------------------------------------------------------------- main


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=50, help="trials per cell (default 50)")
    parser.add_argument(
        "--sk-trials",
        type=int,
        default=20,
        help="trials per cell also fitted by skspatial (default 20)",
    )
    parser.add_argument("--quick", action="store_true", help="a smoke run: few cells, 5 trials")
    parser.add_argument("--seed", type=int, default=2004)
    parser.add_argument(
        "--only",
        choices=("cylinder", "sphere", "plane", "cuboid"),
        action="append",
        help="run only these kinds",
    )
    parser.add_argument(
        "--operator-window",
        action="store_true",
        help="also fit every trial shot over an operator's window (silhouette window enlarged by "
        "0-1 raster step per side, at random) and report both windows",
    )
    parser.add_argument(
        "--session",
        action="store_true",
        help="also acquire every cuboid trial with the scan session's algorithm (raster, fill, "
        "edge bisection; asbuilt.drivers.session) over an operator's window and report it",
    )
    parser.add_argument(
        "--no-sensor",
        action="store_true",
        help="call our fits as for a scan without a sensor block: no range sigma (the fits "
        "estimate the noise) and no viewpoint",
    )
    parser.add_argument(
        "--no-viewpoint",
        action="store_true",
        help="call our fits with the range sigma but no viewpoint (a sensor block without "
        "position)",
    )
    parser.add_argument("--out", default=None, help="write the markdown here instead of stdout")
    args = parser.parse_args(argv)

    trials = 5 if args.quick else args.trials
    sk_trials = min(trials, 3 if args.quick else args.sk_trials)
    ods, lds, ns = ((114.3, 323.8), (3,), (30,)) if args.quick else (ODS_MM, LDS, NS)
    spheres = (0.5,) if args.quick else SPHERE_D
    planes = (3.0,) if args.quick else PLANE_W
    sections = (0.4,) if args.quick else SECTIONS
    kinds = args.only or ["cylinder", "sphere", "plane", "cuboid"]
    ours = _ours(sensor=not args.no_sensor, viewpoint=not args.no_viewpoint)
    sk = _skspatial()
    started = time.perf_counter()

    def progress(kind, key):
        print(f"  {kind} {key} done ({time.perf_counter() - started:.0f} s)", file=sys.stderr)

    plan = {
        "cylinder": ([(od, ld, n) for od in ods for ld in lds for n in ns], cylinder_trial),
        "sphere": ([(d, n) for d in spheres for n in ns], sphere_trial),
        "plane": ([(w, n) for w in planes for n in ns], plane_trial),
        "cuboid": ([(s, f, n) for s in sections for f in (2, 3) for n in ns], cuboid_trial),
    }
    results, missing = {}, []
    for kind in kinds:
        if ours.get(kind) is None:
            missing.append(kind)
            continue
        cells, make = plan[kind]
        results[kind] = run_cells(
            kind,
            cells,
            make,
            trials,
            sk_trials,
            ours[kind],
            sk.get(kind),
            args.seed,
            progress,
            operator=args.operator_window,
            session=args.session and kind == "cuboid",
        )
    elapsed = time.perf_counter() - started

    command = "python benchmarks/fit_accuracy.py" + (
        " " + " ".join(argv if argv is not None else sys.argv[1:])
        if (argv if argv is not None else sys.argv[1:])
        else ""
    )
    out = [
        f"Command: `{command}` ({elapsed:.0f} s on this machine; {trials} trials per cell, "
        f"skspatial on the first {sk_trials} of each cell{'' if sk else ' - not installed'}).",
        "",
        "Simulated pan-tilt range finder: range sigma 2 mm, pointing sigma 0.01 deg (pan and "
        "tilt), objects 3-10 m away, cell-centred raster over the visible side thinned to exactly "
        "n points; 'exact window': the raster over the object's exact angular silhouette window, "
        "'operator window': over that window enlarged by a random 0-1 raster step per side "
        "(same objects). "
        "Errors in mm and degrees; medians and p90 of absolute errors, bias = mean signed error; "
        "CRB = Cramer-Rao bound (RMS over the cell's trials).",
        "",
    ]
    if args.no_viewpoint and not args.no_sensor:
        out += [
            "Our fits called with the range sigma but no viewpoint (`--no-viewpoint`).",
            "",
        ]
    if args.no_sensor:
        out += [
            "Our fits called without a sensor (`--no-sensor`): no range sigma (each fit "
            "estimates the noise from its residuals) and no viewpoint.",
            "",
        ]
    if missing:
        out += [f"Not run (fit not in this tree yet): {', '.join(missing)}.", ""]
    out += ["#### Targets", "", summary(results), ""]
    if args.operator_window:
        out += [
            "#### Exact silhouette window vs operator window (ours; per-cell figures, median and "
            "worst cell)",
            "",
            window_table(results),
            "",
            "Clean cylinder, sphere and plane cells above the 99% chi-square limit of RMSE / CRB "
            "in either window (cell: OD mm / L/D / n, D m / n or width m / n):",
            "",
            window_cells_table(results),
            "",
        ]
    titles = {
        "cylinder": "Cylinders",
        "sphere": "Spheres",
        "plane": "Planes (walls, plates)",
        "cuboid": "Cuboids (columns, beams, piers)",
    }
    versions = [
        ("clean", "clean"),
        ("outliers", "with 20% edge outliers (CRB: of the shots the outliers leave)"),
    ]
    if args.operator_window:
        versions = [(v, f"exact window, {label}") for v, label in versions]
    for kind in ("cylinder", "sphere", "plane", "cuboid"):
        if kind not in results:
            continue
        shown = versions
        if args.operator_window and kind == "cuboid":
            # the window matters to the cuboid's unseen edges: its tables for both windows
            shown = versions + [
                ("clean" + OPERATOR, "operator window, clean"),
                ("outliers" + OPERATOR, "operator window, with 20% edge outliers"),
            ]
        if args.session and kind == "cuboid":
            shown = shown + [
                ("clean" + SESSION, "scan session over an operator window, clean"),
                (
                    "outliers" + SESSION,
                    "scan session over an operator window, with 20% edge outliers",
                ),
            ]
        for version, label in shown:
            out += [f"#### {titles[kind]}, {label}", ""]
            if kind in ("cylinder", "sphere"):
                out.append(cylinder_table(results[kind], kind, version))
            elif kind == "plane":
                out.append(plane_table(results[kind], version))
            else:
                out.append(cuboid_table(results[kind], version))
            out.append("")
    out += [
        "#### Time per fit (all cells, clean and outliers, exact window)",
        "",
        "| kind | ours median ms | ours p90 ms | skspatial median ms | skspatial p90 ms |",
        "|---|---|---|---|---|",
    ]
    for kind, res in results.items():
        t = (
            np.concatenate(
                [
                    np.asarray(c.times)
                    for per in res.values()
                    for (e, v), c in per.items()
                    if e == "ours" and "@" not in v
                ]
            )
            * 1e3
        )
        s = [
            np.asarray(c.times)
            for per in res.values()
            for (e, _), c in per.items()
            if e == "skspatial"
        ]
        s = np.concatenate(s) * 1e3 if s else np.array([])
        out.append(
            f"| {kind} | {fmt(np.median(t))} | {fmt(np.percentile(t, 90))} | "
            f"{fmt(np.median(s)) if s.size else '-'} | "
            f"{fmt(np.percentile(s, 90)) if s.size else '-'} |"
        )
    text = "\n".join(out) + "\n"
    if args.out:
        Path(args.out).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
