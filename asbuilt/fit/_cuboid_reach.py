"""Cuboid sizes whose unseen edges nothing says the shots reach: lower bounds only.

A size no two opposite seen faces bound is the extent of the shots along it, padded by half the
sampling step that reached the edge (:func:`asbuilt.fit._cuboid_sizes.bounds`). That step, and
the standard error built on it, holds when the shots are a pan-tilt raster over a window that
covers the object: the raster's next line would have hit the face had it run on, so the edge
lies within a step of the last hit. Shots aimed by hand (clusters, kept away from the edges to
avoid mixed returns) stop short of an edge by however far the operator stayed from it; the
spacing between their clusters says nothing about that gap (an independent review's column,
hand-aimed on two faces: a 300 mm width fitted 242.4 +- 6.9 mm, z -8.4; over its 48 hand-aimed
box scans 129 of 138 such sizes short, 37 by over 3 standard errors, z down to -9.4).

So when the fit finds no raster lattice from a trusted viewpoint
(:func:`asbuilt.fit._silhouette.raster_grid`, and not even evenly spaced lines in pan or in
tilt alone, which a raster with a few columns occluded still has: the shots are hand-aimed, or
there is no station to read a raster from), a size bounded by extent at an end no edge-bisection shot pins is a
lower bound: its standard error is infinite (null in JSON), the centre's too, a note says so
(with what the shots span of it, the bound itself: the size keeps its pad, so that it does not
depend on the raster being read) and ``diagnostics["unreached_sizes"]`` counts them, as for a size a session saw run on past its
window (:mod:`asbuilt.fit._window`). A dense cloud (``DENSE_SHOTS`` inliers or more: a
scanner's sampling, not shots aimed one by one) reaches its edges to within its point
spacing, and keeps the standard error of that spacing. Numpy only.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from asbuilt.fit.result import FitResult

__all__ = ["DENSE_SHOTS", "lower_bounds", "unreached"]

#: Inliers from which the points are taken for a scanner's dense cloud (it samples the object
#: up to its edges at its point spacing) rather than shots aimed one by one (20-40 an object
#: by hand; no operator aims hundreds).
DENSE_SHOTS = 600


def unreached(lo_face, hi_face, pinned, lattice: bool, inliers: int) -> np.ndarray:
    """Per axis (3,) bool: a size bounded by the shots' extent at an end nothing pins.

    ``lo_face`` / ``hi_face`` (3,) bool: a seen face bounds that end; ``pinned`` (2, 3) bool
    (row 0 the low ends): an edge-bisection shot reached that end; ``lattice``: the shots are a
    pan-tilt raster from a trusted viewpoint; ``inliers``: how many shots the fit kept. All
    False on a raster or a dense cloud (``DENSE_SHOTS``).
    """
    if lattice or inliers >= DENSE_SHOTS:
        return np.zeros(3, bool)
    pinned = np.asarray(pinned, bool)
    lo_open = ~np.asarray(lo_face, bool) & ~pinned[0]
    hi_open = ~np.asarray(hi_face, bool) & ~pinned[1]
    return lo_open | hi_open


def note(sizes, spans, trusted: bool) -> str:
    """The note for the lower-bound ``sizes`` and what the shots span of each (metres, in
    output order); ``trusted``: the fit had a station."""
    plural = len(sizes) > 1
    what = ", ".join(
        f"{size:.3f} m (the shots span {span:.3f} m of it)" for size, span in zip(sizes, spans)
    )
    why = (
        "The shots are not on a pan-tilt raster from the station (aimed by hand, or is the"
        " station's position wrong?)"
        if trusted
        else "Without the station the shots cannot be read as a pan-tilt raster"
    )
    advice = (
        "Check the scan's sensor position; if it is right, shoot a raster over the whole"
        " object, or the face opposite, to measure " + ("them" if plural else "it")
        if trusted
        else "Give the scan's sensor position (a raster is then recognised), or shoot the face "
        "opposite"
    )
    return (
        f"{why}, so nothing says how far the unseen edges lie beyond the outermost shots: the "
        f"size{'s' if plural else ''} {what} bounded by their extent "
        f"{'are lower bounds' if plural else 'is a lower bound'} (at least the span; "
        f"standard error infinite), not {'measurements' if plural else 'a measurement'}. "
        f"{advice}."
    )


def lower_bounds(result: FitResult, sizes=None, trusted: bool = False, spans=None) -> FitResult:
    """``result`` (a cuboid fit) with the ``sizes`` ((3,) bool in its output order; default:
    every size not ``observed``) that have a finite standard error made lower bounds (see the
    module docstring), or ``result`` itself when there is none. ``trusted``: the fit had a
    station (the note's wording); ``spans`` (3,) metres: what the shots span of each size (the
    size without the pad added beyond the outermost shots; default: the sizes).

    The size itself is left as fitted (padded by half the spacing of the shots that reached
    the edge, as a raster's would be): it does not depend on whether a raster was read from
    the shots (a scan's frame turned, or in survey coordinates without its station).

    By default for a fit that did not see where its shots came from (two stations' views
    fitted together, :mod:`asbuilt.fit._cuboid_stations`) when a view's own fit found sizes
    its shots do not reach.
    """
    size_se = list(result.stderr["size"])
    if sizes is None:
        observed = result.observed if result.observed is not None else (False,) * 3
        sizes = [not seen for seen in observed]
    chosen = [k for k in range(3) if sizes[k] and math.isfinite(size_se[k])]
    if not chosen:
        return result
    for k in chosen:
        size_se[k] = math.inf
    # Where the box lies along a size of unknown length is as unknown as the length.
    stderr = {**result.stderr, "size": tuple(size_se), "center": math.inf}
    size = np.asarray(result.primitive.size, dtype=np.float64)
    spans = size if spans is None else np.minimum(np.asarray(spans, dtype=np.float64), size)
    text = note([float(size[k]) for k in chosen], [float(spans[k]) for k in chosen], trusted)
    diagnostics = {**result.diagnostics, "unreached_sizes": float(len(chosen))}
    return dataclasses.replace(
        result, stderr=stderr, notes=(*result.notes, text), diagnostics=diagnostics
    )
