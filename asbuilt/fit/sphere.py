"""Sphere fit: algebraic start, then geometric least squares on orthogonal distances.

Method
------
Starts: the algebraic sphere of all points (Kasa 1976 / Pratt 1987 linearisation
``|p|^2 = 2 c.p + (r^2 - |c|^2)``, solved by linear least squares) and the best of random
four-point spheres by trimmed cost (Fischler & Bolles 1981). The final estimate minimises the
orthogonal distances ``|p - c| - r`` by Gauss-Newton on the four parameters (Lukacs, Marshall &
Martin 1998), robustly (concentration steps, then least squares on the inliers; see
:func:`asbuilt.fit._robust.robust_geometric_fit`), and finally weighted by a fitted incidence
noise model (:func:`_incidence_weighted`; not when the noise is above ``WEIGHTED_NOISE_RATIO``
of the radius, as for thin pipes). With the sensor's position known, the last step measures each
shot along its beam instead (:func:`_along_beams`), which removes the orthogonal distances' bias
under along-the-beam noise. The algebraic fit alone is biased on small caps; only the geometric
one is reported.
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import (
    covariance_from_jacobian,
    incidence_variance,
    noise_level,
    require_spread,
    scoring_subset,
    stderr_of,
    validate_points,
)

# Above this noise level relative to the radius the fit is not weighted by incidence: the
# cylinder's rule and reason.
from asbuilt.fit._cylinder_model import WEIGHTED_NOISE_RATIO
from asbuilt.fit._robust import (
    GeometricModel,
    RobustFit,
    gauss_newton,
    keep_count,
    refit_on,
    robust_geometric_fit,
    settled_fit,
)
from asbuilt.fit._sphere_background import fit_past_background
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Sphere
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = ["fit_sphere", "algebraic_sphere", "METHOD"]

METHOD = "algebraic (Kasa/Pratt) start + robust geometric Gauss-Newton (Lukacs et al. 1998)"


# State: (centre (3,), radius).


def _residuals(state, points):
    center, radius = state
    rel = points - center
    return np.sqrt(np.einsum("ij,ij->i", rel, rel)) - radius


def _jacobian(state, points):
    center, radius = state
    rel = points - center
    distance = np.maximum(np.sqrt(np.einsum("ij,ij->i", rel, rel)), 1e-300)
    jac = np.empty((len(points), 4))
    jac[:, :3] = -rel / distance[:, None]
    jac[:, 3] = -1.0
    return distance - radius, jac


def _update(state, delta, points, weights):
    center, radius = state
    return center + delta[:3], abs(radius + delta[3])


_MODEL = GeometricModel(_residuals, _jacobian, _update, 4)


def algebraic_sphere(points: np.ndarray):
    """Algebraic (Kasa) sphere: linear least squares on ``|p|^2 = 2 c.p + d``.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres

    Returns
    -------
    center : ndarray, shape (3,), metres
    radius : float, metres (NaN when undefined)
    """
    offset = points.mean(axis=0)
    local = points - offset
    design = np.column_stack([2.0 * local, np.ones(len(local))])
    rhs = np.einsum("ij,ij->i", local, local)
    solution, *_ = np.linalg.lstsq(design, rhs, rcond=None)
    center = solution[:3]
    squared = solution[3] + center @ center
    radius = float(np.sqrt(squared)) if squared > 0 else float("nan")
    return center + offset, radius


def _quad_start(points: np.ndarray, keep: int, samples: int = 64, cutoff: float | None = None):
    """Best sphere through four random points, by trimmed cost over ``keep`` points, or, with
    ``cutoff`` (metres), by MSAC cost over every point."""
    n = len(points)
    rng = np.random.default_rng(n)
    index = rng.integers(0, n, (samples, 4))
    base = points[index[:, 0]]
    rest = points[index[:, 1:]] - base[:, None, :]  # (s, 3, 3)
    rhs = 0.5 * np.einsum("sij,sij->si", rest, rest)
    det = np.linalg.det(rest)
    # Degenerate (coplanar) samples are told by each sample's own size: the determinant against
    # the product of its three edges (the sine-like volume of its tetrahedron). Against the
    # extent of every point, one stray return kilometres off (a floor hit 7.4 km away among a
    # 2.5 m sphere's shots) set the threshold above every sample of the sphere, so no
    # four-point start was left, and the fit was refused or not depending on the stray's range.
    edges = np.sqrt(np.einsum("sij,sij->si", rest, rest)).prod(axis=1)
    good = np.abs(det) > 1e-9 * np.maximum(edges, 1e-300)
    if not np.any(good):
        return None
    offset = np.linalg.solve(rest[good], rhs[good][:, :, None])[:, :, 0]
    center = base[good] + offset
    radius = np.linalg.norm(offset, axis=1)
    points, keep = scoring_subset(points, max(keep, 1), rng)
    rel = points[None, :, :] - center[:, None, :]
    residual = np.sqrt(np.einsum("snk,snk->sn", rel, rel)) - radius[:, None]
    if cutoff is not None:
        cost = np.minimum(residual * residual, cutoff * cutoff).sum(axis=1)
    else:
        cost = np.partition(residual * residual, keep - 1, axis=1)[:, :keep].sum(axis=1)
    best = int(np.argmin(cost))
    return center[best], float(radius[best])


#: Four-point samples the MSAC rescue of a refused fit draws (:func:`_msac_rescue`).
RESCUE_SAMPLES = 256


def _msac_rescue(robust, points: np.ndarray, sigma, tolerances: Tolerances):
    """The sphere settled (least squares on its inliers, no concentration steps) from the
    four-point sample of least MSAC cost (Torr & Zisserman 2000: every shot counts, each at
    most the cutoff squared), when its MSAC cost is lower than ``robust``'s (a
    :class:`RobustFit` or None); else ``robust``.

    The trimmed cost of the starts and concentration steps keeps three quarters of the shots:
    with a raster row on the floor below a sphere (8 of 30 shots) it keeps a floor shot, and
    its steps wander off the sphere (an independent ray caster's 1.3 m sphere at 8.5 m was
    refused, 30 of 30 shots outliers). MSAC needs one sample of four sphere shots. ``sigma``
    metres, or None for the prior noise.
    """
    cutoff = tolerances.outlier_cutoff_sigma * float(
        sigma if sigma is not None else tolerances.prior_range_sigma
    )
    start = _quad_start(points, 0, RESCUE_SAMPLES, cutoff)
    if start is None:
        return robust
    settled = settled_fit(points, start, _MODEL, kind="sphere", sigma=sigma, tolerances=tolerances)
    if settled is None:
        return robust
    if robust is None:
        return settled

    def msac(fit):
        return float(np.minimum(fit.residuals * fit.residuals, cutoff * cutoff).sum())

    return settled if msac(settled) < msac(robust) else robust


#: Mean resultant length of the inliers' directions from the centre above which the sphere is
#: taken as seen from one side (a hemisphere of raster shots gives about 0.6, all round 0).
ONE_SIDED = 0.3


#: Angle from the seen side's mean direction beyond which a point faces away from it.
FAR_SIDE_DEG = 95.0


def _drop_far_side(robust: RobustFit, points: np.ndarray) -> RobustFit:
    """Reject inliers on the far side of a sphere seen from one side, and refit without them.

    A station sees at most the hemisphere facing it; a shot that passed the sphere and hit the
    wall behind can land within millimetres of the far side, where its distance alone cannot
    tell it from a surface point. When the inliers' directions from the centre are concentrated
    (mean resultant length above ``ONE_SIDED``), inliers more than ``FAR_SIDE_DEG`` from their
    mean direction are rejected and the fit is redone by least squares on the rest.
    """
    center, _ = robust.state
    kept = robust.inliers
    directions = points - center
    directions /= np.maximum(np.linalg.norm(directions, axis=1), 1e-300)[:, None]
    mean = directions[kept].mean(axis=0)
    length = float(np.linalg.norm(mean))
    if length <= ONE_SIDED:
        return robust
    far = kept & (directions @ (mean / length) < np.cos(np.radians(FAR_SIDE_DEG)))
    mask = kept & ~far
    if not far.any() or np.count_nonzero(mask) <= _MODEL.n_params:
        return robust
    return refit_on(_MODEL, robust, points, mask)


def _incidence_weighted(robust: RobustFit, points: np.ndarray) -> tuple[RobustFit, np.ndarray]:
    """Refit the inliers by weighted least squares with a fitted incidence noise model.

    Seen from a distant station, the cosine of a shot's incidence is the cosine between its
    direction from the centre and the seen side's mean direction;
    :func:`asbuilt.fit._common.incidence_variance` fits the noise model ``A + B cos^2`` and the
    fit is redone with weights ``1 / (A + B cos^2)``. Weights are 1 with even noise, when the
    sphere is seen all round, or when the noise is above ``WEIGHTED_NOISE_RATIO`` of the radius
    (the range noise's sideways part biases a small sphere's radius, and weighting the oblique
    shots up makes that worse: 200 benchmark trials of a 0.2 m sphere, bias -0.41 / +0.28 /
    -0.44 mm at 20 / 30 / 40 points weighted, -0.28 / +0.21 / -0.36 unweighted). Returns the refitted RobustFit (same inliers) and each point's
    variance relative to a square-on shot, shape (n,).
    """
    uniform = np.ones(len(points))
    center, radius = robust.state
    if robust.scale > WEIGHTED_NOISE_RATIO * radius:
        return robust, uniform
    kept = robust.inliers
    directions = points - center
    directions /= np.maximum(np.linalg.norm(directions, axis=1), 1e-300)[:, None]
    mean = directions[kept].mean(axis=0)
    length = float(np.linalg.norm(mean))
    if length <= ONE_SIDED:
        return robust, uniform
    relative = incidence_variance(robust.residuals, (directions @ (mean / length)) ** 2, kept)
    if relative is None:
        return robust, uniform
    weights = np.where(kept, 1.0 / relative, 0.0)
    state, residuals, jacobian = gauss_newton(
        _MODEL, robust.state, points, lambda _r, w=weights: w, 6, 1e-7
    )
    return RobustFit(state, residuals, kept, jacobian[kept], robust.scale), relative


#: Cosine of the incidence (on the current sphere) below which a shot keeps its orthogonal
#: distance in :func:`_along_beams`: near the silhouette the range along a beam changes without
#: bound with the sphere, and a beam may miss a neighbouring candidate sphere altogether.
GRAZING_COS = 0.3


def _along_beams(
    robust: RobustFit, points: np.ndarray, viewpoint: np.ndarray, relative: np.ndarray
) -> RobustFit:
    """Refit the inliers on their range errors along the beams from ``viewpoint``.

    A shot's noise lies along its beam (range) and across it (pointing), not along the surface
    normal, so it moves both a point's distance from the sphere and the normal that distance is
    taken along; orthogonal least squares then shrinks a small sphere's radius (errors in
    variables: 0.2 m spheres scanned by 20-40 shots with 2 mm range noise, -0.12 to -0.14 mm
    from range noise alone, 4-6 standard errors of the mean of 1,000 simulated trials). Each
    shot's residual here is ``(t - R) cos(i)``: its measured range ``R`` less the range ``t``
    at which its beam meets the sphere, times the cosine of the incidence there, which equals
    the orthogonal distance to first order (same weights, same covariance) but depends on the
    noise only through ``R``. The cosines are fixed within each solve and updated between
    (iteratively reweighted); shots within ``GRAZING_COS`` of grazing keep the orthogonal
    distance.

    Not for pipes: on the benchmark's scans the pointing noise pushes silhouette shots outward
    about as much as the range noise shrinks an orthogonal fit, and refitting thin pipes along
    their beams biased them (benchmarks/RESULTS.md).

    Parameters
    ----------
    robust : RobustFit
        The settled fit (orthogonal residuals).
    points : ndarray, shape (n, 3), metres
    viewpoint : ndarray, shape (3,), metres
        The station, in ``points``' frame.
    relative : ndarray, shape (n,)
        Each shot's variance relative to a square-on shot (weights ``1 / relative``).

    Returns
    -------
    RobustFit
        Same inliers and scale, residuals and Jacobian orthogonal at the refitted state; or
        ``robust`` itself when no inlier's beam meets the sphere squarely, or when the refit
        raises the weighted orthogonal cost by more than one noise variance (the correction is
        of second order: a solve that went further took a wrong branch near grazing, or the
        shots were not taken from ``viewpoint``).
    """
    kept = robust.inliers
    rays = points - viewpoint
    ranges = np.linalg.norm(rays, axis=1)
    if np.any(ranges <= 0.0):
        return robust
    beams = rays / ranges[:, None]
    weights = np.where(kept, 1.0 / relative, 0.0)
    state = robust.state
    for _ in range(3):
        _, square = _beam_meets(state, beams, viewpoint)
        cosine = np.sqrt(np.maximum(square, 0.0)) / state[1]
        beam = cosine > GRAZING_COS
        if np.count_nonzero(beam & kept) == 0:
            return robust
        model = GeometricModel(
            _residuals, _beam_jacobian(beams, ranges, viewpoint, cosine, beam), _update, 4
        )
        state, _, _ = gauss_newton(model, state, points, lambda _r, w=weights: w, 6, 1e-9)
    residuals, jacobian = _jacobian(state, points)
    # The correction is of second order: it moves the orthogonal cost by a small fraction of
    # one noise variance. A solve that went further (a wrong branch near grazing) is dropped.
    before = float(weights @ (robust.residuals * robust.residuals))
    if not float(weights @ (residuals * residuals)) <= before + robust.scale**2:
        return robust
    return RobustFit(state, residuals, kept, jacobian[kept], robust.scale)


def _beam_meets(state, beams: np.ndarray, viewpoint: np.ndarray):
    """Where unit beams (n, 3) from ``viewpoint`` (3,) metres meet the sphere ``state``:
    each beam's range to the point nearest the centre, ``ahead`` (n,) metres, and the
    discriminant ``ahead^2 - |c - v|^2 + r^2`` (n,) square metres (negative where the beam
    misses; the first hit is at ``ahead - sqrt``, and ``sqrt / r`` is the incidence's
    cosine)."""
    center, radius = state
    rel = center - viewpoint
    ahead = beams @ rel
    return ahead, ahead * ahead - rel @ rel + radius * radius


def _beam_jacobian(beams, ranges, viewpoint, cosine, beam):
    """The Jacobian function of :func:`_along_beams`' residuals (fixed ``cosine``, shape (n,))."""

    def jacobian(state, points):
        orthogonal, jac = _jacobian(state, points)
        center, radius = state
        rel = center - viewpoint
        ahead, square = _beam_meets(state, beams, viewpoint)
        root = np.sqrt(np.maximum(square, 1e-300))
        meet = ahead - root
        residuals = np.where(beam, (meet - ranges) * cosine, orthogonal)
        along = np.empty_like(jac)
        along[:, :3] = beams - (ahead[:, None] * beams - rel) / root[:, None]
        along[:, 3] = -radius / root
        jac = np.where(beam[:, None], along * cosine[:, None], jac)
        return residuals, jac

    return jacobian


def fit_sphere(
    points,
    *,
    sigma=None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    viewpoint=None,
) -> FitResult:
    """Fit a sphere by robust geometric least squares (orthogonal distances).

    Algorithm: algebraic (Kasa/Pratt) and four-point starts, concentration steps, then
    Gauss-Newton on the inliers (Lukacs, Marshall & Martin 1998); see the module docstring.

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    sigma : float, optional, metres
        The sensor's range sigma; scales the standard errors when given.
    tolerances : Tolerances
    viewpoint : array_like, shape (3,), metres, optional
        The sensor's position: the last step then measures the shots along their beams
        (:func:`_along_beams`), and a fit that is refused, or has three shots or more in front
        of it or inside it, is made again of the nearest surfaces' shots when every shot they
        leave out lies behind the sphere along its beam
        (:mod:`asbuilt.fit._sphere_background`). Without it no shot is taken as background
        that way.

    Returns
    -------
    FitResult
        ``primitive`` is a :class:`~asbuilt.primitives.Sphere`; residuals are positive
        outside. ``covariance`` (4 x 4) is over (centre x, y, z, radius), metres. ``stderr``:
        ``radius``; ``center`` (root of the summed centre variances, the RMS position error).
        The covariance is ``sigma^2 (J^T W J)^-1`` with ``W`` the inliers' incidence weights
        (see :func:`_incidence_weighted`; all 1 with even noise) and ``sigma`` the square-on
        noise level (the sensor's, else from the weighted residuals).
        Diagnostics: ``cap_deg`` (apex angle of the cone from the centre that holds the
        inliers: twice the largest angle between an inlier's direction and their mean
        direction; 360 when they surround the centre).

    Raises
    ------
    FitError
        Too few points, identical, collinear or coplanar points, or too many outliers.
    """
    if viewpoint is None:
        return _fit_shots(points, sigma, tolerances, None)
    # With the station known, whole raster lines on the wall behind the sphere are told from it
    # by the range jumps between neighbouring beams (a fit that is neither refused nor
    # contradicted from the station is returned as it is).
    return fit_past_background(
        _fit_shots,
        validate_points(points, "sphere"),
        np.asarray(viewpoint, dtype=np.float64),
        sigma,
        tolerances,
    )


def _fit_shots(points, sigma, tolerances: Tolerances, viewpoint) -> FitResult:
    """:func:`fit_sphere` of ``points`` (n, 3) metres without the split from the background
    (``sigma`` metres or None, ``viewpoint`` (3,) metres or None): the fit the split makes of
    each subset of the shots."""
    pts = validate_points(points, "sphere")
    require_spread(pts, "sphere", 3)
    offset = pts.mean(axis=0)
    local = pts - offset
    starts = []
    center, radius = algebraic_sphere(local)
    if np.isfinite(radius) and np.all(np.isfinite(center)):
        starts.append((center, radius))
    quad = _quad_start(local, keep_count(len(local), tolerances))
    if quad is not None:
        starts.append(quad)
    try:
        robust = robust_geometric_fit(
            local,
            starts,
            _MODEL,
            kind="sphere",
            sigma=sigma,
            tolerances=tolerances,
            always_refine=2,
            max_starts=2,
        )
    except FitError as exc:
        # Only a refused fit is rescued: offered against every fit that rejects a fifth of the
        # shots, the MSAC sphere also fitted a subset of a thin pipe stub's shots better, and
        # kind "auto" took one such stub (of 600) for a sphere.
        robust = _msac_rescue(None, local, sigma, tolerances)
        if robust is None:
            raise exc from None
    near = robust
    robust = _drop_far_side(near, local)
    far_side = int(np.count_nonzero(near.inliers & ~robust.inliers))
    robust, relative = _incidence_weighted(robust, local)
    if viewpoint is not None:
        robust = _along_beams(robust, local, np.asarray(viewpoint, float) - offset, relative)
    center, radius = robust.state
    # Noise level of a square-on shot; the inliers' weights are 1 / relative variance.
    weights = 1.0 / relative[robust.inliers]
    noise, source = noise_level(
        robust.residuals[robust.inliers] * np.sqrt(weights), 4, sigma, tolerances
    )
    covariance = covariance_from_jacobian(robust.jacobian * np.sqrt(weights)[:, None], noise)
    sphere = Sphere(center + offset, radius)
    directions = local[robust.inliers] - center
    directions /= np.maximum(np.linalg.norm(directions, axis=1), 1e-300)[:, None]
    mean = directions.mean(axis=0)
    if np.linalg.norm(mean) < 1e-9:
        cap = 360.0
    else:
        mean /= np.linalg.norm(mean)
        cap = float(2.0 * np.degrees(np.arccos(np.clip(directions @ mean, -1.0, 1.0)).max()))
        cap = min(cap, 360.0)
    stderr = {
        "radius": stderr_of(covariance[3, 3]),
        "center": stderr_of(np.trace(covariance[:3, :3])),
    }
    notes = []
    outliers = int(len(pts) - np.count_nonzero(robust.inliers))
    if outliers:
        notes.append(
            f"{outliers} outlier point(s) rejected (beyond {tolerances.outlier_cutoff_sigma:g}"
            f" x {robust.scale * 1000:.3g} mm"
            + (f", or {far_side} on the far side" if far_side else "")
            + ")."
        )
    return FitResult(
        primitive=sphere,
        residuals=sphere.distance(pts),
        inliers=robust.inliers,
        stderr=stderr,
        sigma=noise,
        sigma_source=source,
        method=METHOD,
        covariance=covariance,
        diagnostics={"cap_deg": cap},
        notes=tuple(notes),
    )
