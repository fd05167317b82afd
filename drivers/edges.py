"""Where a scan session's raster lines and edge-bisection pairs go (pure functions), and the
brackets the bisection ended on as the scan file records them (:func:`edge_turns`).

Helpers of :func:`asbuilt.drivers.session.scan_target`: the fewest raster lines for an object
(:func:`min_lines`), the pairs of raster cells that bracket the object's silhouette on each side
(:func:`boundary_pairs`), which of them to bisect (:func:`deal_pairs`), and the bracket and
back-step geometry. Angles in radians; a raster's cells as a (rows, cols) bool array of
object hits.
"""

from __future__ import annotations

import math

import numpy as np

from .kinematics import beam
from .plan import Window

__all__ = [
    "BACK_STEPS",
    "SIDES",
    "boundary_pairs",
    "bracket",
    "deal_pairs",
    "distinct_brackets",
    "edge_turns",
    "is_extreme",
    "is_interior",
    "long_sides",
    "min_lines",
    "on_a_line_shot",
    "same_position",
]


#: Fewest raster rows and columns by kind (3 otherwise): a cuboid is mostly seen on two faces,
#: each of which needs two lines of shots for its plane; five lines across the object's window
#: give that wherever the corner falls (a column seen edge-on in a tall window would otherwise
#: get three columns, one of them alone on a face).
_MIN_LINES = {"cuboid": 5}
#: A window at least this many times longer (as an angle) than wide frames an elongated object
#: (a column, a beam): see :func:`min_lines`.
_ELONGATED = 2.0


def min_lines(kind: str, window: Window) -> tuple[int, int]:
    """Fewest raster ``(rows, cols)`` for an object of ``kind`` framed by ``window``.

    ``_MIN_LINES`` across the window (3 for kinds not listed). Along a window at least
    ``_ELONGATED`` times longer than wide (pan extent times the cosine of the middle tilt
    against tilt extent) three lines: an elongated object's seen faces lie side by side across
    the window (a column's or a beam's corner edges run along it), so every line along it
    crosses each of them and their split needs no extra lines there. The shots saved go to the
    edge bisection instead when the object's point budget is small.
    """
    least = _MIN_LINES.get(kind, 3)
    along = long_sides(window)
    if along == ("bottom", "top"):
        return least, 3
    if along == ("left", "right"):
        return 3, least
    return least, least


#: Brackets back inside a pair's last hit, in turn, for a hit off the raster's lines when
#: that hit shares its bisected angle with others (see :func:`scan_target`).
BACK_STEPS = (1.0, 2.0, 4.0)

#: The silhouette's sides, in the order pairs are dealt to them: pan low and high (left, right),
#: tilt low and high (bottom, top).
SIDES = ("left", "right", "bottom", "top")


def on_a_line_shot(inside: np.ndarray, outside: np.ndarray, hit, shots: list, is_hit) -> bool:
    """Whether another hit shares the bisected angle of a pair's last hit.

    The bisected angle is the one in which ``inside`` and ``outside`` (the pair's requested
    ``[pan, tilt]``, radians) differ: pan for a left or right pair, tilt for a bottom or top
    one. ``hit``: the pair's last hit (a :class:`Shot`); ``shots``: the object's shots so far;
    ``is_hit(shot)``: whether one is on the object. Angles are compared where the head reached
    them, not where they were asked for: a head aiming in whole positions puts a request a
    fraction of a position off a raster column on that column.
    """
    axis = 0 if abs(outside[0] - inside[0]) > abs(outside[1] - inside[1]) else 1
    other = 1 - axis
    at = (hit.pan, hit.tilt)
    return any(
        abs((s.pan, s.tilt)[axis] - at[axis]) <= _SAME_ANGLE
        and abs((s.pan, s.tilt)[other] - at[other]) > _SAME_ANGLE
        and is_hit(s)
        for s in shots
    )


#: Angles (radians) closer than this are one head position: far below any unit's step
#: (0.0514 degree on a PTU-D46, 0.01 degree on a Pelco head) and above rounding in radians.
_SAME_ANGLE = 1e-9


def same_position(one, other) -> bool:
    """Whether two shots (:class:`Shot`) were taken with the head at the same position."""
    return abs(one.pan - other.pan) <= _SAME_ANGLE and abs(one.tilt - other.tilt) <= _SAME_ANGLE


def bracket(inside: np.ndarray, outside: np.ndarray) -> float:
    """Angle (radians) between two unit-angle directions ``[pan, tilt]`` (small-angle form)."""
    d_pan = (outside[0] - inside[0]) * math.cos(0.5 * (inside[1] + outside[1]))
    return math.hypot(d_pan, outside[1] - inside[1])


def is_extreme(pair: tuple, cells: np.ndarray, side: str) -> bool:
    """Whether a boundary pair's inside cell lies on the outermost line of object cells on its
    side (``pair``: ``((r, c), (r2, c2))``; ``cells`` (rows, cols) bool): the lowest column
    holding object cells for a left pair, the highest for a right one, the lowest or highest
    row for a bottom or top one."""
    (r, c), _ = pair
    rows, cols = np.nonzero(cells)
    if side == "left":
        return c == cols.min()
    if side == "right":
        return c == cols.max()
    if side == "bottom":
        return r == rows.min()
    return r == rows.max()


def long_sides(window: Window) -> tuple[str, ...]:
    """The silhouette sides that run along an elongated object framed by ``window``: left and
    right for a window at least ``_ELONGATED`` times taller than wide (a column), bottom and
    top for one that many times wider than tall (a beam), none otherwise."""
    wide = window.width * math.cos(0.5 * (window.tilt_min + window.tilt_max))
    if window.height >= _ELONGATED * wide:
        return ("left", "right")
    if wide >= _ELONGATED * window.height:
        return ("bottom", "top")
    return ()


def is_interior(pair: tuple, cells: np.ndarray, side: str) -> bool:
    """Whether a boundary pair's inside cell has object cells on both sides along its side.

    ``pair`` is ``((r, c), (r2, c2))`` (inside cell, outside cell) of ``cells`` (rows, cols)
    bool. For a left or right pair the cells above and below the inside cell, for a bottom or
    top pair those left and right of it, must be on the object (and in the raster): the edge
    then runs on past the pair both ways, and the bisection pins it rather than a row cut
    short by the object's end (a column's bottom, seen from above).
    """
    (r, c), _ = pair
    rows, cols = cells.shape
    steps = ((-1, 0), (1, 0)) if side in ("left", "right") else ((0, -1), (0, 1))
    return all(
        0 <= r + dr < rows and 0 <= c + dc < cols and bool(cells[r + dr, c + dc])
        for dr, dc in steps
    )


def distinct_brackets(pairs: list, axis: int) -> list:
    """One pair per bracket: the middle one of the pairs sharing their angles along ``axis``.

    Pairs of one side that bracket the same two raster lines (a straight edge crossing many
    rows between the same two columns) would be bisected into the same angles: the second
    would pin the same line again, and its shots, sharing angles with the first's, would look
    like a raster line to the fit. Groups keep the order of their first pair.
    """
    groups: dict[tuple, list] = {}
    for pair in pairs:
        key = (round(float(pair[0][axis]), 12), round(float(pair[1][axis]), 12))
        groups.setdefault(key, []).append(pair)
    return [group[(len(group) - 1) // 2] for group in groups.values()]


def deal_pairs(sides: dict[str, list], count: int) -> list:
    """Up to ``count`` pairs, dealt in turn to the sides that have any.

    A side's share is taken at evenly spaced quantiles of its pairs in boundary order (its
    middle one for a share of one), away from the silhouette's corners, where an edge of the
    window's side meets the next. A side with fewer pairs than its share gives them all and the
    rest goes to the others. Returns the pairs as given (``(inside, outside, range, beyond,
    ...)``), side by side.
    """
    available = [side for side in SIDES if sides[side]]
    share = dict.fromkeys(available, 0)
    left = min(count, sum(len(sides[s]) for s in available))
    while left > 0:
        for side in available:
            if left > 0 and share[side] < len(sides[side]):
                share[side] += 1
                left -= 1
    out = []
    for side in available:
        pairs = sides[side]
        k = share[side]
        picks = np.unique(np.floor((np.arange(k) + 0.5) * len(pairs) / k).astype(int)) if k else []
        out.extend(pairs[i] for i in picks)
    return out


def boundary_pairs(cells: np.ndarray) -> dict[str, list]:
    """(inside cell, outside cell) neighbour pairs that straddle the boundary, by side.

    ``cells`` (rows, cols) bool, row 0 at the lowest tilt and column 0 at the lowest pan. A pair
    belongs to the side its outside cell is on: ``"left"`` (lower pan), ``"right"``,
    ``"bottom"`` (lower tilt) or ``"top"``; horizontal pairs are listed row by row, vertical
    ones column by column (boundary order along each side). An object cell on the raster's
    border pairs with the (unshot) cell beyond it (row or column index -1, ``rows`` or
    ``cols``): an operator's window is often only a fraction of a cell wider than the object,
    so its outer cells are on it and the edge lies beyond them.
    """
    rows, cols = cells.shape
    padded = np.zeros((rows + 2, cols + 2), dtype=bool)
    padded[1:-1, 1:-1] = cells
    found: dict[str, list] = {side: [] for side in SIDES}
    for r in range(rows):
        for c in range(-1, cols):
            a, b = padded[r + 1, c + 1], padded[r + 1, c + 2]
            if a != b:
                found["right" if a else "left"].append(
                    ((r, c), (r, c + 1)) if a else ((r, c + 1), (r, c))
                )
    for c in range(cols):
        for r in range(-1, rows):
            a, b = padded[r + 1, c + 1], padded[r + 2, c + 1]
            if a != b:
                found["top" if a else "bottom"].append(
                    ((r, c), (r + 1, c)) if a else ((r + 1, c), (r, c))
                )
    return found


def edge_turns(result, calibration) -> list:
    """``acquisition.edge_brackets`` of an object (``result``, an ObjectScan; ``calibration``
    its chain): per bisected pair whose last hit is one of its points, ``[point index, dx, dy,
    dz, ux, uy, uz]``: the first miss's beam direction less the hit's, and the miss's (unit
    vectors, scan frame), from the angles the head reached (docs/scan-format.md)."""
    kept = np.cumsum(result.on_object) - 1
    out = []
    for hit, miss in result.brackets:
        if not result.on_object[hit]:
            continue
        a, b = result.shots[hit], result.shots[miss]
        _, dirs = beam(calibration, np.array([a.pan, b.pan]), np.array([a.tilt, b.tilt]))
        dirs = dirs / np.linalg.norm(dirs, axis=1, keepdims=True)
        turn = np.round(dirs[1] - dirs[0], 12).tolist()
        out.append([int(kept[hit]), *turn, *np.round(dirs[1], 12).tolist()])
    return out
