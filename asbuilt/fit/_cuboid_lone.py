"""Two raster lines and a lone shot: a frame that only the lone shot turns.

Private helper of :mod:`asbuilt.fit._cuboid_sparse`'s :func:`line_split_spread` and of
:func:`asbuilt.fit.cuboid.fit_cuboid`. Two parallel raster lines on a column (one on each of
two faces, or both on one) leave the box free to turn about them: any corner between the
lines fits them. A single further shot then fixes the turn and fits it exactly, whatever it
is: a face through one line and that shot (a plane through a line and a point), or a face of
its own square to the lines' face (its offset fits one shot).
On the clutter benchmark that shot was a floor or wall shot from the next raster column, and
the fit turned the column 23-35 degrees to put it on a face, 1.3-1.6 m wide for 0.45-0.56,
stating the turn to 0.15-0.18 degree. :func:`lone_shot_lines` finds such a fit; the corners between
the lines (:func:`~asbuilt.fit._cuboid_sparse.corner_frames`, their turn held) are then
compared with it with that shot costing nothing in a corner that leaves it out as background
seen past its box (as a shot alone on a face of its own costs nothing in the sparse
comparison, :func:`~asbuilt.fit._cuboid_sparse.rival`). A corner that would put it inside or
in front of its box is still charged for it: there the shot is on the box, and it tells the
frames apart (a sparse benchmark pier's fourth shot on a side, 0.2 degree off at +-0.5).

A fit of one face holding two lines and one shot beyond them across the lines (a floor shot
on the face's plane where it meets the floor) is found the same way (:func:`_one_face_lines`):
the clutter benchmark's column turned 16 degrees at a stated +-6, 0.53 m wide for 0.26.

One raster line and a lone shot: a fit of one face whose shots lie on one line but for one
shot beside it (:func:`one_line_and_lone_shot`) measures neither the face's turn nor its width,
and :func:`asbuilt.fit.cuboid.fit_cuboid` refuses it (:class:`OneLineFace`): on the clutter
benchmark three columns, each with one raster column on the box and a floor shot from the
next, had been fitted 20-47 degrees turned at a stated +-0.1-6.6, 0.46-1.46 m wide for
0.20-0.33 m.
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit import _faces
from asbuilt.fit._cuboid_sparse import on_two_lines
from asbuilt.fit._small_linalg import svd

__all__ = [
    "LONE_SHOTS",
    "OneLineFace",
    "face_through_station",
    "lone_shot_lines",
    "one_line_and_lone_shot",
]

#: Most shots off the two lines a fit may hold and still be taken as set by them: one shot
#: fits the one parameter it sets (the turn, or a face's offset) exactly; a second on the same
#: face would test it.
LONE_SHOTS = 1
#: Fewest shots on each of the two lines (a raster column on a column's face holds 5-15).
LINE_SHOTS = 3


class OneLineFace(FitError):
    """A cuboid fit refused: its one seen face holds one raster line of shots and at most one
    shot beside it (:func:`one_line_and_lone_shot`), or lies in the plane of one raster line's
    sweep through the station (:func:`face_through_station`). Not retried at another noise
    level: the line's shots fix no face at any."""


def _groups(uv: np.ndarray, radius: float, most: int) -> list[np.ndarray] | None:
    """The points ``uv`` (m, 2) metres in groups, each of the points left within ``radius``
    metres of its first, in order; None past ``most`` groups (cheap on a face of many lines)."""
    left = np.ones(uv.shape[0], dtype=bool)
    out = []
    while left.any():
        if len(out) == most:
            return None
        step = uv - uv[int(np.argmax(left))]
        members = np.flatnonzero(left & (np.einsum("ij,ij->i", step, step) <= radius * radius))
        left[members] = False
        out.append(members)
    return out


def lone_shot_lines(trial, x: np.ndarray, width: float):
    """Whether a fit of two or more faces keeps two parallel lines of shots and at most
    ``LONE_SHOTS`` shot(s) beside them on the faces along the lines; for a fit of one face,
    :func:`_one_face_lines`.

    Parameters
    ----------
    trial : tuple
        :func:`asbuilt.fit._joint.fit_frame`'s tuple (model, label (n,), residual (n,) m,
        inliers (n,) bool, ...).
    x : ndarray, shape (n, 3)
        The centred shots, metres.
    width : float
        The inlier cutoff, metres: each line's shots lie within ``2 * width`` across it, the
        lines lie more than ``4 * width`` apart, and a lone shot more than ``3 * width`` from
        every other kept shot (across the lines' direction).

    Returns
    -------
    tuple or None
        (first line's shots (n,) bool, second line's (n,) bool, the lines' unit direction
        (3,), the lone shots (n,) bool), or None. The lines run along one of the frame's axes;
        faces normal to it (a column's top) are left out: their shots do not turn the frame
        about the lines. With two faces or more, a shot on a face holding both lines is no
        lone shot: their plane is fixed without it, and it tests the frame.
    """
    model, label, _, inliers = trial[:4]
    n = x.shape[0]
    if model.offset.shape[0] < 2:
        return _one_face_lines(trial, x, width)
    axis_of = np.where(inliers & (label >= 0), model.face_axis[np.maximum(label, 0)], -1)
    local = x @ model.axes.T  # (n, 3): the shots in the frame
    for k in range(3):
        side = ((axis_of != k) & (axis_of >= 0)).nonzero()[0]
        if side.size < 2 * LINE_SHOTS + 1:
            continue
        uv = local[side][:, [a for a in range(3) if a != k]]
        # Cheap first: two lines and lone shots are at most 2 + LONE_SHOTS clusters along
        # either direction across them (most faces' shots spread across far more).
        gaps = np.diff(np.sort(uv, axis=0), axis=0) > 2 * width
        if gaps.sum(axis=0).max() > 1 + LONE_SHOTS:
            continue
        # (A line within 2 widths across both ways lies within 2.83 of any of its shots.)
        groups = _groups(uv, 3 * width, 2 + LONE_SHOTS)
        if groups is None:
            continue
        lines = [g for g in groups if g.size >= LINE_SHOTS]
        lone = [g for g in groups if g.size == 1]
        if len(lines) != 2 or len(lines) + len(lone) != len(groups):
            continue
        if not 1 <= len(lone) <= LONE_SHOTS:
            continue
        if any(np.ptp(uv[g], axis=0).max() > 2 * width for g in lines):
            continue
        centres = [uv[g].mean(axis=0) for g in lines]
        if np.linalg.norm(centres[0] - centres[1]) <= 4 * width:
            continue
        masks = [np.zeros(n, dtype=bool) for _ in range(3)]
        for mask, g in zip(masks, [*lines, np.concatenate(lone)]):
            mask[side[g]] = True
        faces = [set(label[mask].tolist()) for mask in masks]
        if faces[2] & faces[0] & faces[1]:
            # On a face through both lines, whose plane they fix: the shot tests the frame.
            continue
        return masks[0], masks[1], model.axes[k].copy(), masks[2]
    return None


def _one_face_lines(trial, x: np.ndarray, width: float):
    """:func:`lone_shot_lines` for a fit of one face: its inliers on two parallel lines across
    the face (:func:`~asbuilt.fit._cuboid_sparse.on_two_lines`) but for one shot beyond them
    across the lines, more than ``3 * width`` from every other: a floor or wall shot of the
    next raster column, on the face's plane where that plane meets the floor. Two lines fix
    the face's plane, and the shot lies on it, but as two faces meeting between the lines fit
    the lines as exactly, the shot is then background past their box: it tells the frames
    apart no better than a lone shot beside two faces' lines, and it bounded the face's width.
    (One face on two lines alone is :func:`~asbuilt.fit._cuboid_sparse.on_two_lines`'s.)"""
    model, label, residual, inliers = trial[:4]
    members = inliers.nonzero()[0]
    if members.size < 2 * LINE_SHOTS + LONE_SHOTS:
        return None
    normal = model.normals()[0]
    rel = x[members] - x[members].sum(axis=0) / members.size
    along = svd(rel)[2][0]
    along = along - (along @ normal) * normal
    w = rel @ np.cross(normal, along)
    for end in dict.fromkeys((int(w.argmin()), int(w.argmax()))):
        if np.abs(np.delete(w, end) - w[end]).min() <= 3 * width:
            continue
        kept = inliers.copy()
        kept[members[end]] = False
        direction = on_two_lines((model, label, residual, kept), x, width)
        if direction is None:
            continue
        rest = np.flatnonzero(kept)
        across = x[rest] @ np.cross(normal, direction)
        order = np.argsort(across)
        cut = int(np.diff(across[order]).argmax()) + 1
        masks = [np.zeros(x.shape[0], dtype=bool) for _ in range(3)]
        masks[0][rest[order[:cut]]] = True
        masks[1][rest[order[cut:]]] = True
        masks[2][members[end]] = True
        if min(cut, rest.size - cut) >= LINE_SHOTS:
            return masks[0], masks[1], direction, masks[2]
    return None


def one_line_and_lone_shot(points: np.ndarray, width: float) -> bool:
    """Whether a one-face fit's shots, ``points`` (m, 3) metres (its inliers), lie within
    ``width`` metres (RMS) of one line, but for at most ``LONE_SHOTS`` shot(s) beside it.

    A plane through a line is free to turn about it, and one shot beside the line fixes that
    turn exactly, whatever the shot hit: a face fitted to a single raster column and one
    floor or wall shot from the next column measures neither its turn nor its width. The one
    shot tried as the lone one is the farthest from the line through them all (a shot far off
    a line of shots stays the farthest from their least-squares line, which it pulls by about
    its distance over m).
    """
    if points.shape[0] < 2:
        return False
    for _ in range(LONE_SHOTS):
        if _faces.on_one_line(points, width):
            return True  # (two shots always are: a drop below leaves two or more)
        rel = points - points.sum(axis=0) / points.shape[0]
        along = svd(rel)[2][0]
        across = rel - np.outer(rel @ along, along)
        points = np.delete(points, int(np.argmax(np.einsum("ij,ij->i", across, across))), axis=0)
    return _faces.on_one_line(points, width)


def face_through_station(cuboid, face_axis: int, view: np.ndarray, width: float) -> bool:
    """Whether the plane of a one-face fit's seen face, the side of ``cuboid`` across its axis
    ``face_axis`` nearer ``view`` (3,) metres, passes within ``width`` metres of that station.

    A beam in a face's plane only grazes it, so no shot measures such a face: the shots it holds
    are one raster line's, one sweep of the pan-tilt head through the station, which lie in one
    plane through it whatever they hit (a column's raster column and the floor shots below its
    base, fitted as a face 1.23 m wide for 0.29 on the clutter benchmark).
    """
    normal = cuboid.axes[face_axis]
    toward = float((view - cuboid.center) @ normal)
    return abs(toward) - 0.5 * float(cuboid.size[face_axis]) <= width
