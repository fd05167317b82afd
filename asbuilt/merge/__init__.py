"""Merging: fitted cylinders become pipes of standard sizes joined by real fittings.

``merge_model(report)`` runs, in order (each step its own module):

1. **which cylinders are pipes** (:func:`is_pipe`): a label (else group) naming a vessel
   (tank, vessel, column...) and no pipe word (pipe, line, header...) excludes it; otherwise it
   is a pipe when linked in the scan, given a nominal hint, or with a fitted OD within
   ``[smallest catalog OD - tolerance, largest catalog OD x 1.1]``. Other cylinders stay
   ``cylinder`` components, unchanged;
2. **joints** between pipes (:mod:`.contiguity`), from ``links`` and inferred from geometry
   (each pipe's allowance grows by its coarsest shot spacing, :func:`shot_spacing`);
3. **runs and joint diameter estimates** (:mod:`.joint`), then **snapping** each run's estimate
   to the catalog (:mod:`.snap`);
4. **orientation regularisation** (:mod:`.regularize`, after GlobFit) and line alignment so
   joined axes meet exactly;
5. **fittings and spools** (:mod:`.spool`): elbows/bends, tees, reducers (concentric, or
   eccentric where the axes are offset by the radii's difference, :mod:`.eccentric`, decided
   before step 4's alignment), butt welds between pipes of one size in line, pipes trimmed or
   extended to them, everything grouped into spools.

Every change to a fitted value is recorded on the component as a
:class:`~asbuilt.model.Correction` (diameter snapped, axis regularised, made coaxial or placed
eccentric, axis shifted, end trimmed/extended), the way a spell checker lists what it corrected.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from asbuilt.catalog import DEFAULT_CATALOG, Catalog, fitting_dims, load_catalog
from asbuilt.errors import CatalogError
from asbuilt.fit.result import FitReport
from asbuilt.labels import DEFAULT_WORDS, EQUIPMENT_TAGS, PIPE_WORDS, VESSEL_WORDS, LabelWords
from asbuilt.model import Component, Correction, Model, model_from_fits
from asbuilt.primitives import Cylinder
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

from .contiguity import (
    LINK_MARGIN,
    Joint,
    connected_groups,
    elbow_bend_limit,
    find_joints,
    joint_pairs,
)
from .crosses import settle_crosses
from .eccentric import eccentric_joints
from .joint import find_runs, joint_estimate
from .loose import loose_ends
from .regularize import align_lines, fit_up, regularize_directions
from .snap import SnapResult, snap_diameter, texts_in_units
from .spool import PipeSpec, build_spools

__all__ = [
    "merge_model",
    "is_pipe",
    "PIPE_WORDS",
    "shot_spacing",
    "VESSEL_WORDS",
    "EQUIPMENT_TAGS",
    "LabelWords",
    "DEFAULT_WORDS",
    "resolve_catalog",
    "resolve_schedule",
]


def is_pipe(
    cylinder: Cylinder,
    *,
    label: str | None,
    group: str | None,
    linked: bool,
    hinted: bool,
    catalog: Catalog,
    tolerance: float,
    words: LabelWords = DEFAULT_WORDS,
) -> tuple[bool, str]:
    """Decide whether a fitted cylinder is a pipe; return (answer, reason).

    The label decides first (the group when there is no label): a word of :data:`PIPE_WORDS`
    ("NPS 8 line from the tank") marks a pipe candidate, else a word of :data:`VESSEL_WORDS`
    ("vertical tank", "column C-3") or an equipment tag (:data:`EQUIPMENT_TAGS`: "TK-101",
    "V-101A") marks a vessel or structure, which is never a pipe. A
    candidate is a pipe when it is linked to another object, carries a nominal hint, or its
    fitted OD (metres) lies within ``[min catalog OD - tolerance, max catalog OD x 1.1]``.
    """
    says, word = words.says(label)
    if says is None:
        says, word = words.says(group)
    if says == "vessel":
        return False, f"labelled {word!r}: a vessel or structure, not a pipe"
    if linked:
        return True, "linked to another object in the scan"
    if hinted:
        return True, "has a nominal size hint"
    od = 2 * cylinder.radius
    low, high = catalog.od_range
    if low - tolerance <= od <= high * 1.1:
        return True, "OD within the catalog's range"
    return False, (
        f"OD {od * 1000:.0f} mm is outside {catalog.name}'s range "
        f"{low * 1000:.1f}-{high * 1000:.0f} mm: kept as a cylinder"
    )


def resolve_catalog(catalog) -> Catalog:
    """``None`` -> the default catalog; a name or path -> loaded; a Catalog -> itself."""
    if catalog is None:
        return load_catalog(DEFAULT_CATALOG)
    if isinstance(catalog, Catalog):
        return catalog
    if isinstance(catalog, str | Path):
        return load_catalog(catalog)
    raise TypeError(f"catalog must be a Catalog, a name or a path, not {type(catalog).__name__}")


def resolve_schedule(catalog: Catalog, schedule: str | None) -> str | None:
    """The schedule to build with: the given one (checked), else the catalog's default, else
    ``STD`` when the catalog lists it; None when the catalog has no walls."""
    if schedule is not None:
        wanted = schedule.strip().upper()  # "" is refused below, not taken for the default
        if wanted not in catalog.schedules:
            raise CatalogError(
                f"schedule {schedule!r} is not in catalog {catalog.name}; use one of "
                f"{', '.join(catalog.schedules) or '(none: this catalog lists no walls)'}",
                source="--schedule",
            )
        return wanted
    if catalog.default_schedule and catalog.default_schedule in catalog.schedules:
        return catalog.default_schedule
    return "STD" if "STD" in catalog.schedules else None


def _stderr_value(result, key: str) -> float:
    """A fit's standard error ``key`` as a float; NaN when missing or not a number."""
    se = result.stderr.get(key) if result.stderr else None
    try:
        se = float(se)
    except (TypeError, ValueError):
        return float("nan")
    return se if np.isfinite(se) else float("nan")


def _stderr_od(result) -> float:
    return 2.0 * _stderr_value(result, "radius")


def shot_spacing(points, inliers, center, axis) -> float:
    """The coarsest spacing (metres) of a pipe's inlier shots along its axis.

    ``points`` (n, 3) metres, ``inliers`` (n,) bool, ``center`` (3,) metres, ``axis`` (3,) unit.
    The largest gap between consecutive sorted axial positions: the scan's last shot may be up
    to this far from the pipe's real end. 0 with fewer than two points.
    """
    pts = np.asarray(points, float)
    mask = np.asarray(inliers, bool)
    if mask.shape == (len(pts),):
        pts = pts[mask]
    if len(pts) < 2:
        return 0.0
    along = np.sort((pts - np.asarray(center)) @ np.asarray(axis))
    return float(np.max(np.diff(along)))


def _vec(x) -> tuple[float, ...]:
    return tuple(float(v) for v in x)


def merge_model(
    report: FitReport,
    *,
    catalog: Catalog | str | None = None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    schedule: str | None = None,
    elbow_radius: str = "long",
    words: LabelWords = DEFAULT_WORDS,
) -> Model:
    """Merge fitted primitives into an as-built model of pipes, fittings and spools.

    Parameters
    ----------
    report : FitReport
        Every object's fit (cylinders become pipes; other primitives pass through).
    catalog : Catalog, str or None
        Pipe catalog (name or path accepted); None = ASME B36.10M.
    tolerances : Tolerances
        ``diameter_tolerance`` (snapping window floor, metres), ``angle_snap_deg`` (orientation
        regularisation), ``intended_angle_deg`` and ``joint_distance`` (contiguity).
    schedule : str, optional
        Wall schedule of the pipes (e.g. ``"STD"``, ``"40"``, ``"10S"``); default: the
        catalog's ``default_schedule``, else STD.
    elbow_radius : {"long", "short"}
        Elbow bend radius from the fittings table.
    words : LabelWords
        The label vocabulary that tells pipes from vessels (:func:`is_pipe`); a rules file's
        ``[general]`` ``pipe_keywords``, ``vessel_keywords`` and ``equipment_tags``
        (:attr:`asbuilt.rules.RulesConfig.label_words`).

    Returns
    -------
    Model
        ``components``: pipes (``Straight``), elbows (``Bend``), tees (``Tee``), reducers
        (``Reducer``) and the unchanged non-pipe components; each
        pipe's ``snap`` says how its size was chosen and ``corrections`` what merging changed.
        ``spools`` lists the connected groups. All in metres; the snaps' sentences (reason,
        notes) tell lengths in inches and feet for a scan in inches or feet
        (:func:`.snap.texts_in_units`).

    Raises
    ------
    CatalogError
        Unknown catalog or schedule.
    """
    if elbow_radius not in ("long", "short"):
        raise ValueError(f"elbow_radius must be 'long' or 'short', not {elbow_radius!r}")
    catalog = resolve_catalog(catalog)
    if catalog.kind != "pipe":
        raise CatalogError(
            f"{catalog.name} is a {catalog.kind} catalog; give a pipe catalog", source="--catalog"
        )
    sched = resolve_schedule(catalog, schedule)
    base = model_from_fits(report)
    tol = tolerances
    scan = report.scan
    linked_ids = {obj_id for link in scan.links for obj_id in link}

    # 1. which cylinders are pipes
    pipe_idx: list[int] = []
    others: dict[int, Component] = {}
    for k, (item, comp) in enumerate(zip(report.fits, base.components)):
        prim = comp.geometry  # inside any insulation (asbuilt.model.bare_cylinder)
        if not isinstance(prim, Cylinder):
            continue
        obj = item.object
        ok, why = is_pipe(
            prim,
            label=obj.label,
            group=obj.group,
            linked=obj.id in linked_ids,
            hinted=bool(obj.nominal),
            catalog=catalog,
            tolerance=tol.diameter_tolerance,
            words=words,
        )
        if ok:
            pipe_idx.append(k)
        else:
            others[k] = Component(
                id=comp.id,
                type="cylinder",
                geometry=prim,
                sources=comp.sources,
                group=comp.group,
                label=comp.label,
                fit=comp.fit,
                snap={"status": "not-pipe", "reason": why},
                insulation=comp.insulation,
            )
    if not pipe_idx:
        comps = tuple(others.get(k, c) for k, c in enumerate(base.components))
        return texts_in_units(base.replace(components=comps, catalog=catalog.name))

    items = [report.fits[k] for k in pipe_idx]
    cyls = [base.components[k].geometry for k in pipe_idx]  # inside any insulation
    ids = [item.object.id for item in items]
    index_of = {obj_id: n for n, obj_id in enumerate(ids)}
    centers = np.array([c.center for c in cyls])
    axes = np.array([c.axis for c in cyls])
    lengths = np.array([c.length for c in cyls])
    ods = np.array([2 * c.radius for c in cyls])
    ses = np.array([_stderr_od(item.result) for item in items])
    links = [(index_of[a], index_of[b]) for a, b in scan.links if a in index_of and b in index_of]

    slack = np.array(
        [
            shot_spacing(item.object.points, item.result.inliers, c.center, c.axis)
            for item, c in zip(items, cyls)
        ]
    )

    # 2. joints
    joint_notes: list[tuple[tuple[int, ...], str]] = []
    joints = find_joints(
        centers,
        axes,
        lengths,
        ods,
        links=links,
        tolerances=tol,
        slack=slack,
        notes=joint_notes,
        names=ids,
    )
    notes_of: dict[int, list[str]] = {}
    for pipes, text in joint_notes:
        for m in pipes:
            notes_of.setdefault(m, []).append(text)
    for m, text in _links_to_other_objects(report, index_of, cyls, slack, tol):
        notes_of.setdefault(m, []).append(text)

    # 3. runs, joint estimates, snapping
    runs = find_runs(ods, ses, joint_pairs(joints), tol.diameter_tolerance)
    run_of = np.zeros(len(ids), int)
    snaps: list[SnapResult] = [None] * len(ids)  # type: ignore[list-item]
    member_hint: list[dict] = [{} for _ in ids]
    run_info: list[dict] = [{} for _ in ids]
    for r, members in enumerate(runs):
        run_of[members] = r
        od_run, se_run = joint_estimate(ods[members], ses[members], floor=tol.sigma_floor)
        if len(members) == 1:
            od_run, se_run = float(ods[members[0]]), float(ses[members[0]])
        hints = [items[m].object.nominal for m in members if items[m].object.nominal]
        chosen_hint = None
        for hint in hints:
            trial = snap_diameter(
                od_run, se_run, catalog, tolerance=tol.diameter_tolerance, hint=hint
            )
            if trial.hint.get("agrees"):
                chosen_hint = hint
                break
        result = snap_diameter(
            od_run, se_run, catalog, tolerance=tol.diameter_tolerance, hint=chosen_hint
        )
        for m in members:
            snaps[m] = result
            own = items[m].object.nominal
            if own:
                member_hint[m] = snap_diameter(
                    od_run, se_run, catalog, tolerance=tol.diameter_tolerance, hint=own
                ).hint
            run_info[m] = {
                "run": [ids[k] for k in members],
                "od_joint": od_run,
                "od_joint_stderr": se_run,
            }

    # a cross's run is its larger pair; outlets of two sizes make it a tee (merge.crosses)
    cross_notes: list[tuple[tuple[int, ...], str]] = []
    joints = tuple(settle_crosses(joints, [float(s.od) for s in snaps], ids, cross_notes))
    joint_notes.extend(cross_notes)
    for pipes, text in cross_notes:
        for m in pipes:
            notes_of.setdefault(m, []).append(text)

    # 4. orientation regularisation and alignment
    parallel_groups = []
    for joint in joints:
        if joint.kind == "inline":
            parallel_groups.append([joint.ends[0][0], joint.ends[1][0]])
        elif joint.kind in ("tee", "lateral", "cross") and joint.through is None:
            parallel_groups.append([joint.ends[0][0], joint.ends[1][0]])
        if joint.kind == "cross":
            parallel_groups.append([joint.ends[-2][0], joint.ends[-1][0]])
    axis_se = np.array([_stderr_value(item.result, "axis_deg") for item in items])
    directions = regularize_directions(
        axes,
        lengths,
        tol_deg=tol.angle_snap_deg,
        parallel_groups=parallel_groups,
        names=ids,
        stderr_deg=axis_se,
        max_deg=min(tol.angle_snap_max_deg, tol.intended_angle_deg),
        elbow_pairs=[
            (joint.ends[0][0], joint.ends[1][0]) for joint in joints if joint.kind == "elbow"
        ],
    )
    new_axes = directions.axes
    build_ods = np.array([float(s.od) for s in snaps])
    build_od_se = np.array(
        [
            0.0 if s.size is not None else float(run_info[m]["od_joint_stderr"])
            for m, s in enumerate(snaps)
        ]
    )
    center_se = np.array([_stderr_value(item.result, "center") for item in items])
    eccentric = eccentric_joints(
        joints,
        centers,
        axes,
        lengths,
        new_axes,
        build_ods,
        run_of,
        center_se,
        axis_se,
        od_se=build_od_se,
    )
    meets, coaxial, offsets = _constraints(joints, eccentric)
    # how far the joined axes miss each other before alignment removes it: beyond the fits'
    # uncertainty it is a fit-up deviation the model must not absorb silently
    fit_up_of: dict[int, list[dict]] = {}
    for found in fit_up(
        centers,
        new_axes,
        meets,
        coaxial,
        center_se,
        axis_se,
        skip=[e.pipes for e in eccentric.values()],
    ):
        if not found.deviates:
            continue
        for m, other in (found.pipes, found.pipes[::-1]):
            fit_up_of.setdefault(m, []).append(
                {
                    "with": ids[other],
                    "miss": found.miss,
                    "stderr": found.stderr,
                    "allowed": found.allowed,
                    "at": _vec(found.point),
                }
            )
    new_centers = centers.copy()
    groups = connected_groups(len(ids), joints)
    group_of_pipe = np.zeros(len(ids), int)
    local = np.zeros(len(ids), int)
    for g, group in enumerate(groups):
        group_of_pipe[group] = g
        local[group] = np.arange(len(group))
    group_meets: dict[int, list] = {}
    group_coaxial: dict[int, list] = {}
    group_offsets: dict[int, list] = {}
    for pairs, table in ((meets, group_meets), (coaxial, group_coaxial)):
        for a, b in pairs:
            table.setdefault(int(group_of_pipe[a]), []).append((int(local[a]), int(local[b])))
    for (a, _), step in zip(coaxial, offsets):
        group_offsets.setdefault(int(group_of_pipe[a]), []).append(step)
    for g, group in enumerate(groups):
        lm = group_meets.get(g, [])
        lc = group_coaxial.get(g, [])
        if lm or lc:
            new_centers[group] = align_lines(
                centers[group],
                new_axes[group],
                lm,
                lc,
                weights=np.maximum(lengths[group], 0.05),
                offsets=group_offsets.get(g),
            )
    eccentric_with: dict[int, dict[int, str]] = {}
    reducer_notes: dict[tuple[int, int], str] = {}
    for found in eccentric.values():
        i, j = found.pipes
        eccentric_with.setdefault(i, {})[j] = found.flat
        eccentric_with.setdefault(j, {})[i] = found.flat
        reducer_notes[min(i, j), max(i, j)] = found.note(ids)

    coaxial_with: dict[int, set[int]] = {}
    meets_with: dict[int, set[int]] = {}
    for pairs, table in ((coaxial, coaxial_with), (meets, meets_with)):
        for a, b in pairs:
            if b in eccentric_with.get(a, {}):
                continue
            table.setdefault(a, set()).add(b)
            table.setdefault(b, set()).add(a)

    # 5. pipe specs and spools
    specs = []
    for m, comp in enumerate(base.components[k] for k in pipe_idx):
        snap = snaps[m]
        size = snap.size
        od = snap.od
        wall = 0.0
        schedule_used = None
        notes: list[str] = []
        if size is not None and sched is not None:
            w = size.wall(sched)
            if w is not None:
                wall, schedule_used = w, sched
            else:
                notes.append(
                    f"{catalog.label(size.nominal)} has no {sched} wall in "
                    f"{catalog.name}: built solid"
                )
        corrections = []
        if size is not None:
            corrections.append(
                Correction(
                    "diameter snapped",
                    before=float(ods[m]),
                    after=float(size.od),
                    size=float(abs(size.od - ods[m]) * 1000.0),
                    unit="mm",
                )
            )
        elif abs(od - ods[m]) > 1e-9:
            corrections.append(
                Correction(
                    "diameter equalised over run",
                    before=float(ods[m]),
                    after=float(od),
                    size=float(abs(od - ods[m]) * 1000.0),
                    unit="mm",
                )
            )
        if directions.angles_deg[m] > 1e-6:
            what = "axis regularised"
            if directions.relations[m]:
                relations = directions.relations[m]
                if eccentric_with.get(m) and not coaxial_with.get(m):
                    relations = [r.replace("coaxial run", "parallel run") for r in relations]
                what += ": " + ", ".join(dict.fromkeys(relations))
            corrections.append(
                Correction(
                    what,
                    before=_vec(axes[m]),
                    after=_vec(new_axes[m]),
                    size=float(directions.angles_deg[m]),
                    unit="deg",
                )
            )
        shift = new_centers[m] - centers[m]
        shift -= (shift @ new_axes[m]) * new_axes[m]
        if np.linalg.norm(shift) > 1e-7:
            parts = []
            if coaxial_with.get(m):
                parts.append(
                    "made coaxial with " + ", ".join(sorted(ids[k] for k in coaxial_with[m]))
                )
            for k, flat in sorted(eccentric_with.get(m, {}).items()):
                parts.append(f"placed eccentric to {ids[k]} (eccentric reducer, flat on {flat})")
            if meets_with.get(m):
                parts.append("shifted to meet " + ", ".join(sorted(ids[k] for k in meets_with[m])))
            corrections.append(
                Correction(
                    "axis " + "; ".join(parts),
                    before=_vec(centers[m]),
                    after=_vec(new_centers[m]),
                    size=float(np.linalg.norm(shift)) * 1000.0,
                    unit="mm",
                )
            )
        snap_map = snap.as_mapping(catalog)
        snap_map["od_fit"] = float(ods[m])
        snap_map["od_stderr"] = float(ses[m]) if np.isfinite(ses[m]) else None
        run_ids = run_info[m]["run"]
        if len(run_ids) > 1:
            snap_map["reason"] = (
                f"joint estimate of the run {', '.join(run_ids)}: " + snap_map["reason"]
            )
        if comp.insulation:
            snap_map["reason"] = (
                f"fitted on {comp.insulation * 1000:g} mm of insulation (cladding OD "
                f"{(ods[m] + 2 * comp.insulation) * 1000:.1f} mm, pipe "
                f"{ods[m] * 1000:.1f} mm): " + snap_map["reason"]
            )
        snap_map.update(run_info[m])
        if member_hint[m]:
            snap_map["hint"] = member_hint[m]
        elif "hint" in snap_map:
            del snap_map["hint"]
        if notes:
            snap_map["notes"] = notes
        if m in fit_up_of:
            snap_map["fit_up"] = fit_up_of[m]
        dims = fitting_dims(catalog, size, od, elbow_radius)
        pipe_comp = Component(
            id=comp.id,
            type="pipe",
            geometry=comp.geometry,
            sources=comp.sources,
            group=comp.group,
            label=comp.label,
            nominal=size.nominal if size else None,
            schedule=schedule_used,
            fit=comp.fit,
            snap=snap_map,
            corrections=tuple(corrections),
            insulation=comp.insulation,
        )
        specs.append(
            PipeSpec(
                id=comp.id,
                center=new_centers[m],
                axis=new_axes[m],
                length=float(lengths[m]),
                od=float(od),
                wall=float(wall),
                dims=dims,
                run=int(run_of[m]),
                component=pipe_comp,
                nominal=size.nominal if size else None,
                schedule=schedule_used,
                notes=list(notes_of.get(m, [])),
                slack=float(slack[m]),
                spacing=_end_step(items[m], cyls[m]),
            )
        )
    group_of = [item.object.group for item in items]
    pipe_components, spools = build_spools(
        specs,
        joints,
        group_of,
        max_bend_deg=elbow_bend_limit(tol),
        reducer_notes=reducer_notes,
        taken_ids=[obj.id for obj in scan.objects],
        joint_distance=tol.joint_distance,
    )
    pipe_components = _mark_loose_ends(pipe_components, joints, joint_notes, ids, slack, tol)

    # assemble in scan order: each pipe's components where the pipe was
    by_source: dict[str, list[Component]] = {}
    for comp in pipe_components:
        key = comp.sources[0] if comp.sources else None
        if key is not None:
            by_source.setdefault(key, []).append(comp)
            last = key
        else:
            by_source[last].append(comp)
    ordered: list[Component] = []
    pipe_set = set(pipe_idx)
    for k, comp in enumerate(base.components):
        if k in pipe_set:
            ordered.extend(by_source.get(comp.id, []))
        else:
            ordered.append(others.get(k, comp))
    merged = base.replace(components=tuple(ordered), spools=tuple(spools), catalog=catalog.name)
    return texts_in_units(merged)  # snap reasons and notes in inches for an imperial scan


def _mark_loose_ends(components, joints, joint_notes, ids, slack, tol):
    """The merged components with ``snap["loose_ends"]`` on pipes left loose at a fitting or
    another pipe (:func:`asbuilt.merge.loose.loose_ends`)."""
    # a lateral's three pipes (its two contacts) are joined to each other
    contacts = [joint.pipes for joint in joints if joint.kind == "contact"]
    groups = [set(pipes) for pipes in contacts]
    for pipes in contacts:
        touching = [g for g in groups if g & set(pipes)]
        groups = [g for g in groups if not g & set(pipes)] + [set().union(*touching)]
    joined = {
        frozenset((ids[p], ids[q]))
        for pipes in [joint.pipes for joint in joints if joint.kind != "link"] + groups
        for p in pipes
        for q in pipes
        if p != q
    }
    noted = {
        frozenset((ids[p], ids[q]))
        for pipes, _ in joint_notes
        for p in pipes
        for q in pipes
        if p != q
    }
    found = loose_ends(
        components,
        reach=tol.joint_distance,
        slack=dict(zip(ids, (float(s) for s in slack))),
        joined=joined,
        noted=noted,
        bend_limit_deg=elbow_bend_limit(tol),
        tolerances=tol,
    )
    return [
        dataclasses.replace(comp, snap={**comp.snap, "loose_ends": found[comp.id]})
        if comp.id in found
        else comp
        for comp in components
    ]


def _end_step(item, cylinder) -> float:
    """The shots' step (metres) along a pipe's axis at its ends, the larger of the two: how far
    its last shot may stand from a real end (:func:`asbuilt.fit._cylinder_finish.end_gaps`, the
    step the fit's length standard error is built on). The mean spacing (extent over shots)
    was a row's own spread on a raster crossing the pipe: "extended 204 mm beyond its last shot
    (shots every 31 mm on average)" for a pipe whose raster lines lay 0.2 m apart along it.
    """
    from asbuilt.fit._common import median_spacing
    from asbuilt.fit._cylinder_finish import end_gaps

    pts = np.asarray(item.object.points, float)
    mask = np.asarray(item.result.inliers, bool)
    if mask.shape == (len(pts),):
        pts = pts[mask]
    if len(pts) < 2:
        return 0.0
    along = (pts - np.asarray(cylinder.center)) @ np.asarray(cylinder.axis)
    return max(end_gaps(along, median_spacing(pts), float(item.result.sigma or 0.0)))


def _links_to_other_objects(report, index_of, cyls, slack, tol):
    """``(pipe index, sentence)`` for each scan link from a pipe to an object that is not a pipe.

    Merging joins pipes only, so such a link builds nothing; it is said, with how far the pipe is
    from the object's shots (more than ``joint_distance`` + :data:`.contiguity.LINK_MARGIN` + the
    pipe's slack is implausible).
    """
    objects = {item.object.id: item for item in report.fits}
    found = []
    for a, b in report.scan.links:
        for pipe_id, other_id in ((a, b), (b, a)):
            if pipe_id not in index_of or other_id in index_of:
                continue
            m = index_of[pipe_id]
            other = objects.get(other_id)
            kind = other.result.primitive.kind if other is not None else "object"
            if kind == "cylinder":
                kind = "cylinder, not a pipe"
            article = "an" if kind[0] in "aeiou" else "a"
            text = (
                f"the scan links {pipe_id} to {other_id} ({article} {kind}): merging joins pipes "
                "only, so no fitting or spool connects them"
            )
            if other is not None and len(other.object.points):
                c = cyls[m]
                half = 0.5 * c.length * np.asarray(c.axis)
                p0, p1 = np.asarray(c.center) - half, np.asarray(c.center) + half
                shots = np.asarray(other.object.points, float)
                along = np.clip((shots - p0) @ (p1 - p0) / max(c.length**2, 1e-12), 0.0, 1.0)
                gaps = np.linalg.norm(shots - (p0 + along[:, None] * (p1 - p0)), axis=1)
                apart = max(float(gaps.min()) - c.radius, 0.0)
                allowed = tol.joint_distance + LINK_MARGIN + float(slack[m])
                if apart > allowed:
                    text += (
                        f"; they are {apart:.2f} m apart (a link may bridge {allowed:.2f} m): "
                        "check the link"
                    )
            found.append((m, text))
    return found


def _constraints(joints: tuple[Joint, ...], eccentric=None):
    """Pairs of lines that must meet, pairs that must be coaxial (or, for an eccentric reducer,
    offset) and each coaxial pair's required sideways step (3,) metres, None for coaxial."""
    meets: list[tuple[int, int]] = []
    coaxial: list[tuple[int, int]] = []
    offsets: list[np.ndarray | None] = []
    eccentric = eccentric or {}
    for index, joint in enumerate(joints):
        if joint.kind == "elbow":
            meets.append((joint.ends[0][0], joint.ends[1][0]))
        elif joint.kind == "inline":
            coaxial.append((joint.ends[0][0], joint.ends[1][0]))
            found = eccentric.get(index)
            offsets.append(None if found is None else found.offset)
        elif joint.kind in ("tee", "lateral", "cross"):
            branch = joint.ends[-1][0]
            if joint.kind == "cross":
                # both outlets on one line; the first meets the run (or the pipe running through)
                (branch, _), (other, _) = joint.ends[-2:]
                coaxial.append((branch, other))
                offsets.append(None)
            if joint.through is None:
                coaxial.append((joint.ends[0][0], joint.ends[1][0]))
                offsets.append(None)
                meets.append((branch, joint.ends[0][0]))
            else:
                meets.append((branch, joint.through))
    return meets, coaxial, offsets
