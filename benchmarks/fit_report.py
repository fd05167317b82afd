"""Statistics and markdown tables for ``benchmarks/fit_accuracy.py``.

A :class:`Cell` accumulates one cell's errors, bounds and times for one estimator and one data
version; the table functions turn ``{cell key: {(estimator, version): Cell}}`` into markdown and
:func:`summary` checks the targets of the fitting benchmark. Versions are ``"clean"`` and
``"outliers"``, shot over the object's exact silhouette window, and the same with the suffix
:data:`OPERATOR` when shot over an operator's window; :func:`window_table` compares the two.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: Suffix of the data versions shot over an operator's window.
OPERATOR = "@operator"
#: Suffix of the cuboid data versions acquired by the scan session's algorithm (raster, fill,
#: edge bisection) over an operator's window.
SESSION = "@session"


@dataclass
class Cell:
    """Accumulated errors of one cell for one estimator and one data version."""

    errors: dict = field(default_factory=dict)
    bounds: dict = field(default_factory=dict)
    times: list = field(default_factory=list)
    failures: int = 0
    trials: int = 0

    def add(self, name, value):
        self.errors.setdefault(name, []).append(value)

    def bound(self, name, value):
        self.bounds.setdefault(name, []).append(value)

    def values(self, name) -> np.ndarray:
        return np.asarray(self.errors.get(name, []), float)

    def rms_bound(self, name) -> float:
        b = np.asarray(self.bounds.get(name, []), float)
        return float(np.sqrt(np.mean(b**2))) if b.size else float("nan")


def _rmse(x) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else float("nan")


def _pct(x, q) -> float:
    return float(np.percentile(np.abs(x), q)) if len(x) else float("nan")


def fmt(x, digits=2) -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{digits}f}"


# --------------------------------------------------------------------------- tables


def _bound_prefix(cell: Cell) -> str:
    """``"retained_"`` for a cell with outliers (its bound is that of the shots the outliers
    leave, see ``trials.Trial``), else ``""``."""
    return "retained_" if cell.bounds.get("retained_radius") else ""


def _ratio(a, b) -> float:
    return a / b if b and math.isfinite(a) and math.isfinite(b) else float("nan")


def _z_rms(cell: Cell, name: str, prefix: str = "", degrees: bool = False) -> float:
    """RMS over the cell's trials of each error divided by that trial's own bound.

    The cell's RMSE / CRB compares two root mean squares; where the trials' bounds differ a lot
    (a pipe seen over a narrow arc has a bound several times the cell's), a single such trial
    dominates both, and the ratio is far noisier than its chi-square limit assumes. Each
    trial's error over its own bound is, for an efficient unbiased estimator, a unit normal
    (radius) or a 2-D tilt of unit RMS (axis), so ``n z_rms^2`` is chi-square with ``n``
    degrees of freedom (radius; axis: ``2 n`` when the two tilts' bounds are equal, fewer when
    one dominates). ``degrees``: the errors are in degrees and the bounds in radians.
    """
    errors = cell.values(name)
    bounds = np.asarray(cell.bounds.get(prefix + name, []), float)
    if not errors.size or errors.size != bounds.size:
        return float("nan")
    if degrees:
        bounds = np.degrees(bounds)
    return _rmse(errors / bounds)


def cylinder_table(results, kind, version, sk_name="skspatial"):
    head = (
        "| OD mm | L/D | n | trials | fails | radius med mm | p90 | bias | RMSE | CRB | RMSE/CRB "
        "| z RMS | axis med deg | p90 | RMSE | CRB | RMSE/CRB | z RMS | max | skspatial radius "
        "med mm | axis med deg | fails/trials |"
    )
    if kind == "sphere":
        head = (
            "| D m | n | trials | fails | radius med mm | p90 | bias | RMSE | CRB | RMSE/CRB "
            "| z RMS | skspatial radius med mm | fails/trials |"
        )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for key, per in results.items():
        ours = per.get(("ours", version))
        sk = per.get((sk_name, version))
        r = ours.values("radius") * 1e3
        bound = _bound_prefix(ours)
        r_b = ours.rms_bound(bound + "radius") * 1e3
        row = [f"{k:g}" for k in key] + [str(ours.trials), str(ours.failures)]
        row += [
            fmt(_pct(r, 50)),
            fmt(_pct(r, 90)),
            fmt(float(np.mean(r)) if len(r) else float("nan")),
            fmt(_rmse(r)),
            fmt(r_b),
            fmt(_ratio(_rmse(r), r_b)),
            fmt(_z_rms(ours, "radius", bound)),
        ]
        if kind == "cylinder":
            a = ours.values("axis")
            a_b = math.degrees(ours.rms_bound(bound + "axis"))
            row += [
                fmt(_pct(a, 50), 3),
                fmt(_pct(a, 90), 3),
                fmt(_rmse(a), 3),
                fmt(a_b, 3),
                fmt(_ratio(_rmse(a), a_b)),
                fmt(_z_rms(ours, "axis", bound, degrees=True)),
                fmt(float(a.max()) if len(a) else float("nan")),
            ]
        if sk is not None:
            row.append(fmt(_pct(sk.values("radius") * 1e3, 50)))
            if kind == "cylinder":
                row.append(fmt(_pct(sk.values("axis"), 50), 3))
            row.append(f"{sk.failures}/{sk.trials}")
        else:
            row += ["-"] * (3 if kind == "cylinder" else 2)
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def plane_table(results, version):
    head = (
        "| width m | n | trials | fails | normal med deg | p90 | RMSE | CRB | RMSE/CRB | "
        "skspatial normal med deg | fails/trials |"
    )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for key, per in results.items():
        ours = per.get(("ours", version))
        sk = per.get(("skspatial", version))
        a = ours.values("normal")
        b = math.degrees(ours.rms_bound("normal"))
        row = [f"{k:g}" for k in key] + [
            str(ours.trials),
            str(ours.failures),
            fmt(_pct(a, 50), 3),
            fmt(_pct(a, 90), 3),
            fmt(_rmse(a), 3),
            fmt(b, 3),
            fmt(_ratio(_rmse(a), b)),
        ]
        if sk is not None:
            row += [fmt(_pct(sk.values("normal"), 50), 3), f"{sk.failures}/{sk.trials}"]
        else:
            row += ["-", "-"]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def cuboid_table(results, version):
    head = (
        "| section m | faces | n | trials | fails | across-size med % | p90 % | length med % "
        "| orientation med deg | p90 | RMSE | CRB | RMSE/CRB |"
    )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for key, per in results.items():
        ours = per.get(("ours", version))
        across = np.concatenate([ours.values("size_a"), ours.values("size_b")]) * 100
        length = ours.values("size_len") * 100
        o = ours.values("orientation")
        b = math.degrees(ours.rms_bound("orientation"))
        row = [f"{k:g}" for k in key] + [
            str(ours.trials),
            str(ours.failures),
            fmt(_pct(across, 50)),
            fmt(_pct(across, 90)),
            fmt(_pct(length, 50)),
            fmt(_pct(o, 50), 3),
            fmt(_pct(o, 90), 3),
            fmt(_rmse(o), 3),
            fmt(b, 3),
            fmt(_ratio(_rmse(o), b)),
        ]
        lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


# --------------------------------------------------------------------------- windows


def _cell_measures(kind, cell):
    """(measure label, value) pairs of one cell for the window comparison."""
    if kind in ("cylinder", "sphere"):
        bound = _bound_prefix(cell)
        r = cell.values("radius")
        out = [("radius RMSE / CRB", _ratio(_rmse(r), cell.rms_bound(bound + "radius")))]
        if kind == "cylinder":
            a = cell.values("axis")
            axis_bound = math.degrees(cell.rms_bound(bound + "axis"))
            out.append(("axis RMSE / CRB", _ratio(_rmse(a), axis_bound)))
        return out
    if kind == "plane":
        a = cell.values("normal")
        return [("normal RMSE / CRB", _ratio(_rmse(a), math.degrees(cell.rms_bound("normal"))))]
    across = np.concatenate([cell.values("size_a"), cell.values("size_b")]) * 100
    return [
        ("across-size median error %", _pct(across, 50)),
        ("across-size p90 error %", _pct(across, 90)),
        ("length median error %", _pct(cell.values("size_len") * 100, 50)),
        ("orientation median deg", _pct(cell.values("orientation"), 50)),
    ]


def window_table(all_results, estimator="ours"):
    """Per kind, data version and measure: median and worst cell, exact vs operator window.

    Parameters
    ----------
    all_results : dict
        ``{kind: {cell key: {(estimator, version): Cell}}}`` with both the plain versions and
        their :data:`OPERATOR` twins.

    Returns
    -------
    str
        A markdown table; kinds without operator-window cells are left out.
    """
    head = (
        "| kind | data | measure | exact window: median cell | worst cell "
        "| operator window: median cell | worst cell |"
    )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for kind in ("cylinder", "sphere", "plane", "cuboid"):
        res = all_results.get(kind)
        if not res:
            continue
        for version in ("clean", "outliers"):
            values = {}
            for per in res.values():
                for window, v in (("exact", version), ("operator", version + OPERATOR)):
                    cell = per.get((estimator, v))
                    if cell is None:
                        continue
                    for label, value in _cell_measures(kind, cell):
                        values.setdefault(label, {}).setdefault(window, []).append(value)
            for label, by_window in values.items():
                if "operator" not in by_window:
                    continue
                row = [kind, version, label]
                for window in ("exact", "operator"):
                    x = np.asarray(by_window.get(window, []), float)
                    x = x[np.isfinite(x)]
                    row += [fmt(float(np.median(x)) if x.size else float("nan"))]
                    row += [fmt(float(x.max()) if x.size else float("nan"))]
                lines.append("| " + " | ".join(row) + " |")
    return "\n".join(lines)


def _limit(count: int) -> float:
    """99% chi-square limit of RMSE / CRB for ``count`` trials (see :func:`_significant`)."""
    from scipy.stats import chi2

    return math.sqrt(chi2.ppf(0.99, count) / count) if count else float("nan")


def window_cells_table(all_results, estimator="ours"):
    """The clean-data cells of the bound-referenced kinds that either window puts significantly
    above the bound, with both windows' RMSE / CRB side by side.

    Parameters
    ----------
    all_results : dict
        ``{kind: {cell key: {(estimator, version): Cell}}}`` with :data:`OPERATOR` twins.

    Returns
    -------
    str
        A markdown table (cylinder, sphere and plane cells; clean data: with outliers most cells
        are above the bound in both windows).
    """
    head = (
        "| kind | cell | measure | exact window RMSE/CRB | operator window RMSE/CRB "
        "| operator max error |"
    )
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for kind in ("cylinder", "sphere", "plane"):
        for key, per in all_results.get(kind, {}).items():
            for version in ("clean",):
                exact = per.get((estimator, version))
                operator = per.get((estimator, version + OPERATOR))
                if exact is None or operator is None:
                    continue
                for (label, a), (_, b) in zip(
                    _cell_measures(kind, exact), _cell_measures(kind, operator)
                ):
                    name = label.split()[0]  # radius, axis or normal: the error's name
                    limit = _limit(len(operator.values(name)))
                    if not (a > limit or b > limit):
                        continue
                    worst = operator.values(name)
                    worst = float(np.abs(worst).max()) if len(worst) else float("nan")
                    unit = " mm" if name == "radius" else " deg"
                    worst_text = fmt(worst * 1e3 if name == "radius" else worst) + unit
                    cell = " / ".join(f"{k:g}" for k in key)
                    lines.append(
                        f"| {kind} | {cell} | {name} | {fmt(a)} | {fmt(b)} | {worst_text} |"
                    )
    return "\n".join(lines)


# --------------------------------------------------------------------------- summary


def _times(results, estimator, n=40, versions=("clean", "outliers")):
    out = []
    for key, per in results.items():
        if key[-1] != n:
            continue
        for version in versions:
            cell = per.get((estimator, version))
            if cell:
                out.extend(cell.times)
    return np.asarray(out)


def _significant(z_values, counts, dof_per_trial: int = 1) -> str:
    """How many cells sit above the bound beyond sampling noise, judged by each cell's per-trial
    z RMS (:func:`_z_rms`).

    For an efficient unbiased estimator ``n z_rms^2`` is chi-square with ``d = n *
    dof_per_trial`` degrees of freedom, so a cell whose z RMS is above ``sqrt(chi2_0.99(d) / d)``
    (1.24 for 50 trials, 1.12 for 200) is above the bound at the 1% level. (The cell's RMSE /
    CRB is not chi-square distributed when the trials' bounds differ, as they do here.) The axis
    uses two degrees of freedom a trial, the stricter limit: exact when both tilts have the
    same bound, too strict when one dominates.
    """
    from scipy.stats import chi2

    pairs = [(z, n * dof_per_trial) for z, n in zip(z_values, counts) if math.isfinite(z)]
    if not pairs:
        return "no cell to test"
    limits = [math.sqrt(chi2.ppf(0.99, d) / d) for _, d in pairs]
    above = sum(z > lim for (z, _), lim in zip(pairs, limits))
    return (
        f"per-trial z RMS (error / that trial's CRB) worst {max(z for z, _ in pairs):.2f}, "
        f"median {np.median([z for z, _ in pairs]):.2f}: {above} cells significantly above the "
        f"bound (99% chi-square limit {min(limits):.2f})"
    )


def _bias_significance(t_values, dofs) -> str:
    """How many cells' mean error differs from zero beyond sampling noise (two-sided t-test at
    the 1% level); with 50 trials a cell's mean has a standard error of about 0.14 x CRB, so the
    0.25 x CRB target is itself within sampling noise of an unbiased estimator."""
    from scipy.stats import t as student

    if not t_values:
        return "no cell to test"
    above = sum(abs(v) > student.ppf(0.995, d) for v, d in zip(t_values, dofs))
    return f"{above} significantly non-zero (two-sided t-test, 1% level)"


def summary(all_results):
    rows = []

    def verdict(ok):
        return "met" if ok else "**missed**"

    ratios_r, ratios_a, biases, max_axis, over5 = [], [], [], 0.0, 0
    # Bias t statistics per cell, and the expected number of axis errors over 5 degrees for an
    # efficient estimator: for a 2-D tilt error with RMS bound b (radians), P(> x) =
    # exp(-x^2 / b^2) (a Rayleigh distribution), summed over the trials' bounds.
    bias_t, bias_dof, expected5 = [], [], 0.0
    trial_counts, axis_counts = [], []
    z_r, z_a = [], []
    out_ratio = []
    # (RMSE with outliers / bound of the shots left) / (clean RMSE / clean bound): how far the
    # outliers move the fit beyond the information they take away.
    efficiency_ratio = []
    for kind in ("cylinder", "sphere"):
        for per in all_results.get(kind, {}).values():
            clean = per[("ours", "clean")]
            dirty = per[("ours", "outliers")]
            r = clean.values("radius")
            rb = clean.rms_bound("radius")
            if len(r):
                ratios_r.append(_rmse(r) / rb)
                z_r.append(_z_rms(clean, "radius"))
                trial_counts.append(len(r))
                biases.append(abs(float(np.mean(r))) / rb)
                if len(r) > 2 and float(np.std(r, ddof=1)) > 0:
                    bias_t.append(
                        float(np.mean(r)) / (float(np.std(r, ddof=1)) / math.sqrt(len(r)))
                    )
                    bias_dof.append(len(r) - 1)
                out_ratio.append(_rmse(dirty.values("radius")) / _rmse(r))
                kept = dirty.rms_bound("retained_radius")
                if math.isfinite(kept):
                    efficiency_ratio.append(
                        (_rmse(dirty.values("radius")) / kept) / (_rmse(r) / rb)
                    )
            if kind == "cylinder":
                a = clean.values("axis")
                ab = math.degrees(clean.rms_bound("axis"))
                if len(a):
                    ratios_a.append(_rmse(a) / ab)
                    z_a.append(_z_rms(clean, "axis", degrees=True))
                    axis_counts.append(len(a))
                    out_ratio.append(_rmse(dirty.values("axis")) / _rmse(a))
                    kept = math.degrees(dirty.rms_bound("retained_axis"))
                    if math.isfinite(kept):
                        efficiency_ratio.append(
                            (_rmse(dirty.values("axis")) / kept) / (_rmse(a) / ab)
                        )
                for cell, name in ((clean, "axis"), (dirty, "retained_axis")):
                    ax = cell.values("axis")
                    if len(ax):
                        max_axis = max(max_axis, float(ax.max()))
                        over5 += int((ax > 5.0).sum())
                    b = np.asarray(cell.bounds.get(name) or cell.bounds.get("axis", []), float)
                    if b.size:
                        expected5 += float(np.exp(-(math.radians(5.0) ** 2) / b**2).sum())
    if ratios_r:
        worst = max(ratios_r)
        rows.append(
            (
                "cylinder + sphere radius RMSE / CRB <= 1.15 in every cell",
                f"worst {worst:.2f}, median {np.median(ratios_r):.2f}, "
                f"{sum(x > 1.15 for x in ratios_r)}/{len(ratios_r)} cells over; "
                + _significant(z_r, trial_counts),
                verdict(worst <= 1.15),
            )
        )
    if ratios_a:
        worst = max(ratios_a)
        rows.append(
            (
                "cylinder axis RMSE / CRB <= 1.15 in every cell",
                f"worst {worst:.2f}, median {np.median(ratios_a):.2f}, "
                f"{sum(x > 1.15 for x in ratios_a)}/{len(ratios_a)} cells over; "
                + _significant(z_a, axis_counts, dof_per_trial=2),
                verdict(worst <= 1.15),
            )
        )
    if biases:
        worst = max(biases)
        rows.append(
            (
                "radius abs(bias) < 0.25 x CRB",
                f"worst {worst:.2f}, {sum(x >= 0.25 for x in biases)}/{len(biases)} cells over; "
                + _bias_significance(bias_t, bias_dof),
                verdict(worst < 0.25),
            )
        )
    if ratios_a:
        rows.append(
            (
                "no cylinder trial with an axis error over 5 degrees",
                f"max {max_axis:.2f} deg, {over5} trials over 5 deg (clean + outliers); an "
                f"efficient estimator would have {expected5:.1f} on these trials' bounds",
                verdict(over5 == 0),
            )
        )
    cub = all_results.get("cuboid", {})
    windows = [("", "")]
    if any(("ours", "clean" + OPERATOR) in per for per in cub.values()):
        windows = [("", ", exact silhouette window"), (OPERATOR, ", operator window")]
    if any(("ours", "clean" + SESSION) in per for per in cub.values()):
        windows.append((SESSION, ", scan session (edge bisection) over an operator window"))
    for suffix, label in windows:
        med, orient, cub_out = [], [], []
        for key, per in cub.items():
            clean = per[("ours", "clean" + suffix)]
            dirty = per[("ours", "outliers" + suffix)]
            across = np.concatenate([clean.values("size_a"), clean.values("size_b")])
            allsizes = np.concatenate([across, clean.values("size_len")])
            if key[-1] >= 30 and len(allsizes):
                med.append(float(np.median(allsizes)) * 100)
            o = clean.values("orientation")
            if len(o):
                orient.append(float(np.median(o)))
                d_o = dirty.values("orientation")
                if len(d_o):
                    cub_out.append(float(np.median(d_o)) / max(float(np.median(o)), 1e-9))
            d_all = np.concatenate(
                [dirty.values("size_a"), dirty.values("size_b"), dirty.values("size_len")]
            )
            if len(d_all) and len(allsizes):
                cub_out.append(float(np.median(d_all)) / max(float(np.median(allsizes)), 1e-9))
        if med:
            rows.append(
                (
                    f"cuboid sizes: median error <= 1% with 30+ points (every cell){label}",
                    f"worst cell {max(med):.2f}%, median cell {np.median(med):.2f}%",
                    verdict(max(med) <= 1.0),
                )
            )
        if orient:
            rows.append(
                (
                    f"cuboid orientation within 0.5 deg (cell medians){label}",
                    f"worst cell median {max(orient):.3f} deg",
                    verdict(max(orient) <= 0.5),
                )
            )
        if not suffix:
            out_ratio.extend(cub_out)
    if out_ratio:
        finite = [x for x in out_ratio if math.isfinite(x)]
        worst = max(finite) if finite else float("nan")
        rows.append(
            (
                "with 20% edge outliers: within 1.3 x the clean figures",
                f"worst ratio {worst:.2f} (cylinder/sphere RMSE, cuboid medians), "
                f"{sum(x > 1.3 for x in finite)}/{len(finite)} over",
                verdict(worst <= 1.3),
            )
        )
    finite = [x for x in efficiency_ratio if math.isfinite(x)]
    if finite:
        worst = max(finite)
        rows.append(
            (
                "with 20% edge outliers, against the bound of the shots they leave: (RMSE / "
                "retained-shot CRB) within 1.3 x the clean RMSE / CRB (cylinder + sphere radius, "
                "cylinder axis)",
                f"worst ratio {worst:.2f}, median {np.median(finite):.2f}, "
                f"{sum(x > 1.3 for x in finite)}/{len(finite)} over",
                verdict(worst <= 1.3),
            )
        )
    for kind, target in (("cylinder", 2.0), ("cuboid", 5.0)):
        res = all_results.get(kind)
        if not res:
            continue
        for versions, label in ((("clean",), "clean"), (("outliers",), "with 20% outliers")):
            t = _times(res, "ours", versions=versions)
            if not t.size:
                continue
            ms = float(np.median(t)) * 1e3
            text = f"median {ms:.2f} ms over {t.size} fits"
            sk_t = _times(res, "skspatial", versions=versions)
            if sk_t.size:
                sk_ms = float(np.median(sk_t)) * 1e3
                text += f"; skspatial {sk_ms:.2f} ms, {sk_ms / ms:.1f}x ours"
            rows.append(
                (
                    f"{kind} fit time at 40 points <= {target:g} ms, {label}",
                    text,
                    verdict(ms <= target),
                )
            )
    lines = ["| target | measured | verdict |", "|---|---|---|"]
    lines += [f"| {a} | {b} | {c} |" for a, b, c in rows]
    return "\n".join(lines)
