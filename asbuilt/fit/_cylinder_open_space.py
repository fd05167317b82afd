"""Open space inside a cylinder fit's silhouette: its shots are not one pipe.

Private helper of the cylinder fit. A vertical pipe shot by a pan-tilt raster shows three or
four raster columns; in cross-section they are three or four points, which a circle fits
exactly. With a box column 0.05-0.5 m beside the pipe in the window (a black-box review's ray
caster at stop 48), a circle through the pipe's columns and the column's face was consistent
with the residuals alone and was kept with every shot an inlier: r 197.8 +-0.5 mm for an
84.2 mm pipe, r 232.9 +-4.4 for 109.6; or the column's faces were fitted as a wide cylinder
and the pipe, seen past their edge, rejected: r 6.4 m for 84.2.

What the residuals do not show, the beams do. A pipe is convex, so the beams that meet it fill
a convex cone seen from the station, and each of them ends on the pipe or on something in
front of it: a raster over the pipe returns a shot for every beam inside its silhouette (a
dropout or two aside). Beams inside a fitted cylinder's silhouette, between or beside its
inliers and within their length, that came back with nothing are open space where the fit
claims a surface: the fit is not one object (free-space carving, Curless & Levoy 1996, "A
volumetric method for building complex models from range images"; the same evidence the
rack neighbours are told apart by, :func:`asbuilt.fit._cylinder_background.depth_segments`).

The raster is read from the shots' directions (:func:`asbuilt.fit._silhouette.raster_grid`:
evenly spaced pan columns and tilt rows); the beams it fired are the cells of its window. A
cell is open when no shot came back along it, its beam passes the fitted axis more than half a
raster step inside the radius (a fitted silhouette a little too wide, or a grazing shot that
did not come back, is not open space) and enters the pipe within its inliers' extent along the
axis, half a step in from each end. A fit is parted by open space when ``OPEN_CELLS`` or more
such cells touch (4-neighbours): one or two missing shots are a dropout.

The fit's shots then fall on raster lines along its axis (pan columns of a plumb pipe, tilt
rows of a level one seen square-on); two neighbouring lines belong to one object unless, on
``OPEN_CELLS`` or more of the cross lines where either holds a kept shot, open space lies
between them or on one of them: the pipe's lines end where the column's go on, or an empty
raster line lies between them. Each side (neighbouring lines not parted) is fitted alone, as
the other cylinders among the shots are (:mod:`asbuilt.fit._cylinder_others`: at least
``FEWEST_SHOTS`` inliers, the radius determined, not a plane, ``FEWEST_ARC_DEGREES`` of arc):
the fit is refused, naming the sides that fit a pipe alone, or saying that none does. A side
that stands is not kept as the object: in a rack the fullest side can be the neighbour (two
of the four review scenes whose fullest side a trial kept), as when no cylinder holds most
shots (:mod:`asbuilt.fit._cylinder_others`). When every side that stands is the fit's own
cylinder found again (a pipe split by a band of dropouts), the fit stands as it was.

When the fit's shots are one side, open space between its lines on fewer than ``OPEN_CELLS``
cross lines is a band of dropouts and the fit stands; open space on ``OPEN_CELLS`` or more
cross lines of the raster lines beyond its first and last (:func:`open_beside`) is its surface
going on past its shots' edge where the beams passed through: a box column's face fitted as a
wide cylinder, the pipe behind it seen past the face's edge. That fit is refused.

What it cannot see: a window whose every beam came back (a raster of three columns, one on the
pipe and two on the column's face behind it, fits a circle exactly: r 406.9 +-2.3 mm for
84.2) or a fit of the column's faces or corner with the pipe's shots rejected, the pipe not
seen past them. Without a station, off a raster, or on an axis slanted across the raster's
lines the fit is left as it is. Lengths in metres, angles in radians.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from asbuilt.errors import FitError
from asbuilt.fit._common import radius_text
from asbuilt.fit._cylinder_others import (
    FEWEST_SHOTS,
    apart,
    cylinder_of,
)
from asbuilt.fit._silhouette import raster_grid, shot_angles

__all__ = [
    "ALONG_RATIO",
    "FILLED_BELOW",
    "FILLED_SHARE",
    "OpenSpaceFit",
    "MOST_CELLS",
    "OPEN_CELLS",
    "OPEN_SPACE",
    "apart_across_open_space",
    "filled_share",
    "open_beside",
    "open_cells",
]

#: Touching open cells (beams inside the fit's silhouette that returned nothing) that make
#: open space: one or two are a dropout (a dark patch, a beam lost at a glancing angle).
OPEN_CELLS = 3
#: The fit's axis runs along the raster's columns (rows) when its extent across the window, in
#: raster steps, is at least this many times its extent along the rows (columns); between the
#: two, no raster line runs along the pipe and its sides are not read from the lines.
ALONG_RATIO = 2.0
#: A raster's beams were all fired (each beam that came back with nothing is a miss) when at
#: least this share of its shots have a shot in a neighbouring cell along a row or column: a
#: raster over an object returns whole runs of neighbours (its lone shots are a mixed return
#: or a grazing edge), while shots picked at random off a fine grid (a tenth of its cells)
#: have a neighbour a third of the time.
FILLED_SHARE = 0.9
#: The raster's cells are read only for a fit whose inliers fill less than this share of the
#: cells its side covers (:func:`filled_share`): reading them costs a fifth of a 40-shot fit.
#: The benchmark's 300 fits of 40 shots from the station (clean and with 20% edge outliers)
#: fill 0.61-1.4 of them; the review's fits across open space 0.01-0.46.
FILLED_BELOW = 0.55
#: Angles of shots closer than this share of their spread lie on one raster line (the
#: shots of a raster share their line's nominal angle to rounding).
_SAME_LINE = 1e-6
#: Raster windows of more cells than this are not searched (a dense cloud, not a sparse scan).
MOST_CELLS = 40_000
#: How a refusal for open space begins.
OPEN_SPACE = "The shots this cylinder fits lie on both sides of open space"


class OpenSpaceFit(FitError):
    """A cylinder fit refused for open space inside its silhouette; ``refused`` is that fit.

    Not retried without the sensor's sigma: the beams that came back with nothing do not
    depend on the noise (the retry's wider inlier band let a pipe's two raster columns beside
    a box column pass as a determined pipe, r 93.9 +-5.2 mm for 161.9). A ``refused`` fit
    whose inliers scatter wider than the sensor's sigma is refitted at their level, as any fit
    is (:mod:`asbuilt.fit._noise_levels`), and that fit checked again.
    """

    def __init__(self, message: str, refused=None):
        super().__init__(message)
        self.refused = refused


def _window_cells(points: np.ndarray, view: np.ndarray):
    """The raster's cells seen from ``view``: ``(index, shape, directions, frame)``, each shot's
    cell (n, 2) int (pan, tilt), the window's shape (2,) in cells, every cell's beam direction
    (cells, 3) unit, and ``frame`` = ``(pan0, low, steps)``, the reference pan, the first
    cell's angles (2,) and the raster's steps (2,) radians; None off a raster, or on one whose
    every cell was not shot (``FILLED_SHARE``)."""
    seen = shot_angles(points, view)
    if seen is None:
        return None
    grid = raster_grid(points, view, seen=seen)
    if grid is None:
        return None
    pan0, angles, steps = seen[0], seen[1], grid[4]
    if not np.all(steps > 0.0):
        return None
    low = angles.min(axis=0)
    index = np.rint((angles - low) / steps).astype(np.int64)
    shape = index.max(axis=0) + 1
    if int(np.prod(shape)) > MOST_CELLS:
        return None
    hit = np.zeros(shape + 2, dtype=bool)
    hit[index[:, 0] + 1, index[:, 1] + 1] = True
    column, row = index[:, 0] + 1, index[:, 1] + 1
    beside = (
        hit[column - 1, row] | hit[column + 1, row] | hit[column, row - 1] | hit[column, row + 1]
    )
    if np.count_nonzero(beside) < FILLED_SHARE * len(index):
        return None  # shots picked here and there off a finer grid: not every cell was shot
    pan = pan0 + low[0] + steps[0] * np.arange(shape[0])
    tilt = low[1] + steps[1] * np.arange(shape[1])
    pan, tilt = np.meshgrid(pan, tilt, indexing="ij")
    cos_tilt = np.cos(tilt).ravel()
    directions = np.column_stack(
        [cos_tilt * np.cos(pan).ravel(), cos_tilt * np.sin(pan).ravel(), np.sin(tilt).ravel()]
    )
    return index, shape, directions, (pan0, low, steps)


def filled_share(cylinder, inliers: np.ndarray, points: np.ndarray, view: np.ndarray) -> float:
    """How many of the raster's cells inside ``cylinder``'s silhouette, seen from ``view``
    (3,) metres, its ``inliers`` (n,) bool of ``points`` (n, 3) metres could fill: their count
    over the silhouette's solid angle in raster cells (a cheap bound before the cells are read:
    each inlier fills one cell, so open space needs the share below one).

    The cell is the finest nonzero step between the shots' pans times that between their
    tilts (a raster's shots share their lines' angles exactly); the silhouette is the finite
    cylinder's side as projected, ``2 r L sin(g)`` over the squared distance (``g`` the angle
    between the axis and the line of sight; beams through an end face are not counted in
    :func:`open_cells` either). Returns ``inf`` when no step is
    seen in either angle.
    """
    # As few numpy calls as can be, on the whole scan: this runs after every fit with a
    # station (each call's dispatch costs more than its arithmetic on 40 shots).
    offset = points - view
    x, y, z = offset[:, 0], offset[:, 1], offset[:, 2]
    angles = np.empty((2, len(points)))
    np.arctan2(y, x, out=angles[0])
    np.arctan2(z, np.hypot(x, y), out=angles[1])
    angles.sort(axis=1)
    if angles[0, -1] - angles[0, 0] > math.pi:
        # The pans may straddle the back (+-pi): measured from the first shot's instead.
        angles[0] = np.sort((np.arctan2(y, x) - math.atan2(y[0], x[0]) + math.pi) % math.tau)
    gaps = angles[:, 1:] - angles[:, :-1]
    gaps[gaps <= (_SAME_LINE * (angles[:, -1] - angles[:, 0]))[:, None]] = np.inf
    pan_step, tilt_step = gaps.min(axis=1).tolist()
    sx, sy, sz = (cylinder.center - view).tolist()
    ax, ay, az = cylinder.axis.tolist()
    horizontal = math.hypot(sx, sy)
    distance = math.hypot(horizontal, sz)
    cosine = min(1.0, abs(sx * ax + sy * ay + sz * az) / distance)
    area = 2.0 * cylinder.radius * cylinder.length * math.sqrt(1.0 - cosine * cosine)
    cell = pan_step * tilt_step * horizontal / distance  # times the cosine of the tilt
    if not 0.0 < cell < math.inf:
        return math.inf
    cells = area / (distance * distance * cell)
    return float(np.count_nonzero(inliers)) / max(cells, 1e-300)


def _inside(cylinder, view: np.ndarray, directions: np.ndarray, margin: float) -> np.ndarray:
    """Which beams from ``view`` along ``directions`` (m, 3) pass the axis of ``cylinder`` at
    least ``margin`` (radians, times the range there) inside its radius, entering it within its
    length less that margin at each end: (m,) bool."""
    axis, radius = cylinder.axis, cylinder.radius
    offset = view - cylinder.center
    along_view = float(offset @ axis)
    along = directions @ axis
    across_d = directions - np.outer(along, axis)
    across_w = offset - along_view * axis
    a = np.einsum("ij,ij->i", across_d, across_d)
    b = across_d @ across_w
    safe = np.maximum(a, 1e-300)
    # Closest approach of each beam to the axis, and how far along the beam it lies.
    nearest = np.sqrt(np.maximum(float(across_w @ across_w) - b * b / safe, 0.0))
    reach = -b / safe
    pad = margin * np.maximum(reach, 0.0)
    entry = reach - np.sqrt(np.maximum(radius * radius - nearest * nearest, 0.0) / safe)
    at = along_view + entry * along
    return (
        (a > 1e-12)
        & (reach > 0.0)
        & (nearest <= radius - pad)
        & (np.abs(at) <= 0.5 * cylinder.length - pad)
    )


def open_cells(cylinder, points: np.ndarray, view: np.ndarray, cells=None):
    """The raster cells inside ``cylinder``'s silhouette, seen from ``view`` (3,) metres, that
    came back with nothing and touch ``OPEN_CELLS`` - 1 others such (module docstring).

    Parameters
    ----------
    cylinder : Cylinder
        The fit (its length the inliers' extent).
    points : ndarray, shape (n, 3), metres
        Every shot of the scan (a beam that came back from anything is no open space).
    view : ndarray, shape (3,), metres
    cells : tuple, optional
        :func:`_window_cells` of ``points`` and ``view``, when already computed.

    Returns
    -------
    ndarray or None
        (pan cells, tilt cells) bool, the open cells; None off a raster.
    """
    if cells is None:
        cells = _window_cells(points, view)
    if cells is None:
        return None
    index, shape, directions, frame = cells
    hit = np.zeros(shape, dtype=bool)
    hit[index[:, 0], index[:, 1]] = True
    inside = _inside(cylinder, view, directions, 0.5 * float(frame[2].max())).reshape(shape)
    empty = inside & ~hit
    if np.count_nonzero(empty) < OPEN_CELLS:
        return np.zeros(shape, dtype=bool)
    labels, count = ndimage.label(empty)
    sizes = np.bincount(labels.ravel(), minlength=count + 1)
    sizes[0] = 0
    return sizes[labels] >= OPEN_CELLS


def _line_axis(cylinder, view: np.ndarray, frame) -> int | None:
    """Which cell index is constant along the raster lines that run along ``cylinder``'s axis
    (0: pan columns, 1: tilt rows), or None when the axis runs slanted across them."""
    pan0, _, steps = frame
    ends = cylinder.center + np.outer([-0.5, 0.5], cylinder.axis) * cylinder.length - view
    pan = np.arctan2(ends[:, 1], ends[:, 0]) - pan0
    pan = (pan + np.pi) % (2.0 * np.pi) - np.pi
    tilt = np.arctan2(ends[:, 2], np.hypot(ends[:, 0], ends[:, 1]))
    span = np.abs([pan[1] - pan[0], tilt[1] - tilt[0]]) / steps
    if span[1] >= ALONG_RATIO * span[0]:
        return 0
    if span[0] >= ALONG_RATIO * span[1]:
        return 1
    return None


def sides(index: np.ndarray, opened: np.ndarray, kept: np.ndarray, line_axis: int) -> list:
    """The shots on each side of open space: masks (n,) bool of the shots on neighbouring raster
    lines along the axis (``line_axis``: :func:`_line_axis`) holding ``kept`` (n,) bool shots,
    parted where ``OPEN_CELLS`` or more cross lines hold a kept shot on either line and an open
    cell (``opened``, :func:`open_cells`) on them or between them."""
    lines = np.unique(index[kept, line_axis])
    mine = np.zeros(opened.shape, dtype=bool)
    mine[index[kept, 0], index[kept, 1]] = True
    if line_axis == 1:
        opened, mine = opened.T, mine.T
    groups, current = [], [lines[0]]
    for a, b in zip(lines[:-1], lines[1:], strict=True):
        parted = opened[a : b + 1].any(axis=0) & (mine[a] | mine[b])
        if np.count_nonzero(parted) >= OPEN_CELLS:
            groups.append(current)
            current = []
        current.append(b)
    groups.append(current)
    return [np.isin(index[:, line_axis], group) for group in groups]


def open_beside(index: np.ndarray, opened: np.ndarray, kept: np.ndarray, line_axis: int) -> int:
    """How many cross lines hold an open cell (``opened``, :func:`open_cells`) on a raster
    line along the axis (``line_axis``: :func:`_line_axis`) beyond the first or last that
    holds a ``kept`` (n,) bool shot of ``index`` (n, 2) int: open space beside the fit's
    shots, inside its silhouette."""
    lines = index[kept, line_axis]
    if line_axis == 1:
        opened = opened.T
    low, high = int(lines.min()), int(lines.max())
    outside = opened[:low].any(axis=0) | opened[high + 1 :].any(axis=0)
    return int(np.count_nonzero(outside))


def _side_fits(fit, points, view, sigma, tolerances, parts) -> list:
    """``(fit, inliers)`` of each of ``parts`` ((n,) bool) that fits a pipe alone
    (:func:`asbuilt.fit._cylinder_others.cylinder_of`), fullest first."""
    found = []
    for mask in parts:
        if np.count_nonzero(mask) >= FEWEST_SHOTS:
            one = cylinder_of(fit, points, mask, sigma, tolerances, view, [])
            if one is not None:
                found.append(one)
    found.sort(key=lambda one: -int(np.count_nonzero(one[1])))
    return found


def apart_across_open_space(fit, points, view, sigma, tolerances, result):
    """``result``, a fit of every shot, checked for open space inside its silhouette.

    Parameters
    ----------
    fit : callable
        ``fit(points, sigma, tolerances, viewpoint)``, the cylinder fit of a subset keeping the
        viewpoint (raises FitError when refused).
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres, or None
        The stated station, even when the fit ignored it: the shots' directions from it fall
        on a raster's lines (:func:`asbuilt.fit._silhouette.raster_grid`), which those from a
        wrong station do not.
    sigma : float or None, metres
    tolerances : Tolerances
    result : FitResult

    Returns
    -------
    FitResult
        ``result`` itself when no open space lies in its silhouette (or nothing can be read:
        no station, no raster, an axis slanted across it), when the open space between its
        raster lines parts none of them, or when each side that fits a pipe fits this one.

    Raises
    ------
    OpenSpaceFit
        Open space parts the fit's shots into sides (the message names those that fit a
        pipe alone), or lies on the raster lines beside them (``refused``: ``result``).
    """
    if view is None or len(points) > MOST_CELLS:
        return result
    if filled_share(result.primitive, result.inliers, points, view) >= FILLED_BELOW:
        return result  # its inliers fill most of its side's cells (the cheap bound first)
    cells = _window_cells(points, view)
    if cells is None:
        return result
    cylinder = result.primitive
    opened = open_cells(cylinder, points, view, cells)
    if not opened.any():
        return result
    line_axis = _line_axis(cylinder, view, cells[3])
    if line_axis is None:
        return result
    kept = np.asarray(result.inliers, dtype=bool)
    parts = sides(cells[0], opened, kept, line_axis)
    what = (
        f"the fit of every shot (r {radius_text(cylinder.radius)}) has"
        f" {int(np.count_nonzero(opened))} raster beams inside its silhouette that came back"
        " with nothing (open space, where a convex pipe would have returned them)"
    )
    if len(parts) < 2:
        # Its own shots are one side. Open space between its lines on fewer than OPEN_CELLS
        # cross lines is a band of dropouts; open space on the lines beside them, where the
        # fitted surface goes on over its shots' edge, says it does not (a box column's face
        # fitted as a wide cylinder, the pipe behind it seen past its edge).
        beside = open_beside(cells[0], opened, kept, line_axis)
        if beside < OPEN_CELLS:
            return result
        others = int(np.count_nonzero(~kept))
        raise OpenSpaceFit(
            f"{OPEN_SPACE}: {what}, on {beside} cross lines of the raster beside its"
            f" {int(np.count_nonzero(kept))} shots, where the surface it claims goes on and"
            " the beams passed through: its shots are the part of something else (a flat or"
            f" angled face) that a wide cylinder fits, not a pipe. {others} shots were left"
            " out of it. Give the object only its pipe's shots, or rescan with more of the"
            " raster on the pipe.",
            refused=result,
        )
    found = _side_fits(fit, points, view, sigma, tolerances, parts)
    if found and all(not apart(one.primitive, cylinder) for one, _ in found):
        return result  # every side fits this very pipe: dropouts, not two objects
    if not found:
        held = ", ".join(str(int(np.count_nonzero(mask))) for mask in parts)
        raise OpenSpaceFit(
            f"{OPEN_SPACE}: {what}, so they are not one pipe. The {len(parts)} sides hold"
            f" {held} shots and none alone fits a pipe (too few raster lines on it, or a flat"
            " face). Give the object only its pipe's shots, or rescan with more of the raster"
            " on the pipe.",
            refused=result,
        )
    # A side that stands is not kept as the object: in a rack the fullest side can be the
    # neighbour, holding most of the shots (review scenes: 2 of 4 kept sides were it). As when
    # no cylinder holds most shots (asbuilt.fit._cylinder_others), the sides are named.
    named = "; ".join(
        f"r {radius_text(one.primitive.radius)} over {int(np.count_nonzero(inliers))} shots"
        for one, inliers in found
    )
    raise OpenSpaceFit(
        f"{OPEN_SPACE}: {what}, so they are not one pipe. Of its {len(parts)} sides"
        f" {len(found)} fit a pipe alone ({named}): which is the object is not known. Give"
        " the object only its own shots.",
        refused=result,
    )
