"""Seed sweep: many small variants per layout; model -> JSON only; topology/size/centre verdicts."""

import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
import gen
import run

c45 = s45 = math.sqrt(0.5)


def fams():
    rack = [
        (
            gen.xf({"A": (0, 0, 0), "B": (3, 0, 0), "C": (3, 2.5, 0)}, T=(0, 0, 2.0)),
            [("P1", "A", "B", 6), ("P2", "B", "C", 6)],
        ),
        (
            gen.xf({"A": (0, 0.4, 0), "B": (2.6, 0.4, 0), "C": (2.6, 2.5, 0)}, T=(0, 0, 2.0)),
            [("Q1", "A", "B", 4), ("Q2", "B", "C", 4)],
        ),
    ]
    st = 2 * 0.064 + 0.060
    C = np.array([2 + st * c45, st * s45, 0])
    jog = [
        (
            gen.xf({"A": (0, 0, 0), "B": (2, 0, 0), "C": C, "D": C + (2, 0, 0)}, T=(0, 0, 1.3)),
            [("P1", "A", "B", 4), ("P2", "B", "C", 4), ("P3", "C", "D", 4)],
        )
    ]
    C2 = np.array([1.5 + 0.8 * c45, 0.8 * s45, 0])
    z2 = [
        (
            gen.xf(
                {"A": (0, 0, 0), "B": (1.5, 0, 0), "C": C2, "D": C2 + (1.5, 0, 0)}, T=(0, 0, 1.4)
            ),
            [("P1", "A", "B", 2), ("P2", "B", "C", 2), ("P3", "C", "D", 2)],
        )
    ]
    combo = [
        (
            gen.xf(
                {
                    "A": (0, 0, 0),
                    "J": (2, 0, 0),
                    "R": (3.5, 0, 0),
                    "E": (5.5, 0, 0),
                    "F": (5.5, 2.0, 0),
                    "D": (2, 0, -1.5),
                },
                gen.rot_z(20),
                (3, 2, 2.2),
            ),
            [
                ("P1", "A", "J", 6),
                ("P2", "J", "R", 6),
                ("P3", "R", "E", 4),
                ("P4", "E", "F", 4),
                ("P5", "J", "D", 6),
            ],
        )
    ]
    red43 = [
        (
            gen.xf({"A": (0, 0, 0), "R": (2.5, 0, 0), "B": (4.5, 0, 0)}, T=(0, 0, 1.4)),
            [("P1", "A", "R", 4), ("P2", "R", "B", 3)],
        )
    ]
    tee64 = [
        (
            gen.xf(
                {"A": (0, 0, 0), "J": (2, 0, 0), "B": (4, 0, 0), "D": (2, 0, 1.3)}, T=(0, 0, 1.0)
            ),
            [("P1", "A", "J", 6), ("P2", "J", "B", 6), ("P3", "J", "D", 4)],
        )
    ]
    s1 = 2 * 0.229 + 0.120
    stub = [
        (
            gen.xf(
                {"A": (0, 0, 0), "B": (2.5, 0, 0), "C": (2.5, 0, s1), "D": (2.5, 2.0, s1)},
                T=(0, 0, 1.0),
            ),
            [("P1", "A", "B", 6), ("P2", "B", "C", 6), ("P3", "C", "D", 6)],
        )
    ]
    return {
        "rackU": (rack, (-1.0, -5.0, 3.2), dict(links="none", spread="uniform"), 20),
        "rackS": (rack, (-1.0, -5.0, 3.2), dict(links="none"), 20),
        "rackUL": (rack, (-1.0, -5.0, 3.2), dict(spread="uniform"), 20),
        "stubNL2": (stub, (-1.5, -4.0, 1.8), dict(links="none"), 16),
        "jog2": (jog, (2.0, -4.5, 1.6), dict(links="none", spread="uniform"), 12),
        "tee2": (tee64, (2.0, -5.0, 1.8), dict(links="none", spread="uniform"), 12),
        "combo2": (combo, (4.0, -5.0, 1.5), dict(links="none", spread="uniform"), 8),
        "zz2": (z2, (1.5, -3.5, 1.7), dict(links="none", spread="uniform"), 8),
        "jog": (jog, (2.0, -4.5, 1.6), dict(links="none"), 8),
        "z2": (z2, (1.5, -3.5, 1.7), dict(), 8),
        "combo": (combo, (4.0, -5.0, 1.5), dict(links="none"), 8),
        "red43": (red43, (2.0, -6.0, 1.0), dict(links="none"), 8),
        "tee64": (tee64, (2.0, -5.0, 1.8), dict(links="none"), 8),
        "stubNL": (stub, (-1.5, -4.0, 1.8), dict(links="none"), 8),
    }


def verdict(res, truth):
    bad = []
    for p in res["pipes"]:
        if isinstance(p, str):
            bad.append(p)
            continue
        if not p["size_ok"]:
            bad.append(f"{p['id']} size {p['nominal']}({p['status']})")
    for f in res["fittings"]:
        if f.get("found") is None:
            bad.append(f"missing {f['kind']} {f['pipes']}")
            continue
        if f["center_err_mm"] > 10:
            bad.append(f"{f['found']} centre {f['center_err_mm']}mm")
        if f["kind"] == "elbow" and abs(f["angle"] - f["truth_angle"]) > 2:
            bad.append(f"{f['found']} angle {f['angle']}")
        if f["kind"] == "reducer" and f.get("eccentric"):
            bad.append(f"{f['found']} eccentric")
        if f.get("nominal") != str(f["truth_nps"][0]):
            bad.append(f"{f['found']} nominal {f.get('nominal')}")
    for e in res["extra"]:
        bad.append(f"extra {e['type']} {e['id']}")
    return bad


if __name__ == "__main__":
    only = sys.argv[1:] or None
    d = Path("sweep")
    d.mkdir(exist_ok=True)
    summary = {}
    for fam, (spools, station, kw, n) in fams().items():
        if only and fam not in only:
            continue
        ok = 0
        for i in range(n):
            seed = (5000 if fam.endswith("2") else 1000) + 37 * i
            name = f"sw_{fam}_{seed}"
            gen.make_case(name, spools, station, "mm", seed, out=str(d), **kw)
            js = d / (name + ".model.json")
            rc, out, err = run.run(
                ["model", str(d / (name + ".json")), "--out", str(js), "--no-check"]
                if False
                else ["model", str(d / (name + ".json")), "--out", str(js)]
            )
            truth = json.loads((d / (name + ".truth.json")).read_text())
            if not js.exists():
                print(name, "NO OUTPUT rc", rc, err[-300:])
                continue
            res = run.compare(name, truth, json.loads(js.read_text()))
            bad = verdict(res, truth)
            errs = [f for f in res["findings"] if f.startswith("error")]
            if not bad:
                ok += 1
            print(
                f"{name} rc{rc} {'OK' if not bad else 'BAD'} {bad} errors={errs[:3]} {'TRACEBACK' if 'Traceback' in err else ''}",
                flush=True,
            )
        summary[fam] = f"{ok}/{n}"
    print("SUMMARY", summary)
