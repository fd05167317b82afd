"""The report of ``benchmarks/fit_digest.py diff A.json B.json``: what changed between two runs
of the same point sets, and whether the changed fits got better or worse against the truth.

Each set falls in one class: *identical* (the same outcome to the last bit, or the same
refusal), *changed* (both fitted, something differs: a parameter, a standard error, the
inlier count, the method, the notes count), *newly refused* (fitted in A, refused in B), *no
longer refused*, *exception changed* (refused in both, another class or message).

Errors against the truth (each set's ``truth``): cylinders and spheres the radius's relative
error and (cylinders) the axis angle, degrees; planes the normal's angle; cuboids the worst
relative size error and the frame's rotation angle, the fitted axes matched to the true ones
(as ``fit_accuracy.cuboid_errors``); a fit of another kind than the truth's (``auto``) is
*wrong kind*. A changed set is *worse* when an error grew by more than 1% of itself and 0.0001
(relative errors) or by more than 0.1 degree (angles), or it took the wrong kind; *better* the
other way round; *mixed* when both; else *same*.
"""

from __future__ import annotations

import itertools
import math
from collections import Counter

import numpy as np

#: Error measures: name -> (unit, threshold below which a change is "same").
METRICS = {
    "radius_rel": ("rel", 1e-4),
    "axis_deg": ("deg", 0.1),
    "normal_deg": ("deg", 0.1),
    "size_rel": ("rel", 1e-4),
    "orientation_deg": ("deg", 0.1),
}
RELATIVE_STEP = 0.01  # a relative error must also move by 1% of itself
UNCOMPARED = ("seconds", "truth")
CLASSES = ("identical", "changed", "newly refused", "no longer refused", "exception changed")


def _vector(values) -> np.ndarray:
    return np.asarray(values, dtype=np.float64)


def _angle_deg(a, b) -> float:
    a, b = _vector(a), _vector(b)
    c = abs(float(a @ b)) / (np.linalg.norm(a) * np.linalg.norm(b))
    return math.degrees(math.acos(min(1.0, c)))


def cuboid_errors(axes, size, true_axes, true_size) -> tuple[float, float]:
    """The worst relative size error and the rotation angle (degrees) between the frames, the
    fitted axes matched to the true ones by the permutation with the largest sum of absolute
    cosines, their signs made a right-handed frame (``fit_accuracy.cuboid_errors``)."""
    axes, size = _vector(axes), _vector(size)
    true_axes, true_size = _vector(true_axes), _vector(true_size)
    dots = axes @ true_axes.T
    match = max(
        (np.array(order) for order in itertools.permutations(range(3))),
        key=lambda order: float(np.abs(dots[order, np.arange(3)]).sum()),
    )
    signs = np.where(dots[match, np.arange(3)] < 0, -1.0, 1.0)
    matched = signs[:, None] * axes[match]
    if np.linalg.det(matched) < 0:
        matched[int(np.argmin(np.abs(dots[match, np.arange(3)])))] *= -1
    rotation = matched @ true_axes.T
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(rotation) - 1) / 2))))
    return float(np.max(np.abs(size[match] - true_size) / true_size)), angle


def errors(record: dict) -> dict | None:
    """The record's errors against its truth (:data:`METRICS` names, or ``wrong_kind``);
    None when it was refused or has no truth to compare with."""
    truth = record.get("truth") or {}
    if record.get("status") != "fit" or not truth:
        return None
    fitted, p = record["fitted"], record["params"]
    if truth.get("kind") and fitted != truth["kind"]:
        return {"wrong_kind": 1.0}
    out = {}
    if fitted in ("cylinder", "sphere") and "radius" in truth:
        out["radius_rel"] = abs(float(p["radius"]) - truth["radius"]) / truth["radius"]
    if fitted == "cylinder" and "axis" in truth:
        out["axis_deg"] = _angle_deg(p["axis"], truth["axis"])
    if fitted == "plane" and "normal" in truth:
        out["normal_deg"] = _angle_deg(p["normal"], truth["normal"])
    if fitted == "cuboid" and "axes" in truth:
        size, angle = cuboid_errors(p["axes"], p["size"], truth["axes"], truth["size"])
        out["size_rel"], out["orientation_deg"] = size, angle
    return out or None


def judge(before: dict, after: dict) -> tuple[str, float, str]:
    """``(verdict, regression score, what moved)`` of a changed set from its errors before and
    after; the score is the largest growth of an error (percentage points or degrees; a wrong
    kind 100), for ranking."""
    if "wrong_kind" in before or "wrong_kind" in after:
        if ("wrong_kind" in before) == ("wrong_kind" in after):
            return "same", 0.0, "wrong kind before and after"
        if "wrong_kind" in after:
            return "worse", 100.0, "right kind -> wrong kind"
        return "better", -100.0, "wrong kind -> right kind"
    worse = better = False
    score, moved = -math.inf, []
    for name, (unit, floor) in METRICS.items():
        if name not in before or name not in after:
            continue
        a, b = before[name], after[name]
        step = max(floor, RELATIVE_STEP * a) if unit == "rel" else floor
        scale = 100.0 if unit == "rel" else 1.0
        score = max(score, (b - a) * scale)
        if abs(b - a) > step:
            worse |= b > a
            better |= b < a
            shown = f"{100 * a:.3g}% -> {100 * b:.3g}%" if unit == "rel" else f"{a:.3g} -> {b:.3g}"
            moved.append(f"{name} {shown}")
    verdict = "mixed" if worse and better else "worse" if worse else "better" if better else "same"
    return verdict, (0.0 if score == -math.inf else score), "; ".join(moved)


def _outcome(record: dict) -> dict:
    return {k: v for k, v in record.items() if k not in UNCOMPARED}


def classify(a: dict, b: dict) -> str:
    """The class (:data:`CLASSES`) of one set's records in run A and run B."""
    if _outcome(a) == _outcome(b):
        return "identical"
    refused_a, refused_b = a["status"] == "refused", b["status"] == "refused"
    if refused_a and refused_b:
        return "exception changed"
    if refused_b:
        return "newly refused"
    if refused_a:
        return "no longer refused"
    return "changed"


def _source(key: str) -> str:
    return key.split("/", 1)[0]


def _median(values) -> str:
    return f"{np.median(values):.3g}" if values else "-"


def _head(name: str, run: dict) -> str:
    state = "dirty" if run.get("dirty") else "clean"
    return (
        f"{name}: {run.get('repo')} at {str(run.get('commit'))[:12]} ({state}), "
        f"{run.get('records_count')} records, {run.get('refused')} refused, "
        f"digest {str(run.get('digest'))[:16]}, {run.get('wall_seconds')} s with {run.get('jobs')} jobs"
    )


def report(run_a: dict, run_b: dict, show: int = 15) -> str:
    """The diff's text; its last line is the one-line verdict."""
    lines = [_head("A", run_a), _head("B", run_b)]
    if run_a.get("sets_sha256") != run_b.get("sets_sha256"):
        lines.append("WARNING: the runs fitted different sets files; compared on their common keys")
    if run_a.get("versions") != run_b.get("versions"):
        lines.append(
            f"WARNING: other library versions: {run_a.get('versions')} -> {run_b.get('versions')}"
        )
    a = {r["key"]: r for r in run_a["records"]}
    b = {r["key"]: r for r in run_b["records"]}
    common = [k for k in a if k in b]
    only_a, only_b = len(a) - len(common), len(b) - len(common)
    classes = {k: classify(a[k], b[k]) for k in common}
    counts = Counter(classes.values())
    lines.append("")
    lines.append(" | ".join(f"{name} {counts[name]}" for name in CLASSES))
    if only_a or only_b:
        lines.append(f"only in A {only_a} | only in B {only_b}")
    by_kind: dict = {}
    for key, name in classes.items():
        by_kind.setdefault(a[key]["kind"], Counter())[name] += 1
    lines += ["", "| kind asked | " + " | ".join(CLASSES) + " |", "|---" * (len(CLASSES) + 1) + "|"]
    for kind, counter in sorted(by_kind.items()):
        lines.append(f"| {kind} | " + " | ".join(str(counter[c]) for c in CLASSES) + " |")

    judged, verdicts = [], Counter()
    per_metric: dict = {}
    per_source: dict = {}
    for key in (k for k in common if classes[k] == "changed"):
        before, after = errors(a[key]), errors(b[key])
        source = per_source.setdefault(_source(key), Counter())
        source["changed"] += 1
        if before is None or after is None:
            verdicts["no truth"] += 1
            continue
        verdict, score, moved = judge(before, after)
        verdicts[verdict] += 1
        source[verdict] += 1
        judged.append((score, key, verdict, moved))
        for name in METRICS:
            if name in before and name in after:
                per_metric.setdefault(name, ([], []))
                per_metric[name][0].append(before[name])
                per_metric[name][1].append(after[name])
    if counts["changed"]:
        lines += ["", f"Changed fits against the truth ({counts['changed']}):"]
        lines.append(
            "  "
            + ", ".join(
                f"{verdicts[v]} {v}" for v in ("better", "worse", "mixed", "same", "no truth")
            )
        )
        for name, (before, after) in per_metric.items():
            scale, unit = (100.0, "%") if METRICS[name][0] == "rel" else (1.0, " deg")
            lines.append(
                f"  {name}: median {_median([scale * v for v in before])}{unit} -> "
                f"{_median([scale * v for v in after])}{unit}, worst {scale * max(before):.3g}{unit} -> "
                f"{scale * max(after):.3g}{unit} ({len(before)} sets)"
            )
        lines.append(
            "  by source: "
            + "; ".join(
                f"{s}: {c['changed']} changed, {c['better']} better, {c['worse']} worse"
                for s, c in sorted(per_source.items())
            )
        )
        worst = sorted((j for j in judged if j[2] in ("worse", "mixed")), reverse=True)[:show]
        if worst:
            lines += ["", f"Worst regressions (up to {show}):"]
            lines += [f"  {key} [{verdict}]: {moved}" for _, key, verdict, moved in worst]
    for name, side in (("newly refused", b), ("exception changed", b), ("no longer refused", b)):
        keys = [k for k in common if classes[k] == name][:show]
        if not keys:
            continue
        lines += ["", f"{name[0].upper()}{name[1:]} (up to {show}):"]
        for key in keys:
            if name == "no longer refused":
                found = errors(b[key]) or {}
                text = ", ".join(
                    f"{m} {100 * v:.3g}%" if METRICS.get(m, ("", 0))[0] == "rel" else f"{m} {v:.3g}"
                    for m, v in found.items()
                )
                lines.append(f"  {key}: was {a[key]['error']}; now {text or 'fitted'}")
            elif name == "exception changed":
                lines.append(f"  {key}: {a[key]['error']} -> {b[key]['error']}")
            else:
                lines.append(f"  {key}: {side[key]['error']}")
    lines += ["", _times(a, b, common), _verdict(counts, verdicts, only_a + only_b)]
    return "\n".join(lines) + "\n"


def _times(a: dict, b: dict, common: list[str]) -> str:
    """Median fit time per kind asked, A -> B (milliseconds)."""
    parts = []
    for kind in sorted({a[k]["kind"] for k in common}):
        keys = [k for k in common if a[k]["kind"] == kind]
        ta = np.median([a[k]["seconds"] for k in keys]) * 1e3
        tb = np.median([b[k]["seconds"] for k in keys]) * 1e3
        parts.append(f"{kind} {ta:.1f} -> {tb:.1f}")
    return "Median fit time, ms (A -> B; timing noise included): " + ", ".join(parts)


def _verdict(counts: Counter, verdicts: Counter, unmatched: int) -> str:
    if sum(counts[c] for c in CLASSES[1:]) == 0 and not unmatched:
        return f"verdict: IDENTICAL ({counts['identical']} sets)"
    gains = verdicts["better"] + counts["no longer refused"]
    losses = verdicts["worse"] + verdicts["mixed"] + counts["newly refused"]
    net = "net better" if gains > losses else "net worse" if losses > gains else "even"
    return (
        f"verdict: CHANGED, {net}: {counts['changed']} changed ({verdicts['better']} better, "
        f"{verdicts['worse']} worse, {verdicts['mixed']} mixed, {verdicts['same']} same), "
        f"{counts['newly refused']} newly refused, {counts['no longer refused']} no longer "
        f"refused, {counts['exception changed']} exception changed"
        + (f", {unmatched} sets in one run only" if unmatched else "")
    )
