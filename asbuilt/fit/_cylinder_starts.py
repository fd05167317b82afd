"""Starting axes for the cylinder fit, and which of them the robust fit trusts first.

Normal-based axes (the smallest eigenvector of the Tukey-reweighted ``sum n n^T`` of local
normals, Hoppe et al. 1992), the points' principal directions, minimal two-point samples
(Schnabel, Wahl & Klein 2007) and a robust line through the points; a pattern search on the
axis (Hooke & Jeeves 1961) polishes the best of them on the robust circle's trimmed cost.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._circles import circle_starts
from asbuilt.fit._common import (
    FreshGenerator,
    orthonormal_bases,
    principal_axes,
    quick_median,
    robust_scale,
    row_norms,
    tukey_weights,
)
from asbuilt.fit._small_linalg import eigh

__all__ = [
    "POLISH_BELOW",
    "OFF_START",
    "OFF_START_COS",
    "SAME_START_COS",
    "SAME_START_RELATIVE",
    "POLISHED_STARTS",
    "same_start",
    "trust_order",
    "axis_starts",
    "normal_axes",
    "starts_of",
    "polish_axes",
    "quick_axes",
    "line_axis",
    "pair_starts",
]


#: Scans with fewer points than this always get the axis pattern search (:func:`polish_axes`)
#: on their best starts; larger ones only when the first fit rejected points (background shots
#: present), keeping the likelier of the two fits. With 20% background shots, starts several
#: degrees off otherwise converge to a wrong radius in a few percent of scenes; the search
#: costs 1-3 ms, which the 40-point speed target on clean scans cannot afford every time.
POLISH_BELOW = 35


#: Trimmed-cost ratio above which the normal-based start (the first) is taken as off ...
OFF_START = 100.0


#: ... when its axis is also more than 45 degrees from the best start's.
OFF_START_COS = float(np.cos(np.radians(45.0)))


#: Two starts are one hypothesis when their axes are within 2 degrees and their centres (across
#: the axis) and radii within 2% of the radius.
SAME_START_COS = float(np.cos(np.radians(2.0)))


SAME_START_RELATIVE = 0.02


#: How many of the best starts get the pattern search (two: with the reconsideration below a
#: third changed one cell of the benchmark by noise and cost about 1 ms with background shots).
POLISHED_STARTS = 2


def same_start(one, other) -> bool:
    """Whether two starts (axis, centre, radius) are one hypothesis (``SAME_START_*``)."""
    axis, center, radius = one
    if abs(float(axis @ other[0])) < SAME_START_COS:
        return False
    scale = SAME_START_RELATIVE * max(radius, other[2])
    offset = other[1] - center
    across = offset - float(offset @ axis) * axis
    return abs(radius - other[2]) <= scale and float(np.sqrt(across @ across)) <= scale


def trust_order(starts: list, costs: list) -> tuple[list, list, int]:
    """The starts in the order :func:`~asbuilt.fit._robust.robust_geometric_fit` trusts them and how many it must
    refine (its ``always_refine``).

    The normal-based start comes first and is refined together with the best other start
    (lowest trimmed cost), except where that pair is redundant: when the best other start is
    the same hypothesis (:func:`same_start`), refining it again would land in the same place;
    when the normal-based start is a far worse, different one (axis more than 45 degrees off,
    trimmed cost ``OFF_START`` times higher), the best start goes first alone. Either way
    further starts are still refined while their cost is below the best refined fit's.
    """
    if len(starts) < 2:
        return starts, costs, 2
    second = 1 + int(np.argmin(costs[1:]))
    if same_start(starts[0], starts[second]):
        return starts, costs, 1
    best = second if costs[second] < costs[0] else 0
    if (
        costs[0] > OFF_START * costs[best]
        and abs(float(starts[0][0] @ starts[best][0])) < OFF_START_COS
    ):
        order = [best] + [k for k in range(len(starts)) if k != best]
        return [starts[k] for k in order], [costs[k] for k in order], 1
    return starts, costs, 2


def _normal_axis(normals: np.ndarray, flatness: np.ndarray):
    """Eigenvectors of the Tukey-reweighted ``sum n n^T``, most perpendicular to normals first."""
    weights = 1.0 / (1.0 + flatness / max(quick_median(flatness), 1e-12))
    vectors = None
    for _ in range(2):
        scatter = (normals * weights[:, None]).T @ normals
        _, vectors = eigh(scatter)
        cosines = normals @ vectors[:, 0]
        scale = robust_scale(cosines, 0.02)
        weights = tukey_weights(cosines, scale)
        if np.count_nonzero(weights) < 3:
            break
    return vectors.T


def _unique(candidates, limit: float = 0.995) -> list[np.ndarray]:
    """Drop directions within ``arccos(limit)`` (about 6 degrees) of an earlier one."""
    unique: list[np.ndarray] = []
    for axis in candidates:
        if all(abs(float(axis @ other)) < limit for other in unique):
            unique.append(axis)
    return unique


def axis_starts(points: np.ndarray, normals, flatness, directions=None) -> list[np.ndarray]:
    """The normals' eigenvectors (most perpendicular first) and the points' principal axes
    (``directions``, rows, when the caller has them already)."""
    if directions is None:
        _, _, directions = principal_axes(points)
    return starts_of(normal_axes(normals, flatness), directions)


def normal_axes(normals: np.ndarray, flatness: np.ndarray) -> np.ndarray:
    """The normals' eigenvectors, rows, most perpendicular to the normals first (the first of
    :func:`axis_starts`)."""
    return _normal_axis(normals, flatness)


def starts_of(normal: np.ndarray, directions: np.ndarray) -> list[np.ndarray]:
    """:func:`axis_starts` from the normals' eigenvectors (:func:`normal_axes`) and the principal
    axes, rows."""
    return _unique(list(normal) + list(directions))


def quick_axes(first_axis: np.ndarray, directions: np.ndarray) -> list[np.ndarray]:
    """The axes the quick path (:func:`asbuilt.fit._cylinder_quick.quick_fit`) starts from:
    the normals' most perpendicular eigenvector (``first_axis``, the first of
    :func:`normal_axes` and so of :func:`axis_starts`) and the points' longest principal axis
    (``directions[0]``, rows), once when within about 6 degrees of each other. On the benchmark's 40-shot scans the quick fit stands as often from
    these two as from all of :func:`axis_starts`' (292 of 300 clean, 177 against 178 of 300
    with 20% edge outliers), at 11-15% fewer instructions per fit: the other eigenvectors and
    principal axes lie across the pipe, and their circles only cost."""
    return _unique([first_axis, directions[0]])


def polish_axes(
    points, states, costs, keep, rng, steps=(8.0, 4.0, 2.0, 1.0, 0.5, 0.25), cutoff=None
):
    """Pattern search on the axis (Hooke & Jeeves 1961) around each start, on the trimmed cost
    of the robust circle across each trial axis (all starts' rings in one batch per step).

    The robust circle's trimmed cost is sharp in the axis (a pipe seen over 1.8 m is smeared by
    3 cm when the axis is 1 degree off), so a start some degrees off, which a local
    least-squares descent may pull onto a background shot, is first brought within a quarter
    degree. Returns the polished (states, costs).
    """
    states, costs = list(states), list(costs)
    if not states:  # no circle across any candidate axis (scattered shots): nothing to polish
        return states, costs
    ring = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
    cos_ring, sin_ring = np.cos(ring)[:, None], np.sin(ring)[:, None]
    for step in steps:
        tilt = np.tan(np.radians(step))
        # Every state's ring at once (s, 8, 3), the same arithmetic as one state at a time.
        axes = np.array([state[0] for state in states])
        u, v = orthonormal_bases(axes)
        trials = axes[:, None, :] + tilt * (cos_ring * u[:, None, :] + sin_ring * v[:, None, :])
        trials = trials.reshape(-1, 3)
        trials /= row_norms(trials)[:, None]
        found, found_costs = circle_starts(
            points, list(trials), keep, rng, keep_invalid=True, cutoff=cutoff
        )
        for k in range(len(states)):
            block = found_costs[8 * k : 8 * k + 8]
            best = int(np.argmin(block))
            if block[best] < costs[k]:
                states[k], costs[k] = found[8 * k + best], block[best]
    return states, costs


def line_axis(points: np.ndarray, keep: int, rng, samples: int = 32, steps: int = 1):
    """Robust principal direction: the best line through two points by trimmed cost, then
    concentration steps (principal direction of the ``keep`` points closest to the line).

    A long pipe's points lie within a radius of its axis, so this is its axis even when
    background shots far behind it spoil the ordinary principal directions.
    """
    n = len(points)
    first = rng.integers(0, n, samples)
    second = rng.integers(0, n, samples)
    direction = points[second] - points[first]
    norm = row_norms(direction)
    good = norm > 1e-12
    if not np.any(good):
        return None
    direction = direction[good] / norm[good, None]
    base = points[first[good]]
    _, distance = _line_distances(points, base, direction)
    cost = np.partition(distance, keep - 1, axis=1)[:, :keep].sum(axis=1)
    best = int(np.argmin(cost))
    axis, point = direction[best], base[best]
    for _ in range(steps):
        rel = points - point
        along = rel @ axis
        distance = np.einsum("ij,ij->i", rel, rel) - along * along
        closest = points[np.argpartition(distance, keep - 1)[:keep]]
        point = closest.sum(axis=0) / len(closest)  # closest.mean(axis=0), less overhead
        centred = closest - point
        # Principal direction: the scatter matrix's leading eigenvector.
        axis = eigh(centred.T @ centred)[1][:, 2]
    return axis


def _line_distances(points: np.ndarray, base: np.ndarray, direction: np.ndarray):
    """Coordinates of points along lines and squared distances from them.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres (centred)
    base : ndarray, shape (s, 3), metres
        A point on each line.
    direction : ndarray, shape (s, 3)
        Unit directions.

    Returns
    -------
    along : ndarray, shape (s, n), metres
    squared : ndarray, shape (s, n), metres^2
        Written out as ``|p|^2 + |b|^2 - 2 p.b - along^2`` (two matrix products instead of an
        (s, n, 3) array of differences; the points are centred, so nothing cancels badly).
    """
    products = np.concatenate([direction, base]) @ points.T
    count = len(base)
    along = products[:count] - np.einsum("ij,ij->i", base, direction)[:, None]
    squared = np.einsum("ij,ij->i", points, points)[None, :] - 2.0 * products[count:]
    squared += np.einsum("ij,ij->i", base, base)[:, None]
    squared -= along * along
    return along, squared


_NEXT, _AFTER = [1, 2, 0], [2, 0, 1]


#: Two-point samples whose normals are within 10 degrees of parallel give no axis.
_PAIR_COS = float(np.cos(np.radians(10.0)))


def pair_starts(points, normals, keep: int, count: int, samples: int = 48):
    """Minimal-sample starts (Schnabel, Wahl & Klein 2007): two points and their normals.

    The axis is the cross product of the normals, the centre the closest approach of the two
    normal lines, the radius the mean distance of the two points from that axis. Every sample
    is scored by its least-trimmed-squares cost over all points; the ``count`` best are kept.
    Shots on the background spoil their own normals, so samples of two clean points (most of
    them with 20% outliers) give starts near the true cylinder even when a fit on all points
    is dragged away.
    """
    n = len(points)
    rng = FreshGenerator(n)  # np.random.default_rng(n)'s draws, remembered
    first = rng.integers(0, n, samples)
    second = rng.integers(0, n, samples)
    d1, d2 = normals[first], normals[second]
    b = np.einsum("ij,ij->i", d1, d2)
    good = (first != second) & (np.abs(b) < _PAIR_COS)
    if not np.any(good):
        return []
    first, second, d1, d2, b = first[good], second[good], d1[good], d2[good], b[good]
    p1, p2 = points[first], points[second]
    # Cross products, written out (np.cross is slow on short stacks).
    axis = d1[:, _NEXT] * d2[:, _AFTER] - d1[:, _AFTER] * d2[:, _NEXT]
    axis /= np.sqrt(np.einsum("ij,ij->i", axis, axis))[:, None]
    w = p1 - p2
    d = np.einsum("ij,ij->i", d1, w)
    e = np.einsum("ij,ij->i", d2, w)
    denom = 1.0 - b * b
    s = (b * e - d) / denom
    t = (e - b * d) / denom
    center = 0.5 * (p1 + s[:, None] * d1 + p2 + t[:, None] * d2)
    _, squared = _line_distances(points, center, axis)
    rho = np.sqrt(np.maximum(squared, 0.0, out=squared), out=squared)
    rows = np.arange(len(first))
    radius = 0.5 * (rho[rows, first] + rho[rows, second])
    residuals = rho - radius[:, None]
    keep = min(keep, n)
    cost = np.partition(residuals * residuals, keep - 1, axis=1)[:, :keep].sum(axis=1)
    order = np.argsort(cost)[:count]
    return [axis[i] for i in order if radius[i] > 0]
