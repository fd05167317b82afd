"""Size rules: nonstandard-diameter, ambiguous-size, hint-mismatch, contiguous-diameter-mismatch,
nonstandard-tee.

A pipe's measured outside diameter (``snap["od_fit"]`` or twice the fitted radius) with its
standard error is compared with the catalog's sizes; a size is a candidate when within
``max(3 standard errors, Tolerances.diameter_tolerance)``, the test merging snaps with.
"""

from __future__ import annotations

import numpy as np

from asbuilt.catalog import parse_nominal
from asbuilt.findings import Suggestion
from asbuilt.model import Component, Cross, Tee
from asbuilt.scan.insulation import MAX_INSULATION
from asbuilt.units import UNITS

from ._catalog import SizeTable, reducing_tee_made, tee_outlets
from ._context import Context, centre_of, ends_of, mm, stderr_value, verdict
from ._graph import FITTING_PASS, adjacency, component_map, contiguous_pipes, fittings_between

__all__ = ["CHECKS", "measured_od", "size_status"]


def measured_od(component: Component) -> tuple[float | None, float | None]:
    """The measured OD and its standard error (metres) of a pipe, or (None, None)."""
    snap = component.snap or {}
    if snap.get("od_fit") is not None:
        od = float(snap["od_fit"])
        s = snap.get("od_stderr")
        return od, None if s is None else float(s)
    if component.fit is not None and component.fit.kind == "cylinder":
        r_se = stderr_value(component.fit.stderr, "radius")
        od = 2 * (float(component.fit.primitive.radius) - float(component.insulation))
        return od, None if r_se is None else 2 * r_se
    return None, None


def _window(ctx: Context, stderr: float | None) -> float:
    return max(3.0 * (stderr or 0.0), float(ctx.general("diameter_tolerance")))


def size_status(ctx: Context, component: Component, table: SizeTable | None) -> str | None:
    """``"snapped"``, ``"no-size"``, ``"ambiguous"`` or ``"hint"`` (from merging when recorded,
    else from the catalog), or None when it cannot be known."""
    status = (component.snap or {}).get("status")
    if status:
        return str(status)
    od, se = measured_od(component)
    if table is None or od is None:
        return None
    found = table.within(od, _window(ctx, se))
    return {0: "no-size", 1: "snapped"}.get(len(found), "ambiguous")


def _candidates(component: Component, table: SizeTable | None, od: float, window: float):
    """(nominal, od) pairs from the snap mapping's ``candidates``, else from the catalog."""
    out = []
    for cand in (component.snap or {}).get("candidates") or ():
        if isinstance(cand, dict):
            nominal, cand_od = cand.get("nominal"), cand.get("od", cand.get("od_catalog"))
        elif isinstance(cand, str):
            continue  # a bare nominal size: no diameter to compare
        else:
            nominal, cand_od = (tuple(cand) + (None, None))[:2]
        if nominal is not None and cand_od is not None:
            out.append((str(nominal), float(cand_od)))
    if not out and table is not None:
        return table.within(od, window)
    return out


def _label(table: SizeTable | None, nominal: str) -> str:
    return table.label(nominal) if table is not None else f"NPS {nominal}"


#: A measured OD farther than this factor outside the catalog's range of ODs is no pipe of
#: this catalog as measured (a 115 m "pipe"): with every pipe of the scan so, a unit slip is
#: looked for (:func:`unit_slip`).
IMPLAUSIBLE_OD_FACTOR = 1.5


def unit_slip(ctx: Context, table: SizeTable | None) -> tuple[str, float] | None:
    """``(unit, factor)`` when the scan's coordinates look written in ``unit`` although the
    file declares another: every measured cylinder's OD (pipes, tanks, chimneys) lies outside
    the catalog's range of ODs by more than ``IMPLAUSIBLE_OD_FACTOR`` as declared, and every
    pipe (a component merging took for one, else every cylinder) is a catalog size, within the
    snapping window, once scaled by ``factor`` (the true unit's metres over the declared
    one's). None otherwise, and without a catalog or a scan.

    Where several units make every pipe a size (a wide window at a coarse unit, where catalog
    sizes are closer than the window, matches by chance), the evidence decides in this order:
    the operator's size hints (a unit in which a hinted pipe is not its hint's size loses), the
    fits' residuals (a unit in which a fit's RMS is no laser range finder's noise,
    :data:`PLAUSIBLE_FIT_RMS`, loses), then each pipe's distance to its nearest size in
    snapping windows."""
    scan = ctx.model.scan
    if table is None or scan is None or not table.sizes or scan.units not in UNITS:
        return None
    measured = [(c, measured_od(c)[0]) for c in ctx.pipes]
    cylinders = [c for c, od in measured if od is not None]
    if not cylinders:
        return None
    smallest = min(size for _, _, size in table.sizes) / IMPLAUSIBLE_OD_FACTOR
    largest = max(size for _, _, size in table.sizes) * IMPLAUSIBLE_OD_FACTOR
    if any(od is not None and smallest <= od <= largest for _, od in measured):
        return None
    pipes = [c for c in cylinders if c.type == "pipe"] or cylinders
    hinted = [(c, od) for c in pipes if (od := _hint(ctx, c, table)[1]) is not None]
    best = None
    for unit, metres in UNITS.items():
        if unit == scan.units:
            continue
        factor = metres / UNITS[scan.units]
        # Each pipe's distance to its nearest size, in snapping windows: the unit that makes
        # every pipe a size, the most closely, wins (a wide window can let two units match).
        score = 0.0
        for component in pipes:
            od, window = _scaled(ctx, component, factor)
            sizes = _sizes_at(table, od, window)
            if not sizes:
                break
            score += abs(sizes[0][1] - od) / window
        else:
            scaled = [(_scaled(ctx, c, factor), hint_od) for c, hint_od in hinted]
            unhinted = sum(abs(od - hint_od) > window for (od, window), hint_od in scaled)
            low, high = PLAUSIBLE_FIT_RMS
            noisy = sum(
                not low <= c.fit.rms * factor <= high
                for c in pipes
                if c.fit is not None and np.isfinite(c.fit.rms) and c.fit.rms > 0
            )
            key = (unhinted, noisy, score)
            if best is None or key < best[0]:
                best = (key, unit, factor)
    return None if best is None else (best[1], best[2])


#: The RMS residual (metres) a cylinder fit of a laser range finder's shots can have: 0.05 mm
#: (a survey-grade instrument on a smooth pipe) to 15 mm (an inexpensive one at its range
#: limit on a rough or lagged surface). A unit reading in which a fit's RMS falls outside is
#: no scan of this kind: millimetre numbers read as centimetres make 2 mm of noise 20 mm.
PLAUSIBLE_FIT_RMS = (5e-5, 0.015)


def _hint(ctx: Context, component: Component, table: SizeTable | None):
    """The operator's size hint of a pipe (the text, as merging recorded it or as the scan
    gives it) and the OD (metres) it names (merging's, else the catalog's); None where unknown."""
    snap = component.snap or {}
    info = snap.get("hint") if isinstance(snap.get("hint"), dict) else {}
    hint = info.get("nominal") or ctx.hint(component)
    od = info.get("od")
    if od is None and table is not None and hint:
        od = table.od(hint)
    return hint, None if od is None else float(od)


def _scaled(ctx: Context, component: Component, factor: float) -> tuple[float, float]:
    """A pipe's measured OD scaled by ``factor`` and its snapping window at that scale, metres."""
    od, se = measured_od(component)
    return od * factor, _window(ctx, None if se is None else se * factor)


def _sizes_at(table: SizeTable, od: float, window: float):
    """The catalog sizes ``(nominal, od)`` within ``window`` of ``od`` (metres), nearest first."""
    return sorted(table.within(od, window), key=lambda size: abs(size[1] - od))


def check_nonstandard(ctx: Context, table: SizeTable | None) -> None:
    slug = "nonstandard-diameter"
    slip = unit_slip(ctx, table)
    for comp in ctx.pipes:
        if size_status(ctx, comp, table) != "no-size":
            continue
        od, se = measured_od(comp)
        if od is None:
            continue
        where = centre_of(comp.geometry)
        catalog = table.standard if table is not None else (ctx.model.catalog or "catalog")
        count = max(int(ctx.opt(slug, "suggest")), 1)
        if table is not None:
            nearest = table.nearest(od, count)
        else:  # no catalog at hand: the nearest sizes merging recorded
            cands = sorted(_candidates(comp, None, od, 0.0), key=lambda c: abs(c[1] - od))
            nearest = [(n, s, od - s) for n, s in cands[:count]]
        if not nearest:
            ctx.emit(
                slug,
                [comp.id],
                f"OD {mm(od)} is no {catalog} size",
                location=where,
                measured=od,
                unit="m",
                stderr=se,
            )
            continue
        snap = comp.snap or {}
        joint = snap.get("od_joint")
        if joint is not None and len(snap.get("run") or ()) > 1:
            # Merging sized the whole run from its pipes' fits together: judge, and say, that.
            od, se = float(joint), snap.get("od_joint_stderr")
            se = None if se is None else float(se)
            nearest = table.nearest(od, count) if table is not None else nearest
        name, size_od, off = nearest[0]
        run = snap.get("run") if joint is not None else None
        together = (
            f" (the run {', '.join(run)} measured together; this pipe alone "
            f"{mm(measured_od(comp)[0])})"
            if run and len(run) > 1
            else ""
        )
        tol = float(ctx.general("diameter_tolerance"))
        outcome = verdict(abs(off), tol, se, ctx.k)
        suggestions = ()
        if slip is not None:
            unit, factor = slip
            sizes = _sizes_at(table, *_scaled(ctx, comp, factor)) or table.nearest(od * factor, 1)
            true_name, true_od = sizes[0][0], sizes[0][1]
            suggestions = (
                Suggestion(
                    f'check the scan\'s "units": its numbers look like {unit}, not '
                    f"{ctx.model.scan.units}; read so, every pipe of the scan is a catalog size "
                    f"(this one {_label(table, true_name)} = {mm(true_od)})",
                    {"field": "units", "value": unit},
                ),
            )
        suggestions += tuple(
            Suggestion(
                f"use {_label(table, n)} ({mm(s)}, {mm(abs(d))} {'smaller' if d > 0 else 'larger'} "
                "than measured) if the catalog and material are right",
                {"object": comp.id, "field": "nominal", "value": n, "od": s},
                unambiguous=False,
            )
            for n, s, d in nearest
        ) + (Suggestion("check the material and catalog (--catalog), or rescan the pipe"),)
        # What was measured, how well, and against which limit: the tolerance the verdict judges
        # the distance to the nearest size by, and the window a size would have been taken in.
        known = f" +- {mm(se)}" if se else ""
        window = _window(ctx, se)
        within = (
            f"within {mm(window)}: 3 standard errors, at least the {mm(tol)} diameter tolerance"
            if window > tol
            else f"within the {mm(tol)} diameter tolerance"
        )
        ctx.emit(
            slug,
            [comp.id],
            f"OD {mm(od)}{known} is no {catalog} size (nearest {_label(table, name)} = "
            f"{mm(size_od)}, {mm(abs(off))} off; a size is taken {within}){together}",
            location=where,
            measured=abs(off),
            allowed=tol,
            stderr=se,
            unit="m",
            suggestions=suggestions,
            outcome="violation" if outcome == "pass" else outcome,
            rescan="scan more points over a wider arc of the pipe to shrink the OD's uncertainty",
        )


#: A pipe snapped with its run to a size this many of its own standard errors from its own
#: fitted OD, and nearer another size, may be that other size (a reducer merging left out).
EQUALISED_SIGMAS = 2.0


def _equalised_away(comp: Component, table: SizeTable | None):
    """``(nearest nominal, its OD, the snapped OD, standard errors off)`` when ``comp`` was
    snapped with the other pipes of its run (``snap["run"]``) to a size more than
    :data:`EQUALISED_SIGMAS` of its own standard errors from its own fitted OD, and another
    catalog size lies nearer that OD; else None.

    Merging equalises contiguous pipes whose ODs agree within three standard errors: a poorly
    measured NPS 6 pipe (187 +- 15 mm) after an NPS 8 one was built as NPS 8 with no reducer,
    silently (an independent review's reducer and reducing-tee scenes, 2 of 28 joints).
    """
    snap = comp.snap or {}
    run = snap.get("run") or ()
    if table is None or snap.get("status") != "snapped" or len(run) < 2:
        return None
    od, se = measured_od(comp)
    snapped = snap.get("od_catalog")
    if od is None or not se or snapped is None:
        return None
    off = abs(od - float(snapped)) / se
    if not off > EQUALISED_SIGMAS:
        return None
    nominal, size_od = min(((n, s) for n, _, s in table.sizes), key=lambda row: abs(row[1] - od))
    if abs(size_od - od) >= abs(float(snapped) - od) or abs(size_od - float(snapped)) < 5e-5:
        return None
    return nominal, size_od, float(snapped), off


def _check_equalised(ctx: Context, table: SizeTable | None, slug: str) -> None:
    for comp in ctx.pipes:
        found = _equalised_away(comp, table)
        if found is None:
            continue
        nominal, size_od, snapped, off = found
        od, se = measured_od(comp)
        others = ", ".join(i for i in comp.snap["run"] if i != comp.id)
        ctx.emit(
            slug,
            [comp.id],
            f"OD {mm(od)} +- {mm(se)} is nearer {_label(table, nominal)} ({mm(size_od)}) than "
            f"the {mm(snapped)} it was given with {others} ({off:.1f} standard errors off its own "
            "fit): the size cannot be decided, and a reducer may be missing",
            location=centre_of(comp.geometry),
            measured=od,
            allowed=snapped,
            stderr=se,
            unit="m",
            suggestions=(
                Suggestion(
                    f"scan more points over a wider arc of {comp.id} to shrink the OD's uncertainty"
                ),
                Suggestion(f'give {comp.id} a size hint ("nominal") in the scan'),
            ),
        )


def check_ambiguous(ctx: Context, table: SizeTable | None) -> None:
    slug = "ambiguous-size"
    _check_equalised(ctx, table, slug)
    for comp in ctx.pipes:
        if size_status(ctx, comp, table) != "ambiguous":
            continue
        od, se = measured_od(comp)
        if od is None:
            continue
        cands = _candidates(comp, table, od, _window(ctx, se))
        sizes = ", ".join(f"{_label(table, n)} = {mm(s)}" for n, s in cands)
        suggestions = (
            Suggestion(
                f"scan more points over a wider arc of {comp.id} to shrink the OD's uncertainty"
            ),
            Suggestion(f'give {comp.id} a size hint ("nominal") in the scan'),
        ) + tuple(
            Suggestion(
                f"use {_label(table, n)} ({mm(s)})",
                {"object": comp.id, "field": "nominal", "value": n, "od": s},
            )
            for n, s in cands
        )
        ctx.emit(
            slug,
            [comp.id],
            f"OD {mm(od)} +- {mm(se or 0.0)} fits {len(cands)} sizes ({sizes}); the size cannot "
            "be decided",
            location=centre_of(comp.geometry),
            measured=od,
            stderr=se,
            unit="m",
            suggestions=suggestions,
        )


#: How many catalog size steps a hint may be off the fitted size for "use the fitted size" to be
#: an unambiguous fix: one, the neighbouring size, is a plausible misread or mistyped hint
#: (6" for an 8" pipe; steps are the catalog's, so NPS 3 1/2 makes 3" and 4" two). Further off, the operator's hint names a clearly different pipe and the
#: fit is the doubtful side: lagging, insulation, a clamp or a coating make it larger (a 4" pipe
#: under 50 mm of lagging fits NPS 8), so a person must decide. Steps, not a ratio of ODs: the
#: neighbouring sizes of ASME B36.10M are 25-33 % apart at NPS 1/8-1 1/4 but 4-25 % apart from
#: NPS 8 up, so no one ratio separates a misread size from a lagged pipe across the catalog.
_HINT_MISREAD_STEPS = 1


def _size_steps(table: SizeTable, od_a: float, od_b: float) -> int:
    """How many catalog size steps lie between two ODs (metres): the number of the table's
    sizes above the smaller OD and up to the larger, each within 0.05 mm (0: the same size)."""
    low, high = sorted((od_a, od_b))
    return sum(1 for _, _, s in table.sizes if low + 5e-5 < s <= high + 5e-5)


def _hint_units(
    ctx: Context, component: Component, od: float, hint_od: float, slip
) -> tuple[str, float] | None:
    """``(unit, factor)`` when a pipe's disagreement with its hint is a unit slip rather than
    lagging or a misread: :func:`unit_slip` found one for the whole scan (``slip``), or the
    fitted OD is further from the hint's OD than any insulation explains (half the difference
    over :data:`~asbuilt.scan.insulation.MAX_INSULATION`) and another unit's reading (a ratio
    of 1000, 100, 10, 25.4, 304.8, 12, 39.37... between the units) puts it within the snapping
    window of the hint's OD. None otherwise, and without a scan of known units."""
    if slip is not None:
        return slip
    scan = ctx.model.scan
    if scan is None or scan.units not in UNITS or abs(od - hint_od) / 2 <= MAX_INSULATION:
        return None
    best = None
    for unit, metres in UNITS.items():
        factor = metres / UNITS[scan.units]
        scaled, window = _scaled(ctx, component, factor)
        off = abs(scaled - hint_od) / window
        if unit != scan.units and off <= 1 and (best is None or off < best[0]):
            best = (off, unit, factor)
    return None if best is None else (best[1], best[2])


def _hint_units_text(ctx: Context, component: Component, hint_od: float, reading) -> str:
    """What a pipe's numbers look like read in ``reading`` = (unit, factor): ``numbers look like
    mm, not m; read so, P1's OD is 167.1 mm, the hint's size``."""
    unit, factor = reading
    scaled, window = _scaled(ctx, component, factor)
    return (
        f"numbers look like {unit}, not {ctx.model.scan.units}; read so, {component.id}'s OD "
        f"is {mm(scaled)}" + (", the hint's size" if abs(scaled - hint_od) <= window else "")
    )


def check_hint(ctx: Context, table: SizeTable | None) -> None:
    slug = "hint-mismatch"
    slip = unit_slip(ctx, table)
    for comp in ctx.pipes:
        snap = comp.snap or {}
        hint, hint_od = _hint(ctx, comp, table)
        if not hint or snap.get("hint_rejected"):
            continue
        if hint_od is None and table is not None and comp.type == "pipe":
            # only a pipe's hint names a catalog size (a tank's "3000 ID" does not)
            catalog = table.standard
            unread = parse_nominal(hint) is None
            ctx.emit(
                slug,
                [comp.id],
                f"the hint {hint!r} "
                + ("cannot be read as a nominal size" if unread else f"names no {catalog} size")
                + ", so it was not used",
                location=centre_of(comp.geometry),
                suggestions=(
                    Suggestion(
                        f"write {comp.id}'s hint as a nominal size of {catalog} (e.g. 4\" or "
                        "DN100), or choose the catalog it belongs to (--catalog)"
                    ),
                ),
            )
            continue
        od, se = measured_od(comp)
        if hint_od is None or od is None:
            continue
        tol = float(ctx.general("diameter_tolerance"))
        off = abs(od - float(hint_od))
        if verdict(off, tol, se, ctx.k) != "violation":
            continue  # a hint is given because fits can be weak: only a clear disagreement counts
        fitted = table.within(od, _window(ctx, se)) if table is not None else []
        suggestions = [Suggestion(f"check the hint {hint!r} on the object, or rescan it")]
        steps = None if table is None else _size_steps(table, float(hint_od), od)
        if len(fitted) == 1:
            n, s = fitted[0]
            steps = _size_steps(table, float(hint_od), s)
            suggestions.insert(
                0,
                Suggestion(
                    f"use the fitted size {_label(table, n)} ({mm(s)}) instead of the hint",
                    {
                        "object": comp.id,
                        "field": "nominal",
                        "value": n,
                        "od": s,
                        "reject_hint": True,
                    },
                    # the neighbouring size is a plausible misread hint; a size further off is
                    # not: the operator said what the pipe is, and lagging, a clamp or a
                    # coating make a fit larger (a person decides, --fix does not)
                    unambiguous=steps <= _HINT_MISREAD_STEPS,
                ),
            )
        cause = ""
        reading = _hint_units(ctx, comp, od, float(hint_od), slip)
        if reading is not None:
            # 83 m of "lagging" is millimetre numbers in a metre file: say so, not insulation
            text = _hint_units_text(ctx, comp, float(hint_od), reading)
            change = {"field": "units", "value": reading[0]}
            suggestions.insert(0, Suggestion(f'check the scan\'s "units": its {text}', change))
            cause = (
                f"; the fit is {od / float(hint_od):.4g} times the hint's OD, a unit slip rather "
                f"than lagging: the scan's {text}"
            )
        elif abs(od - float(hint_od)) / 2 > MAX_INSULATION:
            cause = (
                f"; more than any lagging or insulation explains (at most "
                f'{mm(MAX_INSULATION)} thick): check the hint, the fit and the scan\'s "units"'
            )
        elif steps is not None and steps > _HINT_MISREAD_STEPS and od > float(hint_od):
            more = mm((od - float(hint_od)) / 2)
            cause = (
                f"; the fit is {steps} catalog sizes above the hint: lagging or insulation about "
                f"{more} thick, a coating or a clamp may cover the pipe (give the scan object's "
                '"insulation" thickness)'
                if not comp.insulation
                else f"; the fit is {steps} catalog sizes above the hint: the insulation may be "
                f"about {more} thicker than the {mm(comp.insulation)} given"
            )
        ctx.emit(
            slug,
            [comp.id],
            f"the hint {hint} ({mm(hint_od)}) disagrees with the fitted OD {mm(od)} by {mm(off)}"
            + cause,
            location=centre_of(comp.geometry),
            measured=off,
            allowed=tol,
            stderr=se,
            unit="m",
            suggestions=tuple(suggestions),
        )


def is_merged(model) -> bool:
    """Whether merging ran on a model: it has spools or fittings."""
    return bool(model.spools) or any(
        c.type in ("elbow", "tee", "cross", "reducer", "coupling") for c in model.components
    )


def _size_of(comp: Component, table: SizeTable | None) -> tuple[str | None, float | None]:
    od = 2 * comp.geometry.outer_radius if hasattr(comp.geometry, "outer_radius") else None
    if od is None and hasattr(comp.geometry, "radius"):
        od = 2 * comp.geometry.radius
    nominal = comp.nominal
    if nominal is None and table is not None and od is not None:
        nominal = table.nominal_for(od)
    return nominal, od


def _size_change_explained(comps, between, ca, cb) -> bool:
    """Whether the fittings ``between`` two pipes explain a change of size: a reducer, or a tee
    one of whose pipes is its outlet no larger than the run (ASME B16.9 tees reduce on the
    outlet only: a run changing size at a tee, or an outlet larger than the run, needs a
    reducer)."""
    if any(f.type == "reducer" for f in between):
        return True
    for tee in (f for f in between if f.type in ("tee", "cross")):
        g = tee.geometry
        if not isinstance(g, Tee | Cross):
            continue
        for branch in (ca, cb):
            at_outlet = any(
                float(np.linalg.norm(np.asarray(end) - outlet)) < 1e-3
                for end in ends_of(branch.geometry)
                for outlet in g.outlets
            )
            if at_outlet and g.branch_outer_radius <= g.outer_radius + 1e-9:
                return True
    return False


def check_contiguous(ctx: Context, table: SizeTable | None) -> None:
    slug = "contiguous-diameter-mismatch"
    if not is_merged(ctx.model):
        return  # merging inserts the reducers that explain a size change: judge merged models
    comps = component_map(ctx.model)
    pipes = [c.id for c in ctx.pipes]
    graph = adjacency(
        ctx.model, float(ctx.opt("clash", "touch_distance")), float(ctx.general("joint_distance"))
    )
    tol = float(ctx.general("diameter_tolerance"))
    touching = adjacency(ctx.model, float(ctx.opt("clash", "touch_distance")), links=False)
    # through tees too: a tee passes its run's size on (B16.9 tees reduce on the outlet only)
    passing = (*FITTING_PASS, "tee", "cross")
    for a, b, path in contiguous_pipes(ctx.model, graph, pipes, passing):
        between = fittings_between(ctx.model, touching, a, b) or []
        if _size_change_explained(comps, [comps[x] for x in between], comps[a], comps[b]):
            continue  # a reducer, or a tee's smaller outlet, joins them: sizes may differ
        ca, cb = comps[a], comps[b]
        (na, oda), (nb, odb) = _size_of(ca, table), _size_of(cb, table)
        if oda is None or odb is None:
            continue
        (fa, sa), (fb, sb) = measured_od(ca), measured_od(cb)
        fa, fb = (fa if fa is not None else oda), (fb if fb is not None else odb)
        diff = abs(fa - fb)
        se = float(np.hypot(sa or 0.0, sb or 0.0))
        outcome = verdict(diff, tol, se, ctx.k)
        same_model = abs(oda - odb) <= 1e-6
        if na is not None and nb is not None and na != nb:
            outcome = "unverifiable" if outcome == "pass" else outcome  # sizes differ, fits agree
        elif na is not None and na == nb:
            continue
        elif same_model and outcome != "violation":
            continue  # merging gave both one size; an undecided size is ambiguous-size's finding
        if outcome == "pass":
            continue
        # the shared size: the inverse-variance mean of the two measured ODs, snapped
        measures = [measured_od(ca), measured_od(cb)]
        suggestions = []
        if table is not None and all(m[0] is not None for m in measures):
            weights = np.array([1.0 / max(m[1] or tol, 1e-6) ** 2 for m in measures])
            values = np.array([m[0] for m in measures])
            mean = float(weights @ values / weights.sum())
            mean_se = float(1.0 / np.sqrt(weights.sum()))
            shared = table.within(mean, _window(ctx, mean_se))
            undecided = any(size_status(ctx, comps[c], table) == "ambiguous" for c in (a, b))
            # The shared size must be one each fit allows (within its own snapping window): two
            # fits of clearly different sizes (an NPS 4 and an NPS 3 pipe) average to a third
            # size neither pipe is, which no fix may impose.
            agreed = [
                (n, s)
                for n, s in shared
                if all(abs(s - od) <= _window(ctx, se) for od, se in measures)
            ]
            if len(agreed) == 1:
                n, s = agreed[0]
                targets = [c for c in (a, *path, b) if _size_of(comps[c], table)[1] != s]
                suggestions.append(
                    Suggestion(
                        f"make {', '.join(targets)} {_label(table, n)} ({mm(s)}), the size both fits "
                        "agree on",
                        {"objects": targets, "field": "nominal", "value": n, "od": s},
                        # merging found the size undecidable: a person decides, not --fix
                        unambiguous=not undecided,
                    )
                )
        suggestions.append(
            Suggestion(f"if the size really changes, add a reducer between {a} and {b}")
        )
        tees = [
            x for x in (fittings_between(ctx.model, touching, a, b) or []) if "tee" == comps[x].type
        ]
        if tees and not same_model:
            la = _label(table, na) if na else mm(oda)
            lb = _label(table, nb) if nb else mm(odb)
            text = (
                f"{a} is {la} but {b} is {lb} at the tee {tees[0]}, which ASME B16.9 does not "
                "make: tees reduce on the outlet only (a smaller outlet, or a reducer after the tee)"
            )
        elif same_model:  # one modelled size: the fits are what disagree
            text = (
                f"the fits of {a} ({mm(fa)}) and the contiguous {b} ({mm(fb)}) disagree by "
                f"{mm(diff)} with no reducer"
            )
        else:
            la = _label(table, na) if na else mm(oda)
            lb = _label(table, nb) if nb else mm(odb)
            text = f"{a} is {la} but the contiguous {b} is {lb} with no reducer"
        ctx.emit(
            slug,
            [a, *path, b],
            text,
            location=0.5 * (centre_of(ca.geometry) + centre_of(cb.geometry)),
            measured=diff,
            allowed=tol,
            stderr=se,
            outcome=outcome,
            rescan=f"scan {a} and {b} over wider arcs to measure both diameters better",
            unit="m",
            suggestions=tuple(suggestions),
        )


def _nps_key(nominal: str) -> float:
    """An NPS nominal (``"2 1/2"``) as a number, for ordering sizes largest first."""
    from ._catalog import nps_value

    value = nps_value(nominal)
    return -1.0 if value is None else value


def _spoken_list(items) -> str:
    """``"5, 4 and 3"``."""
    items = list(items)
    return items[0] if len(items) == 1 else f"{', '.join(items[:-1])} and {items[-1]}"


def _branch_off_square_deg(tee: Tee | Cross) -> float:
    """How far (degrees) a tee's branch axis is from square to its run."""
    run = np.asarray(tee.run_end, dtype=np.float64) - np.asarray(tee.run_start, dtype=np.float64)
    branch = np.asarray(tee.branch_end, dtype=np.float64) - np.asarray(tee.center, np.float64)
    lengths = float(np.linalg.norm(run) * np.linalg.norm(branch))
    if lengths == 0.0:
        return 0.0
    return float(np.degrees(np.arcsin(min(1.0, abs(float(run @ branch)) / lengths))))


def check_tee_sizes(ctx: Context, table: SizeTable | None) -> None:
    """One warning per reducing-outlet tee whose run and outlet sizes the fittings catalog
    does not make (ASME B16.9 Table 8, ``catalogs/<fittings>-tees.toml``), as merging notes a
    reducer of a pair B16.9 does not make. Equal tees need no list; an outlet larger than the
    run is contiguous-diameter-mismatch's error; a run size the list does not cover, or sizes
    the catalog cannot name, give no verdict."""
    slug = "nonstandard-tee"
    if table is None or tee_outlets(table.fittings) is None:
        return
    for tee in ctx.model.components:
        g = tee.geometry
        if (tee.type, type(g)) not in (("tee", Tee), ("cross", Cross)):
            continue
        word = tee.type  # a reducing cross is made of the reducing tee's pairs (Table 8)
        if g.branch_outer_radius >= g.outer_radius - 1e-9:
            continue  # an equal tee, or an outlet larger than the run (AB104)
        if _branch_off_square_deg(g) > float(ctx.general("intended_angle_deg")):
            continue  # a lateral: no B16.9 tee at all, merge-note's (AB302) to say
        run = tee.nominal or table.nominal_for(2 * g.outer_radius)
        outlet = table.nominal_for(2 * g.branch_outer_radius)
        if reducing_tee_made(table.fittings, run, outlet) is not False:
            continue
        made = sorted(tee_outlets(table.fittings)[run], key=_nps_key, reverse=True)
        connects = [str(c) for c in (tee.snap or {}).get("connects") or ()]
        outlets = 2 if word == "cross" else 1
        branch = " and ".join(connects[-outlets:]) if connects else "the outlet pipe"
        run_pipes = ", ".join(connects[:-outlets]) or "the run"
        two = ("two", "s") if word == "cross" else ("an", "")
        fittings = table.fittings_standard or table.fittings
        ctx.emit(
            slug,
            [tee.id, *connects],
            f"the {word} {tee.id} joins an {_label(table, run)} run to {two[0]} "
            f"{_label(table, outlet)} outlet{two[1]}, a reducing {word} {fittings} does not "
            f"make ({_label(table, run)} reduces on the outlet to {_spoken_list(made)} only)",
            location=np.asarray(g.center, dtype=np.float64),
            suggestions=(
                Suggestion(
                    f"check on site how {branch} joins {run_pipes}: a reduction this large is "
                    "usually a branch outlet fitting (MSS SP-97, e.g. a weldolet), or a "
                    f"{word} of a listed outlet ({_spoken_list(made)}) with a reducer on it; "
                    f"the model shows a reducing {word}"
                ),
                Suggestion(f"check the sizes of {run_pipes} and {branch}"),
            ),
        )


CHECKS = {
    "nonstandard-diameter": check_nonstandard,
    "ambiguous-size": check_ambiguous,
    "hint-mismatch": check_hint,
    "contiguous-diameter-mismatch": check_contiguous,
    "nonstandard-tee": check_tee_sizes,
}
