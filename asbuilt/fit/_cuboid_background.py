"""Which shots a cuboid frame leaves out can only be background.

Private helper of the cuboid fit. With a trusted viewpoint and the sensor's noise level, a
first frame whose joint fit rejects only shots that lie where only background can (the wall
behind a column, reached by beams that grazed its edge, or mixed returns between the two)
stands without the exhaustive search of the other frames
(:func:`asbuilt.fit._joint.best_fit`). Lengths in metres.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._robust import DESIGN_CONTAMINATION

__all__ = ["BACKGROUND_SHARE", "FACE_REACH", "FACE_SHOTS", "only_background", "seen_past"]

#: At most this share of the shots may be left out (the cylinder fit's trimmed-cost design
#: contamination).
BACKGROUND_SHARE = DESIGN_CONTAMINATION
#: ... and no this many of them may lie within twice the width of one plane across a box axis:
#: every face of a box is such a plane, so they may be a face the frame left out (a random
#: scatter of mixed returns rarely lines up so).
FACE_SHOTS = 3
#: ... counting, with seen faces across two axes, only the shots within the span of the kept
#: shots along the other two axes widened by this many times that span on either side (a face
#: left out lies within it, a raster step beyond it at most, here a whole box size; the wall
#: behind lies metres off).
FACE_REACH = 1.0


def only_background(axes, face_axis, signed, kept, left_out, n: int, width: float) -> bool:
    """Whether the shots a frame left out can only be background.

    At most ``BACKGROUND_SHARE`` of the ``n`` shots are left out; each lies more than twice
    ``width`` behind every seen face's plane (a plausible frame's faces face the station: a shot
    that grazed the box and came back from the wall, or a mixed return between them, lies
    behind them all; one in front of a face plane, off the box, hit something else first); and
    no ``FACE_SHOTS`` of them lie within twice ``width`` of one plane across a box axis
    (:func:`_near_the_box`; a face the frame left out, a column's top or its side seen at
    grazing incidence, lies behind the other faces' planes too).

    Parameters
    ----------
    axes : ndarray, shape (3, 3)
        The frame's axes (rows, unit).
    face_axis : ndarray, shape (m,), int
        The axis each seen face is normal to.
    signed : ndarray, shape (r, m), metres
        Each left-out shot's signed distance to each seen face's plane, positive on the
        station's side (outward).
    kept : ndarray, shape (k, 3), metres
        The shots the frame keeps.
    left_out : ndarray, shape (r, 3), metres
    n : int
        All the shots.
    width : float, metres
        The fit's inlier cutoff.
    """
    if left_out.shape[0] > BACKGROUND_SHARE * n:
        return False
    if not np.all(signed < -2.0 * width):
        return False
    if left_out.shape[0] < FACE_SHOTS:
        return True
    along = left_out @ axes.T  # (r, 3): along each box axis
    near = _near_the_box(face_axis, kept @ axes.T, along)
    for k in range(3):
        values = np.sort(along[near[:, k], k])
        if values.size < FACE_SHOTS:
            continue
        if np.any(values[FACE_SHOTS - 1 :] - values[: 1 - FACE_SHOTS] <= 2.0 * width):
            return False
    return True


def _near_the_box(face_axis, kept: np.ndarray, along: np.ndarray) -> np.ndarray:
    """Which left-out shots could lie on a face across each box axis that the frame left out,
    shape (r, 3) bool: with seen faces across two axes or more, those within the box's span
    (``FACE_REACH``) along the two other axes; every one otherwise. ``kept`` (k, 3) and
    ``along`` (r, 3), metres: the kept and the left-out shots' coordinates along the box axes.

    A face the frame left out and a station sees (a column's top, a side at grazing incidence)
    lies across an axis no seen face is normal to, within the box's cross-section. Seen faces
    across two axes span the box along every axis with their shots (each from its edge with
    the other), so the shots of such a face lie within that span; a raster row's shots on the
    wall behind lie in one plane across the vertical axis too, but metres off the box. One seen
    face spans nothing along its own normal: there every left-out shot counts.
    """
    if len(set(np.asarray(face_axis).tolist())) < 2:
        return np.ones(along.shape, dtype=bool)
    low, high = kept.min(axis=0), kept.max(axis=0)
    reach = FACE_REACH * (high - low)
    inside = (along >= low - reach) & (along <= high + reach)  # (r, 3)
    near = np.empty(along.shape, dtype=bool)
    for k in range(3):
        near[:, k] = np.all(np.delete(inside, k, axis=1), axis=1)
    return near


def seen_past(signed, ranges, kept_ranges, width: float) -> np.ndarray:
    """Which left-out shots are background seen past the box, shape (r,) bool.

    Such a shot lies more than twice ``width`` behind every seen face's plane and farther from
    the station than every kept shot by as much: its beam went past the box (beside it, or
    through the plane of a face seen at grazing incidence) and returned from behind it, from
    the wall or floor an operator's window takes in around a column. It does not contradict
    the box, so it does not count against the fit's outlier limit (a window a raster step
    wider than a 0.3 m column puts half its shots on the wall).

    Parameters
    ----------
    signed : ndarray, shape (r, m), metres
        Each left-out shot's signed distance to each seen face's plane, positive on the
        station's side (outward).
    ranges : ndarray, shape (r,), metres
        The left-out shots' distances from the station.
    kept_ranges : ndarray, shape (k,), metres
        The kept shots' distances from the station.
    width : float, metres
        The fit's inlier cutoff.
    """
    if kept_ranges.size == 0 or signed.shape[0] == 0:
        return np.zeros(signed.shape[0], dtype=bool)
    behind = np.all(signed < -2.0 * width, axis=1)
    return behind & (ranges > kept_ranges.max() + 2.0 * width)
