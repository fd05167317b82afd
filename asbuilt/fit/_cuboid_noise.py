"""Noise level search of the cuboid fit when the sensor's range sigma is unknown.

Private helper of :func:`asbuilt.fit.cuboid.fit_cuboid`: the joint fit is tried at noise levels
a factor apart from the estimated one and the level whose fit explains the points best (Torr's
inlier/outlier mixture plus the fit's description length) is kept
(:func:`_likeliest_noise`). Lengths in metres.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import diagonal_extent
from asbuilt.fit._joint import complexity
from asbuilt.fit._mixture import mixture_score
from asbuilt.tolerances import Tolerances

#: Without the sensor's sigma, the joint fit is also tried at noise levels this many times
#: apart from the estimated one (:func:`_likeliest_noise`) ...
NOISE_LADDER_STEP = 3.0
#: ... with at most this many fits in all ...
NOISE_LADDER_LEVELS = 6
#: ... and never above this level (metres): no range finder worth scanning with is noisier.
NOISE_LADDER_CEILING = 0.03
#: Levels in a row that score nothing (fail, implausible, too many outliers) after which the
#: search stops going that way while nothing has scored yet.
NOISE_LADDER_MISSES = 2
#: Relative score difference within which two levels tie: two levels that settle on the same
#: fit score the same up to rounding. A tie walks on to the next level without counting as a
#: gain or a loss: a rounding "gain" ended the search before the other direction was tried,
#: and a rounding "loss" ended it on a plateau (a clean box's fit changed when its points were
#: translated, and rejected up to a quarter of its shots).
_TIE = 1e-9


def _likeliest_noise(
    attempt, estimate: float, x: np.ndarray, tolerances: Tolerances, plausible, outliers=None
):
    """The noise level, and its fit, that explain the points best when the sensor's is unknown.

    The estimate (:func:`asbuilt.fit._faces.noise_scale`) comes from planes of neighbouring
    shots. On a sparse raster across narrow faces most neighbourhoods straddle an edge and the
    estimate can come out ten times the noise: a consensus band that wide takes both faces of a
    0.2 m column for one plane (residuals of centimetres) or finds no face at all. Where a
    raster line is the only plane found, it can come out at the sigma floor, and a band that
    narrow rejects half the shots. So the level is searched: from the estimate down by factors
    of ``NOISE_LADDER_STEP`` while the likelihood rises, and, when the estimate's fit failed or
    rejected shots and going down did not help, up likewise (at most ``NOISE_LADDER_LEVELS``
    fits, between the sigma floor and ``NOISE_LADDER_CEILING``). The likelihood: Gaussian
    inliers with their own maximum-likelihood sigma and uniform outliers over the points' extent
    (Torr's mixture, :func:`asbuilt.fit._mixture.mixture_score`) plus the fit's
    :func:`~asbuilt.fit._joint.complexity`: the description length of which face (or the
    outliers) each shot belongs to, and ``ln n`` per fitted parameter (rotation and one offset
    per face: the Bayesian information criterion, Schwarz 1978). A band too narrow
    for the noise rejects good shots, or splits one noisy face into parallel slices that each
    fit their shots closer than the noise; both cost more than they save. A fit that fails, is
    implausible (``plausible``: e.g. two opposite faces without a viewpoint) or rejects more
    than ``max_outlier_fraction`` of the points scores nothing, and ``NOISE_LADDER_MISSES``
    such levels in a row end the search that way (narrower bands end on faces of three shots
    fitted exactly). If no level scores, the fit nearest the estimate stands, else its error.

    Parameters
    ----------
    attempt : callable
        ``attempt(noise) -> best_fit tuple`` (:func:`asbuilt.fit._joint.best_fit`).
    estimate : float, metres
    x : ndarray, shape (n, 3), metres
    tolerances : Tolerances
    plausible : callable
        ``plausible(model) -> bool`` (:func:`asbuilt.fit._cuboid_grazing.plausible`); an implausible
        fit scores nothing.
    outliers : callable, optional
        ``outliers(fitted, noise) -> int``, the rejected shots that count against the outlier
        limit (:func:`asbuilt.fit._joint.counted_outliers`); default every rejected shot.

    Returns
    -------
    noise : float, metres
    fitted : tuple
        ``attempt(noise)``.
    """
    floor = float(tolerances.sigma_floor)
    n = x.shape[0]
    extent = diagonal_extent(x)
    tried: dict[float, tuple] = {}  # level -> (score, fitted or the FitError)

    def scored(level: float) -> float:
        try:
            fitted = attempt(level)
        except FitError as exc:
            tried[level] = (math.inf, exc)
            return math.inf
        model, _, residual, inliers = fitted[:4]
        score = math.inf
        rejected = (
            n - int(np.count_nonzero(inliers)) if outliers is None else outliers(fitted, level)
        )
        if plausible(model) and rejected <= tolerances.max_outlier_fraction * n:
            score = mixture_score(residual, inliers, extent, floor) + complexity(fitted)
        tried[level] = (score, fitted)
        return score

    start = min(max(estimate, floor), NOISE_LADDER_CEILING)
    best, best_score = start, scored(start)
    first = tried[start][1]
    full = not isinstance(first, FitError) and bool(first[3].all())
    for factor in (1.0 / NOISE_LADDER_STEP, NOISE_LADDER_STEP):
        if factor > 1.0 and full:
            break  # the estimate's band kept every shot: a wider one cannot do better
        level, moved, misses = best * factor, False, 0
        if factor < 1.0 and best > floor:
            level = max(level, floor)  # the floor itself is a level
        while len(tried) < NOISE_LADDER_LEVELS and floor <= level <= NOISE_LADDER_CEILING:
            score = scored(level)
            margin = _TIE * max(1.0, abs(best_score)) if math.isfinite(best_score) else 0.0
            if score < best_score - margin:
                best, best_score, moved, misses = level, score, True, 0
            elif math.isfinite(best_score) and score > best_score + margin:
                break  # the likelihood fell: farther levels are worse still
            elif math.isfinite(best_score):
                pass  # a tie (the same fit): walk on, without calling it a gain
            else:
                misses += 1
                if misses == NOISE_LADDER_MISSES:
                    # Narrower and narrower bands that still explain nothing end on a few
                    # shots per face fitted exactly, far below the noise: stop.
                    break
            if factor < 1.0:
                if level == floor:
                    break
                level = max(level * factor, floor)
            else:
                level *= factor
        if moved:
            break
    if math.isfinite(best_score):
        return best, tried[best][1]
    # No level scored: the fit nearest the estimate (an implausible one, as the segmentation
    # would return with a known sigma), else the estimate's error.
    for level in sorted(tried, key=lambda value: abs(math.log(value / start))):
        if not isinstance(tried[level][1], FitError):
            return level, tried[level][1]
    raise first
