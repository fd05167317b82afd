"""One column seen from two stations: how often the two linked views are fused, and how well
the fused box measures the sizes no single station can.

A station sees at most two sides of a column, so one view alone bounds its far sizes only by
the extent of its shots. Two linked ``cuboid`` objects of one box scanned from different
stations are fitted as one (``asbuilt.fit._cuboid_stations``, docs/fitting.md "One box seen
from two stations"). This script simulates that: a column (section ``s`` x ``s`` * U(0.8, 1.2),
3 m high, standing on the ground, turned at random about the vertical), two stations 3 to 10 m
away at 1-2 m height, the second one either across the column (150-210 degrees round from the
first) or beside it (70-110 degrees round), each shooting its raster over the exact silhouette
window (or an operator's window with ``--operator-window``) with the simulated pan-tilt range
finder of ``asbuilt.sim`` (range sigma 2 mm, pointing noise 0.01 degree, beam divergence 0.5
mrad, mixed returns at silhouettes with probability 0.3, as ``asbuilt simulate`` does). The scan
document (two objects, each with its ``station``, linked) goes through ``asbuilt.fit`` as a
user's scan would.

Per cell: how many pairs were fused; over the fused pairs, each size's relative error where
the fit says the size was observed, the share of sizes observed (of 3), the RMS of error /
standard error of the observed sizes (1 for honest standard errors), the worst axis error; and
how many views alone observed both horizontal sizes (what the fusion adds).

Run: ``python benchmarks/two_station_boxes.py [--trials 30] [--operator-window] [--out F]``
(about a minute at 30 trials).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from asbuilt.errors import AsbuiltError  # noqa: E402
from asbuilt.fit import fit, fit_points  # noqa: E402
from asbuilt.scan import loads_scan  # noqa: E402
from asbuilt.sim.raycast import BoxShape, PlaneShape  # noqa: E402
from asbuilt.sim.scene import Scene, SceneObject, Station  # noqa: E402
from asbuilt.sim.sensor import scan_object  # noqa: E402

SIGMA_R = 0.002
SECTIONS = (0.2, 0.4, 0.6)
#: (name, range of the second station's bearing round the column from the first's, degrees)
LAYOUTS = (("across", (150.0, 210.0)), ("beside", (70.0, 110.0)))
POINTS = (20, 30, 40)
HEIGHT = 3.0


def _station(rng, centre, bearing) -> Station:
    distance = rng.uniform(3.0, 10.0)
    position = centre + distance * np.array([math.cos(bearing), math.sin(bearing), 0.0])
    position[2] = rng.uniform(1.0, 2.0)
    return Station(id=f"S{bearing:.3f}", position=position, range_sigma=SIGMA_R)


def trial(rng, section: float, layout: tuple[float, float], n: int, operator: bool):
    """One column and its two views: the scan document (metres) and the truth."""
    size = np.array([section * rng.uniform(0.8, 1.2), section * rng.uniform(0.8, 1.2), HEIGHT])
    yaw = rng.uniform(0.0, math.pi)
    axes = np.array(
        [[math.cos(yaw), math.sin(yaw), 0.0], [-math.sin(yaw), math.cos(yaw), 0.0], [0, 0, 1.0]]
    )
    centre = np.array([0.0, 0.0, 0.5 * HEIGHT])
    first = rng.uniform(-math.pi, math.pi)
    second = first + math.radians(rng.uniform(*layout))
    stations = (_station(rng, centre, first), _station(rng, centre, second))
    box = SceneObject(
        id="C1",
        kind="cuboid",
        shape=BoxShape(center=centre, axes=axes, size=size),
        truth=None,
        points=n,
        scan=True,
        station=stations[0].id,
        index=0,
    )
    ground = SceneObject(
        id="ground",
        kind=None,
        shape=PlaneShape(point=np.zeros(3), normal=np.array([0.0, 0.0, 1.0])),
        truth=None,
        points=0,
        scan=False,
        station=stations[0].id,
        index=1,
    )
    scene = Scene(units="m", stations=stations, objects=(box, ground))
    objects = []
    for k, station in enumerate(stations):
        shots = scan_object(
            scene, 0, n_points=n, station=station, rng=rng, exact=True, operator_window=operator
        )
        objects.append(
            {
                "id": ("C1", "C1b")[k],
                "kind": "cuboid",
                "station": station.position.tolist(),
                "points": shots.points.tolist(),
            }
        )
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"range_sigma": SIGMA_R},
        "objects": objects,
        "links": [["C1", "C1b"]],
    }
    return doc, {"axes": axes, "size": size}


def _matched(result, truth):
    """Per true axis k: the fitted size along it, its standard error, whether it was observed,
    and the angle (degrees) between the true and the fitted axis."""
    out = []
    for k in range(3):
        cosines = np.abs(result.primitive.axes @ truth["axes"][k])
        j = int(cosines.argmax())
        out.append(
            (
                float(result.primitive.size[j]),
                float(result.stderr["size"][j]),
                bool(result.observed[j]),
                math.degrees(math.acos(min(1.0, float(cosines[j])))),
            )
        )
    return out


def _axis_error(result, truth) -> float:
    """The largest angle (degrees) between an axis the fit measured and the true axis nearest
    it (a view that saw one face measured only that face's normal)."""
    assumed = result.diagnostics.get("assumed_size")
    rows = range(3) if assumed is None else (int(assumed),)
    cosines = [float(np.abs(truth["axes"] @ result.primitive.axes[r]).max()) for r in rows]
    return math.degrees(math.acos(min(1.0, min(cosines))))


def cell(section, layout, n, count, operator) -> dict:
    fused = refused = views_both = views_off = 0
    errors, zs, angles, observed = [], [], [], []
    for s in range(count):
        rng = np.random.default_rng([n, int(layout[0]), int(section * 1000), s, operator])
        try:
            doc, truth = trial(rng, section, layout, n, operator)
        except ValueError:
            refused += 1
            continue
        for view in doc["objects"]:
            try:
                alone = fit_points(
                    "cuboid", np.array(view["points"]), sigma=SIGMA_R, viewpoint=view["station"]
                )
            except AsbuiltError:
                continue
            matched = _matched(alone, truth)
            views_both += all(m[2] for m in matched[:2])
            views_off += _axis_error(alone, truth) > 5.0
        report = fit(loads_scan(json.dumps(doc), source="two-station.json"))
        fits = {item.object.id: item for item in report.fits}
        if report.failures:
            refused += 1
        item = fits.get("C1")
        if item is None or item.object.extra.get("fused_with") != "C1b":
            continue
        fused += 1
        matched = _matched(item.result, truth)
        angles.append(_axis_error(item.result, truth))
        observed.append(sum(m[2] for m in matched))
        for k, (value, stderr, seen, _angle) in enumerate(matched):
            if seen:
                error = value - truth["size"][k]
                errors.append(abs(error) / truth["size"][k])
                zs.append(error / stderr if stderr > 0 else math.inf)
    return {
        "fused": fused,
        "refused": refused,
        "views_both": views_both,
        "views_off": views_off,
        "errors": np.array(errors),
        "z": np.array(zs),
        "angles": np.array(angles),
        "observed": np.array(observed),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=30, help="column pairs per cell (30)")
    parser.add_argument("--operator-window", action="store_true")
    parser.add_argument("--out", type=Path, help="also write the table (Markdown) here")
    args = parser.parse_args(argv)
    window = "operator window" if args.operator_window else "exact silhouette window"
    lines = [
        f"Columns seen from two stations, {window}, {args.trials} pairs a cell (fused: pairs "
        "fitted as one box; sizes: relative error of each size the fused fit says it observed; "
        "z: error / standard error of those sizes; views alone with both: of the 2 x pairs single "
        "views, fitted alone, those that observed both horizontal sizes; > 5 deg off: those with an axis "
        "more than 5 degrees from the truth)",
        "",
        "| section m | layout | points a view | fused | observed sizes (mean of 3) "
        "| size median % | size p90 % | size worst % | z RMS | axis worst deg "
        "| views alone with both | views alone > 5 deg off | refused |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for section in SECTIONS:
        for name, layout in LAYOUTS:
            for n in POINTS:
                c = cell(section, layout, n, args.trials, args.operator_window)
                e, z = c["errors"], c["z"]
                if e.size:
                    figures = (
                        f"{c['observed'].mean():.2f} | {100 * np.median(e):.2f} | "
                        f"{100 * np.percentile(e, 90):.2f} | {100 * e.max():.2f} | "
                        f"{math.sqrt(np.mean(z**2)):.2f} | {c['angles'].max():.2f}"
                    )
                else:
                    figures = "- | - | - | - | - | -"
                lines.append(
                    f"| {section} | {name} | {n} | {c['fused']}/{args.trials} | {figures} "
                    f"| {c['views_both']} | {c['views_off']} | {c['refused']} |"
                )
                print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    print()
    print(text, end="")
    if args.out is not None:
        args.out.write_text(text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
