"""Joint rules: joint-gap, merge-note, fit-up and unjoined-end.

Two pipes are *contiguous* when the scan links them or their ends lie within
``Tolerances.joint_distance``; merged spools join such pipes end to end or through a fitting.
A pair still apart after merging is explained only when the gap is within the rule's tolerance
(collinear pipes) or when the pipes' axes meet where an ASME B16.9 elbow of their size and angle
would put its ends (centre-to-end ``R tan(theta / 2)``, ``R`` the 90 degree long-radius
centre-to-end; 1.5 x NPS inches when the catalog has no fittings).

One problem is one finding: a pair merging's notes (merge-note, AB302) already report as not
joined, a scan link no fitting realises, is not measured again by joint-gap (AB301) when
merge-note reports it at least as gravely.
"""

from __future__ import annotations

import numpy as np

from asbuilt.catalog import DEFAULT_CATALOG
from asbuilt.findings import SEVERITIES, Suggestion
from asbuilt.merge.loose import IN_LINE_DEG

from ._catalog import SizeTable, nps_value, size_table
from ._context import Context, centre_of, mm, stderr_value, verdict
from ._graph import adjacency, fittings_between, inferred_pairs, linked_pairs

__all__ = ["CHECKS", "joint_geometry"]


def _ends(geometry):
    """(start, end, unit axis, radius) of a straight pipe geometry."""
    if hasattr(geometry, "start"):
        start, end = np.array(geometry.start), np.array(geometry.end)
        radius = geometry.outer_radius
    else:
        start, end = (np.array(e) for e in geometry.ends)
        radius = geometry.radius
    axis = (end - start) / np.linalg.norm(end - start)
    return start, end, axis, float(radius)


def joint_geometry(ga, gb) -> dict:
    """How two straight pipes' facing ends relate.

    Returns a dict with ``ea``, ``eb`` (the facing end points, (3,) m), ``angle_deg`` between the
    axes (0 = collinear direction), ``gap`` (m; axial gap for collinear pipes, negative when they
    overlap), ``offset`` (m; closest distance between the two axis lines) and, for meeting axes,
    ``corner`` ((3,) m) with ``da``, ``db`` the distances from each end to it.
    """
    sa, fa, ua, ra = _ends(ga)
    sb, fb, ub, rb = _ends(gb)
    # facing ends: the closest pair of ends
    options = [
        (np.linalg.norm(pa - pb), pa, qa, pb, qb)
        for pa, qa in ((sa, fa), (fa, sa))
        for pb, qb in ((sb, fb), (fb, sb))
    ]
    _, ea, oa, eb, ob = min(options, key=lambda t: t[0])
    out_a = (ea - oa) / np.linalg.norm(ea - oa)  # pointing out of pipe a at its facing end
    out_b = (eb - ob) / np.linalg.norm(eb - ob)
    cos = float(np.clip(np.dot(out_a, -out_b), -1.0, 1.0))
    angle = float(np.degrees(np.arccos(cos)))
    result = {"ea": ea, "eb": eb, "angle_deg": angle, "radius": max(ra, rb)}
    w = eb - ea
    cross = np.cross(out_a, out_b)
    if np.linalg.norm(cross) < 1e-9:
        lateral = w - np.dot(w, out_a) * out_a
        result.update(gap=float(np.dot(w, out_a)), offset=float(np.linalg.norm(lateral)))
        return result
    # closest points of the two lines ea + s*out_a and eb + t*out_b
    a, b, c = 1.0, float(np.dot(out_a, out_b)), 1.0
    d, e = float(np.dot(out_a, w)), float(np.dot(out_b, w))
    den = a * c - b * b
    s = (d * c - b * e) / den
    t = (b * d - a * e) / den
    pa, pb = ea + s * out_a, eb + t * out_b
    result.update(
        gap=float(np.dot(w, out_a)),
        offset=float(np.linalg.norm(pa - pb)),
        corner=0.5 * (pa + pb),
        da=float(s),
        db=float(t),
    )
    return result


def _elbow_centre_to_end(
    table: SizeTable | None, nominal: str | None, od: float, angle_deg: float
) -> float | None:
    """Centre-to-end (m) of a long-radius elbow turning ``angle_deg`` (None if size unknown)."""
    radius = None
    if table is not None:
        nominal = nominal or table.nominal_for(od)
        if nominal is not None and nominal in table.elbow_lr:
            radius = table.elbow_lr[nominal]
    if radius is None and nominal is not None:
        # By the catalog's NPS: a DN catalog's "150" is NPS 6, not 150.
        nps = table.nps_of(nominal) if table is not None else nps_value(nominal)
        if nps is not None and nps >= 1:
            radius = 1.5 * nps * 0.0254
    if radius is None:
        return None
    return radius * float(np.tan(np.radians(angle_deg) / 2.0))


#: An unsnapped pipe (``--no-merge``) is taken for the catalog size nearest its fitted OD when
#: within this fraction of it (catalog sizes are 10-25% apart; a fit's OD is within 1-2 mm).
_SIZE_MATCH = 0.03


def _catalog_size(table: SizeTable, comp) -> str | None:
    """The catalog nominal of a pipe: its snapped size, else the size nearest its OD."""
    if comp.nominal and comp.nominal in table.tee_run | table.reducer:
        return comp.nominal
    od = 2 * _ends(comp.geometry)[3]
    exact = table.nominal_for(od)
    if exact is not None:
        return exact
    nearest = table.nearest(od, 1)
    if nearest and abs(nearest[0][2]) <= _SIZE_MATCH * od:
        return nearest[0][0]
    return None


def _inline_fitting(table: SizeTable | None, ca, cb, others, geo) -> tuple[str, float] | None:
    """The B16.9 fitting whose length would fill the gap between two collinear pipes' facing
    ends, as ``(what, length in metres)``, or None: a concentric reducer's ``H`` when their
    sizes differ, an equal tee's run ``2 C`` when another pipe's axis crosses the gap (a
    branch, left unmerged: ``--no-merge`` or a tee merging did not build). Needs the
    catalog's fittings table."""
    if table is None:
        return None
    na, nb = _catalog_size(table, ca), _catalog_size(table, cb)
    if na is None or nb is None:
        return None
    if na != nb:
        large = na if _ends(ca.geometry)[3] >= _ends(cb.geometry)[3] else nb
        length = table.reducer.get(large)
        return None if length is None else (f"{table.label(large)} reducer's H", length)
    run = table.tee_run.get(na)
    if run is None:
        return None
    middle = 0.5 * (geo["ea"] + geo["eb"])
    along = geo["eb"] - geo["ea"]
    along = along / max(float(np.linalg.norm(along)), 1e-12)
    for other in others:
        start, end, axis, radius = _ends(other.geometry)
        if abs(float(axis @ along)) > np.cos(np.radians(45.0)):
            continue  # in line with the run, not a branch
        miss = (middle - start) - ((middle - start) @ axis) * axis
        near_end = min(np.linalg.norm(start - middle), np.linalg.norm(end - middle))
        # The branch's axis crosses the run at the gap, its end short of the run's far side
        # by no more than a pipe length the scan may have missed (a tee's outlet M ~ C).
        if np.linalg.norm(miss) <= geo["radius"] and near_end <= 4 * run + geo["radius"]:
            return (f"{table.label(na)} tee's run (2 x C)", 2 * run)
    return None


def _length_se(comp) -> float:
    if comp.fit is None:
        return 0.0
    se = stderr_value(comp.fit.stderr, "length")
    return 0.0 if se is None else se


#: What merging's notes say of a pair it found but did not join (docs/merging.md: "Everything
#: found but not joined goes to the pipes' merge_notes"): a link too far apart or whose axes
#: miss, a bend past an elbow, an end another joint took.
_NOT_JOINED = "not joined"


def _notes_say_it(ctx: Context, slug: str = "joint-gap") -> bool:
    """Whether merge-note reports merging's notes in this run at least as gravely as rule
    ``slug`` would report the pair (it runs, and its severity is no milder)."""
    if not ctx.config.is_active("merge-note"):
        return False
    rank = SEVERITIES.index
    return rank(ctx.config.severity("merge-note")) <= rank(ctx.config.severity(slug))


def _said_not_joined(ca, cb) -> bool:
    """Whether merging left a note on both pipes saying it did not join them (the same note
    on each: merging puts a pair's note on both pipes)."""
    notes_a = {str(n) for n in (ca.snap or {}).get("merge_notes") or ()}
    notes_b = {str(n) for n in (cb.snap or {}).get("merge_notes") or ()}
    return any(_NOT_JOINED in note for note in notes_a & notes_b)


def check_joint_gap(ctx: Context, table: SizeTable | None) -> None:
    """One finding per contiguous pair of pipes not joined by a fitting whose ends a B16.9
    fitting does not explain; a pair merging's notes already report as not joined (a scan
    link no fitting realises) is left to merge-note, which says why, when merge-note reports
    it (:func:`_notes_say_it`)."""
    slug = "joint-gap"
    by_notes = _notes_say_it(ctx)
    tol = float(ctx.opt(slug, "tolerance"))
    snap = float(ctx.general("angle_snap_deg"))
    touch = float(ctx.opt("clash", "touch_distance"))
    pipes = {c.id: c for c in ctx.pipes}
    near = inferred_pairs(ctx.model, touch, float(ctx.general("joint_distance")))
    near |= {p for p in linked_pairs(ctx.model) if p <= set(pipes)}
    # touching ends only: a scan link says the pipes should be joined, not that they are (every
    # linked pair was skipped, so a linked 50 mm gap went unreported)
    joined = adjacency(ctx.model, touch, links=False)
    for pair in sorted(near, key=sorted):
        a, b = sorted(pair)
        if fittings_between(ctx.model, joined, a, b) is not None:
            continue  # joined directly or through fittings (a tee and the reducer after it)
        ca, cb = pipes[a], pipes[b]
        if by_notes and _said_not_joined(ca, cb):
            continue  # merge-note's finding on this pair says the same, and why
        geo = joint_geometry(ca.geometry, cb.geometry)
        se = float(np.hypot(_length_se(ca), _length_se(cb)))
        fitting = None
        if geo["angle_deg"] <= snap:
            if geo["offset"] > geo["radius"]:
                kind, size = "offset", geo["offset"]
            else:
                kind = "gap" if geo["gap"] >= 0 else "overlap"
                size = abs(geo["gap"])
            if kind == "gap" and size > tol:
                others = [c for c in ctx.pipes if c.id not in pair]
                # An unmerged model names no catalog: the default one's fittings explain.
                fittings = table if table is not None else size_table(DEFAULT_CATALOG)
                fitting = _inline_fitting(fittings, ca, cb, others, geo)
                if fitting is not None:
                    kind = "gap" if geo["gap"] >= fitting[1] else "overlap"
                    size = abs(geo["gap"] - fitting[1])
            explained = kind != "offset" and size <= tol
        else:
            if "corner" not in geo or geo["offset"] > geo["radius"]:
                kind, size = "offset", geo["offset"]
                explained = False
            else:
                od = 2 * geo["radius"]
                expected = _elbow_centre_to_end(
                    table, ca.nominal or cb.nominal, od, geo["angle_deg"]
                )
                if expected is None:
                    continue  # size unknown: no fitting can be looked up
                size = max(abs(geo["da"] - expected), abs(geo["db"] - expected))
                kind = "gap" if min(geo["da"], geo["db"]) > expected else "overlap"
                explained = size <= tol
        if explained:
            continue
        outcome = verdict(size, tol, se, ctx.k)
        if outcome == "pass":
            continue
        ctx.emit(
            slug,
            [a, b],
            f"{kind} of {mm(size)} between the ends of {a} and {b}, "
            + (
                f"besides the {fitting[0]} of {mm(fitting[1])} that fits there"
                if fitting is not None
                else "which no catalog fitting explains"
            ),
            location=0.5 * (geo["ea"] + geo["eb"]),
            measured=size,
            allowed=tol,
            stderr=se,
            unit="m",
            outcome=outcome,
            rescan=f"scan the ends of {a} and {b} near the joint",
            suggestions=(
                Suggestion(f"look for a missing part (valve, flange, fitting) between {a} and {b}"),
                Suggestion(f"scan {a} and {b} up to the joint"),
            ),
        )


def check_merge_notes(ctx: Context, table: SizeTable | None = None) -> None:
    """One finding per note merging left on pipes (``snap["merge_notes"]``): what it could not
    join as the scan asked, or pipe it added or removed to fit a fitting. A note on several
    pipes (a link between two, a lateral's three, the pieces of a split pipe) is one finding
    naming them all."""
    slug = "merge-note"
    carriers: dict[str, list] = {}
    for comp in ctx.pipes:
        for note in (comp.snap or {}).get("merge_notes") or ():
            carriers.setdefault(str(note), []).append(comp)
    for note, comps in carriers.items():
        ids = list(dict.fromkeys(comp.id for comp in comps))
        ctx.emit(
            slug,
            ids,
            note,
            location=centre_of(comps[0].geometry),
            suggestions=(
                Suggestion(
                    f"check {', '.join(ids)} against the site and the scan's links; scan the "
                    "pipe ends up to the fittings"
                ),
            ),
        )


def check_fit_up(ctx: Context, table: SizeTable | None = None) -> None:
    """One finding per joined pair whose axes merging found missing each other beyond the fits'
    uncertainty before it shifted them to meet (``snap["fit_up"]``, see
    :func:`asbuilt.merge.regularize.fit_up`): the shift and its standard error."""
    slug = "fit-up"
    by_source: dict[str, list[str]] = {}
    for comp in ctx.pipes:
        for source in comp.sources or (comp.id,):
            by_source.setdefault(source, []).append(comp.id)
    seen = set()
    for comp in ctx.pipes:
        own = comp.sources[0] if comp.sources else comp.id
        for entry in (comp.snap or {}).get("fit_up") or ():
            key = frozenset((own, entry["with"]))
            if key in seen:
                continue
            seen.add(key)
            first, second = sorted((own, str(entry["with"])))
            ids = [*by_source.get(first, [first]), *by_source.get(second, [second])]
            miss, se = float(entry["miss"]), float(entry["stderr"])
            ctx.emit(
                slug,
                ids,
                f"the axes of {first} and {second} miss each other by {mm(miss)} (+- {mm(se)}) "
                f"at their joint, more than the fits explain ({mm(float(entry['allowed']))}); "
                "merging shifted them to meet",
                location=np.asarray(entry["at"], float),
                measured=miss,
                allowed=float(entry["allowed"]),
                stderr=se,
                unit="m",
                suggestions=(
                    Suggestion(
                        f"check the fit-up of {first} and {second} on site (an offset at the "
                        "joint) and that they are joined there"
                    ),
                    Suggestion(f"scan {first} and {second} near the joint"),
                ),
            )


#: A pipe whose outlet runs within this angle (degrees) of a tee's outlet axis, from the other
#: side of the run, is where a straight cross's fourth outlet would be.
_CROSS_DEG = 10.0


def _outward_at(comp, end: str) -> np.ndarray:
    start, stop, axis, _ = _ends(comp.geometry)
    return axis if end == "end" else -axis


def _unjoined_reason(record: dict, comp, other, names: str) -> tuple[str, str]:
    """Why merging left the end loose, and what to do: ``(clause, suggestion)``."""
    pipe, kind, target = comp.id, record.get("touches_type"), str(record["touches"])
    angle = float(record.get("angle_deg", 90.0))
    if record.get("corner") is not None:
        return _facing_reason(record, pipe, target)
    if kind == "tee":
        geo = other.geometry if other is not None else None
        outlet = None
        if geo is not None and hasattr(geo, "branch_end"):
            outlet = np.asarray(geo.branch_end, float) - np.asarray(geo.center, float)
            outlet = outlet / max(float(np.linalg.norm(outlet)), 1e-12)
        out = _outward_at(comp, str(record.get("end")))
        if outlet is not None and float(out @ outlet) >= np.cos(np.radians(_CROSS_DEG)):
            return (
                f"the tee already joins {names}, and {pipe} does not meet it as a cross's "
                "fourth pipe (merging builds a cross where both outlets are of one size on one "
                "line; its notes say what is off)",
                f"if {pipe} is welded to {target} on site, the fitting is a cross: check the "
                f"pipes' positions and sizes (a cross's outlets are on one line, of one size) "
                f"or model it by hand; if not, scan {pipe} up to its end",
            )
        return (
            f"the tee already joins {names}, and no ASME B16.9 fitting joins a fourth pipe "
            "that way",
            f"check on site what joins {pipe} at {target} (a branch outlet fitting on the tee, "
            f"a part the scan missed) and model it by hand; if nothing does, scan {pipe} up to "
            "its end",
        )
    if kind == "pipe":
        if angle < 90.0 - _CROSS_DEG and angle > _CROSS_DEG:
            why = (
                f"it meets {target} at {angle:.0f} degrees, and an ASME B16.9 tee's outlet is "
                "square (a lateral or an angled branch outlet, which the catalog does not have)"
            )
        else:
            why = (
                f"no fitting of the catalog joins it there ({target}'s ends are taken or too near)"
            )
        return (
            why,
            f"check on site how {pipe} joins {target} (a branch outlet fitting such as an MSS "
            "SP-97 latrolet or weldolet, a lateral, a field weld) and model it by hand; if it "
            f"stops short of {target}, scan {pipe} up to its end",
        )
    return (
        f"the {kind} already joins {names}",
        f"check on site what joins {pipe} at {target} (a part the scan missed) and model it by "
        f"hand; if nothing does, scan {pipe} up to its end",
    )


def _facing_reason(record: dict, pipe: str, target: str) -> tuple[str, str]:
    """Why an open end facing another pipe's open end from beyond merging's reach was not
    joined, and what to do (:func:`asbuilt.merge.loose.loose_ends`'s ``corner`` records).
    When a scan link would have merging join them (the record's ``linkable``), linking is
    the change :func:`_link_suggestion` offers, and the advice is the other case."""
    bend = float(record.get("bend_deg", 90.0))
    if record.get("linkable"):
        link = "accept the link (the suggestion above)"
    else:
        link = (
            "model the part by hand (they are too far apart for a scan link to join: merging "
            "invents no pipe)"
        )
    if bend < IN_LINE_DEG:
        return (
            f"{target} continues its line {mm(float(record['gap']))} past its end, beyond "
            "merging's reach (joint_distance plus the shot spacing)",
            f"if one pipe runs on between them (a stretch or a valve the scan did not reach), "
            f"{link}; otherwise scan both up to their ends",
        )
    return (
        f"their axes meet {mm(float(record['gap']))} past its end and "
        f"{mm(float(record.get('beyond', 0.0)))} past {target}'s, where a {bend:.0f} degree "
        "elbow would join them, beyond merging's reach (joint_distance plus the shot spacing)",
        f"if an elbow joins them (the scan stopped short of it), {link}; otherwise scan "
        f"{pipe} and {target} up to their ends",
    )


def _link_suggestion(record: dict, comp, other) -> Suggestion | None:
    """The scan link that would have merging join a facing pair (``--accept`` it; never
    automatic: only a person knows whether an elbow or a pipe the scan did not reach is
    there), or None when no link would (:func:`asbuilt.merge.loose.link_would_join`)."""
    if record.get("corner") is None or not record.get("linkable") or other is None:
        return None
    a = comp.sources[0] if comp.sources else comp.id
    b = other.sources[0] if other.sources else other.id
    joint = "in line" if float(record.get("bend_deg", 90.0)) < IN_LINE_DEG else "with an elbow"
    return Suggestion(
        f"link {a} and {b} in the scan and merge again: merging then joins them {joint}",
        {"objects": [a, b], "field": "link"},
        unambiguous=False,
    )


def check_unjoined_ends(ctx: Context, table: SizeTable | None = None) -> None:
    """One finding per pipe end merging left loose at a fitting or another pipe
    (``snap["loose_ends"]``, :func:`asbuilt.merge.loose.loose_ends`): a fourth pipe at a tee,
    a pipe ending on another's side where no tee can be built. An end merging's notes already
    report as not joined to it (a scan link it could not make) is left to merge-note when
    merge-note reports it (:func:`_notes_say_it`); a pair of pipes whose ends joint-gap
    measures (contiguous free ends) is left to joint-gap."""
    slug = "unjoined-end"
    by_notes = _notes_say_it(ctx, slug)
    comps = {c.id: c for c in ctx.model.components}
    gap_pairs = set()
    if ctx.config.is_active("joint-gap"):
        touch = float(ctx.opt("clash", "touch_distance"))
        gap_pairs = inferred_pairs(ctx.model, touch, float(ctx.general("joint_distance")))
    seen = set()
    for comp in ctx.pipes:
        for record in (comp.snap or {}).get("loose_ends") or ():
            target = str(record["touches"])
            if by_notes and record.get("noted"):
                continue  # merge-note says this pair is not joined, and why
            pair = frozenset((comp.id, target))
            if pair in gap_pairs or pair in seen:
                continue  # joint-gap measures these ends; or said from the other pipe's end
            seen.add(pair)
            other = comps.get(target)
            kind = record.get("touches_type") or (other.type if other else "component")
            joins = [str(p) for p in record.get("touches_pipes") or ()]
            names = ", ".join(joins[:-1]) + f" and {joins[-1]}" if len(joins) > 1 else target
            gap = float(record.get("gap", 0.0))
            where = f"ends on the {kind}" if gap < 5e-4 else f"ends {mm(gap)} from the {kind}"
            if kind == "pipe":
                where = "ends on" if gap < 5e-4 else f"ends {mm(gap)} from"
            if record.get("corner") is not None:
                in_line = float(record.get("bend_deg", 90.0)) < IN_LINE_DEG
                where = f"ends {mm(gap)} short of" + ("" if in_line else " a corner with")
            why, suggestion = _unjoined_reason(record, comp, other, names)
            link = _link_suggestion(record, comp, other)
            ctx.emit(
                slug,
                [comp.id, target],
                f"{comp.id} {where} {target} but is not joined to it: {why}",
                location=np.asarray(record["at"], float),
                measured=gap,
                unit="m",
                suggestions=(*((link,) if link else ()), Suggestion(suggestion)),
            )


CHECKS = {
    "joint-gap": check_joint_gap,
    "merge-note": check_merge_notes,
    "fit-up": check_fit_up,
    "unjoined-end": check_unjoined_ends,
}
