"""A box's own shots, split from the background a raster window reached past it.

Private helper of the cuboid fit. A rectangular pan-tilt window around a beam seen obliquely
(a diagonal strip in the window), or around a column with a wall close behind, puts most of
its shots on the wall: an independent ray caster's beams 0.15-0.6 m deep with a wall behind
had 20-37 of 50-230 shots on the beam, and the fit took the wall for a face, reporting a box
metres across (57 of 60 such scans) with centimetre standard errors. A file from another
acquisition tool holds such shots; ``asbuilt scan`` drops them (``drivers/raster.py``,
``foreground_threshold``).

From the station, a box fitted to the wall has the beam's shots in front of it: their beams
meet the fitted box farther away than they were measured, which no box can cause (the beam
stops at the first surface it meets). When at least ``FRONT_SHOTS`` shots are so, or the fit
was refused, the shots are cut into surfaces at the range jumps between neighbouring beams
(:func:`asbuilt.fit._cylinder_background.depth_segments`, as for pipes) and the nearest
surfaces are fitted alone. Such a fit stands when every shot it leaves out can only be
background: not in front of the box, its beam not through it, and beyond the box's nearest
point along the beam. Lengths in metres.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.fit._common import median_spacing
from asbuilt.fit._cylinder_background import (
    depth_segments,
    rescued,
    segment_noise,
    subset_fits,
    taken_back,
)
from asbuilt.tolerances import MIN_POINTS

__all__ = [
    "FRONT_SHOTS",
    "MOST_SUBSETS",
    "REACH_SPACINGS",
    "beam_box",
    "behind",
    "contradicting",
    "fit_nearest_box",
    "measured_part",
    "seen_planes",
]

#: A fitted box with this many shots in front of it (along their beams, beyond the inlier
#: cutoff) is a fit of something behind the object: one or two can be a stray return (dust,
#: a wire), three lined up are a surface.
FRONT_SHOTS = 3
#: At most this many subsets of the nearest surfaces are fitted, nearest first.
MOST_SUBSETS = 4
#: A left-out shot on a seen face's plane is taken back within this many of the kept shots'
#: spacings of the box.
REACH_SPACINGS = 3.0
#: Beams within this many of the shots' median angular spacing are raster neighbours (a
#: raster's diagonal is 1.41 steps when its steps are equal).
_CHAIN_STEPS = 1.6


def beam_box(cuboid, points: np.ndarray, view: np.ndarray, shrink: float = 0.0):
    """Where each shot's beam crosses the box (slab method, Kay & Kajiya 1986).

    Parameters
    ----------
    cuboid : Cuboid
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres
        The station.
    shrink : float, metres
        The box is taken this much smaller on every side (not below zero).

    Returns
    -------
    ranges, entry, exit : ndarray, shape (n,), metres
        Each shot's range, and the ranges along its beam where it enters and leaves the box
        (``entry > exit`` where the beam misses it).
    """
    beams = points - view
    ranges = np.linalg.norm(beams, axis=1)
    directions = beams / ranges[:, None]
    half = np.maximum(0.5 * np.asarray(cuboid.size) - shrink, 0.0)
    start = (view - cuboid.center) @ cuboid.axes.T  # (3,) the station in the box's frame
    along = directions @ cuboid.axes.T  # (n, 3)
    with np.errstate(divide="ignore", invalid="ignore"):
        low = (-half - start) / along
        high = (half - start) / along
    near, far = np.fmin(low, high), np.fmax(low, high)
    # A beam parallel to a slab is inside it for every range, or for none.
    parallel = along == 0.0
    inside = np.abs(start) <= half
    near = np.where(parallel, np.where(inside, -np.inf, np.inf), near)
    far = np.where(parallel, np.where(inside, np.inf, -np.inf), far)
    return ranges, near.max(axis=1), far.min(axis=1)


def contradicting(cuboid, points: np.ndarray, view: np.ndarray, cutoff: float) -> np.ndarray:
    """Which shots no beam can have measured if the box were there, shape (n,) bool: more than
    ``cutoff`` metres in front of it along their beams (the beam meets it farther away), or
    that much inside it (the beam stops at its surface)."""
    ranges, entry, leave = beam_box(cuboid, points, view)
    front = (entry < leave) & (leave > 0.0) & (ranges < entry - cutoff)
    return front | (cuboid.distance(points) < -cutoff)


def behind(cuboid, points: np.ndarray, view: np.ndarray, cutoff: float) -> np.ndarray:
    """Which shots can be background seen past the box, shape (n,) bool: more than ``cutoff``
    metres beyond the box's nearest point along their beams, and their beams clear of the box
    taken ``cutoff`` smaller on every side (a beam cannot reach a wall through the box; one
    that grazed its edge and came back from the wall, or a mixed return, passes outside).

    A shot whose beam would meet the box farther on than it was measured lies in front of the
    box, not behind it: something nearer stopped the beam, so it is no background of this box
    (a pier's shots, in front of the floor its fit took for a face).
    """
    ranges, entry, leave = beam_box(cuboid, points, view, cutoff)
    crossing = (entry < leave) & (leave > 0.0)
    through = crossing & (ranges > entry)
    in_front = crossing & (ranges < entry - cutoff)
    directions = (points - view) / ranges[:, None]
    nearest = ((cuboid.corners - view) @ directions.T).min(axis=0)  # (n,)
    return ~through & ~in_front & (ranges > nearest + cutoff)


def measured_part(found, shots: np.ndarray, view: np.ndarray, cutoff: float):
    """The part of a fitted box its shots measured, for the test of which left-out shots lie
    behind it: for a fit that saw one face (its depth set to the smaller visible width, not
    measured), the rectangle its ``shots`` (m, 3) metres (its inliers) span on that face, the
    one facing ``view`` (3,) metres, as a plate ``4 cutoff`` metres deep; the box itself
    otherwise.

    Past its shots a box's edges are padded into the gap up to the next raster line, and a
    one-face box's back is made up: beams through those parts say only that the box ends
    sooner. A column's 82 shots, seen on one face in a window twice its width, fitted 0.52 m
    wide and deep, and the wall shots a raster step beside it passed through the pad and the
    made-up depth (53 of 215), so the column's fit was thrown out and the wall's taken for the
    column (1.3 x 1.3 x 4.9 m for 0.45 x 0.43 x 3.6 m).
    """
    cuboid = found.primitive
    if found.diagnostics.get("faces") != 1:
        # Two or three seen faces: a receding beam's near part, its edge padded into the gap
        # up to its far part (cut off at a range jump), must not take that far part for
        # background (its shots' beams run through the pad, so the next subset is fitted).
        return cuboid
    local = (shots - cuboid.center) @ cuboid.axes.T
    low, high = local.min(axis=0), local.max(axis=0)
    toward = (view - cuboid.center) @ cuboid.axes.T
    # The seen face's normal is the axis whose size the fit assumed, not the axis nearest the
    # beams: a face seen at more than 45 degrees from its normal (a wall-side column from far
    # along the wall) would otherwise have its plate laid across the side it was not seen on.
    k = int(found.diagnostics["assumed_size"])
    front = 0.5 * float(cuboid.size[k]) * np.sign(toward[k])
    low[k], high[k] = sorted((front, front - 4.0 * cutoff * np.sign(toward[k])))
    size = np.maximum(high - low, 4.0 * cutoff)
    middle = 0.5 * (low + high)
    return dataclasses.replace(cuboid, center=cuboid.center + middle @ cuboid.axes, size=size)


def seen_planes(cuboid, points: np.ndarray, cutoff: float) -> list[tuple[np.ndarray, float]]:
    """The planes ``(unit normal (3,), offset metres)`` of the box's faces that at least
    ``FRONT_SHOTS`` of ``points`` (n, 3) metres lie within ``cutoff`` metres of, on the face."""
    planes = []
    for k in range(3):
        normal = cuboid.axes[k]
        along = (points - cuboid.center) @ normal
        for sign in (-1.0, 1.0):
            on = np.abs(along - sign * 0.5 * cuboid.size[k]) <= cutoff
            on &= np.abs(cuboid.distance(points)) <= cutoff
            if np.count_nonzero(on) >= FRONT_SHOTS:
                planes.append((normal, float(normal @ cuboid.center + sign * 0.5 * cuboid.size[k])))
    return planes


def _on_seen_planes(points: np.ndarray, cutoff: float, view: np.ndarray):
    """The cuboid's take-back rule (:func:`~asbuilt.fit._cylinder_background.taken_back`): the
    shots within ``cutoff`` metres of the plane of a face the fit saw (:func:`seen_planes`) and
    within ``REACH_SPACINGS`` of its kept shots' spacing of the box. A beam seen obliquely is
    cut at range jumps along its length, and its far part lies on the near part's faces, a
    raster step or two on; a wall far behind meets those planes only metres away.

    A beam receding from the station (``view`` (3,) metres) has its sides' far part a raster
    step on from the near part but metres off along the beams (seen at 80-88 degrees, each
    step in range is 6-30 times the step across), so a shot on a seen face's plane is also
    taken back when its beam is a raster neighbour (within ``_CHAIN_STEPS`` of the shots'
    median angular spacing) of a shot on that plane already kept or taken, in a chain: the
    face goes on, without a gap in the raster, as far as its shots do."""
    beams = points - view
    units = beams / np.linalg.norm(beams, axis=1)[:, None]
    cosines = np.clip(units @ units.T, -1.0, 1.0)
    np.fill_diagonal(cosines, -1.0)
    step = float(np.median(np.arccos(cosines.max(axis=1))))
    adjacent = cosines >= np.cos(_CHAIN_STEPS * step)

    def nearby(found, mask) -> np.ndarray:
        kept = points[mask][found.inliers]
        near = np.zeros(len(points), dtype=bool)
        planes = seen_planes(found.primitive, kept, cutoff)
        if not planes or len(kept) < 2:
            return near
        reach = REACH_SPACINGS * median_spacing(kept)
        close = found.primitive.distance(points) <= reach
        held = np.zeros(len(points), dtype=bool)
        held[np.flatnonzero(mask)[found.inliers]] = True
        for normal, offset in planes:
            on = np.abs(points @ normal - offset) <= cutoff
            grown = on & (held | close)
            while True:
                more = on & ~grown & adjacent[:, grown].any(axis=1)
                if not more.any():
                    break
                grown |= more
            near |= grown
        return near

    return nearby


def _nearest_first(segments: list, n: int):
    """Masks (n,) bool of the nearest surfaces (``segments``, nearest first): the nearest
    alone, then with the next and so on, each of at least the cuboid's ``MIN_POINTS`` shots
    and leaving the farthest out, at most ``MOST_SUBSETS`` of them."""
    mask = np.zeros(n, dtype=bool)
    made = 0
    for members in segments[:-1]:
        mask = mask.copy()
        mask[members] = True
        if mask.sum() < MIN_POINTS["cuboid"]:
            continue
        yield mask
        made += 1
        if made == MOST_SUBSETS:
            return


def fit_nearest_box(
    fit, points: np.ndarray, view: np.ndarray, sigma, tolerances, contradictions: int
):
    """The cuboid fit of the nearest surfaces' shots, when it leaves out only background;
    else None.

    ``fit(points, sigma, tolerances, viewpoint)`` fits a subset of ``points`` (n, 3) metres as
    seen from ``view`` (3,) metres (``sigma`` the sensor's, metres, or None). The surfaces
    (:func:`~asbuilt.fit._cylinder_background.depth_segments`) are taken nearest first, the
    nearest alone, then with the next and so on (a box face seen at grazing incidence can be cut
    from its front face by a jump of its own), each subset of at least the cuboid's
    ``MIN_POINTS``; shots of the other surfaces on the planes of a subset's box's seen faces are
    taken back and the box fitted again (:func:`_on_seen_planes`). The first fit of whose left-out
    shots fewer than ``FRONT_SHOTS``, and fewer than the ``contradictions`` (shots
    :func:`contradicting` the fit of all of them; a large number for a refused fit), lie
    anywhere but :func:`behind` it stands (a mixed return at a silhouette can pass through a
    box fitted a little wide), its residuals over every shot, with a note.
    """
    n = len(points)
    segments = depth_segments(points, view, segment_noise(sigma, tolerances))
    masks = _nearest_first(segments, n)
    for found, mask, cutoff in subset_fits(fit, points, view, sigma, tolerances, masks):
        found, kept = taken_back(
            fit, found, points, mask, sigma, tolerances, view, _on_seen_planes(points, cutoff, view)
        )
        left_out = ~kept
        measured = measured_part(found, points[kept][found.inliers], view, cutoff)
        wrong = ~behind(measured, points[left_out], view, cutoff)
        if np.count_nonzero(wrong) >= min(FRONT_SHOTS, contradictions):
            continue
        inliers = np.zeros(n, dtype=bool)
        inliers[kept] = found.inliers
        note = (
            f"{int(np.count_nonzero(left_out))} shot(s) lie behind the box along their beams, on "
            "what the raster reached past it (the range jumps there), and were left out as "
            "background before the fit."
        )
        return rescued(found, points, inliers, note, background=int(np.count_nonzero(left_out)))
    return None
