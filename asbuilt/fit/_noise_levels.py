"""The noise level a fit runs at: the sensor's range sigma, the residuals' own level when the
points scatter significantly wider (a rough surface, an optimistic sigma), and the fit of a scan
without a sigma, which prefers the fit at the prior noise when the shots it rejects are
background (a private helper of :mod:`asbuilt.fit`, numpy only)."""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.errors import FitError, located
from asbuilt.fit._common import diagonal_extent, quick_median
from asbuilt.fit._cuboid_inside import ShotsInside
from asbuilt.fit._cuboid_lone import OneLineFace
from asbuilt.fit._cuboid_sparse import AmbiguousFrame
from asbuilt.fit._cylinder_far_side import FarSideFit
from asbuilt.fit._cylinder_open_space import OpenSpaceFit
from asbuilt.fit._cylinder_planes import BACKGROUND_PLANE_SHOTS, BackgroundPlaneFit
from asbuilt.fit.result import FitResult
from asbuilt.tolerances import Tolerances

#: The residuals' own noise estimate must exceed the sensor's range sigma by this factor before
#: it replaces the sensor's: at 20 inliers the estimate's standard error is about 16% of sigma,
#: so 1.5 is three standard errors; below it an optimistic sigma costs a shot or two, not the fit.
WIDER_NOISE_RATIO = 1.5
#: ... and by at most this factor: points scattered wider than five times the sensor's noise
#: about the best primitive are not that primitive (a box labelled a cylinder), and the fit's
#: error stands.
WIDER_NOISE_LIMIT = 5.0


def _fit_with_noise(
    kind: str, function, points: np.ndarray, sigma, tolerances, options
) -> FitResult:
    """The fit with the sensor's ``sigma`` (metres), refitted with the residuals' noise level
    when the points scatter significantly wider than the sensor's noise.

    The inlier test is ``outlier_cutoff_sigma`` sensor sigmas, so a rough, corroded or
    insulated surface, or a range sigma copied from an optimistic data sheet, makes good shots
    look like outliers: a third of them can be rejected and the standard errors come out too
    small. The noise level is estimated from the likeliest inlier set of the fit's residuals
    (nested by size, Gaussian inliers and uniform outliers, as in
    :func:`asbuilt.fit._robust.best_inlier_set`); when it is above ``WIDER_NOISE_RATIO`` times
    the sensor's sigma, the object is refitted with it and a note says so. A fit that fails on
    too many outliers is tried once without the sensor's sigma and kept when its noise level is
    within ``WIDER_NOISE_LIMIT`` sensor sigmas, or within a typical range finder's noise
    (``WIDER_NOISE_RATIO`` times ``tolerances.prior_range_sigma``: the sensor's sigma is then
    what is wrong); otherwise its error stands, with the scatter the fit found.
    """
    if kind == "hull":
        return function(np.array(points), sigma=sigma, tolerances=tolerances, **options)
    if sigma is None:
        return _fit_without_sigma(function, points, tolerances, options)
    sigma = float(sigma)
    try:
        result = function(np.array(points), sigma=sigma, tolerances=tolerances, **options)
    except (AmbiguousFrame, BackgroundPlaneFit, FarSideFit, OneLineFace, ShotsInside):
        # Shots that fit frames far apart as well at the sensor's noise: a lower level found
        # without it would only make one frame look settled. A plane-like cylinder on a wall
        # or floor, a box face on one raster line, shots inside the box: the shots' scatter is
        # not what is wrong.
        raise
    except OpenSpaceFit as open_space:
        return _past_open_space(open_space, function, points, sigma, tolerances, options)
    except FitError as first:
        try:
            # With the prior-noise rescue: the fit of every shot at its own scale can be a
            # metre-wide cylinder through pipe and wall at 60 mm, over the limit below, where
            # the fit at the prior noise keeps the pipe (an optimistic 0.5 mm for a 2 mm finder).
            result = _fit_without_sigma(function, points, tolerances, options, sigma)
        except FitError:
            raise first from None
        # Within a typical range finder's noise the points are that kind and the sensor's
        # sigma is what is wrong (0.2 mm declared for a 2 mm finder: ten times): wider than
        # both limits, they are not that kind (a box labelled a cylinder), and the error
        # stands; where the sigma is finer than a typical finder's, it says what the shots
        # scatter by (auto's fit without the sigma may be of another kind: not said).
        prior = float(tolerances.prior_range_sigma)
        if not result.sigma <= max(WIDER_NOISE_LIMIT * sigma, WIDER_NOISE_RATIO * prior):
            if kind == "auto" or sigma >= prior:
                raise first from None
            first.message += (
                " (Fitted at its own noise level instead of the scan's range sigma,"
                f" {sigma * 1000:.3g} mm, the best {result.kind} leaves the shots scattered by"
                f" {result.sigma * 1000:.3g} mm, more"
                f" than a range finder's noise: these shots are not one {result.kind}, unless"
                " range_sigma is far too optimistic.)"
            )
            first.args = (located(first.source, first.where, first.message),)
            raise first from None
        if result.sigma > WIDER_NOISE_RATIO * sigma:
            return _noted_wider(result, result.sigma, sigma)
        return _noted_found(result, sigma)
    noise = _residual_noise(result, points, tolerances, _not_background(result, sigma, tolerances))
    if not WIDER_NOISE_RATIO * sigma < noise:
        return _rough_rival(kind, function, result, points, sigma, tolerances, options)
    try:
        wider = function(np.array(points), sigma=noise, tolerances=tolerances, **options)
    except FitError:
        if noise <= WIDER_NOISE_LIMIT * sigma:
            raise
        return result
    if _left_basin(result, wider):
        return result
    # Also beyond WIDER_NOISE_LIMIT: a fit that stands at the sensor's sigma while its likeliest
    # inliers scatter five times wider has rejected good shots beyond three sensor sigmas and
    # claims standard errors five times too small (the review's pipes declared 0.5 mm for a
    # 2 mm finder, fitted with their wall rows left out: 9 of 24 pipe shots rejected, radius
    # errors up to 15 standard errors).
    return _noted_wider(wider, noise, sigma)


def _past_open_space(
    error: OpenSpaceFit, function, points: np.ndarray, sigma: float, tolerances, options
) -> FitResult:
    """The fit refused for open space (``error.refused``, a cylinder at the sensor's
    ``sigma``) refitted at its inliers' noise level when they scatter wider, as any fit is
    (:func:`_fit_with_noise`), the refit checked again; else ``error`` raised.

    Not retried without the sigma: the beams that came back with nothing do not depend on
    it (the retry's wider band let a pipe's two raster columns beside a box column pass as a
    determined pipe). But the refused fit can be what the sensor's sigma made of a rough pipe:
    a pipe through a floor, its grazing column's beams missing, fitted first as a 1.5 m
    cylinder with the floor, whose refit at the 3.25 mm the shots scatter by is the pipe.
    """
    result = error.refused
    if result is None:
        raise error
    noise = _residual_noise(result, points, tolerances, _not_background(result, sigma, tolerances))
    if not WIDER_NOISE_RATIO * sigma < noise:
        raise error
    try:
        wider = function(np.array(points), sigma=noise, tolerances=tolerances, **options)
    except FitError:
        raise error from None
    if _left_basin(result, wider):
        raise error
    return _noted_wider(wider, noise, sigma)


#: Shots a fit at the sensor's sigma rejects whose median distance from it is at most this many
#: inlier thresholds (``outlier_cutoff_sigma`` sensor sigmas) away may be a rough surface's
#: scatter rather than background: background behind an object (a wall, the floor) lies tens
#: of thresholds off, while a surface scattering by ``s`` leaves its rejected shots a median
#: 1-2 ``s`` from a fit that kept them.
NEAR_REJECTION_RATIO = WIDER_NOISE_LIMIT
#: The kinds whose fit can settle in a rival basin with tight inliers: a free radius bends the
#: surface through a subset of a rough surface's shots. A plane cannot, and there the shots a
#: fit rejects near it are mixed returns at a plate's edges (between the plate and the wall
#: behind), which the wider fit took in: the accuracy benchmark's clean 0.5 m plates at 30
#: and 40 shots went from 1.06 to 1.11-1.13 times the bound.
RIVAL_KINDS = ("cylinder", "sphere")


def _rough_rival(kind, function, result, points, sigma, tolerances, options) -> FitResult:
    """``result`` (fitted at the sensor's ``sigma``, metres), or, for the ``RIVAL_KINDS``, the
    fit at a wider noise level when that explains ``points`` (n, 3) metres more likely.

    A rough surface with an optimistic sigma can put a fit in a rival basin: a radius 16% too
    large that holds 25 of 31 shots to 1.7 mm and rejects the rest a few sigmas off (a black-box
    review's NPS 6 pipe with 6 mm scatter declared 2 mm), where the residuals' own noise
    (:func:`_residual_noise`) cannot see it, since its inliers are tight. When the rejected
    shots lie near (``NEAR_REJECTION_RATIO``), the object is fitted again at the noise level
    that keeps them, and the two fits are compared as mixtures of Gaussian inliers at their own
    noise and uniform outliers with the cost of saying which shots are outliers
    (:func:`asbuilt.fit._mixture.mixture_score` plus :func:`~asbuilt.fit._mixture.mixing_cost`,
    the same primitive on both sides); the likelier one is kept, the wider one with a note.
    """
    if kind not in RIVAL_KINDS:
        return result
    rejected = np.abs(np.asarray(result.residuals, dtype=np.float64)[~result.inliers])
    threshold = float(tolerances.outlier_cutoff_sigma) * sigma
    if rejected.size < 2 or not quick_median(rejected) <= NEAR_REJECTION_RATIO * threshold:
        return result
    residuals = np.asarray(result.residuals, dtype=np.float64)
    near = np.abs(residuals) <= NEAR_REJECTION_RATIO * threshold
    used = 0 if result.covariance is None else len(result.covariance)
    dof = int(np.count_nonzero(near)) - used
    if dof <= 0:
        return result
    level = float(np.sqrt(residuals[near] @ residuals[near] / dof))
    if not WIDER_NOISE_RATIO * sigma < level <= WIDER_NOISE_LIMIT * sigma:
        return result
    try:
        wider = function(np.array(points), sigma=level, tolerances=tolerances, **options)
    except FitError:
        return result
    if wider.kind != result.kind:
        return result
    if not _mixture_cost(wider, points, tolerances) < _mixture_cost(result, points, tolerances):
        return result
    noise = max(_residual_noise(wider, points, tolerances), level)
    return _noted_wider(wider, noise, sigma)


def _left_basin(first: FitResult, wider: FitResult) -> bool:
    """Whether ``wider``, the fit of the same points at a wider noise level than ``first``,
    rejects more than one of ``first``'s inliers: a wider threshold keeps every shot a fit had
    unless the search went to another basin (a 0.88 m cylinder through part of a 0.6 m pipe's
    shots and mixed returns, where the pipe had been found at the sensor's sigma with its wall
    rows left out); then ``first`` stands."""
    return int(np.count_nonzero(first.inliers & ~wider.inliers)) > 1


#: Without a sensor sigma, rejected shots whose median distance from the fit made with the
#: assumed noise is at least this many times the noise of the fit made without it are taken as
#: background (a wall behind the pipe, 1.4 m from it: 150 times), not as the scatter of a rough
#: surface (shots beyond three assumed sigmas of a surface scattering by s lie a median 1-2 s
#: from it).
BACKGROUND_RATIO = 5.0


def _fit_without_sigma(
    function, points: np.ndarray, tolerances, options, sensor_sigma: float | None = None
) -> FitResult:
    """The fit of a scan that gives no sensor sigma, with its noise level from its residuals;
    when that noise is over ``WIDER_NOISE_RATIO`` times ``tolerances.prior_range_sigma`` (or the
    fit is refused), the fit made with the prior noise as the sensor's is preferred if the shots
    it rejects are background (``BACKGROUND_RATIO``), then settled with its inliers' own noise.

    Without a sigma every threshold scales with the residuals, so shots of a wall behind a pipe
    (a window run past the pipe's end: 15 of 36 shots) make the residuals wide enough to hold
    them, and a cylinder of 0.8 m through pipe and wall shots "fits" all of them at 9 mm (an
    independent ray caster's plant, 16 of 54 pipe fits). With the prior noise the robust search
    rejects them, and the 2 mm noise the pipe's shots then show is the residuals' own.
    """
    prior = float(tolerances.prior_range_sigma)
    refused = None
    try:
        result = function(np.array(points), sigma=None, tolerances=tolerances, **options)
    except FitError as exc:
        result, refused = None, exc
    if result is not None and not result.sigma > WIDER_NOISE_RATIO * prior:
        return result
    try:
        assumed = function(np.array(points), sigma=prior, tolerances=tolerances, **options)
    except FitError:
        assumed = None
    wide = prior if result is None else float(result.sigma)
    rejected = None if assumed is None else np.abs(assumed.residuals[~assumed.inliers])
    distance = float(np.median(rejected)) if rejected is not None and rejected.size else 0.0
    if not (
        distance >= BACKGROUND_RATIO * wide
        or _likelier_background(assumed, result, points, tolerances)
    ):
        if result is None:
            raise refused
        if sensor_sigma is None and result.sigma > FAR_WIDER_RATIO * prior:
            # Not presented as a fit like any other: a 2 m "pipe" through a pipe's shots and the
            # wall rows behind it scatters by 40-60 mm.
            note = (
                f"The shots scatter by {result.sigma * 1000:.3g} mm about the {result.kind}, "
                f"{result.sigma / prior:.0f} times the {prior * 1000:g} mm noise of a typical "
                "range finder, and no fit at that noise explains most of them: a very rough "
                "surface, or shots of more than one surface (background behind the object). "
                "Give sensor.range_sigma and the station, or check the shots."
            )
            result = dataclasses.replace(result, notes=(*result.notes, note))
        return result
    noise = max(_residual_noise(assumed, points, tolerances), float(tolerances.sigma_floor))
    try:
        settled = function(np.array(points), sigma=noise, tolerances=tolerances, **options)
    except FitError:
        settled = assumed
    if _left_basin(assumed, settled):
        settled = assumed
    note = (
        f"{int(np.count_nonzero(~settled.inliers))} shot(s) lie far from the {settled.kind} the "
        f"others fit to {noise * 1000:.3g} mm (a median {distance:.3g} m away) and "
        "were taken as background"
        + (
            f"; {'at its own scale' if sensor_sigma else 'without a sensor sigma'} a "
            f"{result.kind} through all the shots would have fitted at {wide * 1000:.3g} mm"
            if result is not None
            else ""
        )
        + (
            # The sensor's sigma was given but refused every fit (the caller says why).
            "."
            if sensor_sigma
            else ". Give sensor.range_sigma (and the station) so that the fit need not guess."
        )
    )
    return dataclasses.replace(
        settled, sigma=noise, sigma_source="residuals", notes=(*settled.notes, note)
    )


#: A fit without a sensor sigma whose noise level is over this many times the prior range sigma
#: is no rough surface's (measured roughness of pipes and walls: 5-10 mm); the fit at the prior
#: noise may replace it on likelihood alone (:func:`_likelier_background`).
FAR_WIDER_RATIO = 10.0


def _likelier_background(assumed, result, points: np.ndarray, tolerances: Tolerances) -> bool:
    """Whether the fit at the prior noise (``assumed``, its rejected shots taken as background)
    explains ``points`` (n, 3) metres more likely than the fit of every shot at its own scale
    (``result``), when that scale is over ``FAR_WIDER_RATIO`` prior sigmas.

    Gaussian inliers at each fit's own noise and uniform outliers over the points' extent, with
    the description length of which shots are outliers (:func:`asbuilt.fit._mixture`; the
    same primitive, so the same parameter count). The median distance test
    (``BACKGROUND_RATIO``) misses background near a wide fit: a 2.3 m sphere through a 1.3 m
    sphere and the floor row below it scatters by 226 mm, and the floor shots lie a median
    0.75 m from the 1.3 m sphere that fits the rest to 2 mm.
    """
    if assumed is None or result is None:
        return False
    if not float(result.sigma) > FAR_WIDER_RATIO * float(tolerances.prior_range_sigma):
        return False
    return _mixture_cost(assumed, points, tolerances) < _mixture_cost(result, points, tolerances)


def _mixture_cost(fit: FitResult, points: np.ndarray, tolerances: Tolerances) -> float:
    """Minus twice the log-likelihood of ``fit``'s residuals over ``points`` (n, 3) metres as
    Gaussian inliers at their own noise and uniform outliers over the points' extent, with the
    description length of which shots are outliers (:func:`asbuilt.fit._mixture.mixture_score`
    plus :func:`~asbuilt.fit._mixture.mixing_cost`). Lower is likelier; fits of the same
    primitive compare without a parameter count."""
    from asbuilt.fit._mixture import mixing_cost, mixture_score

    extent = diagonal_extent(points)
    kept = int(np.count_nonzero(fit.inliers))
    score = mixture_score(fit.residuals, fit.inliers, extent, float(tolerances.sigma_floor))
    return score + mixing_cost([kept, len(fit.inliers) - kept])


def _not_background(result: FitResult, sigma: float, tolerances: Tolerances):
    """The shots (n,) bool whose scatter can tell a rough surface, or None for all of them.

    A cylinder fit that left out a wall or floor as background
    (:mod:`asbuilt.fit._cylinder_planes`) has most shots on it, decimetres off the pipe: its
    likeliest inlier set took them in and put the noise at 0.2-1.9 m (the review's wide
    windows), whose refit lost the pipe; a cuboid fit past a floor or ceiling
    (:mod:`asbuilt.fit._cuboid_planes`) likewise, at 1.0-2.6 m, whose refit returned the floor
    as the box. Only the shots within ``NEAR_REJECTION_RATIO`` inlier thresholds of the fit
    are then weighed: a rough surface's scatter lies there.
    """
    if not result.diagnostics.get(BACKGROUND_PLANE_SHOTS):
        return None
    threshold = float(tolerances.outlier_cutoff_sigma) * sigma
    return (
        np.abs(np.asarray(result.residuals, dtype=np.float64)) <= NEAR_REJECTION_RATIO * threshold
    )


def _residual_noise(
    result: FitResult, points: np.ndarray, tolerances: Tolerances, among=None
) -> float:
    """The noise level (metres) of a fit's likeliest inlier set: RMS with the degrees of
    freedom of the fit's covariance taken off, and with fewer than
    ``tolerances.min_noise_dof`` of them the missing ones counted as residuals of the prior
    noise (:func:`asbuilt.fit._common.noise_level`'s rule: the likeliest set of a few shots
    is the few that scatter least, 0.78 mm from 2 mm shots on an independent review's drum,
    whose refit at that level then rejected 5 of its 14 good shots); over the shots ``among``
    (n,) bool only when given."""
    from asbuilt.fit._robust import best_inlier_set

    residuals = np.asarray(result.residuals, dtype=np.float64)
    if among is not None:
        residuals, points = residuals[among], points[among]
        result = dataclasses.replace(result, residuals=residuals, inliers=result.inliers[among])
    if result.inliers.all():
        chosen = result.inliers  # the likeliest set is at least the inliers: here every point
    else:
        extent = diagonal_extent(points)
        floor = float(tolerances.sigma_floor)
        chosen = best_inlier_set(residuals, result.inliers, extent, floor)
    used = 0 if result.covariance is None else len(result.covariance)
    dof = max(int(np.count_nonzero(chosen)) - used, 0)
    kept = residuals[chosen]
    missing = max(int(tolerances.min_noise_dof) - dof, 0)
    squares = float(kept @ kept) + missing * float(tolerances.prior_range_sigma) ** 2
    return float(np.sqrt(squares / (dof + missing))) if dof + missing > 0 else 0.0


def _noted_found(result: FitResult, sigma: float) -> FitResult:
    """``result`` (fitted without the sensor's sigma, its own noise level within
    ``WIDER_NOISE_RATIO`` of it) where the fit with the sensor's sigma failed, with a note."""
    note = (
        f"With the sensor's range sigma ({sigma * 1000:.3g} mm) the robust search found no "
        f"{result.kind} holding most points; the search with the residuals' own noise level did "
        f"({result.sigma * 1000:.3g} mm, which agrees with the sensor's), and its fit is kept."
    )
    return dataclasses.replace(result, notes=(*result.notes, note))


def _noted_wider(result: FitResult, noise: float, sigma: float) -> FitResult:
    """``result`` (fitted with the residuals' noise level) marked as such, with a note."""
    note = (
        f"The points scatter by {noise * 1000:.3g} mm about the {result.kind}, more than the "
        f"sensor's range sigma ({sigma * 1000:.3g} mm): a rough or coated surface, or an "
        f"optimistic sigma. The fit used {noise * 1000:.3g} mm for its outlier test and "
        "standard errors."
    )
    return dataclasses.replace(
        result, sigma=noise, sigma_source="residuals", notes=(*result.notes, note)
    )
