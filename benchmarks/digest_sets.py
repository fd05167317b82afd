"""The point sets of the regression digest (``benchmarks/fit_digest.py sets``).

Every set is drawn, with the benchmark's own fixed seeds, from a generator a benchmark script
already uses, and is fitted by ``fit_digest.py run`` with that benchmark's own call (the same
kind, ``sigma`` and ``viewpoint``, or the same scan document through :func:`asbuilt.fit.fit`).
The sets are drawn once and stored (``SETS.npz``), so two versions of the fitting code are
compared on the very same points, whatever either of them does to the simulator.

Sources (``--sources``; trials per cell at ``--scale 1``):

* ``trials``: ``benchmarks/trials.py`` as ``fit_accuracy.py`` draws it (seed 2004, one
  generator per cell, operator-window and session twins from the same state): cylinders (45
  cells x 20 trials), spheres (12 x 5), planes (6 x 5), each clean and with 20% edge outliers
  over the exact and the operator's window; cuboids (18 x 14) over the exact and the operator's
  window and by the scan session; the first two trials of each cell also as ``--no-sensor``
  fits them (no sigma, no viewpoint) and with sigma but no viewpoint;
* ``clutter_cuboids``: boxes among a floor, wall or ceiling (16 cells x 30, seed 47);
* ``sparse_cuboids``: cuboid trials of 7-15 points, both windows (30 cells x 10 each);
* ``two_station_boxes``: columns seen from two stations (18 cells x 5, both windows): each view
  fitted alone and the linked pair through :func:`asbuilt.fit.fit` (call ``scan``);
* ``flanged_branches``: the tests' flanged tee branches, alone and with the header (5 x 8);
* ``end_plane_pipes``: the tests' pipes at a flange face or a wall (5 configurations x 60);
* ``insulated_pipes``: simulated lagged pipes through :func:`asbuilt.fit.fit` (84 cells x 3);
* ``auto_choice``: the accuracy trials at 20 and 40 points through ``fit_auto``, with and
  without the sensor (54 cells x 2);
* ``dense_objects``: the dense pipe, column, tank head and wall at 1,000 and 10,000 points,
  fitted as their own kind and as ``auto``.

A ``--scale`` below 1 keeps, in each source, an evenly spread share of its cells (the first
always) with one trial each: ``--scale 0.001`` gives a few sets of every source.
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

FORMAT = "asbuilt-fit-digest-sets"
SOURCES = (
    "trials",
    "clutter_cuboids",
    "sparse_cuboids",
    "two_station_boxes",
    "flanged_branches",
    "end_plane_pipes",
    "insulated_pipes",
    "auto_choice",
    "dense_objects",
)
#: The accuracy benchmark's and auto_choice.py's seed.
ACCURACY_SEED = 2004


def _floats(value):
    """``value`` (a number or nested arrays) as plain floats in nested lists, for JSON."""
    return np.asarray(value, dtype=np.float64).tolist()


class SetCollector:
    """The point sets drawn so far, in order, and their description."""

    def __init__(self):
        self.entries: list[dict] = []
        self.points: list[np.ndarray] = []
        self._keys: set[str] = set()

    def add(
        self, key, kind, points, *, truth, sigma=None, viewpoint=None, call="fit_points", **extra
    ):
        """Add one set.

        Parameters
        ----------
        key : str
            Unique and stable: ``source/cell/trial/version``.
        kind : str
            The kind asked: cylinder, cuboid, sphere, plane or auto.
        points : array_like, shape (n, 3), metres
        truth : dict
            The true object: ``kind`` and whichever of ``radius``, ``axis``, ``center``,
            ``normal``, ``point``, ``size``, ``axes`` are known (metres, unit vectors).
        sigma : float, optional, metres
            The range sigma the benchmark passes.
        viewpoint : array_like, shape (3,), metres, optional
            The station the benchmark passes.
        call : str
            ``fit_points``, ``fit_auto`` or ``scan`` (``extra`` then holds ``scan``, the scan
            document, and ``object``, the id whose fit is recorded).
        """
        if key in self._keys:
            raise ValueError(f"duplicate set key {key}")
        self._keys.add(key)
        self.entries.append(
            {
                "key": key,
                "source": key.split("/", 1)[0],
                "kind": kind,
                "call": call,
                "sigma": None if sigma is None else float(sigma),
                "viewpoint": None if viewpoint is None else _floats(viewpoint),
                "truth": {k: (v if isinstance(v, str) else _floats(v)) for k, v in truth.items()},
                **extra,
            }
        )
        self.points.append(np.asarray(points, dtype=np.float64).reshape(-1, 3))


def _cells(cells: list, trials: int, scale: float) -> list[tuple[object, int]]:
    """``(cell, trials)`` to draw: ``trials * scale`` (rounded, at least 1) of every cell, or
    below one trial a cell an evenly spread share of the cells (the first always), one each."""
    per = trials * scale
    if per >= 1:
        return [(c, int(round(per))) for c in cells]
    return [
        (c, 1)
        for i, c in enumerate(cells)
        if i == 0 or math.floor((i + 1) * per) > math.floor(i * per)
    ]


def _twin(rng):
    twin = np.random.Generator(type(rng.bit_generator)())
    twin.bit_generator.state = copy.deepcopy(rng.bit_generator.state)
    return twin


# --------------------------------------------------------------------------- sources


def _trials(out: SetCollector, scale: float) -> None:
    import trials as tm

    station = tm.STATION.position
    groups = (
        ("cylinder", [(od, ld, n) for od in tm.ODS_MM for ld in tm.LDS for n in tm.NS], 20),
        ("sphere", [(d, n) for d in tm.SPHERE_D for n in tm.NS], 5),
        ("plane", [(w, n) for w in tm.PLANE_W for n in tm.NS], 5),
        ("cuboid", [(s, f, n) for s in tm.SECTIONS for f in (2, 3) for n in tm.NS], 14),
    )
    makers = {
        "cylinder": tm.cylinder_trial,
        "sphere": tm.sphere_trial,
        "plane": tm.plane_trial,
        "cuboid": tm.cuboid_trial,
    }
    for kind, cells, count in groups:
        make = makers[kind]
        for key, trials in _cells(cells, count, scale):
            rng = np.random.default_rng([ACCURACY_SEED, tm.hash_key(kind, key)])
            cell = f"{kind}{key}".replace(" ", "")
            for t in range(trials):
                # fit_accuracy.run_cells: the twins start from the trial's generator state.
                op_rng, se_rng = _twin(rng), _twin(rng)
                versions = [("", make(rng, *key)), (tm.OPERATOR, make(op_rng, *key, operator=True))]
                if kind == "cuboid":
                    versions.append((tm.SESSION, make(se_rng, *key, session=True)))
                for suffix, trial in versions:
                    truth = {"kind": kind, **trial.truth}
                    truth.pop("los", None)
                    for name, data in (("clean", trial.clean), ("outliers", trial.dirty)):
                        modes = [("", tm.SIGMA_R, station)]
                        if not suffix and t < max(1, round(2 * min(scale, 1.0))):
                            modes += [("+nosensor", None, None), ("+noview", tm.SIGMA_R, None)]
                        for mode, sigma, view in modes:
                            out.add(
                                f"trials/{cell}/{t}/{name}{suffix}{mode}",
                                kind,
                                data,
                                truth=truth,
                                sigma=sigma,
                                viewpoint=view,
                            )


def _box_truth(box) -> dict:
    return {"kind": "cuboid", "center": box.center, "axes": box.axes, "size": box.size}


def _clutter(out: SetCollector, scale: float) -> None:
    import clutter_cuboids as cc

    cells = [(name, margin) for name in cc.SCENES for margin in cc.MARGINS]
    for (name, margin), trials in _cells(cells, 30, scale):
        rng = np.random.default_rng([47, cc.SCENES.index(name), cc.MARGINS.index(margin)])
        for t in range(trials):
            box, station, others = cc.scene(name, rng)
            points = cc.shots(box, station, others, margin, 30, rng)
            out.add(
                f"clutter_cuboids/{name},margin={margin:g}/{t}/clean",
                "cuboid",
                points,
                truth=_box_truth(box),
                sigma=cc.SIGMA,
                viewpoint=station,
            )


def _sparse(out: SetCollector, scale: float) -> None:
    import sparse_cuboids as sc
    import trials as tm

    cells = [
        (operator, section, faces, n)
        for operator in (False, True)
        for section in sc.SECTIONS
        for faces in sc.FACES
        for n in sc.POINTS
    ]
    for (operator, section, faces, n), trials in _cells(cells, 10, scale):
        window = "operator" if operator else "exact"
        for s in range(trials):
            rng = np.random.default_rng([n, faces, int(section * 1000), s])
            trial = tm.cuboid_trial(rng, section, faces, n, operator=operator)
            truth = {"kind": "cuboid", **trial.truth}
            truth.pop("los")
            out.add(
                f"sparse_cuboids/{window},{section},{faces},{n}/{s}/clean",
                "cuboid",
                trial.clean,
                truth=truth,
                sigma=tm.SIGMA_R,
                viewpoint=tm.STATION.position,
            )


def _two_stations(out: SetCollector, scale: float) -> None:
    import two_station_boxes as ts

    cells = [
        (operator, section, layout, n)
        for operator in (False, True)
        for section in ts.SECTIONS
        for layout in ts.LAYOUTS
        for n in ts.POINTS
    ]
    for (operator, section, (name, layout), n), trials in _cells(cells, 5, scale):
        window = "operator" if operator else "exact"
        for s in range(trials):
            rng = np.random.default_rng([n, int(layout[0]), int(section * 1000), s, operator])
            try:
                doc, truth = ts.trial(rng, section, layout, n, operator)
            except ValueError:  # the benchmark counts it refused: no scan to fit
                continue
            truth = {"kind": "cuboid", "center": [0.0, 0.0, 0.5 * ts.HEIGHT], **truth}
            cell = f"two_station_boxes/{window},{section},{name},{n}/{s}"
            for view in doc["objects"]:
                out.add(
                    f"{cell}/view-{view['id']}",
                    "cuboid",
                    view["points"],
                    truth=truth,
                    sigma=ts.SIGMA_R,
                    viewpoint=view["station"],
                )
            both = np.vstack([np.asarray(v["points"]) for v in doc["objects"]])
            out.add(
                f"{cell}/linked", "cuboid", both, truth=truth, call="scan", scan=doc, object="C1"
            )


def _flanged(out: SetCollector, scale: float) -> None:
    import flanged_branches as fb

    scenes = fb._scenes_module()
    for (header, branch), seeds in _cells(fb.PAIRS, 8, scale):
        for seed in range(seeds):
            shapes = scenes._tee(header, branch, seed)
            points, on = scenes._shoot(shapes, seed)
            shape = shapes[0]
            axis = (shape.end - shape.start) / np.linalg.norm(shape.end - shape.start)
            truth = {
                "kind": "cylinder",
                "radius": branch,
                "axis": axis,
                "center": 0.5 * (shape.start + shape.end),
            }
            cell = f"flanged_branches/{2000 * header:.1f}-{2000 * branch:.1f}/{seed}"
            for which, chosen in (("branch", points[on]), ("window", points)):
                out.add(
                    f"{cell}/{which}",
                    "cylinder",
                    chosen,
                    truth=truth,
                    sigma=scenes.SIGMA,
                    viewpoint=scenes.STATION,
                )


def _end_planes(out: SetCollector, scale: float) -> None:
    import end_plane_pipes as ep

    scenes = ep._scenes_module()
    for (radius, surface, slant), seeds in _cells(scenes.CONFIGURATIONS, 60, scale):
        for seed in range(seeds):
            points, station, axis, labels = scenes._scene(seed, radius, surface, slant)
            share = float(np.mean(labels == "end"))
            out.add(
                f"end_plane_pipes/{2e3 * radius:.1f},{surface},{slant:.0f}/{seed}/clean",
                "cylinder",
                points,
                truth={"kind": "cylinder", "radius": radius, "axis": axis},
                sigma=scenes.SIGMA,
                viewpoint=station,
                end_share=share,
            )


def _insulated(out: SetCollector, scale: float) -> None:
    import insulated_pipes as ip

    from asbuilt.catalog import load_catalog
    from asbuilt.sim.scene import scene_from_dict
    from asbuilt.sim.simulate import simulate_scan

    catalog = load_catalog("asme-b36.10m")
    cells = [(nps, t, n) for nps in ip.SIZES for t in ip.THICKNESSES_MM for n in ip.POINTS]
    rng = np.random.default_rng(1)  # the benchmark's seed, one generator for every cell
    for (nps, t_mm, n), trials in _cells(cells, 3, scale):
        od = catalog.size(nps).od
        for t in range(trials):
            scene = ip.scene_doc(od, t_mm / 1000.0, n, rng)
            doc = simulate_scan(scene_from_dict(scene), seed=int(rng.integers(2**31)))
            geometry = scene["objects"][0]["geometry"]
            start, end = np.array(geometry["start"]), np.array(geometry["end"])
            (obj,) = [o for o in doc["objects"] if o["id"] == "P1"]
            out.add(
                f"insulated_pipes/NPS{nps},{t_mm:g}mm,{n}/{t}/clean",
                "cylinder",
                obj["points"],
                truth={
                    "kind": "cylinder",
                    "radius": 0.5 * od + t_mm / 1000.0,  # the cladding the beams hit
                    "axis": (end - start) / np.linalg.norm(end - start),
                    "center": 0.5 * (start + end),
                },
                call="scan",
                scan=doc,
                object="P1",
            )


def _auto(out: SetCollector, scale: float) -> None:
    import auto_choice as ac
    import trials as tm

    for (kind, key, make), trials in _cells(ac.cells((20, 40)), 2, scale):
        rng = np.random.default_rng([ACCURACY_SEED, tm.hash_key(kind, key)])
        cell = f"{kind}{key}".replace(" ", "")
        for t in range(trials):
            trial = make(rng, *key)
            truth = {"kind": kind, **trial.truth}
            truth.pop("los", None)
            for version, data in (("clean", trial.clean), ("outliers", trial.dirty)):
                for mode, sigma, viewpoint in ac.MODES:
                    out.add(
                        f"auto_choice/{cell}/{t}/{version}+{mode.replace(' ', '')}",
                        "auto",
                        data,
                        truth=truth,
                        sigma=sigma,
                        viewpoint=viewpoint,
                        call="fit_auto",
                    )


def _dense(out: SetCollector, scale: float) -> None:
    import dense_objects as do

    truths = {
        "pipe": {
            "kind": "cylinder",
            "radius": 0.1,
            "axis": [1.0, 0.0, 0.0],
            "center": [1.0, 3.0, 1.0],
        },
        "column": {
            "kind": "cuboid",
            "center": [1.0, 5.0, 1.0],
            "axes": np.eye(3),
            "size": [0.4, 0.3, 2.0],
        },
        "tank head": {"kind": "sphere", "radius": 0.3, "center": [0.0, 4.0, 1.0]},
        "wall": {"kind": "plane", "normal": [0.0, 1.0, 0.0], "point": [0.0, 6.0, 1.0]},
    }
    makers = {"pipe": do.pipe, "column": do.column, "tank head": do.tank_head, "wall": do.wall}
    counts = (1000, 10000)  # the benchmark's default, drawn in its order from its seed
    wanted = {c for c, _ in _cells([(name, n) for name in makers for n in counts], 1, scale)}
    rng = np.random.default_rng(2026)
    for name, make in makers.items():
        for n in counts:
            points = make(n, rng)
            if (name, n) not in wanted:
                continue
            truth = truths[name]
            for kind in (truth["kind"], "auto"):
                out.add(
                    f"dense_objects/{name.replace(' ', '-')},{n}/0/{kind}",
                    kind,
                    points,
                    truth=truth,
                    sigma=do.NOISE,
                    viewpoint=do.SENSOR,
                )


GENERATORS = {
    "trials": _trials,
    "clutter_cuboids": _clutter,
    "sparse_cuboids": _sparse,
    "two_station_boxes": _two_stations,
    "flanged_branches": _flanged,
    "end_plane_pipes": _end_planes,
    "insulated_pipes": _insulated,
    "auto_choice": _auto,
    "dense_objects": _dense,
}


# --------------------------------------------------------------------------- file


def content_hash(entries: list[dict], points: np.ndarray, offsets: np.ndarray) -> str:
    """SHA-256 of the sets' description and points (independent of the zip's timestamps)."""
    digest = hashlib.sha256(json.dumps(entries, sort_keys=True).encode())
    digest.update(np.ascontiguousarray(points, dtype="<f8").tobytes())
    digest.update(np.ascontiguousarray(offsets, dtype="<i8").tobytes())
    return digest.hexdigest()


def git_state(repo: Path) -> dict:
    """``commit`` (``git rev-parse HEAD``), ``dirty`` and the first changed paths of ``repo``."""

    def git(*args):
        done = subprocess.run(["git", "-C", str(repo), *args], capture_output=True, text=True)
        return done.stdout if done.returncode == 0 else None

    commit = git("rev-parse", "HEAD")
    status = git("status", "--porcelain")
    changed = [line[3:] for line in (status or "").splitlines()]
    return {
        "commit": None if commit is None else commit.strip(),
        "dirty": bool(changed),
        "dirty_paths": changed[:20],
    }


def draw(scale: float = 1.0, sources=SOURCES, progress=None) -> SetCollector:
    """Every source's sets at ``scale``, in :data:`SOURCES` order."""
    for path in (str(ROOT), str(HERE)):  # the benchmark modules and this checkout's asbuilt
        if path not in sys.path:
            sys.path.insert(0, path)
    out = SetCollector()
    for source in SOURCES:
        if source in sources:
            started, before = time.perf_counter(), len(out.entries)
            GENERATORS[source](out, scale)
            if progress is not None:
                progress(source, len(out.entries) - before, time.perf_counter() - started)
    return out


def save(out: SetCollector, path: Path, meta: dict) -> dict:
    """Write the sets to ``path`` (npz: ``points`` (N, 3) metres, ``offsets`` (m + 1,) and
    ``index``, the JSON of every set's description and the file's ``meta``); returns meta."""
    points = np.vstack(out.points) if out.points else np.zeros((0, 3))
    offsets = np.concatenate([[0], np.cumsum([len(p) for p in out.points])]).astype(np.int64)
    counts: dict = {}
    for entry in out.entries:
        by_source = counts.setdefault(entry["source"], {})
        by_source[entry["kind"]] = by_source.get(entry["kind"], 0) + 1
    meta = {
        "format": FORMAT,
        "version": 1,
        **meta,
        "sets": len(out.entries),
        "counts": counts,
        "sha256": content_hash(out.entries, points, offsets),
    }
    index = json.dumps({"meta": meta, "sets": out.entries})
    path = Path(path)
    with path.open("wb") as handle:  # np.savez would add ".npz" to another name
        np.savez_compressed(handle, points=points, offsets=offsets, index=np.array(index))
    return meta


def load(path) -> tuple[dict, list[dict], np.ndarray, np.ndarray]:
    """``(meta, entries, points, offsets)`` of a sets file, its content hash checked."""
    with np.load(path, allow_pickle=False) as data:
        index = json.loads(str(data["index"]))
        points, offsets = data["points"], data["offsets"]
    meta, entries = index["meta"], index["sets"]
    if meta.get("format") != FORMAT:
        raise ValueError(f"{path}: not a fit digest sets file")
    if content_hash(entries, points, offsets) != meta["sha256"]:
        raise ValueError(f"{path}: the sets do not match their recorded hash")
    return meta, entries, points, offsets
