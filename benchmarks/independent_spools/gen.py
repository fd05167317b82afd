"""Independent spool-scan generator for reviewing `asbuilt model`.

Layout = nodes + pipes (node graph).  The fitting at each node follows from its degree and
angles: degree 2 bent -> elbow (ASME B16.9 LR 90 A / 45 B), degree 2 straight with a size
change -> concentric reducer (H of the large end, centred on the node), degree 3 -> straight
tee (C run, M branch).  Pipes run between the fittings' ends.  Shots: pan-tilt range finder,
ray cast against every pipe (finite cylinder) and the scene planes, range sigma 2 mm along the
beam, pointing sigma 0.01 deg.  Everything here is metres; files are written in their unit.
"""

import json
import math
import sys
from pathlib import Path

import numpy as np

OD = {2: 0.0603, 3: 0.0889, 4: 0.1143, 6: 0.1683, 8: 0.2191}
# B16.9: 90 LR A, 45 LR B, tee C, tee M, reducer H (by large end), metres
B169 = {
    2: (0.076, 0.035, 0.064, 0.064, 0.076),
    3: (0.114, 0.051, 0.086, 0.086, 0.089),
    4: (0.152, 0.064, 0.105, 0.105, 0.102),
    6: (0.229, 0.095, 0.143, 0.143, 0.140),
    8: (0.305, 0.127, 0.178, 0.178, 0.152),
}
UNIT = {"m": 1.0, "mm": 0.001, "in": 0.0254, "cm": 0.01, "ft": 0.3048}
SIG_R = 0.002
SIG_P = math.radians(0.01)


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def rot_z(deg):
    a = math.radians(deg)
    return np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])


def build(nodes, pipes):
    """nodes: name -> xyz (m); pipes: list of (id, n1, n2, nps). Returns truth pipes, fittings."""
    nodes = {k: np.asarray(v, float) for k, v in nodes.items()}
    inc = {k: [] for k in nodes}
    for pid, a, b, nps in pipes:
        inc[a].append((pid, b, nps))
        inc[b].append((pid, a, nps))
    cut = {}  # (pid, node) -> cut-back from node
    fittings = []
    for n, lst in inc.items():
        P = nodes[n]
        if len(lst) == 1:
            cut[(lst[0][0], n)] = 0.0
            continue
        dirs = [unit(nodes[o] - P) for _, o, _ in lst]
        if len(lst) == 2:
            (p1, _, s1), (p2, _, s2) = lst
            cosang = float(np.dot(dirs[0], dirs[1]))
            between = math.degrees(math.acos(max(-1, min(1, cosang))))
            bend = 180 - between
            if bend < 1 and s1 == s2:
                # butt weld between two pipe objects of one run (no fitting)
                cut[(p1, n)] = cut[(p2, n)] = 0.0
                fittings.append(dict(kind="weld", nps=[s1], center=P.tolist(), pipes=[p1, p2]))
            elif bend < 1:
                big = max(s1, s2)
                H = B169[big][4]
                cut[(p1, n)] = cut[(p2, n)] = H / 2
                fittings.append(
                    dict(kind="reducer", nps=[big, min(s1, s2)], center=P.tolist(), pipes=[p1, p2])
                )
            else:
                assert s1 == s2
                if abs(bend - 90) < 0.5:
                    d = B169[s1][0]
                elif abs(bend - 45) < 0.5:
                    d = B169[s1][1]
                else:
                    raise ValueError(f"bend {bend}")
                cut[(p1, n)] = cut[(p2, n)] = d
                fittings.append(
                    dict(
                        kind="elbow",
                        nps=[s1],
                        angle=round(bend, 3),
                        center=P.tolist(),
                        pipes=[p1, p2],
                    )
                )
        elif len(lst) == 3:
            # run = the two collinear ones
            best = None
            for i in range(3):
                for j in range(i + 1, 3):
                    c = np.dot(dirs[i], dirs[j])
                    if best is None or c < best[0]:
                        best = (c, i, j)
            _, i, j = best
            k = 3 - i - j
            run_nps = max(lst[i][2], lst[j][2])
            C, M = B169[run_nps][2], B169[run_nps][3]
            cut[(lst[i][0], n)] = cut[(lst[j][0], n)] = C
            cut[(lst[k][0], n)] = M
            fittings.append(
                dict(
                    kind="tee",
                    nps=[run_nps, lst[k][2]],
                    center=P.tolist(),
                    pipes=[lst[i][0], lst[j][0], lst[k][0]],
                )
            )
        else:
            raise ValueError("no crosses")
    tp = []
    for pid, a, b, nps in pipes:
        d = unit(nodes[b] - nodes[a])
        s = nodes[a] + d * cut[(pid, a)]
        e = nodes[b] - d * cut[(pid, b)]
        assert np.dot(e - s, d) > 0.02, pid
        tp.append(
            dict(
                id=pid,
                nps=nps,
                od=OD[nps],
                start=s.tolist(),
                end=e.tolist(),
                length=float(np.linalg.norm(e - s)),
            )
        )
    return tp, fittings


def ray_cyl(o, d, s, e, r):
    a = e - s
    L = np.linalg.norm(a)
    a = a / L
    w = o - s
    dp = d - np.dot(d, a) * a
    wp = w - np.dot(w, a) * a
    A = np.dot(dp, dp)
    B = 2 * np.dot(dp, wp)
    C = np.dot(wp, wp) - r * r
    disc = B * B - 4 * A * C
    if A < 1e-15 or disc < 0:
        return None
    for t in sorted([(-B - math.sqrt(disc)) / (2 * A), (-B + math.sqrt(disc)) / (2 * A)]):
        if t > 1e-6:
            h = np.dot(o + t * d - s, a)
            if 0 <= h <= L:
                return t
    return None


def ray_plane(o, d, p, n):
    den = np.dot(d, n)
    if abs(den) < 1e-12:
        return None
    t = np.dot(np.asarray(p) - o, n) / den
    return t if t > 1e-6 else None


def cast(o, d, pipes, planes):
    best = (None, None)
    for p in pipes:
        t = ray_cyl(o, d, np.array(p["start"]), np.array(p["end"]), p["od"] / 2)
        if t is not None and (best[0] is None or t < best[0]):
            best = (t, p["id"])
    for i, (pp, nn) in enumerate(planes):
        t = ray_plane(o, d, pp, np.asarray(nn, float))
        if t is not None and (best[0] is None or t < best[0]):
            best = (t, f"plane{i}")
    return best


def jitter(d, rng):
    pan = math.atan2(d[1], d[0]) + rng.normal(0, SIG_P)
    tilt = math.asin(max(-1, min(1, d[2]))) + rng.normal(0, SIG_P)
    return np.array(
        [math.cos(tilt) * math.cos(pan), math.cos(tilt) * math.sin(pan), math.sin(tilt)]
    )


SPREAD = "strat"  # "strat": operator spreads the shots evenly along the pipe; "uniform": random


def shoot_pipe(p, S, pipes, planes, rng, n, phi_max_deg=75, n_graze=0, margin=0.04):
    s0, e0 = np.array(p["start"]), np.array(p["end"])
    a = unit(e0 - s0)
    L = np.linalg.norm(e0 - s0)
    r = p["od"] / 2
    m = min(margin, 0.1 * L)
    pts = []
    tries = 0
    while len(pts) < n and tries < 50 * n:
        tries += 1
        if SPREAD == "strat":
            h = m + (L - 2 * m) * ((len(pts) + rng.uniform(0, 1)) / n)
        else:
            h = rng.uniform(m, L - m)
        c = s0 + a * h
        v = S - c
        vp = v - np.dot(v, a) * a
        u = unit(vp)
        w = np.cross(a, u)
        phi = math.radians(rng.uniform(-phi_max_deg, phi_max_deg))
        tgt = c + r * (math.cos(phi) * u + math.sin(phi) * w)
        d0 = unit(tgt - S)
        d = jitter(d0, rng)
        t, hit = cast(S, d, pipes, planes)
        if hit != p["id"]:
            continue  # operator re-aims when the beam is blocked
        pts.append(S + d0 * (t + rng.normal(0, SIG_R)))
    grazes = 0
    tries = 0
    while grazes < n_graze and tries < 200:
        tries += 1
        h = rng.uniform(m, L - m)
        c = s0 + a * h
        d0 = unit(c - S)
        side = np.cross(d0, a)
        side = unit(side)
        tgt = c + side * r * rng.choice([-1, 1]) * rng.uniform(1.01, 1.12)
        d0 = unit(tgt - S)
        d = jitter(d0, rng)
        t, hit = cast(S, d, pipes, planes)
        if t is None or hit == p["id"] or not str(hit).startswith("plane"):
            continue
        if t - np.linalg.norm(c - S) > 1.5:
            continue  # background farther than 1.5 m behind: not a wall 'behind' the pipe
        pts.append(S + d0 * (t + rng.normal(0, SIG_R)))
        grazes += 1
    order = rng.permutation(len(pts))
    return [pts[i] for i in order], grazes


def make_case(
    name,
    spools,
    station,
    units,
    seed,
    planes=(),
    links="all",
    nominal=False,
    stations=None,
    phi_max=None,
    n_graze=0,
    group_prefix="SP",
    out="cases",
    spread="strat",
):
    """spools: list of (nodes, pipes).  stations: optional pid -> station (m)."""
    global SPREAD
    SPREAD = spread
    rng = np.random.default_rng(seed)
    k = UNIT[units]
    allp, allf, objs, link_pairs = [], [], [], []
    for si, (nodes, pipes) in enumerate(spools):
        tp, tf = build(nodes, pipes)
        for p in tp:
            p["group"] = f"{group_prefix}-{si + 1}"
        for f in tf:
            f["group"] = f"{group_prefix}-{si + 1}"
        allp += tp
        allf += tf
        for f in tf:
            ps = f["pipes"]
            if f["kind"] == "tee":
                link_pairs += [[ps[0], ps[1]], [ps[0], ps[2]]]
            else:
                link_pairs.append(ps)
    S0 = np.asarray(station, float)
    for p in allp:
        S = np.asarray(stations[p["id"]], float) if stations and p["id"] in stations else S0
        n = int(rng.integers(20, 41))
        phim = (phi_max or {}).get(p["id"], 75) if isinstance(phi_max, dict) else (phi_max or 75)
        pts, g = shoot_pipe(
            p,
            S,
            allp,
            planes,
            rng,
            n,
            phim,
            n_graze if planes else 0,
            margin=0.01 if p["length"] < 0.3 else 0.04,
        )
        assert len(pts) >= 20, (name, p["id"], len(pts))
        p["shots"] = len(pts)
        p["grazes"] = g
        p["station"] = S.tolist()
        o = {
            "id": p["id"],
            "kind": "cylinder",
            "group": p["group"],
            "points": [[round(x / k, 4 if units != "m" else 6) for x in q] for q in pts],
        }
        if nominal:
            o["nominal"] = f'{p["nps"]}"'
        if stations and p["id"] in stations:
            o["station"] = [round(x / k, 4) for x in S]
        objs.append(o)
    if links == "all":
        lk = link_pairs
    elif links == "none":
        lk = None
    else:
        lk = links
    scan = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": units,
        "name": name,
        "sensor": {"position": [round(x / k, 4) for x in S0], "range_sigma": round(SIG_R / k, 6)},
        "objects": objs,
    }
    if lk:
        scan["links"] = lk
    truth = {
        "name": name,
        "units_file": units,
        "seed": seed,
        "pipes": allp,
        "fittings": allf,
        "links": lk,
        "planes": [[list(map(float, a)), list(map(float, b))] for a, b in planes],
    }
    Path(out).mkdir(exist_ok=True)
    Path(out, name + ".json").write_text(json.dumps(scan, indent=1))
    Path(out, name + ".truth.json").write_text(json.dumps(truth, indent=1))
    return scan, truth


def xf(nodes, R=None, T=(0, 0, 0)):
    R = np.eye(3) if R is None else R
    return {k: (R @ np.asarray(v, float) + np.asarray(T, float)).tolist() for k, v in nodes.items()}


def all_cases(out):
    c45, s45 = math.cos(math.pi / 4), math.sin(math.pi / 4)
    # 01 L, NPS 6, mm, links
    make_case(
        "c01_L_nps6_mm_links",
        [
            (
                xf({"A": (0, 0, 0), "B": (3, 0, 0), "C": (3, 2.5, 0)}, T=(0, 0, 1.2)),
                [("P1", "A", "B", 6), ("P2", "B", "C", 6)],
            )
        ],
        (-2.5, -4.5, 1.6),
        "mm",
        1,
        out=out,
    )
    # 02 U, NPS 4, m, no links, rotated 30 deg, seen from a platform above
    make_case(
        "c02_U_nps4_m_rot30_nolinks",
        [
            (
                xf(
                    {"A": (0, 0, 0), "B": (2.5, 0, 0), "C": (2.5, 1.5, 0), "D": (0, 1.5, 0)},
                    rot_z(30),
                    (10, 5, 1.0),
                ),
                [("P1", "A", "B", 4), ("P2", "B", "C", 4), ("P3", "C", "D", 4)],
            )
        ],
        (9.0, -1.0, 4.5),
        "m",
        2,
        links="none",
        out=out,
    )
    # 03 Z with two 45s, NPS 3, inches, links
    C = np.array([2 + 1.2 * c45, 1.2 * s45, 0])
    make_case(
        "c03_Z45_nps3_in_links",
        [
            (
                xf({"A": (0, 0, 0), "B": (2, 0, 0), "C": C, "D": C + (2, 0, 0)}, T=(0, 0, 1.5)),
                [("P1", "A", "B", 3), ("P2", "B", "C", 3), ("P3", "C", "D", 3)],
            )
        ],
        (2.0, -5.0, 2.5),
        "in",
        3,
        out=out,
    )
    # 04 tee NPS 6, wall behind, grazing shots, partial links
    make_case(
        "c04_tee_nps6_wall_mm",
        [
            (
                xf(
                    {"A": (0, 0, 0), "J": (2, 0, 0), "B": (4, 0, 0), "D": (2, 0, -1.4)},
                    T=(0, 0, 2.0),
                ),
                [("P1", "A", "J", 6), ("P2", "J", "B", 6), ("P3", "J", "D", 6)],
            )
        ],
        (2.0, -5.0, 1.6),
        "mm",
        4,
        planes=[((0, 0.45, 0), (0, -1, 0))],
        n_graze=3,
        links=[["P1", "P2"], ["P1", "P3"]],
        out=out,
    )
    # 05 reducer 8x6, mm, nominal hints, no links
    make_case(
        "c05_reducer_8x6_mm_hint",
        [
            (
                xf({"A": (0, 0, 0), "R": (2.5, 0, 0), "B": (4.5, 0, 0)}, T=(0, 0, 1.4)),
                [("P1", "A", "R", 8), ("P2", "R", "B", 6)],
            )
        ],
        (2.0, -6.0, 1.0),
        "mm",
        5,
        links="none",
        nominal=True,
        out=out,
    )
    # 06 riser NPS 4 with floor, one link only
    make_case(
        "c06_riser_nps4_floor_mm",
        [
            (
                xf({"A": (0, 0, 0.4), "B": (2, 0, 0.4), "C": (2, 0, 3.4), "D": (2, 2, 3.4)}),
                [("P1", "A", "B", 4), ("P2", "B", "C", 4), ("P3", "C", "D", 4)],
            )
        ],
        (-2.0, -5.0, 1.5),
        "mm",
        6,
        planes=[((0, 0, 0), (0, 0, 1))],
        n_graze=2,
        links=[["P1", "P2"]],
        out=out,
    )
    # 07 skew 3-D L: heading 37 deg, second leg perpendicular and rising 40 deg; metres, links
    u = np.array([math.cos(math.radians(37)), math.sin(math.radians(37)), 0])
    hp = np.array([-u[1], u[0], 0])
    v = math.cos(math.radians(40)) * hp + math.sin(math.radians(40)) * np.array([0, 0, 1])
    B = np.array([1, 1, 1.0]) + 2.8 * u
    make_case(
        "c07_skew3d_nps6_m_links",
        [
            (
                {"A": (1, 1, 1.0), "B": B, "C": B + 2.2 * v},
                [("P1", "A", "B", 6), ("P2", "B", "C", 6)],
            )
        ],
        (6.0, -3.0, 1.5),
        "m",
        7,
        out=out,
    )
    # 08 rolling offset with a stub shorter than its OD, NPS 6, two 90s, links
    st = 2 * 0.229 + 0.120
    make_case(
        "c08_stub120_nps6_mm_links",
        [
            (
                xf(
                    {"A": (0, 0, 0), "B": (2.5, 0, 0), "C": (2.5, 0, st), "D": (2.5, 2.0, st)},
                    T=(0, 0, 1.0),
                ),
                [("P1", "A", "B", 6), ("P2", "B", "C", 6), ("P3", "C", "D", 6)],
            )
        ],
        (-1.5, -4.0, 1.8),
        "mm",
        8,
        out=out,
    )
    # 09 jog: two 45s with a 60 mm stub, NPS 4, no links
    st = 2 * 0.064 + 0.060
    C = np.array([2 + st * c45, st * s45, 0])
    make_case(
        "c09_jog45_stub60_nps4_nolinks",
        [
            (
                xf({"A": (0, 0, 0), "B": (2, 0, 0), "C": C, "D": C + (2, 0, 0)}, T=(0, 0, 1.3)),
                [("P1", "A", "B", 4), ("P2", "B", "C", 4), ("P3", "C", "D", 4)],
            )
        ],
        (2.0, -4.5, 1.6),
        "mm",
        9,
        links="none",
        out=out,
    )
    # 10 two stations, NPS 8 L, each leg from its own set-up
    make_case(
        "c10_two_stations_nps8_mm",
        [
            (
                xf({"A": (0, 0, 0), "B": (4, 0, 0), "C": (4, 3, 0)}, T=(0, 0, 1.5)),
                [("P1", "A", "B", 8), ("P2", "B", "C", 8)],
            )
        ],
        (2.0, -5.0, 1.6),
        "mm",
        10,
        stations={"P2": (9.0, 1.5, 1.6)},
        out=out,
    )
    # 11 arc-limited (shots within +-50 deg: 100 deg of arc), NPS 4 Z of 90s, no links
    make_case(
        "c11_arc100_nps4_nolinks",
        [
            (
                xf(
                    {"A": (0, 0, 0), "B": (2.5, 0, 0), "C": (2.5, 0, 1.2), "D": (5, 0, 1.2)},
                    T=(0, 0, 1.0),
                ),
                [("P1", "A", "B", 4), ("P2", "B", "C", 4), ("P3", "C", "D", 4)],
            )
        ],
        (2.5, -6.0, 1.6),
        "mm",
        11,
        links="none",
        phi_max=50,
        out=out,
    )
    # 12 combo: tee, reducer 6x4 after the tee, elbow NPS 4; rotated 20 deg, metres, no links, hints
    make_case(
        "c12_combo_tee_red_elbow_m",
        [
            (
                xf(
                    {
                        "A": (0, 0, 0),
                        "J": (2, 0, 0),
                        "R": (3.5, 0, 0),
                        "E": (5.5, 0, 0),
                        "F": (5.5, 2.0, 0),
                        "D": (2, 0, -1.5),
                    },
                    rot_z(20),
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
        ],
        (4.0, -5.0, 1.5),
        "m",
        12,
        links="none",
        nominal=True,
        out=out,
    )
    # 13 NPS 2 Z with 45s, mm, links
    C = np.array([1.5 + 0.8 * c45, 0.8 * s45, 0])
    make_case(
        "c13_Z45_nps2_mm_links",
        [
            (
                xf({"A": (0, 0, 0), "B": (1.5, 0, 0), "C": C, "D": C + (1.5, 0, 0)}, T=(0, 0, 1.4)),
                [("P1", "A", "B", 2), ("P2", "B", "C", 2), ("P3", "C", "D", 2)],
            )
        ],
        (1.5, -3.5, 1.7),
        "mm",
        13,
        out=out,
    )
    # 14 pipe rack: two nested parallel Ls (NPS 6 and NPS 4) 0.4 m apart, two groups, no links
    make_case(
        "c14_rack_two_spools_mm",
        [
            (
                xf({"A": (0, 0, 0), "B": (3, 0, 0), "C": (3, 2.5, 0)}, T=(0, 0, 2.0)),
                [("P1", "A", "B", 6), ("P2", "B", "C", 6)],
            ),
            (
                xf({"A": (0, 0.4, 0), "B": (2.6, 0.4, 0), "C": (2.6, 2.5, 0)}, T=(0, 0, 2.0)),
                [("Q1", "A", "B", 4), ("Q2", "B", "C", 4)],
            ),
        ],
        (-1.0, -5.0, 3.2),
        "mm",
        14,
        links="none",
        out=out,
    )


def extra_cases(out):
    c45, s45 = math.cos(math.pi / 4), math.sin(math.pi / 4)
    rack = [
        (
            xf({"A": (0, 0, 0), "B": (3, 0, 0), "C": (3, 2.5, 0)}, T=(0, 0, 2.0)),
            [("P1", "A", "B", 6), ("P2", "B", "C", 6)],
        ),
        (
            xf({"A": (0, 0.4, 0), "B": (2.6, 0.4, 0), "C": (2.6, 2.5, 0)}, T=(0, 0, 2.0)),
            [("Q1", "A", "B", 4), ("Q2", "B", "C", 4)],
        ),
    ]
    # 15 the rack with the operator's links
    make_case("c15_rack_two_spools_links_mm", rack, (-1.0, -5.0, 3.2), "mm", 14, out=out)
    # 16 the rack, uneven (random) shot placement as in v1, no links, other seed
    make_case(
        "c16_rack_two_spools_uniform_mm",
        rack,
        (-1.0, -5.0, 3.2),
        "mm",
        140,
        links="none",
        out=out,
        spread="uniform",
    )
    # 17 reducing tee 6x4 (B16.9: C 143, M 130), branch rising, inches, links
    make_case(
        "c17_reducing_tee_6x4_in",
        [
            (
                xf(
                    {"A": (0, 0, 0), "J": (2, 0, 0), "B": (4, 0, 0), "D": (2, 0, 1.3)},
                    T=(0, 0, 1.0),
                ),
                [("P1", "A", "J", 6), ("P2", "J", "B", 6), ("P3", "J", "D", 4)],
            )
        ],
        (2.0, -5.0, 1.8),
        "in",
        17,
        out=out,
    )
    # 18 riser with a 45-45 offset, NPS 4, cm, no links
    st = 0.6
    C = np.array([st * c45, 0, 2.0 + st * s45])
    make_case(
        "c18_riser_offset45_nps4_cm",
        [
            (
                xf({"A": (0, 0, 0.5), "B": (0, 0, 2.0), "C": C, "D": C + (0, 0, 1.5)}, T=(1, 1, 0)),
                [("P1", "A", "B", 4), ("P2", "B", "C", 4), ("P3", "C", "D", 4)],
            )
        ],
        (1.0, -4.0, 1.6),
        "cm",
        18,
        links="none",
        out=out,
    )
    # 19 tee whose branch is seen on 100 deg of arc only, NPS 8, no links, wall behind
    make_case(
        "c19_tee_nps8_arc_wall_mm",
        [
            (
                xf(
                    {"A": (0, 0, 0), "J": (2.5, 0, 0), "B": (5, 0, 0), "D": (2.5, 0, -1.6)},
                    T=(0, 0, 2.2),
                ),
                [("P1", "A", "J", 8), ("P2", "J", "B", 8), ("P3", "J", "D", 8)],
            )
        ],
        (2.5, -7.0, 1.5),
        "mm",
        19,
        planes=[((0, 0.5, 0), (0, -1, 0))],
        n_graze=2,
        links="none",
        phi_max={"P3": 50},
        out=out,
    )


def extra_cases2(out):
    # 20 one NPS 6 run shot as two objects (split at a butt weld, e.g. at a support), then a 90; links
    sp = [
        (
            xf({"A": (0, 0, 0), "W": (2.5, 0, 0), "B": (5, 0, 0), "C": (5, 2, 0)}, T=(0, 0, 1.5)),
            [("P1", "A", "W", 6), ("P2", "W", "B", 6), ("P3", "B", "C", 6)],
        )
    ]
    make_case("c20_split_run_weld_links_mm", sp, (2.5, -5.0, 3.5), "mm", 20, out=out)
    # 21 the same without links
    make_case(
        "c21_split_run_weld_nolinks_mm", sp, (2.5, -5.0, 3.5), "mm", 21, links="none", out=out
    )
    # 22 one long pipe scanned from two stations as two linked objects (P1 from S1, P2 from S2), elbow to P3
    make_case(
        "c22_two_station_split_links_mm",
        sp,
        (1.0, -5.0, 1.6),
        "mm",
        22,
        stations={"P2": (6.5, -4.0, 1.6), "P3": (8.0, 1.0, 1.6)},
        out=out,
    )
    # 23 wrong operator hint: NPS 6 L labelled 4"
    make_case(
        "c23_wrong_hint_mm",
        [
            (
                xf({"A": (0, 0, 0), "B": (3, 0, 0), "C": (3, 2.5, 0)}, T=(0, 0, 1.2)),
                [("P1", "A", "B", 6), ("P2", "B", "C", 6)],
            )
        ],
        (-2.5, -4.5, 1.6),
        "mm",
        23,
        nominal=True,
        out=out,
    )


if __name__ == "__main__":
    all_cases(sys.argv[1] if len(sys.argv) > 1 else "cases")
    extra_cases(sys.argv[1] if len(sys.argv) > 1 else "cases")
    extra_cases2(sys.argv[1] if len(sys.argv) > 1 else "cases")
