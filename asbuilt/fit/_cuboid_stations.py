"""One box seen from two stations: two linked cuboid objects fitted as one.

A station sees at most two sides of a column (and its top or bottom face at most). To measure
the whole section the operator scans the column again from a second station across it, as a
second object with its own ``station``, and links the two. Fitted apart, each view bounds the
sides it did not see only by its shots' extent (or, with one face seen, assumes the depth), and
merging finds two boxes in one place. Fitted as one object, the shots have no single
viewpoint, and the segmentation, which looks for a frame one station can have seen, took the
two views' faces for one view of a wrong frame or refused them (an independent review: a
0.4 x 0.6 m column scanned front and back came out 0.67 x 0.67 m from one face's shots, or
"not one box").

:func:`fuse_box_views` fits the shots together on the frame the two views agree on: the faces
each view's own fit (with its station) put at least ``MIN_FACE_SHOTS`` inliers on become one
set of faces, fitted jointly with exactly orthogonal axes (:func:`asbuilt.fit.cuboid.fit_cuboid`'s
joint fit, seeded with that frame instead of a segmentation), so that a pair of opposite faces
seen from the two stations measures a size.

Two cuboid fits are one box when their axes agree, matched in any order and sign (within
``SAME_AXES_DEG`` or three combined standard errors), and their boxes overlap along every axis
by more than ``MIN_OVERLAP`` of the shorter extent (two columns side by side do not); a view
that saw one face measured only that face's normal (its in-plane axes come from a rectangle
around its shots). The joint fit stands when it keeps all but ``max_outlier_fraction`` of the
shots, its axes and extent still agree with each view's by the same tests, and each face of a
measured size holds ``MIN_FACE_SHOTS`` shots of its own, off the planes of the other faces (a
second station sees a side up to the edge it shares with the first station's front; shots on
that edge alone would leave the side's offset to nothing).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Cuboid
from asbuilt.tolerances import Tolerances

__all__ = ["MIN_FACE_SHOTS", "MIN_OVERLAP", "SAME_AXES_DEG", "fuse_box_views", "same_box"]

#: Axes closer than this (degrees), or than three combined standard errors, are one direction.
SAME_AXES_DEG = 3.0
#: Shortest overlap along each axis, as a fraction of the shorter of the two boxes' extents.
MIN_OVERLAP = 0.25
#: Inliers a view's fit must put on a face for it to count as seen (three define a plane).
MIN_FACE_SHOTS = 3


@dataclass(frozen=True)
class BoxSeed:
    """The faces to fit (see :func:`asbuilt.fit.cuboid._fit_cuboid_shots`): ``axes`` (3, 3)
    rows, ``face_axis`` (m,) int, ``face_sign`` (m,) +-1, ``face_offset`` (m,) metres from the
    scan frame's origin, ``noise`` metres."""

    axes: np.ndarray
    face_axis: np.ndarray
    face_sign: np.ndarray
    face_offset: np.ndarray
    noise: float


def _reliable(fit: FitResult) -> np.ndarray:
    """The directions (r, 3) a view's fit measured: its three axes, or with one face seen only
    that face's normal (the in-plane axes of a lone face come from a rectangle around its
    shots, not from the box)."""
    assumed = fit.diagnostics.get("assumed_size")
    axes = fit.primitive.axes
    return axes if assumed is None else axes[[int(assumed)]]


def _axes_se(fit: FitResult) -> np.ndarray:
    """The angular standard errors (3,) degrees of the fit's axes (0 where not given)."""
    values = (fit.stderr or {}).get("axes_deg", (0.0, 0.0, 0.0))
    return np.nan_to_num(np.asarray(values, dtype=np.float64), nan=np.inf)


def _frame(one: FitResult, two: FitResult) -> np.ndarray | None:
    """The axes (3, 3) rows both views are fitted in: a view's that saw two faces or more
    (``one``'s first), else the two lone faces' normals when parallel or square to each other
    (within ``SAME_AXES_DEG``); None otherwise."""
    for fit in (one, two):
        if "assumed_size" not in fit.diagnostics:
            return fit.primitive.axes.copy()
    normal, other = _reliable(one)[0], _reliable(two)[0]
    cosine = abs(float(normal @ other))
    if cosine >= np.cos(np.radians(SAME_AXES_DEG)):
        return one.primitive.axes.copy()
    if cosine <= np.sin(np.radians(SAME_AXES_DEG)):
        across = other - (other @ normal) * normal
        across /= np.linalg.norm(across)
        return np.vstack([normal, across, np.cross(normal, across)])
    return None


def _agrees(axes: np.ndarray, fit: FitResult) -> bool:
    """Whether each direction ``fit`` measured lies along one of ``axes`` (3, 3), within
    ``SAME_AXES_DEG`` or three of its standard errors."""
    se = _axes_se(fit)
    assumed = fit.diagnostics.get("assumed_size")
    rows = range(3) if assumed is None else (int(assumed),)
    for row in rows:
        cosine = float(np.abs(axes @ fit.primitive.axes[row]).max())
        angle = np.degrees(np.arccos(min(cosine, 1.0)))
        if not angle <= max(SAME_AXES_DEG, 3.0 * float(se[row])):
            return False
    return True


def _interval(box: Cuboid, axis: np.ndarray) -> tuple[float, float]:
    """The extent (metres) of ``box`` along the unit ``axis`` (3,)."""
    middle = float(box.center @ axis)
    half = 0.5 * float(np.abs(box.axes @ axis) @ box.size)
    return middle - half, middle + half


def same_box(one: FitResult, two: FitResult) -> np.ndarray | None:
    """The common axes (3, 3) of two cuboid fits that are one box (see the module docstring),
    else None."""
    if not (isinstance(one.primitive, Cuboid) and isinstance(two.primitive, Cuboid)):
        return None
    axes = _frame(one, two)
    if axes is None or not (_agrees(axes, one) and _agrees(axes, two)):
        return None
    for axis in axes:
        lo_one, hi_one = _interval(one.primitive, axis)
        lo_two, hi_two = _interval(two.primitive, axis)
        overlap = min(hi_one, hi_two) - max(lo_one, lo_two)
        if not overlap > MIN_OVERLAP * min(hi_one - lo_one, hi_two - lo_two):
            return None
    return axes


def _face_shots(box: Cuboid, points: np.ndarray, width: float, alone: bool = False) -> np.ndarray:
    """How many of ``points`` (m, 3) metres lie within ``width`` metres of each face plane of
    ``box``, nearest it, shape (6,): rows k with outward sign -1, then k with sign +1.
    ``alone``: only shots farther than ``width`` from every other face plane (a shot on the
    edge where two faces meet supports neither)."""
    local = (points - box.center) @ box.axes.T  # (m, 3)
    half = 0.5 * box.size
    distance = np.abs(np.hstack([local + half, local - half]))  # (m, 6)
    order = np.argsort(distance, axis=1)
    rows = np.arange(local.shape[0])
    near = distance[rows, order[:, 0]] <= width
    if alone:
        near &= distance[rows, order[:, 1]] > width
    return np.bincount(order[near, 0], minlength=6)


def seen_faces(fit: FitResult, points: np.ndarray, width: float) -> list[tuple[np.ndarray, float]]:
    """The faces of ``fit``'s cuboid that hold at least ``MIN_FACE_SHOTS`` of its inliers
    within ``width`` metres (with one face seen, that face only): (outward unit normal (3,),
    the face's centre (3,) metres) each. ``points`` (n, 3) metres are the fit's
    shots."""
    box = fit.primitive
    half = 0.5 * box.size
    counts = _face_shots(box, points[fit.inliers], width)
    assumed = fit.diagnostics.get("assumed_size")
    faces = []
    for index in np.flatnonzero(counts >= MIN_FACE_SHOTS).tolist():
        k, sign = index % 3, (1.0 if index >= 3 else -1.0)
        if assumed is not None and k != int(assumed):
            continue  # a lone face's rectangle sides are not faces
        normal = sign * box.axes[k]
        faces.append((normal, box.center + half[k] * normal))
    return faces


def _seed(axes: np.ndarray, faces: list, noise: float) -> BoxSeed | None:
    """The faces (outward normal, centre point) on ``axes`` (3, 3): each on the axis nearest its
    normal, through its centre (a face two views saw: the mean of their offsets); None with
    fewer than two. (The offset is taken along the new normal through the face's centre: the
    view's own offset along its own normal would put the plane kilometres off at survey
    coordinates, where a milliradian between the normals times the distance from the origin
    is metres.)"""
    offsets: dict[tuple[int, float], list[float]] = {}
    for normal, centre in faces:
        cosines = axes @ normal
        k = int(np.abs(cosines).argmax())
        sign = float(np.sign(cosines[k]))
        offsets.setdefault((k, sign), []).append(float(sign * axes[k] @ centre))
    if len(offsets) < 2:
        return None
    keys = sorted(offsets)
    return BoxSeed(
        axes=axes,
        face_axis=np.array([k for k, _ in keys], dtype=np.int64),
        face_sign=np.array([sign for _, sign in keys], dtype=np.float64),
        face_offset=np.array([float(np.mean(offsets[key])) for key in keys]),
        noise=float(noise),
    )


def fuse_box_views(
    one: FitResult,
    two: FitResult,
    points_one: np.ndarray,
    points_two: np.ndarray,
    sigma: float | None,
    tolerances: Tolerances,
) -> FitResult | None:
    """One cuboid fit of two views' shots (``points_one`` then ``points_two``, (n1, 3) and
    (n2, 3) metres, as fitted apart to ``one`` and ``two``), or None when they are not one box
    (:func:`same_box`), together have fewer than two faces, or the joint fit is refused or
    disagrees with either view.

    Method: the faces each view's fit puts at least ``MIN_FACE_SHOTS`` inliers on
    (:func:`seen_faces`) are merged into one frame in ``one``'s axes and fitted as
    :func:`asbuilt.fit.cuboid.fit_cuboid` fits a segmentation's frame (joint orthogonal-distance
    fit with exactly perpendicular axes, Tukey IRLS, least-squares refit on the inliers, sizes
    between opposite faces or from the faces to the shots' extent), without a viewpoint.
    """
    from asbuilt.fit._cuboid_open import open_past_faces
    from asbuilt.fit._cuboid_reach import lower_bounds
    from asbuilt.fit.cuboid import _fit_cuboid_shots

    axes = same_box(one, two)
    if axes is None:
        return None
    cutoff = tolerances.outlier_cutoff_sigma
    faces = [
        *seen_faces(one, points_one, cutoff * max(one.sigma, tolerances.sigma_floor)),
        *seen_faces(two, points_two, cutoff * max(two.sigma, tolerances.sigma_floor)),
    ]
    seed = _seed(axes, faces, max(one.sigma, two.sigma))
    if seed is None:
        return None
    points = np.vstack([points_one, points_two])
    try:
        joint = _fit_cuboid_shots(points, sigma=sigma, tolerances=tolerances, seed=seed)
    except FitError:
        return None
    if not joint.inliers.all():
        width = cutoff * max(joint.sigma, tolerances.sigma_floor)
        joint = open_past_faces(joint, points, width)
    lost = int(np.count_nonzero(~joint.inliers))
    if lost > tolerances.max_outlier_fraction * len(points):
        return None
    if same_box(joint, one) is None or same_box(joint, two) is None:
        return None
    # A size between opposite faces is measured only if each face holds shots of its own: a
    # second station sees a side up to the edge it shares with the first station's front, and
    # a side whose only shots lie on that edge would have its offset set by nothing.
    width = cutoff * max(joint.sigma, tolerances.sigma_floor)
    alone = _face_shots(joint.primitive, points[joint.inliers], width, alone=True)
    for row in np.flatnonzero(joint.observed).tolist():
        if min(alone[row], alone[row + 3]) < MIN_FACE_SHOTS:
            return None
    if any(view.diagnostics.get("unreached_sizes") for view in (one, two)):
        # A view's shots were not a raster reaching its edges (asbuilt.fit._cuboid_reach):
        # nor are the joint fit's, which sees no station to tell.
        joint = lower_bounds(joint, trusted=True)
    return joint
