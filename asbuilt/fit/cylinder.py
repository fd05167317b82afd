"""Cylinder fit for sparse scans of pipes and columns: partial arcs, short stubs, edge outliers.

Method
------
1. Axis starts: the direction most perpendicular to the local surface normals (smallest
   eigenvector of ``sum n n^T`` over k-nearest-neighbour PCA normals, Hoppe et al. 1992, with a
   Tukey reweighting against normals spoiled by outliers) and its other eigenvectors, the
   points' principal directions, the cross products of the normals of the three best two-point
   samples (Schnabel, Wahl & Klein 2007; short stubs, whose principal direction is across the axis),
   and a robust line through the points (long thin pipes with background shots).
2. For each start, a robust circle in the plane perpendicular to the axis gives the centre and
   radius: the Kasa (1976) algebraic circle or the best circumcircle of random triples, polished
   by least-trimmed-squares concentration steps. Below ``POLISH_BELOW`` points the best start's
   axis is also refined by a pattern search on that circle's trimmed cost.
3. Geometric least squares over five parameters (two axis tilts, two across-axis centre
   offsets, the radius) minimising the orthogonal distances ``|P_perp (p - c)| - r``
   (Lukacs, Marshall & Martin 1998, "Faithful least-squares fitting of spheres, cylinders,
   cones and tori"; Eberly, "Fitting 3D data with a cylinder"), by Gauss-Newton with an
   analytic Jacobian, wrapped in the robust scheme of
   :func:`asbuilt.fit._robust.robust_geometric_fit` (concentration steps from the best starts,
   MSAC choice, then least squares on the inliers). The normal-based start and the best other
   one are both refined unless that is redundant (:func:`~asbuilt.fit._cylinder_starts.trust_order`: the same hypothesis
   twice, or a normal-based start far worse and far off).
4. When the viewpoint is known and the fit is in doubt (a sparse scan, rejected shots, or a beam
   that would have passed through the fitted pipe), the best starts are settled again and the
   shots' beams decide (:mod:`asbuilt.fit._visibility`): a fit that explains some shots only by
   placing them on its own far side, behind it along their beams, pays for them as outliers.
5. Shots on the far side of a pipe seen from one side are rejected (a station cannot see them:
   they are background shots that landed on the infinite cylinder), and the inliers are refitted
   with weights from a fitted incidence noise model (range noise along the beam makes grazing
   shots more precise than square-on ones).

6. When more than a quarter of the shots lie off that fit, or it was refused or ignored the
   viewpoint, a plane across the pipe's end holding many of them (a flange face, the wall the
   pipe enters) is looked for by RANSAC and the pipe fitted again without its shots
   (:mod:`asbuilt.fit._cylinder_end_plane`); that fit replaces the first when the geometry
   says the plane bounds the pipe and it explains the other shots better (MSAC).

The geometric estimate is the final one: algebraic circle fits alone are biased on partial arcs.

Scans of 35 points or more with a known sigma first try the quick path
(:mod:`asbuilt.fit._cylinder_quick`): the fit from step 1's first axes alone stands when the
scan says it needs no second look (clean, or every rejected shot where only background can be).

This module holds the sequence; the steps live in :mod:`asbuilt.fit._cylinder_starts` (1, and
the order in which starts are trusted), :mod:`asbuilt.fit._cylinder_model` (3 and 5: the
least-squares model, the far-side and incidence refits) and
:mod:`asbuilt.fit._cylinder_checks` (4: the consistency checks and the MSAC rescue); the chosen
fit's last checks, refinements and result are :mod:`asbuilt.fit._cylinder_finish`'s.
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._circles import circle_starts
from asbuilt.fit._common import (
    check_spread,
    local_normals,
    principal_axes,
    random_subset,
    validate_points,
)
from asbuilt.fit._cylinder_background import (
    NEAR_SHARE,
    depth_segments,
    fit_without_background,
    fit_without_background_plane,
    segment_noise,
)
from asbuilt.fit._cylinder_checks import (
    RESCUE_REJECTED,
    admissible,
    better_fit,
    consistent,
    doubtful,
    half_line_axes,
    msac_fits,
    one_station_could_see,
    robust_extent,
    same_basin,
    shot_from,
    unhidden_starts,
    unseen,
)
from asbuilt.fit._cylinder_end_plane import (
    END_PLANE_SHOTS,
    drawn_to_a_face,
    fit_without_end_plane,
    worth_a_look,
)
from asbuilt.fit._cylinder_far_side import without_far_side
from asbuilt.fit._cylinder_finish import (
    METHOD,
    VIEW_IGNORED,
    NeedsFullSearch,
    Scene,
    finished,
)
from asbuilt.fit._cylinder_model import (
    MODEL,
    stacked,
)
from asbuilt.fit._cylinder_open_space import apart_across_open_space
from asbuilt.fit._cylinder_others import (
    NO_MAJORITY,
    OTHER_ANGLE,
    OTHER_RADIUS,
    OTHER_SHOTS,
    cylinders_named,
    with_other_cylinder,
)
from asbuilt.fit._cylinder_planes import fit_past_planes
from asbuilt.fit._cylinder_quick import quick_fit as _quick_fit
from asbuilt.fit._cylinder_quick import rejected_are_background, robust_among
from asbuilt.fit._cylinder_starts import (
    POLISH_BELOW,
    POLISHED_STARTS,
    line_axis,
    normal_axes,
    pair_starts,
    polish_axes,
    quick_axes,
    starts_of,
)
from asbuilt.fit._robust import (
    RobustFit,
    keep_count,
    likelier,
)
from asbuilt.fit._visibility import (
    cylinder_beam_excess,
    reconsidered,
)
from asbuilt.fit.result import FitResult
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = [
    "END_PLANE_SHOTS",
    "ON_RASTER",
    "VIEW_IGNORED",
    "OTHER_ANGLE",
    "OTHER_RADIUS",
    "OTHER_SHOTS",
    "fit_cylinder",
    "METHOD",
]


#: How many of the best starts are settled again and judged by their beams when the viewpoint
#: is known (:func:`asbuilt.fit._visibility.reconsidered`).
RECONSIDERED_STARTS = 4


#: Above this many points (a dense cloud, not a sparse scan) the starts are found on this many
#: of them at random (memory and time otherwise grow with starts x samples x points).
DENSE_POINTS = 2000


#: A fit of the shots alone overrules the stated viewpoint only if it rejects fewer than this
#: fraction of them: edge outliers (up to a fifth of the shots) leave a fit that can, while one
#: rejecting a third or more is as doubtful as the station it would overrule (measured on the
#: independent ray caster: a thin pipe at 10 m whose raster was 60% mixed returns was fitted
#: 12 cm too wide, the station given as wrong).
OVERRULE_REJECTED = 1.0 / 3.0


def _robust_fit(local, starts, costs, robust_from, polished, tolerances) -> RobustFit:
    """The robust fit from the starts (already polished below ``POLISH_BELOW`` points); above,
    the polished starts are tried too when the first fit rejected shots, and the likelier fit
    kept."""
    robust = robust_from(starts, costs)
    if len(local) < POLISH_BELOW:
        return robust
    if starts and not robust.inliers.all():
        # Background shots present: also try the polished starts and keep the likelier fit.
        try:
            second = robust_from(*polished(starts, costs))
        except FitError:
            second = None
        if second is not None and likelier(second, robust, local, tolerances):
            robust = second
    return robust


#: Radius factors of the seeds :func:`_radius_seeds` adds to a reconsidered fit.
RADIUS_SEED_FACTORS = (0.5, 2.0)


def _radius_seeds(state, view, known, extent) -> list:
    """Seeds with the fit's radius scaled by ``RADIUS_SEED_FACTORS`` and its near side, as seen
    from ``view`` (3,) metres, kept in place.

    A few raster columns along a pipe pin its near side and its axis, not its radius: the
    circles across the axis pass through two or three clusters of shots, and a start settles
    in whichever radius basin is nearest. Seeds of another radius with the same near side let
    the beams and the MSAC cost choose (an NPS 4 pipe at 7 m seen by two columns of 10 shots
    was fitted r 27.6 mm for 57.2, one shot rejected, where the true basin costs less).
    """
    axis, center, radius = state
    toward = center - view
    toward = toward - (toward @ axis) * axis
    length = float(np.linalg.norm(toward))
    if length <= 0.0:
        return []
    toward /= length
    seeds = []
    for factor in RADIUS_SEED_FACTORS:
        seed = (axis, center + (factor - 1.0) * radius * toward, factor * radius)
        if not any(same_basin(seed, other, extent) for other in (*known, *seeds)):
            seeds.append(seed)
    return seeds


def fit_cylinder(
    points,
    *,
    sigma=None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    viewpoint=None,
) -> FitResult:
    """Fit a bounded circular cylinder to points on its visible side.

    Works on partial arcs down to about 90 degrees and on stubs shorter than their diameter;
    up to ``tolerances.max_outlier_fraction`` of edge outliers are rejected and reported. See
    the module docstring for the algorithm (normal, two-point and line starts, robust circles,
    axis pattern search, robust geometric Gauss-Newton after Lukacs, Marshall & Martin 1998,
    least squares on the inliers weighted by a fitted incidence noise model).

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    sigma : float, optional, metres
        The sensor's range sigma (of a square-on shot); sets the inlier threshold and scales
        the standard errors when given.
    tolerances : Tolerances
    viewpoint : array_like, shape (3,), metres, optional
        Where the shots were taken from. When given and the fit is in doubt (:func:`~asbuilt.fit._cylinder_checks.doubtful`),
        the fit is settled again from the best starts of other basins and the beams decide
        between them (a shot's beam must reach it without passing through the pipe,
        :mod:`asbuilt.fit._visibility`); a viewpoint the shots cannot have come from is ignored
        with a note, unless from it the nearest surface holds ``NEAR_SHARE`` of the shots with
        the rest behind it (a pipe before a wall that no fit found: refused).

    Returns
    -------
    FitResult
        ``primitive`` is a :class:`~asbuilt.primitives.Cylinder` whose ``center`` is the
        mid-point of the inliers' extent along the axis and ``length`` that extent. The axis
        sign follows :func:`asbuilt.fit._common.orient` (largest component positive).
        Residuals are orthogonal distances, positive outside. ``covariance`` (5 x 5) is over
        (tilt of the axis towards ``u``, tilt towards ``v`` (radians, about ``center``), centre
        offset along ``u``, along ``v`` (metres), radius (metres)) with
        ``u, v = orthonormal_basis(axis)``: ``sigma^2 (J^T W J)^-1``, ``W`` the inliers'
        weights (1 / variance relative to a square-on shot, see :func:`~asbuilt.fit._cylinder_model.incidence_weighted`;
        all 1 when the noise looks even) and ``sigma`` the square-on noise level (the sensor's,
        else the weighted residuals' RMS with the degrees of freedom corrected). ``stderr``:
        ``radius``; ``axis_deg`` (RMS axis angle error, the root of the two tilt variances);
        ``center`` (across-axis position, root of the two offset variances); ``length``
        (the length is the inliers' extent, short of the pipe's by the part of the step after
        each end's last shot that the pipe still fills: uniform over a step ``s`` that is a
        root-mean-square shortfall of ``s / sqrt(3)``, so ``sqrt((s1^2 + s2^2) / 3)`` with
        ``s1, s2`` the shots' step along the axis at each end
        (:func:`~asbuilt.fit._cylinder_finish.end_gaps`), plus the noise and the axis-tilt
        effect, in quadrature). Measured against the
        scatter of repeated simulated scans (range 2 mm, angle 0.01 degree): the radius error
        is overstated by up to 1.4x at 3 m and understated by up to 1.25x at 10 m on the
        benchmark's raster, overstated up to 3.4x on rasters reaching the silhouette (oblique
        shots' noise lies mostly along the beam); see docs/fitting.md. Diagnostics: ``arc_deg`` (angular coverage of the inliers about
        the axis), ``length_over_diameter``, ``starts`` (starts tried).

    Raises
    ------
    FitError
        Too few points, identical, collinear or coplanar points, or too many outliers.
    """
    pts = validate_points(points, "cylinder")
    view = None if viewpoint is None else np.asarray(viewpoint, dtype=np.float64)
    try:
        result = _fit_rescued(pts, sigma, tolerances, view)
    except FitError as error:
        if len(pts) > DENSE_POINTS:
            raise
        if not error.message.startswith(NO_MAJORITY):
            raise
        # A tee's header or a rack neighbour in the window: said, not guessed
        # (asbuilt.fit._cylinder_others).
        named = cylinders_named(_subset_fit(view), pts, view, sigma, tolerances)
        if not named:
            raise
        raise FitError(error.message + named, source=error.source, where=error.where) from None
    if len(pts) > DENSE_POINTS:
        return result
    stated = view
    if view is not None and _view_ignored(result):
        view = None
    # Beams inside the fit's silhouette that came back with nothing: not one pipe, refused
    # (asbuilt.fit._cylinder_open_space). Read from the stated station even when the fit
    # ignored it: the shots' directions from a wrong one fall on no raster.
    result = apart_across_open_space(_subset_fit(stated), pts, stated, sigma, tolerances, result)
    # Inliers on the pipe's far side from the station: a raster line past its silhouette that
    # three lines' exact circle took in (asbuilt.fit._cylinder_far_side).
    result = without_far_side(_subset_fit(view), result, pts, view, sigma, tolerances)
    return with_other_cylinder(_subset_fit(view), pts, view, sigma, tolerances, result)


def _subset_fit(view):
    """The fit of a subset of the shots for :mod:`asbuilt.fit._cylinder_others`: every rescue
    (a flange face across a branch's end, a wall behind it) but not that step itself; with a
    ``view``, one that keeps it."""
    if view is None:
        return _fit_rescued

    def fit(points, sigma, tolerances, viewpoint):
        result = _fit_rescued(points, sigma, tolerances, viewpoint)
        if _view_ignored(result):
            raise FitError(VIEW_IGNORED)
        return result

    return fit


def _fit_rescued(points, sigma, tolerances, viewpoint) -> FitResult:
    """:func:`fit_cylinder` before other cylinders among the shots are looked for.
    ``points`` (n, 3) metres are validated (:func:`validate_points`) and ``viewpoint`` (3,)
    metres, when given, an array: both come from :func:`fit_cylinder`."""
    background = False
    try:
        result, background = _fit_with_rescues(points, sigma, tolerances, viewpoint)
    except FitError as exc:
        result, error = None, exc
    first = None if result is None or _view_ignored(result) else result
    face_explained = False
    if len(points) <= DENSE_POINTS and _face_worth_a_look(
        first, points, sigma, tolerances, background
    ):
        # Shots on a flange face or the wall the pipe enters lie on one plane across its end.
        reference = result
        if result is None and viewpoint is not None:
            reference = _fit_or_none(points, sigma, tolerances)  # refused only for the view?
        fit = _fit_cylinder if viewpoint is None else _fit_seen_from
        across = fit_without_end_plane(fit, points, sigma, tolerances, viewpoint, first, reference)
        if across is not None:
            # A floor or wall around the pipe can still hold the fit past the end plane (a
            # metre-wide cylinder through floor shots): the background planes are looked for
            # when it is in doubt too. Its face's shots are explained when it beat a first fit
            # (a review's pipe through a floor, no first fit: the floor taken as a pipe whose
            # end plane was the pipe's own shots).
            face_explained = first is not None
            result = first = across
    if viewpoint is not None and len(points) <= DENSE_POINTS:
        # A wall behind the pipe, a floor under it or one it passes through: one plane with
        # the pipe's shots in front of it (asbuilt.fit._cylinder_planes).
        past = fit_past_planes(
            _fit_past_end, points, viewpoint, sigma, tolerances, first, face_explained
        )
        if past is not None:
            result = past
    if result is None:
        raise error
    return result


def _fit_or_none(points, sigma, tolerances) -> FitResult | None:
    """The fit of the shots alone (no viewpoint), or None when refused."""
    try:
        return _fit_cylinder(points, sigma, tolerances, None)
    except FitError:
        return None


def _fit_with_rescues(points, sigma, tolerances, viewpoint) -> tuple[FitResult, bool]:
    """:func:`fit_cylinder` before the surface across the pipe's end is looked for: the fit of
    the shots as they are, else with the background behind the pipe left out; and whether
    that fit's rejected shots were all shown to be background (:func:`_fit_and_proof`)."""
    result = error = None
    try:
        result, background = _fit_and_proof(points, sigma, tolerances, viewpoint)
    except FitError as exc:
        if viewpoint is None:
            if sigma is None or len(np.asarray(points)) > DENSE_POINTS:
                raise
            # Without the beams, the rows on a wall behind a pipe are one plane of shots.
            rescued = fit_without_background_plane(
                _fit_cylinder, validate_points(points, "cylinder"), float(sigma), tolerances
            )
            if rescued is None:
                raise
            return rescued, False
        error = exc
    if viewpoint is None or (result is not None and not _view_ignored(result)):
        return result, background
    # Refused, or the viewpoint blamed: whole raster lines on the background behind the pipe
    # can outnumber what the robust starts take; the shots in front of the range jumps alone
    # may still be the pipe.
    pts = validate_points(points, "cylinder")
    view = np.asarray(viewpoint, dtype=np.float64)
    segments = []
    if len(pts) <= DENSE_POINTS:
        segments = depth_segments(pts, view, segment_noise(sigma, tolerances))
        rescued = fit_without_background(_fit_seen_from, pts, view, sigma, tolerances, segments)
        if rescued is not None:
            return rescued, False
    if result is None:
        raise error
    if len(segments) > 1 and len(segments[0]) >= NEAR_SHARE * len(pts):
        # A pipe before a wall as seen from the viewpoint, and no fit of the pipe stood: a fit
        # ignoring the viewpoint takes the wall for pipe. A wrong station (the far side, another
        # frame) sees one surface, or fragments with no large one nearest (docs/fitting.md).
        raise FitError(VIEW_CONTRADICTED)
    return result, False


def _face_worth_a_look(first, points, sigma, tolerances, background: bool = False) -> bool:
    """Whether to look for a face across the pipe's end after the ``first`` fit (None when
    refused or when it ignored the viewpoint): many shots off it, or a face may have drawn it
    (:mod:`asbuilt.fit._cylinder_end_plane`), unless every shot it rejected was shown to be
    background (``background``, :func:`_fit_and_proof`)."""
    if worth_a_look(first, sigma, tolerances):
        return True
    # A face that drew the fit leaves the pipe's shots off it: in front of it (a wall the pipe
    # enters, refused as not background) or, for a short branch's near face, too many of them
    # (40-50%, over the 25% the test allows). Of 1,152 such benchmark fits the look was taken
    # on 8 and found no face on any (docs/fitting.md, "Thin branches").
    return not background and drawn_to_a_face(first, points, sigma, tolerances)


def _fit_past_end(points, sigma, tolerances, viewpoint) -> FitResult:
    """:func:`_fit_seen_from` of the shots left past background planes, itself checked for a
    face across the pipe's end (:mod:`asbuilt.fit._cylinder_end_plane`): with a tee's header
    left out as background, its branch's flange face is left in and can draw the fit across it."""
    result = _fit_seen_from(points, sigma, tolerances, viewpoint)
    if _face_worth_a_look(result, points, sigma, tolerances):
        across = fit_without_end_plane(
            _fit_seen_from, points, sigma, tolerances, viewpoint, result, result
        )
        if across is not None:
            return across
    return result


def _fit_seen_from(points, sigma, tolerances, viewpoint) -> FitResult:
    """:func:`_fit_cylinder` of a subset that must keep its viewpoint: the background rescue
    takes the viewpoint as right (its surfaces are cut by range jumps seen from it), so a
    subset's fit that ignored it is no rescue (FitError)."""
    result = _fit_cylinder(points, sigma, tolerances, viewpoint)
    if _view_ignored(result):
        raise FitError(VIEW_IGNORED)
    return result


#: Why a fit that would ignore the viewpoint is refused (:func:`fit_cylinder`).
VIEW_CONTRADICTED = (
    "No cylinder fits these shots as seen from the viewpoint (each would hide more than a"
    " third of them behind itself), yet from it the nearest surface holds much of the scan"
    " with the rest behind it (range jumps between neighbouring beams), as a pipe before a"
    " wall, and no fit of that surface stands: ignoring the viewpoint would take the"
    " background for pipe. Check the scan's sensor position or the object's station; if"
    " they are right, rescan with more of the raster on the pipe."
)


#: Why a fit that would ignore the viewpoint is refused when the shots were shot from it
#: (:func:`~asbuilt.fit._cylinder_checks.shot_from`).
ON_RASTER = (
    "yet their directions from it fall on a pan-tilt raster's columns and rows, so they were"
    " shot from there"
)


def _view_ignored(result: FitResult) -> bool:
    return VIEW_IGNORED in result.notes


def _fit_cylinder(points, sigma, tolerances, viewpoint) -> FitResult:
    """:func:`fit_cylinder` of the shots as they are."""
    return _fit_and_proof(points, sigma, tolerances, viewpoint)[0]


def _fit_and_proof(points, sigma, tolerances, viewpoint) -> tuple[FitResult, bool]:
    """:func:`_fit_cylinder`, and whether the fit rejected shots that its robust choice showed
    to be background (:func:`~asbuilt.fit._cylinder_quick.rejected_are_background`, on the
    quick path or in the full search)."""
    pts = validate_points(points, "cylinder")
    offset = pts.sum(axis=0) / len(pts)  # pts.mean(axis=0), without its overhead
    local = pts - offset
    everything = None
    if len(local) > DENSE_POINTS:
        # A dense cloud: the starts and the robust choice run on a random subsample (their
        # batched circles grow as starts x samples x points), and the chosen fit is then
        # settled on every point.
        rng = np.random.default_rng(len(local))
        everything, local = local, random_subset(local, DENSE_POINTS, rng)
    _, spread, directions = principal_axes(local)
    check_spread(spread, "cylinder", 3)
    normals, flatness = local_normals(local, tolerances.normal_neighbours)
    keep = keep_count(len(local), tolerances)
    # The quick path needs only the first normal axis; the full search, every distinct axis.
    normal = normal_axes(normals, flatness)
    view = None if viewpoint is None else np.asarray(viewpoint, dtype=np.float64) - offset
    if sigma is not None and everything is None and len(local) >= POLISH_BELOW:
        quick = _quick_fit(local, quick_axes(normal[0], directions), keep, sigma, view, tolerances)
        if quick is not None:
            robust, quick_starts, rejected = quick
            scene = Scene(pts, offset, local, None, view, sigma, tolerances)
            try:
                return finished(robust, scene, False, quick_starts, None), rejected
            except NeedsFullSearch:
                pass
            except FitError:
                # A quick fit that rejected shots and that its last checks (edge-on shots, shots
                # seen through the pipe) refuse: the full search decides.
                if not rejected:
                    raise
    starts = []
    rng = np.random.default_rng(len(local))
    axes = starts_of(normal, directions) + pair_starts(local, normals, keep, 3)
    line = line_axis(local, keep, rng)
    if line is not None:
        axes.append(line)
    starts, costs = circle_starts(local, axes, keep, rng)

    # The robust choice runs again with the polished starts added when the first one rejects
    # shots; what it computed for the same starts is reused (:func:`robust_geometric_fit`).
    refined: dict = {}

    def robust_from(starts, costs):
        return robust_among(local, starts, costs, sigma, tolerances, refined)

    def polished(starts, costs):
        order = np.argsort(costs)[:POLISHED_STARTS]
        better, better_costs = polish_axes(
            local, [starts[k] for k in order], [costs[k] for k in order], keep, rng
        )
        return starts[:1] + better + starts[1:], costs[:1] + better_costs + costs[1:]

    # The MSAC circles' fits, made once per kind of rescue (judged by the beams, or blind and
    # by the shots inside the pipe), when a rescue first needs them.
    msac: dict = {}

    def rescue(current, seen_from):
        blind = seen_from is None
        if blind not in msac:
            msac[blind] = msac_fits(local, axes, sigma, tolerances, keep, rng, inside=blind)
        cutoff = tolerances.outlier_cutoff_sigma * sigma
        chosen = better_fit(msac[blind], current, local, seen_from, cutoff)
        if chosen is not None or (
            current is not None and consistent(current, local, seen_from, cutoff)
        ):
            return chosen
        # The last resort, when no consistent fit stands and no MSAC circle gave one: the
        # half-keep robust line's circles (half_line_axes).
        if (blind, "half") not in msac:
            msac[blind, "half"] = msac_fits(
                local,
                half_line_axes(local),
                sigma,
                tolerances,
                keep,
                np.random.default_rng(len(local)),
                inside=blind,
            )
        return better_fit(msac[blind, "half"], current, local, seen_from, cutoff)

    if starts and len(local) < POLISH_BELOW:
        starts, costs = polished(starts, costs)
    try:
        robust = _robust_fit(local, starts, costs, robust_from, polished, tolerances)
    except FitError:
        # Too many outliers to the robust choice; with the beams to judge, the other starts
        # may still settle on the pipe, and without them the MSAC circles may.
        if sigma is None or not starts:
            raise
        if view is None:
            robust = rescue(None, None)
            if robust is None:
                raise
        else:
            robust = None
    blind, ignored_view = robust, False

    cutoff_sigma = tolerances.outlier_cutoff_sigma

    def reconsider(robust, excess):
        # The robust fit itself (settled: its concentration steps fit subsets) and the best
        # starts from other basins: one in the robust fit's basin (or an earlier seed's) would
        # settle where that one did.
        seeds = []
        known = [] if robust is None else [robust.state]
        extent = robust_extent(local)
        for k in np.argsort(costs):
            if len(seeds) == RECONSIDERED_STARTS:
                break
            if not any(same_basin(starts[k], other, extent) for other in [*known, *seeds]):
                seeds.append(starts[k])
        if robust is not None and view is not None and len(local) < POLISH_BELOW:
            # Sparse scans only, where a few raster columns can leave the radius open.
            seeds.extend(_radius_seeds(robust.state, view, (*known, *seeds), extent))
        options = {
            "kind": "cylinder",
            "sigma": sigma,
            "tolerances": tolerances,
            # Sparse scans get the thorough search (hidden or rejected good shots decide their
            # fits); on denser ones the plain settle finds the pipe (benchmark) in half the time.
            "thorough": len(local) < POLISH_BELOW,
        }
        try:
            chosen = reconsidered(robust, local, known + seeds, MODEL, excess, **options)
        except FitError:
            if excess is None:
                raise
            chosen = None
        if excess is not None:
            # The chosen fit (or, when no seed settled, the cheapest start) still hides shots
            # behind itself: the starts found without them get a say.
            if chosen is not None:
                state, inliers = chosen.state, chosen.inliers
                scale = sigma if sigma is not None else chosen.scale
            else:
                state, scale = starts[int(np.argmin(costs))], sigma
                inliers = np.abs(MODEL.residuals(state, local)) <= cutoff_sigma * scale
            unhidden = unhidden_starts(state, inliers, local, excess, axes, scale, tolerances)
            if unhidden:
                chosen = reconsidered(chosen, local, unhidden, MODEL, excess, **options)
        if chosen is None:
            raise FitError(
                "No cylinder explains most of these points; check that they are one cylinder."
            )
        return chosen

    # One fit's beam excess is asked several times (its score in reconsidered, then by
    # unhidden_starts, then its score again against the unhidden starts): kept per fit.
    excesses: dict = {}

    def beam_excess(states, x):
        key = (id(states[0]), id(x)) if len(states) == 1 else None
        if key in excesses:
            return excesses[key][1]
        found = cylinder_beam_excess(*stacked(states), x, view)
        if key is not None:
            excesses[key] = ((states[0], x), found)  # kept alive: their ids stay theirs
        return found

    if (
        sigma is not None
        and everything is None
        and len(local) >= POLISH_BELOW
        and robust is not None
        and not robust.inliers.all()
        and rejected_are_background(robust, local, sigma, view, tolerances)
    ):
        # The robust choice among every start rejected only background (as the quick path
        # judges it): the beams' second look and the MSAC rescue would settle on it again.
        try:
            fit = finished(
                robust,
                Scene(pts, offset, local, None, view, sigma, tolerances),
                False,
                starts,
                reconsider,
            )
            return fit, True
        except FitError:
            pass  # its last checks refuse it: the full search decides
    if (
        view is not None
        and starts
        and (robust is None or doubtful(robust, local, view, len(local), sigma, tolerances))
    ):
        try:
            robust = reconsider(robust, beam_excess)
        except FitError:
            # No seed settled on the pipe: the MSAC rescue below is the last chance.
            if sigma is None or robust is not None:
                raise
            rescued = rescue(None, view)
            if rescued is None:
                raise
            robust = rescued
        rescued = None
        # Asked once: when no rescue replaces the fit, the test below is of the same fit.
        hidden = robust is None or unseen(robust, local, view)
        if hidden and sigma is not None:
            rescued = rescue(robust, view)
        if rescued is not None:
            robust = rescued
        elif blind is not None and hidden:
            # Even the best fit hides a third of the shots behind itself: the shots were not
            # taken from this viewpoint (if one station could have seen the fit of the shots
            # alone; checked below).
            robust, ignored_view = blind, True
    if (
        sigma is not None
        and robust is not None
        and everything is None
        and (
            np.mean(~robust.inliers) >= RESCUE_REJECTED
            or (
                (view is None or ignored_view)
                and not admissible(robust, local, tolerances.outlier_cutoff_sigma * sigma)
            )
        )
    ):
        # A fifth of the shots rejected (near the background the trimmed cost can take), or,
        # without the beams to judge, shots inside the pipe: the circles chosen by MSAC get
        # their say (every shot decides).
        rescued = rescue(robust, None if ignored_view else view)
        if rescued is not None:
            robust = rescued
    if ignored_view:
        # The fit of the shots alone overrules the stated viewpoint only if it is a pipe one
        # station could have seen and rejects few shots; otherwise (a thin pipe's front shots
        # and the wall behind it; mixed returns strung between them taking a wide circle) the
        # viewpoint is not to blame.
        rejected = int(np.count_nonzero(~robust.inliers))
        if not one_station_could_see(robust, local):
            why = "could not have been seen from any one station either"
        elif rejected >= OVERRULE_REJECTED * len(local):
            why = f"rejects {rejected} of the {len(local)} shots, too many to overrule the station"
        elif shot_from(local, view):
            # Seen from the station the shots lie on a pan-tilt raster: they were shot from it.
            why = f"hides some behind itself from the station, {ON_RASTER}"
        else:
            why = None
        if why is not None:
            raise FitError(
                "No cylinder fits these shots as seen from the viewpoint (each would hide more"
                f" than a third of them behind itself), and the best fit of the shots alone {why}."
                " Check the scan's sensor position or the object's station (shots taken from"
                ' two stations belong in one object per station, each with its "station");'
                " if they are right, many shots are background, mixed returns or another"
                " surface beside the pipe (a wall it enters, a flange): give only the pipe's"
                " shots, or rescan with more shots on the pipe."
            )
    scene = Scene(pts, offset, local, everything, view, sigma, tolerances)
    return finished(robust, scene, ignored_view, starts, reconsider), False
