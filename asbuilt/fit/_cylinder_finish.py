"""The last stage of a cylinder fit: the chosen robust fit's checks and refinements, and its
:class:`~asbuilt.fit.result.FitResult`.

Private helper of :mod:`asbuilt.fit.cylinder`, which settles on a robust fit (the quick path's
or the full search's) and hands it here with the scan (:class:`Scene`): good shots the robust
basin rejected are taken back (:func:`readmitted`), fits seen edge-on are refused, dense clouds
are settled on every point, far-side shots and shots the pipe would have hidden from the
viewpoint are dropped (:func:`not_seen_through`), the inliers are weighted by incidence, and the
result's centre, length (with the raster step at each end, :func:`end_gaps`), covariance and
standard errors are computed (:func:`finished`). Lengths in metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import (
    arc_coverage_deg,
    covariance_from_jacobian,
    median_spacing,
    noise_level,
    orient,
    quick_median,
    stderr_of,
)
from asbuilt.fit._cylinder_checks import (
    EDGE_ON_DEG,
    EDGE_ON_QUARTILE_DEG,
    doubtful_blind,
    edge_on,
    seen_through,
)
from asbuilt.fit._cylinder_model import (
    MODEL,
    angles_about,
    drop_far_side,
    facing,
    flip_covariance,
    incidence_weighted,
    rms,
)
from asbuilt.fit._cylinder_two_lines import on_two_lines, on_two_raster_lines, radius_reach
from asbuilt.fit._robust import refit_on, robust_geometric_fit
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Cylinder
from asbuilt.tolerances import MIN_POINTS, Tolerances

__all__ = [
    "METHOD",
    "VIEW_IGNORED",
    "NeedsFullSearch",
    "Scene",
    "end_gaps",
    "finished",
    "not_seen_through",
    "readmitted",
]


METHOD = (
    "normal-based axis starts + Kasa circle + robust geometric Gauss-Newton on orthogonal "
    "distances (Lukacs, Marshall & Martin 1998)"
)


#: The note of a fit that ignored the stated viewpoint (:func:`finished`).
VIEW_IGNORED = (
    "The viewpoint was ignored: every cylinder found that honours it would have more than a "
    "third of the shots seen through the pipe from it. Check the scan's sensor position or the "
    "station; if they are right, many shots lie on another surface beside the pipe (a wall it "
    "enters, a flange): give only the pipe's shots."
)


def readmitted(robust, local, cutoff: float):
    """The least-squares fit of every shot, from ``robust``'s state, when it explains each
    within ``cutoff`` metres and at an MSAC cost (cut at ``cutoff``) no higher than the robust
    fit's; else ``robust``.

    The robust choice can settle in a basin that rejects a few good shots: 30 shots over 120
    degrees of a 0.1 m pipe, all within 2.6 sigma of the least-squares cylinder (r 96.5 mm),
    came out r 90.7 mm with 3 rejected (the sensor's sigma given, no viewpoint). The later
    checks (far side, hidden shots) still judge the re-admitted shots.
    """
    if robust.inliers.all() or np.abs(robust.residuals[~robust.inliers]).max() > 2 * cutoff:
        return robust  # (a shot twice the cutoff off is no good shot a nearby fit could take)
    every = refit_on(MODEL, robust, local, np.ones(len(local), bool))
    if not (np.abs(every.residuals) <= cutoff).all():
        return robust
    kept = robust.residuals[robust.inliers]
    robust_cost = float(kept @ kept) + cutoff * cutoff * int(np.count_nonzero(~robust.inliers))
    if float(every.residuals @ every.residuals) > robust_cost:
        return robust
    return every


#: Refits after dropping inliers seen through the pipe (:func:`not_seen_through`) before the
#: fit is refused: each refit can move the pipe onto other shots' beams.
THROUGH_ROUNDS = 3


def not_seen_through(robust, local, view, sigma, tolerances: Tolerances):
    """The fit without the inliers its own pipe would have hidden from the viewpoint
    (:func:`seen_through`), refitted by least squares, and how many were dropped; FitError when
    too few shots are left, more than ``tolerances.max_outlier_fraction`` are rejected, or the
    refits keep hiding shots.

    The robust choice scores hidden shots but can still settle on a fit that hides a few (a
    wide circle through a thin pipe's front shots and the wall rows behind it, when fewer than
    ``UNSEEN_FRACTION`` of its inliers are hidden); those shots are outliers.
    """
    n = len(local)
    dropped = 0
    for round_ in range(THROUGH_ROUNDS + 1):
        cutoff = tolerances.outlier_cutoff_sigma * (sigma if sigma is not None else robust.scale)
        through = seen_through(robust, local, view, cutoff)
        count = int(np.count_nonzero(through))
        if not count:
            return robust, dropped
        keep = robust.inliers & ~through
        left = int(np.count_nonzero(keep))
        if (
            round_ == THROUGH_ROUNDS
            or left < MIN_POINTS["cylinder"]
            or n - left > tolerances.max_outlier_fraction * n
        ):
            break
        robust = refit_on(MODEL, robust, local, keep)
        dropped += count
    raise FitError(
        f"The cylinder these shots fit best (r {robust.state[2] * 1000:.0f} mm) would hide"
        f" {count} of its own shots behind itself as seen from the viewpoint, and without them"
        f" {left} of the {n} shots are left: they are mostly background and mixed returns"
        " around a thin pipe, or the station is wrong. Rescan with more shots across the pipe,"
        " or check the scan's sensor position or the object's station."
    )


#: The largest gap between shots along a pipe's axis over their median gap from which the shots
#: are taken to lie on separate raster lines (:func:`end_gaps`): evenly spaced shots vary by
#: their noise, lines crossing the axis are several of their own spreads apart.
_ROW_BREAK = 4.0

#: Gaps at each end a line's pattern of shots along the axis repeats within (:func:`end_gaps`).
_PATTERN = 3


def end_gaps(along: np.ndarray, spacing: float, noise: float) -> tuple[float, float]:
    """The step of the shots along the axis beyond each end, metres: from the outermost shot to
    the nearest one farther in by more than a row's own spread (a quarter of the median
    nearest-neighbour ``spacing``, at least three ``noise``), else ``spacing``.

    Each end lies somewhere in the step after the last shot that hit. The nearest-neighbour
    spacing alone is the step across the raster where that is the smaller: the sample plant's
    chimney, shot by rows metres apart of shots 0.3 m apart, had its length known to
    +-0.12 m, and came out 2.7 m short (17.3 m of 20).
    ``along``: the inliers' coordinates along the axis, shape (m,) metres.
    """
    ordered = along.copy()  # np.sort(along), without its wrapper
    ordered.sort()
    same_row = max(0.25 * spacing, 3.0 * noise)
    gaps = ordered[1:] - ordered[:-1]  # np.diff's differences, without its overhead
    if gaps.size:
        # Raster lines crossing the axis obliquely spread along it: a line's shots lie a few
        # centimetres apart along the axis, the lines tenths of a metre apart. Told by the
        # nearest-neighbour spacing alone, a line's own spread passed for the step (a pipe at
        # 30-60 degrees to the rows: length 4.60 m of 6 +-21 mm). When the gaps fall in two
        # scales (the largest over _ROW_BREAK times the median), a break between lines is a
        # gap above their geometric mean.
        typical, widest = quick_median(gaps), float(gaps.max())
        if widest > _ROW_BREAK * typical:
            same_row = max(same_row, math.sqrt(typical * widest))
    low = ordered[ordered > ordered[0] + same_row]
    high = ordered[ordered < ordered[-1] - same_row]
    # Lines of two or three shots each alternate a short gap (within a line) and a long one
    # (between lines), too close in scale for the break above: the step is the longest of the
    # end's first _PATTERN gaps.
    return (
        max(
            float(low[0] - ordered[0]) if low.size else spacing,
            float(gaps[:_PATTERN].max(initial=0.0)),
        ),
        max(
            float(ordered[-1] - high[-1]) if high.size else spacing,
            float(gaps[-_PATTERN:].max(initial=0.0)),
        ),
    )


class NeedsFullSearch(Exception):
    """Raised by :func:`finished` when a quick fit needs the other starts it never made."""


@dataclass(frozen=True)
class Scene:
    """What the last stage of a cylinder fit (:func:`finished`) needs of the scan.

    ``pts`` (n, 3) metres as given; ``offset`` (3,) metres, their centroid; ``local`` (m, 3)
    metres, ``pts - offset`` or a subsample of it when ``everything`` (n, 3) holds all of them
    (dense clouds); ``view`` (3,) metres in ``local``'s frame, or None; ``sigma`` metres or
    None.
    """

    pts: np.ndarray
    offset: np.ndarray
    local: np.ndarray
    everything: np.ndarray | None
    view: np.ndarray | None
    sigma: float | None
    tolerances: Tolerances


def finished(robust, scene: Scene, ignored_view, starts, reconsider) -> FitResult:
    """The chosen robust fit's checks and refinements (edge-on shots, dense clouds settled on
    every point, far-side shots, incidence weights) and its :class:`FitResult` (see
    :func:`~asbuilt.fit.cylinder.fit_cylinder`; ``scene`` the scan, :class:`Scene`;
    ``reconsider(robust, None)`` settles a fit again from other starts, or is None when the
    caller guarantees it is not needed)."""
    pts, offset, local, everything = scene.pts, scene.offset, scene.local, scene.everything
    view, sigma, tolerances = scene.view, scene.sigma, scene.tolerances
    if not ignored_view:
        # Without the sensor's sigma, at the prior noise level: a fit whose own scale came from
        # its grazing shots (small errors across the surface) had rejected the square-on ones.
        noise = sigma if sigma is not None else max(robust.scale, tolerances.prior_range_sigma)
        robust = readmitted(robust, local, tolerances.outlier_cutoff_sigma * noise)
    if view is not None and edge_on(robust, local, view):
        # Shots strung along the viewpoint's own beams also say that the viewpoint is right.
        raise FitError(
            "The shots this cylinder fits were nearly all seen edge-on from the viewpoint (half"
            f" of them within {90 - EDGE_ON_DEG:g} degrees of grazing, or three quarters within"
            f" {90 - EDGE_ON_QUARTILE_DEG:g}): they are returns strung"
            " along their beams (mixed pixels between a thin pipe and what lies behind it), not"
            " a pipe's surface. Rescan with more shots across the pipe, or check the station.",
        )
    if everything is not None:
        local = everything
        robust = robust_geometric_fit(
            local, [robust.state], MODEL, kind="cylinder", sigma=sigma, tolerances=tolerances
        )
    near = robust
    # One fit's directions about its axis, asked by the far-side test and, when neither it nor
    # the shots seen through the pipe changed the fit, by the incidence weights.
    seen = facing(near, local)
    robust = drop_far_side(near, local, tolerances, seen)
    far_side = int(np.count_nonzero(near.inliers & ~robust.inliers))
    if view is None and starts and far_side and doubtful_blind(robust, local):
        # The far-side refit slid onto a plane: the likeliest other basin replaces it if closer
        # (a plate with shots behind it is nearly a plane; a looser cylinder is no better).
        if reconsider is None:
            raise NeedsFullSearch
        settled = reconsider(robust, None)
        if rms(settled.residuals[settled.inliers]) < rms(robust.residuals[robust.inliers]):
            robust, far_side = settled, 0
    through = 0
    if view is not None and not ignored_view:
        robust, through = not_seen_through(robust, local, view, sigma, tolerances)
    robust, relative = incidence_weighted(robust, local, seen if robust is near else None)
    axis, center, radius = robust.state
    kept = local[robust.inliers]
    along = (kept - center) @ axis
    low, high = float(along.min()), float(along.max())
    length = high - low
    if length <= 0:
        raise FitError("The points must spread along the cylinder's axis to give it a length.")
    mid = center + 0.5 * (low + high) * axis
    # Noise level of a square-on shot; the inliers' weights are 1 / relative variance.
    weights = 1.0 / relative[robust.inliers]
    noise, source = noise_level(
        robust.residuals[robust.inliers] * np.sqrt(weights), 5, sigma, tolerances
    )
    # Re-express the Jacobian about the mid-point (the reported centre): shift the along-axis
    # coordinate used by the tilt columns.
    jac = robust.jacobian.copy()
    shift = 0.5 * (low + high)
    jac[:, 0] -= shift * jac[:, 2]
    jac[:, 1] -= shift * jac[:, 3]
    covariance = covariance_from_jacobian(jac * np.sqrt(weights)[:, None], noise)
    tilt_var = covariance[0, 0] + covariance[1, 1]
    angles = angles_about(axis, center, kept)
    # Without the sensor's sigma the residuals cannot give the noise: on two lines the circle
    # bends to absorb it (an independent review's rack pipe: 0.77 mm RMS from 2 mm shots, and
    # no radius above the fit's passing at that level). The prior noise stands in for it.
    walk_noise = noise if sigma is not None else max(noise, float(tolerances.prior_range_sigma))
    lines_along = on_two_lines(
        kept, axis, center, tolerances.outlier_cutoff_sigma * walk_noise, angles
    )
    # Two raster lines across or slanted over the pipe leave a valley of radii as well.
    lines_over = (
        not lines_along
        and view is not None
        and not ignored_view
        and on_two_raster_lines(kept, view)
    )
    two_lines = lines_along or lines_over
    # Unit weights: the incidence weights were fitted at this fit's own incidences, and a
    # line it holds at exact grazing (its shots along their beams, tangent to it) shows no
    # residual and so weighs most, pinning this very radius (three tank columns, the grazing
    # one taken as a tangent: r 1.59 m +-22 mm for 1.95).
    unit = np.ones(len(kept))
    reach = radius_reach(kept, unit, axis, center, radius, walk_noise) if two_lines else radius
    if reach > radius:
        # Two raster lines along the pipe bound its radius only from below
        # (asbuilt.fit._cylinder_two_lines): the radii the shots accept, and the centre that
        # moves with them, widen the covariance's errors.
        spread = 0.5 * (reach - radius)
        covariance[4, 4] += spread**2
        covariance[2, 2] += 0.5 * spread**2
        covariance[3, 3] += 0.5 * spread**2
    gaps = end_gaps(along, median_spacing(kept), noise)
    length_se = stderr_of(
        (gaps[0] ** 2 + gaps[1] ** 2) / 3.0 + 2.0 * noise**2 + (radius**2) * tilt_var
    )
    oriented = orient(axis)
    cylinder = Cylinder(mid + offset, oriented, radius, length)
    stderr = {
        "radius": stderr_of(covariance[4, 4]),
        "axis_deg": float(np.degrees(stderr_of(tilt_var))),
        "center": stderr_of(covariance[2, 2] + covariance[3, 3]),
        "length": length_se,
    }
    if oriented is not axis:
        covariance = flip_covariance(covariance, axis, oriented)
    notes = []
    if ignored_view:
        notes.append(VIEW_IGNORED)
    if reach > radius:
        lines = "two raster lines over the pipe" if lines_over else "two lines along the pipe"
        notes.append(
            f"The shots lie on {lines}: they fit radii from {radius * 1000:.3g}"
            f" to {reach * 1000:.3g} mm as well (the radius's standard error spans them). Take"
            " a third raster line across the pipe to measure it."
        )
    outliers = int(len(pts) - robust.inliers.sum())
    if outliers:
        notes.append(
            f"{outliers} outlier point(s) rejected (beyond {tolerances.outlier_cutoff_sigma:g}"
            f" x {robust.scale * 1000:.3g} mm"
            + (f", or {far_side} on the far side of the pipe" if far_side else "")
            + (f", or {through} seen through it from the viewpoint" if through else "")
            + ")."
        )
    diagnostics = {
        "arc_deg": arc_coverage_deg(angles),
        "length_over_diameter": length / (2.0 * radius),
        "starts": float(len(starts)),
    }
    if reach > radius:
        diagnostics["radius_reach"] = reach
    return FitResult(
        primitive=cylinder,
        residuals=cylinder.distance(pts),
        inliers=robust.inliers,
        stderr=stderr,
        sigma=noise,
        sigma_source=source,
        method=METHOD,
        covariance=covariance,
        diagnostics=diagnostics,
        notes=tuple(notes),
    )
