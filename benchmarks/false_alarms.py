"""False alarms of the compliance rules: error findings on simulated scans of compliant objects.

Each scene holds objects that comply with every rule (plumb columns, straight standard-size pipes,
a perfect spool built from ASME B16.9 fittings). Each is scanned many times by the simulated
pan-tilt range finder (asbuilt.sim: range sigma 2 mm, pointing sigma 0.01 degree, the paper's
point counts), then fitted, merged and checked with the shipped rules exactly as
``asbuilt check`` does. An error finding on a compliant object is a false alarm; the target is
under 1% of objects. Warnings (unverifiable, weak geometry...) are counted separately: they are
allowed, since a sparse scan often cannot verify a tolerance.

Run: ``python benchmarks/false_alarms.py [--runs 200] [--markdown]``.
"""

from __future__ import annotations

import argparse
import json
import time
from collections import Counter
from pathlib import Path

from asbuilt.pipeline import build_model
from asbuilt.scan import loads_scan
from asbuilt.sim.scene import load_scene, scene_from_dict
from asbuilt.sim.simulate import simulate_scan

ROOT = Path(__file__).resolve().parents[1]

STATION = {
    "id": "S1",
    "position": [0.0, 0.0, 1.5],
    "range_sigma": 0.002,
    "angular_sigma_deg": 0.01,
    "dropout": 0.02,
    "mixed_return": 0.5,
}


def _scene(name: str, objects: list) -> dict:
    return {
        "format": "asbuilt-scene",
        "version": 1,
        "name": name,
        "units": "m",
        "seed": 0,
        "stations": [STATION],
        "objects": objects,
    }


def scenes() -> dict:
    """Scene name -> loaded scene of compliant objects."""
    columns = _scene(
        "plumb columns",
        [
            {
                "id": "C1",
                "kind": "cuboid",
                "points": 36,
                "label": "steel column",
                "geometry": {
                    "type": "member",
                    "start": [-1.5, 5.0, 0.0],
                    "end": [-1.5, 5.0, 4.0],
                    "section": [0.35, 0.35],
                },
            },
            {
                "id": "C2",
                "kind": "cuboid",
                "points": 36,
                "label": "concrete column",
                "geometry": {
                    "type": "member",
                    "start": [1.5, 5.0, 0.0],
                    "end": [1.5, 5.0, 4.0],
                    "section": [0.4, 0.4],
                },
            },
        ],
    )
    pipes = _scene(
        "straight standard pipes",
        [
            {
                "id": "P1",
                "kind": "cylinder",
                "points": 30,
                "nominal": '4"',
                "geometry": {
                    "type": "cylinder",
                    "start": [-1.5, 4.0, 1.0],
                    "end": [1.5, 4.0, 1.0],
                    "od": 0.1143,
                },
            },
            {
                "id": "P2",
                "kind": "cylinder",
                "points": 34,
                "nominal": '8"',
                "geometry": {
                    "type": "cylinder",
                    "start": [-2.0, 6.0, 2.5],
                    "end": [2.0, 6.0, 2.5],
                    "od": 0.2191,
                },
            },
            {
                "id": "P3",
                "kind": "cylinder",
                "points": 30,
                "nominal": '6"',
                "geometry": {
                    "type": "cylinder",
                    "start": [3.0, 4.0, 0.2],
                    "end": [3.0, 4.0, 3.0],
                    "od": 0.1683,
                },
            },
        ],
    )
    spool = load_scene(ROOT / "samples" / "scenes" / "spool.scene.json")
    return {
        "plumb columns (2 x 36 pts)": scene_from_dict(columns),
        "straight pipes NPS 4/8/6 (30-34 pts)": scene_from_dict(pipes),
        "perfect spool SP-101 (6 pipes, 26-36 pts)": spool,
    }


def faulty_scenes() -> dict:
    """Scene name -> (scene, the rule slug that must report an error) for detection power."""

    def lean(offset_m: float) -> dict:
        return _scene(
            "leaning column",
            [
                {
                    "id": "C1",
                    "kind": "cuboid",
                    "points": 36,
                    "label": "steel column",
                    "geometry": {
                        "type": "member",
                        "start": [3.0, 5.0, 0.0],
                        "end": [3.0 + offset_m, 5.0, 4.0],
                        "section": [0.35, 0.35],
                    },
                },
            ],
        )

    odd = _scene(
        "nonstandard pipe",
        [
            {
                "id": "P1",
                "kind": "cylinder",
                "points": 30,
                "geometry": {
                    "type": "cylinder",
                    "start": [-1.5, 4.0, 1.0],
                    "end": [1.5, 4.0, 1.0],
                    "od": 0.1270,
                },
            },
        ],
    )
    clash = _scene(
        "crossing pipes",
        [
            {
                "id": "P1",
                "kind": "cylinder",
                "points": 30,
                "geometry": {
                    "type": "cylinder",
                    "start": [-1.5, 4.0, 1.0],
                    "end": [1.5, 4.0, 1.0],
                    "od": 0.1143,
                },
            },
            {
                "id": "P2",
                "kind": "cylinder",
                "points": 30,
                "geometry": {
                    "type": "cylinder",
                    "start": [0.0, 2.5, 1.05],
                    "end": [0.0, 5.5, 1.05],
                    "od": 0.1143,
                },
            },
        ],
    )
    return {
        "column leaning 1:100 (40 mm over 4 m)": (scene_from_dict(lean(0.04)), "out-of-plumb"),
        # twice AISC 303's 1:500 (8 mm over 4 m): how fine a lean 36 shots on two faces can tell
        "column leaning 1:250 (16 mm over 4 m)": (scene_from_dict(lean(0.016)), "out-of-plumb"),
        "pipe OD 127.0 mm (no ASME size; NPS 4 is 114.3)": (
            scene_from_dict(odd),
            "nonstandard-diameter",
        ),
        "NPS 4 pipes crossing 50 mm apart": (scene_from_dict(clash), "clash"),
    }


def detection(runs: int, seed0: int = 5000) -> list[dict]:
    """Share of noisy scans of faulty scenes where the expected rule reports an error."""
    rows = []
    for name, (scene, slug) in faulty_scenes().items():
        found = 0
        for k in range(runs):
            model = build_model(loads_scan(json.dumps(simulate_scan(scene, seed=seed0 + k))))
            found += any(f.slug == slug and f.severity == "error" for f in model.findings)
        rows.append({"scene": name, "rule": slug, "scans": runs, "detected": found})
    return rows


def run(runs: int, seed0: int = 1000) -> list[dict]:
    """Check ``runs`` noisy scans of each scene; one result row per scene."""
    rows = []
    for name, scene in scenes().items():
        errors, warnings, objects = Counter(), Counter(), 0
        erroneous_objects = 0
        start = time.perf_counter()
        for k in range(runs):
            doc = simulate_scan(scene, seed=seed0 + k)
            scan = loads_scan(json.dumps(doc))
            model = build_model(scan)
            n = len(scan.objects)
            objects += n
            flagged = set()
            for f in model.findings:
                if f.severity == "error":
                    errors[f.slug] += 1
                    flagged.update(f.objects)
                elif f.severity == "warning":
                    warnings["unverifiable" if f.unverifiable else f.slug] += 1
            erroneous_objects += len(flagged & {o.id for o in scan.objects})
        rows.append(
            {
                "scene": name,
                "scans": runs,
                "objects": objects,
                "objects_with_errors": erroneous_objects,
                "rate": erroneous_objects / objects,
                "errors": dict(errors),
                "warnings": dict(warnings),
                "seconds": time.perf_counter() - start,
            }
        )
    return rows


def timing(n: int = 1000, repeats: int = 3) -> dict:
    """Seconds for check_model on ``n`` components (half columns on a grid, half short pipes
    between them at three levels), each with a fit, the best of ``repeats`` runs."""
    import numpy as np

    from asbuilt.fit.result import FitResult
    from asbuilt.model import Component, Model, Straight
    from asbuilt.primitives import Cuboid, Cylinder
    from asbuilt.rules import check_model

    rng = np.random.default_rng(0)
    comps = []
    side = int(np.ceil(np.sqrt(n / 2)))
    for i in range(n // 2):
        x, y = (i % side) * 1.0, (i // side) * 1.0
        t = np.radians(rng.uniform(0, 0.3))
        axis = np.array([np.sin(t), 0.0, np.cos(t)])
        axes = np.array([np.cross([0, 1.0, 0], axis), [0, 1.0, 0], axis])
        box = Cuboid([x, y, 1.5], axes, [0.3, 0.3, 3.0])
        fit = FitResult(
            box,
            np.zeros(36),
            np.ones(36, bool),
            {"axes_deg": 0.05, "size": (0.001,) * 3, "center": 0.001},
            0.002,
            "sensor",
            "synthetic",
            diagnostics={"faces": 2},
        )
        comps.append(Component(id=f"C{i}", type="cuboid", geometry=box, fit=fit))
    for i in range(n - n // 2):
        x, y, z = (i % side) + 0.5, (i // side) + 0.5, 2.0 + (i % 3) * 0.3
        cyl = Cylinder([x, y, z], [1.0, 0, 0], 0.05715, 0.8)
        fit = FitResult(
            cyl,
            np.zeros(30),
            np.ones(30, bool),
            {"radius": 0.0005, "axis_deg": 0.1, "center": 0.001, "length": 0.003},
            0.002,
            "sensor",
            "synthetic",
            diagnostics={"arc_deg": 150.0},
        )
        comps.append(
            Component(
                id=f"P{i}",
                type="pipe",
                nominal="4",
                geometry=Straight([x - 0.4, y, z], [x + 0.4, y, z], 0.05715),
                fit=fit,
            )
        )
    model = Model(components=tuple(comps), catalog="asme-b36.10m")
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        findings = check_model(model)
        best = min(best, time.perf_counter() - start)
    return {"components": len(comps), "seconds": best, "findings": len(findings)}


def markdown(rows: list[dict]) -> str:
    lines = [
        "| scene | scans | objects | objects with an error | false-alarm rate | errors by rule "
        "| warnings per object | s per scan |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        errors = ", ".join(f"{k} {v}" for k, v in sorted(r["errors"].items())) or "none"
        warn = ", ".join(f"{k} {v / r['objects']:.2f}" for k, v in sorted(r["warnings"].items()))
        lines.append(
            f"| {r['scene']} | {r['scans']} | {r['objects']} | {r['objects_with_errors']} "
            f"| {100 * r['rate']:.2f}% | {errors} | {warn or 'none'} "
            f"| {r['seconds'] / r['scans']:.3f} |"
        )
    total_obj = sum(r["objects"] for r in rows)
    total_err = sum(r["objects_with_errors"] for r in rows)
    lines.append(
        f"| **all** | | {total_obj} | {total_err} | **{100 * total_err / total_obj:.2f}%** | | | |"
    )
    return "\n".join(lines)


def detection_markdown(rows: list[dict]) -> str:
    lines = ["| faulty scene | rule | scans | detected as error |", "|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['scene']} | `{r['rule']}` | {r['scans']} "
            f"| {r['detected']} ({100 * r['detected'] / r['scans']:.0f}%) |"
        )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=200, help="noisy scans per scene")
    parser.add_argument("--markdown", action="store_true", help="print a markdown table")
    args = parser.parse_args()
    rows = run(args.runs)
    found = detection(max(args.runs // 4, 1))
    speed = timing(1000)
    if args.markdown:
        print(markdown(rows))
        print()
        print(detection_markdown(found))
        print()
        print(
            f"check_model on {speed['components']} components (every rule, shipped defaults): "
            f"{speed['seconds']:.2f} s, {speed['findings']} findings"
        )
    else:
        print(json.dumps({"false_alarms": rows, "detection": found, "timing": speed}, indent=2))


if __name__ == "__main__":
    main()
