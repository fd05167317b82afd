"""A floor, a ceiling or a wall a raster window reached around a box, left out before its fit.

Private helper of the cuboid fit. An operator's pan-tilt window a little wider than a column,
a pier or a beam puts shots on what lies behind it: the floor around a pier seen from above,
the ceiling over a beam seen from below, the wall behind a column. Such a surface is one plane
holding more shots than any face of the box, and the fit took it for a face: an independent
ray caster's piers on a floor in windows twice their width came out 2.6 x 2.6 x 19.8 m for
0.33 x 0.39 x 0.95 m (20 of 20), with centimetre standard errors. Cutting the shots at range
jumps (:mod:`asbuilt.fit._cuboid_foreground`) cannot help there: a pier stands on the floor
with no jump between them.

Two things tell such a plane from a face of the box, as seen from the station:

- shots lie in front of it (a box is convex: no shot on it lies on the station's side of one
  of its seen faces' planes; the box in front of the wall does);
- its shots run out to more of the raster window's outermost lines than the shots in front of
  it do (the operator framed the box; the floor, ceiling or wall fills the window around it).
  A pipe in front of a column crosses the window as the column does, so neither is taken for
  background.

Such planes are left out, the largest first, each judged among the shots still left, and the
box fitted to the rest. The fit stands when no left-out shots (fewer than ``INSIDE_SHOTS``)
were measured through it: their directions lie outside the silhouette its own shots span as
seen from the station (a box is opaque; the floor beside a pier and in front of it, and the
wall's next raster line past a column's edge, lie outside it). The caller keeps it only when
fewer shots lie in front of its box than of the first fit's. Lengths in metres, angles in
radians.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree

from asbuilt.errors import FitError
from asbuilt.fit._cuboid_sparse import AmbiguousFrame
from asbuilt.fit._cylinder_background import (
    BACKGROUND_PLANE_SHOTS,
    near_random_planes,
    rescued,
    segment_noise,
)
from asbuilt.tolerances import MIN_POINTS

__all__ = [
    "FRONT_CUTOFFS",
    "MOST_PLANES",
    "PLANE_SHOTS",
    "SIDE_SHARE",
    "background_planes",
    "fit_past_planes",
]

#: A plane holding fewer shots is not taken for a background surface (two raster lines of
#: three shots).
PLANE_SHOTS = 6
#: Random point triples tried for planes in each round (RANSAC hypotheses).
PLANE_SAMPLES = 300
#: At most this many planes are left out (a floor, a wall and a ceiling around a box).
MOST_PLANES = 3
#: Candidate planes judged per round, fullest first.
CANDIDATES = 6
#: A shot lies in front of a plane when it is more than this many inlier cutoffs nearer the
#: station than the plane (a mixed return at the box's edge lies between the two).
FRONT_CUTOFFS = 3.0
#: A set of shots reaches a side of the raster window when it holds at least this share of the
#: shots on that side's outermost line (a beam seen obliquely touches a side only at a corner).
SIDE_SHARE = 0.5
#: A plane flanks the shots in front of it on a side where at least this many of its shots
#: lie beyond them all (a floor around a pier flanks it on four sides, around a column's foot
#: on three; a column behind a pipe flanks it above and below only, and the pipe flanks the
#: column on its two sides).
FLANK_SHOTS = 2
#: A plane's shots spread across their second direction by less than this many inlier cutoffs
#: lie on one raster line: any plane through that line holds them.
LINE_CUTOFFS = 3.0
#: A shot lies on a window side's outermost line when its angle is within this many raster
#: steps of that side.
LINE_STEPS = 0.5
#: A left-out shot was measured through the box when its direction lies inside the box's
#: shots' silhouette by more than this many raster steps (one on its edge is a raster
#: neighbour, its beam past the box).
INSIDE_STEPS = 0.25
#: Fewer than this many left-out shots may lie inside the box's silhouette (one or two can be
#: a stray return, a mixed one at a corner; as :data:`asbuilt.fit._cuboid_foreground.FRONT_SHOTS`).
INSIDE_SHOTS = 3


def _raster_step(ang: np.ndarray) -> float:
    """The median angular distance (radians) from each shot's direction ``ang`` (n, 2) to its
    nearest neighbour's: the raster's finer step."""
    distance, _ = cKDTree(ang).query(ang, k=2)
    return float(np.median(distance[:, 1]))


def _side_lines(ang: np.ndarray, step: float) -> np.ndarray:
    """Which shots lie on each side's outermost line of the window, shape (4, n) bool: pan
    least and greatest, tilt least and greatest (``ang`` (n, 2) radians, the raster ``step``
    radians)."""
    reach = LINE_STEPS * step
    low, high = ang.min(axis=0), ang.max(axis=0)
    return np.array(
        [
            ang[:, 0] <= low[0] + reach,
            ang[:, 0] >= high[0] - reach,
            ang[:, 1] <= low[1] + reach,
            ang[:, 1] >= high[1] - reach,
        ]
    )


def _sides_reached(lines: np.ndarray, members: np.ndarray, among: np.ndarray) -> int:
    """How many window sides ``members`` (n,) bool reach: hold at least ``SIDE_SHARE`` of the
    shots of ``among`` (n,) bool on that side's outermost line (``lines`` (4, n) bool)."""
    reached = 0
    for line in lines:
        total = np.count_nonzero(line & among)
        if total and np.count_nonzero(line & members) >= SIDE_SHARE * total:
            reached += 1
    return reached


def _plane_through(points: np.ndarray, cutoff: float, start: np.ndarray):
    """The total least squares plane of the shots within ``cutoff`` metres of the plane of
    ``start`` (n,) bool's shots, refitted twice: ``(normal (3,), offset, members (n,) bool)``,
    or None when its shots lie on one line (their spread across it under ``LINE_CUTOFFS``
    cutoffs) or are fewer than ``PLANE_SHOTS``."""
    members = start
    for _ in range(3):
        if np.count_nonzero(members) < PLANE_SHOTS:
            return None
        chosen = points[members]
        centre = chosen.mean(axis=0)
        _, spread, vt = np.linalg.svd(chosen - centre, full_matrices=False)
        if spread[1] / np.sqrt(len(chosen)) < LINE_CUTOFFS * cutoff:
            return None
        normal = vt[2]
        offset = float(normal @ centre)
        members = np.abs(points @ normal - offset) <= cutoff
    if np.count_nonzero(members) < PLANE_SHOTS:
        return None
    return normal, offset, members


def _flanks(angles: np.ndarray, outer: np.ndarray, inner: np.ndarray, step: float) -> int:
    """On how many of the four sides (pan and tilt, least and greatest) at least
    ``FLANK_SHOTS`` shots of ``outer`` (n,) bool lie more than half a raster ``step`` (radians)
    beyond every shot of ``inner`` (n,) bool (``angles`` (n, 2) radians)."""
    low, high = angles[inner].min(axis=0), angles[inner].max(axis=0)
    beyond = np.concatenate(
        [angles[outer] < low - 0.5 * step, angles[outer] > high + 0.5 * step], axis=1
    )
    return int(np.count_nonzero(beyond.sum(axis=0) >= FLANK_SHOTS))


def _background_plane(points, view, cutoff, left, angles, step, rng):
    """The fullest plane among the shots ``left`` (n,) bool that is background (see the
    module docstring), as its shots (n,) bool, or None (``angles`` (n, 2) radians, the raster
    ``step`` radians)."""
    lines = _side_lines(angles, step)
    index = np.flatnonzero(left)
    if len(index) < PLANE_SHOTS + MIN_POINTS["cuboid"]:
        return None
    near = near_random_planes(points[index], cutoff, PLANE_SAMPLES, rng)
    counts = near.sum(axis=0)
    tried: list[np.ndarray] = []
    for k in np.argsort(-counts, kind="stable"):
        if counts[k] < PLANE_SHOTS or len(tried) == CANDIDATES:
            break
        start = np.zeros(len(points), dtype=bool)
        start[index[near[:, k]]] = True
        if any(np.count_nonzero(start & seen) > 0.5 * counts[k] for seen in tried):
            continue  # mostly a plane judged already (many triples lie on each face)
        plane = _plane_through(points, cutoff, start)
        if plane is None:
            continue
        normal, offset, members = plane
        members &= left
        tried.append(members | start)
        toward = 1.0 if normal @ view > offset else -1.0
        front = left & (toward * (points @ normal - offset) > FRONT_CUTOFFS * cutoff)
        if np.count_nonzero(front) < MIN_POINTS["cuboid"]:
            continue
        own = _sides_reached(lines, members, left)
        if own < 2 or own <= _sides_reached(lines, front, left):
            continue
        # Flanking is judged on the shots in front that the plane's own shots surround (the
        # floor before a wall is in front of it too, and as wide as the window).
        framed = front.copy()
        framed[front] = _inside(angles[members], angles[front], -LINE_STEPS * step)
        if not framed.any():
            return members  # beside the shots in front, not around them: a floor below a brace
        outside = _flanks(angles, members, framed, step)
        if outside >= 3 and _flanks(angles, framed, members, step) <= 1:
            return members
    return None


def background_planes(points: np.ndarray, view: np.ndarray, cutoff: float, angles) -> np.ndarray:
    """The shots on background planes around a box, shape (n,) bool (none when there are none).

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres
        The station.
    cutoff : float, metres
        The inlier cutoff (shots within it of a plane lie on it).
    angles : ndarray, shape (n, 2), radians
        Each shot's pan and tilt from the station
        (:func:`asbuilt.fit._silhouette.shot_angles`).

    Notes
    -----
    Round by round (at most ``MOST_PLANES``), among the shots not yet left out, the fullest
    plane (RANSAC hypotheses, Fischler & Bolles 1981, refined by total least squares) that
    holds at least ``PLANE_SHOTS`` shots off one line, has at least the cuboid's
    ``MIN_POINTS`` shots more than ``FRONT_CUTOFFS`` cutoffs in front of it, and reaches at
    least two sides of the window, and more sides than those shots in front of it do, is left
    out. Deterministic: the hypotheses are drawn from a generator seeded with ``n``.
    """
    n = len(points)
    left = np.ones(n, dtype=bool)
    step = _raster_step(angles)
    rng = np.random.default_rng(n)
    for _ in range(MOST_PLANES):
        plane = _background_plane(points, view, cutoff, left, angles, step, rng)
        if plane is None:
            break
        left &= ~plane
    return ~left


def _inside(kept: np.ndarray, others: np.ndarray, margin: float) -> np.ndarray:
    """Which directions ``others`` (r, 2) radians lie inside the convex hull of ``kept`` (k, 2)
    radians by more than ``margin`` radians, shape (r,) bool (none when the hull is flat)."""
    if len(others) == 0:
        return np.zeros(0, dtype=bool)
    try:
        # Each facet's outward unit normal and offset (inside: below every facet's line).
        planes = ConvexHull(kept).equations  # (f, 3)
    except QhullError:
        return np.zeros(len(others), dtype=bool)
    depth = others @ planes[:, :2].T + planes[:, 2]
    return (depth < -margin).all(axis=1)


def fit_past_planes(fit, points: np.ndarray, view: np.ndarray, sigma, tolerances, angles):
    """The cuboid fit of the shots off the floor, ceiling or wall a raster window reached
    around the box (:func:`background_planes`), when fewer than ``INSIDE_SHOTS`` left-out shots
    lie inside its shots' silhouette; else None. A box whose own shots fit frames far apart
    equally well raises :class:`~asbuilt.fit._cuboid_sparse.AmbiguousFrame`.

    Parameters
    ----------
    fit : callable
        ``fit(points, sigma, tolerances, viewpoint)``, the cuboid fit of a subset.
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres
        The station.
    sigma : float or None, metres
        The sensor's range noise (None: the prior noise finds the planes).
    tolerances : Tolerances
    angles : ndarray, shape (n, 2), radians
        Each shot's pan and tilt from the station.

    Returns
    -------
    FitResult or None
        The subset's fit as the fit of every shot (residuals over all, the background's shots
        not inliers), with a note.
    """
    cutoff = tolerances.outlier_cutoff_sigma * segment_noise(sigma, tolerances)
    background = background_planes(points, view, cutoff, angles)
    if not background.any():
        return None
    margin = INSIDE_STEPS * _raster_step(angles)
    mask = ~background
    try:
        found = fit(points[mask], sigma, tolerances, view)
    except AmbiguousFrame:
        # The box's own shots fit frames far apart as well: that is the answer, not the
        # background's box the first fit made of the rest.
        raise
    except FitError:
        return None
    kept = np.flatnonzero(mask)[found.inliers]
    if np.count_nonzero(_inside(angles[kept], angles[background], margin)) >= INSIDE_SHOTS:
        return None
    inliers = np.zeros(len(points), dtype=bool)
    inliers[kept] = True
    note = (
        f"{int(np.count_nonzero(background))} shot(s) lie on a floor, ceiling or wall behind "
        "the box (a plane with the box's shots in front of it that fills more of the raster "
        "window than they do) and were left out as background before the fit."
    )
    result = rescued(found, points, inliers, note)
    # Counted for the noise check (asbuilt.fit._noise_levels): the shots left out lie far off
    # the box and are no rough surface's scatter.
    left_out = float(np.count_nonzero(background))
    return dataclasses.replace(
        result, diagnostics={**result.diagnostics, BACKGROUND_PLANE_SHOTS: left_out}
    )
