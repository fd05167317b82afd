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
from asbuilt.fit._small_linalg import eigh, svd

__all__ = [
    "AmbiguousFrame",
    "SPARSE_SHOTS",
    "corner_frames",
    "corner_fit",
    "describe",
    "equal_fits",
    "frame_angle",
    "line_split_spread",
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


def corner_frames(
    trial,
    x: np.ndarray,
    width: float,
    view: np.ndarray,
    frame_class,
    turns=(0.0,),
    fixed=False,
    lines=None,
) -> list:
    """Frames that split a fitted face holding two parallel lines of shots into two faces
    meeting at a convex corner between them, each face turned 45 degrees from the viewpoint,
    with the corner's bisector then turned by each of ``turns`` (degrees) about the lines (two
    faces through one line each fit every such corner).

    ``trial`` is :func:`asbuilt.fit._joint.fit_frame`'s tuple, ``x`` (n, 3) metres the
    centred shots, ``width`` metres the inlier cutoff, ``view`` (3,) metres the viewpoint
    (centred frame); ``frame_class`` builds the frame
    (:class:`asbuilt.fit._faces.Frame`). Another seen face is kept when its normal lies
    along the lines (the top of a pier whose sides hold one raster column each); the joint
    fit then settles the corner, turning it about the lines too unless ``fixed`` (then each
    frame keeps its turn: the lines cannot set it, and a fit left free to turn about them
    drifts as the noise takes it, on the clutter benchmark's columns often off the lines
    altogether, rejecting every shot). ``lines``, (first line's shots (n,) bool, second's,
    unit direction (3,)), gives the two lines instead, on any of the fit's faces
    (:func:`asbuilt.fit._cuboid_lone.lone_shot_lines`).
    """
    model, label, _, inliers = trial[:4]
    normals = model.normals()
    out = []
    if lines is not None:
        mine = lines[0] | lines[1]
        found = [(-1, mine, lines[2], lines[0][mine])]
    else:
        found = []
        for f in range(model.offset.shape[0]):
            mine = inliers & (label == f)
            if np.count_nonzero(mine) < 4:
                continue
            split = _two_lines(x[mine], normals[f], width)
            if split is not None:
                found.append((f, mine, *split))
    for f, mine, direction, first in found:
        # The corner's bisector points at the viewpoint (across the lines), so both faces
        # face it.
        toward = view - x[mine].mean(axis=0)
        toward = toward - (toward @ direction) * direction
        norm = float(np.linalg.norm(toward))
        if norm == 0.0:
            continue
        toward /= norm
        for turn in turns:
            t = math.radians(turn)
            bisector = math.cos(t) * toward + math.sin(t) * np.cross(direction, toward)
            across = np.cross(bisector, direction)
            members = np.flatnonzero(mine)
            a, b = members[first], members[~first]
            if (x[a] @ across).mean() > (x[b] @ across).mean():
                a, b = b, a
            axes = np.vstack(
                [
                    (bisector - across) / math.sqrt(2.0),
                    (bisector + across) / math.sqrt(2.0),
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
                    direction if fixed else None,
                )
            )
    return out


#: Most parallel lines of shots across two adjacent seen faces whose other splits between the
#: faces are fitted as rivals (:func:`line_split_frames`). Up to three lines every split fits
#: exactly (a frame turning about the lines has one rotation and two offsets); with more, a
#: split is exact no longer but can stay within noise where the lines are close together.
LINE_SPLIT_LINES = 6
#: RMS residual (in inlier cutoffs) across the lines of a split's corner fitted to them by
#: least squares, past which the split is not fitted: a frame that keeps every line's shots
#: within the cutoff leaves them an RMS below one cutoff, and the least-squares corner's RMS
#: is the lowest any corner along the same lines reaches (the margin covers a frame that also
#: tilts the lines' direction). On the accuracy benchmark's clean 40-shot scans 4 splits in 5
#: fail it, none of them a rival that fits as well.
LINE_SPLIT_RMS = 1.0


def _side_faces(model) -> tuple[int, int, int] | None:
    """(face, face, common axis) of a frame's two adjacent seen faces whose common edge is along
    an axis no other face except one across that axis is normal to, or None."""
    per_axis = np.bincount(model.face_axis, minlength=3)
    for k in range(3):
        sides = [f for f in range(model.offset.shape[0]) if model.face_axis[f] != k]
        if len(sides) == 2 and model.face_axis[sides[0]] != model.face_axis[sides[1]]:
            if per_axis[k] <= 1:
                return sides[0], sides[1], k
    return None


def raster_line_groups(trial, x: np.ndarray, width: float):
    """The shots of two adjacent seen faces as parallel lines along their common edge, in
    order across the faces from the first face's far end, round the corner, to the second's.

    Parameters
    ----------
    trial : tuple
        :func:`asbuilt.fit._joint.fit_frame`'s tuple (model, label (n,), residual (n,) m,
        inliers (n,) bool, ...).
    x : ndarray, shape (n, 3)
        The centred shots, metres.
    width : float
        The inlier cutoff, metres: a line's shots lie within ``2 * width`` across it, and
        lines are more than ``4 * width`` apart.

    Returns
    -------
    tuple or None
        (faces (f1, f2), common axis k, list of index arrays, one per line), or None when the
        frame has no such pair of faces, a face's shots are spread across it (not lines), or
        there are more than ``LINE_SPLIT_LINES`` lines.
    """
    model, label, _, inliers = trial[:4]
    if model.offset.shape[0] == 1:
        return _one_face_lines(trial, x, width)
    sides = _side_faces(model)
    if sides is None:
        return None
    f1, f2, k = sides
    i, j = int(model.face_axis[f1]), int(model.face_axis[f2])
    normals = model.normals()
    # The corner: where the two faces' planes meet, in the plane across the common axis.
    corner_i = model.offset[f1] * model.face_sign[f1]
    corner_j = model.offset[f2] * model.face_sign[f2]
    on1, on2 = np.flatnonzero(inliers & (label == f1)), np.flatnonzero(inliers & (label == f2))
    if on1.size == 0 or on2.size == 0 or normals.shape[0] != model.offset.shape[0]:
        return None
    # A walk across the faces: the first face's shots at minus their distance from the
    # corner, the second's at plus theirs.
    members = np.concatenate([on1, on2])
    walk = np.concatenate(
        [-np.abs(x[on1] @ model.axes[j] - corner_j), np.abs(x[on2] @ model.axes[i] - corner_i)]
    )
    return _lines(members, walk, (f1, f2), k, width)


def _lines(members, walk, faces, k, width):
    """:func:`raster_line_groups`' answer from the shots ``members`` (m,) at ``walk`` (m,)
    metres across the lines, or None."""
    order = np.argsort(walk, kind="stable")
    ordered = walk[order]
    # The lines as slices between the cuts (np.split's parts, without its Python overhead).
    cuts = ((ordered[1:] - ordered[:-1]) > 4 * width).nonzero()[0] + 1
    ends = [0, *cuts.tolist(), order.shape[0]]
    parts = list(zip(ends[:-1], ends[1:]))
    lines = [members[order[a:b]] for a, b in parts]
    # (Two lines, one on each face, leave the frame free to turn: the fit's covariance says
    # so, as it cannot for a choice between splits.)
    if len(lines) < 3 or len(lines) > LINE_SPLIT_LINES:
        return None
    for a, b in parts:
        part = ordered[a:b]
        if np.maximum.reduce(part) - np.minimum.reduce(part) > 2 * width:  # np.ptp
            return None  # shots spread across a face: not lines, and they fix its direction
    return faces, k, lines


def _one_face_lines(trial, x: np.ndarray, width: float):
    """:func:`raster_line_groups` for a one-face fit: its shots as lines along the in-plane
    axis they spread along most."""
    model, label, _, inliers = trial[:4]
    on = np.flatnonzero(inliers & (label == 0))
    if on.size < 3:
        return None
    u = int(model.face_axis[0])
    others = [a for a in range(3) if a != u]
    spread = [float(np.ptp(x[on] @ model.axes[a])) for a in others]
    k = others[int(np.argmax(spread))]
    across = others[int(np.argmin(spread))]
    return _lines(on, x[on] @ model.axes[across], (0,), k, width)


def _direction_through(points: np.ndarray, across: np.ndarray) -> np.ndarray:
    """The unit direction (3,) in the plane ``across`` (2, 3) (orthonormal rows) of the line
    that best fits the points' (m, 3) metres projections (total least squares)."""
    plan = points @ across.T
    rel = plan - plan.mean(axis=0)
    _, _, vt = svd(rel)
    return vt[0] @ across


def corner_fit(first: np.ndarray, second: np.ndarray):
    """The two perpendicular lines in a plane that fit two sets of points best by least
    squares, the first set's line and the second's.

    With the first line along the unit direction t and the second along its normal, the sum
    of squares is ``n1 C1 n1 + t C2 t`` (``C`` the sets' scatter matrices about their
    centroids, ``n1`` t turned by 90 degrees), the quadratic form of ``R^T C1 R + C2`` in t:
    its eigenvector of the smallest eigenvalue is t, and that eigenvalue the least sum of
    squares.

    Parameters
    ----------
    first, second : ndarray, shape (m1, 2) and (m2, 2)
        The points, metres (at least one each).

    Returns
    -------
    rms : float
        The least RMS distance of the points to their lines, metres.
    normals : ndarray, shape (2, 2)
        The lines' unit normals (rows: the first's, the second's).
    offsets : ndarray, shape (2,)
        The lines' offsets, metres: a point p on line i has ``normals[i] . p == offsets[i]``.
    """
    quarter = np.array([[0.0, -1.0], [1.0, 0.0]])
    c1, c2 = first.mean(axis=0), second.mean(axis=0)
    d1, d2 = first - c1, second - c2
    values, vectors = eigh(quarter.T @ (d1.T @ d1) @ quarter + d2.T @ d2)
    t = vectors[:, 0]
    normals = np.vstack([quarter @ t, t])
    offsets = np.array([normals[0] @ c1, normals[1] @ c2])
    rms = math.sqrt(max(float(values[0]), 0.0) / (first.shape[0] + second.shape[0]))
    return rms, normals, offsets


def line_split_frames(trial, x: np.ndarray, width: float, view: np.ndarray, frame_class):
    """Frames that split two adjacent seen faces' lines of shots between them otherwise.

    A face holding one or two parallel lines of shots (raster columns on a column's sides)
    lies in a plane through them whatever face its neighbours are on: three lines fit the
    corner between the first and the second or between the second and the third exactly, and
    the fit's covariance, given the split, cannot say so. Each other split of
    :func:`raster_line_groups`' three or more lines (a corner between two consecutive lines)
    gives a frame whose first face runs through the lines on its side (or, holding one line,
    is square to the second face through the lines on the other). Faces across the common
    axis (a top) are kept. Two kinds of split are left out before the fit: one whose lines no
    corner fits within ``LINE_SPLIT_RMS`` cutoffs (:func:`corner_fit`), whose fit could not
    keep them all, and one whose corner, fitted to its lines, lies nearer the chosen split's
    shots (each shot nearer the plane of the face the chosen frame put it on), where the joint
    fit, which assigns each shot to its nearest face, returns to the chosen frame. The joint
    fit then settles each frame, and :func:`rival` compares them with the chosen one.

    Parameters
    ----------
    trial : tuple
        The chosen fit (:func:`asbuilt.fit._joint.fit_frame`'s tuple).
    x : ndarray, shape (n, 3)
        The centred shots, metres.
    width : float
        The inlier cutoff, metres.
    view : ndarray, shape (3,)
        The viewpoint, metres (centred frame): orients a face whose side is not set by the
        other face's shots.
    frame_class : type
        Builds a frame (:class:`asbuilt.fit._faces.Frame`).

    Returns
    -------
    frames : list
        The frames (empty when the faces are not a few lines of shots).
    lined : ndarray, shape (n,), bool
        The shots on the lines (for :func:`contained`).
    along : ndarray, shape (3,), or None
        The lines' unit direction (the chosen frame's axis), None without frames.
    """
    lined = np.zeros(x.shape[0], dtype=bool)
    found = raster_line_groups(trial, x, width)
    if found is None:
        return [], lined, None
    model, label, _, inliers = trial[:4]
    faces, k, lines = found
    lined[np.concatenate(lines)] = True
    along = model.axes[k]
    plan = np.delete(model.axes, k, axis=0)  # (2, 3): the plane across the common edge
    splits = []
    # (One face: every split is another frame.)
    chosen = sum(int(label[line[0]] == faces[0]) for line in lines) if len(faces) == 2 else 0
    on_first = np.zeros(x.shape[0], dtype=bool)  # the chosen split's first face
    if chosen:
        on_first[np.concatenate(lines[:chosen])] = True
    for m in range(1, len(lines)):
        if m == chosen:
            continue  # the chosen frame's own split
        first, second = np.concatenate(lines[:m]), np.concatenate(lines[m:])
        rms, normals, offsets = corner_fit(x[first] @ plan.T, x[second] @ plan.T)
        if rms > LINE_SPLIT_RMS * width:
            continue  # no frame of this split keeps the lines' shots
        if chosen:
            # Each shot to the nearer of the split's corner planes: the chosen split again?
            both = np.concatenate([first, second])
            off = np.abs((x[both] @ plan.T) @ normals.T - offsets)
            if np.array_equal(off[:, 0] < off[:, 1], on_first[both]):
                continue
        if m >= 2:
            splits.append((first, second, _direction_through(x[first], plan)))
        else:
            d2 = _direction_through(x[second], plan)
            splits.append((first, second, np.cross(along, d2)))
    out = []
    for first, second, d1 in splits:
        c1, c2 = x[first].mean(axis=0), x[second].mean(axis=0)
        d1 = d1 - (d1 @ along) * along
        d1 /= np.linalg.norm(d1)
        n1 = np.cross(along, d1)
        # Outward: the other face's shots lie behind each face (a convex corner); where
        # they lie in its plane, the face faces the viewpoint.
        s1 = float(n1 @ (c2 - c1)) or -float(n1 @ (view - c1))
        n1 = -n1 if s1 > 0 else n1
        s2 = float(d1 @ (c1 - c2)) or -float(d1 @ (view - c2))
        n2 = -d1 if s2 > 0 else d1
        face_axis, face_sign = [0, 1], [1.0, 1.0]
        face_offset = [float((x[first] @ n1).mean()), float((x[second] @ n2).mean())]
        labels = -np.ones(x.shape[0], dtype=np.int64)
        labels[first], labels[second] = 0, 1
        for g in range(model.offset.shape[0]):
            if g in faces:
                continue
            sign = float(model.face_sign[g] * (model.axes[model.face_axis[g]] @ along))
            sign = 1.0 if sign > 0 else -1.0
            theirs = inliers & (label == g)
            labels[theirs] = len(face_axis)
            face_axis.append(2)
            face_sign.append(sign)
            face_offset.append(float(model.offset[g]))
        out.append(
            frame_class(
                np.vstack([n1, n2, along]),
                np.array(face_axis, dtype=np.int64),
                np.array(face_sign),
                np.array(face_offset),
                labels,
            )
        )
    return out, lined, along


def contained(trial, x: np.ndarray, width: float, lined: np.ndarray) -> bool:
    """Whether every inlier of a frame's fit among the ``lined`` (n,) bool shots (the lines of
    :func:`line_split_frames`) lies inside every seen face's plane (within ``width`` metres,
    the inlier cutoff): on the surface of a convex box, not past one of its faces (a corner
    turned the wrong way puts one face's shots outside the other). Other inliers may lie on a
    face's plane far past the box (a floor shot on the plane of a column's side). ``trial`` is
    :func:`asbuilt.fit._joint.fit_frame`'s tuple, ``x`` (n, 3) metres the centred shots."""
    model, _, _, inliers = trial[:4]
    if not (inliers & lined).any():
        return False
    return bool((model.all_residuals(x[inliers & lined]) <= width).all())


#: Incidence (degrees) past which a shot's range residual is taken at this angle's cosine: a
#: face seen edge-on would divide by nothing.
_RANGE_INCIDENCE_DEG = 85.0


def range_cost(trial, x: np.ndarray, view: np.ndarray, cap: float, skip=None) -> float:
    """MSAC cost (metres squared, each term capped at ``cap`` squared) of a frame's fit over
    the shots' residuals along their beams from ``view`` (3,) metres (centred frame).

    A range finder's noise lies along the beam, and a shot's distance to its face is that
    error times the cosine of its incidence: the orthogonal cost favours a frame that turns a
    face with many shots toward grazing incidence, though along the beams it fits them no
    better (three raster columns on a column's two faces, split either way, 25 sigma^2 apart
    orthogonally and equal along the beams). ``trial`` is
    :func:`asbuilt.fit._joint.fit_frame`'s tuple, ``x`` (n, 3) metres the centred shots;
    ``skip`` (n,) bool, optional: shots left out of the sum.
    """
    model, label, residual = trial[:3]
    if skip is not None:
        x, label, residual = x[~skip], label[~skip], residual[~skip]
    beams = x - view
    beams /= np.maximum(np.linalg.norm(beams, axis=1), 1e-12)[:, None]
    cosine = np.abs(np.einsum("ij,ij->i", beams, model.normals()[label]))
    cosine = np.maximum(cosine, math.cos(math.radians(_RANGE_INCIDENCE_DEG)))
    return float(np.sum(np.minimum((residual / cosine) ** 2, cap * cap)))


def on_two_lines(trial, x: np.ndarray, width: float) -> np.ndarray | None:
    """The lines' unit direction (3,) when a one-face fit's inliers lie on two parallel lines
    across its face (two raster columns), each within ``2 * width`` metres across and more
    than ``4 * width`` apart, else None: the cheap test before :func:`corner_frames` (which
    tries pairs of shots). ``trial`` is :func:`asbuilt.fit._joint.fit_frame`'s tuple, ``x``
    (n, 3) metres the centred shots."""
    model, _, _, inliers = trial[:4]
    members = x[inliers]
    if model.offset.shape[0] != 1 or members.shape[0] < 4:
        return None
    rel = members - members.mean(axis=0)
    normal = model.normals()[0]
    # Across the lines: the in-plane direction square to the points' longest spread; then
    # again square to the lines' own spread (each line about its own centre). Two lines of
    # unequal reach (a raster column cut short by the floor) tilt the first direction: across
    # it each line spreads over 20 mm and failed the test.
    centred = rel
    for _ in range(2):
        _, _, vt = svd(centred)
        along = vt[0] - (vt[0] @ normal) * normal
        along = along / max(float(np.linalg.norm(along)), 1e-12)
        w = rel @ np.cross(normal, along)
        order = np.argsort(w)
        gaps = np.diff(w[order])
        cut = int(gaps.argmax())
        if gaps[cut] <= 4 * width or not 1 <= cut <= w.size - 3:
            return None
        low, high = order[: cut + 1], order[cut + 1 :]
        if np.ptp(w[low]) <= 2 * width and np.ptp(w[high]) <= 2 * width:
            return along
        centred = rel.copy()
        centred[low] -= rel[low].mean(axis=0)
        centred[high] -= rel[high].mean(axis=0)
    return None


#: Turns (degrees) of the corner between a face's two raster lines (from the bisector facing
#: the viewpoint) at which two faces meeting there are fitted as rivals of the one face: two
#: perpendicular planes, each through one of two parallel lines, meet anywhere on a circle,
#: and only facing the viewpoint with the shots on a convex box bounds the turn.
CORNER_TURNS_DEG = (-30.0, -15.0, 0.0, 15.0, 30.0)
#: The standard error (degrees) of a one-face fit's turn about its two raster lines when two
#: faces meeting between them fit as well: the corner may lie anywhere the faces still face
#: the station, a turn of up to +-90 degrees, uniform: 90 / sqrt(3).
CORNER_TURN_SE_DEG = 52.0


def equal_fits(best, others, costs, counts, admissible) -> list:
    """The fitted frames of ``others`` that fit the shots as well as ``best`` or better (cost
    within ``RIVAL_COST``, no more shots rejected) and are ``admissible``, as (fit, angle
    degrees from ``best``) pairs: where the shots leave the frame free to lie, whatever its
    covariance says (arguments as for :func:`rival`)."""
    cost, rejected = costs(best), counts(best)
    out = []
    for trial in others:
        if trial is best or not admissible(trial):
            continue
        if counts(trial) <= rejected and costs(trial) <= cost + RIVAL_COST:
            out.append((trial, frame_angle(best[0].axes, trial[0].axes)))
    return out


def line_split_spread(
    best,
    split,
    lined,
    along,
    x,
    view,
    cap,
    costs,
    counts,
    plausible,
    fitted,
    frame_class,
    lone=None,
):
    """How far the frames that split a fit's raster lines otherwise lie, when they fit as well.

    Three or more raster lines on two faces (:func:`line_split_frames`, ``split`` their fits)
    split otherwise as exactly, and a face of two lines may as well be two faces meeting
    between them, free to turn (:func:`corner_frames`). Either is an answer the shots cannot
    rule out: rather than refuse the fit (on the cuboid benchmark such rivals stood beside
    fits whose frame was within 2 degrees of the truth twice as often as not), the fit keeps
    its frame and reports their spread as its uncertainty.

    Parameters
    ----------
    best : tuple
        The chosen fit (:func:`asbuilt.fit._joint.fit_frame`'s tuple; its 7th item is whether
        it has one face).
    split : list of tuple
        The fits of :func:`line_split_frames`' frames.
    lined : ndarray, shape (n,), bool
        The shots on the lines (:func:`line_split_frames`).
    along : ndarray, shape (3,), or None
        The lines' unit direction.
    x : ndarray, shape (n, 3)
        The centred shots, metres.
    view : ndarray, shape (3,)
        The viewpoint, metres (centred frame).
    cap : float
        The inlier cutoff, metres.
    costs, counts : callable
        Fit (and optionally shots (n,) bool that cost nothing where it leaves them out as
        background seen past its box) -> cost (units of sigma squared, along the beams with a
        trusted viewpoint) and fit -> shots it rejects that count against it (as for
        :func:`rival`).
    plausible : callable
        Fit -> whether a station can have seen its box.
    fitted : callable
        Frame -> its fit (the joint fit, remembered with the others).
    frame_class : type
        Builds a frame (:class:`asbuilt.fit._faces.Frame`).
    lone : tuple or None
        :func:`asbuilt.fit._cuboid_lone.lone_shot_lines` of ``best``: two lines and a lone
        shot that alone turns the frame about them (passed to ``costs`` as the shots that
        cost nothing where a fit leaves them out as background).

    Returns
    -------
    turn : tuple or None
        (the lines' unit direction (3,), degrees): the turn about the lines to the farthest
        frame that fits as well (``CORNER_TURN_SE_DEG`` for a face of two lines, or two lines
        and a lone shot, that two faces meeting between the lines fit as well), else None.
    rivals : list of tuple
        The fits of the other splits that fit as well (their sizes differ from the fit's), and
        of such corners when a lone shot set the frame (it alone set a size too).
    """

    def admissible(trial, shots) -> bool:
        return plausible(trial) and contained(trial, x, cap, shots)

    found = equal_fits(best, split, costs, counts, lambda trial: admissible(trial, lined))
    turn = max((angle for _, angle in found), default=0.0)
    lines_along = on_two_lines(best, x, cap) if best[6] else None
    if lines_along is not None:
        # One face through two raster lines may as well be two faces meeting between them,
        # each through one line and free to turn about it (that fit's covariance says so).
        frames = corner_frames(best, x, cap, view, frame_class, CORNER_TURNS_DEG, fixed=True)
        corners = [fitted(frame) for frame in frames]
        # Judged by their cost alone (MSAC, which charges each rejected shot the cap): a
        # corner's two planes, each through one line, classify the floor and the wall past the
        # column (background or not) otherwise than the one plane, and one shot more counted
        # against a corner that fits the lines' shots as well kept every such corner out (the
        # clutter benchmark's columns, 13-41 degrees off at a standard error of 0.1-0.3).
        spread = equal_fits(best, corners, costs, lambda t: 0, lambda t: admissible(t, best[3]))
        if spread:
            # Any such corner fits (it meets the lines anywhere on a circle): the turn is
            # unknown, not just as far as the corners tried (the review's columns, 8-43
            # degrees off).
            turn = max(turn, max(angle for _, angle in spread), CORNER_TURN_SE_DEG)
            along = lines_along
    rivals = [trial for trial, _ in found]
    if lines_along is None and lone is not None:
        # Two lines and a lone shot that fits whatever frame turns a face onto it: the corners
        # between the lines are compared with that shot costing nothing where a corner leaves
        # it out as background seen past its box (:mod:`asbuilt.fit._cuboid_lone`).
        frames = corner_frames(
            best, x, cap, view, frame_class, CORNER_TURNS_DEG, fixed=True, lines=lone[:3]
        )
        corners = [fitted(frame) for frame in frames]
        spread = equal_fits(
            best,
            corners,
            lambda trial: costs(trial, lone[3]),
            lambda t: 0,
            # (Every other kept shot, a top's too, inside the turned box.)
            lambda trial: admissible(trial, best[3] & ~lone[3]),
        )
        if spread:
            turn = max(turn, max(angle for _, angle in spread), CORNER_TURN_SE_DEG)
            along = lone[2]
            # The lone shot bounded the face it turned onto: the corners' boxes, each from the
            # lines' shots alone, say how far that size is known.
            rivals += [trial for trial, _ in spread]
    return ((along, turn) if turn > 0.0 else None), rivals
