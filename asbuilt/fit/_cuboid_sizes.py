"""Cuboid sizes and their standard errors, once the faces' frame is fitted.

Each axis is bounded by its seen faces, else by the extreme inlier padded by half the sampling
step that reached it (:func:`bounds`), or by the raster's silhouette when the points are a
pan-tilt raster (:func:`silhouette_bounds`, through :mod:`asbuilt.fit._silhouette`); one seen
face gets its depth from its in-plane widths (:func:`one_face_depth`). The sizes' and centre's
standard errors are propagated from the joint fit's covariance by finite differences, plus
each extent bound's own noise and the gap it was padded across (:func:`propagate`). The
method's description is step 3 of :mod:`asbuilt.fit.cuboid`.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.fit import _faces, _silhouette
from asbuilt.fit._joint import (
    FaceModel,
    median,
    rodrigues,
)

__all__ = ["bounds", "covariance", "one_face_depth", "propagate", "silhouette_bounds"]


def _spacing(coords: np.ndarray, noise: float) -> float:
    """Median spacing (metres) between raster lines from sorted 1-D coordinates (k,)."""
    if coords.shape[0] < 2:
        return 0.0
    gaps = np.diff(np.sort(coords))
    big = gaps[gaps > max(0.3 * gaps.max(), noise)]
    return median(big) if big.size else 0.0


def _outward_spacing(proj: np.ndarray, extreme: int, k: int, sign: float) -> float | None:
    """Spacing (metres) of the shots leading out to an extreme point along axis ``k``.

    ``proj`` (m, 3): the inliers in the box frame; ``extreme`` indexes the outermost one along
    ``sign * axis k``. The spacing is the distance along the axis to the nearest inlier behind
    it within 45 degrees of the axis (the previous shot of the raster row or bisection that
    reached the edge), None when there is none.
    """
    delta = sign * (proj[extreme, k] - proj[:, k])
    across = [j for j in range(3) if j != k]  # the other two axes (np.delete is slow)
    lateral = _faces.row_norms((proj - proj[extreme])[:, across])
    behind = (delta > 0.0) & (lateral <= delta)
    return float(delta[behind].min()) if behind.any() else None


#: Cosine of the largest angle between a bisection's line and an axis for the bisection to
#: bound that axis (75 degrees).
_ALONG = math.cos(math.radians(75.0))


def _bisected(x, direction, i, edges) -> bool:
    """Whether point ``i`` is an edge-bisection shot whose line runs along ``direction`` (3,).

    The line (through the shot and its partner, the raster shot it started from) must not be
    within 15 degrees of perpendicular to the axis (``_ALONG``): a bisection across the axis
    (a column's top, bisected vertically, seen as the extreme of a horizontal axis near a
    corner) says nothing about that axis's edge. The top face of a pier seen from above is
    bisected along the line of sight, diagonal to both of its axes: it pins whichever far edge
    it ends on.
    """
    if edges is None or edges[0][i] < 0:
        return False
    step = x[i] - x[edges[1][i]]
    length = float(np.linalg.norm(step))
    return length > 0.0 and abs(float(step @ direction)) >= _ALONG * length


def _pinned(x, index, along, sign, axis, edges, tol) -> bool:
    """Whether an edge bisection along ``sign * axis`` ended at the extreme inlier (within tol).

    ``index`` (m,): the inliers; ``along`` (m,): their coordinates along ``axis`` (3,). The
    outermost inlier bisected along the axis (:func:`_bisected`) pins the edge there, to the
    session's tolerance; when it is within ``tol`` (metres: the residual cut, or half the pad
    the extreme would get, whichever is larger) of the extreme inlier, the edge is at the
    extreme: the raster's last hit just crossed the edge the bisection found (a shot on a line
    straddling the edge, its pointing error putting it past the edge). Farther in, it pinned
    another stretch of the silhouette (which need not be straight in angle: a horizontal edge
    seen from below dips towards its nearest point), and the extreme point keeps the raster's
    pad.
    """
    if edges is None:
        return False
    best = None
    for m in (edges[0][index] >= 0).nonzero()[0]:
        if _bisected(x, axis, index[m], edges):
            value = sign * along[m]
            best = value if best is None else max(best, value)
    return best is not None and float(np.max(sign * along)) - best <= tol


def bounds(x, label, inliers, model, noise, edge_pad, edges=None):
    """Per-axis (lo, hi) bounds in the centred frame, which come from faces, and the extreme points.

    An extent bound is the extreme inlier plus ``edge_pad`` times the sampling step there: the
    edge lies within one step past the last hit. Two measures of that step: the median spacing
    of the raster lines along the axis (lines crossing the edge obliquely come closer than a
    whole step) and the spacing of the shots that led out to the extreme point
    (:func:`_outward_spacing`: a few millimetres for an edge-bisection shot, whose bracket
    halves at each step); the smaller one is the finer sampling that reached the edge.

    When the outermost edge-bisection shot along the axis (``edges``: the ``(along, partner)``
    answer of :func:`asbuilt.fit._silhouette.edge_shots`; the line through it and its partner
    within 75 degrees of the axis) is the extreme inlier, or within the residual cut or half
    the pad of it (:func:`_pinned`), the extreme is the bound itself: the session bisects until
    the bracket is a few millimetres across, about the range noise, so no pad is added.

    Returns lo (3,), hi (3,), lo_face (3,) bool, hi_face (3,) bool, lo_point (3,) int, hi_point
    (3,) int (index of the extreme inlier defining an extent bound, -1 for face bounds), pad
    (2, 3) metres (what was added beyond the extreme point: row 0 below lo, row 1 above hi).
    """
    proj = x @ model.axes.T
    lo, hi = np.zeros(3), np.zeros(3)
    lo_face, hi_face = np.zeros(3, bool), np.zeros(3, bool)
    lo_pt, hi_pt = -np.ones(3, np.int64), -np.ones(3, np.int64)
    pads = np.zeros((2, 3))
    index = inliers.nonzero()[0]
    inner = proj[index]
    for k in range(3):
        for f in np.flatnonzero(model.face_axis == k):
            if model.face_sign[f] > 0:
                hi[k], hi_face[k] = model.offset[f], True
            else:
                lo[k], lo_face[k] = -model.offset[f], True
        along = proj[index, k]
        lines = index[model.face_axis[label[index]] != k]
        median = _spacing(proj[lines, k], noise)
        if not hi_face[k]:
            top = int(along.argmax())
            local = _outward_spacing(inner, top, k, 1.0)
            pads[1, k] = edge_pad * (median if local is None else min(local, median))
            if _pinned(x, index, along, 1.0, model.axes[k], edges, max(noise, 0.5 * pads[1, k])):
                pads[1, k] = 0.0
            hi_pt[k] = index[top]
            hi[k] = along.max() + pads[1, k]
        if not lo_face[k]:
            bottom = int(along.argmin())
            local = _outward_spacing(inner, bottom, k, -1.0)
            pads[0, k] = edge_pad * (median if local is None else min(local, median))
            if _pinned(x, index, along, -1.0, model.axes[k], edges, max(noise, 0.5 * pads[0, k])):
                pads[0, k] = 0.0
            lo_pt[k] = index[bottom]
            lo[k] = along.min() - pads[0, k]
    return lo, hi, lo_face, hi_face, lo_pt, hi_pt, pads


def silhouette_bounds(x, origin, model, lo, hi, lo_pt, hi_pt, pad, viewpoint, found, edges):
    """Replace extent bounds (in place: lo, hi, pad) by the raster silhouette solution.

    ``found`` is :func:`asbuilt.fit._silhouette.raster_grid`'s answer for ``viewpoint``. A
    bound an edge-bisection shot reached (``edges``, :func:`asbuilt.fit._silhouette.edge_shots`;
    no pad) is known to the session's tolerance and stays: the window's side beyond it may be
    at the half-step rule, which seen obliquely (a pier's foot from above) can put the edge a
    raster step of angle, most of a metre, away. The
    solution is used only if it cuts off less than half the box's extent along any axis; a
    bound it would put inside an inlier stays at that inlier (a side pinned on a raster line is
    short of the edge by up to a bisection bracket across the beam, more along a face seen at
    grazing incidence). Returns whether it was used.
    """
    pan0, window, _on_grid, pinned, steps = found

    def open_side(k, side):
        point = hi_pt[k] if side else lo_pt[k]
        return point >= 0 and not (pad[side, k] == 0.0 and edges[0][point] >= 0)

    free = [(k, side) for side in (0, 1) for k in range(3) if open_side(k, side)]
    if not free:
        return False
    side_tol = None
    if pinned.any():
        # A side at the half-step rule is uncertain by +-half a step (uniform over the step in
        # which an operator's window edge falls: sd step / sqrt 12); a side at a bisection shot
        # is known to the session's tolerance, far better. Pure rasters keep equal weights.
        side_tol = np.where(pinned, _silhouette._ANGLE_TOL, np.repeat(steps, 2) / np.sqrt(12.0))
    new_lo, new_hi = _silhouette.solve_bounds(
        lo, hi, free, model.axes, origin, viewpoint, pan0, window, side_tol=side_tol
    )
    proj = x @ model.axes.T
    for k, side in free:
        extreme = proj[hi_pt[k], k] if side else proj[lo_pt[k], k]
        beyond = new_hi[k] - extreme if side else extreme - new_lo[k]
        span = hi[k] - lo[k]
        if not np.isfinite(beyond) or beyond < -0.5 * span or beyond > 2.0 * span:
            return False
    for k, side in free:
        if side:
            pad[1, k] = max(new_hi[k] - proj[hi_pt[k], k], 0.0)
            hi[k] = proj[hi_pt[k], k] + pad[1, k]
        else:
            pad[0, k] = max(proj[lo_pt[k], k] - new_lo[k], 0.0)
            lo[k] = proj[lo_pt[k], k] - pad[0, k]
    return True


def one_face_depth(lo, hi, lo_face, hi_face, model):
    """With one seen face: set the unseen depth to the smaller in-plane width, behind the face."""
    k = int(model.face_axis[0])
    widths = [hi[j] - lo[j] for j in range(3) if j != k]
    depth = max(min(widths), 1e-6)
    if hi_face[k]:
        lo[k] = hi[k] - depth
    else:
        hi[k] = lo[k] + depth
    return lo, hi


def _derived(model, x, lo_pt, hi_pt, lo_face, hi_face, pad, one_face):
    """Sizes (3,) and local centre (3,) as a function of the model state (for error propagation)."""
    proj = x @ model.axes.T
    lo, hi = np.zeros(3), np.zeros(3)
    # Called once per parameter by propagate: plain Python over the few faces.
    faces = list(zip(model.face_axis.tolist(), model.face_sign.tolist(), model.offset.tolist()))
    for k in range(3):
        for axis, sign, offset in faces:
            if axis != k:
                continue
            if sign > 0:
                hi[k] = offset
            else:
                lo[k] = -offset
        if not hi_face[k]:
            hi[k] = proj[hi_pt[k], k] + pad[1, k] if hi_pt[k] >= 0 else hi[k]
        if not lo_face[k]:
            lo[k] = proj[lo_pt[k], k] - pad[0, k] if lo_pt[k] >= 0 else lo[k]
    if one_face:
        lo, hi = one_face_depth(lo, hi, lo_face, hi_face, model)
    return np.concatenate([hi - lo, model.axes.T @ (0.5 * (hi + lo))])


def covariance(model, x, label, sigma):
    """Parameter covariance (q + m, q + m): sigma^2 (J^T J)^-1 on the inliers."""
    jac = model.jacobian(x, label)
    return sigma**2 * np.linalg.pinv(jac.T @ jac)


def propagate(model, x, cov, bounds_info, sigma, one_face):
    """Standard errors of sizes (3,) and centre (3,) by finite-difference linear propagation."""
    lo_pt, hi_pt, lo_face, hi_face, pad = bounds_info
    base = _derived(model, x, lo_pt, hi_pt, lo_face, hi_face, pad, one_face)
    q = model.rot_basis.shape[1]
    grads = np.zeros((base.shape[0], cov.shape[0]))
    eps = 1e-7
    for p in range(cov.shape[0]):
        trial = FaceModel(
            model.axes, model.face_axis, model.face_sign, model.offset, model.rot_basis
        )
        if p < q:
            trial.axes = model.axes @ rodrigues(model.rot_basis[:, p] * eps).T
        else:
            trial.offset = model.offset.copy()
            trial.offset[p - q] += eps
        grads[:, p] = (
            _derived(trial, x, lo_pt, hi_pt, lo_face, hi_face, pad, one_face) - base
        ) / eps
    out = grads @ cov @ grads.T
    # An extent bound also carries its defining point's own noise (not in the parameters) and
    # the gap it was padded across: the edge lies anywhere between the extreme point and twice
    # the pad beyond it (uniform: variance pad^2 / 3). Half a raster step for a raster's last
    # line, a few millimetres for an edge-bisection shot.
    extent_var = np.zeros(3)
    for k in range(3):
        extent_var[k] = sigma**2 * ((not lo_face[k]) + (not hi_face[k]))
        extent_var[k] += (pad[0, k] ** 2 * (not lo_face[k]) + pad[1, k] ** 2 * (not hi_face[k])) / 3
    size_var = np.diag(out)[:3] + extent_var
    centre_cov = out[3:, 3:] + model.axes.T @ np.diag(extent_var / 4.0) @ model.axes
    return np.sqrt(size_var), float(np.sqrt(np.trace(centre_cov)))
