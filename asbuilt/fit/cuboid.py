"""Cuboid fitting (columns, beams, boxes) from sparse range points with 1, 2 or 3 seen faces.

The method generalises the paper's two- and three-face cuboid fitting (Kwon et al. 2004,
"Fitting range data to primitives for rapid local 3D modeling using sparse range point clouds",
cuboid steps 1-4) and replaces its ``z = Ax + By + C`` plane fits, which fail on vertical faces,
by orthogonal-distance fits of all faces at once with exactly perpendicular normals:

1. Segmentation (:mod:`asbuilt.fit._faces`): local k-neighbour normals and point triples propose
   planes scored by consensus (RANSAC, Fischler and Bolles 1981); a second face is searched
   exactly perpendicular to the first (point pairs), further faces along the third axis or
   opposite seen faces (a third face, whose direction the first two fix, from two points at
   least); a face must be contiguous with its neighbour (a convex corner) and, when
   the viewpoint is trusted, face it; a frame must be a box seen from the viewpoint (at most
   two faces across an axis, facing opposite ways, none turned away). The frame explaining
   most points is fitted first. If its fit rejects points, is implausible, or has a face whose
   raster shots lie on one line (a single column: its direction about that line is free), the
   segmentation is rerun trying every first-face hypothesis, every frame explaining as many
   segmented points is fitted too (three raster columns on two narrow faces fit either
   corner; the shots left out of the segmentation, or rejected, decide) and the plausible fit
   with the lowest MSAC cost over all points wins (Torr and Zisserman 2000); if the winner
   rejects more than ``max_outlier_fraction`` of the points, the frame whose fit keeps the
   most points wins.
2. Joint fit: one rotation (3 small-angle parameters, applied with Rodrigues' formula so the axes
   stay exactly orthonormal) and one offset per seen face minimise the squared orthogonal
   distances of every point to its nearest face plane (Gauss-Newton with an analytic Jacobian).
   Points are reassigned to faces by residual each iteration (points next to an edge), Tukey's
   biweight (IRLS; the scale starts at the noise level and is re-estimated by the median
   absolute residual on the weights' support) downweights outliers, points beyond
   ``outlier_cutoff_sigma`` robust sigmas are rejected and a plain least-squares refit on the
   inliers gives the final estimate and its covariance (Gauss-Newton normal matrix). Faces the
   refined frame reveals among the rejected points are then added and the fit repeated.
   With the shots a raster from the viewpoint, a face's shots spread along the beams (a
   raster column on a column and the next on the wall behind, in one plane nearly through
   the station: :mod:`asbuilt.fit._beam_fans`) are left out but for the group nearest the
   station and the frame is fitted again; a fit with a face seen edge-on from every shot,
   which the other faces leave free to turn, ranks after the other plausible fits; shots
   seen past the box (behind every seen face, farther than every kept shot) are background,
   not counted against ``max_outlier_fraction``, unless the shots contradict the viewpoint
   (a wrong station: :mod:`asbuilt.fit._cuboid_viewpoint`), which refuses the fit.
3. Sizes: between two opposite seen faces (``observed`` True); otherwise from a seen face (the
   fitted corner edge) to the farthest inlier along that axis, or between the extreme inliers
   when no face bounds the axis (``observed`` False: the paper's point-projection step). Those
   extent bounds stop short of the true edge by up to the spacing of the shots that reached it:
   a raster step for a raster's last line, the final bracket (a few millimetres) for an
   acquisition session's edge-bisection shots. Each extent bound is padded by ``edge_pad``
   (0.5) times that spacing, the middle of the gap in which the edge lies: the smaller of the
   median spacing of the raster lines along the axis and the distance along the axis from the
   extreme inlier to the nearest inlier behind it within 45 degrees of the axis (the previous
   shot of its raster row or bisection line). A face whose shots are one raster line across
   the axis (grazing incidence) measures no line spacing; the step there is derived from the
   neighbour face's lines across the common edge (:func:`asbuilt.fit._cuboid_sizes._corner_step`),
   else the local spacing, else the inliers' extent. When the points are a pan-tilt raster seen from the viewpoint
   (given, or the scan frame's origin; checked: the directions must fall on a raster's evenly
   spaced pan columns and tilt rows, extra off-grid edge shots allowed), the unseen edges are
   instead placed where the box's silhouette meets the raster window, the raster's angular
   extent widened by half a step (:mod:`asbuilt.fit._silhouette`; the project's raster shoots at
   cell centres), each side that edge-bisection shots reach beyond the last raster line being
   placed at the outermost of them, and a side with a bisection hit just inside its last line
   on that line. Where the solution would put a bound at or inside its extreme inlier and no
   bisection placed the window side it moves, the edge is still anywhere up to the next raster
   beam along that face (:func:`asbuilt.fit._cuboid_sizes.raster_gaps`): the bound is put in
   the middle of that gap, and the gap is its uncertainty.
   Over an operator's window (a little wider than the object) the half-step rule is right only
   within half a step either way; the bisection shots are what make those sizes accurate. Edge-bisection shots (an acquisition session's, told from the
   raster by their angles from a given viewpoint: :func:`asbuilt.fit._silhouette.edge_shots`)
   end within the session's tolerance (2 mm) of the silhouette, so an extent bound that the
   outermost bisection shot along its axis reaches gets no pad. Such shots often straddle the
   edge and come back as mixed returns (the fit rejects them); their direction is still
   good, so each is put back where its beam enters the fitted box and bounds the edge as a
   clean hit would. Bisection shots are left out of the segmentation where they crowd within
   millimetres of each other (no normal from such neighbourhoods). The size's standard error
   includes the remaining gap: the edge is taken as uniform between the extreme point and
   the larger of twice the pad and the gap to the next raster line along its face beyond it
   (variance ``(gap/2 - pad)^2 + gap^2/12`` per extent bound; pad^2 / 3 at gap 2 pad),
   besides the extreme point's own noise; a bound a bisection shot pins has no gap.
   All of this presumes a raster that reached the edges. Without a raster lattice from a
   trusted viewpoint (shots aimed by hand, or no station to read one from), a size bounded by
   extent at an end no bisection shot pins is a lower bound: standard error infinite, the
   centre's too, a note with what the shots span of it (:mod:`asbuilt.fit._cuboid_reach`);
   the size keeps its pad. A dense cloud (``_cuboid_reach.DENSE_SHOTS`` inliers) is exempt.
4. One seen face: the face normal is fitted, the in-plane axes come from the minimum-area
   bounding rectangle of the projected points (rotating calipers, Freeman and Shapira 1975) and
   the unseen depth is set to the smaller in-plane width (a column seen face-on is about
   square), behind the face as seen from the viewpoint; ``observed`` is False for all three
   sizes and a note says so.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit import _faces, _silhouette, _vectors
from asbuilt.fit._beam_fans import raster_lines
from asbuilt.fit._common import noise_level, random_subset
from asbuilt.fit._cuboid_bisection import mixed_returns, spread_subset
from asbuilt.fit._cuboid_edges import raster_corners
from asbuilt.fit._cuboid_foreground import FRONT_SHOTS, contradicting, fit_nearest_box
from asbuilt.fit._cuboid_inside import ShotsInside, too_many_inside
from asbuilt.fit._cuboid_lone import OneLineFace, face_through_station, one_line_and_lone_shot
from asbuilt.fit._cuboid_noise import _likeliest_noise
from asbuilt.fit._cuboid_occluder import behind_occluder
from asbuilt.fit._cuboid_open import open_past_faces
from asbuilt.fit._cuboid_planes import fit_past_planes
from asbuilt.fit._cuboid_reach import lower_bounds, unreached
from asbuilt.fit._cuboid_sizes import (
    SUBSET_GRAZING_DEG,
    bounds,
    covariance,
    extent_spans,
    one_face_depth,
    propagate,
    raster_gaps,
    rival_size_spread,
    silhouette_bounds,
    single_lines,
)
from asbuilt.fit._cuboid_sparse import AmbiguousFrame, describe
from asbuilt.fit._cuboid_viewpoint import checked
from asbuilt.fit._joint import (
    best_fit,
    counted_outliers,
    expand_frame,
    fit_frame,
    median,
    plausible,
)
from asbuilt.fit._neighbours import local_normals
from asbuilt.fit._opposite import outside_outline
from asbuilt.fit._small_linalg import singular_values
from asbuilt.fit.result import FitResult, rotation_diagnostics
from asbuilt.primitives import Cuboid, as_points, as_vector
from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS, Tolerances

__all__ = ["fit_cuboid"]

METHOD = (
    "normal/RANSAC face segmentation + orthogonality-constrained joint plane fit (Gauss-Newton, "
    "Tukey IRLS, least-squares refit on inliers); sizes between faces, else from the fitted edges "
    "to the raster silhouette or the points' extent (generalised two-face method of Kwon et al. "
    "2004)"
)


#: Most points the face segmentation looks at (a dense cloud is subsampled for it: its plane
#: hypotheses are scored against every segmented point).
_SEGMENTED_POINTS = 2000

#: Fewest shots on the fitted box's faces for a fit: three fix a face's plane, a fourth checks
#: it. Fewer (the rest rejected, or discounted as background seen past the box) is no box.
_MIN_ON_FACES = 4


def _validate(points) -> np.ndarray:
    try:
        pts = np.array(as_points(points))
    except ValueError as exc:
        raise FitError(f"cuboid: {exc}") from None
    need = MIN_POINTS["cuboid"]
    if pts.shape[0] < need:
        raise FitError(
            f"cuboid: {pts.shape[0]} points are too few; a cuboid needs at least {need} "
            "(30 or more on two or three faces for a reliable size). Measure more points."
        )
    spread = singular_values(pts - pts.mean(axis=0))
    if spread[0] < 1e-9:
        raise FitError(
            "cuboid: all points coincide; measure points spread over the object's faces."
        )
    if spread[1] < 1e-9 * max(spread[0], 1.0):
        raise FitError("cuboid: all points lie on one line; measure points across the faces too.")
    return pts


def _canonical(axes, size, observed):
    """Reorder axes: the one nearest vertical last and pointing up, then right-handed."""
    third = int(np.argmax(np.abs(axes[:, 2])))
    rest = [k for k in range(3) if k != third]
    rest.sort(key=lambda k: -abs(axes[k, 0]))
    order = [rest[0], rest[1], third]
    new = axes[order].copy()
    if new[2, 2] < 0:
        new[2] = -new[2]
    if new[0, np.argmax(np.abs(new[0]))] < 0:
        new[0] = -new[0]
    new[1] = _vectors.cross3(new[2], new[0])
    return new, size[order], tuple(bool(observed[k]) for k in order), order


def fit_cuboid(
    points,
    *,
    sigma: float | None = None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    viewpoint=None,
    edge_pad: float = 0.5,
    silhouette: bool = True,
) -> FitResult:
    """Fit a cuboid to sparse range points on 1, 2 or 3 (or more) of its faces.

    Method: face segmentation by local normals and plane consensus, a joint orthogonal-distance
    fit of all seen faces with exactly perpendicular normals (Gauss-Newton, Tukey IRLS, refit on
    inliers), sizes between opposite faces or from the fitted edges to the points' extent
    (generalising Kwon et al. 2004); see the module docstring for the steps.

    With the viewpoint given, a fit with shots in front of its box or inside it, or a refused one, is
    tried again on the nearest surfaces' shots, the rest left out when they can only be
    background behind the box (:mod:`asbuilt.fit._cuboid_foreground`). An extent size past
    whose end shots left out of the fit lie on a seen face's plane (a receding beam's far
    part) is a lower bound: standard error infinite (:mod:`asbuilt.fit._cuboid_open`).

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
        Range points on the box's visible faces; n >= ``MIN_POINTS["cuboid"]``.
    sigma : float or None, metres
        The sensor's range noise; scales the standard errors. None: estimated from the residuals.
    tolerances : Tolerances
        Uses ``normal_neighbours``, ``face_angle_deg``, ``outlier_cutoff_sigma``,
        ``max_outlier_fraction`` and ``sigma_floor``.
    viewpoint : array_like, shape (3,), metres, or None
        The sensor position (``scan.sensor.position``). It orients a single seen face (the box
        lies behind it), rules out faces turned away from it, and lets the raster silhouette
        bound the unseen edges. None tries the scan frame's origin, trusted only if the points
        are a plain pan-tilt raster seen from there (edge-bisection shots are used with a given
        viewpoint only).
    edge_pad : float
        Fraction of the local shot spacing (see the module docstring, step 3) added beyond the
        last point to an extent bound when the silhouette cannot be used (0.5: the middle of
        the gap in which the edge lies; 0: the paper's plain extent).
    silhouette : bool
        Use the raster silhouette for unseen edges when the raster check passes.

    Returns
    -------
    FitResult
        ``primitive`` a :class:`~asbuilt.primitives.Cuboid` (axes rows ordered so the one nearest
        vertical is last); ``residuals`` (n,) metres, the distance of inliers to their face plane
        and of outliers to the box surface; ``observed`` per size (True only between two seen
        opposite faces); ``stderr`` ``size`` (3 values, metres), ``axes_deg`` (3 values: the
        angular standard error of each output axis's direction, degrees), ``center`` (root of
        the trace of the centre covariance, metres); ``covariance`` of [rotation vector (radians, world frame, about the inliers'
        centroid; 2 components with one seen face), face offsets (metres, in face order)];
        ``diagnostics`` ``faces``, ``outliers``, ``iterations``, ``scale`` (robust residual sigma,
        metres), ``faces_axis0..2`` (seen faces normal to each output axis), ``silhouette`` (1.0
        when the raster window placed the unseen edges), ``mended`` (rejected bisection shots put
        back on the box along their beam), ``open_sizes`` (sizes made lower bounds, when any),
        ``unreached_sizes`` (sizes made lower bounds because the shots are not a raster that
        reaches the edges, when any: their standard errors infinite), ``rotation_deg_0..2``
        and ``rotation_corr_01/02/12`` (the rotation's covariance in the output axes' frame:
        :func:`asbuilt.fit.result.rotation_diagnostics`).

    Raises
    ------
    FitError
        Too few points, coincident or collinear points, no planar face, or more outliers than
        ``tolerances.max_outlier_fraction``; :class:`~asbuilt.fit._cuboid_lone.OneLineFace`
        when the one face seen holds one raster line of shots and at most one beside it;
        :class:`~asbuilt.fit._cuboid_inside.ShotsInside` when many shots lie inside the box.
    """
    options = {"edge_pad": edge_pad, "silhouette": silhouette}
    result = _fit_box(points, sigma, tolerances, viewpoint, options)
    # (The points were validated by the fit, whose rows ``result`` follows.)
    pts = np.asarray(points, dtype=np.float64)
    if result.diagnostics.get("faces") == 1:
        noise = result.sigma if sigma is None else sigma
        width = tolerances.outlier_cutoff_sigma * max(noise, tolerances.sigma_floor)
        if one_line_and_lone_shot(pts[result.inliers], width):
            # A line of shots on something before the box (a pipe in front of a column) is
            # the nearest surface: the box may stand behind it (asbuilt.fit._cuboid_occluder).
            behind = behind_occluder(
                lambda subset: fit_cuboid(
                    subset,
                    sigma=sigma,
                    tolerances=tolerances,
                    viewpoint=viewpoint,
                    edge_pad=edge_pad,
                    silhouette=silhouette,
                ),
                result,
                pts,
                None if viewpoint is None else np.asarray(viewpoint, dtype=np.float64),
                width,
            )
            if behind is not None:
                return behind
            raise OneLineFace(
                "cuboid: the shots on the one face seen lie on one raster line (and at most "
                "one shot beside it), which measures neither the face's turn nor its width; "
                "take shots across the face on two or more raster lines, or on a second face."
            )
        face = int(result.diagnostics["assumed_size"])
        if viewpoint is not None and face_through_station(
            result.primitive, face, np.asarray(viewpoint, dtype=np.float64), width
        ):
            raise OneLineFace(
                "cuboid: the one face seen lies in the plane of one raster line's sweep through "
                "the station (a beam in a face's plane only grazes it), so its shots measure "
                "neither the face's turn nor its width; take shots across the face on two or "
                "more raster lines, or on a second face."
            )
    if result.inliers.all():
        return result  # no shot left out, so none that could run on past an end or lie inside
    # Shots the fit left out that lie on a seen face's plane past an extent bound (a receding
    # beam's far part, cut off at range jumps): that size is only a lower bound.
    cutoff = tolerances.outlier_cutoff_sigma * max(result.sigma, tolerances.sigma_floor)
    result = open_past_faces(result, pts, cutoff)
    inside = too_many_inside(result.primitive, pts, result.inliers, cutoff)
    if inside:
        raise ShotsInside(
            f"cuboid: {inside} of the {len(pts)} shots lie inside the fitted box, where no beam "
            "can measure one: the box was fitted to another surface (a wall or floor behind "
            "the object); aim the shots at the object's faces only, or take a second face."
        )
    return result


def _fit_box(points, sigma, tolerances, viewpoint, options) -> FitResult:
    """:func:`fit_cuboid` before its open-end check: the shots' fit, or with ``viewpoint``
    the nearest surfaces' when the first fit is contradicted or refused; refused when the shots
    contradict the viewpoint (:mod:`asbuilt.fit._cuboid_viewpoint`)."""
    if viewpoint is None:
        return _fit_cuboid_shots(points, sigma=sigma, tolerances=tolerances, **options)
    try:
        view = np.array(as_vector(viewpoint, "viewpoint"))
    except ValueError as exc:
        raise FitError(f"cuboid: {exc}") from None
    # Validated once here (the same refusal the fit itself would raise first), not by every
    # fit of the shots below.
    pts = _validate(points)
    result, error = _fit_seen_from(pts, sigma, tolerances, view, options)
    return checked(
        result,
        error,
        pts,
        view,
        lambda: _fit_cuboid_shots(
            pts, sigma=sigma, tolerances=tolerances, validated=True, **options
        ),
    )


def _fit_seen_from(points, sigma, tolerances, view, options):
    """:func:`_fit_box` as seen from ``view`` (3,) metres, as ``(result, error)``: the fit
    (None when refused) and the refusal (a FitError, None when fitted); ``points`` (n, 3)
    metres, validated (:func:`_validate`)."""
    edge_pad = options["edge_pad"]
    result = error = None
    try:
        result = _fit_cuboid_shots(
            points, sigma=sigma, tolerances=tolerances, viewpoint=view, validated=True, **options
        )
    except AmbiguousFrame:
        raise  # a subset of the shots cannot tell the frames apart either
    except FitError as exc:
        error = exc
    if result is not None and result.inliers.all():
        return result, None  # every shot on a face: none in front of the box or inside it
    pts = points
    contradictions = len(pts)
    if result is not None:
        width = tolerances.outlier_cutoff_sigma * max(result.sigma, tolerances.sigma_floor)
        # Every shot, not only the rejected: a frame built on the wall can keep shots of the
        # object on a face's plane in front of another face.
        contradictions = int(np.count_nonzero(contradicting(result.primitive, pts, view, width)))
        if contradictions < FRONT_SHOTS:
            return result, None

    def fitter(silhouette: bool):
        def fit_subset(subset, sigma, tolerances, viewpoint):
            return _fit_cuboid_shots(
                subset,
                sigma=sigma,
                tolerances=tolerances,
                viewpoint=viewpoint,
                edge_pad=edge_pad,
                silhouette=silhouette,
            )

        return fit_subset

    def against(found) -> int:
        # The shots no beam can have measured with the box there (in front of it along the
        # beam, or inside it).
        width = tolerances.outlier_cutoff_sigma * max(found.sigma, tolerances.sigma_floor)
        return int(np.count_nonzero(contradicting(found.primitive, pts, view, width)))

    planes = None
    seen = _silhouette.shot_angles(pts, view)
    if seen is not None:
        planes = fit_past_planes(fitter(False), pts, view, sigma, tolerances, seen[1])
        if planes is not None and _on_its_box(planes, sigma, tolerances):
            if against(planes) < min(FRONT_SHOTS, contradictions):
                return planes, None
            if against(planes) >= contradictions:
                planes = None  # no fewer shots in front of it than of the first fit's box
        else:
            planes = None
    rescued = fit_nearest_box(fitter(False), pts, view, sigma, tolerances, contradictions)
    if rescued is not None and not _on_its_box(rescued, sigma, tolerances):
        rescued = None
    if planes is not None and rescued is not None:
        # Both stand: the one fewer shots contradict (a floor left after the wall and fitted
        # as the box has the brace on it in front of it; a nearest surface's box metres wide
        # has the beam's other shots inside it).
        return (planes if against(planes) < against(rescued) else rescued), None
    if rescued is not None or planes is not None:
        return (rescued if rescued is not None else planes), None
    return result, error


def _on_its_box(found: FitResult, sigma, tolerances) -> bool:
    """Whether every inlier of ``found`` (a subset's fit taken for every shot, its residuals
    to the box's surface) lies within twice the inlier cutoff of its box (``sigma`` metres or
    None: the fit's own noise level). The subset's fit keeps shots within the cutoff of a
    face's plane; one far past the box along that plane is on no face of it (a box 0.2 m
    deep with shots 0.17 m in front of its face, rms 60 mm at a 2 mm sigma, its note saying
    the rejected lay beyond 3 x 2 mm of their face)."""
    noise = found.sigma if sigma is None else sigma
    width = tolerances.outlier_cutoff_sigma * max(noise, tolerances.sigma_floor)
    kept = np.abs(found.residuals[found.inliers])
    return kept.size == 0 or float(kept.max()) <= 2.0 * width


def _seed_frame(seed, x: np.ndarray, origin: np.ndarray, threshold: float) -> _faces.Frame:
    """The segmentation frame of ``seed``'s faces (see :func:`_fit_cuboid_shots`) over the
    centred points ``x`` (n, 3) metres, ``origin`` (3,) their centroid: each point labelled
    with its nearest face plane within ``threshold`` metres, else -1."""
    axes = np.array(seed.axes, dtype=np.float64)
    face_axis = np.array(seed.face_axis, dtype=np.int64)
    face_sign = np.array(seed.face_sign, dtype=np.float64)
    normals = face_sign[:, None] * axes[face_axis]
    offset = np.array(seed.face_offset, dtype=np.float64) - normals @ origin
    distance = np.abs(x @ normals.T - offset[None, :])
    labels = distance.argmin(axis=1)
    labels[distance[np.arange(x.shape[0]), labels] >= threshold] = -1
    return _faces.Frame(axes, face_axis, face_sign, offset, labels)


def _fit_cuboid_shots(
    points,
    *,
    sigma: float | None = None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    viewpoint=None,
    edge_pad: float = 0.5,
    silhouette: bool = True,
    seed=None,
    validated: bool = False,
) -> FitResult:
    """:func:`fit_cuboid` of the shots as they are.

    ``seed``, optional: the faces to fit instead of a segmentation's frames (two stations'
    views of one box, :mod:`asbuilt.fit._cuboid_stations`): ``axes`` (3, 3) rows, ``face_axis``
    (m,) int, ``face_sign`` (m,) +-1, ``face_offset`` (m,) metres from the scan frame's origin
    (outward normal . point = offset) and ``noise`` (metres, the consensus level when
    ``sigma`` is None). That frame alone is fitted: no search, so no frame a single station
    could have seen replaces its opposite faces. ``validated``: ``points`` is already
    :func:`_validate`'s array.
    """
    pts = points if validated else _validate(points)
    n = pts.shape[0]
    try:
        view = None if viewpoint is None else np.array(as_vector(viewpoint, "viewpoint"))
    except ValueError as exc:
        raise FitError(f"cuboid: {exc}") from None
    floor = tolerances.sigma_floor
    cutoff = tolerances.outlier_cutoff_sigma

    origin = pts.mean(axis=0)
    x = pts - origin
    # The viewpoint (given, or the scan frame's origin) is trusted when the points' directions
    # from it fall on a pan-tilt raster's rows and columns.
    viewpoint = np.zeros(3) if view is None else view
    seen = _silhouette.shot_angles(pts, viewpoint)  # once for every raster reading below
    grid = _silhouette.raster_grid(pts, viewpoint, seen=seen)
    # Without a given viewpoint, the scan frame's origin is trusted on a plain raster only: a
    # raster with off-grid shots could also be two stations' points seen from one of them.
    trusted = view is not None or (grid is not None and grid[2].all())
    if not trusted:
        grid = None
    # Bisection shots are told from the raster by their angles from a trusted viewpoint only.
    edges = (
        _silhouette.edge_shots(pts, viewpoint, seen) if trusted else (-np.ones(n, np.int64),) * 2
    )
    if grid is not None:
        # A raster's lone corner shot, a whole step from its neighbour, is no bisection's.
        edges = raster_corners(edges, seen, grid[4])
    if grid is not None and np.any(edges[0] >= 0):
        # Bisection shots are not raster shots, even when one falls within the line width of
        # the raster line it started from; they pin the window's sides.
        grid = _silhouette.raster_grid(pts, viewpoint, off_grid=edges[0] >= 0, seen=seen)
    # Segmentation works on the raster's shots and the bisection shots that stand apart from
    # them: a bisection's later hits lie millimetres apart on a line next to an edge, so their
    # neighbourhoods give no normal and would shrink the spacing scale, but its first hits
    # sample a narrow face half a raster step farther out. The joint fit and the bounds use
    # every point.
    seg = spread_subset(x, edges[0] < 0)
    if seg.size < max(MIN_POINTS["cuboid"], n // 2):
        seg = np.arange(n)
    if seg.size > _SEGMENTED_POINTS:
        # A dense cloud: faces are found on a random subsample; the fit still uses every point.
        seg = random_subset(seg, _SEGMENTED_POINTS, np.random.default_rng(seg.size))
    xs = x[seg]
    # The shots' raster rows and columns, for the test that no face holds
    # shots spread along the beams (:mod:`asbuilt.fit._beam_fans`). Only where the shots are
    # checked to be a raster from the viewpoint: from a wrong viewpoint every face would split.
    raster = None if grid is None else (seen[1], raster_lines(seen[1], grid[4]))
    normals, local_rms, hood = local_normals(xs, tolerances.normal_neighbours)
    fourth = hood[:, min(3, hood.shape[1] - 1)]
    reach = median(np.linalg.norm(xs[fourth] - xs, axis=1))

    def bands(noise: float) -> tuple[float, float]:
        """The consensus threshold and the face gap (metres) at ``noise`` (metres)."""
        threshold = cutoff * max(noise, floor)
        return threshold, threshold + 1.5 * reach

    def attempt(noise: float):
        """Segmentation and joint fit with the consensus threshold of ``noise`` (metres)."""
        threshold, gap = bands(noise)
        search = _faces.Segmentation(
            xs, normals, threshold, gap, tolerances.face_angle_deg, viewpoint - origin, trusted
        )

        def segmentation(exhaustive: bool) -> list:
            frames = search.frames(exhaustive)
            return [expand_frame(frame, seg, n) for frame in frames] if seg.size < n else frames

        frames = segmentation(False)
        if not frames:
            raise FitError(
                "cuboid: no planar face found (no three points on one plane); check the points "
                "or fit the object as a hull."
            )
        return best_fit(
            frames,
            lambda: segmentation(True),
            (x, noise, floor, cutoff, gap, viewpoint - origin, trusted, raster),
            tolerances.max_outlier_fraction,
            edges[0] < 0,
            known_noise=sigma is not None,
        )

    if seed is not None:
        noise = float(sigma) if sigma is not None else float(seed.noise)
        threshold, gap = bands(noise)
        fitted = fit_frame(
            _seed_frame(seed, x, origin, threshold),
            x,
            noise,
            floor,
            cutoff,
            gap,
            viewpoint - origin,
            trusted,
            raster,
        )
    elif sigma is not None:
        noise = float(sigma)
        fitted = attempt(noise)
    else:
        noise, fitted = _likeliest_noise(
            attempt,
            _faces.noise_scale(xs, normals, local_rms, floor),
            x,
            tolerances,
            lambda model: plausible(model, viewpoint - origin, trusted),
            lambda fitted, level: counted_outliers(
                fitted, x, viewpoint - origin, trusted, cutoff * max(level, floor)
            ),
        )
    model, label, residual, inliers, scale, iterations, one_face = fitted
    if model.rival is not None:
        # Few shots that fit frames far apart as well: any one frame's standard errors lie.
        raise AmbiguousFrame(describe(model.rival, n))
    notes: list[str] = []
    if one_face:
        notes.append(
            "one face seen: the in-plane axes come from the minimum-area rectangle of the points "
            "and the unseen depth is set to the smaller visible width (not measured)"
        )
    n_out = n - int(np.count_nonzero(inliers))
    # Shots seen past the box (the wall behind a column, in an operator's window) are
    # background, not a sign that the points are not one box.
    width = cutoff * max(scale, noise)
    if counted_outliers(fitted, x, viewpoint - origin, trusted, width) > (
        tolerances.max_outlier_fraction * n
    ):
        raise FitError(
            f"cuboid: {n_out} of {n} points are outliers (more than "
            f"{tolerances.max_outlier_fraction:.0%}); the points do not look like one box. "
            "Check the object's points or fit it as a hull."
        )

    kept = int(np.count_nonzero(inliers))
    if kept < _MIN_ON_FACES:
        # Every other shot discounted as background seen past the box passes the outlier
        # limit, but a box on so few shots (one, on a column before a wall whose window put
        # most shots on the wall) is not a fit: its sizes and standard errors are made up (0 m,
        # an orientation error of millions of degrees).
        raise FitError(
            f"cuboid: only {kept} of {n} points lie on the fitted box's faces (at least "
            f"{_MIN_ON_FACES} are needed); the rest are rejected or seen past it. Check the "
            "object's points (mostly background?) or fit it as a hull."
        )

    if not trusted and not one_face and seed is None:
        # (A seed's faces were each seen by a view fitted with its own station.)
        # Without a station, two opposite faces are a measured size only if their shots share
        # the box's outline (asbuilt.fit._opposite); a wall behind the box, shot past its
        # sides, fits a "back face" as closely, and the frame built on it is wrong throughout.
        face = outside_outline(model, x, label, inliers, width)
        if face is not None:
            raise FitError(
                "cuboid: without the station, the shots of one face reach far past the outline "
                "of the face opposite it (a wall or floor behind the object taken for its far "
                "side?); give the scan's sensor position, or check the object's points."
            )

    if n_out:
        notes.append(
            f"{n_out} outlier point(s) rejected (beyond {cutoff:g} x "
            f"{max(scale, noise) * 1000:.3g} mm of their face)."
        )

    # Bisection shots rejected as mixed returns still carry their direction: put back on their
    # face along the beam, they bound the edge as a clean hit would (extra rows of xb).
    xb, label_b, inliers_b, edges_b, mended = x, label, inliers, edges, 0
    if trusted and not one_face:
        extra, extra_label, extra_of = mixed_returns(
            x, label, inliers, model, edges, viewpoint - origin, cutoff * max(scale, noise)
        )
        if extra_of.size:
            mended = int(extra_of.size)
            xb = np.vstack([x, extra])
            label_b = np.concatenate([label, extra_label])
            inliers_b = np.concatenate([inliers, np.ones(mended, bool)])
            edges_b = tuple(np.concatenate([e, e[extra_of]]) for e in edges)
    single = single_lines(xb, label_b, inliers_b, model, cutoff * scale)
    lo, hi, lo_face, hi_face, lo_pt, hi_pt, pad = bounds(
        xb, label_b, inliers_b, model, cutoff * scale, edge_pad, edges_b, single
    )
    # Sides an edge-bisection shot pins (no pad): known to the session's tolerance.
    pinned = (pad == 0.0) & (np.stack([lo_pt, hi_pt]) >= 0)
    # Sizes bounded by the shots' extent where no raster says the shots reach the edges (hand
    # aimed, or no station to read a raster from) are lower bounds (asbuilt.fit._cuboid_reach).
    # The size itself stays padded as before: it does not depend on the raster being read (a
    # scan's frame turned, or in survey coordinates without its station). A seed's views (two
    # stations) were each checked by their own fits.
    short = np.zeros(3, bool)
    if seed is None:
        bisected = pinned & bool(np.any(edges_b[0] >= 0))
        lattice = grid is not None or _silhouette.on_raster_lines(seen)
        short = unreached(lo_face, hi_face, bisected, lattice, int(np.count_nonzero(inliers)))
    used_window = False
    gaps = None
    if grid is not None and not one_face:
        # Rejected shots on raster lines beyond the box (a window run across the wall behind
        # it) put the window's sides on the background, not on the box's silhouette.
        grid = _silhouette.background_sides(grid, seen[1], inliers)
    if silhouette and grid is not None and not one_face:
        gaps = raster_gaps(
            xb, origin, model, label_b, lo, hi, lo_pt, hi_pt, viewpoint, grid, cutoff * scale
        )
        used_window = silhouette_bounds(
            xb, origin, model, lo, hi, lo_pt, hi_pt, pad, viewpoint, grid, edges_b, gaps, pinned
        )
    elif grid is not None and not one_face:
        # Without the window (a subset of a raster: :func:`fit_cuboid`'s nearest surfaces, cut
        # at range jumps) the raster's beams still say how far along each face the next line
        # would have hit, and the edge lies anywhere in that gap: a receding beam's far face,
        # seen at 80-88 degrees, has gaps of a metre where its lines' spacing said 0.2 m. The
        # gap widens the standard error only: the bound stays, so the subset fit that stands
        # (its box decides which shots lie behind it) is the same.
        gaps = raster_gaps(
            xb,
            origin,
            model,
            label_b,
            lo,
            hi,
            lo_pt,
            hi_pt,
            viewpoint,
            grid,
            cutoff * scale,
            grazing_deg=SUBSET_GRAZING_DEG,
        )
    if used_window:
        notes.append(
            "edges no seen face bounds were placed on the pan-tilt raster's silhouette window "
            "(the raster's angular extent from the viewpoint widened by half a raster step"
            + (", edge-bisection shots where they reach beyond it" if grid[3].any() else "")
            + ")"
        )
    if one_face:
        lo, hi = one_face_depth(lo, hi, lo_face, hi_face, model)
    size = np.maximum(hi - lo, 1e-6)
    centre = origin + model.axes.T @ (0.5 * (hi + lo))

    # Uncertainty: covariance of the inlier refit, scaled by the sensor or by the residuals.
    n_par = model.rot_basis.shape[1] + model.offset.shape[0]
    sig, source = noise_level(residual[inliers], n_par, sigma, tolerances)
    sig = max(sig, floor)
    cov = covariance(model, x[inliers], label[inliers], sig)
    # The gap beyond an extent bound is its own face's raster step, unless a bisection shot
    # pins the edge; a raster window's solution moves the bound within it, it does not pin it.
    spans = extent_spans(
        xb, label_b, inliers_b, model, cutoff * scale, lo_pt, hi_pt, pad, pinned, single
    )
    if gaps is not None:
        # Over a raster, the gap up to the next raster line along the face is measured from
        # the beams themselves (:func:`raster_gaps`), not from the lines' spacing.
        known = np.isfinite(gaps) & ~pinned
        # Without the window, the gap only ever widens the lines' spacing (a subset's face
        # spacing can be the wider: its raster has holes where the background was).
        floor = 2.0 * pad[known] if silhouette else spans[known]
        spans[known] = np.maximum(floor, gaps[known])
    size_se, centre_se = propagate(
        model, xb, cov, (lo_pt, hi_pt, lo_face, hi_face, pad), sig, one_face, spans
    )
    if model.split_rivals:
        # Other splits of the raster lines between the faces fit as well (kept, not refused:
        # asbuilt.fit._cuboid_sparse.line_split_spread): each size, and the centre, is known
        # only to within theirs, in quadrature with the fit's own error.
        spread, shift = rival_size_spread(model, x, label, inliers, cutoff * scale, edge_pad, edges)
        size_se = np.hypot(np.asarray(size_se, dtype=np.float64), spread)
        centre_se = math.hypot(centre_se, shift)
    c_rot = model.rot_basis @ cov[: model.rot_basis.shape[1], : model.rot_basis.shape[1]]
    c_rot = c_rot @ model.rot_basis.T
    if one_face:
        longest = float(np.max(size[1:]))
        in_plane_angle = reach / max(longest, 1e-9)
        c_rot = c_rot + in_plane_angle**2 * np.outer(model.axes[0], model.axes[0])
    if model.turn is not None:
        # Two faces meeting between the face's two raster lines fit as well: its turn about
        # the lines is known only to the farthest such frame (asbuilt.fit._cuboid_sparse).
        c_rot = c_rot + math.radians(model.turn[1]) ** 2 * np.outer(model.turn[0], model.turn[0])
    # Each axis direction's variance: the rotation covariance across that axis (the rotation
    # about an axis leaves it unmoved). Per axis, because a column's tilt error (its long
    # axis) is several times smaller than its yaw error (the two across it).
    axis_var = np.array([np.trace(c_rot) - model.axes[k] @ c_rot @ model.axes[k] for k in range(3)])

    observed = lo_face & hi_face
    if one_face:
        # The depth behind a single seen face is assumed (the smaller visible width), not
        # measured: no standard error can be given for it.
        size_se = np.array(size_se, dtype=np.float64)
        size_se[int(model.face_axis[0])] = np.inf
        # and the centre lies half that made-up depth behind the face: as unknown (a review's
        # one-face box: centre 280 mm off at +-59 mm, z 4.8 in 4 of 4 seeds)
        centre_se = math.inf
    faces_per_axis = np.bincount(model.face_axis, minlength=3)
    axes, size, observed_t, order = _canonical(model.axes, size, observed)
    size_se = size_se[order]
    axes_deg = np.degrees(np.sqrt(np.maximum(axis_var[list(order)], 0.0)))
    faces_per_axis = faces_per_axis[order]
    # The rotation's covariance in the output axes' frame: a column's two tilt components
    # (its long axis toward each of the other two) are rotations about those axes, and one seen
    # face measures the tilt across it far better than the turn in its plane
    # (asbuilt.rules.alignment judges a lean per direction from them).
    frame_cov = axes @ c_rot @ axes.T
    cuboid = Cuboid(center=centre, axes=axes, size=size)

    residuals = cuboid.distance(pts)
    residuals[inliers] = residual[inliers]
    diagnostics = {
        "faces": float(model.offset.shape[0]),
        "outliers": float(n_out),
        "iterations": float(iterations),
        "scale": float(scale),
        "faces_axis0": float(faces_per_axis[0]),
        "faces_axis1": float(faces_per_axis[1]),
        "faces_axis2": float(faces_per_axis[2]),
        "silhouette": float(used_window),
        "mended": float(mended),
        **rotation_diagnostics(frame_cov),
    }
    if model.turn is not None:
        # The turn about the raster lines to the farthest frame splitting them otherwise, and
        # the output axis it is about (asbuilt.fit._cuboid_open leaves it out of a face's tilt).
        diagnostics["turn_deg"] = float(model.turn[1])
        diagnostics["turn_axis"] = float(np.argmax(np.abs(axes @ model.turn[0])))
    if one_face:
        diagnostics["assumed_size"] = float(
            np.flatnonzero(np.asarray(order) == model.face_axis[0])[0]
        )
    if not any(observed_t):
        notes.append("no two opposite faces seen: every size is bounded by the points' extent")
    result = FitResult(
        primitive=cuboid,
        residuals=residuals,
        inliers=inliers,
        stderr={
            "size": tuple(float(v) for v in size_se),
            "axes_deg": tuple(float(v) for v in axes_deg),
            "center": centre_se,
        },
        sigma=float(sig),
        sigma_source=source,
        method=METHOD,
        covariance=cov,
        observed=observed_t,
        diagnostics=diagnostics,
        notes=tuple(notes),
    )
    if not short.any():
        return result
    # The lower bound is what the shots span: the size without its pads.
    span = np.maximum(size - pad.sum(axis=0)[list(order)], 1e-6)
    return lower_bounds(result, short[list(order)], trusted, span)
