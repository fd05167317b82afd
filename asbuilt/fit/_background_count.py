"""Counting a fit's rejected shots that can only be background seen from the station.

A robust fit rejects the shots a raster window reached past the object (the wall behind a
tank, the floor under a pipe) as outliers like any other; with the station known, those whose
beams cleared the fitted object and ended beyond it are the background itself, not the object's
shots. The count goes into ``diagnostics[BACKGROUND_SHOTS]``, which the ``outliers`` rule (AB404)
does not count: an independent review's spools framed a little wider than the pipes drew the
warning on 24 of 24 such pipes with the station given, every rejected shot on the wall behind.
The fit itself is unchanged.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.fit._common import fit_cutoff
from asbuilt.fit._cuboid_foreground import behind as behind_box
from asbuilt.fit._sphere_background import behind as behind_sphere
from asbuilt.fit.result import BACKGROUND_PLANE_SHOTS, BACKGROUND_SHOTS, FitResult
from asbuilt.primitives import Cuboid, Cylinder, Sphere
from asbuilt.tolerances import Tolerances

__all__ = ["behind_fit", "with_background_count"]


def behind_fit(primitive, points: np.ndarray, view: np.ndarray, cutoff: float) -> np.ndarray:
    """Which of ``points`` (n, 3) metres can only be background of ``primitive`` seen from
    ``view`` (3,) metres, shape (n,) bool: each more than ``cutoff`` metres beyond where its beam
    met the object (or passed nearest it), its beam through the object by at most ``cutoff``.
    A cylinder is the fitted one, of its length (a beam past a pipe's free end met none); kinds
    other than cylinder, sphere and cuboid have no behind: all False."""
    if isinstance(primitive, Cylinder):
        return _behind_cylinder(primitive, points, view, cutoff)
    if isinstance(primitive, Sphere):
        return behind_sphere(primitive, points, view, cutoff)
    if isinstance(primitive, Cuboid):
        return behind_box(primitive, points, view, cutoff)
    return np.zeros(len(points), dtype=bool)


def _behind_cylinder(cylinder, points: np.ndarray, view: np.ndarray, cutoff: float):
    """:func:`behind_fit` of a cylinder: each beam passes the axis, where nearest it, no more
    than ``cutoff`` inside the radius (or beyond the fitted length there, a raster row past a
    pipe's free end), and its shot lies more than ``cutoff`` past that point along the beam.

    The depth a beam reaches inside, not the chord it runs (the fits' own test,
    :func:`asbuilt.fit._visibility.cylinder_beam_excess`): a wall shot whose beam grazed the
    silhouette 1 mm inside a 57 mm pipe (the pointing noise, a radius fitted a millimetre
    wide) runs a 21 mm chord, and is background all the same, as for spheres and boxes.
    """
    axis = np.asarray(cylinder.axis, dtype=np.float64)
    rays = points - view
    ranges = np.sqrt(np.einsum("ij,ij->i", rays, rays))
    beams = rays / np.where(ranges > 0.0, ranges, 1.0)[:, None]
    start = view - cylinder.center
    along = beams @ axis
    start_along = float(start @ axis)
    # A beam parallel to the axis has no nearest point; the floor makes its ``at`` 0 (the station).
    square = np.maximum(1.0 - along * along, 1e-12)
    at = (along * start_along - beams @ start) / square  # metres along each beam
    nearest = start + at[:, None] * beams
    axial = nearest @ axis
    radial = nearest - axial[:, None] * axis
    depth = float(cylinder.radius) - np.sqrt(np.einsum("ij,ij->i", radial, radial))
    past_end = np.abs(axial) > 0.5 * float(cylinder.length) + cutoff
    return ((depth <= cutoff) | past_end) & (ranges - at > cutoff)


def with_background_count(
    result: FitResult, points: np.ndarray, view, sigma, tolerances: Tolerances
) -> FitResult:
    """``result`` with ``diagnostics[BACKGROUND_SHOTS]`` raised to the count of its rejected
    shots that lie behind its primitive seen from ``view`` (:func:`behind_fit`; ``points``
    (n, 3) metres in the order of ``result.residuals``; ``sigma`` metres, the sensor's, or None
    for the fit's own noise); unchanged without a viewpoint or when no more are behind.

    The shots a rescue left out on planes around the object (``BACKGROUND_PLANE_SHOTS``) are
    subtracted first: the rule adds both counts, and a floor under a pipe is not behind it, so
    the sum never exceeds the larger of the rescue's count and this one.
    """
    if view is None or result.inliers.all():
        return result
    cutoff = fit_cutoff(result, sigma, tolerances)
    rejected = points[~result.inliers]
    count = int(np.count_nonzero(behind_fit(result.primitive, rejected, view, cutoff)))
    known = float(result.diagnostics.get(BACKGROUND_SHOTS, 0.0))
    on_planes = float(result.diagnostics.get(BACKGROUND_PLANE_SHOTS, 0.0))
    if not count - on_planes > known:
        return result
    diagnostics = {**result.diagnostics, BACKGROUND_SHOTS: float(count - on_planes)}
    return dataclasses.replace(result, diagnostics=diagnostics)
