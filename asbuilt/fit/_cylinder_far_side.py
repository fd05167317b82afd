"""Shots on a cylinder fit's far side as seen from the station: a raster line past the pipe.

Private helper of :mod:`asbuilt.fit.cylinder`. A vertical tank shot by three raster columns
shows three lines in cross-section, and a circle fits any three exactly. When the operator's
window reaches past the tank's silhouette, one column lands on the wall behind it; the circle
through the tank's two columns and that wall column fits every shot to the noise, with a
standard error of a millimetre, and is 1.5-2 times the tank's radius (black-box review: about
1 in 40 tanks scanned by three columns before a wall, radius x1.6). The wall column lies on
that circle's far side: from the station its beams would have crossed the pipe before reaching
it. The residuals cannot show this (three lines, no redundancy); the beams do.

The checks inside the fit drop an inlier whose beam ran through the middle half of the pipe
(:func:`asbuilt.fit._cylinder_checks.seen_through`, within ``THROUGH_FRACTION`` of the radius
of the axis), a test kept narrow on purpose: inside the search a fit on its way to the pipe can
hide a shot or two, and dropping them there changes which rescue settles. The finished fit is
judged here by the whole far half: an inlier whose beam passed within ``FAR_FRACTION`` of the
radius of the axis (a chord of at least 0.87 radii through the pipe) and that lies beyond the
chord's middle by more than the inlier cutoff was not seen by that station, whatever noise or
mixed return it carries (neither moves a shot half a chord along its beam). Such inliers are
left out and the rest fitted again (the whole fit, rescues and all); when that refit leaves the
radius undetermined (a tank's two columns: two lines bound it only from below) the fit is
refused, saying why. Lengths in metres.
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import radius_text
from asbuilt.fit._cylinder_background import DETERMINED_RADIUS, rescued
from asbuilt.fit._cylinder_checks import seen_through
from asbuilt.tolerances import MIN_POINTS

__all__ = ["FAR_FRACTION", "FAR_ROUNDS", "FarSideFit", "without_far_side"]

#: A beam that passed the fitted axis within this fraction of the radius crossed at least 0.87
#: radii of pipe before reaching a shot beyond its chord's middle.
FAR_FRACTION = 0.9
#: Rounds of leaving far-side inliers out and fitting again: each refit can put other shots
#: on its own far side.
FAR_ROUNDS = 2


class FarSideFit(FitError):
    """A cylinder fit refused: its inliers on the far side of the pipe as seen from the
    station, left out, leave no determined pipe. Not retried without the sensor's sigma: the
    beams do not depend on the noise."""


class _Fit:
    """The finished fit's axis, centre and radius (``state``) and ``inliers``, as
    :func:`~asbuilt.fit._cylinder_checks.seen_through` reads a robust fit."""

    def __init__(self, result):
        cylinder = result.primitive
        self.state = (
            np.asarray(cylinder.axis, dtype=np.float64),
            np.asarray(cylinder.center, dtype=np.float64),
            float(cylinder.radius),
        )
        self.inliers = np.asarray(result.inliers, dtype=bool)


def _far_side(result, points: np.ndarray, view: np.ndarray, tolerances) -> np.ndarray:
    """The inliers of ``result`` on its pipe's far side from ``view`` (module docstring),
    (n,) bool; the cutoff is ``tolerances.outlier_cutoff_sigma`` times the fit's noise."""
    cutoff = tolerances.outlier_cutoff_sigma * float(result.sigma)
    return seen_through(_Fit(result), points, view, cutoff, FAR_FRACTION)


def without_far_side(fit, result, points: np.ndarray, view, sigma, tolerances):
    """``result``, the cylinder fit of ``points`` (n, 3) metres seen from ``view`` ((3,)
    metres, or None: nothing to judge), fitted again without its inliers on the pipe's far
    side when it has any (module docstring); the refit's residuals and inliers are over every
    shot, the left-out shots outliers, with a note.

    ``fit(points, sigma, tolerances, viewpoint)`` fits a subset keeping the viewpoint
    (FitError otherwise); ``sigma`` metres or None.

    Raises
    ------
    FarSideFit
        The shots left once the far-side ones are out fit no pipe whose radius is known to
        ``DETERMINED_RADIUS`` of itself (a tank's two columns, once the wall column behind
        it is out), or the refits keep finding far-side inliers.
    """
    if view is None:
        return result
    first = result
    keep = np.ones(len(points), dtype=bool)
    for _ in range(FAR_ROUNDS):
        far = _far_side(result, points, view, tolerances)
        if not far.any():
            break
        keep &= ~far
        found = None
        # Too few shots left to fit at all (every inlier on the far side): refused as such.
        if np.count_nonzero(keep) >= MIN_POINTS["cylinder"]:
            try:
                found = fit(points[keep], sigma, tolerances, view)
            except FitError:
                pass
        if (
            found is None
            or not found.stderr["radius"] <= DETERMINED_RADIUS * found.primitive.radius
        ):
            raise _refused(first, points, view, tolerances, found)
        inliers = np.zeros(len(points), dtype=bool)
        inliers[keep] = found.inliers
        left = int(np.count_nonzero(~keep))
        note = (
            f"{left} shot(s) on the far side of the pipe as seen from the station (their beams"
            " would have crossed it first) were left out before the fit."
        )
        result = rescued(found, points, inliers, note)
    else:
        if _far_side(result, points, view, tolerances).any():
            raise _refused(first, points, view, tolerances, None)
    return result


def _refused(first, points: np.ndarray, view, tolerances, found) -> FarSideFit:
    """The refusal of ``first``, the fit whose far-side inliers left no pipe: ``found`` is the
    fit of the other shots (undetermined), or None (refused, or itself with far-side shots)."""
    count = int(np.count_nonzero(_far_side(first, points, view, tolerances)))
    reach = None if found is None else (found.diagnostics or {}).get("radius_reach")
    if reach is not None:
        rest = (
            "the others lie on two lines along it, which radii up to"
            f" {reach * 1000:.0f} mm fit as well"
        )
    elif found is not None:
        rest = (
            f"the others do not determine its radius (r {radius_text(found.primitive.radius)}"
            f" +-{found.stderr['radius'] / found.primitive.radius:.0%})"
        )
    else:
        rest = "no cylinder fits the others"
    return FarSideFit(
        f"The cylinder these shots fit best (r {radius_text(first.primitive.radius)}) has"
        f" {count} of its {first.n_inliers} shots on its far side as seen from the station:"
        " their beams would have crossed the pipe before reaching them, so they are background"
        " past its silhouette (three raster lines fit a circle exactly whatever they hit, and a"
        f" line on the wall behind a tank becomes its far side). Without them {rest}. Rescan"
        " with the window on the pipe and more raster lines across it, or give only the"
        " pipe's shots.",
        where="points",
    )
