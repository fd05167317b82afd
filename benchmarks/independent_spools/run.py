"""Run asbuilt model/check on every case and compare with truth.  Usage: run.py CASEDIR [case-glob]"""

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np

PY = sys.executable  # the interpreter running this script, with asbuilt installed
NPS_OD = {"2": 0.0603, "3": 0.0889, "4": 0.1143, "6": 0.1683, "8": 0.2191}


def run(args):
    r = subprocess.run(["nice", PY, "-m", "asbuilt"] + args, capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def step_solids(path):
    code = f"""
from OCP.STEPControl import STEPControl_Reader
from OCP.TopExp import TopExp_Explorer
from OCP.TopAbs import TopAbs_SOLID
from OCP.IFSelect import IFSelect_RetDone
r = STEPControl_Reader(); st = r.ReadFile({str(path)!r})
assert st == IFSelect_RetDone, st
r.TransferRoots(); sh = r.OneShape()
e = TopExp_Explorer(sh, TopAbs_SOLID); n = 0
while e.More(): n += 1; e.Next()
print(n)
"""
    r = subprocess.run(["nice", PY, "-c", code], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else "ERR " + r.stderr.strip()[-200:]


def elbow_corner(c):
    C = np.array(c["center"])
    e1, e2 = map(np.array, c["ends"])
    R = c["bend_radius"]
    th = math.radians(c["angle_deg"])
    m = (e1 + e2) / 2
    d = (m - C) / np.linalg.norm(m - C)
    return C + d * R / math.cos(th / 2)


def comp_center(c):
    if c["type"] == "elbow":
        return elbow_corner(c)
    if c["type"] == "tee":
        return np.array(c["center"])
    if c["type"] in ("reducer", "coupling"):
        return (np.array(c["start"]) + np.array(c["end"])) / 2
    return None


def compare(case, truth, model):
    comps = model["components"]
    res = {"pipes": [], "fittings": [], "extra": [], "notes": []}
    for p in truth["pipes"]:
        c = next((c for c in comps if c.get("source") == p["id"] or (c["id"] == p["id"])), None)
        if c is None:
            res["pipes"].append(f"{p['id']}: MISSING")
            continue
        s, e = np.array(p["start"]), np.array(p["end"])
        if c["shape"] == "straight" or c["shape"] == "cylinder":
            ms, me = np.array(c["start"]), np.array(c["end"])
            d1 = max(np.linalg.norm(ms - s), np.linalg.norm(me - e))
            d2 = max(np.linalg.norm(ms - e), np.linalg.norm(me - s))
            dend = min(d1, d2) * 1000
        else:
            dend = float("nan")
        ok = c.get("nominal") == str(p["nps"])
        res["pipes"].append(
            dict(
                id=p["id"],
                type=c["type"],
                nominal=c.get("nominal"),
                truth=p["nps"],
                size_ok=ok,
                end_err_mm=round(dend, 1),
                od=c.get("od"),
                spool=c.get("spool"),
                status=c.get("snap", {}).get("status"),
            )
        )
    fits = [c for c in comps if c["type"] in ("elbow", "tee", "reducer", "coupling")]
    used = set()
    for f in truth["fittings"]:
        cands = [c for c in fits if c["type"] == f["kind"] and c["id"] not in used]
        best = None
        for c in cands:
            d = np.linalg.norm(comp_center(c) - np.array(f["center"]))
            if best is None or d < best[0]:
                best = (d, c)
        if best is None or best[0] > 0.5:
            res["fittings"].append(
                dict(
                    kind=f["kind"],
                    pipes=f["pipes"],
                    found=None,
                    note="MISSING"
                    + (f" (nearest {best[1]['id']} {best[0] * 1000:.0f} mm)" if best else ""),
                )
            )
            continue
        d, c = best
        used.add(c["id"])
        item = dict(
            kind=f["kind"],
            pipes=f["pipes"],
            found=c["id"],
            center_err_mm=round(d * 1000, 1),
            nominal=c.get("nominal"),
            truth_nps=f["nps"],
            standard=c.get("snap", {}).get("standard"),
        )
        if f["kind"] == "elbow":
            item["angle"] = round(c["angle_deg"], 2)
            item["truth_angle"] = f["angle"]
            item["bend_radius_mm"] = round(c["bend_radius"] * 1000, 1)
        if f["kind"] == "reducer":
            item["od_start_end"] = (c["od_start"], c["od_end"])
            item["eccentric"] = c.get("eccentric")
        if f["kind"] == "tee":
            item["od"] = (c["od"], c["branch_od"])
        res["fittings"].append(item)
    for c in fits:
        if c["id"] not in used:
            res["extra"].append(
                dict(id=c["id"], type=c["type"], center=[round(x, 3) for x in comp_center(c)])
            )
    res["spools"] = [(s["id"], s["components"]) for s in model.get("spools", [])]
    res["findings"] = [
        f"{f['severity']} {f['code']} {f['slug']} {f['objects']}: {f['message'][:300]}"
        for f in model.get("findings", [])
    ]
    return res


def main():
    cdir = Path(sys.argv[1])
    pat = sys.argv[2] if len(sys.argv) > 2 else "*"
    odir = cdir.parent / "out"
    odir.mkdir(exist_ok=True)
    for sc in sorted(cdir.glob(pat + ".json")):
        if sc.name.endswith(".truth.json"):
            continue
        name = sc.stem
        truth = json.loads((cdir / (name + ".truth.json")).read_text())
        st, js = odir / (name + ".step"), odir / (name + ".json")
        for f in (st, js):
            if f.exists():
                f.unlink()
        rc, out, err = run(["model", str(sc), "--out", str(st), "--out", str(js)])
        crc, cout, cerr = run(["check", str(sc)])
        rep = {
            "case": name,
            "model_rc": rc,
            "model_stderr": err.strip()[-1500:],
            "model_stdout": out.strip()[-800:],
            "check_rc": crc,
            "check_out": cout.strip()[-3000:],
            "check_err": cerr.strip()[-800:],
        }
        if js.exists():
            model = json.loads(js.read_text())
            rep.update(compare(name, truth, model))
            rep["n_components"] = len(model["components"])
            rep["step_solids"] = step_solids(st) if st.exists() else "no step"
        (odir / (name + ".result.json")).write_text(json.dumps(rep, indent=1, default=str))
        print(
            f"== {name}: model rc {rc}, check rc {crc}, comps {rep.get('n_components')}, solids {rep.get('step_solids')}"
        )
        for p in rep.get("pipes", []):
            print("   pipe", p)
        for f in rep.get("fittings", []):
            print("   fit ", f)
        for f in rep.get("extra", []):
            print("   EXTRA", f)
        print("   spools", rep.get("spools"))
        for f in rep.get("findings", []):
            print("   F", f)
        if "Traceback" in err or "Traceback" in cerr:
            print("   TRACEBACK", (err + cerr)[-1500:])
        if not js.exists():
            print("   NO OUTPUT", err[-500:])


if __name__ == "__main__":
    main()
