"""Whether a wide curved fit measured its curvature, or a plane explains its shots as well.

Private helper of :mod:`asbuilt.fit` (the refusal of a plane-like radius) and of
:mod:`asbuilt.fit._cylinder_planes` (a plane-like first fit taken for a floor). A cylinder or
sphere many times wider than its shots is nested with their plane: it has the plane's three
parameters and one (sphere) or two (cylinder) more, so the drop in the sum of squares it buys
is a likelihood-ratio statistic (Seber & Wild 1989, 5.2). Lengths in metres.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import chdtri, fdtri

from asbuilt.fit._small_linalg import singular_values, svd

__all__ = ["CURVATURE_TAIL", "LONE_CUTOFFS", "curvature_measured"]

#: Upper tail probability of the tests that a plane-like fit's curvature must pass
#: (:func:`curvature_measured`): on a flat wall the curvature's extra parameters (one for a
#: sphere, two for a cylinder) lower the sum of squares below the plane's by chi-square
#: sigma^2 by chance alone, more than one sigma^2 in 32% (sphere) and 61% (cylinder) of walls,
#: which let kilometre-wide solids through; at 1e-3 one wall in a thousand. A real wide curve
#: clears it by far: a 10 m tank seen over 1 m lies 12 mm off its chord's plane.
CURVATURE_TAIL = 1e-3

#: A shot farther than this many noise levels from the plane of the others is not of their
#: surface (:func:`curvature_measured`), as the outlier cutoff judges a shot off a fit.
LONE_CUTOFFS = 3.0


def curvature_measured(kept: np.ndarray, residuals: np.ndarray, sigma: float, params: int) -> bool:
    """Whether a curved fit of the shots ``kept`` (m, 3) metres, with ``params`` parameters (4
    a sphere, 5 a cylinder), its ``residuals`` (m,) metres at noise level ``sigma`` metres,
    explains them significantly more closely than their plane does.

    The drop ``d`` of the sum of squares below the plane's, with ``k = params - 3`` (at least
    1) degrees of freedom, must pass at tail ``CURVATURE_TAIL``: the chi-square test at the
    stated noise, ``d >= sigma^2 chi2_k``, and, when the shots scatter about the fit wider than
    ``sigma`` (pointing noise on a face seen obliquely, a mixed return within the cutoff), the
    F test against that scatter, ``(d / k) / (s / (m - params)) >= F_{k, m - params}``, ``s``
    the fit's sum of squares: a curvature must stand out from the scatter the shots show (two
    raster columns on a tank, which a plane through them fits, had passed as r 381 m +-25%).

    Both are made again without the shot lying farthest off the plane of the others when that
    is more than ``LONE_CUTOFFS`` noise levels, and again without the next such shot, as many
    as the curvature has parameters: that many shots off one plane fit the curvature exactly
    whatever they hit (a drum's rim or side shot among the inliers of a fit of its flat end,
    the other 23 on one plane to 1.5 mm: r 46 m +-12%). A set left with no degree of freedom
    is judged by the tests before.
    """
    extra = max(params - 3, 1)
    keep = np.ones(len(kept), dtype=bool)
    for left_out in range(extra + 1):
        shots = kept[keep]
        dof = len(shots) - params
        if dof < 1 and left_out:
            return True  # too few left to test: the whole set's tests stand
        centred = shots - shots.mean(axis=0)
        plane_sse = float(singular_values(centred)[-1] ** 2)
        fit_sse = float(np.sum(residuals[keep] ** 2))
        drop = plane_sse - fit_sse
        if drop < sigma**2 * chdtri(extra, CURVATURE_TAIL):
            return False
        scatter = fit_sse / dof if dof >= 1 else 0.0
        wider = scatter > sigma**2
        if wider and drop / extra < scatter * fdtri(extra, dof, 1.0 - CURVATURE_TAIL):
            return False
        lone = _off_the_plane(shots, LONE_CUTOFFS * math.sqrt(max(scatter, sigma**2)))
        if lone is None:
            return True
        keep[np.flatnonzero(keep)[lone]] = False
    return True


def _off_the_plane(shots: np.ndarray, cutoff: float) -> int | None:
    """The index of the one of ``shots`` (m, 3) metres farthest from the plane of the others
    (total least squares) when that is more than ``cutoff`` metres, else None."""
    centred = shots - shots.mean(axis=0)
    farthest = int(np.argmax(np.abs(centred @ svd(centred)[2][-1])))
    others = np.delete(shots, farthest, axis=0)
    middle = others.mean(axis=0)
    normal = svd(others - middle)[2][-1]
    return farthest if abs(float((shots[farthest] - middle) @ normal)) > cutoff else None
