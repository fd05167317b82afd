"""Whether a cylinder fit is consistent with its scan, and the MSAC circles that replace it
when it is not.

With a viewpoint the beams judge a fit (no third of the shots hidden behind the pipe, no fit
seen edge-on); without one, no shots may lie inside the pipe and no fit may be nearly a plane
over the points. The rescue fits come from circles chosen by MSAC cost (Torr & Zisserman 2000),
where every shot decides.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._circles import INSIDE_CAP, circle_starts
from asbuilt.fit._common import column_medians, quick_median
from asbuilt.fit._cylinder_model import MODEL, angles_about
from asbuilt.fit._cylinder_starts import POLISH_BELOW, line_axis, polish_axes
from asbuilt.fit._robust import RobustFit, keep_count, settled_fit
from asbuilt.fit._silhouette import raster_grid
from asbuilt.fit._visibility import (
    cylinder_beam_excess,
    edge_on_degrees,
    one_side_could_see,
)
from asbuilt.tolerances import MIN_POINTS, Tolerances

__all__ = [
    "SAME_BASIN_COS",
    "SAME_BASIN_RELATIVE",
    "PLANE_LIKE",
    "UNSEEN_FRACTION",
    "THROUGH_FRACTION",
    "RESCUE_STARTS",
    "RESCUE_SAMPLES",
    "RESCUE_REJECTED",
    "INSIDE_SHOTS",
    "SNAP_DEG",
    "msac_fits",
    "half_line_axes",
    "admissible",
    "better_fit",
    "consistent",
    "EDGE_ON_DEG",
    "EDGE_ON_QUARTILE_DEG",
    "edge_on",
    "ONE_STATION_DEG",
    "one_station_could_see",
    "RASTER_SHARE",
    "shot_from",
    "unseen",
    "unhidden_starts",
    "doubtful",
    "doubtful_blind",
    "robust_extent",
    "same_basin",
]


#: Two states are in one basin when their axes are within 5 degrees and radii within 10%.
SAME_BASIN_COS = float(np.cos(np.radians(5.0)))


SAME_BASIN_RELATIVE = 0.10


#: A cylinder this many times wider than the points' extent is, over them, nearly a plane.
PLANE_LIKE = 3.0


#: Fraction of the best fit's inliers seen through the pipe beyond which the viewpoint is taken
#: as wrong: from a wrong viewpoint about half of the shots of the true pipe are.
UNSEEN_FRACTION = 1.0 / 3.0


#: Circles (best by MSAC cost, one per candidate axis) settled by :func:`msac_fits`, and
#: the random triples it tries per axis: MSAC needs one triple of pipe shots from three raster
#: columns, 1 in 6 triples when a third of the shots are background.
RESCUE_STARTS = 4


RESCUE_SAMPLES = 96


#: Share of rejected shots from which a fit is compared with the MSAC circles' fits. Fits that
#: rejected 20-25% were wrong in 4 of 20 independent wall-line scans with 25% (the trimmed
#: cost's design contamination); it costs the benchmark's 20%-outlier fits about 3 ms.
RESCUE_REJECTED = 0.2


#: Shots inside the fitted pipe (:func:`_inside`) from which a fit is compared with the MSAC
#: circles' fits: one good shot lies beyond 3 sigma inside with probability 0.13%, two of 40
#: in under 0.2% of scans.
INSIDE_SHOTS = 2


#: Point pairs tried for the half-keep robust line of :func:`msac_fits`: with half the shots
#: background a pair is two pipe shots one time in four.
HALF_LINE_SAMPLES = 48

#: Candidate axes within this many degrees of plumb or level also get their plumb/level twin.
SNAP_DEG = 5.0


def half_line_axes(points: np.ndarray) -> list:
    """The robust line through the closest half of the shots (``[axis]``, or ``[]``), as a
    candidate axis for :func:`msac_fits`, the last resort when no consistent fit stands (none,
    or one that leaves shots inside its pipe, or hides a third of them behind it:
    :func:`better_fit`) and none of the other candidates' MSAC circles gave one.

    A pipe's shots lie within a radius of its axis however many background shots there are,
    while background beyond what the trimmed cost's starts allow (a window run past the pipe's
    end onto the wall: 15 of 36 shots) spoils every other axis estimate: none was within 5
    degrees of the pipe's, and the fit was refused or a 0.8 m cylinder through pipe and wall
    shots kept. Offered only then: the MSAC cost of a wider cylinder through the pipe's front and
    a few wall shots 0.2 m behind can be lower than the pipe's (an independent ray caster's
    rack and narrow-arc scans), so the line does not compete with a consistent fit. Its own generator
    leaves every other draw of the fit as it was.
    """
    minimum = MIN_POINTS["cylinder"]
    rng = np.random.default_rng(len(points) + 1)
    axis = line_axis(
        points, max(len(points) // 2, minimum), rng, samples=HALF_LINE_SAMPLES, steps=2
    )
    return [] if axis is None else [axis]


def msac_fits(points, axes, sigma: float, tolerances, keep, rng, inside: bool) -> list:
    """Fits from circles chosen by MSAC cost (``circle_starts(cutoff=...)``), for when the
    beams reject the robust choice (it hides a third of the shots behind the pipe, or no start
    settled) or it rejected ``RESCUE_REJECTED`` of the shots: whole raster lines on the wall
    behind a pipe are more background than the trimmed cost allows, and a large circle through
    pipe and wall shots wins it. Each of the ``RESCUE_STARTS`` best circles is settled by least
    squares on its inliers; plane-like cylinders (:func:`doubtful_blind`) are left out.
    :func:`better_fit` chooses among them."""
    cutoff = tolerances.outlier_cutoff_sigma * sigma
    # Background shots tilt every axis estimate by a degree or two, which smears a 3 m pipe's
    # projection by centimetres; plant pipes are mostly plumb or level, so each candidate
    # within SNAP_DEG of either gets its plumb or level twin (least squares then settles the
    # axis freely).
    snapped = []
    for axis in axes:
        if abs(axis[2]) >= np.cos(np.radians(SNAP_DEG)):
            snapped.append(np.array([0.0, 0.0, 1.0]))
        elif abs(axis[2]) <= np.sin(np.radians(SNAP_DEG)):
            level = np.array([axis[0], axis[1], 0.0])
            snapped.append(level / np.linalg.norm(level))
    starts, costs = circle_starts(
        points,
        list(axes) + snapped,
        keep,
        rng,
        samples=RESCUE_SAMPLES,
        cutoff=cutoff,
        inside=inside,
    )
    order = np.argsort(costs)[:RESCUE_STARTS]
    starts, costs = [starts[k] for k in order], [costs[k] for k in order]
    if inside:
        # A candidate axis a degree off smears a long pipe's circle by centimetres and leaves
        # its flank shots inside, so without the beams the best circles' axes are searched
        # (on the same cost) before they are settled.
        starts, costs = polish_axes(points, starts, costs, keep, rng, cutoff=cutoff)
    fits = []
    extent = robust_extent(points)  # once for every fit's doubtful_blind
    for k in range(len(starts)):
        fit = settled_fit(
            points, starts[k], MODEL, kind="cylinder", sigma=sigma, tolerances=tolerances
        )
        # A cylinder metres wide is a plane through pipe and wall shots, not a pipe.
        if fit is not None and not doubtful_blind(fit, points, extent):
            fits.append(fit)
    return fits


def _inside(robust: RobustFit, points: np.ndarray, cutoff: float) -> np.ndarray:
    """Shots deeper than ``cutoff`` (metres) inside a fit's solid, within its inliers' extent
    along the axis (beyond its ends the infinite cylinder is not the pipe), shape (n,) bool.

    No beam reaches the inside of an opaque pipe, from any viewpoint: a background shot lies
    outside the pipe, and a mixed-pixel return at its silhouette at most a footprint radius
    inside. Shots well inside a fitted cylinder say that it is the wrong one (a large circle
    through the pipe's front shots and the wall behind leaves the pipe's flanks inside it).
    """
    axis, center, _ = robust.state
    along = (points - center) @ axis
    kept = along[robust.inliers]
    if kept.size == 0:
        return np.zeros(len(points), dtype=bool)
    within = (along >= kept.min() - cutoff) & (along <= kept.max() + cutoff)
    return within & (robust.residuals < -cutoff) & (robust.residuals >= -INSIDE_CAP * cutoff)


def admissible(robust: RobustFit, points: np.ndarray, cutoff: float) -> bool:
    """Whether fewer than ``INSIDE_SHOTS`` shots lie inside the fit's pipe (:func:`_inside`)."""
    return int(np.count_nonzero(_inside(robust, points, cutoff))) < INSIDE_SHOTS


def better_fit(candidates, robust, points, view, cutoff: float):
    """The candidate with the lowest MSAC cost (every shot, threshold ``cutoff`` metres;
    Torr & Zisserman 2000) that is consistent with the scan, if it beats ``robust``; else None.

    With ``view`` known, consistent means hiding no third of the shots behind the pipe
    (:func:`unseen`), and each shot's beam excess counts in its cost as in the beams' second
    look (:func:`asbuilt.fit._visibility.visible_score`): on residuals alone a 27.5 mm
    circle wrapping two front shots round its far side, 17-22 mm past where their beams
    entered it, beat the 57 mm pipe the beams had chosen (MSAC 191 against 196; the accuracy
    benchmark's worst outlier trial). Without it, leaving no shots inside the pipe
    (:func:`admissible`), and any consistent candidate beats a ``robust`` fit that is not.
    """

    def cost(fit):
        squares = fit.residuals**2
        if view is not None:
            beyond = cylinder_beam_excess(*fit.state, points, view)
            squares = squares + beyond * beyond
        return float(np.minimum(squares, cutoff**2).sum())

    best, best_cost = None, np.inf
    if robust is not None and (view is not None or admissible(robust, points, cutoff)):
        best_cost = cost(robust)
    for fit in candidates:
        if cost(fit) < best_cost and consistent(fit, points, view, cutoff):
            best, best_cost = fit, cost(fit)
    return best


def consistent(fit: RobustFit, points: np.ndarray, view, cutoff: float) -> bool:
    """Whether a fit is consistent with its scan: with ``view`` known, it hides no third of the
    shots behind its pipe (:func:`unseen`); without, it leaves no shots inside it
    (:func:`admissible`, ``cutoff`` metres)."""
    if view is None:
        return admissible(fit, points, cutoff)
    return not unseen(fit, points, view)


#: Median incidence across the axis (:func:`edge_on_degrees`) of a fit's inliers above which
#: they are taken as returns strung along their beams, not a surface: half of a real pipe's
#: shots would lie within 1.5% of its radius from its silhouette. Measured: at most 76 degrees
#: over the benchmark's 4,500 cylinder fits (a wrong 20-shot fit of a thin pipe; right fits at
#: most 70), 77-88 for the mixed-pixel "pipes" metres wide fitted to an independent ray
#: caster's NPS 1 pipe 10 m away seen by three raster rows.
EDGE_ON_DEG = 80.0
#: Lower-quartile incidence above which the inliers are taken as strung along their beams too:
#: three quarters of a real pipe's shots would lie within the outer 9% of its silhouette's
#: half-width (evenly spread across it, the lower quartile is at 14.5 degrees). Measured with
#: the viewpoint on 1,800 benchmark cylinder fits (20 trials a cell, clean and with outliers):
#: at most 27.4 degrees for the right ones, 61.5 for the wrong ones (15 mm off); 76.8-78.2
#: for the 0.8-0.9 m mixed-pixel "pipes" whose median (77.6-79.4) stayed under
#: ``EDGE_ON_DEG``, fitted to an independent ray caster's NPS 1 pipe 10 m away seen by three
#: raster rows.
EDGE_ON_QUARTILE_DEG = 65.0


def edge_on(robust: RobustFit, points: np.ndarray, view: np.ndarray) -> bool:
    """Whether the fit's inliers were mostly seen edge-on from ``view``: their median incidence
    above ``EDGE_ON_DEG``, or their lower quartile above ``EDGE_ON_QUARTILE_DEG``."""
    axis, center, _ = robust.state
    angles = edge_on_degrees(axis, center, points[robust.inliers], view)
    angles = angles[np.isfinite(angles)]
    if not angles.size:
        return False
    # np.percentile(angles, [25, 50]) (linear interpolation), without its overhead (a tenth
    # of a clean 40-point fit's time).
    angles.sort()  # a fresh array: np.sort's copy is not needed
    ordered = angles
    quartile, median = (_interpolated(ordered, q) for q in (0.25, 0.5))
    return bool(median > EDGE_ON_DEG or quartile > EDGE_ON_QUARTILE_DEG)


def _interpolated(ordered: np.ndarray, fraction: float) -> float:
    """The ``fraction`` quantile of sorted values by linear interpolation between the closest
    ranks (numpy's default method)."""
    position = fraction * (ordered.size - 1)
    low = int(position)
    if low + 1 >= ordered.size:
        return float(ordered[low])
    return float(ordered[low] + (position - low) * (ordered[low + 1] - ordered[low]))


#: Median incidence below which a fit's inliers could have been seen from one unknown station
#: (:func:`one_station_could_see`). A raster across a pipe samples its silhouette about evenly,
#: a median incidence near 30 degrees; a "pipe" through a thin pipe's front shots and the wall
#: behind (two clusters some 165 degrees apart) shows one cluster at 75 degrees or more from any
#: direction that faces both.
ONE_STATION_DEG = 60.0


def one_station_could_see(robust: RobustFit, points: np.ndarray) -> bool:
    """Whether one unknown station could have seen the fit's inliers (:func:`one_side_could_see`,
    with all but ``UNSEEN_FRACTION`` of them facing it, not edge-on)."""
    axis, center, _ = robust.state
    angles = angles_about(axis, center, points[robust.inliers])
    return one_side_could_see(angles, 1.0 - UNSEEN_FRACTION, ONE_STATION_DEG)


#: Share of the shots whose directions from a station must fall on one pan-tilt raster's
#: columns and rows for the shots to be taken as shot from it (:func:`shot_from`): a raster's
#: own shots all do, edge outliers included (their directions are still the raster's).
RASTER_SHARE = 0.9


def shot_from(points: np.ndarray, view) -> bool:
    """Whether the shots ``points`` (n, 3) metres were shot from ``view`` (3,) metres: seen
    from it, ``RASTER_SHARE`` of their directions fall on evenly spaced pan columns and tilt
    rows (:func:`asbuilt.fit._silhouette.raster_grid`).

    A pan-tilt range finder records each point along its nominal angles, so from the station
    that shot them the directions line up on the raster's lines whatever the ranges, and from
    anywhere else (another frame, the far side, several set-ups merged) they do not. A fit
    that would ignore such a station is wrong, not the station: three raster columns over a
    tank, one of them past its silhouette on the wall behind, fit a circle exactly with that
    column on its far side (r 1.5-2 times the tank's to a millimetre, "the viewpoint was
    ignored")."""
    grid = raster_grid(points, np.asarray(view, dtype=np.float64))
    return grid is not None and np.count_nonzero(grid[2]) >= RASTER_SHARE * len(points)


def unseen(robust: RobustFit, points, view) -> bool:
    """Whether the viewpoint cannot be where the shots came from: more than ``UNSEEN_FRACTION``
    of the best fit's inliers lie beyond its pipe along their beams by more than a tenth of its
    radius (a scan whose sensor position is in another frame, or shots from several stations
    without their ``station``). Asked of the fit the beams chose, so a wrong fit hiding shots
    behind itself is not mistaken for a wrong viewpoint."""
    axis, center, radius = robust.state
    excess = cylinder_beam_excess(axis, center, radius, points[robust.inliers], view)
    return bool(np.count_nonzero(excess > 0.1 * radius) / max(excess.size, 1) > UNSEEN_FRACTION)


#: A shot whose beam passed within this fraction of the radius of a fitted pipe's axis and which
#: lies beyond the middle of the beam's chord through it was seen through the pipe: range noise
#: on a shot of the pipe's surface moves it along its beam, and pointing noise moves the beam
#: by a tiny fraction of the radius, so neither reaches the pipe's middle half.
THROUGH_FRACTION = 0.5


def seen_through(
    robust: RobustFit, points: np.ndarray, view, cutoff: float, fraction: float = THROUGH_FRACTION
) -> np.ndarray:
    """The fit's inliers, shape (n,) bool, whose beams from ``view`` (3,) metres ran through
    the middle of its pipe (within ``fraction`` of the radius of its axis) and end beyond the
    middle of their chord by more than ``cutoff`` metres.

    Such a shot contradicts the fit that takes it as an inlier: the pipe would have stopped
    its beam. A wide circle through a thin pipe's front shots and the wall behind it does this
    (an NPS 2 line 8 m away fitted r 612 mm with 3 of its 9 inliers behind its front).
    ``robust``: anything with the fit's ``state`` (axis, centre, radius) and ``inliers``.
    """
    axis, center, radius = robust.state
    view = np.asarray(view, dtype=np.float64)
    beams = points - view
    start = view - center
    start_across = start - (start @ axis) * axis
    across = beams - (beams @ axis)[:, None] * axis  # (np.outer) each beam's part across the axis
    square = np.einsum("ij,ij->i", across, across)
    crossing = across @ start_across
    safe = np.maximum(square, 1e-300)
    # Nearest the axis at fraction -crossing / square of the way to the shot: before the shot
    # (below 1) for a beam that ran past the axis, beyond it for a shot on the near side, so
    # most fits' shots are settled without the chord.
    closest = start_across @ start_across - crossing * crossing / safe
    deep = robust.inliers & (square > 1e-24) & (-crossing < safe)
    deep &= closest < (fraction * radius) ** 2
    if deep.any():
        chord = cylinder_beam_excess(axis, center, radius, points[deep], view)
        deep[deep] = chord > 2.0 * cutoff
    return deep


def doubtful(robust: RobustFit, points, view, count: int, sigma, tolerances: Tolerances) -> bool:
    """Whether a robust fit deserves a second look at the other starts (:func:`reconsidered`).

    Sparse scans (below ``POLISH_BELOW`` points) always do: there a subset of the shots can
    pull the choice of start into the wrong basin. Larger ones do when the fit rejected shots
    or some inlier's beam ran through the fitted pipe by more than the inlier threshold.
    """
    if count < POLISH_BELOW or not robust.inliers.all():
        return True
    threshold = tolerances.outlier_cutoff_sigma * (sigma if sigma is not None else robust.scale)
    return bool((cylinder_beam_excess(*robust.state, points, view) > threshold).any())


def doubtful_blind(robust: RobustFit, points: np.ndarray, extent: float | None = None) -> bool:
    """Without a viewpoint: whether a fit is nearly a plane over the points (radius above
    ``PLANE_LIKE`` times their extent): a long thin pipe's silhouette shots and the wall shots
    beyond them lie in one plane through the station, which a cylinder of kilometres fits to a
    centimetre. (Reconsidering every doubtful fit by likelihood turned stubs' axes by 90
    degrees: a likelihood with each fit's own noise rewards fitting fewer shots closely.)
    ``extent``: :func:`robust_extent` of ``points`` when the caller has it already."""
    if extent is None:
        extent = robust_extent(points)
    return robust.state[2] > PLANE_LIKE * extent


def robust_extent(points: np.ndarray) -> float:
    """The extent of ``points`` (n, 3) metres, robustly: four times their median distance from
    their median (about the full length of a pipe seen over its length; background shots
    ignored), metres."""
    middle = column_medians(points)
    return 4.0 * quick_median(np.sqrt(np.einsum("ij,ij->i", points - middle, points - middle)))


def same_basin(one, other, extent: float) -> bool:
    """Whether two states are near enough to settle in one place (``SAME_BASIN_*``): a coarser
    test than :func:`~asbuilt.fit._cylinder_starts.same_start`, for choosing which starts to settle again. Two cylinders
    both wider than ``PLANE_LIKE`` times the points' ``extent`` (metres) are one basin whatever
    their axes: over the points both are nearly the same plane, along which the axis is
    unobservable."""
    if min(one[2], other[2]) > PLANE_LIKE * extent:
        return True
    if abs(float(one[0] @ other[0])) < SAME_BASIN_COS:
        return False
    return abs(one[2] - other[2]) <= SAME_BASIN_RELATIVE * max(one[2], other[2])


#: How many of the circles found without a fit's hidden shots are settled (:func:`unhidden_starts`).
UNHIDDEN_STARTS = 3


def unhidden_starts(
    state, inliers, points, excess, axes, scale: float, tolerances: Tolerances
) -> list:
    """Starts found without the shots a fit hides behind itself: the ``UNHIDDEN_STARTS`` best
    robust circles (:func:`~asbuilt.fit._circles.circle_starts`, trimmed cost) on the candidate
    ``axes`` over the ``points`` (n, 3) metres whose beams do not pass through the pipe
    ``state`` by more than the inlier cut of ``scale`` metres (``excess(states, points)``,
    metres), ``inliers`` (n,) bool being its inliers; [] when it hides none.

    A fit that explains inliers only by putting them on its own far side is wrong about them,
    and wrong about itself when its trimmed cost needed them: two raster lines on a wall behind
    a pipe (10 of 35 shots, more than the trimmed cost's design contamination) are fitted,
    with the pipe's front, by a circle five times the pipe's size, on every candidate axis.
    Left out, they leave the pipe's circle to the trimmed cost. The beams then judge the
    settled starts against the fit (:func:`asbuilt.fit._visibility.reconsidered`).
    """
    beyond = excess([state], points)[0]
    hidden = inliers & (beyond > tolerances.outlier_cutoff_sigma * scale)
    if not hidden.any():
        return []
    rest = points[~hidden]
    if len(rest) < MIN_POINTS["cylinder"]:
        return []
    # Its own generator, so the rescue's draws (on the shared one) stay as they were.
    rng = np.random.default_rng(len(rest))
    found, costs = circle_starts(rest, axes, keep_count(len(rest), tolerances), rng)
    # A few: a candidate axis a degree off smears a long pipe's circle by centimetres, so the
    # pipe's circle need not be the cheapest; settling corrects the axis.
    return [found[k] for k in np.argsort(costs)[:UNHIDDEN_STARTS]]
