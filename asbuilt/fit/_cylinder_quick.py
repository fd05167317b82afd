"""The cylinder fit's quick path: the first axis starts alone, when what they give needs no
second look.

Scans of at least ``POLISH_BELOW`` shots with a known sigma are mostly either clean or carry a
few edge outliers: shots that grazed the pipe and came back from the wall behind it, or mixed
returns between the two. The circles across the normals' axis and the points' longest principal
axis (:func:`~asbuilt.fit._cylinder_starts.quick_axes`) then settle on the pipe, and
the full search (two-point and line starts, the robust choice among all of them, the beams'
second look and the MSAC rescue; :func:`asbuilt.fit.cylinder.fit_cylinder`) settles on the same
minimum at several times the cost. The quick fit stands only when the scan itself says so
(:func:`quick_fit`); anything else takes the full search, exactly as without this shortcut.
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._circles import circle_starts
from asbuilt.fit._common import FreshGenerator, orthonormal_basis, within_noise
from asbuilt.fit._cylinder_checks import (
    UNSEEN_FRACTION,
    admissible,
    doubtful,
    doubtful_blind,
)
from asbuilt.fit._cylinder_model import (
    MODEL,
    ONE_SIDED,
    angles_about,
    drop_far_side,
    mean_direction,
)
from asbuilt.fit._cylinder_starts import line_axis, trust_order
from asbuilt.fit._robust import RobustFit, keep_count, robust_geometric_fit
from asbuilt.fit._vectors import cross3
from asbuilt.fit._visibility import excess_and_beyond
from asbuilt.tolerances import Tolerances

__all__ = ["QUICK_CHI2_TAIL", "quick_fit", "rejected_are_background", "robust_among"]


#: Upper tail probability of the chi-square test a quick fit's inliers must pass: a fit in a
#: wrong basin that still keeps its shots within the inlier threshold fits them worse than the
#: noise allows.
QUICK_CHI2_TAIL = 1e-3

#: A quick fit that rejected shots stands only if each lies more than this many inlier cutoffs
#: off it. A shot nearer than that may be a good one a nearby basin keeps: letting them through
#: changed 4 of 600 benchmark fits by up to 4.7 mm against the full search, none at twice the
#: cutoff (and :func:`asbuilt.fit._cylinder_finish.readmitted` leaves such fits alone).
CLEAR_OF_CUTOFFS = 2.0


def robust_among(local, starts, costs, sigma, tolerances, memo=None) -> RobustFit:
    """The robust geometric fit among circle starts (:func:`trust_order` first); ``memo`` as
    in :func:`~asbuilt.fit._robust.robust_geometric_fit`."""
    starts, costs, trusted = trust_order(starts, costs)
    return robust_geometric_fit(
        local,
        starts,
        MODEL,
        kind="cylinder",
        sigma=sigma,
        tolerances=tolerances,
        start_costs=costs,
        always_refine=trusted,
        memo=memo,
    )


def quick_fit(local, axes, keep, sigma, view, tolerances: Tolerances):
    """The robust fit from the circles across ``axes`` alone
    (:func:`~asbuilt.fit._cylinder_starts.quick_axes`), when it needs no second look; else
    None.

    A fit that keeps every shot stands when no shot lay farther from the cheapest start than
    its radius, its residuals pass a chi-square test at ``sigma`` (tail ``QUICK_CHI2_TAIL``),
    and nothing would reconsider it: with a viewpoint, no beam runs through the fitted pipe
    (:func:`~asbuilt.fit._cylinder_checks.doubtful`); without one, no shot lies inside the pipe
    (:func:`~asbuilt.fit._cylinder_checks.admissible`) nor on its far side
    (:func:`~asbuilt.fit._cylinder_model.drop_far_side`).

    A fit that rejected shots stands when they can only be background
    (:func:`rejected_are_background`).

    Parameters
    ----------
    local : ndarray, shape (n, 3), metres (centred)
    axes : list of ndarray, shape (3,)
        The candidate axes (:func:`~asbuilt.fit._cylinder_starts.quick_axes`).
    keep : int
    sigma : float, metres
    view : ndarray, shape (3,), metres (in ``local``'s frame), or None
    tolerances : Tolerances

    Returns
    -------
    (RobustFit, list of starts, bool) or None
        The fit, the starts it came from, and whether it rejected shots (the caller then still
        falls back on the full search if the fit's last checks refuse it).
    """
    # Fresh generators seeded with the shot count (FreshGenerator: the same draws).
    starts, costs = circle_starts(local, axes, keep, FreshGenerator(len(local)))
    if not starts:
        return None
    best = starts[int(np.argmin(costs))]
    # The first starts' refinements, kept for the second try below (the same candidates).
    refined: dict = {}
    try:
        robust = robust_among(local, starts, costs, sigma, tolerances, refined)
    except FitError:
        # Edge outliers spoiled the normals and principal axes, so no start settled on the
        # pipe (142 of the benchmark's 750 40-point scans with 20% edge outliers, 83 of them
        # with no shot a radius off the cheapest circle): the robust line through the shots
        # (the full search's, from the same random draws) finds the axis of 138 of the 142.
        # Of the 120 fits this makes quick (with and without the viewpoint), 119 are the full
        # search's to a micrometre; one keeps a shot the full search rejects, 0.2 mm apart.
        line = line_axis(local, keep, FreshGenerator(len(local)))
        if line is None:
            return None
        more, more_costs = circle_starts(local, [line], keep, FreshGenerator(len(local)))
        starts, costs = starts + more, costs + more_costs
        try:
            robust = robust_among(local, starts, costs, sigma, tolerances, refined)
        except FitError:
            return None
    if not robust.inliers.all():
        if rejected_are_background(robust, local, sigma, view, tolerances):
            return robust, starts, True
        return None
    # A shot farther from the cheapest circle than its radius is background (a wall behind the
    # pipe). On the benchmark's clean 40-point scans the farthest shot is at most 0.7 radii
    # away; with 20% edge outliers, a median 15. (Asked only of a fit that kept every shot.)
    if float(np.abs(MODEL.residuals(best, local)).max()) > best[2]:
        return None  # kept by a basin other than the cheapest circle's: the full search decides
    if not within_noise(robust.residuals, sigma, MODEL.n_params, QUICK_CHI2_TAIL):
        return None
    if view is not None:
        if doubtful(robust, local, view, len(local), sigma, tolerances):
            return None
    elif not admissible(robust, local, tolerances.outlier_cutoff_sigma * sigma):
        return None
    elif not drop_far_side(robust, local, tolerances).inliers.all():
        return None
    return robust, starts, False


def rejected_are_background(
    robust: RobustFit, local: np.ndarray, sigma: float, view, tolerances: Tolerances
) -> bool:
    """Whether a quick fit that rejected shots may stand: its inliers are a pipe seen as the
    noise allows and every rejected shot lies where only background can.

    - The rejected are within the trimmed cost's design contamination (``n - keep_count``),
      and each lies over ``CLEAR_OF_CUTOFFS`` inlier cutoffs off the fit.
    - The inliers pass the chi-square test at ``sigma``, and the pipe is no plane of
      kilometres' radius (:func:`~asbuilt.fit._cylinder_checks.doubtful_blind`).
    - With the viewpoint: no inlier's beam ran through the pipe by more than the cutoff, the
      viewpoint is not one the inliers were mostly hidden from (as
      :func:`~asbuilt.fit._cylinder_checks.unseen`), and every rejected shot lies beyond the
      first surface of the pipe its beam met
      (:func:`~asbuilt.fit._visibility.beyond_first_surface`; a beam that passed the end of
      the pipe, of its inliers' length, met none: a column's floor shots in front of its
      foot, or its wall rows above its top, are background): a shot that grazed the pipe
      and came back from the wall, or a mixed return between them, lies beyond it; a shot in
      front of the pipe, off it, is another surface's (a wider pipe sharing this one's near
      side showed its fourth raster column 3-7 cm in front of the thinner fit's silhouette). No kept shot is a mixed return (:func:`_mixed_return_kept`):
      one kept within the cutoff inside the pipe thins the fit by millimetres, where the full
      search's polished starts reject it.
    - Without it: no shot lies inside the pipe
      (:func:`~asbuilt.fit._cylinder_checks.admissible`), the inliers face one side (mean
      resultant over :data:`~asbuilt.fit._cylinder_model.ONE_SIDED`), no rejected shot lies on
      that side of the axis by more than the cutoff (beams from a station some metres off run
      nearly parallel across a pipe, so what lies in front of the axis along them was met
      before the pipe's silhouette), and no kept shot is a mixed return along beams taken
      parallel to that side (which misses one at the very silhouette: docs/fitting.md).
    """
    rejected = ~robust.inliers
    n = rejected.size
    if np.count_nonzero(rejected) > n - keep_count(n, tolerances):
        return False
    cutoff = tolerances.outlier_cutoff_sigma * sigma
    if (np.abs(robust.residuals[rejected]) <= CLEAR_OF_CUTOFFS * cutoff).any():
        return False
    if not within_noise(robust.residuals[robust.inliers], sigma, MODEL.n_params, QUICK_CHI2_TAIL):
        return False
    if doubtful_blind(robust, local):
        return False
    axis, center, radius = robust.state
    if view is not None:
        # The pipe as fitted, of its inliers' length (to the cutoff): a rejected shot whose beam
        # passed its end (a column's wall rows above its top) met no pipe, so it is background
        # wherever it lies; against the infinite cylinder a floor shot in front of a column's
        # foot lay "in front of the pipe".
        along = (local[robust.inliers] - center) @ axis
        span = (float(along.min()) - cutoff, float(along.max()) + cutoff)
        excess, beyond = excess_and_beyond(axis, center, radius, local, view, span)
        excess = excess[robust.inliers]
        unseen = np.count_nonzero(excess > 0.1 * radius) / max(excess.size, 1)
        if (excess > cutoff).any() or unseen > UNSEEN_FRACTION:
            return False
        # Rejected shots lie beyond the pipe's first surface; kept ones on it, up to the range
        # noise along their beams.
        if (beyond[rejected] < -cutoff).any():
            return False
        return not _mixed_return_kept(beyond[~rejected], robust.residuals[~rejected], sigma, cutoff)
    if not admissible(robust, local, cutoff):
        return False
    mean = mean_direction(angles_about(axis, center, local[robust.inliers]))
    resultant = float(np.hypot(*mean))
    if resultant <= ONE_SIDED:
        return False
    u, v = orthonormal_basis(axis)
    facing = (mean[0] * u + mean[1] * v) / resultant
    lateral = cross3(axis, facing)
    toward = (local - center) @ facing  # (n,) metres towards the station, across the axis
    if (toward[rejected] > cutoff).any():
        return False
    # Kept shots lie on the pipe's first surface along beams taken parallel to ``facing``, up
    # to the noise: a mixed return kept within the threshold inside the pipe near its
    # silhouette lies centimetres beyond it. Beams from a station some metres off are not
    # parallel, though: at the very silhouette a mixed return 6 cm along its beam can lie only
    # 5 mm beyond the parallel beam's surface, and passes (a tighter limit refuses nearly every
    # scan: good shots round the parallel silhouette lie beyond it too). The viewpoint's own
    # beams catch it.
    across = (local[~rejected] - center) @ lateral
    surface = np.sqrt(np.maximum(radius * radius - across * across, 0.0))
    beyond = surface - toward[~rejected]
    return not _mixed_return_kept(beyond, robust.residuals[~rejected], sigma, cutoff)


def _mixed_return_kept(beyond: np.ndarray, residuals: np.ndarray, sigma: float, limit: float):
    """Whether a kept shot looks like a mixed return: more than ``limit`` metres beyond the
    pipe's first surface along its beam (``beyond``, (m,) metres) and inside the pipe by more
    than ``sigma`` (``residuals`` (m,) metres, negative inside)."""
    return bool(((beyond > limit) & (residuals < -sigma)).any())
