"""Edge-bisection shots that are a raster's own shots after all.

Private helper of the cuboid fit. :func:`asbuilt.fit._silhouette.edge_shots` takes a shot for a
bisection's when its angle is off the lattice of the raster lines crossing its own line, and,
with a single such line, when it is alone on its line next to a raster line. A raster over a
beam seen obliquely (a diagonal strip in the window) ends in such a shot: the last row holds
one shot, whose column holds one more, a row away. Taken for a bisection shot, it pinned the
beam's far end with no pad and no gap: an independent ray caster's beams 4.8-7.7 m long, seen
at 80-86 degrees there, came out 0.3-1.4 m short with a 2 mm standard error (z 24-640).

A session bisects between a raster hit and the neighbouring miss on the next line, so each of
its shots lies strictly between two neighbouring lines: a fraction of a step from the raster
shot it started from, never a whole step. A flagged shot a whole number of raster steps from
its partner (the nearest raster shot on its line), within the line width, is a raster shot.
Numpy only; angles in radians.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._silhouette import _LINE_WIDTH

__all__ = ["raster_corners"]


def raster_corners(edges, seen, steps) -> tuple[np.ndarray, np.ndarray]:
    """``edges`` with the shots that lie a whole raster step or more from their partner along
    the bisected angle, on the lattice, taken back as raster shots.

    Parameters
    ----------
    edges : tuple of ndarray
        :func:`asbuilt.fit._silhouette.edge_shots`'s ``(along, partner)``, each (n,) int.
    seen : tuple
        :func:`asbuilt.fit._silhouette.shot_angles` of the same shots (its angles (n, 2) and
        the line blur, radians).
    steps : ndarray, shape (2,)
        The raster's pan and tilt steps (:func:`asbuilt.fit._silhouette.raster_grid`).

    Returns
    -------
    tuple of ndarray
        ``(along, partner)``, copies, -1 for the shots taken back.
    """
    along, partner = edges
    flagged = ((along >= 0) & (partner >= 0)).nonzero()[0]
    if seen is None or flagged.size == 0:
        return edges
    _, ang, blur = seen
    along, partner = along.copy(), partner.copy()
    for i in flagged:
        j = int(along[i])
        step = float(steps[j])
        if not step > 0.0:
            continue
        # The line width edge_shots tells lines apart by.
        tol = max(_LINE_WIDTH * 1e-2 * float(np.ptp(ang[:, j])), blur)
        offset = abs(float(ang[i, j] - ang[partner[i], j])) / step
        whole = round(offset)
        if whole >= 1 and abs(offset - whole) * step <= tol:
            along[i] = partner[i] = -1
    return along, partner
