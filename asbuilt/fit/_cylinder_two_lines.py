"""A pipe whose shots lie on two raster lines along it: the radius is bounded only from below.

Private helper of :mod:`asbuilt.fit._cylinder_finish`. Two raster columns along a vertical
pipe (or two rows along a horizontal one) put the shots on two straight lines on its surface.
In the cross-section they are two short arcs, and a circle through both fits them for any
radius above half their distance: the arcs' own curvature (a sagitta of a fraction of a
millimetre over a few centimetres) is below the noise. The least-squares fit then settles
near that smallest radius, where the circle bends most freely and absorbs the noise (an
independent review: 38.9 +-1.3 mm for a 57.1 mm pipe, 49.9 +-1.0 for 84.2; the true radius fits
the shots at a chi-square of 25 for 36 shots, the fit at 6.6). Its covariance, a linearisation
at that bend, does not see the long flat valley beyond.

:func:`on_two_lines` detects the two lines, and :func:`radius_reach` walks the radius up that
valley: the fit's axis and centre refitted at each larger radius (held fixed), for as long as
the shots still pass the chi-square test at the sensor's noise. The radius's standard error then spans the
radii the shots accept.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares
from scipy.stats import chi2

from asbuilt.fit._common import orthonormal_basis, row_norms
from asbuilt.fit._cylinder_model import angles_about
from asbuilt.fit._small_linalg import svd

__all__ = [
    "LINE_SPREAD",
    "RADIUS_STEPS",
    "on_two_lines",
    "on_two_raster_lines",
    "radius_reach",
]

#: Radii tried above the fit's, as multiples of it: up to eight times (a wider pipe than that
#: would have been hit by more raster lines at any usual raster step).
RADIUS_STEPS = (1.25, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0)
#: Chi-square tail probability at which a radius no longer fits the shots.
_ACCEPT = 0.99
#: Shots on one raster line share its pan (or tilt) to within this share of the gap to the
#: next line: a line's own width is the head's rounding or encoder scatter, a few thousandths
#: of a step.
LINE_SPREAD = 0.1


def on_two_lines(
    kept: np.ndarray, axis: np.ndarray, center: np.ndarray, width: float, about=None
) -> bool:
    """Whether a cylinder fit's inliers lie on two straight lines along it.

    The inliers' directions about the axis are split at their two widest gaps into two
    groups, each spanning at most half the narrower of those gaps; each must hold at least
    three shots lying within ``width`` metres RMS of a straight line (total least squares)
    that runs within 30 degrees of the axis. Where the gaps do not part two narrow groups,
    the shots may still lie on two straight lines slanted across the pipe
    (:func:`_on_two_straight_lines`).

    Parameters
    ----------
    kept : ndarray, shape (m, 3)
        The inliers, metres.
    axis : ndarray, shape (3,)
        The fitted unit axis.
    center : ndarray, shape (3,)
        A point on the axis, metres.
    width : float
        Metres: the inlier cutoff.
    about : ndarray, shape (m,), optional
        The inliers' directions about the axis, radians (``angles_about``), when known.
    """
    if kept.shape[0] < 6:
        return False
    if about is None:
        about = angles_about(axis, center, kept)
    order = about.argsort()  # np.argsort's order, without its wrapper
    angles = about[order]
    closed = np.concatenate([angles, [angles[0] + 2.0 * math.pi]])
    gaps = closed[1:] - closed[:-1]  # np.diff's differences, without its overhead
    first, second = sorted(gaps.argsort()[-2:].tolist())
    # Each group's own angular extent (the circle less the two gaps and the other group's):
    # lines are narrow beside the gaps that part them, scattered shots are not.
    inner = float(gaps[first + 1 : second].sum())
    outer = 2.0 * math.pi - inner - float(gaps[first] + gaps[second])
    if 2.0 * max(inner, outer) > min(gaps[first], gaps[second]):
        return _on_two_straight_lines(kept, axis, width)
    groups = [
        order[first + 1 : second + 1],
        np.concatenate([order[second + 1 :], order[: first + 1]]),
    ]
    for group, span in zip(groups, (inner, outer), strict=True):
        if group.size < 3:
            return False
        if _flat_arc(kept[group], axis, center, span, width):
            continue
        line = _line(kept[group], width)
        if line is None or abs(float(line[1] @ axis)) < math.cos(math.radians(30.0)):
            return False
    return True


def _flat_arc(group: np.ndarray, axis: np.ndarray, center: np.ndarray, span: float, width: float):
    """Whether the shots ``group`` (m, 3) metres, spanning ``span`` radians about the ``axis``
    through ``center``, bow by at most ``width`` metres over that arc (its sagitta): such a
    group is one line along the pipe as far as its curvature goes, however its shots scatter.

    A raster line grazing the pipe's silhouette is not straight to within the noise: its
    shots, mixed returns between the pipe and the wall behind included, spread along the
    grazing beams, which the fitted surface follows there within the inlier cutoff for
    decimetres. Seen as no line, its tangent passed for a measured curvature: three raster
    columns over a tank, the third on the wall behind and left out, fitted r 1.59 m +-22 mm
    for 1.95 from the front column and the grazing one.
    """
    rel = group - center
    radial = rel - np.outer(rel @ axis, axis)
    distance = float(np.median(row_norms(radial)))
    return distance * (1.0 - math.cos(0.5 * span)) <= width


#: Shots at each end of the inliers' run tried as the ends of a line in
#: :func:`_on_two_straight_lines`: each of two lines of shots ends among the few outermost.
END_SHOTS = 5


def _line(points: np.ndarray, width: float):
    """The straight line (a point (3,) metres, a unit direction (3,)) that ``points`` (m, 3)
    metres lie within ``width`` metres RMS of (total least squares), or None."""
    mean = points.mean(axis=0)
    _, singular, vt = svd(points - mean)
    if math.sqrt(float(singular[1] ** 2 + singular[2] ** 2) / len(points)) > width:
        return None
    return mean, vt[0]


def _apart(one, other, width: float) -> bool:
    """Whether two lines (:func:`_line`) run within 30 degrees of each other (as lines on a
    cylinder do) and more than twice ``width`` metres apart at their middles: two lines, not
    one ribbon of shots split anywhere (a thin pipe's shots, 21 mm across, at a 6 mm cutoff)."""
    if abs(float(one[1] @ other[1])) < math.cos(math.radians(30.0)):
        return False
    offset = other[0] - one[0]
    across = offset - (offset @ one[1]) * one[1]
    return float(np.linalg.norm(across)) > 2.0 * width


def _on_two_straight_lines(kept: np.ndarray, axis: np.ndarray, width: float) -> bool:
    """Whether the inliers ``kept`` (m, 3) metres of a fit along the unit ``axis`` (3,) lie on
    two straight lines of three shots or more each, whatever their angle about the axis.

    Two raster lines slanted across a pipe (a window turned to the pipe) sweep its surface at
    a few degrees to the axis: their directions about it run into each other, so the gaps of
    :func:`on_two_lines` cannot part them, yet over a short arc each line is straight to
    within the noise, and any two lines lie on cylinders of many radii (an independent
    review's plumb NPS 4 pipe behind a floor: r 30.1 +-1.8 mm for 57.15 from two such lines).
    Each line ends among the ``END_SHOTS`` outermost shots at each end of the run along the
    axis; every such pair of ends is tried as one line (the shots within
    ``width`` of it), the rest must be the other, each within half ``width`` RMS of its line
    (as thin as the noise, not a band of shots over the arc), the two within 30 degrees of
    each other and apart (:func:`_apart`).
    """
    if kept.shape[0] < 6:
        return False
    order = (kept @ axis).argsort()
    n = kept.shape[0]
    ends = min(END_SHOTS, n // 2)
    line = _near_end_pairs(kept, kept[order[:ends]], kept[order[-ends:]], width)
    count = line.sum(axis=1)  # np.count_nonzero's counts, without its Python wrapper
    # Only a candidate line of 3 to n - 3 shots can leave a second line of three or more.
    candidates = np.flatnonzero((count >= 3) & (count <= n - 3))
    if not candidates.size:
        return False
    line = line[candidates]
    # The rest, against the line through its own first and last shot along the run: a quick
    # screen, so that only a likely pair of lines pays for the two fits below.
    ranked = ~line[:, order]
    rest_first = order[ranked.argmax(axis=1)]
    rest_last = order[n - 1 - ranked[:, ::-1].argmax(axis=1)]
    rest = _near_line(kept, kept[rest_first], kept[rest_last], 2.0 * width)
    for k in np.flatnonzero((line | rest).all(axis=1)):
        # Each line as thin as the noise (half the cutoff RMS: 1.5 noise levels, where shots
        # spread evenly over a band as wide as the cutoff give 1.7, a rough pipe's shots
        # over its whole arc).
        one = _line(kept[line[k]], 0.5 * width)
        other = None if one is None else _line(kept[~line[k]], 0.5 * width)
        if other is not None and _apart(one, other, width):
            return True
    return False


def _near_end_pairs(points: np.ndarray, starts: np.ndarray, ends: np.ndarray, width: float):
    """:func:`_near_line` of every line from one of ``starts`` (e, 3) metres to one of ``ends``
    (e, 3) metres, shape (e * e, n) bool, row ``e * i + j`` the line from ``starts[i]`` to
    ``ends[j]``.

    The same sums as :func:`_near_line` of the e * e pairs (each row's offsets and their
    products summed by the same einsum loop), but the offsets from each start and their
    squares are taken once, not once per end: on 40 points numpy spends most of this test on
    the (e * e, n, 3) offsets.
    """
    e = len(starts)
    direction = (ends[None, :, :] - starts[:, None, :]).reshape(e * e, 3)
    direction /= np.maximum(row_norms(direction), 1e-12)[:, None]
    offset = points[None, :, :] - starts[:, None, :]  # (e, n, 3)
    square = np.einsum("ink,ink->in", offset, offset)
    along = np.einsum("ink,ijk->ijn", offset, direction.reshape(e, e, 3)).reshape(e * e, -1)
    return square.repeat(e, axis=0) - along**2 <= width**2


def _near_line(points: np.ndarray, first: np.ndarray, last: np.ndarray, width: float):
    """Which of ``points`` (n, 3) metres lie within ``width`` metres of each line from
    ``first`` (p, 3) to ``last`` (p, 3) metres, shape (p, n) bool."""
    direction = last - first
    direction /= np.maximum(row_norms(direction), 1e-12)[:, None]
    offset = points[None, :, :] - first[:, None, :]
    along = np.einsum("pnk,pk->pn", offset, direction)
    return np.einsum("pnk,pnk->pn", offset, offset) - along**2 <= width**2


def on_two_raster_lines(kept: np.ndarray, view: np.ndarray) -> bool:
    """Whether a cylinder fit's inliers ``kept`` (m, 3) metres all lie on two raster lines
    (two pans or two tilts) seen from the station ``view`` (3,) metres, three shots or more
    on each.

    Two raster lines across or slanted over a pipe are two curves on it, and cylinders of many
    radii (their axes and centres moved) pass through both within the noise, as for two lines
    along it (:func:`on_two_lines`): a black-box review's ray caster, pipes through a floor or
    lying on it, each shot by two raster rows slanted over it (15-18 shots a row), fitted
    r 41-86 mm for 57-110 mm at +-1-4 mm, the true radius passing the chi-square test as
    closely as the fit. Each line's shots share its angle to within ``LINE_SPREAD`` of the gap
    between the two lines.
    """
    if kept.shape[0] < 6:
        return False
    rel = kept - view
    mean = rel.sum(axis=0)
    # The tangents of each shot's pan about the shots' mean direction and of its tilt, rows
    # of one array (monotonic in the angles over a window, and fewer numpy calls: this runs
    # after every fit with a station).
    flat = rel[:, :2] @ np.array([[mean[0], -mean[1]], [mean[1], mean[0]]])
    tangents = np.empty((2, kept.shape[0]))
    np.divide(flat[:, 1], flat[:, 0], out=tangents[0])
    np.divide(rel[:, 2], np.sqrt(flat[:, 0] ** 2 + flat[:, 1] ** 2), out=tangents[1])
    ordered = np.sort(tangents, axis=1)
    gaps = ordered[:, 1:] - ordered[:, :-1]
    last = kept.shape[0] - 1
    for row, split in enumerate(gaps.argmax(axis=1).tolist()):
        gap = float(gaps[row, split])
        if not gap > 0.0 or min(split + 1, last - split) < 3:
            continue
        spread = max(
            ordered[row, split] - ordered[row, 0], ordered[row, last] - ordered[row, split + 1]
        )
        if spread <= LINE_SPREAD * gap:
            return True
    return False


def _fixed_radius_chi2(kept, weights, axis, center, radius, noise) -> float:
    """Least chi-square of the inliers (m, 3) metres, with ``weights`` (m,) (inverse relative
    variances), about a cylinder of the given ``radius`` metres, its axis and centre refitted
    from ``axis`` (3,) and ``center`` (3,) metres."""
    u, v = orthonormal_basis(axis)
    scale = np.sqrt(weights) / noise

    def residuals(q: np.ndarray) -> np.ndarray:
        direction = axis + q[0] * u + q[1] * v
        direction = direction / np.linalg.norm(direction)
        rel = kept - (center + q[2] * u + q[3] * v)
        across = rel - np.outer(rel @ direction, direction)
        return (np.linalg.norm(across, axis=1) - radius) * scale

    # From the fit's place and from the centre moved away by the added radius on either side
    # (the larger circle through the same two lines has its centre farther from them).
    grow = radius - float(
        np.median(np.linalg.norm((kept - center) - np.outer((kept - center) @ axis, axis), axis=1))
    )
    mid = kept.mean(axis=0) - center
    toward = mid - (mid @ axis) * axis
    toward = toward / max(float(np.linalg.norm(toward)), 1e-12)
    best = math.inf
    for sign in (0.0, -1.0, 1.0):
        start = np.array([0.0, 0.0, sign * grow * (toward @ u), sign * grow * (toward @ v)])
        fit = least_squares(residuals, start, method="lm")
        best = min(best, 2.0 * float(fit.cost))
    return best


def radius_reach(kept, weights, axis, center, radius, noise, n_parameters=5) -> float:
    """The largest radius (metres) at which a two-line fit's inliers still pass the
    chi-square test, its axis and centre refitted: the top of the radii the shots accept.

    Parameters
    ----------
    kept : ndarray, shape (m, 3)
        The inliers, metres.
    weights : ndarray, shape (m,)
        Their weights (inverse relative variances).
    axis, center : ndarray, shape (3,)
        The fitted unit axis and a point on it, metres.
    radius : float
        The fitted radius, metres.
    noise : float
        Metres: the noise level of a square-on shot (the sensor's sigma when given).
    n_parameters : int
        The cylinder's parameters (the chi-square test's degrees of freedom are the shots less
        these).

    Returns
    -------
    float
        Metres; ``radius`` itself when no larger radius tried passes.
    """
    limit = chi2.ppf(_ACCEPT, max(kept.shape[0] - n_parameters, 1))
    reach = radius
    for factor in RADIUS_STEPS:
        trial = factor * radius
        if _fixed_radius_chi2(kept, weights, axis, center, trial, noise) > limit:
            break
        reach = trial
    return reach
