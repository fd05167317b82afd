"""Speed of ``asbuilt model`` and the exports (wall time, peak memory, start-up cost).

Run from the repository root::

    .venv/bin/python benchmarks/model_speed.py [--repeat 3] [--objects 1000]

What it measures (all numbers printed as a Markdown report):

1. ``asbuilt model`` on the paper-like sample ``samples/plant.json`` (13 objects) and on a
   52-object scan made by tiling that sample four times (copies moved 40 m apart), writing
   STEP + GLB + DXF. Each run is a fresh process that first imports everything the command
   needs (interpreter, numpy/scipy, rich, CadQuery/OCP, ezdxf, trimesh, the asbuilt modules;
   timed as "imports") and then runs ``asbuilt.cli.main`` (timed as "beyond start-up": loading,
   fitting, merging, checking, solids, writing, including first-call costs); the process's wall
   and CPU time and peak resident memory (``os.wait4``) are reported too. Medians of
   ``--repeat``.
2. The same work in one warm process (imports done, one warm-up run first): load + fit + merge +
   check, then solids + STEP + GLB + DXF, timed separately.
3. A generated ``--objects``-object model (pipes with walls, elbows, cuboids, cylinders, spheres,
   plates and hulls, no fitting) written to STEP in one process on one core: total and per
   object, split into solids and STEP writing.
4. Start-up of ``asbuilt fit`` (must not import CadQuery) next to ``asbuilt model``'s.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYTHON = sys.executable
PLANT = ROOT / "samples" / "plant.json"

FIT_IMPORTS = (
    "import rich.console, rich.table, asbuilt.cli, asbuilt.scan, asbuilt.fit, asbuilt.fit.output"
)
MODEL_IMPORTS = (
    FIT_IMPORTS + ", asbuilt.pipeline, asbuilt.merge, asbuilt.rules, asbuilt.export, "
    "asbuilt.cad.assembly, asbuilt.export.step, asbuilt.export.gltf, asbuilt.export.dxf, "
    "cadquery.occ_impl.exporters.assembly"
)


def run_process(argv: list[str]) -> tuple[float, float, float]:
    """Wall seconds, CPU seconds (user + system) and peak RSS (MB) of a child process."""
    start = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    out, err = proc.stdout.read().decode(), proc.stderr.read().decode()
    proc.stdout.close()
    proc.stderr.close()
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed: {err}")
    run_process.last_stdout = out
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0


def median_run(argv: list[str], repeat: int) -> tuple[float, float, float]:
    runs = [run_process(argv) for _ in range(repeat)]
    return (
        statistics.median(r[0] for r in runs),
        statistics.median(r[1] for r in runs),
        max(r[2] for r in runs),
    )


_TIMED_CLI = """
import json, sys, time
t0, c0 = time.perf_counter(), time.process_time()
{imports}
t1, c1 = time.perf_counter(), time.process_time()
from asbuilt.cli import main
code = main({argv!r})
t2, c2 = time.perf_counter(), time.process_time()
print(json.dumps({{"imports": t1 - t0, "work": t2 - t1, "work_cpu": c2 - c1, "code": code}}))
"""


def timed_cli(argv: list[str], repeat: int) -> dict[str, float]:
    """``asbuilt ARGV`` in fresh processes that import first, then run: medians of each part."""
    script = _TIMED_CLI.format(imports=MODEL_IMPORTS, argv=argv)
    walls, cpus, rss, imports, work, work_cpu = [], [], [], [], [], []
    for _ in range(repeat):
        wall, cpu, peak = run_process([PYTHON, "-c", script])
        parts = json.loads(run_process.last_stdout.strip().splitlines()[-1])
        walls.append(wall)
        cpus.append(cpu)
        rss.append(peak)
        imports.append(parts["imports"])
        work.append(parts["work"])
        work_cpu.append(parts["work_cpu"])
    return {
        "work_cpu": statistics.median(work_cpu),
        "wall": statistics.median(walls),
        "cpu": statistics.median(cpus),
        "rss": max(rss),
        "imports": statistics.median(imports),
        "work": statistics.median(work),
    }


def tiled_scan(source: Path, copies: int, spacing: float, target: Path) -> int:
    """Write a scan with ``copies`` copies of ``source``'s objects moved ``spacing`` m apart."""
    document = json.loads(source.read_text())
    factor = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254, "ft": 0.3048}[document["units"]]
    objects, links = [], []
    for k in range(copies):
        shift = spacing / factor * k
        for obj in document["objects"]:
            copy = {key: value for key, value in obj.items() if key != "measurements"}
            copy["id"] = f"{obj['id']}-{k}"
            if obj.get("group"):
                copy["group"] = f"{obj['group']}-{k}"
            copy["points"] = [[p[0] + shift, p[1], p[2]] for p in obj["points"]]
            objects.append(copy)
        links += [[f"{a}-{k}", f"{b}-{k}"] for a, b in document.get("links", [])]
    document["objects"], document["links"] = objects, links
    document["name"] = f"{document.get('name', 'scan')} x{copies}"
    target.write_text(json.dumps(document))
    return len(objects)


def generated_model(count: int):
    """A model of ``count`` components of every kind, laid out on a grid (no fitting)."""
    import numpy as np

    from asbuilt.model import Bend, Component, Model, Straight
    from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

    rng = np.random.default_rng(1)
    components = []
    tetra = np.array([[0, 0, 0], [0.4, 0, 0], [0, 0.4, 0], [0, 0, 0.4]], float)
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    for i in range(count):
        x, y = 2.0 * (i % 40), 2.0 * (i // 40)
        kind = i % 10
        if kind < 4:
            end = [x + 1.5, y + rng.uniform(-0.2, 0.2), 0.0]
            geometry, ctype = Straight([x, y, 0], end, 0.0573, 0.006), "pipe"
        elif kind == 4:
            geometry, ctype = (
                Bend([x, y, 0], [x + 0.15, y + 0.15, 0], [x, y + 0.15, 0], 0.0573, 0.006),
                "elbow",
            )
        elif kind == 5:
            angle = rng.uniform(0, math.pi)
            axes = np.array(
                [
                    [math.cos(angle), math.sin(angle), 0],
                    [-math.sin(angle), math.cos(angle), 0],
                    [0, 0, 1],
                ]
            )
            geometry, ctype = Cuboid([x, y, 2], axes, [0.3, 0.4, 4.0]), "cuboid"
        elif kind == 6:
            geometry, ctype = Cylinder([x, y, 1], [0, 0, 1], 0.15, 2.0), "cylinder"
        elif kind == 7:
            geometry, ctype = Sphere([x, y, 1], 0.4), "sphere"
        elif kind == 8:
            outline = [
                [x - 0.5, y - 0.5, 0],
                [x + 0.5, y - 0.5, 0],
                [x + 0.5, y + 0.5, 0],
                [x - 0.5, y + 0.5, 0],
            ]
            geometry, ctype = Plane([x, y, 0], [0, 0, 1], outline), "plane"
        else:
            geometry, ctype = Hull(tetra + [x, y, 0], faces), "hull"
        components.append(Component(f"O{i}", ctype, geometry, group=f"G{i // 100}"))
    return Model(components=tuple(components), name=f"generated {count}")


def warm_timings(scan_path: Path, folder: Path, repeat: int) -> dict[str, float]:
    from asbuilt.export import export_models
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    outputs = [folder / "warm.step", folder / "warm.glb", folder / "warm.dxf"]
    fit_times, export_times = [], []
    for i in range(repeat + 1):  # the first run warms up the kernel's lazy imports
        start = time.perf_counter()
        model = build_model(load_scan(scan_path))
        middle = time.perf_counter()
        export_models(model, outputs)
        end = time.perf_counter()
        if i:
            fit_times.append(middle - start)
            export_times.append(end - middle)
    return {
        "fit+merge+check": statistics.median(fit_times),
        "solids+STEP+GLB+DXF": statistics.median(export_times),
        "objects": len(model.components),
    }


def step_timings(count: int, folder: Path) -> dict[str, float]:
    from asbuilt.cad import prepare
    from asbuilt.export.step import read_step, write_step

    model = generated_model(count)
    start, cpu_start = time.perf_counter(), time.process_time()
    cad = prepare(model)
    middle = time.perf_counter()
    path = folder / "generated.step"
    write_step(cad, path)
    end, cpu_end = time.perf_counter(), time.process_time()
    solids = len(read_step(path))
    return {
        "solids": middle - start,
        "step": end - middle,
        "total": end - start,
        "cpu": cpu_end - cpu_start,
        "count": count,
        "read_back": solids,
        "size_mb": path.stat().st_size / 1e6,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--objects", type=int, default=1000)
    args = parser.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        tiled = folder / "plant-x4.json"
        n_tiled = tiled_scan(PLANT, 4, 40.0, tiled)
        rows = []
        startup_model = median_run([PYTHON, "-c", MODEL_IMPORTS], args.repeat)
        startup_fit = median_run([PYTHON, "-c", FIT_IMPORTS], args.repeat)
        version = median_run([PYTHON, "-m", "asbuilt", "--version"], args.repeat)
        for label, scan in (
            ("plant.json (13 objects)", PLANT),
            (f"plant.json tiled x4 ({n_tiled} objects)", tiled),
        ):
            argv = ["model", str(scan), "--quiet"]
            for suffix in (".step", ".glb", ".dxf"):
                argv += ["--out", str(folder / f"out{suffix}")]
            rows.append((label, timed_cli(argv, args.repeat)))
        fit_run = median_run([PYTHON, "-m", "asbuilt", "fit", str(PLANT), "--json"], args.repeat)
        check = subprocess.run(
            [
                PYTHON,
                "-c",
                "import sys; from asbuilt.cli import main; "
                f"main(['fit', {str(PLANT)!r}, '--json']); "
                "sys.stderr.write(str('cadquery' in sys.modules or 'OCP' in sys.modules))",
            ],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        )
        fit_loads_cadquery = check.stderr.strip().splitlines()[-1]

        warm_plant = warm_timings(PLANT, folder, args.repeat)
        warm_tiled = warm_timings(tiled, folder, args.repeat)
        step = step_timings(args.objects, folder)

    print("## Model and export speed\n")
    print(
        "`asbuilt model SCAN --out x.step --out x.glb --out x.dxf --quiet`, each in a fresh "
        "process that first imports everything the command needs, then runs it; medians of "
        f"{args.repeat}:\n"
    )
    print(
        "| scan | process wall | process CPU | peak RSS | imports | beyond start-up: wall | "
        "beyond start-up: CPU |"
    )
    print("|---|---|---|---|---|---|---|")
    for label, row in rows:
        print(
            f"| {label} | {row['wall']:.2f} s | {row['cpu']:.2f} s | {row['rss']:.0f} MB | "
            f"{row['imports']:.2f} s | {row['work']:.2f} s | {row['work_cpu']:.2f} s |"
        )
    print()
    print("In one warm process (imports done, after a warm-up run), median:\n")
    print("| scan | components | load+fit+merge+check | solids+STEP+GLB+DXF |")
    print("|---|---|---|---|")
    for label, warm in (("plant.json", warm_plant), ("plant.json x4", warm_tiled)):
        print(
            f"| {label} | {warm['objects']} | {warm['fit+merge+check']:.3f} s | "
            f"{warm['solids+STEP+GLB+DXF']:.3f} s |"
        )
    print(
        f"\n{step['count']} generated objects to STEP (one process, one core): "
        f"{step['total']:.2f} s wall in all = {1000 * step['total'] / step['count']:.2f} ms per "
        f"object, {step['cpu']:.2f} s CPU (solids {step['solids']:.2f} s, STEP writing "
        f"{step['step']:.2f} s wall; "
        f"{step['size_mb']:.1f} MB; {step['read_back']} solids read back).\n"
    )
    print("| start-up | wall | CPU | peak RSS |")
    print("|---|---|---|---|")
    for label, (wall, cpu, rss) in (
        ("`python -m asbuilt --version`", version),
        ("a process importing what `asbuilt fit` imports", startup_fit),
        (
            "a process importing what `asbuilt model` imports (CadQuery, OCP, ezdxf, trimesh)",
            startup_model,
        ),
        ("`asbuilt fit samples/plant.json --json` (whole run)", fit_run),
    ):
        print(f"| {label} | {wall:.2f} s | {cpu:.2f} s | {rss:.0f} MB |")
    print(f"\n`asbuilt fit` loads CadQuery/OCP: {fit_loads_cadquery}.")


if __name__ == "__main__":
    main()
