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

from asbuilt.fit import _silhouette
from asbuilt.fit._common import row_norms
from asbuilt.fit._joint import (
    FaceModel,
    median,
    rodrigues,
)
from asbuilt.fit._small_linalg import pinv, svd

__all__ = [
    "SUBSET_GRAZING_DEG",
    "bounds",
    "covariance",
    "extent_spans",
    "one_face_depth",
    "propagate",
    "raster_gaps",
    "rival_size_spread",
    "silhouette_bounds",
    "single_lines",
]


def _spacing(coords: np.ndarray, noise: float) -> float:
    """Median spacing (metres) between raster lines from sorted 1-D coordinates (k,)."""
    if coords.shape[0] < 2:
        return 0.0
    ordered = coords.copy()  # np.diff(np.sort(coords)) without the wrappers
    ordered.sort()
    gaps = ordered[1:] - ordered[:-1]
    big = gaps[gaps > max(0.3 * np.maximum.reduce(gaps), noise)]
    return median(big) if big.size else 0.0


#: Cosine of the largest angle between a line of shots (a bisection's, or a face's single
#: raster line) and an axis for the line to sample that axis (75 degrees).
_ALONG = math.cos(math.radians(75.0))


def _step(median: float | None, local: float | None, along: np.ndarray) -> float:
    """The sampling step (metres) in which an extent bound's edge lies.

    The finer of the raster lines' median spacing along the axis and the local spacing that
    led out to the extreme inlier (:func:`bounds`), whichever are known (None: not measured);
    with neither, the inliers' extent along the axis (``along`` (m,), metres): nothing
    bounds the edge more closely, and the standard error says so.
    """
    if median is None:
        return float(np.ptp(along)) if local is None else local
    return median if local is None else min(local, median)


#: A face's shots are one line when their spread across it is under this fraction of their
#: spread along it (RMS), or under the residual width: a raster line's shots scatter across it
#: by the pointing noise over the cosine of the incidence (4 mm at 7 m and 74 degrees, more
#: than the faces' residuals) and run along it over the face, decimetres apart; two lines a
#: raster step apart spread across by half a step.
_LINE_RATIO = 0.02


def _single_lines(proj, label, index, model, width) -> list:
    """Per seen face: the direction (3,) of its one line of shots, or None.

    ``proj`` (n, 3): the points in the box frame; ``label`` (n,): their faces; ``index`` (m,):
    the inliers. A face's shots are one line (a single raster column or row: a face at grazing
    incidence) when they lie within ``width`` metres (RMS) of it or spread across it less
    than ``_LINE_RATIO`` times along it; the direction is in the box frame. Faces with fewer than two inliers: None.
    """
    out = []
    for f in range(model.offset.shape[0]):
        members = index[label[index] == f]
        direction = None
        if members.shape[0] >= 2:
            on = proj[members]
            rel = on - np.add.reduce(on, axis=0) / on.shape[0]  # np.mean's sum and division
            _, spread, vt = svd(rel)
            if spread[1] < max(width * math.sqrt(members.shape[0]), _LINE_RATIO * spread[0]):
                direction = vt[0]
        out.append(direction)
    return out


def single_lines(x, label, inliers, model, width) -> list:
    """:func:`_single_lines` of the points ``x`` (n, 3) metres, centred, with their faces
    ``label`` (n,) and ``inliers`` (n,) bool: :func:`bounds` and :func:`extent_spans` take it
    computed once (an SVD per face)."""
    return _single_lines(x @ model.axes.T, label, inliers.nonzero()[0], model, width)


def _line_faces(label, index, model, k, single) -> np.ndarray:
    """The inliers (indices into the points) whose raster lines measure the spacing along ``k``.

    A face normal to axis ``k`` has no extent along it. A face that is one line of shots
    (``single``: :func:`_single_lines`) within 15 degrees of perpendicular to ``k``
    (``_ALONG``) is a single raster line across the axis: its shots share one coordinate along
    ``k`` up to the noise, and their gaps are noise, not a spacing (the next line, where the
    edge could be, is a whole raster step away). A single line along the axis (a column's
    shots up its long axis) or diagonal to it samples the axis and counts.
    """
    keep = np.zeros(label.shape[0], bool)
    for f in (model.face_axis != k).nonzero()[0]:
        if single[f] is not None and abs(single[f][k]) < _ALONG:
            continue
        keep[index[label[index] == f]] = True
    return keep.nonzero()[0]


def _face_spacing(proj, label, index, model, k, extreme, single, noise) -> float | None:
    """The raster lines' median spacing (metres) along axis ``k`` on the extreme inlier's face.

    The lines' spacing differs from face to face (a face seen obliquely spreads them, a pier's
    top seen from above too), and the edge beyond the extreme inlier lies within a step of
    its own face's lines. None when that face is normal to ``k``, is one line of shots across
    ``k`` (:func:`_single_lines`) or shows fewer than two lines along ``k``.
    """
    f = int(label[extreme])
    if model.face_axis[f] == k:
        return None
    if single[f] is not None and abs(single[f][k]) < _ALONG:
        return None
    members = index[label[index] == f]
    value = _spacing(proj[members, k], noise)
    return value if value > 0.0 else None


def _corner_step(proj, label, index, model, k, sign, extreme, single, medians) -> float | None:
    """The raster step (metres) along axis ``k`` on a face that is one line of shots.

    The extreme inlier ``extreme`` (index into the points) along ``sign * axis k`` is on a
    face normal to another axis ``j`` whose shots are one line along the third axis (a column
    of a raster across a face at grazing incidence), and a face normal to ``k`` (the
    neighbour across their common edge) has raster lines spaced ``s = medians[j]`` along
    ``j``. The raster's lines are evenly spaced across the line of sight (``w`` apart), so
    with the neighbour at incidence ``t`` its lines are ``s = w / cos t`` apart and the
    single line's face, at right angles, has lines ``w / sin t`` apart; the step that crossed
    the edge, from the neighbour's line nearest the edge (``a`` from it) to the single line
    (``b`` from it), is ``a cos t + b sin t = w``. So ``tan t = (s - a) / b`` and the
    single-line face's step is ``s b / (s - a)``: longer than ``b``, the more so the nearer
    ``a`` is to a whole step (the edge crossed late in the step). ``s - a`` is kept at least
    a tenth of ``s`` (the noise in ``a``). None when the geometry does not apply.
    """
    f = int(label[extreme])
    j = int(model.face_axis[f])
    direction = single[f]
    if j == k or direction is None or abs(direction[k]) >= _ALONG or abs(direction[j]) >= _ALONG:
        return None
    spacing = medians[j]
    neighbour = (model.face_axis == k).nonzero()[0]
    if spacing is None or spacing <= 0.0 or neighbour.size != 1:
        return None
    g = int(neighbour[0])
    if sign * model.face_sign[g] > 0:
        return None  # the neighbour face is on the extreme's side: no corner between them
    plane_j = model.face_sign[f] * model.offset[f]
    plane_k = model.face_sign[g] * model.offset[g]
    on_neighbour = index[label[index] == g]
    if on_neighbour.size == 0:
        return None
    a = float(np.min(np.abs(proj[on_neighbour, j] - plane_j)))
    b = abs(float(proj[extreme, k]) - plane_k)
    return spacing * b / max(spacing - a, 0.1 * spacing)


def _outward_spacing(proj: np.ndarray, extreme: int, k: int, sign: float) -> float | None:
    """Spacing (metres) of the shots leading out to an extreme point along axis ``k``.

    ``proj`` (m, 3): the inliers in the box frame; ``extreme`` indexes the outermost one along
    ``sign * axis k``. The spacing is the distance along the axis to the nearest inlier behind
    it within 45 degrees of the axis (the previous shot of the raster row or bisection that
    reached the edge), None when there is none.
    """
    delta = sign * (proj[extreme, k] - proj[:, k])
    across = [j for j in range(3) if j != k]  # the other two axes (np.delete is slow)
    lateral = row_norms((proj - proj[extreme])[:, across])
    behind = (delta > 0.0) & (lateral <= delta)
    return float(delta[behind].min()) if behind.any() else None


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


def bounds(x, label, inliers, model, noise, edge_pad, edges=None, single=None):
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
    the bracket is a few millimetres across, about the range noise, so no pad is added. (Or
    until one head position: a scan that records its brackets has the bound moved to the
    middle of the last one and its gap added to the standard error afterwards,
    :mod:`asbuilt.fit._edge_brackets`.)

    ``single``: :func:`single_lines` of these points, when already computed.

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
    if single is None:
        single = _single_lines(proj, label, index, model, noise)
    # None: no raster lines cross the axis on a face along it (a face seen at grazing
    # incidence carries one line only): the spacing there is not measured.
    medians = []
    for k in range(3):
        lines = _line_faces(label, index, model, k, single)
        medians.append(_spacing(proj[lines, k], noise) if lines.size else None)
    for k in range(3):
        for f in (model.face_axis == k).nonzero()[0]:
            if model.face_sign[f] > 0:
                hi[k], hi_face[k] = model.offset[f], True
            else:
                lo[k], lo_face[k] = -model.offset[f], True
        along = proj[index, k]
        for side, sign in ((1, 1.0), (0, -1.0)):
            if (hi_face if side else lo_face)[k]:
                continue
            end = int(along.argmax() if side else along.argmin())
            local = _outward_spacing(inner, end, k, sign)
            if medians[k] is None:
                # The extreme is on a face carrying one line: the step across it follows from
                # the neighbour face's lines (:func:`_corner_step`), else the step behind it.
                corner = _corner_step(
                    proj, label, index, model, k, sign, index[end], single, medians
                )
                local = local if corner is None else max(corner, local or 0.0)
            pads[side, k] = edge_pad * _step(medians[k], local, along)
            tol = max(noise, 0.5 * pads[side, k])
            if _pinned(x, index, along, sign, model.axes[k], edges, tol):
                pads[side, k] = 0.0
            if side:
                hi_pt[k] = index[end]
                hi[k] = along.max() + pads[1, k]
            else:
                lo_pt[k] = index[end]
                lo[k] = along.min() - pads[0, k]
    return lo, hi, lo_face, hi_face, lo_pt, hi_pt, pads


def extent_spans(
    x, label, inliers, model, noise, lo_pt, hi_pt, pad, pinned=None, single=None
) -> np.ndarray:
    """How far (metres) beyond each extent bound's extreme inlier its edge may lie, (2, 3).

    Row 0 below lo, row 1 above hi (0 where a face bounds the side). The pad (:func:`bounds`)
    is half the finer of the steps that reached the edge, the middle of the gap if that step
    is the one the edge lies in. But the raster's lines are spaced differently on each face
    (a face seen obliquely spreads them, a pier's top seen from above too), and the edge
    beyond the extreme inlier lies within a step of its own face's lines
    (:func:`_face_spacing`): the gap is the larger of twice the pad and that step. Only an
    edge-bisection shot narrows it (``pinned`` (2, 3) bool, optional: the sides whose edge
    :func:`bounds` found pinned by one, no pad; their gap stays twice the pad): a raster
    window's solution (:func:`silhouette_bounds`) moves the bound but does not pin it, since
    an operator's window side lies anywhere within a step of the last line of hits, and a
    window side shared by several free bounds does not say which of them reaches it.
    ``noise`` is the residual cut (metres); ``lo_pt``/``hi_pt``/``pad`` as :func:`bounds`
    returns them; ``single``: :func:`single_lines` of these points, when already computed.
    """
    proj = x @ model.axes.T
    index = inliers.nonzero()[0]
    if single is None:
        single = _single_lines(proj, label, index, model, noise)
    spans = 2.0 * np.asarray(pad, dtype=np.float64)
    for k in range(3):
        for side, point in ((0, lo_pt[k]), (1, hi_pt[k])):
            if point < 0 or (pinned is not None and pinned[side, k]):
                continue
            own = _face_spacing(proj, label, index, model, k, int(point), single, noise)
            if own is not None:
                spans[side, k] = max(spans[side, k], own)
    return spans


#: A neighbouring beam meeting the extreme shot's face beyond this incidence (degrees) says
#: nothing about the gap: it runs along the face, and its hit is metres away or none.
_GRAZING_DEG = 85.0
#: The same for a fit without the window (a subset of a raster): there its gaps only widen the
#: bounds' standard errors, and a face seen at 85-88 degrees (a receding beam's far part) has
#: its next raster line metres on, which is the gap.
SUBSET_GRAZING_DEG = 88.0


def raster_gaps(
    x, origin, model, label, lo, hi, lo_pt, hi_pt, viewpoint, found, noise, grazing_deg=None
):
    """The gap (metres) along each axis from an extent bound's extreme shot to the next raster line.

    The shots are a pan-tilt raster seen from ``viewpoint`` (``found``:
    :func:`asbuilt.fit._silhouette.raster_grid`'s answer, its pan and tilt steps). Each of the
    raster's neighbouring beams of the extreme shot (a step of pan, or of tilt, either way)
    meets the shot's face plane somewhere; where that is within the face across the axis
    (between ``lo`` and ``hi`` (3,) along the face's third axis) and beyond the shot along
    ``sign * axis k`` by more than ``noise`` (metres), the beam would have hit the face had it
    reached so far, and did not (the shot is the extreme one; a beam just past the operator's
    window is taken as a miss too, as the window's half-step rule takes it). The edge lies
    between the shot and the nearest such point: the next raster line along that face (the
    review's oblique faces: 0.1-0.35 m). Unlike the lines' spacing (:func:`_face_spacing`),
    this holds on a face whose rows are not at one height (an oblique face's rows climb with
    range) and on a face that is one line of shots.

    ``x`` (n, 3): the points about ``origin`` (3,); ``label`` (n,): their faces; ``lo_pt`` /
    ``hi_pt`` (3,): the extreme shots (:func:`bounds`, -1 at a face bound). Returns (2, 3),
    row 0 below lo and row 1 above hi, NaN where no neighbouring beam meets the face within
    ``grazing_deg`` (default ``_GRAZING_DEG``) of its normal and within it across the axis.
    """
    grazing_deg = _GRAZING_DEG if grazing_deg is None else grazing_deg
    pan0, _window, _on_grid, _pinned, steps = found
    gaps = np.full((2, 3), np.nan)
    # The sides whose extreme shot lies on a face along the axis (k, side, sign, point, face).
    cases = []
    for k in range(3):
        for side, sign, point in ((0, -1.0, lo_pt[k]), (1, 1.0, hi_pt[k])):
            if point < 0:
                continue
            f = int(label[point])
            j = int(model.face_axis[f])
            if j != k:
                cases.append((k, side, sign, int(point), f, j))
    if not cases:
        return gaps
    station = np.asarray(viewpoint, dtype=np.float64) - origin
    k, side, sign, point, f, j = (np.array(column) for column in zip(*cases))
    m = 3 - j - k
    # Each extreme shot's four raster neighbours' beams (pan and tilt a step either way), all
    # cases in one batch: (c, 4) angles, (c, 4, 3) unit beams.
    ang = _silhouette._angles(x[point] + origin, viewpoint, pan0)
    offsets = np.array(
        [[steps[0], 0.0], [-steps[0], 0.0], [0.0, steps[1]], [0.0, -steps[1]]], dtype=np.float64
    )
    pan = ang[:, 0, None] + pan0 + offsets[None, :, 0]
    tilt = ang[:, 1, None] + offsets[None, :, 1]
    beam = np.stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)], axis=-1)
    normal = model.axes[j]  # (c, 3)
    plane = model.face_sign[f] * model.offset[f]  # (c,)
    facing = np.einsum("cbi,ci->cb", beam, normal)
    # Along the face (beyond _GRAZING_DEG): its hit says nothing about the edge.
    usable = np.abs(facing) >= math.cos(math.radians(grazing_deg))
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = (plane - normal @ station)[:, None] / facing
    usable &= reach > 0.0
    hit = (station + np.where(usable, reach, 0.0)[:, :, None] * beam) @ model.axes.T
    rows = np.arange(len(cases))
    across = hit[rows[:, None], np.arange(4)[None, :], m[:, None]]
    # Past the face's side: a miss there bounds nothing along k.
    usable &= (lo[m][:, None] <= across) & (across <= hi[m][:, None])
    proj = np.einsum("ci,ci->c", x[point], model.axes[k])
    advance = sign[:, None] * (
        hit[rows[:, None], np.arange(4)[None, :], k[:, None]] - proj[:, None]
    )
    usable &= advance > noise
    nearest = np.where(usable, advance, np.inf).min(axis=1)
    gaps[side, k] = np.where(np.isfinite(nearest), nearest, np.nan)
    return gaps


def _touched_sides(x, origin, viewpoint, found) -> np.ndarray:
    """Which raster window sides (4,) bool an edge-bisection shot placed.

    ``found`` as :func:`asbuilt.fit._silhouette.raster_grid` returns it for the points
    ``x + origin`` (x (n', 3), its first n rows the shots it read; mended rows after them). A
    side is placed by bisection when it is pinned at a bisection hit, or put on the raster's
    last line (a bisection hit just inside it) instead of half a step beyond: either way the
    silhouette is known there to the session's tolerance, not to a raster step.
    """
    pan0, window, on_grid, pinned, steps = found
    ang = _silhouette._angles(x[: on_grid.shape[0]][on_grid] + origin, viewpoint, pan0)
    rule = np.array(
        [
            ang[:, 0].min() - 0.5 * steps[0],
            ang[:, 0].max() + 0.5 * steps[0],
            ang[:, 1].min() - 0.5 * steps[1],
            ang[:, 1].max() + 0.5 * steps[1],
        ]
    )
    return pinned | (np.abs(window - rule) > 0.05 * np.repeat(steps, 2))


def silhouette_bounds(
    x, origin, model, lo, hi, lo_pt, hi_pt, pad, viewpoint, found, edges, gaps=None, fixed=None
):
    """Replace extent bounds (in place: lo, hi, pad) by the raster silhouette solution.

    ``found`` is :func:`asbuilt.fit._silhouette.raster_grid`'s answer for ``viewpoint``. A
    bound an edge-bisection shot reached (``edges``, :func:`asbuilt.fit._silhouette.edge_shots`;
    no pad) is known to the session's tolerance and stays: the window's side beyond it may be
    at the half-step rule, which seen obliquely (a pier's foot from above) can put the edge a
    raster step of angle, most of a metre, away. The
    solution is used only if it cuts off less than half the box's extent along any axis; a
    bound it would put at or inside its extreme inlier keeps the extent rule's pad (``pad`` as
    :func:`bounds` set it): nothing pins that edge, which lies anywhere in the gap up to the
    next raster line beyond the last hit (along a face seen obliquely, 0.1-0.35 m). Clamping
    such a bound to the inlier, with no pad, had reported it to the range noise: an
    independent review's cabinet 1.255 m high came out 1.117 +- 0.003 m. With ``gaps`` (2, 3)
    (:func:`raster_gaps`) known for that side, its pad is half the gap instead. But where the
    bound moves a window side that an edge-bisection shot placed (:func:`_touched_sides`: by
    a tenth of a raster step or more as it crosses its gap), the solution is known to the
    session's tolerance: it stands, pad 0 included, and the side is marked in ``fixed`` (2, 3)
    bool, optional, in place (no gap beyond it: :func:`extent_spans`). Returns whether the
    solution was used.
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
    touched = _touched_sides(x, origin, viewpoint, found)
    # The solved box and, per free bound, the box with that bound moved across its gap (one
    # batch): which window sides each bound moves.
    los = np.repeat(new_lo[None], len(free) + 1, axis=0)
    his = np.repeat(new_hi[None], len(free) + 1, axis=0)
    for c, (k, side) in enumerate(free):
        reach = 2.0 * pad[side, k]
        if gaps is not None and np.isfinite(gaps[side, k]):
            reach = max(reach, gaps[side, k])
        if side:
            his[c + 1, k] += reach
        else:
            los[c + 1, k] -= reach
    extents = _silhouette._extents(los, his, model.axes, origin, viewpoint, pan0)
    moves = np.abs(extents[1:] - extents[0]) > 0.1 * np.repeat(steps, 2)
    for c, (k, side) in enumerate(free):
        point = hi_pt[k] if side else lo_pt[k]
        beyond = new_hi[k] - proj[point, k] if side else proj[point, k] - new_lo[k]
        if np.any(touched & moves[c]):
            # A bisection placed a window side this bound moves: the solution is as good.
            pad[side, k] = max(beyond, 0.0)
            if fixed is not None:
                fixed[side, k] = True
        # A solution at or inside the extreme inlier says only that this bound is not the one
        # the window side reaches (another free bound meeting the same side took it up, or the
        # operator's window ends short of the silhouette): the edge is still somewhere in the
        # gap beyond the last hit, so the extent rule's pad (the middle of that gap) stays.
        elif beyond > 0.0:
            pad[side, k] = beyond
        elif gaps is not None and np.isfinite(gaps[side, k]):
            pad[side, k] = 0.5 * gaps[side, k]
        if side:
            hi[k] = proj[point, k] + pad[1, k]
        else:
            lo[k] = proj[point, k] - pad[0, k]
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
    return sigma**2 * pinv(jac.T @ jac)


def propagate(model, x, cov, bounds_info, sigma, one_face, spans=None):
    """Standard errors of sizes (3,) and centre (3,) by finite-difference linear propagation.

    ``spans`` (2, 3) metres, optional: the gap beyond each extent bound's extreme point in
    which its edge lies (:func:`extent_spans`); by default twice the pad.
    """
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
    # With a wider gap ``spans`` than twice the pad, the edge is uniform over the gap and the
    # pad is off its middle: variance (span / 2 - pad)^2 + span^2 / 12 (pad^2 / 3 at span 2 pad).
    extent_var = np.zeros(3)
    for k in range(3):
        extent_var[k] = sigma**2 * ((not lo_face[k]) + (not hi_face[k]))
        if spans is None:
            extent_var[k] += (
                pad[0, k] ** 2 * (not lo_face[k]) + pad[1, k] ** 2 * (not hi_face[k])
            ) / 3
            continue
        for side, open_side in ((0, not lo_face[k]), (1, not hi_face[k])):
            if open_side:
                span = spans[side, k]
                extent_var[k] += (0.5 * span - pad[side, k]) ** 2 + span**2 / 12.0
    size_var = np.diag(out)[:3] + extent_var
    centre_cov = out[3:, 3:] + model.axes.T @ np.diag(extent_var / 4.0) @ model.axes
    return np.sqrt(size_var), float(np.sqrt(np.trace(centre_cov)))


def rival_size_spread(model, x, label, inliers, width, edge_pad, edges=None):
    """How far the sizes and the centre of the frames that split the fit's raster lines
    otherwise (``model.split_rivals``, :func:`asbuilt.fit._cuboid_sparse.line_split_spread`)
    lie from its own: a frame turned about the lines puts other shots on each face and bounds
    the box elsewhere.

    Both frames' boxes are taken the same way, as :func:`bounds` of each fit's own inliers
    among the shots ``x`` (n, 3) metres (centred; ``label`` (n,), ``inliers`` (n,) bool are
    ``model``'s, ``width`` metres the inlier cutoff, ``edge_pad`` and ``edges`` as for
    :func:`bounds`): the raster window, which may move an unseen edge of either, is not read
    again for the rival, so only the part of the difference the frame makes is counted.

    Returns
    -------
    sizes : ndarray, shape (3,)
        Per axis of ``model``, metres: the largest difference between a rival's size along
        its nearest axis and the fit's own.
    centre : float
        Metres: the largest distance between a rival's centre and the fit's own.
    """

    def box(frame, frame_label, frame_inliers) -> tuple[np.ndarray, np.ndarray]:
        single = single_lines(x, frame_label, frame_inliers, frame, width)
        lo, hi = bounds(x, frame_label, frame_inliers, frame, width, edge_pad, edges, single)[:2]
        return hi - lo, frame.axes.T @ (0.5 * (hi + lo))

    spread, shift = np.zeros(3), 0.0
    if not model.split_rivals:
        return spread, shift
    own, own_centre = box(model, label, inliers)
    for trial in model.split_rivals:
        other, other_centre = box(trial[0], trial[1], trial[3])
        nearest = np.abs(model.axes @ trial[0].axes.T).argmax(axis=1)
        spread = np.maximum(spread, np.abs(other[nearest] - own))
        shift = max(shift, float(np.linalg.norm(other_centre - own_centre)))
    return spread, shift
