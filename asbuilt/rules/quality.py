"""Scan quality rules: too-few-points, weak-geometry, poor-fit, outliers, ambiguous-kind,
another-object.

They judge the fit each component comes from (``component.fit``); merged fittings have none.
The residual test is a chi-square one in disguise: for ``d`` degrees of freedom the RMS of
Gaussian residuals over the sensor sigma has a standard error of about ``1 / sqrt(2 d)`` of itself.
The outlier share's standard error is the binomial ``sqrt(p (1 - p) / n)``.
"""

from __future__ import annotations

import numpy as np

from asbuilt.findings import Suggestion
from asbuilt.fit.auto import ONE_FACE_CUBOID, RIVAL_PREFIX
from asbuilt.fit.cylinder import (
    END_PLANE_SHOTS,
    OTHER_ANGLE,
    OTHER_RADIUS,
    OTHER_SHOTS,
    VIEW_IGNORED,
)
from asbuilt.fit.result import BACKGROUND_KEYS, NEIGHBOUR_SHOTS

from ._context import Context, centre_of, mm, stderr_value, verdict

__all__ = ["CHECKS"]

#: Parameters per fitted kind (degrees of freedom are points minus these).
_PARAMETERS = {"cylinder": 5, "cuboid": 9, "sphere": 4, "plane": 3, "hull": 0}


def _fitted(ctx: Context):
    seen = set()
    for comp in ctx.model.components:
        if comp.fit is None or id(comp.fit) in seen:
            continue
        seen.add(id(comp.fit))
        yield comp


def check_points(ctx: Context) -> None:
    slug = "too-few-points"
    for comp in _fitted(ctx):
        kind = comp.fit.kind
        if kind in ("cylinder", "cuboid"):
            needed = int(ctx.general(f"recommended_points_{kind}"))
        else:
            needed = int(ctx.opt(slug, kind))
        count = comp.fit.n_points
        if count >= needed:
            continue
        ctx.emit(
            slug,
            [comp.id],
            f"{count} points for a {kind}; the paper's accuracy needs at least {needed}",
            location=centre_of(comp.geometry),
            measured=count,
            allowed=needed,
            unit="points",
            suggestions=(Suggestion(f"scan at least {needed - count} more points on {comp.id}"),),
        )


def _apart(value: float, limit: float) -> tuple[str, str]:
    """``value`` and ``limit`` written with the fewest decimals (0 to 3) that tell them apart,
    so that a visible arc of 89.6 degrees reads ``89.6 < 90``, not ``90 < 90``."""

    def text(number: float, decimals: int) -> str:
        out = f"{number:.{decimals}f}"
        return out.rstrip("0").rstrip(".") if decimals else out

    for decimals in range(4):
        if text(value, decimals) != text(limit, decimals):
            break
    return text(value, decimals), text(limit, decimals)


def check_weak(ctx: Context) -> None:
    slug = "weak-geometry"
    min_arc = float(ctx.opt(slug, "min_arc_deg"))
    min_ld = float(ctx.opt(slug, "min_length_over_diameter"))
    min_faces = int(ctx.opt(slug, "min_faces"))
    max_rel = float(ctx.opt(slug, "max_relative_stderr"))
    for comp in _fitted(ctx):
        fit, prim = comp.fit, comp.fit.primitive
        diag = fit.diagnostics or {}
        reasons, advice = [], []
        worst = None
        if fit.kind == "cylinder":
            # The arc and length/diameter limits are the paper's, for pipes (a size to snap, an
            # axis to join). A tank, drum or column kept as a cylinder is squat and seen over
            # under 90 degrees from one station by nature; its standard errors say how well it
            # is known (a review's tanks: radius +-0.22% median, flagged on 86 of 164 fits).
            piping = comp.type == "pipe"
            arc = diag.get("arc_deg")
            if piping and arc is not None and float(arc) < min_arc:
                reasons.append("visible arc {} deg < {}".format(*_apart(float(arc), min_arc)))
                advice.append("shots across a wider arc (from a second position)")
            ld = diag.get("length_over_diameter", prim.length / (2 * prim.radius))
            if piping and float(ld) < min_ld:
                reasons.append(f"length/diameter {float(ld):.2f} < {min_ld:.2f}")
                advice.append("shots along a longer stretch")
            r_se = stderr_value(fit.stderr, "radius")
            if r_se is not None:
                worst = r_se / prim.radius
        elif fit.kind == "cuboid":
            faces = diag.get("faces")
            if faces is not None and int(faces) < min_faces:
                reasons.append(f"{int(faces)} face seen, {min_faces} needed")
                advice.append("shots on a second face")
            worst, size_reason = _cuboid_size_weakness(fit, max_rel)
            if size_reason:
                reasons.append(size_reason[0])
                advice.append(size_reason[1])
        elif fit.kind == "sphere":
            r_se = stderr_value(fit.stderr, "radius")
            if r_se is not None:
                worst = r_se / prim.radius
        if diag.get("open_sizes"):
            # A size the scan saw run on past its window (asbuilt.fit._window): a lower bound.
            what = "its length" if fit.kind == "cylinder" else "a size"
            reasons.append(f"{what} runs on past the scan window (a lower bound, not measured)")
            advice.append("a window over its ends")
        unreached = _count(diag.get("unreached_sizes"))
        if unreached:
            # Hand-aimed shots kept off the edges (asbuilt.fit._cuboid_reach): the size is the
            # shots' span, short by however far the operator stayed from the edges.
            sizes = "a size is" if unreached == 1 else f"{unreached} sizes are"
            reasons.append(
                f"{sizes} only a lower bound (the shots, not a raster, stop short of edges)"
            )
            advice.append("shots near both edges of each face, or a raster from the station")
        if fit.kind != "cuboid" and worst is not None and np.isfinite(worst) and worst > max_rel:
            reasons.append(f"size known to +-{worst * 100:.1f}% > {max_rel * 100:.0f}%")
            advice.append("more points")
        if not reasons:
            continue
        ctx.emit(
            slug,
            [comp.id],
            f"the fit is too weak to trust: {'; '.join(reasons)}",
            location=centre_of(comp.geometry),
            measured=worst,
            allowed=max_rel,
            unit="ratio",
            suggestions=(Suggestion(f"rescan {comp.id} with {', '.join(dict.fromkeys(advice))}"),),
        )


def _cuboid_size_weakness(fit, max_rel: float) -> tuple[float | None, tuple[str, str] | None]:
    """A cuboid's largest relative size standard error over its sizes that have one, and when
    it exceeds ``max_rel`` the reason and advice naming that size.

    Every size with a finite standard error counts: one measured between two seen faces and
    one bounded by the points' extent (its error the raster step in which the unseen edge
    lies). A size with an infinite one (a lower bound: run on past the window, shots off a
    raster, the depth behind a lone face) has its own reason above, not this one.
    """
    size_se = fit.stderr.get("size") if fit.stderr else None
    if size_se is None:
        return None, None
    se = np.asarray(size_se, dtype=np.float64).ravel()
    size = np.asarray(fit.primitive.size, dtype=np.float64).ravel()
    if se.size != size.size:
        return None, None
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = se / size
    finite = np.isfinite(rel)
    if not finite.any():
        return None, None
    k = int(np.flatnonzero(finite)[np.argmax(rel[finite])])
    worst = float(rel[k])
    if worst <= max_rel:
        return worst, None
    observed = fit.observed is not None and k < len(fit.observed) and bool(fit.observed[k])
    reason = (
        f"a size of {mm(float(size[k]))} known to +-{mm(float(se[k]))}"
        f" ({worst * 100:.1f}% > {max_rel * 100:.0f}%)"
    )
    if observed:
        return worst, (reason, "more points on both faces it lies between")
    # Bounded by the points' extent: the unseen edge lies somewhere in the raster step past
    # the last shot (a window wider than the object puts it at the window's side).
    return worst, (
        reason + ", an unseen edge placed within a raster step",
        "shots on its unseen edges (an `asbuilt scan` session's edge bisection finds them)",
    )


def _sensor_sigma(ctx: Context, fit) -> float | None:
    if fit.sigma_source == "sensor" and fit.sigma > 0:
        return float(fit.sigma)
    scan = ctx.model.scan
    if scan is not None and scan.sensor.range_sigma:
        return float(scan.sensor.range_sigma)
    return None


def check_poor_fit(ctx: Context) -> None:
    slug = "poor-fit"
    allowed = float(ctx.opt(slug, "max_rms_ratio"))
    for comp in _fitted(ctx):
        fit = comp.fit
        sigma = _sensor_sigma(ctx, fit)
        if sigma is None or fit.n_inliers < 2 or not np.isfinite(fit.rms):
            continue
        ratio = fit.rms / sigma
        dof = max(fit.n_inliers - _PARAMETERS.get(fit.kind, 0), 1)
        se = ratio / np.sqrt(2.0 * dof)
        outcome = verdict(ratio, allowed, se, ctx.k)
        if outcome != "violation":
            continue  # the sensor's sigma is a nominal value: only clear excesses are reported
        ctx.emit(
            slug,
            [comp.id],
            f"residual RMS {fit.rms * 1000:.1f} mm is {ratio:.1f} times the sensor sigma "
            f"{sigma * 1000:.1f} mm",
            location=centre_of(comp.geometry),
            measured=ratio,
            allowed=allowed,
            stderr=se,
            unit="sigma",
            suggestions=(
                Suggestion(f"check that {comp.id} is a {fit.kind} (or fit it as auto/hull)"),
                Suggestion(f"inspect {comp.id} for bends or damage"),
            ),
        )


def check_outliers(ctx: Context) -> None:
    slug = "outliers"
    allowed = float(ctx.opt(slug, "max_share"))
    for comp in _fitted(ctx):
        fit = comp.fit
        n = fit.n_points
        if n == 0:
            continue
        rejected = n - fit.n_inliers
        # Shots the cylinder fit found on a surface across the pipe's end (a flange face, the
        # wall it enters) are explained, not background the fit may have taken for the pipe.
        on_end = _count(fit.diagnostics.get(END_PLANE_SHOTS))
        # ... and those that fit another cylinder are another object, which another-object
        # reports with its own remedy.
        on_other = min(_count(fit.diagnostics.get(OTHER_SHOTS)), max(rejected - on_end, 0))
        # ... and those a rescue found behind the object along their beams, or on a wall,
        # floor or ceiling around it, are the background itself, told apart and left out:
        # the fit did not take it for the object (an independent review's tanks before a
        # wall drew this warning on every good fit).
        behind = sum(_count(fit.diagnostics.get(key)) for key in BACKGROUND_KEYS)
        on_background = min(behind, max(rejected - on_end - on_other, 0))
        # ... and those on a neighbour's surface, which its own shots fit, left out before
        # the pipe was fitted again.
        neighbour = _count(fit.diagnostics.get(NEIGHBOUR_SHOTS))
        on_neighbour = min(neighbour, max(rejected - on_end - on_other - on_background, 0))
        unexplained = rejected - on_end - on_other - on_background - on_neighbour
        share = unexplained / n
        se = float(np.sqrt(max(share * (1 - share), 1.0 / n) / n))
        if share <= allowed:
            continue
        outcome = verdict(share, allowed, se, ctx.k)
        explained = []
        if on_end:
            explained.append(
                f"{on_end} more lie on a plane across the pipe's end: a flange face, or the"
                " wall it enters"
            )
        if on_other:
            explained.append(f"{on_other} more fit another cylinder")
        if on_background:
            explained.append(f"{on_background} more were told apart as the background behind it")
        if on_neighbour:
            explained.append(f"{on_neighbour} more lie on a neighbour's surface")
        said = "; ".join(explained)
        ctx.emit(
            slug,
            [comp.id],
            f"{unexplained} of {n} points ({share * 100:.0f}%) were rejected as outliers"
            + (f" ({said})" if said else ""),
            location=centre_of(comp.geometry),
            measured=share,
            allowed=allowed,
            stderr=se,
            unit="ratio",
            outcome="violation" if outcome == "unverifiable" else outcome,
            suggestions=(
                Suggestion(f"rescan {comp.id} aiming away from its edges and the background"),
            ),
        )


def _count(value) -> int:
    """A diagnostics count (a float, or None / NaN from a model file) as an int, 0 if unknown."""
    return int(value) if value is not None and np.isfinite(value) else 0


def check_ambiguous_kind(ctx: Context) -> None:
    """Objects of kind ``auto`` whose shots another kind explains as well (the fit's
    ``auto_rival_<kind>`` diagnostics, :func:`asbuilt.fit.auto.fit_auto`), and those fitted as
    a plane from one face of what their label calls a vessel or structure (a column seen
    face-on: ``auto_one_face_cuboid``), whose depth the shots do not measure."""
    slug = "ambiguous-kind"
    words = ctx.config.label_words
    for comp in _fitted(ctx):
        fit = comp.fit
        noun = words.vessel_noun(comp.label, comp.group)
        if fit.diagnostics.get(ONE_FACE_CUBOID) and noun is not None:
            ctx.emit(
                slug,
                [comp.id],
                f"auto chose a plane, but {comp.id} is labelled a {noun} and the shots saw one"
                " face of it: they cannot tell a wall or plate from a box seen face-on, whose"
                f" depth they do not measure; the model has a {noun} as a plate",
                location=centre_of(comp.geometry),
                measured=1.0,
                unit="faces",
                suggestions=(
                    Suggestion(f"set the kind of {comp.id} to cuboid in the scan if it is a box"),
                    Suggestion(f"take shots on a second face of {comp.id}"),
                ),
            )
            continue
        rivals = {
            key[len(RIVAL_PREFIX) :]: float(gap)
            for key, gap in fit.diagnostics.items()
            if key.startswith(RIVAL_PREFIX)
        }
        if not rivals:
            continue
        names = " or a ".join(sorted(rivals))
        closest = min(rivals.values())
        ctx.emit(
            slug,
            [comp.id],
            f"auto chose {fit.kind}, but a {names} explains the shots as well (BIC "
            f"{closest:+.1f}); these shots cannot tell them apart",
            location=centre_of(comp.geometry),
            measured=closest,
            unit="BIC",
            suggestions=tuple(
                Suggestion(f"set the kind of {comp.id} to {kind} in the scan if it is one")
                for kind in (fit.kind, *sorted(rivals))
            )
            + (Suggestion(f"take more shots on {comp.id}, across its width"),),
        )


def check_another_object(ctx: Context) -> None:
    """Cylinders whose rejected shots fit another cylinder (the fit's ``other_cylinder_*``
    diagnostics, :mod:`asbuilt.fit._cylinder_others`): a tee's header, a rack neighbour, or
    the object itself when the fit settled on its neighbour."""
    slug = "another-object"
    for comp in _fitted(ctx):
        fit = comp.fit
        shots = _count(fit.diagnostics.get(OTHER_SHOTS))
        radius = fit.diagnostics.get(OTHER_RADIUS)
        if not shots or radius is None or not np.isfinite(radius):
            continue
        angle = float(fit.diagnostics.get(OTHER_ANGLE, float("nan")))
        ctx.emit(
            slug,
            [comp.id],
            f"{shots} of {fit.n_points} points, left out of the fit, fit another cylinder"
            f" (radius {mm(float(radius))}, axis {angle:.0f} deg from the fitted one's);"
            " the fit may be of a neighbour or header rather than the object aimed at",
            location=centre_of(comp.geometry),
            measured=shots,
            unit="points",
            suggestions=(
                Suggestion(
                    f"if {comp.id} is the other cylinder, give it only that cylinder's shots"
                    " (or rescan with the raster window on it alone)"
                ),
                Suggestion(f"scan the other cylinder as an object of its own, beside {comp.id}"),
            ),
        )


def check_viewpoint_ignored(ctx: Context) -> None:
    """Cylinders fitted only by ignoring the station (the fit's note
    :data:`asbuilt.fit.cylinder.VIEW_IGNORED`): every cylinder that honours it would have more
    than a third of the shots seen through the pipe. With the station right that is a fit
    through the shots of more than one surface; an independent review's rack and occlusion
    scenes had 3 such fits, all wrong by 50 mm to 4 m (one snapped to NPS 18 for an NPS 4)."""
    slug = "viewpoint-ignored"
    for comp in _fitted(ctx):
        fit = comp.fit
        if VIEW_IGNORED not in fit.notes:
            continue
        ctx.emit(
            slug,
            [comp.id],
            "no cylinder that honours the station fits the shots: the one kept would have more"
            " than a third of them measured through it, so it likely runs through the shots of"
            " more than one surface (a neighbour, a wall) and its size and axis are in doubt",
            location=centre_of(comp.geometry),
            suggestions=(
                Suggestion(
                    f"give {comp.id} only its own shots (rescan with the raster window on it alone)"
                ),
                Suggestion(f"check the scan's sensor position or {comp.id}'s station"),
            ),
        )


CHECKS = {
    "too-few-points": check_points,
    "weak-geometry": check_weak,
    "poor-fit": check_poor_fit,
    "outliers": check_outliers,
    "ambiguous-kind": check_ambiguous_kind,
    "another-object": check_another_object,
    "viewpoint-ignored": check_viewpoint_ignored,
}
