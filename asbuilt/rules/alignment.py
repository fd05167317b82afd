"""Alignment rules: misaligned-axis, out-of-plumb, slope.

``misaligned-axis`` judges the *model's* axes (what merging regularised, and what ``--fix``
can regularise further); ``out-of-plumb`` and ``slope`` judge the *measured* axes (the fitted
primitive), because regularisation snaps axes within ``angle_snap_deg`` (2 degrees), far more
than a plumb tolerance of 1:500 (0.11 degree) or a drainage slope of 1% (0.57 degree).

Axis standard errors come from the fit (``stderr["axis_deg"]`` for cylinders; for cuboids the
long axis's entry of ``"axes_deg"``, one per axis of ``Cuboid.axes``, or its one value when it is
a scalar); without them they are estimated as for a straight-line fit,
``sigma / (L * sqrt(n / 12))`` radians for ``n`` points spread evenly over a length ``L``.
"""

from __future__ import annotations

import re

import numpy as np

from asbuilt.findings import Suggestion
from asbuilt.fit.result import rotation_covariance
from asbuilt.merge.regularize import SNAP_SIGMA
from asbuilt.model import Component
from asbuilt.primitives import Cuboid

from ._catalog import nps_value
from ._context import Context, axis_of, centre_of, deg, mm, stderr_value, verdict, verdict_min
from ._graph import adjacency, contiguous_pipes

__all__ = ["CHECKS", "measured_axis", "axis_stderr_deg", "rotation_between", "material_of"]

_Z = np.array([0.0, 0.0, 1.0])


def measured_axis(component: Component, measured: bool = True):
    """(unit axis (3,), length m, centre (3,) m) of the fitted primitive when ``measured`` and a
    fit exists, else of the model geometry; None for geometries without one axis."""
    if measured and component.fit is not None:
        found = axis_of(component.fit.primitive)
        if found is not None:
            return found
    return axis_of(component.geometry)


def axis_stderr_deg(component: Component) -> float | None:
    """Standard error (degrees) of a component's main axis direction, or None without a fit."""
    fit = component.fit
    if fit is None:
        return None
    prim = fit.primitive
    if isinstance(prim, Cuboid):
        value = stderr_value(fit.stderr, "axes_deg", int(np.argmax(prim.size)))
    else:
        value = stderr_value(fit.stderr, "axis_deg")
    if value is not None and np.isfinite(value):
        return value
    found = axis_of(prim)
    if found is None or fit.n_inliers < 3:
        return None
    length = max(found[1], 1e-9)
    return float(np.degrees(fit.sigma / (length * np.sqrt(fit.n_inliers / 12.0))))


def tilt_components(component: Component):
    """A cuboid column's lean per direction, from its fit's rotation covariance
    (:func:`asbuilt.fit.result.rotation_covariance`), or None without one (a cylinder, a model
    document written before it was stored).

    Returns ``(c, cov, across)``: the tilt ``c`` (2,) of the long axis away from vertical,
    ``sin`` of the lean angle per direction, along the principal directions of its covariance
    (the best measured first), ``cov`` (2,) the variances of those components (radians^2,
    ascending), and ``across`` whether the best-measured direction is the normal of the one
    face seen (a fit of one face: its tilt across the face, toward the station, is measured and
    its turn in the face's plane is not).

    The long axis ``a`` is ``axes[L]``; it tilts toward another axis ``e`` by ``c = -z . e``
    (``a . e = 0``), and a rotation ``w`` of the frame moves that by ``-w . (e x z)``; with the
    rotation's covariance ``M`` in the axes' frame, the two components' covariance is
    ``J M J^T`` with rows ``-axes @ (e x z)``.
    """
    fit = component.fit
    if fit is None or not isinstance(fit.primitive, Cuboid):
        return None
    m = rotation_covariance(fit.diagnostics or {})
    if m is None:
        return None
    axes = np.asarray(fit.primitive.axes, dtype=np.float64)
    long = int(np.argmax(fit.primitive.size))
    others = [k for k in range(3) if k != long]
    c = np.array([-axes[k] @ _Z for k in others])
    jac = np.array([-(axes @ np.cross(axes[k], _Z)) for k in others])
    cov = jac @ m @ jac.T
    variances, directions = np.linalg.eigh(0.5 * (cov + cov.T))
    components = directions.T @ c
    assumed = (fit.diagnostics or {}).get("assumed_size")
    across = False
    if assumed is not None and np.isfinite(assumed) and int(assumed) in others:
        # the best-measured direction lies along the seen face's normal
        normal = others.index(int(assumed))
        across = abs(directions[normal, 0]) > abs(directions[1 - normal, 0])
    return components, np.maximum(variances, 0.0), across


def _lean_by_direction(comp, height, cos_lean, allowed, k):
    """The lean's lower bound from one direction alone, when that decides more than the whole
    lean does: ``(outcome, stderr, text)`` or None.

    Each principal direction's component ``p`` (a length over the height) bounds the lean from
    below, ``lean >= |p|``; with its standard error ``s`` counted ``sqrt(2)`` times (the root of
    the sum of both directions' variances when they are equal), the lean is certainly over the
    allowance when ``|p| - k sqrt(2) s`` is. A column measured alike in every direction is thus
    judged as before (the lean against the root of the sum of both variances); one seen on a
    single face, whose tilt across the face is known to a few hundredths of a degree and whose
    turn in it to degrees, is judged by the direction it measured.
    """
    found = tilt_components(comp)
    if found is None:
        return None
    components, variances, across = found
    scale = height / max(cos_lean, 1e-9)
    parts = np.abs(components) * scale
    own = np.sqrt(variances) * scale  # each component's own standard error (the messages')
    ses = np.sqrt(2.0) * own  # as the verdict counts it
    lower = parts - k * ses
    best = int(np.argmax(lower))
    if lower[best] > allowed:
        where = (
            "toward the station (across its one seen face)"
            if across and best == 0
            else "in one direction"
        )
        return (
            "violation",
            float(ses[best]),
            f"; {where} alone it leans {mm(parts[best])} +- {mm(own[best])}",
        )
    if not across or ses[1] < 3.0 * ses[0]:
        return None  # no direction measured much better than the lean as a whole
    shown = f"1:{height / parts[0]:.0f}" if parts[0] > 0 else "plumb"
    if parts[0] + k * ses[0] <= allowed:
        bound = parts[0] + k * ses[0]
        said = f"plumb toward the station to 1:{height / bound:.0f} ({mm(bound)} at most)"
    else:
        said = f"toward the station it leans {mm(parts[0])} +- {mm(own[0])} ({shown})"
    return (
        "unverifiable",
        None,
        f"; {said}, across its one seen face; the sideways lean, along the face, is not "
        f"measured (known to +- {mm(own[1])} only)",
    )


def rotation_between(a, b) -> np.ndarray:
    """The smallest rotation (3, 3) taking unit vector ``a`` to unit vector ``b`` (Rodrigues)."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    v = np.cross(a, b)
    c = float(np.dot(a, b))
    if np.linalg.norm(v) < 1e-12:
        if c > 0:
            return np.eye(3)
        perp = np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0])
        perp /= np.linalg.norm(perp)
        return 2 * np.outer(perp, perp) - np.eye(3)
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    return np.eye(3) + vx + vx @ vx * (1.0 / (1.0 + c))


def _rot_z(angle_deg: float) -> np.ndarray:
    t = np.radians(angle_deg)
    return np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1.0]])


def _elevation_deg(axis) -> float:
    """Angle (degrees) between an axis and the horizontal plane, in [0, 90]."""
    return float(np.degrees(np.arcsin(min(abs(float(axis[2])), 1.0))))


def _words(component: Component) -> set[str]:
    """The whole words (lower case) of a component's label, group and id."""
    text = " ".join(filter(None, (component.label, component.group, component.id))).lower()
    return set(re.split(r"[^a-z0-9-]+", text))


def material_of(ctx: Context, component: Component) -> str:
    """``"steel"`` or ``"concrete"`` from label/group keywords, else the rules' default."""
    words = _words(component)
    for material in ("concrete", "steel"):
        if words & {k.lower() for k in ctx.general(f"{material}_keywords")}:
            return material
    return str(ctx.general("default_material"))


def is_round_column(ctx: Context, component: Component) -> bool:
    """Whether a cylinder is a column, not a pipe: a word of its label, group or id is in
    ``column_keywords`` or ``concrete_keywords`` (a steel keyword alone names a steel pipe too)."""
    keys = [*ctx.general("column_keywords"), *ctx.general("concrete_keywords")]
    return bool(_words(component) & {k.lower() for k in keys})


def is_tank(ctx: Context, component: Component) -> bool:
    """Whether a cylinder is a storage tank: a word of its label, group or id is one of
    ``tank_keywords`` (or its plural), or one of them with a number joined to it (an equipment
    tag: ``TK-101``, ``tk101``, ``tank-2a``)."""
    keys = [re.escape(k.lower()) for k in ctx.general("tank_keywords")]
    if not keys:
        return False
    word = re.compile("(" + "|".join(keys) + r")(s|-?\d+[a-z]?)?")
    return any(word.fullmatch(w) for w in _words(component))


def _plan_azimuth(component: Component) -> float | None:
    """Plan direction (degrees, modulo 90) of a component's horizontal axis or a vertical box's
    face; None when it has none."""
    found = axis_of(component.geometry)
    if found is None:
        return None
    axis = found[0]
    intended = 45.0
    if _elevation_deg(axis) < intended and np.hypot(axis[0], axis[1]) > 0:
        return float(np.degrees(np.arctan2(axis[1], axis[0])) % 90.0)
    geom = component.geometry
    if isinstance(geom, Cuboid):
        for row in geom.axes:
            if abs(row[2]) < 0.5:
                return float(np.degrees(np.arctan2(row[1], row[0])) % 90.0)
    return None


def _fixes(cid, touching, dev, snap, se, description, rotation, centre) -> tuple:
    """The rotation fix. A deviation beyond :data:`~asbuilt.merge.regularize.SNAP_SIGMA` of
    the axes' standard errors ``se`` (degrees; None: unknown) is measured, not noise (a column
    built leaning, a line laid askew): making it regular would draw what was not built, so the
    fix is offered for a person to accept (``--accept``), never applied by ``--fix`` alone.
    Otherwise it is unambiguous for a free component; for one joined to others (a pipe in a
    spool) rotating it would open its joints, so the advice is to merge again with a larger
    snap angle instead (merging regularises an axis only within ``SNAP_SIGMA`` standard
    errors, whatever the snap angle)."""
    change = {
        "object": cid,
        "field": "rotation",
        "value": np.asarray(rotation).tolist(),
        "about": [float(x) for x in centre],
    }
    if se is not None and dev > SNAP_SIGMA * se:
        return (Suggestion(description, change, unambiguous=False),)
    if not touching.get(cid):
        return (Suggestion(description, change, unambiguous=True),)
    return (
        Suggestion(
            f"if it is meant to be regular, merge again with [general] angle_snap_deg = "
            f"{np.ceil(dev + 0.5):.0f} (now {snap:g}) so merging regularises it and "
            "rebuilds its joints"
        ),
        Suggestion(description, change, unambiguous=False),
    )


def check_misaligned(ctx: Context) -> None:
    slug = "misaligned-axis"
    snap = float(ctx.general("angle_snap_deg"))
    intended = float(ctx.general("intended_angle_deg"))
    comps = {c.id: c for c in ctx.model.components}
    touching = adjacency(ctx.model, float(ctx.opt("clash", "touch_distance")))
    for comp in ctx.model.components:
        found = axis_of(comp.geometry)
        if found is None:
            continue
        axis, _, centre = found
        elev = _elevation_deg(axis)
        dev, direction = (90.0 - elev, "vertical") if elev > 45 else (elev, "horizontal")
        if not snap < dev < intended:
            continue
        se = axis_stderr_deg(comp)
        target = (
            (np.sign(axis[2]) or 1.0) * _Z
            if direction == "vertical"
            else (np.array([axis[0], axis[1], 0.0]) / np.hypot(axis[0], axis[1]))
        )
        rot = rotation_between(axis, target)
        ctx.emit(
            slug,
            [comp.id],
            f"axis is {deg(dev)} off {direction} (regularised within {deg(snap)}, intended "
            f"beyond {deg(intended)})",
            location=centre,
            measured=dev,
            allowed=snap,
            stderr=se,
            unit="deg",
            outcome=verdict(dev, snap, se, ctx.k),
            rescan=f"scan {comp.id} over a longer stretch to measure its axis better",
            suggestions=_fixes(
                comp.id,
                touching,
                dev,
                snap,
                se,
                f"make {comp.id}'s axis {direction} (rotate it {deg(dev)} about its centre)",
                rot,
                centre,
            ),
        )
    if not ctx.opt(slug, "compare_in_plan"):
        return
    graph = adjacency(
        ctx.model, float(ctx.opt("clash", "touch_distance")), float(ctx.general("joint_distance"))
    )
    pairs = {tuple(sorted((a, b))) for a in graph for b in graph[a]}
    pipes = [c.id for c in ctx.model.components if c.type in ("pipe", "cylinder")]
    pairs |= {(a, b) for a, b, _ in contiguous_pipes(ctx.model, graph, pipes)}
    for pair in sorted(pairs):
        if pair[0] not in comps or pair[1] not in comps:
            continue
        za, zb = _plan_azimuth(comps[pair[0]]), _plan_azimuth(comps[pair[1]])
        if za is None or zb is None:
            continue
        diff = (zb - za) % 90.0
        dev = min(diff, 90.0 - diff)
        if not snap < dev < intended:
            continue
        sa, sb = axis_stderr_deg(comps[pair[0]]), axis_stderr_deg(comps[pair[1]])
        se = float(np.hypot(sa or 0.0, sb or 0.0)) if (sa or sb) else None
        turn = -diff if diff < 45 else 90.0 - diff
        second = comps[pair[1]]
        centre = centre_of(second.geometry)
        ctx.emit(
            slug,
            list(pair),
            f"axis is {deg(dev)} off parallel/perpendicular to {pair[0]} in plan "
            f"(regularised within {deg(snap)}, intended beyond {deg(intended)})",
            location=centre,
            measured=dev,
            allowed=snap,
            stderr=se,
            unit="deg",
            outcome=verdict(dev, snap, se, ctx.k),
            rescan=f"scan {pair[0]} and {pair[1]} over longer stretches",
            suggestions=_fixes(
                pair[1],
                touching,
                dev,
                snap,
                se,
                f"turn {pair[1]} {deg(abs(turn))} about the vertical to line up with {pair[0]}",
                _rot_z(turn),
                centre,
            ),
        )


def _one_per_fit(components):
    """Components grouped by the fit they come from (merging may cut one scanned pipe into pieces
    at a tee): ``(first component, ids of the group)``; components without a fit stand alone."""
    groups: dict[int, list] = {}
    order = []
    for comp in components:
        key = id(comp.fit) if comp.fit is not None else id(comp)
        if key not in groups:
            groups[key] = []
            order.append(key)
        groups[key].append(comp)
    return [(groups[k][0], [c.id for c in groups[k]]) for k in order]


def check_plumb(ctx: Context) -> None:
    slug = "out-of-plumb"
    intended = float(ctx.general("intended_angle_deg"))
    for comp, ids in _one_per_fit(ctx.model.components):
        if comp.type not in ("cuboid", "cylinder", "pipe"):
            continue
        found = measured_axis(comp)
        if found is None:
            continue
        axis, height, centre = found
        lean_deg = 90.0 - _elevation_deg(axis)
        if lean_deg >= intended:
            continue
        se_deg = axis_stderr_deg(comp)
        if comp.type == "cuboid" or is_round_column(ctx, comp):
            material = material_of(ctx, comp)
        elif comp.type == "cylinder" and is_tank(ctx, comp):
            material = "tank"  # a merged pipe is never one, whatever its line number says
        else:
            material = "pipe"
        if material == "steel":
            ratio = float(ctx.opt(slug, "steel_ratio"))
            allowed = height / ratio
            standard = "AISC 303-16 7.13.1.1"
        elif material == "concrete":
            allowed = min(
                float(ctx.opt(slug, "concrete_fraction")) * height,
                float(ctx.opt(slug, "concrete_max")),
            )
            ratio = height / allowed
            standard = "ACI 117-10"
        elif material == "tank":
            ratio = float(ctx.opt(slug, "tank_ratio"))
            allowed = height / ratio
            standard = "API 650 7.5.2"
        else:
            ratio = float(ctx.opt(slug, "pipe_ratio"))
            allowed = height / ratio
            standard = "rules file pipe_ratio"
        lean = height * np.tan(np.radians(lean_deg))
        se = None if se_deg is None else height * np.radians(se_deg)
        outcome = verdict(lean, allowed, se, ctx.k)
        split = None
        if outcome == "unverifiable":
            # The lean's standard error is its worst direction's; a direction measured far
            # better (across a column's one seen face) may still decide.
            cos_lean = float(np.cos(np.radians(lean_deg)))
            split = _lean_by_direction(comp, height, cos_lean, allowed, ctx.k)
            if split is not None and split[0] == "violation":
                outcome, se = "violation", split[1]
        if material == "pipe" and outcome == "unverifiable":
            continue  # no plumb standard for pipes: only clear leans are reported
        shown = f"1:{height / lean:.0f}" if lean > 0 else "plumb"
        # Enough decimals that a lean over the limit never reads as equal to it.
        leans, limit = mm(lean), mm(allowed)
        places = 1
        while leans == limit and lean != allowed and places < 4:
            places += 1
            leans, limit = f"{lean * 1000:.{places}f} mm", f"{allowed * 1000:.{places}f} mm"
        ctx.emit(
            slug,
            ids,
            f"leans {leans} over {height:.2f} m ({shown}), allowed {limit} "
            f"(1:{ratio:.0f}, {standard})"
            + (
                split[2]
                if split is not None
                else f"; the lean is known to +- {mm(se)} only"
                if outcome == "unverifiable" and se
                else ""
            ),
            location=centre,
            measured=lean,
            allowed=allowed,
            stderr=se,
            unit="m",
            outcome=outcome,
            rescan=f"scan more points on {comp.id} over a longer stretch of its height (near the "
            "top and the bottom) and on a second face",
            suggestions=()
            if outcome == "unverifiable"
            else (Suggestion(f"survey {comp.id}'s plumb and realign or shim it"),),
        )


def _required_slope(ctx: Context, comp: Component) -> tuple[float, str]:
    """The slope a drain must have and where the requirement comes from."""
    required = float(ctx.opt("slope", "required"))
    if ctx.opt("slope", "use_ipc_704") and comp.nominal:
        # By the catalog's NPS: a DN catalog's "150" is NPS 6, not 150.
        table = ctx.catalog
        nps = table.nps_of(comp.nominal) if table is not None else nps_value(comp.nominal)
        if nps is not None:
            return (0.02 if nps <= 2.5 else 0.01 if nps <= 6 else 0.005), "IPC 2021 table 704.1"
    return required, "the rules file's slope.required"


def _has_keyword(text: str, keywords: list[str]) -> bool:
    """Whether a keyword is a whole word (or words) of ``text``: "drain" names "roof drain",
    not "raindrain" nor "drainage"."""
    return any(
        re.search(rf"(?<![a-z0-9]){re.escape(keyword)}(?![a-z0-9])", text) for keyword in keywords
    )


def check_slope(ctx: Context) -> None:
    slug = "slope"
    intended = float(ctx.general("intended_angle_deg"))
    keywords = [k.lower() for k in ctx.opt(slug, "keywords")]
    for comp, ids in _one_per_fit(ctx.pipes):
        if keywords:
            text = " ".join(filter(None, (comp.label, comp.group))).lower()
            if not _has_keyword(text, keywords):
                continue
        required, source = _required_slope(ctx, comp)
        if required <= 0:
            continue
        found = measured_axis(comp)
        if found is None:
            continue
        axis, _, centre = found
        elev = _elevation_deg(axis)
        if elev >= intended:
            continue
        slope = float(np.tan(np.radians(elev)))
        se_deg = axis_stderr_deg(comp)
        se = None if se_deg is None else float(np.radians(se_deg))
        outcome = verdict_min(slope, required, se, ctx.k)
        known = f" (known to +- {se * 100:.2f}%)" if se else ""
        if slope < required:
            text = f"slope {slope * 100:.2f}%{known} is below the required drainage slope"
        else:  # at least the required slope, but not known well enough to say so
            text = (
                f"slope {slope * 100:.2f}%{known} cannot be told from the required drainage slope"
            )
        ctx.emit(
            slug,
            ids,
            f"{text} {required * 100:.2f}% ({source})",
            location=centre,
            measured=slope,
            allowed=required,
            stderr=se,
            unit="ratio",
            outcome=outcome,
            rescan=f"scan {comp.id} over a longer stretch to measure its slope better",
            suggestions=()
            if outcome == "unverifiable"
            else (Suggestion(f"regrade {comp.id} to at least {required * 100:.2f}%"),),
        )


CHECKS = {
    "misaligned-axis": check_misaligned,
    "out-of-plumb": check_plumb,
    "slope": check_slope,
}
