"""A pipe's own shots, split from whole raster lines on the background behind it.

Private helper of the cylinder fit. An operator's raster window a little larger than a pipe
puts whole rows (or columns) of shots on the wall or floor behind it: a third to a half of the
shots, more than the robust starts are built for (a quarter), so every start either takes a
metre-wide cylinder through pipe and wall or hides shots behind itself, and the fit was
refused, or kept with the viewpoint ignored (an independent ray caster: 273 mm and 406 mm pipes
4-6 m away with the wall 1-2 m behind refused; an NPS 3 pipe at 4 m fitted r 928 mm).

The station sees the pipe in front of the wall: between neighbouring beams the range jumps
by the pipe's distance from the wall, while along one surface it changes by the beams' spacing
times the tangent of the incidence. Cut at those jumps, the shots fall into surfaces, and the
nearest of them are the pipe's (range-image segmentation at depth discontinuities, Hoover et
al. 1996, "An experimental comparison of range image segmentation algorithms"). A fit of
those shots alone stands when every other shot can only be background: behind the first
surface of the pipe its beam met, its beam clear of the pipe. Lengths in metres.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial import Delaunay, QhullError

from asbuilt.errors import FitError
from asbuilt.fit._neighbours import components
from asbuilt.fit._small_linalg import svd
from asbuilt.fit._vectors import cross_rows
from asbuilt.fit._visibility import excess_and_beyond
from asbuilt.fit.result import BACKGROUND_PLANE_SHOTS, BACKGROUND_SHOTS

__all__ = [
    "JUMP_SLOPE",
    "JUMP_NOISE",
    "GAP_STEPS",
    "NEAR_SHARE",
    "MOST_SUBSETS",
    "DETERMINED_RADIUS",
    "depth_segments",
    "near_subsets",
    "only_background_behind",
    "fit_without_background",
    "rescued",
    "BACKGROUND_PLANE_SHOTS",
    "BACKGROUND_SHOTS",
    "random_planes",
    "segment_noise",
    "subset_fits",
    "taken_back",
    "within",
    "PLANE_SHOTS",
    "PLANE_SAMPLES",
    "MOST_PLANES",
    "behind_the_pipe",
    "near_random_planes",
    "refit_without",
    "fit_without_background_plane",
]

#: Neighbouring beams whose ranges differ by more than this many times their spacing across the
#: beams (the range times the angle between them) lie on two surfaces: on one surface the range
#: changes by the spacing times the tangent of the incidence, so this cuts beyond 72 degrees of
#: incidence (a pipe's shot near its silhouette may be cut off, or a long pipe seen obliquely
#: cut into its raster columns; the nearest surfaces are taken together and such shots taken
#: back by their residuals), while a wall 0.3 m behind a pipe seen by beams 20-60 mm apart is
#: 5-15 spacings off. The reviewer's 406 mm pipe seen at a steep yaw had its wall shots 4.2-4.6
#: of its finest spacings off the pipe's far end.
JUMP_SLOPE = 3.0
#: ... and by more than this many range sigmas (two shots of one surface in nearly the same
#: direction differ by their noise).
JUMP_NOISE = 6.0
#: With ``gaps``, beams that came back more than this many of their finest raster steps apart
#: (over the diagonal of the coarsest cells) have open space between them.
GAP_STEPS = 3.5
#: A subset of the shots is tried only if it holds at least this share of them (a pipe framed
#: by a raster a little larger than itself keeps about half; fewer would let one wall row be
#: taken as a pipe).
NEAR_SHARE = 0.4
#: A subset's fit stands only if its radius is known to this fraction of itself (one standard
#: error; as :data:`asbuilt.fit.UNDETERMINED_RELATIVE`): the front line of a thin pipe 10 m
#: away, in front of its mixed returns, fits a 4 m "pipe" +-36 m.
DETERMINED_RADIUS = 0.5
#: At most this many subsets are fitted, nearest first.
MOST_SUBSETS = 4


def segment_noise(sigma, tolerances) -> float:
    """The range noise (metres) the shots are cut into surfaces at: the sensor's ``sigma``,
    else the prior noise."""
    return float(sigma) if sigma is not None else float(tolerances.prior_range_sigma)


def depth_segments(
    points: np.ndarray, view: np.ndarray, noise: float, gaps: bool = False
) -> list[np.ndarray]:
    """The shots cut into surfaces at range jumps between neighbouring beams, nearest first.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres
        The station.
    noise : float, metres
        The range noise.
    gaps : bool
        Also cut where beams that came back lie more than ``GAP_STEPS`` raster steps apart
        (the beams between them returned nothing: open space between two pipes of a rack
        with nothing behind them).

    Returns
    -------
    list of ndarray of int
        The shots of each surface (connected through neighbouring beams without a jump,
        ``JUMP_SLOPE``, ``JUMP_NOISE``), ordered by their median range.
    """
    beams = points - view
    ranges = np.sqrt(np.einsum("ij,ij->i", beams, beams))
    directions = beams / ranges[:, None]
    n = len(points)
    # Neighbouring beams: the Delaunay triangulation of the directions, projected on the plane
    # across their mean (a raster's rows and columns and its diagonals, however unequal its
    # steps).
    mean = directions.sum(axis=0)
    mean /= np.linalg.norm(mean)
    across = svd(directions - np.outer(directions @ mean, mean), full_matrices=True)[2][:2]
    try:
        triangles = Delaunay(directions @ across.T).simplices
    except QhullError:
        return [np.arange(n)]  # the beams lie on one line: no surfaces to tell apart
    edges = np.unique(
        np.sort(np.vstack([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [0, 2]]]), 1),
        axis=0,
    )
    rows, cols = edges[:, 0], edges[:, 1]
    angle = np.arccos(np.clip(np.einsum("ij,ij->i", directions[rows], directions[cols]), -1, 1))
    # The spacing is the raster's finest step at either shot, not the edge's own length: a
    # raster's columns can lie five rows' steps apart, and over such a step the wall 1.8 m
    # behind a pipe is under five spacings off (a pipe's shots along it change range by the
    # step times the tangent of the pipe's yaw, well under five of the finest steps).
    finest = np.full(n, np.inf)
    np.minimum.at(finest, rows, angle)
    np.minimum.at(finest, cols, angle)
    spacing = np.minimum(ranges[rows], ranges[cols]) * np.minimum(finest[rows], finest[cols])
    jump = np.abs(ranges[rows] - ranges[cols])
    linked = jump <= np.maximum(JUMP_SLOPE * spacing, JUMP_NOISE * noise)
    if gaps:
        # A raster's diagonal is under 1.5 of its coarser step, its coarser step (the
        # benchmark's cells are up to 1.4 x 0.7 of a square one) under 2 of its finest.
        linked &= angle <= GAP_STEPS * np.maximum(finest[rows], finest[cols])
    labels = components(n, rows[linked], cols[linked])
    segments = [np.flatnonzero(labels == k) for k in np.unique(labels)]
    return sorted(segments, key=lambda members: float(np.median(ranges[members])))


def near_subsets(segments: list, n: int, share: float = NEAR_SHARE) -> list[np.ndarray]:
    """Masks (n,) bool of the nearest surfaces' shots (``segments``: :func:`depth_segments` of
    the n shots), each holding at least ``share`` of the shots (``NEAR_SHARE`` for a pipe) and
    leaving some out, nearest first (at most ``MOST_SUBSETS``).

    The nearest surface alone, then with the next nearest, and so on: a pipe's silhouette shots
    seen nearly edge-on can be cut from its front by a jump of their own.
    """
    if len(segments) < 2:
        return []
    masks = []
    mask = np.zeros(n, dtype=bool)
    for members in segments[:-1]:
        mask = mask.copy()
        mask[members] = True
        if mask.sum() >= share * n:
            masks.append(mask)
        if len(masks) == MOST_SUBSETS:
            break
    return masks


def only_background_behind(cylinder, points: np.ndarray, view: np.ndarray, left_out, cutoff):
    """Whether every shot ``left_out`` (n,) bool of a fitted ``cylinder`` (a
    :class:`~asbuilt.primitives.Cylinder`) can only be background seen from ``view``: each lies
    more than ``cutoff`` metres beyond the first surface of the pipe its beam met (where it
    entered it, or where it passed closest to its axis), and its beam ran through the pipe by
    at most ``cutoff`` (a beam cannot reach the wall through the pipe). The pipe is the fitted
    one, of its length: a beam that passed its end (a column's top, a pipe's free end) met
    none, and its shot is background wherever it lies (:func:`excess_and_beyond` with a span).
    """
    if not left_out.any():
        return True
    # Where the pipe is known to be: its kept shots' extent (the fitted length), to the cutoff.
    # Not a raster step further: the first row past the pipe's end lies a step past its last
    # kept shot by construction, and is the very row that shows where the pipe ends (with
    # the step as the margin, 32 of the review's 76 plumb pipes before a wall were refused).
    reach = 0.5 * cylinder.length + cutoff
    excess, beyond = excess_and_beyond(
        cylinder.axis, cylinder.center, cylinder.radius, points[left_out], view, (-reach, reach)
    )
    return bool((beyond > cutoff).all() and (excess <= cutoff).all())


#: Rounds of taking back left-out shots near a subset's fit (:func:`taken_back`) and fitting
#: it again.
TAKE_BACK_ROUNDS = 3


def taken_back(fit, found, points, mask, sigma, tolerances, view, nearby):
    """``found`` (the fit of ``points[mask]``) fitted again with the left-out shots that
    ``nearby(found, mask)`` ((n,) bool) names, until none is left to take back
    (``TAKE_BACK_ROUNDS``), and the mask of the shots it fitted; a refit that fails keeps the
    last fit. The cylinder's rule is :func:`within`; the cuboid's is its seen faces' planes
    (:mod:`asbuilt.fit._cuboid_foreground`)."""
    for _ in range(TAKE_BACK_ROUNDS):
        near = nearby(found, mask) & ~mask
        if not near.any():
            break
        try:
            found, mask = fit(points[mask | near], sigma, tolerances, view), mask | near
        except FitError:
            break
    return found, mask


def within(points: np.ndarray, cutoff: float):
    """The take-back rule (:func:`taken_back`) of the shots within ``cutoff`` metres of the
    fitted primitive's surface (a pipe's silhouette shot cut off by its own steep range)."""
    return lambda found, _mask: np.abs(found.primitive.distance(points)) <= cutoff


def refit_without(fit, points: np.ndarray, left_out: np.ndarray, sigma, tolerances, view, cutoff):
    """The pipe fitted without the ``left_out`` shots ((n,) bool), those within ``cutoff``
    metres of it taken back (:func:`taken_back`, :func:`within`), as ``(found, rest, inliers)``:
    the fit, the (n,) bool mask of the shots it fitted and its inliers among all ``points`` (n,
    3) metres; None when the fit is refused, keeps under ``NEAR_SHARE`` of the shots or leaves
    its radius undetermined (standard error over ``DETERMINED_RADIUS`` of it). ``fit``,
    ``sigma`` (metres), ``view`` as in :func:`taken_back`."""
    n = len(points)
    try:
        found = fit(points[~left_out], sigma, tolerances, view)
    except FitError:
        return None
    found, rest = taken_back(
        fit, found, points, ~left_out, sigma, tolerances, view, within(points, cutoff)
    )
    inliers = np.zeros(n, dtype=bool)
    inliers[rest] = found.inliers
    if (
        inliers.sum() < NEAR_SHARE * n
        or not found.stderr["radius"] <= DETERMINED_RADIUS * found.primitive.radius
    ):
        return None
    return found, rest, inliers


def subset_fits(fit, points: np.ndarray, view: np.ndarray, sigma, tolerances, masks):
    """``(fit, mask, cutoff)`` for each of ``masks`` ((n,) bool) whose shots ``fit(points[mask],
    sigma, tolerances, view)`` fits (the rest are skipped), with the fit's inlier cutoff in
    metres (``outlier_cutoff_sigma`` times the sensor's ``sigma``, else the fit's own noise
    level but not below the prior)."""
    prior = float(tolerances.prior_range_sigma)
    for mask in masks:
        try:
            found = fit(points[mask], sigma, tolerances, view)
        except FitError:
            continue
        noise = sigma if sigma is not None else max(found.sigma, prior)
        yield found, mask, tolerances.outlier_cutoff_sigma * noise


def fit_without_background(
    fit, points: np.ndarray, view: np.ndarray, sigma, tolerances, segments=None
):
    """The cylinder fit of the nearest surfaces' shots (:func:`near_subsets`), when it leaves
    out only background; else None. ``segments``: :func:`depth_segments` of ``points`` at the
    sensor's sigma (else the prior noise), when the caller has it already.

    ``fit(points, sigma, tolerances, viewpoint)`` fits a subset of ``points`` (n, 3) metres as
    seen from ``view`` (3,) metres (``sigma`` the sensor's, metres, or None). The shots of the
    other surfaces within the outlier cutoff of the subset's fit are taken back and the fit
    made again (a pipe's silhouette shot cut off by its own steep range). The fit stands when
    it keeps at least ``NEAR_SHARE`` of the shots and every shot outside the subset it fitted
    is background (:func:`only_background_behind`); the subset's own rejected shots were
    judged by the fit. Its residuals and inliers are over every shot, with a note.
    """
    n = len(points)
    if segments is None:
        segments = depth_segments(points, view, segment_noise(sigma, tolerances))
    masks = near_subsets(segments, n)
    for found, mask, cutoff in subset_fits(fit, points, view, sigma, tolerances, masks):
        found, mask = taken_back(
            fit, found, points, mask, sigma, tolerances, view, within(points, cutoff)
        )
        inliers = np.zeros(n, dtype=bool)
        inliers[mask] = found.inliers
        radius = found.primitive.radius
        if not found.stderr["radius"] <= DETERMINED_RADIUS * radius:
            continue  # a few shots of a thin pipe's front line: no pipe to rescue it with
        if inliers.sum() < NEAR_SHARE * n or not only_background_behind(
            found.primitive, points, view, ~mask, cutoff
        ):
            continue
        left = int(np.count_nonzero(~mask))
        note = (
            f"{left} shot(s) lie behind the pipe along their beams, on what the raster reached"
            " past its silhouette (the range jumps there), and were left out as background"
            " before the fit."
        )
        return rescued(found, points, inliers, note, background=left)
    return None


#: Without a viewpoint, a plane holding at least this many shots within the cutoff is taken as
#: a candidate background (two raster rows on a wall: any two parallel rows are coplanar, so
#: the planes of a pipe's row and a wall's row are candidates too, and the fit decides).
PLANE_SHOTS = 6
#: Random point triples tried for the planes, and how many of the fullest distinct planes are
#: left out in turn.
PLANE_SAMPLES = 300
MOST_PLANES = 4


def random_planes(points: np.ndarray, samples: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """The planes through ``samples`` random triples of ``points`` (n, 3) metres (RANSAC
    hypotheses, Fischler & Bolles 1981; degenerate triples dropped): unit normals (planes, 3)
    and offsets (planes,) metres, ``normal @ x == offset`` on each."""
    triples = rng.integers(0, len(points), (samples, 3))
    first = points[triples[:, 0]]
    # np.cross's products and differences, without its overhead (a tenth of the planes' cost).
    normals = cross_rows(points[triples[:, 1]] - first, points[triples[:, 2]] - first)
    lengths = np.linalg.norm(normals, axis=1)
    good = lengths > 1e-12
    normals = normals[good] / lengths[good, None]
    return normals, np.einsum("ij,ij->i", normals, first[good])


def near_random_planes(points: np.ndarray, cutoff: float, samples: int, rng) -> np.ndarray:
    """Which of ``points`` (n, 3) metres lie within ``cutoff`` metres of the planes through
    ``samples`` random triples of them (:func:`random_planes`): bool array (n, planes)."""
    normals, offsets = random_planes(points, samples, rng)
    return np.abs(points @ normals.T - offsets) <= cutoff


def _fullest_planes(points: np.ndarray, cutoff: float, rng) -> list[np.ndarray]:
    """Masks (n,) bool of the shots within ``cutoff`` metres of the fullest planes through
    random triples of ``points`` (n, 3) metres, at least ``PLANE_SHOTS`` each, fullest first,
    none the same set twice (at most ``MOST_PLANES``)."""
    near = near_random_planes(points, cutoff, PLANE_SAMPLES, rng)
    counts = near.sum(axis=0)
    masks: list[np.ndarray] = []
    for k in np.argsort(-counts, kind="stable"):
        if counts[k] < PLANE_SHOTS or len(masks) == MOST_PLANES:
            break
        if not any((near[:, k] == mask).all() for mask in masks):
            masks.append(near[:, k])
    return masks


def behind_the_pipe(cylinder, points: np.ndarray, inliers, left_out, cutoff: float) -> bool:
    """Without a viewpoint: whether every shot ``left_out`` (n,) bool lies outside ``cylinder``
    by more than ``cutoff`` metres and behind the plane that touches its back, as seen from the
    side its ``inliers`` (n,) bool face (the station's side: a wall the raster reached past the
    pipe is behind it, since the pipe stands in front of it; a rough surface's scatter, a
    second surface in front, or the shots of the true pipe beside a wrong one are not: with
    "behind the axis" three of 36 fits rescued on the review's scans had been wrong ones)."""
    if not left_out.any():
        return True
    rel = points - cylinder.center
    radial = rel - np.outer(rel @ cylinder.axis, cylinder.axis)
    facing = radial[inliers].sum(axis=0)
    if not np.linalg.norm(facing) > 0.0:
        return False
    residuals = np.linalg.norm(radial[left_out], axis=1) - cylinder.radius
    depth = radial[left_out] @ (facing / np.linalg.norm(facing))
    return bool((residuals > cutoff).all() and (depth < cutoff - cylinder.radius).all())


def fit_without_background_plane(fit, points: np.ndarray, sigma: float, tolerances):
    """Without a viewpoint: the cylinder fit with the shots of one of the fullest planes left
    out (:func:`_fullest_planes`), when it keeps at least ``NEAR_SHARE`` of the shots (on the
    review's scans without a station, more than half would have refused 18 right rescues to
    spare 2 wrong ones, which keep 10 of 22 and 12 of 28 shots), its radius
    is known to ``DETERMINED_RADIUS`` of itself and every shot it leaves out is behind the pipe
    (:func:`behind_the_pipe`); else None.

    ``fit(points, sigma, tolerances, viewpoint)`` as in :func:`fit_without_background`; ``sigma``
    metres (the sensor's, or the prior noise a scan without one is tried at). Whole raster rows
    on a wall behind a pipe lie on one plane; with a third of the shots there the robust starts
    found no cylinder at the prior noise (an independent ray caster's NPS 8 pipe, 12 of 42
    shots on the wall 1.7 m behind), and a 1 m cylinder through pipe and wall at 38 mm was kept.
    """
    n = len(points)
    cutoff = tolerances.outlier_cutoff_sigma * sigma
    rng = np.random.default_rng(n)
    for plane in _fullest_planes(points, cutoff, rng):
        if (~plane).sum() < NEAR_SHARE * n:
            continue
        refit = refit_without(fit, points, plane, sigma, tolerances, None, cutoff)
        if refit is None:
            continue
        found, rest, inliers = refit
        if not behind_the_pipe(found.primitive, points, inliers, ~rest, cutoff):
            continue
        note = (
            f"{int(np.count_nonzero(~rest))} shot(s) on one plane behind the pipe (raster lines"
            " past its silhouette, on a wall) were left out as background before the fit."
        )
        return rescued(found, points, inliers, note, background=int(np.count_nonzero(~rest)))
    return None


def rescued(found, points, inliers, note: str, background: int | None = None):
    """``found`` (a FitResult on a subset) as the fit of every one of ``points`` (n, 3) metres:
    its residuals over all of them, ``inliers`` (n,) bool, and ``note`` added; ``background``,
    when given, the count of shots left out as background (``diagnostics[BACKGROUND_SHOTS]``)."""
    diagnostics = found.diagnostics
    if background is not None:
        diagnostics = {**diagnostics, BACKGROUND_SHOTS: float(background)}
    return dataclasses.replace(
        found,
        residuals=found.primitive.distance(points),
        inliers=inliers,
        notes=(*found.notes, note),
        diagnostics=diagnostics,
    )
