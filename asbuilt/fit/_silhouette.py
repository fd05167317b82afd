"""Unseen cuboid edges from the pan-tilt raster's silhouette window.

Private helper of :mod:`asbuilt.fit.cuboid`. A pan-tilt range finder records each point as
``station + range * direction(pan, tilt)`` with the *nominal* raster angles, so seen from the
station the points' directions fall exactly on the raster's columns (one pan each) and rows (one
tilt each), whatever the range noise. The operator's raster spans the object's angular window
with shots at the cells' centres (``asbuilt.sim.sensor``: ``EDGE_INSET`` = 0.5, the outer shots
half a raster step inside the silhouette), so the window is the points' angular extent widened by
half a step on each side. An edge no seen face bounds (the far side of a face, a column's top and
bottom) is then placed where the box's silhouette touches that window, instead of at the last
point, which stops short of it by up to a raster step.

Over an operator's window (marked by eye, a little wider than the object) the silhouette lies
anywhere between the last line of hits and the first line of misses, so the half-step rule is
right only on average (within half a step either way). An acquisition session therefore adds
edge-bisection shots (``asbuilt.drivers.session``: between a hit and a miss, bisected until the
bracket is a few millimetres across): those points are off the raster's lines, but the rest
still are. :func:`raster_grid` finds the raster among them (the lines carrying at least two
points, then every point on those lines' evenly spaced grid; shots :func:`edge_shots` calls
bisection shots are never raster shots, even within the line width of the line they started
from) and each side of the window that off-grid shots reach beyond the raster's last line (in
the angle they are off the raster's lines in: a pan bisection keeps its row's tilt) is placed
at the outermost of them instead: a bisection hit lies inside the silhouette, within the
session's tolerance of it, and beyond the last raster hit, so it pins that side far more
tightly than half a step. A side whose last raster line has a bisection hit just inside it
(within ``_NEAR`` of a step) is placed on that line: the silhouette runs along the line (its
shots straddle the edge, or the bisection from its shot missed at every step and the session
shot again a few brackets inside). Other sides keep the half-step rule. :func:`solve_bounds`
weights each side by how well it is known.

Everything here is numpy; angles in radians, lengths in metres.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._common import quick_median
from asbuilt.fit._small_linalg import inv

__all__ = [
    "background_sides",
    "edge_shots",
    "on_raster_lines",
    "raster_grid",
    "raster_window",
    "shot_angles",
    "solve_bounds",
]

#: Samples per box edge when measuring the box's angular extent (the tilt extreme of a convex
#: box can lie inside an edge).
_EDGE_SAMPLES = 9
#: A line of shots is this much narrower than the raster step (relative) or it is not a raster.
_LINE_WIDTH = 0.02
#: Share of the shots that must have an angle on a line shared with another shot, or their angles
#: are not a raster's lattice and no shot is taken for a bisection's: in a session every shot
#: keeps its row's tilt or its column's pan (1.0 over 960 simulated sessions), while recorded
#: angles jittered by 0.01 degree leave 20-73% of a raster's shots sharing no line, and a jittered
#: shot beside a coincidental line would be taken for a bisection shot and get no edge pad.
_LATTICE_SHARE = 0.9
#: Rounded coordinates blur a line by this fraction of the raster step or more: the raster's
#: lines, and a bisection's offsets from them, can no longer be told from the rounding.
_ROUNDED_OUT = 0.1
#: Gaps between sorted angles below this fraction of the widest are within a line (the widest
#: is a raster step or more).
_SMALL_GAP = 0.1
#: A line scattered by jitter spans about this many of its median within-line gaps (a gap is
#: about half the scatter's sigma on a line of six: 12 gaps make 6 sigma, so that no shot of
#: a raster line falls off it by chance and is taken for a bisection's).
_BLUR_GAPS = 12.0
#: Grids a file's coordinates may be rounded to (metres), by family (the metre, the inch, the
#: foot), coarsest first: 1, 2 or 5 units of a decade, from 10 mm down to 1 micrometre (finer
#: rounding moves a shot's angle far less than a line's width). Each family's last (finest)
#: grid divides all its others, so data off it is off the whole family.
_QUANTA = tuple(
    np.array(
        sorted(
            {
                round(m * unit * 10.0**k, 15)
                for m in (1.0, 2.0, 5.0)
                for k in range(-7, -1)
                if 1e-6 <= m * unit * 10.0**k <= 0.01
            },
            reverse=True,
        )
    )
    for unit in (1.0, 0.0254, 0.3048)
)
#: Gaps between raster lines must be whole multiples of the step within this fraction.
_STEP_MULTIPLE = 0.15
#: Least distance across the beam (metres) between a bisection shot and the shot that gives
#: its line's direction.
_SPAN = 0.01
#: A bisection hit this close inside the raster's outermost line (in steps) pins that side at
#: the line: the silhouette runs along it (the line's shots straddle the edge, or the
#: bisection from its shot missed at every step).
_NEAR = 0.1
#: Silhouette fit weights: window sides matched to 0.1 mrad, bounds kept within 0.1 m of their
#: start (a raster step at most) unless the window needs them moved.
_ANGLE_TOL = 1e-4
_PRIOR_M = 0.1


def _pan_tilt(points: np.ndarray, viewpoint: np.ndarray, pan0: float):
    """Pan (relative to ``pan0``) and tilt (k,) each, radians, of points (k, 3) seen from
    ``viewpoint``."""
    rel = points - viewpoint
    pan = np.arctan2(rel[:, 1], rel[:, 0]) - pan0
    pan = (pan + np.pi) % (2.0 * np.pi) - np.pi
    tilt = np.arctan2(rel[:, 2], np.hypot(rel[:, 0], rel[:, 1]))
    return pan, tilt


def _angles(points: np.ndarray, viewpoint: np.ndarray, pan0: float) -> np.ndarray:
    """Pan (relative to ``pan0``) and tilt of points (k, 3) seen from ``viewpoint``; (k, 2) rad."""
    return np.column_stack(_pan_tilt(points, viewpoint, pan0))


def coordinate_quantum(points: np.ndarray) -> float:
    """The grid a file rounded the coordinates to (metres), 0.0 when they are not rounded.

    A file in millimetres with whole numbers holds multiples of 0.001 m: each shot's direction
    from the station is then off by up to about a quantum over its range, which can be more
    than the width of a raster line of exact (nominal) angles.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    """
    values = np.asarray(points, dtype=np.float64).ravel()
    if values.size == 0 or not np.all(np.isfinite(values)):
        return 0.0

    def on_grid(quantum: float) -> bool:
        ratio = values / quantum
        return bool(np.all(np.abs(ratio - np.round(ratio)) <= 1e-6))

    found = 0.0
    for family in _QUANTA:
        # off the finest grid, off every grid of the family: one test for unrounded points (a
        # cuboid fit calls this up to three times)
        if on_grid(family[-1]):
            found = max(found, next(float(q) for q in family if on_grid(q)))
    return found


def _rounding_width(points: np.ndarray, viewpoint: np.ndarray) -> float:
    """Widest spread (radians) that rounding gives the angles of shots along one line: two
    shots, each coordinate off by up to half a quantum, at the nearest horizontal reach."""
    quantum = coordinate_quantum(points)
    if quantum == 0.0:
        return 0.0
    rel = points - viewpoint
    reach = float(np.hypot(rel[:, 0], rel[:, 1]).min())
    return float(np.sqrt(2.0) * quantum / max(reach, 1e-3))


def _line_blur(points: np.ndarray, viewpoint: np.ndarray, ang: np.ndarray) -> float:
    """How wide (radians) a raster line of these shots may be: the file's rounding
    (:func:`_rounding_width`), or recorded angles that scatter about their line (a head's
    encoder read back, not its commanded angles): then the gaps between neighbouring angles
    within lines, which are zero for nominal angles, are the scatter's, and a line spans
    several of them."""
    blur = _rounding_width(points, viewpoint)
    for j in range(ang.shape[1]):
        ordered = ang[:, j].copy()  # np.diff(np.sort(...)) without the wrappers
        ordered.sort()
        gaps = ordered[1:] - ordered[:-1]
        if gaps.size == 0 or np.maximum.reduce(gaps) <= 0.0:
            continue
        small = gaps[gaps < _SMALL_GAP * np.maximum.reduce(gaps)]
        if small.size >= 3:
            blur = max(blur, _BLUR_GAPS * quick_median(small))
    return blur


def on_raster_lines(seen) -> bool:
    """Whether shots' pan or tilt alone falls on evenly spaced lines (``seen``:
    :func:`shot_angles`' result, or None): a raster with a few columns occluded by something in
    front reads no grid (:func:`raster_grid`) but keeps its rows; shots aimed by hand have
    neither."""
    return seen is not None and any(_grid_step(seen[1][:, j], seen[2]) is not None for j in (0, 1))


def _grid_step(values: np.ndarray, rounding: float = 0.0) -> float | None:
    """Raster step (radians) of 1-D angles falling on evenly spaced lines; None if they do not.

    ``rounding`` (radians): the spread a line may have from the file's rounding alone.
    """
    ordered = values.copy()  # np.diff(np.sort(values)) without the wrappers
    ordered.sort()
    gaps = ordered[1:] - ordered[:-1]
    if gaps.size == 0 or np.maximum.reduce(gaps) <= 0.0:
        return None
    big = gaps > 0.25 * np.maximum.reduce(gaps)
    step = float(np.minimum.reduce(gaps[big]))
    multiple = gaps[big] / step
    # (The methods and reductions np.any, np.round and np.cumsum call, unwrapped.)
    if np.logical_or.reduce(np.abs(multiple - multiple.round()) > _STEP_MULTIPLE):
        return None
    # Width of each line of shots (sum of the small gaps between its members).
    line_id = np.concatenate([[0], big.cumsum()])
    width = np.zeros(line_id[-1] + 1)
    np.add.at(width, line_id[1:], np.where(big, 0.0, gaps))
    if np.maximum.reduce(width) > max(_LINE_WIDTH * step, rounding) or (
        rounding > _ROUNDED_OUT * step
    ):
        return None
    return step


def _lines(values: np.ndarray, tol: float) -> np.ndarray:
    """Line label (k,) of 1-D values: sorted values closer than ``tol`` share a line."""
    order = np.argsort(values)
    label = np.empty(values.shape[0], dtype=np.int64)
    label[order] = np.concatenate([[0], np.cumsum(np.diff(values[order]) > tol)])
    return label


def _on_lines(values: np.ndarray, step: float, ref: float, rounding: float = 0.0) -> np.ndarray:
    """Whether each value (k,) lies on the grid ``ref + i * step`` (within ``_LINE_WIDTH``
    steps, or the file's ``rounding`` in radians when wider)."""
    phase = (values - ref) / step
    return np.abs(phase - np.round(phase)) <= max(_LINE_WIDTH, rounding / step)


def _shot_alike(ang: np.ndarray, off: np.ndarray, labels: list) -> bool:
    """Whether the points off the raster look shot by the same head (``off``: (n,) bool).

    Edge-bisection shots keep a raster row's tilt or column's pan, and fill rasters have lines
    of their own: nearly every such point shares its pan or its tilt with another point. Points
    from another station, seen from this viewpoint, have angles of their own.
    """
    if not off.any():
        return True
    shared = np.zeros(ang.shape[0], dtype=bool)
    for label in labels:
        shared |= np.bincount(label)[label] >= 2
    return np.count_nonzero(off & ~shared) <= 0.1 * np.count_nonzero(off)


def shot_angles(points: np.ndarray, viewpoint: np.ndarray):
    """The shots' directions from ``viewpoint``, as :func:`raster_grid` and :func:`edge_shots`
    read them (a fit calling both, or one twice, computes them once and passes them on).

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    viewpoint : ndarray, shape (3,), metres

    Returns
    -------
    tuple or None
        ``(pan0, ang, blur)``: the reference pan (radians, that of the points' mean
        direction), ``ang`` (n, 2) radians, each shot's pan relative to ``pan0`` and tilt, and
        ``blur`` (radians), how wide a raster line may be (:func:`_line_blur`). None when a
        point lies at the viewpoint.
    """
    rel = points - viewpoint
    if np.any(np.linalg.norm(rel, axis=1) < 1e-6):
        return None
    mean = rel.mean(axis=0)
    pan0 = float(np.arctan2(mean[1], mean[0]))
    ang = _angles(points, viewpoint, pan0)
    return pan0, ang, _line_blur(points, viewpoint, ang)


def raster_grid(
    points: np.ndarray, viewpoint: np.ndarray, off_grid: np.ndarray | None = None, seen=None
):
    """The raster's angular window and which points are on its grid, edge shots allowed.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
        All measured points (outliers too: their directions are still shot directions).
    viewpoint : ndarray, shape (3,), metres
    off_grid : ndarray, shape (n,), bool, optional
        Points known not to be raster shots (edge-bisection shots found by :func:`edge_shots`):
        a bisection's deepest hit can come within the line width of the raster line it started
        from, and counted on that line it would move the window's side by up to half a step
        instead of pinning it.
    seen : tuple or None, optional
        :func:`shot_angles` of ``points`` and ``viewpoint``, when already computed.

    Returns
    -------
    tuple or None
        ``(pan0, window, on_grid, pinned, steps)``: the reference pan (radians); ``window`` (4,)
        radians, ``[pan_min, pan_max, tilt_min, tilt_max]`` with pan relative to ``pan0``;
        ``on_grid`` (n,) bool, the points on the raster's columns and rows; ``pinned`` (4,)
        bool, the window sides placed at an off-grid (edge) shot instead of half a step beyond
        the last raster line; ``steps`` (2,) radians, the raster's pan and tilt steps. None when
        no raster of at least two evenly spaced columns and
        rows carries most (at least half, and 7) of the points.

    Notes
    -----
    Without off-grid points this is :func:`raster_window`. Otherwise (provided the off-grid
    points share their pan or tilt with others, as a session's fill and bisection shots do:
    :func:`_shot_alike`) the lines (columns, then rows) holding a single point are set aside (a bisection shot has a pan or a tilt of its
    own; raster lines hold a point per row or column on the object), the step is measured on
    the points left, and every point on that step's grid (both angles within ``_LINE_WIDTH``
    steps of a line) is a raster point. A window side is pinned when off-grid points lie beyond
    the raster's outermost line on that side (off the raster's lines in that angle, to the
    tight tolerance of :func:`edge_shots`): it is then their outermost angle. Failing that, a
    side with an ``off_grid`` shot off the lines within ``_NEAR`` steps inside its outermost
    line is placed on the line (not pinned: the silhouette reaches the line, and runs along it
    when straight; a slanted one may reach past it, so the side keeps the half-step rule's
    weight).
    """
    if seen is None:
        seen = shot_angles(points, viewpoint)
    if seen is None:
        return None
    n = points.shape[0]
    pan0, ang, rounding = seen
    known = np.ones(n, dtype=bool) if off_grid is None else ~np.asarray(off_grid, dtype=bool)
    steps = (
        [_grid_step(ang[known, j], rounding) for j in range(2)]
        if known.sum() >= 2
        else [None, None]
    )
    if steps[0] is not None and steps[1] is not None and known.all():
        on_grid = np.ones(n, dtype=bool)
    else:
        on_grid = None
        for least in (2, 3):
            keep = known.copy()
            labels = []
            for j in range(2):
                spread = float(np.ptp(ang[:, j]))
                label = _lines(ang[:, j], max(_LINE_WIDTH * 1e-2 * max(spread, 1e-12), rounding))
                labels.append(label)
                keep &= np.bincount(label)[label] >= least
            if np.count_nonzero(keep) < max(7, n // 2):
                continue
            steps = [_grid_step(ang[keep, j], rounding) for j in range(2)]
            if steps[0] is None or steps[1] is None:
                continue
            refs = [float(ang[keep, j].min()) for j in range(2)]
            grid = _on_lines(ang[:, 0], steps[0], refs[0], rounding)
            grid &= _on_lines(ang[:, 1], steps[1], refs[1], rounding)
            grid &= known
            if np.count_nonzero(grid) >= max(7, n // 2) and _shot_alike(ang, ~grid, labels):
                on_grid = grid
                break
        if on_grid is None:
            return None
    inner = ang[on_grid]
    window = np.array(
        [
            inner[:, 0].min() - 0.5 * steps[0],
            inner[:, 0].max() + 0.5 * steps[0],
            inner[:, 1].min() - 0.5 * steps[1],
            inner[:, 1].max() + 0.5 * steps[1],
        ]
    )
    pinned = np.zeros(4, dtype=bool)
    bisected = ~known
    for j in range(2):
        low, high = inner[:, j].min(), inner[:, j].max()
        # Off-grid shots off the raster's lines along j (a pan bisection keeps its row's tilt:
        # it says nothing about the tilt sides).
        tight = max(_LINE_WIDTH * 1e-2 * max(float(np.ptp(ang[:, j])), 1e-12), rounding)
        phase = (ang[:, j] - low) / steps[j]
        across = ~on_grid & (np.abs(phase - np.round(phase)) * steps[j] > tight)
        if not across.any():
            continue
        values = ang[across, j]
        near = _NEAR * steps[j]
        if values.min() < low:
            window[2 * j], pinned[2 * j] = values.min(), True
        elif np.any(bisected & across & (ang[:, j] <= low + near)):
            window[2 * j] = low
        if values.max() > high:
            window[2 * j + 1], pinned[2 * j + 1] = values.max(), True
        elif np.any(bisected & across & (ang[:, j] >= high - near)):
            window[2 * j + 1] = high
    return pan0, window, on_grid, pinned, np.array(steps, dtype=float)


#: Raster lines beyond the object's outermost hit line, holding only shots the fit rejected,
#: that show a window side is the operator's, not the object's silhouette: one such line may
#: be mixed returns on the silhouette's own outermost line (the edge straddling the beam's
#: footprint), two are background seen past the object (a window run across the wall behind
#: a column).
BACKGROUND_LINES = 2


def background_sides(grid, angles: np.ndarray, inliers: np.ndarray):
    """``grid`` (:func:`raster_grid`'s answer) with each window side that the object does not
    reach moved in to half a raster step beyond the object's outermost raster line.

    The half-step rule reads a raster's window as the object's silhouette window. A window
    run wider across the wall behind a column puts its sides on the wall: the column's unseen
    edges were solved out to them (a 0.5 x 0.5 m column in a window twice its width came out
    0.96 x 1.24 m). Where ``BACKGROUND_LINES`` or more raster lines beyond the inliers'
    outermost line hold only rejected shots, the silhouette ends in the gap after that line,
    at half a step beyond it on average, as on a window fitted to the silhouette. A side
    pinned by edge-bisection shots stays.

    Parameters
    ----------
    grid : tuple
        ``(pan0, window, on_grid, pinned, steps)`` as :func:`raster_grid` returns it.
    angles : ndarray, shape (n, 2), radians
        Each shot's pan (relative to ``pan0``) and tilt (:func:`shot_angles`).
    inliers : ndarray, shape (n,), bool

    Returns
    -------
    tuple
        ``grid`` itself when no side moves, else a copy with the moved sides.
    """
    pan0, window, on_grid, pinned, steps = grid
    kept = inliers & on_grid
    if not kept.any() or inliers.all():
        return grid
    moved_window, moved_pinned = np.array(window, dtype=np.float64), np.array(pinned)
    for axis in (0, 1):
        step = float(steps[axis])
        if not step > 0:
            continue
        mine = angles[kept, axis]
        rejected = angles[~inliers, axis]
        for side, edge, sign in ((2 * axis, mine.min(), -1.0), (2 * axis + 1, mine.max(), 1.0)):
            if moved_pinned[side]:
                continue
            beyond = sign * (rejected - edge) / step
            lines = np.unique(np.rint(beyond[beyond > 0.5]))
            if lines.size >= BACKGROUND_LINES and sign * (window[side] - edge) > 0.5 * step:
                moved_window[side] = edge + sign * 0.5 * step
    if np.array_equal(moved_window, window):
        return grid
    return pan0, moved_window, on_grid, moved_pinned, steps


def raster_window(points: np.ndarray, viewpoint: np.ndarray):
    """The raster's angular window, if the points are a pan-tilt raster shot from ``viewpoint``.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
        All measured points (outliers too: their directions are still raster directions).
    viewpoint : ndarray, shape (3,), metres

    Returns
    -------
    tuple or None
        ``(pan0, window)``: the reference pan (radians) and ``window`` shape (4,) radians,
        ``[pan_min, pan_max, tilt_min, tilt_max]`` with pan relative to ``pan0``; None when the
        directions from ``viewpoint`` do not fall on a raster (edge shots allowed: see
        :func:`raster_grid`).
    """
    found = raster_grid(points, viewpoint)
    return None if found is None else found[:2]


def _in_progression(v: float, others: np.ndarray, tol: float) -> bool:
    """Whether ``v`` and two of ``others`` (sorted, distinct) are three evenly spaced values.

    A raster's lines are evenly spaced; the hits of one bisection are not, nor are they with
    the raster shot they started from (each step at most halves the previous one, and the
    bracket's far end missed).
    """
    step = others - v
    apart = np.abs(step) > tol
    if not apart.any():
        return False
    # v, a, a + d or v - d, v, a for every a = v + d of the others: is a third value there?
    targets = np.concatenate([others[apart] + step[apart], v - step[apart]])
    k = np.searchsorted(others, targets)
    last = others.size - 1
    below = others[np.clip(k - 1, 0, last)]
    above = others[np.clip(k, 0, last)]
    return bool(np.any((np.abs(below - targets) <= tol) | (np.abs(above - targets) <= tol)))


def edge_shots(points: np.ndarray, viewpoint: np.ndarray, seen=None):
    """Which points look like edge-bisection shots of an acquisition session.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    viewpoint : ndarray, shape (3,), metres
    seen : tuple or None, optional
        :func:`shot_angles` of ``points`` and ``viewpoint``, when already computed.

    Returns
    -------
    along : ndarray, shape (n,), int
        ``0`` for a shot bisected along pan (its tilt on a raster row, its pan on no raster
        column), ``1`` along tilt, ``-1`` for the others (raster and fill shots, or points not
        shot from ``viewpoint``).
    partner : ndarray, shape (n,), int
        For a bisection shot, the nearest raster shot on its row (column), normally the one its
        bisection started from, else the nearest other shot at least ``_SPAN`` (1 cm) away
        across the beam: the two span the bisection's direction on the surface. ``-1`` for
        the others.

    Notes
    -----
    A session (``asbuilt.drivers.session``) bisects between a raster hit and a neighbouring
    miss of the same row (or column), so every bisection shot keeps the row's tilt (the
    column's pan) and has a pan (tilt) between two raster columns, at a binary fraction of
    the step. Raster columns (of the raster or of a fill raster) hold shots on two rows or
    more; a bisection's pans hold one shot (the session bisects one pair per bracket, so no two
    bisections share angles). A shot whose pan holds one row is a raster shot when its pan and
    two others of its row are evenly spaced (a one-column fill raster, a raster's lone corner
    shot), and a pan-bisection shot when it is off the lattice of the raster columns crossing
    its row (a whole number of their smallest spacing from them; with one such column on the
    row, a one-column fill raster's, there is no lattice and the lone pan is taken for a
    bisection's; with none, for a raster shot); the same with pan and tilt exchanged. A shot that
    would be both is neither. Repeated shots in one direction (a head rounding to whole
    counts) count once. Lines are told apart at 0.02 % of the angular spread (the shots'
    angles are the nominal ones, exact to rounding), and a shot is on a raster's lattice within
    that too: a bisection's deepest hits come within a fraction of a percent of a step of the
    line it started from. When the file rounded its coordinates (to 1 mm, say) or recorded
    scattered angles (encoders read back), a line is as wide as that blur
    (:func:`_line_blur`); a blur of a tenth of a step or more, or fewer than
    ``_LATTICE_SHARE`` of the shots sharing a line, leaves no lattice to be off, and no shot is
    taken for a bisection's.
    """
    n = points.shape[0]
    out = -np.ones(n, dtype=np.int64)
    partner = -np.ones(n, dtype=np.int64)
    if n < 3:
        return out, partner
    if seen is None:
        seen = shot_angles(points, viewpoint)
    if seen is None:
        return out, partner
    _, ang, rounding = seen
    rel = points - viewpoint
    for j in range(2):
        # blurred by more than a tenth of even the widest gap between its angles: no lattice
        # at all (a dense cloud, where the per-shot search below would also take minutes)
        if rounding > _ROUNDED_OUT * float(np.max(np.diff(np.sort(ang[:, j])))):
            return out, partner
    labels, tols = [], []
    for j in range(2):
        tol = max(_LINE_WIDTH * 1e-2 * max(float(np.ptp(ang[:, j])), 1e-12), rounding)
        labels.append(_lines(ang[:, j], tol))
        tols.append(tol)
    # Each line's positions along the other angle, repeated directions counted once: the
    # distinct (column, row) label pairs, as one integer each (one 1-D np.unique, not two of
    # rows, which cost more than the rest of this test).
    rows = int(labels[1].max()) + 1
    on_col, on_row = np.divmod(np.unique(labels[0] * rows + labels[1]), rows)
    full = [
        np.bincount(on, minlength=int(label.max()) + 1)[label] >= 2
        for on, label in ((on_col, labels[0]), (on_row, labels[1]))
    ]
    if np.mean(full[0] | full[1]) < _LATTICE_SHARE:
        return out, partner
    flagged = np.zeros((2, n), dtype=bool)
    for j in range(2):
        for i in (~full[j]).nonzero()[0]:
            own = labels[1 - j] == labels[1 - j][i]
            v = ang[i, j]
            # on an evenly spaced progression of its own line (a one-column fill raster, a
            # raster's lone corner shot): a raster shot
            if _in_progression(v, np.unique(ang[own & (labels[j] != labels[j][i]), j]), tols[j]):
                continue
            # else off the lattice of the raster columns crossing its row: a bisection shot
            lines = np.unique(ang[own & full[j], j])
            if lines.size == 0:
                continue
            gaps = np.diff(lines)
            gaps = gaps[gaps > tols[j]]
            if gaps.size == 0:
                # one raster column on the row (a one-column fill raster): no lattice to be off;
                # a lone pan, on no progression, next to a raster column is a bisection's
                flagged[j, i] = True
                continue
            step = float(gaps.min())
            if tols[j] > _ROUNDED_OUT * step:
                continue  # the file's rounding blurs the lattice: no offset can be told
            offset = (v - lines[0]) % step
            flagged[j, i] = min(offset, step - offset) > tols[j]
    reach = np.linalg.norm(rel, axis=1)
    for j in range(2):
        for i in (flagged[j] & ~flagged[1 - j]).nonzero()[0]:
            line = ((labels[1 - j] == labels[1 - j][i]) & (labels[j] != labels[j][i])).nonzero()[0]
            if line.size == 0:
                continue
            # the nearest raster shot on the line (the one the bisection started from), else
            # the nearest shot at least _SPAN away across the beam, so that the two span the
            # line's direction well above the range noise (millimetres)
            apart = np.abs(ang[line, j] - ang[i, j]) * reach[i]
            start = ~(flagged[0, line] | flagged[1, line]) & (apart >= _SPAN)
            if np.any(start):
                line, apart = line[start], apart[start]
            elif np.any(apart >= _SPAN):
                line, apart = line[apart >= _SPAN], apart[apart >= _SPAN]
            out[i] = j
            partner[i] = line[int(np.argmin(apart))]
    return out, partner


def _edge_fractions() -> np.ndarray:
    """Fractions (m, 3) in [0, 1]^3 sampling the 12 edges of the unit cube."""
    t = np.linspace(0.0, 1.0, _EDGE_SAMPLES)
    rows = []
    for k in range(3):
        a, b = [j for j in range(3) if j != k]
        for fa in (0.0, 1.0):
            for fb in (0.0, 1.0):
                block = np.zeros((t.size, 3))
                block[:, k] = t
                block[:, a] = fa
                block[:, b] = fb
                rows.append(block)
    return np.unique(np.concatenate(rows), axis=0)


_FRACTIONS = _edge_fractions()


def _extent(lo, hi, axes, origin, viewpoint, pan0) -> np.ndarray:
    """Angular extent [pan_min, pan_max, tilt_min, tilt_max] (4,) of the box lo..hi (local)."""
    return _extents(lo[None, :], hi[None, :], axes, origin, viewpoint, pan0)[0]


def _extents(lo, hi, axes, origin, viewpoint, pan0) -> np.ndarray:
    """Angular extents (b, 4) of b boxes given by bounds lo, hi (b, 3) in one batch."""
    local = lo[:, None, :] + _FRACTIONS[None, :, :] * (hi - lo)[:, None, :]
    world = origin + local.reshape(-1, 3) @ axes
    pan, tilt = _pan_tilt(world, viewpoint, pan0)
    # Each box's samples in a contiguous row: reducing along the middle axis of (b, m, 2)
    # angles cost more than the angles themselves (the same least and greatest values). The
    # (b, 4) answer is column-major, as the fancy-indexed one was: the solver's products of it
    # go through BLAS in that layout, and another layout rounds differently.
    pan, tilt = pan.reshape(lo.shape[0], -1), tilt.reshape(lo.shape[0], -1)
    # Rows of a fresh (4, b) array, as np.stack builds it, without its Python overhead.
    out = np.empty((4, lo.shape[0]))
    np.minimum.reduce(pan, axis=1, out=out[0])
    np.maximum.reduce(pan, axis=1, out=out[1])
    np.minimum.reduce(tilt, axis=1, out=out[2])
    np.maximum.reduce(tilt, axis=1, out=out[3])
    return out.T


def solve_bounds(lo, hi, free, axes, origin, viewpoint, pan0, window, iterations=10, side_tol=None):
    """Move the free bounds so that the box's angular extent matches the raster window.

    Parameters
    ----------
    lo, hi : ndarray, shape (3,), metres
        Box bounds along each row of ``axes`` (local coordinates about ``origin``).
    free : list of (int, int)
        The bounds to adjust: (axis, 0 for lo or 1 for hi).
    axes : ndarray, shape (3, 3)
        Rows: the box's unit axes.
    origin : ndarray, shape (3,), metres
    viewpoint : ndarray, shape (3,), metres
    pan0 : float, radians
    window : ndarray, shape (4,), radians
    iterations : int
        Gauss-Newton iterations (forward-difference Jacobian evaluated at the first and fourth
        iterate) of the window misfit plus a weak pull of each bound to its start value.
    side_tol : ndarray, shape (4,), radians, optional
        How well each window side is known (the misfit of a side is divided by it); default
        ``_ANGLE_TOL`` for all four. It matters only when the window determines the bounds more
        than once over (three free bounds and four sides seen from above a pier).

    Returns
    -------
    lo, hi : ndarray, shape (3,), metres
        The adjusted bounds (copies).
    """
    lo, hi = np.array(lo, float), np.array(hi, float)
    if not free:
        return lo, hi
    eps = 1e-6
    jac = None
    count = len(free)
    start = np.array([(hi if side else lo)[k] for k, side in free])
    # Weights: window sides to _ANGLE_TOL, bounds held to their start within _PRIOR_M, so that
    # bounds the window does not determine (several meeting at one silhouette corner) take the
    # smallest change.
    prior = np.eye(count) / _PRIOR_M**2
    tol = np.full(4, _ANGLE_TOL) if side_tol is None else np.asarray(side_tol, dtype=float)
    for it in range(iterations):
        if jac is None or it == 3:
            # Chord method: the Jacobian of the first iterate (refreshed once) serves them all;
            # the box and its perturbed copies are measured in one batch.
            los, his = (
                np.repeat(lo[None], count + 1, axis=0),
                np.repeat(hi[None], count + 1, axis=0),
            )
            for c, (k, side) in enumerate(free):
                (his if side else los)[c + 1, k] += eps
            measured = _extents(los, his, axes, origin, viewpoint, pan0)
            base = measured[0]
            jac = ((measured[1:] - base) / eps).T / tol[:, None]
            inverse = inv(jac.T @ jac + prior)
        else:
            base = _extent(lo, hi, axes, origin, viewpoint, pan0)
        now = np.array([(hi if side else lo)[k] for k, side in free])
        gradient = jac.T @ ((base - window) / tol) + prior @ (now - start)
        delta = -inverse @ gradient
        for c, (k, side) in enumerate(free):
            (hi if side else lo)[k] += delta[c]
        if np.abs(delta).max() < 1e-7:
            break
    return lo, hi
