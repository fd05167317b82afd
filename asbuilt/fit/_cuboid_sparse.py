"""Cuboid fits from few shots: every plane hypothesis, and frames the shots cannot tell apart.

Private helpers of :mod:`asbuilt.fit.cuboid`. With fewer than ``SPARSE_SHOTS`` shots a box's
faces hold two to six shots each, and a plane through two raster lines on different faces (two
parallel columns are always coplanar) holds as many as a face: the random triples and the
six best first planes of the usual search (:mod:`asbuilt.fit._faces`) then often miss every
true face, and the frame found leaves good shots out. There the segmentation takes every
point triple and more first planes, a second face from two shots (its direction is fixed by
the first face and the pair), and every contiguous second face rather than the first found;
the joint fit then compares every frame (:func:`asbuilt.fit._joint.best_fit`).

Even so, a few shots may fit two frames tens of degrees apart equally well: one raster column
on each of two faces leaves the box free to turn about them (two perpendicular planes, each
through one of two parallel lines, meet anywhere on a circle), and a face holding just two
parallel raster lines may as well be two faces meeting at a corner between them
(:func:`corner_frames` offers that frame). :func:`rival` finds such a frame among the fitted
ones, and the fit is then refused: its standard errors would describe only the frame it
happened to pick.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.errors import FitError

__all__ = [
    "AmbiguousFrame",
    "SPARSE_SHOTS",
    "corner_frames",
    "describe",
    "frame_angle",
    "lone_face_shots",
    "rival",
]

#: At most this many shots is a sparse fit (the accuracy benchmark starts at 20).
SPARSE_SHOTS = 16
#: Frames differing by more than this (degrees, the largest angle between matched axes) are
#: different answers, not the same frame within its noise (sparse fits' axes stray 1-3
#: degrees).
RIVAL_DEG = 5.0
#: A rival's MSAC cost (units of sigma squared) may exceed the winner's by at most this and
#: still fit the shots as well: the chi-square 95% point for three degrees of freedom (the
#: frame's rotation).
RIVAL_COST = 7.81


class AmbiguousFrame(FitError):
    """A sparse cuboid fit refused: its shots fit frames far apart equally well. Not retried
    on a subset of the shots (fewer shots cannot tell the frames apart either)."""


def frame_angle(a: np.ndarray, b: np.ndarray) -> float:
    """The largest angle (degrees) between each row of ``a`` (3, 3) and its nearest row of
    ``b`` (3, 3), up to sign: how far apart two box frames are."""
    cosines = np.abs(a @ b.T).max(axis=1)
    return float(np.degrees(np.arccos(np.clip(cosines.min(), -1.0, 1.0))))


def rival(best, others, costs, counts, admissible) -> tuple | None:
    """A fitted frame that fits the shots as well as ``best`` but lies more than ``RIVAL_DEG``
    from it, or that fits them significantly better (cost lower by more than ``RIVAL_COST``)
    at any angle, or None.

    The second kind has other faces under the shots, so other sizes: the winner was chosen on
    costs that charged a shot alone on a face of its own (:func:`lone_face_shots`; a 0.2 m
    pier's top shot, where the winner put a side's shot on a face of two shots with the top
    shot and left the other out as seen past its box, sizes 23% off with standard errors of
    millimetres).

    Parameters
    ----------
    best : tuple
        The chosen fit (:func:`asbuilt.fit._joint.fit_frame`'s tuple; model first).
    others : list of tuple
        Every fit tried (``best`` among them is skipped).
    costs : callable
        Fit -> MSAC cost over all shots, units of sigma squared.
    counts : callable
        Fit -> shots it rejects that count against it (not background).
    admissible : callable
        Fit -> whether it can be the box (plausible, no face seen edge-on from every shot).

    Returns
    -------
    tuple or None
        (rival fit, angle degrees) of the farthest such frame.
    """
    cost, rejected = costs(best), counts(best)
    found = None
    for trial in others:
        if trial is best or not admissible(trial):
            continue
        if counts(trial) > rejected or costs(trial) > cost + RIVAL_COST:
            continue
        angle = frame_angle(best[0].axes, trial[0].axes)
        # (chi-square test at 95%, as for equally well: significantly better.)
        better = costs(trial) < cost - RIVAL_COST
        if (angle > RIVAL_DEG or better) and (found is None or angle > found[1]):
            found = (trial, angle)
    return found


def lone_face_shots(trial, x: np.ndarray, view: np.ndarray, width: float) -> np.ndarray:
    """Which shots a frame's fit rejects a face of their own can hold, shape (n,) bool.

    A face no other shot reaches holds one shot exactly whatever its offset, so a shot alone on
    a face (the top of a pier hit once) is rejected by the true frame while a frame tens of
    degrees off can turn a seen face onto it and keep it: the shots cannot tell these frames
    apart, and the rival comparison (:func:`rival`) must not count that shot against the true
    one. Such a face is normal to an axis no seen face is normal to, faces the viewpoint
    ``view`` (3,) metres (centred frame), and keeps the box a box: its shots within ``width``
    metres (the inlier cutoff) of its plane and inside every seen face's, every inlier inside
    its own. One face per free axis (the one holding the most rejected shots). ``trial`` is
    :func:`asbuilt.fit._joint.fit_frame`'s tuple, ``x`` (n, 3) metres the centred shots.
    """
    model, _, _, inliers = trial[:4]
    out = np.zeros(x.shape[0], dtype=bool)
    rejected = np.flatnonzero(~inliers)
    if rejected.size == 0 or not inliers.any():
        return out
    # Inside every seen face's plane (a shot past one is not on this box's surface).
    inside = (model.all_residuals(x[rejected]) <= width).all(axis=1)
    candidates = rejected[inside]
    seen = np.bincount(model.face_axis, minlength=3)
    for u in np.flatnonzero(seen == 0):
        along = x @ model.axes[u]
        best = None
        for sign in (1.0, -1.0):
            if sign * float(view @ model.axes[u]) <= 0.0:
                continue
            kept_max = float((sign * along[inliers]).max())
            for i in candidates:
                offset = sign * float(along[i])
                if offset + width < kept_max or sign * float(view @ model.axes[u]) <= offset:
                    continue
                held = candidates[np.abs(sign * along[candidates] - offset) <= width]
                if best is None or held.size > best.size:
                    best = held
        if best is not None:
            out[best] = True
            candidates = candidates[~out[candidates]]
    return out


def describe(angle: float, n: int) -> str:
    """The refusal message for a sparse fit with a rival frame ``angle`` degrees away."""
    if angle <= RIVAL_DEG:
        # A frame that fits significantly better, with other faces under the shots.
        what = (
            f"fit box frames {angle:.0f} degrees apart equally well or better, with other faces "
            "under the shots"
        )
    else:
        what = f"fit box frames {math.floor(angle)} degrees apart equally well"
    return (
        f"cuboid: the {n} shots {what} (too few shots across the faces: e.g. one raster "
        "column on a face leaves the box free to turn about it, and a face hit once fits any "
        "frame); take more shots, at least two columns and two rows on each seen face."
    )


def _two_lines(points: np.ndarray, normal: np.ndarray, width: float):
    """Split a face's points (m, 3) metres on the plane of unit ``normal`` (3,) into two
    parallel lines, each of two points at least and within ``width`` metres across, at least
    ``4 * width`` apart: (line direction (3,), first line's mask (m,) bool), or None."""
    m = points.shape[0]
    for i in range(m - 1):
        for j in range(i + 1, m):
            step = points[j] - points[i]
            step = step - (step @ normal) * normal
            length = float(np.linalg.norm(step))
            if length < 4 * width:
                continue
            direction = step / length
            across = np.cross(normal, direction)
            w = points @ across
            order = np.argsort(w)
            gaps = np.diff(w[order])
            cut = int(gaps.argmax())
            if gaps[cut] < 4 * width or cut < 1 or cut > m - 3:
                continue
            low, high = w[order[: cut + 1]], w[order[cut + 1 :]]
            if np.ptp(low) > 2 * width or np.ptp(high) > 2 * width:
                continue
            first = np.zeros(m, dtype=bool)
            first[order[: cut + 1]] = True
            return direction, first
    return None


def corner_frames(trial, x: np.ndarray, width: float, view: np.ndarray, frame_class) -> list:
    """Frames that split a fitted face holding two parallel lines of shots into two faces
    meeting at a convex corner between them, each face turned 45 degrees from the viewpoint.

    ``trial`` is :func:`asbuilt.fit._joint.fit_frame`'s tuple, ``x`` (n, 3) metres the
    centred shots, ``width`` metres the inlier cutoff, ``view`` (3,) metres the viewpoint
    (centred frame); ``frame_class`` builds the frame
    (:class:`asbuilt.fit._faces.Frame`). Another seen face is kept when its normal lies
    along the lines (the top of a pier whose sides hold one raster column each); the joint
    fit then settles the corner.
    """
    model, label, _, inliers = trial[:4]
    normals = model.normals()
    out = []
    for f in range(model.offset.shape[0]):
        mine = inliers & (label == f)
        if np.count_nonzero(mine) < 4:
            continue
        split = _two_lines(x[mine], normals[f], width)
        if split is None:
            continue
        direction, first = split
        # The corner's bisector points at the viewpoint (across the lines), so both faces
        # face it.
        toward = view - x[mine].mean(axis=0)
        toward = toward - (toward @ direction) * direction
        norm = float(np.linalg.norm(toward))
        if norm == 0.0:
            continue
        toward /= norm
        across = np.cross(toward, direction)
        members = np.flatnonzero(mine)
        a, b = members[first], members[~first]
        if (x[a] @ across).mean() > (x[b] @ across).mean():
            a, b = b, a
        axes = np.vstack(
            [
                (toward - across) / math.sqrt(2.0),
                (toward + across) / math.sqrt(2.0),
                direction,
            ]
        )
        face_axis, face_sign, face_offset = [0, 1], [1.0, 1.0], []
        labels = -np.ones(x.shape[0], dtype=np.int64)
        labels[a], labels[b] = 0, 1
        face_offset = [float((x[a] @ axes[0]).mean()), float((x[b] @ axes[1]).mean())]
        for g in range(model.offset.shape[0]):
            along = float(normals[g] @ direction)
            if g == f or abs(along) < math.cos(math.radians(RIVAL_DEG)):
                continue
            theirs = inliers & (label == g)
            if not theirs.any():
                continue
            sign = 1.0 if along > 0 else -1.0
            labels[theirs] = len(face_axis)
            face_axis.append(2)
            face_sign.append(sign)
            face_offset.append(float((x[theirs] @ (sign * direction)).mean()))
        out.append(
            frame_class(
                axes,
                np.array(face_axis, dtype=np.int64),
                np.array(face_sign),
                np.array(face_offset),
                labels,
            )
        )
    return out
