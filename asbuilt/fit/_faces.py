"""Face segmentation for cuboid fitting: local normals, plane hypotheses, an orthogonal frame.

Private helpers of :mod:`asbuilt.fit.cuboid`. Everything is numpy (metres, unit vectors) and
deterministic: the random plane hypotheses come from a fixed-seed generator.

The segmentation is the paper's normal-based method (Kwon et al. 2004, step 1: normals of small
neighbourhoods group the points by face) made robust for sparse rasters whose neighbourhoods
often straddle an edge: each point's local normal and random point triples propose candidate
planes scored by consensus (RANSAC, Fischler and Bolles 1981); the best few first faces are
grown into a cuboid frame (a second face constrained perpendicular to the first and proposed by
point pairs, further faces along the remaining axis or opposite the seen ones), and the frame
explaining the most points wins.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from asbuilt.fit._common import median_spacing, quick_median, row_norms
from asbuilt.fit._cuboid_sparse import SPARSE_SHOTS
from asbuilt.fit._small_linalg import eigh, singular_values
from asbuilt.fit._vectors import cross3, cross_rows, perpendicular_basis, unit_rows

__all__ = [
    "Frame",
    "extra_faces",
    "frame_from",
    "noise_scale",
    "segment",
    "unit_rows",
]

_RNG_SEED = 20040601
_TRIPLES = 100
#: First-face hypotheses tried; after ``_MAX_FIRST`` only while the best frame explains less
#: than ``_ENOUGH`` of the points (two raster lines on different faces also span a plane).
_MAX_FIRST = 3
_MAX_FIRST_HARD = 6
#: First planes kept, and second faces tried per first plane, from at most ``SPARSE_SHOTS``
#: shots (:mod:`asbuilt.fit._cuboid_sparse`): there every triple is a hypothesis.
_SPARSE_FIRST = 40
_SPARSE_SECOND = 12
_ENOUGH = 0.75
_MAX_PAIRS = 150
#: Above this many points, pairwise work is sampled or sorted instead of done on dense
#: matrices (the fit stays linear-ish in the number of points).
_DENSE_LIMIT = 600
_MIN_FACE_POINTS = 3
#: Points enough for a face whose direction two other seen faces fix (only its offset is free).
_MIN_THIRD_FACE_POINTS = 2
#: Share of a plane's consensus points on one face of a built frame for it to be that face.
_SAME_FACE = 0.9
_EYE3 = np.eye(3)
_EYE3.setflags(write=False)
#: ``ndarray.sum``'s own reduction, called directly: the hot paths sum small arrays thousands of
#: times a fit, and the method's Python wrapper costs more than the sum.
_ADD = np.add.reduce
_MAX = np.maximum.reduce
_MIN = np.minimum.reduce
#: A face's points must be spread off a line by this many consensus thresholds (RMS): a raster
#: line lies in every plane through it and would otherwise pass for a face.
_MIN_SPREAD = 1.5
#: Raster steps (along a face seen near grazing) its first shot may lie from the common edge,
#: as ``gap`` allows 1.5 times the points' spacing (:func:`_grazing_gap`).
_EDGE_STEPS = 1.5
#: Below this cosine of incidence (80 degrees) a face's shots get no stretched gap: a plane
#: through the station holds every shot along one raster line's beams, face or not.
_MIN_STRETCHED_COS = math.cos(math.radians(80.0))


@dataclass(frozen=True, eq=False)
class Frame:
    """A segmentation hypothesis: an orthonormal frame and the seen faces.

    Attributes
    ----------
    axes : ndarray, shape (3, 3)
        Rows are orthonormal directions (unit vectors).
    face_axis : ndarray, shape (m,), int
        The row of ``axes`` each face is normal to.
    face_sign : ndarray, shape (m,), float
        +1 or -1: the face's outward normal is ``face_sign * axes[face_axis]``.
    face_offset : ndarray, shape (m,), metres
        Plane offsets: a point x on face f has ``outward_normal . x == face_offset``.
    labels : ndarray, shape (n,), int
        Face index of each point within the consensus threshold of a face, else -1.
    fixed_turn : ndarray, shape (3,), or None
        A unit direction the joint fit may not turn the frame about (None: free to turn
        every way). A corner offered between two parallel raster lines
        (:func:`asbuilt.fit._cuboid_sparse.corner_frames`) is free to turn about them: fitted
        free, it drifts wherever the noise takes it, or away from the lines altogether.
    """

    axes: np.ndarray
    face_axis: np.ndarray
    face_sign: np.ndarray
    face_offset: np.ndarray
    labels: np.ndarray
    fixed_turn: np.ndarray | None = None

    @property
    def n_faces(self) -> int:
        return int(self.face_axis.shape[0])


def noise_scale(points: np.ndarray, normals: np.ndarray, rms: np.ndarray, floor: float) -> float:
    """Noise level (metres) of points on planar faces, without knowing the sensor's sigma.

    The lower quartile of the local plane RMS values is a first guess, but on a sparse raster
    most neighbourhoods straddle an edge; so the guess (capped at 1 cm) only sets a generous
    consensus band for the best plane among the local-normal planes, and the noise is the
    median absolute residual (times 1.4826) of that plane's total least squares refit.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    normals : ndarray, shape (n, 3)
        Local normals (:func:`asbuilt.fit._neighbours.local_normals`).
    rms : ndarray, shape (n,), metres
        Local plane RMS values.
    floor : float, metres
    """
    guess = min(max(float(np.percentile(rms, 25.0)), floor), 0.01)
    band = 3.0 * guess
    offsets = np.einsum("ij,ij->i", normals, points)
    dist = np.abs(normals @ points.T - offsets[:, None])
    best = int(np.argmax((dist < band).sum(axis=1)))
    normal, offset, mask, _ = _batch_refine(
        points, normals[best : best + 1], offsets[best : best + 1], band
    )
    if np.count_nonzero(mask[0]) < 4:
        return guess
    resid = np.abs(points[mask[0]] @ normal[0] - offset[0])
    return float(max(1.4826 * np.median(resid), floor))


def _batch_refine(points, normals, offsets, threshold, basis=None, rounds=2):
    """Re-fit many candidate planes to their consensus sets at once (total least squares).

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    normals : ndarray, shape (c, 3)
        Candidate unit normals.
    offsets : ndarray, shape (c,), metres
    threshold : float, metres
    basis : ndarray, shape (3, 2), or None
        When given, normals stay in the span of its columns (planes containing the missing
        direction).

    Returns
    -------
    normals (c, 3), offsets (c,), masks (c, n) bool, spread (c,) metres
        ``spread`` is the RMS distance of each consensus set from its best-fit line (0 for
        collinear points, which lie in every plane through their line).
    """
    coords = points if basis is None else points @ basis
    dim = coords.shape[1]
    outer = (coords[:, :, None] * coords[:, None, :]).reshape(coords.shape[0], dim * dim)
    last = None  # the previous round's covariances and their eigen-decomposition
    for _ in range(rounds + 1):
        masks = np.abs(normals @ points.T - offsets[:, None]) < threshold
        if _ == rounds and basis is not None:
            break  # only the masks are wanted (no spread within a basis)
        weight = masks.astype(np.float64)
        count = np.maximum(_ADD(weight, axis=1), 1.0)
        mean = weight @ coords / count[:, None]
        second = (weight @ outer).reshape(-1, dim, dim) / count[:, None, None]
        cov = second - mean[:, :, None] * mean[:, None, :]
        if last is None:
            values, vectors = eigh(cov)
        else:
            # A plane whose consensus set stayed put has the same covariance, bit for bit, and
            # so the same decomposition: only the others are decomposed again.
            values, vectors = last[1].copy(), last[2].copy()
            moved = (cov != last[0]).reshape(cov.shape[0], -1).any(axis=1)
            if moved.any():
                values[moved], vectors[moved] = eigh(cov[moved])
        last = (cov, values, vectors)
        if _ == rounds:
            break
        fresh = vectors[:, :, 0] if basis is None else vectors[:, :, 0] @ basis.T
        ok = count >= 3
        normals = np.where(ok[:, None], fresh, normals)
        centre = mean if basis is None else mean @ basis.T
        offsets = np.where(ok, np.einsum("ij,ij->i", normals, centre), offsets)
    if basis is None:
        spread = np.sqrt(np.clip(values[:, 1], 0.0, None))
    else:
        spread = np.full(normals.shape[0], np.inf)
    return normals, offsets, masks, spread


def _distinct(normals, offsets, order, cos_face, threshold, limit):
    """Indices (in ``order``) of up to ``limit`` planes differing in direction or offset."""
    chosen: list[int] = []
    order = np.asarray(order, dtype=np.int64)[: 8 * limit]
    if order.size == 0:
        return chosen
    sub_n, sub_o = normals[order], offsets[order]
    same = (np.abs(sub_n @ sub_n.T) > cos_face) & (
        np.abs(sub_o[:, None] - sub_o[None, :]) < 2 * threshold
    )
    m = order.size
    order = order.tolist()
    # Each row of ``same`` as the bits of one Python int (bit j: column j), so that the greedy
    # pass below is integer arithmetic, not three numpy calls per plane chosen.
    if m <= 64:
        padded = np.zeros((m, 64), bool)
        padded[:, :m] = same
        rows = np.packbits(padded, axis=1, bitorder="little").view(np.uint64)[:, 0].tolist()
    else:
        packed = np.packbits(same, axis=1, bitorder="little")
        rows = None
    alive = (1 << m) - 1
    while len(chosen) < limit and alive:
        pos = (alive & -alive).bit_length() - 1  # the first plane still alive
        chosen.append(order[pos])
        row = rows[pos] if rows is not None else int.from_bytes(packed[pos].tobytes(), "little")
        alive &= ~row
    return chosen


def _first_planes(points, normals, threshold, cos_face, rng, limit=_MAX_FIRST_HARD):
    """Up to ``limit`` distinct refined planes with the largest consensus, best first."""
    n = points.shape[0]
    seeds = np.arange(n) if n <= 200 else rng.choice(n, 200, replace=False)
    if n <= SPARSE_SHOTS:
        tri = np.array(list(itertools.combinations(range(n), 3)), dtype=np.int64)
        limit = _SPARSE_FIRST
    else:
        tri = rng.integers(0, n, size=(_TRIPLES, 3))
    a, b, c = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    cross = cross_rows(b - a, c - a)
    scale = row_norms(b - a) * row_norms(c - a)
    good = row_norms(cross) > 0.05 * np.maximum(scale, 1e-300)
    tri_normals, ok = unit_rows(cross[good])
    cand_n = np.concatenate([normals[seeds], tri_normals[ok]])
    cand_p = np.concatenate([points[seeds], a[good][ok]])
    offsets = np.einsum("ij,ij->i", cand_n, cand_p)
    counts = _ADD(np.abs(cand_n @ points.T - offsets[:, None]) < threshold, axis=1)
    order = (-counts).argsort(kind="stable")
    # Planes with too few points come last in the order: left out before the greedy choice,
    # they could only have been chosen after every plane kept, so the same planes are chosen.
    order = order[counts[order] >= _MIN_FACE_POINTS]
    top = _distinct(cand_n, offsets, order, cos_face, threshold, 4 * limit)
    if not top:
        return []
    ref_n, ref_o, masks, spread = _batch_refine(points, cand_n[top], offsets[top], threshold)
    sizes = _ADD(masks, axis=1)
    usable = (sizes >= _MIN_FACE_POINTS) & (spread >= _MIN_SPREAD * threshold)
    order = [i for i in (-sizes).argsort(kind="stable") if usable[i]]
    keep = _distinct(ref_n, ref_o, order, cos_face, threshold, limit)
    return [(ref_n[i], float(ref_o[i]), masks[i]) for i in keep]


def _second_plane(points, normals, first, threshold, gap, rng, viewpoint=None, every=False):
    """The best plane perpendicular to ``first`` among the points off it, contiguous with it
    (its shots allowed farther from the edge when seen at grazing incidence from a trusted
    ``viewpoint`` (3,) metres: :func:`_grazing_gap`)."""
    d1, o1, mask1 = first
    least = _MIN_THIRD_FACE_POINTS if every else _MIN_FACE_POINTS
    rest = (~mask1).nonzero()[0]  # np.flatnonzero without its wrapper
    if rest.size < least:
        return [] if every else None
    sub = points[rest]
    basis = perpendicular_basis(d1)
    # Point pairs: the plane through both that contains d1 (exactly perpendicular to face 1).
    r = rest.size
    if r > _DENSE_LIMIT:
        # Dense: draw the pairs directly (all pairs of 10,000 points would take 800 MB).
        i, j = rng.integers(0, r, (2, 2 * _MAX_PAIRS))
        distinct = i != j
        i, j = np.minimum(i, j)[distinct][:_MAX_PAIRS], np.maximum(i, j)[distinct][:_MAX_PAIRS]
    elif r * (r - 1) // 2 > _MAX_PAIRS:
        i, j = _pairs(r, rng.choice(r * (r - 1) // 2, _MAX_PAIRS, replace=False))
    else:
        i, j = _pairs(r, np.arange(r * (r - 1) // 2))
    # Local normals made perpendicular to d1.
    # (Dense: the local normals of 200 points at random, as for the first planes.)
    if r <= _DENSE_LIMIT:
        seed_normals, seed_points = normals[rest], sub
    else:
        seeds = rng.choice(r, 200, replace=False)
        seed_normals, seed_points = normals[rest[seeds]], sub[seeds]
    # Both kinds of candidate in one array, pairs first (each row's arithmetic as if apart:
    # fewer numpy calls on a hot path).
    pairs = i.shape[0]
    raw = np.empty((pairs + seed_points.shape[0], 3))
    raw[:pairs] = cross_rows(d1, sub[j] - sub[i])
    raw[pairs:] = seed_normals - (seed_normals @ d1)[:, None] * d1
    length = row_norms(raw)
    unit, ok = unit_rows(raw, length)
    ok[:pairs] &= length[:pairs] > 2 * threshold
    cand_n = unit[ok]
    cand_p = np.concatenate([sub[i], seed_points])[ok]
    found = []
    if cand_n.shape[0] == 0:
        return found if every else None
    first_step: list = []  # face 1's raster step, for every candidate (:func:`_grazing_gap`)
    offsets = np.einsum("ij,ij->i", cand_n, cand_p)
    counts = _ADD(np.abs(cand_n @ sub.T - offsets[:, None]) < threshold, axis=1)
    order = (-counts).argsort(kind="stable")
    order = order[counts[order] >= least]  # as for the first planes: the same ones chosen
    limit = _SPARSE_SECOND if every else 8
    top = np.array(_distinct(cand_n, offsets, order, 0.999, threshold, limit), dtype=np.int64)
    if not top.size:
        return found if every else None
    ref_n, ref_o, masks, _ = _batch_refine(
        sub, cand_n[top], offsets[top], threshold, basis, rounds=1
    )
    sizes = _ADD(masks, axis=1)
    order = (-sizes).argsort(kind="stable")
    order = order[sizes[order] >= least]
    for c in _distinct(ref_n, ref_o, order, 0.999, threshold, limit if every else 5):
        mask = np.zeros(points.shape[0], bool)
        mask[rest[masks[c]]] = True
        face = (ref_n[c], float(ref_o[c]), mask)
        if _contiguous(points, first, face, threshold, gap):
            if not every:
                return face
            found.append(face)
            continue
        if viewpoint is not None:
            # Asked only of a face the plain gap refuses: the grazing allowance is never less.
            wider = _grazing_gap(points, first, face, threshold, gap, viewpoint, first_step)
            if wider > gap and _contiguous(points, first, face, threshold, gap, wider):
                if not every:
                    return face
                found.append(face)
    return found if every else None


def _pairs(r: int, index: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows i < j (each (k,) int) of the pairs at positions ``index`` (k,) int in the
    row-major list of all pairs of r items (``np.triu_indices(r, 1)``'s order), without
    building that list."""
    a = np.arange(r - 1)
    starts = a * (2 * r - a - 1) // 2  # position of pair (a, a + 1)
    row = np.searchsorted(starts, index, "right") - 1
    return row, index - starts[row] + row + 1


def _contiguous(points, face_a, face_b, threshold, gap, gap_b=None) -> bool:
    """Whether two perpendicular faces' points meet at their common edge like a convex corner.

    Each face's points must lie on one side of the other face's plane (within the threshold) and
    come within ``gap`` of it (``gap_b`` for face b's points, when given: :func:`_grazing_gap`).
    """
    pairs = ((face_a, face_b, gap if gap_b is None else gap_b), (face_b, face_a, gap))
    for (na, oa, _), (_, _, mb), allowed in pairs:
        dist = points[mb] @ na - oa
        # Points beyond the threshold on both sides: the largest and smallest distance tell.
        if _MAX(dist) > threshold and _MIN(dist) < -threshold:
            return False
        if _MIN(np.abs(dist)) > allowed:
            return False
    return True


def _grazing_gap(points, face_a, face_b, threshold, gap, viewpoint, step_a=None) -> float:
    """The gap face b's shots may leave to face a's plane, seen from a trusted ``viewpoint``
    (3,) metres: ``gap``, or more when face b is seen near grazing incidence,
    ``threshold + _EDGE_STEPS * r * step / cos(b)`` with ``step`` the raster's angular step
    (the median angle between face a's shots and their nearest neighbours, radians), ``r`` and
    ``cos(b)`` the median range and cosine of incidence of face b's shots.

    A pan-tilt raster's shots on a face seen at incidence theta lie ``r * step / cos(theta)``
    apart, so the first of them beyond the common edge can be that far from it, while ``gap``
    comes from the points' own spacing, mostly the better-seen face's: the one raster column on
    a box's side seen at 76 degrees lay 0.39 m behind the front face (a 0.27 m gap), and the box
    was fitted as its front alone. A line of background shots a metre behind a column is still
    too far: a step there spans decimetres. Face b seen beyond ``_MIN_STRETCHED_COS`` gets
    ``gap``: a plane through the station holds every shot along one raster line's beams.
    ``step_a``, optional: a list that holds face a's step once computed (empty before), so
    that the candidates for face b against one face a share it.
    """
    beams_b = points[face_b[2]] - viewpoint
    ranges = row_norms(beams_b)
    cos_b = quick_median(np.abs(beams_b @ face_b[0]) / ranges)
    seen_a = points[face_a[2]] - viewpoint
    if cos_b < _MIN_STRETCHED_COS or seen_a.shape[0] < 2:
        return gap
    if step_a:
        step = step_a[0]
    else:
        step = median_spacing(seen_a / row_norms(seen_a)[:, None])  # chords of unit vectors
        if step_a is not None:
            step_a.append(step)
    return max(gap, threshold + _EDGE_STEPS * quick_median(ranges) * step / cos_b)


def _orient(axis_vec, offset, inside_points):
    """Sign making the face's outward normal point away from the other faces' points."""
    if inside_points.shape[0] == 0:
        return 1.0
    above = np.count_nonzero(inside_points @ axis_vec > offset)
    return -1.0 if 2 * above > inside_points.shape[0] else 1.0


def extra_faces(points, axes, faces, threshold, gap, viewpoint=None, opposite=True):
    """Add faces along the frame's axes (third face, opposite faces) while they pass the checks.

    ``faces`` is a list of (axis, unsigned offset, mask); returns the grown list. With a trusted
    ``viewpoint`` (3,) a face turned away from it is never added; with ``opposite`` False no
    face across an axis a seen face is already normal to (a frame one station can have seen).
    """
    view_proj = None if viewpoint is None else axes @ viewpoint
    proj_all = None
    while True:
        explained = np.zeros(points.shape[0], bool)
        for _, _, mask in faces:
            explained |= mask
        free = (~explained).nonzero()[0]
        if free.size < _MIN_THIRD_FACE_POINTS:
            return faces
        best = None
        if proj_all is None:
            proj_all = points @ axes.T  # the axes stay: once for every face added
        body = proj_all[explained]  # the seen faces' shots, once for every candidate below
        box = (body, _MIN(body, axis=0), _MAX(body, axis=0)) if body.size else (body, None, None)
        seen_axes = {axis for axis, _, _ in faces}
        free_proj = proj_all[free]
        if free.size <= _DENSE_LIMIT:
            # Every axis's counts at once (:func:`_within`'s dense count, per column).
            # (Axis by axis: (3, m, m) differences, each row a contiguous run.)
            cols = free_proj.T
            diff = np.abs(cols[:, :, None] - cols[:, None, :])
            counts = _ADD(diff < threshold, axis=2)
            peaks = counts.argmax(axis=1).tolist()
            peak_counts = counts[[0, 1, 2], peaks].tolist()
        for k in range(3):
            if not opposite and k in seen_axes:
                continue
            # A face across the one axis no seen face is normal to has only its offset free
            # (the other two fix its direction): two points that agree on it suffice (the top
            # of a pier that a sparse raster crosses once).
            least = (
                _MIN_THIRD_FACE_POINTS
                if k not in seen_axes and len(seen_axes) == 2
                else _MIN_FACE_POINTS
            )
            proj = free_proj[:, k]
            if free.size <= _DENSE_LIMIT:
                c, count = peaks[k], peak_counts[k]
            else:
                within = _within(proj, threshold)
                c = int(within.argmax())
                count = within[c]
            if count < least or (best is not None and count <= best[0]):
                continue
            members = proj[np.abs(proj - proj[c]) < threshold]
            offset = float(_ADD(members)) / members.size  # np.mean's sum and division
            mask = np.zeros(points.shape[0], bool)
            mask[free[np.abs(proj - offset) < threshold]] = True
            if _acceptable(
                proj_all, explained, faces, k, offset, mask, threshold, gap, view_proj, box
            ):
                best = (int(np.count_nonzero(mask)), k, offset, mask)
        if best is None:
            return faces
        faces = faces + [(best[1], best[2], best[3])]


def _within(values: np.ndarray, threshold: float) -> np.ndarray:
    """How many of ``values`` (m,) lie within ``threshold`` of each (itself included); above
    ``_DENSE_LIMIT`` values by sorting (a pair exactly ``threshold`` apart may then round the
    other way)."""
    if values.size <= _DENSE_LIMIT:
        return _ADD(np.abs(values[:, None] - values[None, :]) < threshold, axis=1)
    ordered = np.sort(values)
    return np.searchsorted(ordered, values + threshold, "left") - np.searchsorted(
        ordered, values - threshold, "right"
    )


def _acceptable(
    proj, explained, faces, k, offset, mask, threshold, gap, view_proj=None, box=None
) -> bool:
    """A new face along axis k: not on an occupied side, inside the box, contiguous with a face,
    and (with ``view_proj``, the viewpoint's coordinates (3,)) facing the viewpoint. ``box``:
    ``proj[explained]`` and its least and greatest coordinates (3,), when already computed."""
    if box is None:
        body = proj[explained]
        box = (body, _MIN(body, axis=0), _MAX(body, axis=0)) if body.size else (body, None, None)
    body, body_lo, body_hi = box
    if not body.size:
        return False  # no shot on a seen face yet: no box for the new face to bound or touch
    inside = body[:, k] - offset
    side = -1.0 if 2 * np.count_nonzero(inside > 0) > inside.size else 1.0
    if _MAX(side * inside) > gap:
        # A seen face's shot beyond the new face by more than the shots' spacing, outside the
        # box it would close: one raster row across a column without a sigma had passed for
        # its top, 1.7 m below the highest shots. (Within the spacing: a corner's shots, whose
        # noise along their beams moves them across the edge.)
        return False
    if view_proj is not None and side * (view_proj[k] - offset) <= 0:
        return False
    if sum(1 for axis, _, _ in faces if axis == k) >= 2:
        return False  # a box has two faces across each axis
    for axis, off, fmask in faces:
        if axis != k or not fmask.any():
            continue
        theirs, ours = proj[fmask, k], body[:, k]
        # Means as np.mean computes them (sum, then divide), without its Python overhead.
        other_side = -1.0 if theirs.sum() / theirs.size < ours.sum() / ours.size else 1.0
        if other_side == side or abs(off - offset) < 2 * threshold:
            return False
    new = proj[mask]
    # Outside the seen faces' extent (widened by the gap) along another axis: the least and
    # greatest coordinates tell, as a per-point test would.
    new_lo, new_hi = _MIN(new, axis=0).tolist(), _MAX(new, axis=0).tolist()
    lo, hi = (body_lo - gap).tolist(), (body_hi + gap).tolist()
    for j in range(3):
        if j == k:
            continue
        if new_lo[j] < lo[j] or new_hi[j] > hi[j]:
            return False
    for axis, off, fmask in faces:
        if axis == k or not fmask.any():
            continue
        if np.abs(proj[fmask, k] - offset).min() > gap:
            continue
        if np.abs(new[:, axis] - off).min() > gap:
            continue
        return True
    return False


def is_box(face_axis: np.ndarray, face_sign: np.ndarray, face_offset: np.ndarray) -> bool:
    """Whether faces can be faces of one box: at most two across each axis, and two across
    one axis face opposite ways with the box between them.

    ``face_axis`` (m,) int, ``face_sign`` (m,) +1/-1 and ``face_offset`` (m,) metres as in
    :class:`Frame`.
    """
    axis = face_axis.tolist()  # a handful of faces: plain Python is cheaper than numpy here
    for k in range(3):
        on = [f for f, fk in enumerate(axis) if fk == k]
        if len(on) > 2:
            return False
        if len(on) == 2:
            a, b = on
            if face_sign[a] == face_sign[b]:
                return False
            # outward +axis at axis.x = o+, outward -axis at axis.x = -o-: o+ > -o-
            if face_offset[a] + face_offset[b] <= 0.0:
                return False
    return True


def frame_from(points, axes, faces, threshold, viewpoint) -> Frame:
    """Signs, offsets and labels for faces given as (axis, unsigned offset, mask)."""
    return _frame_and_distances(points, axes, faces, threshold, viewpoint)[0]


def _frame_and_distances(points, axes, faces, threshold, viewpoint):
    """:func:`frame_from`, and each point's distance (n, m) metres to each face plane."""
    m = len(faces)
    face_axis = np.array([f[0] for f in faces], dtype=np.int64)
    face_sign = np.ones(m)
    face_offset = np.zeros(m)
    anyone = np.zeros(points.shape[0], bool)
    for _, _, mask in faces:
        anyone |= mask
    for idx, (k, off, mask) in enumerate(faces):
        others = anyone & ~mask  # the other faces' points, but for this face's own
        if others.any():
            sign = _orient(axes[k], off, points[others])
        else:
            view = np.zeros(3) if viewpoint is None else viewpoint
            sign = 1.0 if axes[k] @ view - off >= 0 else -1.0
        face_sign[idx] = sign
        face_offset[idx] = sign * off
    normals = face_sign[:, None] * axes[face_axis]
    dist = np.abs(points @ normals.T - face_offset[None, :])
    labels = dist.argmin(axis=1)
    labels[dist[np.arange(points.shape[0]), labels] >= threshold] = -1
    return Frame(axes, face_axis, face_sign, face_offset, labels), dist


def _score(distances: np.ndarray, threshold) -> tuple[int, float]:
    """Points within ``threshold`` of a face and minus their squared distances' sum, from the
    distances (n, m) metres of :func:`_frame_and_distances`."""
    dist = distances.min(axis=1)
    kept = dist < threshold
    return int(np.count_nonzero(kept)), -float(_ADD(dist[kept] ** 2))


def _already_a_face(tried_frames, normal, mask, cos_face) -> bool:
    """Whether a plane is (nearly) a face of a frame built from an earlier hypothesis.

    The same face means about the same direction and nearly the same points
    (``_SAME_FACE`` of the plane's consensus ``mask`` (n,) bool on that face): a plane a
    little off a face's direction that also takes in points the frame put on another face
    (the other corner of three raster columns on two narrow faces) is a hypothesis of its own.
    """
    count = max(int(np.count_nonzero(mask)), 1)
    for _, _, frame in tried_frames:
        if frame.n_faces < 2:
            continue
        normals = frame.face_sign[:, None] * frame.axes[frame.face_axis]
        for f in (np.abs(normals @ normal) > cos_face).nonzero()[0]:
            if np.count_nonzero(mask & (frame.labels == f)) >= _SAME_FACE * count:
                return True
    return False


def has_opposite(face_axis) -> bool:
    """Whether faces normal to the axes ``face_axis`` (m,) int put two across one axis."""
    axes = [int(axis) for axis in face_axis]
    return len(set(axes)) < len(axes)


def on_one_line(points: np.ndarray, width: float) -> bool:
    """Whether points (m, 3) metres, m >= 2, lie within ``width`` metres (RMS) of one line: a
    single raster column or row, which lies in every plane through it."""
    rel = points - points.sum(axis=0) / points.shape[0]
    return bool(singular_values(rel)[1] < width * math.sqrt(points.shape[0]))


def _one_station(points, axes, base, grown, threshold, gap) -> list:
    """A frame without opposite faces from a grown one that has them (faces as (axis,
    unsigned offset, mask)).

    A face opposite a seen one whose points also lie in one plane across the axis no face is
    normal to (a single raster line: it lies in every plane through it) is put on that plane
    instead: one line of shots along a side face seen at grazing incidence lies far from the
    near face's edge, beyond the contiguity that :func:`extra_faces` asks of a new face. The
    smaller of two opposite faces is moved first. Otherwise the ``base`` faces are grown again
    without opposite faces.
    """
    faces = list(grown)
    proj = points @ axes.T
    for k in range(3):
        across = [f for f, face in enumerate(faces) if face[0] == k]
        if len(across) < 2:
            continue
        across.sort(key=lambda f: int(np.count_nonzero(faces[f][2])))
        for f in across:
            free = {0, 1, 2} - {face[0] for face in faces}
            if not free:
                break
            members = points[faces[f][2]]
            if members.shape[0] < 2:
                continue
            # One line: within the threshold of it (RMS). The frame's direction may still be
            # off by a fraction of a degree, which tilts a long line across the new plane.
            if on_one_line(members, threshold):
                u = free.pop()
                values = proj[faces[f][2], u]
                faces[f] = (u, float(values.sum()) / values.size, faces[f][2])
                break
    if has_opposite([face[0] for face in faces]):
        return extra_faces(points, axes, base, threshold, gap, None, opposite=False)
    return faces


def _all_facing(points, frame: Frame, viewpoint) -> bool:
    """Whether every face's outward normal points toward the viewpoint."""
    normals = frame.face_sign[:, None] * frame.axes[frame.face_axis]
    for f in range(frame.n_faces):
        members = points[frame.labels == f]
        if members.shape[0] and normals[f] @ (viewpoint - members.sum(axis=0) / len(members)) <= 0:
            return False
    return True


class Segmentation:
    """A cuboid segmentation search that can be taken further (see :func:`segment`).

    :meth:`frames` tries first-face hypotheses until the usual stop (a frame explains every
    point, or ``_MAX_FIRST`` were tried and the best explains ``_ENOUGH`` of them); asked
    again ``exhaustive``, it goes on from there to every first face, without redoing the
    hypotheses already built (same random draws, so the same frames as a fresh exhaustive
    search).
    """

    def __init__(
        self, points, normals, threshold, gap, face_angle_deg, viewpoint=None, visible_only=False
    ):
        self.points, self.normals = points, normals
        self.threshold, self.gap = threshold, gap
        self.viewpoint, self.visible_only = viewpoint, visible_only
        self.rng = np.random.default_rng(_RNG_SEED)
        self.cos_face = float(np.cos(np.radians(face_angle_deg)))
        self.first = _first_planes(points, normals, threshold, self.cos_face, self.rng)
        self.tried = 0  # first planes taken so far
        self.built: list = []  # (score, order, frame)
        self.best_score = None
        self.settled = False  # a plausible frame explains every point

    def _stop(self) -> bool:
        enough = self.best_score is not None and self.best_score[1] >= _ENOUGH * len(self.points)
        return self.settled or (self.tried >= _MAX_FIRST and enough)

    def _build(self, first) -> None:
        points, threshold, gap, viewpoint = self.points, self.threshold, self.gap, self.viewpoint
        d1, o1, mask1 = first
        if _already_a_face(self.built, d1, mask1, self.cos_face):
            return  # it would grow into a frame already built
        trusted = viewpoint if self.visible_only else None
        sparse = len(points) <= SPARSE_SHOTS
        second = _second_plane(
            points, self.normals, first, threshold, gap, self.rng, trusted, every=sparse
        )
        if not sparse:
            second = [] if second is None else [second]
        if not second:
            axes = np.vstack([d1, perpendicular_basis(d1).T])
            self._add(axes, [(0, o1, mask1)])
        for d2, _o2, mask2 in second:
            d2 = d2 - (d2 @ d1) * d1
            d2 /= np.linalg.norm(d2)
            axes = np.vstack([d1, d2, cross3(d1, d2)])
            on2 = points[mask2]
            faces = [(0, o1, mask1), (1, float(d2 @ (on2.sum(axis=0) / len(on2))), mask2)]
            base = faces
            faces = extra_faces(
                points, axes, base, threshold, gap, viewpoint if self.visible_only else None
            )
            if not self.visible_only and has_opposite([face[0] for face in faces]):
                # Without a trusted viewpoint, a line of shots on a side face seen at grazing
                # incidence lies in the plane opposite a seen face as well as in the third
                # axis's, and the greedy growth takes the first: the frame one station can
                # have seen (no opposite faces) is offered too.
                self._add(axes, _one_station(points, axes, base, faces, threshold, gap))
            self._add(axes, faces)

    def _add(self, axes, faces) -> None:
        """Rank and keep the frame of ``faces`` (axis, unsigned offset, mask) on ``axes``."""
        points, threshold, viewpoint = self.points, self.threshold, self.viewpoint
        frame, distances = _frame_and_distances(points, axes, faces, threshold, viewpoint)
        # A frame that cannot be a box (faces on both sides of the points across one axis, or
        # one turned away from a trusted viewpoint) ranks below every frame that can.
        plausible = is_box(frame.face_axis, frame.face_sign, frame.face_offset)
        if self.visible_only and viewpoint is not None:
            plausible = plausible and _all_facing(points, frame, viewpoint)
        score = (plausible,) + _score(distances, threshold)
        self.built.append((score, len(self.built), frame))
        if self.best_score is None or score > self.best_score:
            self.best_score = score
        if score[1] == len(points) and plausible:
            self.settled = True  # no other hypothesis can explain more

    def frames(self, exhaustive: bool = False) -> list[Frame]:
        """Every frame built so far, best first, after searching on (to the usual stop, or
        with ``exhaustive`` through every first face)."""
        while self.tried < len(self.first) and (exhaustive or not self._stop()):
            self.tried += 1
            self._build(self.first[self.tried - 1])
        ranked = sorted(self.built, key=lambda item: (item[0], -item[1]), reverse=True)
        return [frame for _, _, frame in ranked]


def segment(
    points: np.ndarray,
    normals: np.ndarray,
    threshold: float,
    gap: float,
    face_angle_deg: float,
    viewpoint: np.ndarray | None = None,
    visible_only: bool = False,
) -> Frame | None:
    """Find the cuboid frame and seen faces that explain the most points.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    normals : ndarray, shape (n, 3)
        Unoriented local normals (:func:`asbuilt.fit._neighbours.local_normals`).
    threshold : float, metres
        Consensus distance of a point to its face plane.
    gap : float, metres
        How far apart two adjacent faces' points may stop short of their common edge.
    face_angle_deg : float, degrees
        Normals closer than this are the same direction (distinct first-face hypotheses).
    viewpoint : ndarray, shape (3,), metres, or None
        Where the sensor was (default: the origin); orients a single seen face.
    visible_only : bool
        The viewpoint is known to be right: frames with a face turned away from it (impossible
        for points seen from there) rank below every other frame.

    Returns
    -------
    Frame or None
        None when no plane has three points. :class:`Segmentation` gives every frame tried,
        and can search on through every first face (three raster columns on two narrow
        faces are explained by either corner; only shots left out of the segmentation, or
        the fit, can tell).
    """
    frames = Segmentation(
        points, normals, threshold, gap, face_angle_deg, viewpoint, visible_only
    ).frames()
    return frames[0] if frames else None
