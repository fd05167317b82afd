"""A wall behind a pipe, a floor under it or a floor it passes through, left out before its fit.

Private helper of the cylinder fit. An operator's pan-tilt window over a pipe also catches what
lies around it: the wall behind it, the floor it lies on, the floor or wall it rises out of.
With a viewpoint such shots often outnumber the pipe's, and no start settled on the pipe: a
black-box review's ray caster, a wall 0.05-0.5 m behind the pipe, refused 140 of 150 fits
(the pipe's own shots alone fit correctly), and a plane was returned as a cylinder of metres
to kilometres (r 35.6 m +-1.9 m for a 57 mm pipe on a floor). Cutting the shots at range jumps
(:mod:`asbuilt.fit._cylinder_background`) cannot part a pipe from a floor it lies on or rises
out of: there is no jump between them.

Such a surface is one plane with the pipe in front of it as seen from the station: a wall
behind a pipe, a floor under it, and a floor or wall the pipe passes through on the station's
side all have the pipe's shots on the station's side of their plane, and nothing behind them
(they are opaque). A plane through the pipe's own shots has shots on both sides (its front
rows before the plane through its silhouette rows, those rows behind the plane through its
front). So the fullest plane (RANSAC hypotheses refined by total least squares) holding
``PLANE_SHOTS`` shots or more, with ``FRONT_SHOTS`` or more shots over ``FRONT_CUTOFFS``
cutoffs in front of it and at most a few behind, is left out, and the pipe fitted to the rest
(up to ``MOST_PLANES`` such planes, a floor and a wall, each judged among the shots still
left). That fit stands when it is a pipe (its radius known to half itself, no wider than
``PLANE_LIKE`` times its inliers' extent and over the inlier cutoff, ``FRONT_SHOTS``
inliers or more), at most ``NEAR_SHARE`` of the left-out shots lie within ``FRONT_CUTOFFS``
cutoffs of it (a plane through a rough pipe's own silhouette rows has every other shot in
front of it too, but its shots lie on the pipe), fewer than
``CROSSED_SHOTS`` left-out shots' beams cross the fitted pipe (a beam that met the pipe ends
on it, not in front of it or behind it), and it explains the shots off the left-out planes
better than the first fit did, if that one stood. Lengths in metres.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import extent_of, radius_text
from asbuilt.fit._cuboid_lone import one_line_and_lone_shot
from asbuilt.fit._cuboid_planes import LINE_CUTOFFS, _plane_through
from asbuilt.fit._curvature import curvature_measured
from asbuilt.fit._cylinder_background import (
    BACKGROUND_PLANE_SHOTS,
    DETERMINED_RADIUS,
    random_planes,
    rescued,
    segment_noise,
    taken_back,
    within,
)
from asbuilt.fit._cylinder_checks import PLANE_LIKE
from asbuilt.fit._cylinder_end_plane import worth_a_look

__all__ = [
    "BACKGROUND_PLANE_SHOTS",
    "BackgroundPlaneFit",
    "CROSSED_SHOTS",
    "FRONT_CUTOFFS",
    "FRONT_SHOTS",
    "MOST_PLANES",
    "PLANE_SHOTS",
    "fit_past_planes",
    "in_doubt",
    "plane_like",
]

#: A plane holding fewer shots is not taken for a background surface (two raster lines of
#: three shots, as :data:`asbuilt.fit._cuboid_planes.PLANE_SHOTS`).
PLANE_SHOTS = 6
#: Random point triples tried for the planes in each round (RANSAC hypotheses).
PLANE_SAMPLES = 300
#: At most this many planes are left out (a floor and a wall around a pipe, and one more).
MOST_PLANES = 3
#: Distinct candidate planes judged per round, fullest first.
CANDIDATES = 12
#: Two candidate planes whose shots share more than this share of their union are one.
SAME_SHARE = 0.8
#: A shot lies in front of (behind) a plane when it is more than this many inlier cutoffs
#: nearer the station than (farther than) the plane.
FRONT_CUTOFFS = 3.0
#: A background plane has at least this many shots in front of it, and the pipe fitted past it
#: at least this many inliers (half the 20 shots a cylinder fit is recommended).
FRONT_SHOTS = 10
#: ... and at most this many behind it, or this share of the shots left (an opaque surface
#: hides what lies behind it; a stray return or two).
BEHIND_SHOTS = 2
BEHIND_SHARE = 0.02
#: At most this share of the left-out shots may lie within ``FRONT_CUTOFFS`` cutoffs of the
#: refitted pipe (a floor meets a pipe lying on it along one line of shots).
NEAR_SHARE = 1.0 / 3.0
#: Fewer than this many left-out shots may have beams that cross the refitted pipe (one or two
#: stray or mixed returns at its silhouette; as :data:`asbuilt.fit._cuboid_planes.INSIDE_SHOTS`).
CROSSED_SHOTS = 3


def plane_like(result, points: np.ndarray) -> bool:
    """Whether a cylinder fit (a FitResult over ``points`` (n, 3) metres) is wider than
    ``PLANE_LIKE`` times its inliers' extent across its axis: over them, nearly a plane (a
    floor seen at grazing incidence is a strip tens of metres long, which a cylinder laid
    along it bends over only across its width)."""
    kept = points[result.inliers]
    cylinder = result.primitive
    return len(kept) < 2 or cylinder.radius > PLANE_LIKE * extent_of(kept, cylinder.axis)


def in_doubt(first, points: np.ndarray, sigma, tolerances, face_explained: bool = False) -> bool:
    """Whether to look for background planes after the ``first`` fit (a FitResult over
    ``points`` (n, 3) metres, or None when it was refused or ignored the viewpoint): always
    when refused; when its radius is not known to ``DETERMINED_RADIUS`` of itself, it is
    :func:`plane_like`, or many of its shots lie off it
    (:func:`asbuilt.fit._cylinder_end_plane.worth_a_look`, ``face_explained`` passed on)."""
    if first is None:
        return True
    stderr = first.stderr.get("radius")
    return bool(
        not stderr <= DETERMINED_RADIUS * first.primitive.radius
        or plane_like(first, points)
        or worth_a_look(first, sigma, tolerances, face_explained)
    )


def _same_set(one: np.ndarray, other: np.ndarray) -> bool:
    """Whether two sets of shots (n,) bool share more than ``SAME_SHARE`` of their union."""
    return np.count_nonzero(one & other) > SAME_SHARE * np.count_nonzero(one | other)


def _heights(points: np.ndarray, view: np.ndarray, samples: int, rng):
    """Each of ``points``' (n, 3) metres height above the planes through ``samples`` random
    triples of them (RANSAC hypotheses, Fischler & Bolles 1981; degenerate triples dropped),
    positive on the side of ``view`` (3,) metres: shape (n, planes), metres; and the height of
    ``view`` above each plane, shape (planes,) metres."""
    normals, offsets = random_planes(points, samples, rng)
    heights = points @ normals.T - offsets
    station = normals @ view - offsets
    return heights * np.where(station > 0.0, 1.0, -1.0), np.abs(station)


def _background(heights: np.ndarray, station, cutoff: float) -> tuple[np.ndarray, np.ndarray]:
    """For the planes of ``heights`` (n, planes) metres (:func:`_heights`): which of them have
    ``FRONT_SHOTS`` or more shots more than ``FRONT_CUTOFFS`` times ``cutoff`` metres in front
    of them and few behind, and the station (heights ``station`` (planes,) metres above them)
    off them by more than that too, (planes,) bool; and how many shots lie on each (planes,).

    A plane through the station is seen edge-on: it holds its shots' beams, so an opaque
    surface there returns none of them and hides nothing, and "in front of it" means nothing
    from the station. One raster line's shots lie on such a plane whatever they hit (a
    vertical tank's raster column, its lid and the wall above it), with the range noise in the
    plane; taken for a wall with the tank in front of it, it left one of three columns out and
    the two others fitted a pipe of 0.4 times the tank's radius to a millimetre.
    """
    n = len(heights)
    front = np.count_nonzero(heights > FRONT_CUTOFFS * cutoff, axis=0)
    behind = np.count_nonzero(heights < -FRONT_CUTOFFS * cutoff, axis=0)
    on = np.count_nonzero(np.abs(heights) <= cutoff, axis=0)
    few = max(BEHIND_SHOTS, BEHIND_SHARE * n)
    seen = np.asarray(station) > FRONT_CUTOFFS * cutoff
    return (front >= FRONT_SHOTS) & (behind <= few) & seen, on


def _background_plane(points, view, cutoff, left, rng):
    """The fullest plane among the shots ``left`` (n,) bool with ``FRONT_SHOTS`` of them in
    front of it and few behind (see the module docstring), as its shots (n,) bool among
    ``left``, or None (``points`` (n, 3) and ``view`` (3,) metres, ``cutoff`` metres).

    Every hypothesis is judged before any is refined: the fullest planes are often a floor
    and a row of pipe shots together (with pipe shots behind them), and a pure floor's
    hypotheses hold fewer shots than they do.
    """
    index = np.flatnonzero(left)
    if len(index) < PLANE_SHOTS + FRONT_SHOTS:
        return None
    chosen = points[index]
    heights, station = _heights(chosen, view, PLANE_SAMPLES, rng)
    valid, on = _background(heights, station, cutoff)
    order = np.flatnonzero(valid & (on >= PLANE_SHOTS))
    seen: list[np.ndarray] = []
    for k in order[np.argsort(-on[order], kind="stable")][:CANDIDATES]:
        start = np.zeros(len(points), dtype=bool)
        start[index[np.abs(heights[:, k]) <= cutoff]] = True
        if any(_same_set(start, other) for other in seen):
            continue  # many triples lie on one wall
        seen.append(start)
        plane = _plane_through(chosen, cutoff, start[index])
        if plane is None:
            continue
        normal, offset, members = plane
        if one_line_and_lone_shot(chosen[members], LINE_CUTOFFS * cutoff):
            # One raster line and a shot beside it: a plane through a line turns freely about
            # it and the lone shot sets that turn whatever it hit, so the plane measures no
            # surface (a tank's raster column and one lid shot, taken for a wall with the
            # tank's other columns in front of it, left a pipe of a third of its radius).
            continue
        # The refined plane must still have the shots in front and few behind.
        station = float(normal @ view - offset)
        height = (chosen @ normal - offset) * (1.0 if station > 0.0 else -1.0)
        if _background(height[:, None], abs(station), cutoff)[0][0]:
            found = np.zeros(len(points), dtype=bool)
            found[index[members]] = True
            return found
    return None


def _crossing(cylinder, points: np.ndarray, view: np.ndarray, cutoff: float) -> np.ndarray:
    """Which beams from ``view`` (3,) through ``points`` (m, 3) metres meet ``cylinder`` (a
    :class:`~asbuilt.primitives.Cylinder` narrowed by ``cutoff`` metres) from outside, within
    its length widened by ``cutoff``, anywhere along their line beyond the station, shape
    (m,) bool. A beam into an open end meets its inside first, which is not this surface: a
    ray caster lets it through to the wall beyond, a scanner gets the inside's return."""
    radius = cylinder.radius - cutoff
    if len(points) == 0 or radius <= 0.0:
        return np.zeros(len(points), dtype=bool)
    axis = np.asarray(cylinder.axis, dtype=np.float64)
    start = view - np.asarray(cylinder.center, dtype=np.float64)
    beams = points - view
    beams /= np.linalg.norm(beams, axis=1)[:, None]
    along, start_along = beams @ axis, start @ axis
    across = beams - np.outer(along, axis)
    start_across = start - start_along * axis
    a = np.einsum("ij,ij->i", across, across)
    b = across @ start_across
    c = start_across @ start_across - radius**2
    disc = b * b - a * c
    hit = (disc > 0.0) & (a > 1e-15)
    entry = (-b - np.sqrt(np.where(hit, disc, 0.0))) / np.where(hit, a, 1.0)
    # Where the beam enters the infinite cylinder must lie within the pipe's length.
    return (
        hit
        & (entry > 0.0)
        & (np.abs(start_along + entry * along) <= 0.5 * cylinder.length + cutoff)
    )


def _msac(distances: np.ndarray, cutoff: float) -> float:
    """MSAC cost (Torr & Zisserman 2000) of ``distances`` (m,) metres at ``cutoff`` metres."""
    return float(np.minimum(distances**2, cutoff**2).sum())


def _stands(found, points, rest, inliers, view, cutoff, first, out) -> bool:
    """Whether the fit ``found`` of the shots ``rest`` (n,) bool (its ``inliers`` (n,) bool
    among all ``points``) is a pipe consistent with the shots it left out (module docstring),
    and explains the shots off the left-out planes ``out`` (n,) bool better than ``first``."""
    cylinder = found.primitive
    if (
        np.count_nonzero(inliers) < FRONT_SHOTS
        or cylinder.radius <= cutoff  # any line of shots fits a pipe thinner than the cutoff
        or not found.stderr["radius"] <= DETERMINED_RADIUS * cylinder.radius
        or cylinder.radius > PLANE_LIKE * extent_of(points[inliers], cylinder.axis)
    ):
        return False
    if np.count_nonzero(_crossing(cylinder, points[~rest], view, cutoff)) >= CROSSED_SHOTS:
        return False
    # Background lies well off the pipe; a plane through a rough pipe's own silhouette rows
    # (every other shot in front of it) leaves shots a cutoff or two off its refit.
    off = np.abs(cylinder.distance(points[~rest]))
    if np.count_nonzero(off <= FRONT_CUTOFFS * cutoff) > NEAR_SHARE * len(off):
        return False
    if first is None or plane_like(first, points):
        return True
    return (
        _msac(cylinder.distance(points[~out]), cutoff)
        < _msac(first.residuals[~out], cutoff) - cutoff**2
    )


class BackgroundPlaneFit(FitError):
    """A cylinder fit refused: it is nearly a plane and most of its inliers lie on a wall or
    floor with other shots in front of it. Not retried without the sensor's sigma (the shots'
    scatter is not what is wrong; on the review's scenes every such retry that stood was a
    wrong pipe)."""


#: Why a plane-like fit of shots that mostly lie on a background plane is refused.
PLANE_NOT_PIPE = (
    "The cylinder these shots fit best (r {radius}) is nearly a plane over its inliers, and"
    " most of them lie on one plane with other shots in front of it as seen from the station:"
    " a wall or floor behind or under the pipe, not the pipe. No fit of the shots off that"
    " plane stands. Give only the pipe's shots, or rescan with the raster on the pipe."
)


def fit_past_planes(
    fit, points: np.ndarray, view: np.ndarray, sigma, tolerances, first, face_explained=False
):
    """The cylinder fit with background planes left out (module docstring), or None.

    Parameters
    ----------
    fit : callable
        ``fit(points, sigma, tolerances, viewpoint)``, the cylinder fit of a subset that keeps
        its viewpoint (raises FitError otherwise).
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres
        The station.
    sigma : float or None, metres
        The sensor's range noise (None: the prior noise finds the planes).
    tolerances : Tolerances
    first : FitResult or None
        The first fit (None when refused or when it ignored the viewpoint). Nothing is looked
        for unless it is :func:`in_doubt`.
    face_explained : bool
        Whether ``first`` left out a face across the pipe's end after beating a fit of every
        shot (for :func:`in_doubt`: those shots are not in doubt).

    Returns
    -------
    FitResult or None
        The subset's fit as the fit of every shot (residuals over all, the planes' shots not
        inliers), with a note; None when no plane is found or no fit past them stands.

    Raises
    ------
    BackgroundPlaneFit
        When ``first`` is :func:`plane_like`, no fit past the planes stands, and most of its
        inliers lie on the first background plane found (a floor or wall fitted as a pipe).
    """
    if not in_doubt(first, points, sigma, tolerances, face_explained):
        return None
    n = len(points)
    cutoff = tolerances.outlier_cutoff_sigma * segment_noise(sigma, tolerances)
    rng = np.random.default_rng(n)
    left = np.ones(n, dtype=bool)
    first_plane = None
    for _ in range(MOST_PLANES):
        plane = _background_plane(points, view, cutoff, left, rng)
        if plane is None:
            break
        first_plane = plane if first_plane is None else first_plane
        left &= ~plane
        try:
            found = fit(points[left], sigma, tolerances, view)
        except FitError:
            continue
        found, rest = taken_back(
            fit, found, points, left, sigma, tolerances, view, within(points, cutoff)
        )
        inliers = np.zeros(n, dtype=bool)
        inliers[rest] = found.inliers
        if _stands(found, points, rest, inliers, view, cutoff, first, ~left):
            note = (
                f"{int(np.count_nonzero(~rest))} shot(s) on a wall or floor behind, under or"
                " around the pipe (a plane with the pipe's shots in front of it as seen from"
                " the station) were left out as background before the fit."
            )
            result = rescued(found, points, inliers, note)
            left_out = float(np.count_nonzero(~rest))
            diagnostics = {**result.diagnostics, BACKGROUND_PLANE_SHOTS: left_out}
            return dataclasses.replace(result, diagnostics=diagnostics)
    if (
        first is not None
        and first_plane is not None
        and plane_like(first, points)
        # Nearly a plane over its whole extent (kilometres wide), or across its axis only and
        # known to within itself, so it would have been returned: an undetermined first fit
        # a few times its width is refused anyway, and its retry without the sigma may find
        # the pipe.
        and (
            first.stderr["radius"] <= first.primitive.radius
            or first.primitive.radius > PLANE_LIKE * extent_of(points[first.inliers])
        )
        and np.count_nonzero(first_plane & first.inliers) > 0.5 * np.count_nonzero(first.inliers)
        # Nearly a plane in the shots too, not only by its size: a tank seen over a fifth of
        # its width by three raster columns is a few times wider than its shots, and the plane
        # through its outer columns has the middle one in front of it; its curvature (a
        # sagitta of 25 mm at 2 mm noise) was refused as a floor fitted as a pipe.
        and not curvature_measured(
            points[first.inliers], first.residuals[first.inliers], first.sigma, 5
        )
    ):
        shown = radius_text(first.primitive.radius)
        raise BackgroundPlaneFit(PLANE_NOT_PIPE.format(radius=shown))
    return None
