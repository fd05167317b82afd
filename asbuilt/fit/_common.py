"""Shared numerics for the primitive fits: validation, robust scales, normals, Gauss-Newton.

Everything here is a pure numpy function on float64 arrays in metres. The fits in
:mod:`asbuilt.fit.plane`, :mod:`.sphere` and :mod:`.cylinder` share one robust scheme
(:func:`robust_geometric_fit`):

1. the starts are ranked by their least-trimmed-squares cost (Rousseeuw 1984; the sum of the
   ``h`` smallest squared residuals, ``h`` = the points less the design contamination); the
   first start and the best few are refined by concentration steps (Rousseeuw & Van Driessen
   2006: Gauss-Newton on the ``h`` points closest to the current surface) and compared by their
   MSAC cost (Torr & Zisserman 2000);
2. points within ``outlier_cutoff_sigma`` noise scales of the winner are the inliers (the sensor
   sigma, else :func:`residual_scale`), and the final estimate is plain geometric least squares
   on the inliers only (so clean data gets the efficient estimate), repeated until the inlier
   set is stable; without a sensor sigma, the likeliest of a few nested inlier sets is taken
   once (:func:`mixture_score`), so that a small-sample scale does not reject good shots.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg.lapack import dposv as _dposv

from asbuilt.errors import FitError
from asbuilt.fit._mixture import mixture_score
from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS, Tolerances

__all__ = [
    "validate_points",
    "principal_axes",
    "require_spread",
    "check_spread",
    "orthonormal_basis",
    "orthonormal_bases",
    "basis_floats",
    "quick_median",
    "orient",
    "robust_scale",
    "tukey_weights",
    "residual_scale",
    "few_residual_dof",
    "settled_fit",
    "trimmed_cost",
    "keep_count",
    "noise_level",
    "covariance_from_jacobian",
    "stderr_of",
    "mixture_score",
    "incidence_variance",
    "MIN_RELATIVE_VARIANCE",
    "EVIDENCE",
    "local_normals",
    "arc_coverage_deg",
    "GeometricModel",
    "RobustFit",
    "robust_geometric_fit",
    "TUKEY_C",
    "DESIGN_CONTAMINATION",
]

#: Tukey biweight tuning constant: 95% efficiency at the Gaussian (Holland & Welsch 1977).
TUKEY_C = 4.685
#: MAD to Gaussian sigma.
_MAD_TO_SIGMA = 1.482602218505602


def validate_points(points, kind: str) -> np.ndarray:
    """Return ``points`` as a float64 array, raising FitError when they cannot be fitted at all.

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    kind : str
        The primitive being fitted (a key of :data:`asbuilt.tolerances.MIN_POINTS`).

    Returns
    -------
    ndarray, shape (n, 3), metres
        A float64 copy.
    """
    try:
        array = np.array(points, dtype=np.float64, copy=True)
    except (TypeError, ValueError):
        raise FitError("The points must be numbers in an (n, 3) array.") from None
    if array.ndim != 2 or array.shape[1] != 3:
        raise FitError(f"The points must have shape (n, 3), not {array.shape}.")
    if not np.all(np.isfinite(array)):
        raise FitError("The points must be finite (a coordinate is NaN or infinite).")
    need = MIN_POINTS[kind]
    if len(array) < need:
        raise FitError(
            f"A {kind} needs at least {need} points, got {len(array)}; measure more points."
        )
    return array


def principal_axes(points: np.ndarray, weights: np.ndarray | None = None):
    """Weighted centroid and principal directions of points.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    weights : ndarray, shape (n,), optional
        Non-negative weights; uniform when None.

    Returns
    -------
    centroid : ndarray, shape (3,), metres
    spread : ndarray, shape (3,), metres
        Root-mean-square extent along each direction, descending.
    directions : ndarray, shape (3, 3)
        Rows are the unit principal directions, matching ``spread``.
    """
    if weights is None:
        centroid = points.sum(axis=0) / len(points)  # points.mean(axis=0), cheaper
        centred = points - centroid
        total = float(len(points))
    else:
        total = float(weights.sum())
        centroid = (weights @ points) / total
        centred = (points - centroid) * np.sqrt(weights)[:, None]
    _, singular, vt = np.linalg.svd(centred, full_matrices=False)
    spread = np.zeros(3)
    spread[: len(singular)] = singular / np.sqrt(max(total, 1.0))
    if vt.shape[0] < 3:
        vt = np.vstack([vt, np.cross(vt[0], vt[1]) if vt.shape[0] == 2 else np.eye(3)[1:]])
    return centroid, spread, vt


def require_spread(points: np.ndarray, kind: str, dimensions: int) -> np.ndarray:
    """Raise FitError unless the points span ``dimensions`` independent directions.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    kind : str
        Named in the message.
    dimensions : int
        1 (not all identical), 2 (not collinear) or 3 (not coplanar).

    Returns
    -------
    ndarray, shape (3,), metres
        The RMS spread along the three principal directions, descending.
    """
    _, spread, _ = principal_axes(points)
    check_spread(spread, kind, dimensions)
    return spread


def check_spread(spread: np.ndarray, kind: str, dimensions: int) -> None:
    """:func:`require_spread` on a spread the caller has from :func:`principal_axes` already.

    Parameters
    ----------
    spread : ndarray, shape (3,), metres
        RMS spread along the principal directions, descending.
    kind : str
    dimensions : int
    """
    size = spread[0]
    relative = 1e-9
    if size <= 1e-12:
        raise FitError(f"The points are all identical; a {kind} needs points spread over it.")
    if dimensions >= 2 and spread[1] <= relative * size:
        raise FitError(
            f"The points must not be collinear; a {kind} needs points spread over a surface."
        )
    if dimensions >= 3 and spread[2] <= relative * size:
        raise FitError(
            f"The points must not be coplanar; a {kind} needs points on a curved surface."
        )


def basis_floats(ax: float, ay: float, az: float) -> tuple[float, ...]:
    """``(ux, uy, uz, vx, vy, vz)`` of :func:`orthonormal_basis` in Python floats (one code
    path for the single and the batched version, so both round alike)."""
    mx, my, mz = abs(ax), abs(ay), abs(az)
    # u = axis x e_least (the first least-aligned coordinate axis on ties), written out
    # (np.cross is slow on single 3-vectors).
    if mx <= my and mx <= mz:
        ux, uy, uz = 0.0, az, -ay
    elif my <= mz:
        ux, uy, uz = -az, 0.0, ax
    else:
        ux, uy, uz = ay, -ax, 0.0
    norm = (ux * ux + uy * uy + uz * uz) ** 0.5
    ux, uy, uz = ux / norm, uy / norm, uz / norm
    return ux, uy, uz, ay * uz - az * uy, az * ux - ax * uz, ax * uy - ay * ux


def orthonormal_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors ``u``, ``v`` completing ``axis`` to a right-handed frame.

    Deterministic: ``u`` is ``axis`` x e, with e the coordinate axis least aligned with ``axis``,
    normalised; ``v = axis x u``. The fits' covariances are expressed in this basis.

    Parameters
    ----------
    axis : ndarray, shape (3,)
        Unit vector.

    Returns
    -------
    u, v : ndarray, shape (3,)
    """
    if isinstance(axis, np.ndarray):
        ax, ay, az = axis.tolist()
    else:
        ax, ay, az = (float(value) for value in axis)
    ux, uy, uz, vx, vy, vz = basis_floats(ax, ay, az)
    return np.array((ux, uy, uz)), np.array((vx, vy, vz))


def orthonormal_bases(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`orthonormal_basis` of many axes at once, bit for bit the same.

    Parameters
    ----------
    axes : ndarray, shape (a, 3)
        Unit vectors.

    Returns
    -------
    u, v : ndarray, shape (a, 3)
    """
    frames = np.array([basis_floats(*axis) for axis in axes.tolist()]).reshape(-1, 6)
    return frames[:, :3], frames[:, 3:]


def orient(direction: np.ndarray) -> np.ndarray:
    """Give a sign-free direction its canonical sign: its largest component positive.

    Ties (within 1e-9) go to z, then x, then y, so a vertical axis points up and a horizontal
    pipe along x or y points along +x or +y; a small slope or measurement noise never flips it
    (the sign changes only near 45 degrees between two coordinate axes).

    Parameters
    ----------
    direction : ndarray, shape (3,)

    Returns
    -------
    ndarray, shape (3,)
    """
    magnitudes = np.abs(direction)
    largest = float(magnitudes.max())
    for index in (2, 0, 1):
        if magnitudes[index] >= largest - 1e-9:
            return direction if direction[index] > 0 else -direction
    return direction


def robust_scale(residuals: np.ndarray, floor: float) -> float:
    """Gaussian-consistent scale of residuals: 1.4826 x median |r|, at least ``floor``.

    The median is taken about zero because fit residuals are centred on the surface.

    Parameters
    ----------
    residuals : ndarray, shape (n,), metres
    floor : float, metres

    Returns
    -------
    float, metres
    """
    size = residuals.size
    if size == 0:
        return float(floor)
    magnitudes = np.abs(residuals)
    half = size // 2
    if size % 2:
        median = float(np.partition(magnitudes, half)[half])
    else:
        part = np.partition(magnitudes, (half - 1, half))
        median = 0.5 * float(part[half - 1] + part[half])
    return max(_MAD_TO_SIGMA * median, float(floor))


#: Half-width, in robust sigmas, of the window whose RMS :func:`residual_scale` measures.
WIDE_WINDOW = 8.0


def residual_scale(residuals: np.ndarray, floor: float, n_params: int) -> float:
    """Noise scale for the inlier test: the larger of the MAD scale and the RMS of the points
    within ``WIDE_WINDOW`` MAD scales (with the degrees of freedom the fit used up).

    For Gaussian residuals both estimate sigma. Range-finder residuals are a mixture (grazing
    shots are several times more precise than square-on ones), whose median absolute value
    understates the spread of the noisier shots; a 3-sigma test on the MAD alone then rejects
    good square-on shots (measured: 1-2 in 20 on a 0.6 m tank at 3 m). Shots on the background,
    centimetres to metres off, stay outside the wide window.

    Parameters
    ----------
    residuals : ndarray, shape (n,), metres
    floor : float, metres
    n_params : int

    Returns
    -------
    float, metres
    """
    scale = robust_scale(residuals, floor)
    wide = np.abs(residuals) <= WIDE_WINDOW * scale
    dof = int(np.count_nonzero(wide)) - n_params
    if dof > 0:
        scale = max(scale, float(np.sqrt(np.sum(residuals[wide] ** 2) / dof)))
    return scale


def tukey_weights(residuals: np.ndarray, scale: float, c: float = TUKEY_C) -> np.ndarray:
    """Tukey biweight IRLS weights ``(1 - (r / (c s))^2)^2`` inside ``c s``, else 0.

    Parameters
    ----------
    residuals : ndarray, shape (n,), metres
    scale : float, metres
    c : float
        Tuning constant in units of ``scale``.

    Returns
    -------
    ndarray, shape (n,)
    """
    u = residuals / (c * scale)
    return np.where(np.abs(u) < 1.0, (1.0 - u * u) ** 2, 0.0)


#: Outlier fraction the start selection is designed for: the product promises to cope with 20%
#: edge outliers; trimming only that much (plus margin) keeps a wrong surface that happens to
#: fit half of a sparse scan from beating the right one that fits all of it.
DESIGN_CONTAMINATION = 0.25


def keep_count(n: int, tolerances: Tolerances) -> int:
    """Points a trimmed cost sums over: ``n`` less the design contamination (at least 1).

    The design contamination is ``DESIGN_CONTAMINATION`` (25%), or
    ``tolerances.max_outlier_fraction`` when that is smaller.
    """
    fraction = min(DESIGN_CONTAMINATION, tolerances.max_outlier_fraction)
    return max(1, n - int(np.floor(fraction * n)))


def trimmed_cost(residuals: np.ndarray, keep: int) -> float:
    """Least-trimmed-squares cost: sum of the ``keep`` smallest squared residuals, metres^2."""
    squares = residuals * residuals
    if keep >= squares.size:
        return float(squares.sum())
    return float(np.partition(squares, keep - 1)[:keep].sum())


def noise_level(
    residuals: np.ndarray, n_params: int, sigma: float | None, tolerances: Tolerances
) -> tuple[float, str]:
    """The noise level standard errors are scaled by, and where it comes from.

    Parameters
    ----------
    residuals : ndarray, shape (m,), metres
        Inlier residuals of the final fit.
    n_params : int
        Parameters estimated by the fit.
    sigma : float or None, metres
        The sensor's range sigma when known.
    tolerances : Tolerances

    Returns
    -------
    sigma : float, metres
        The sensor's sigma, else ``sqrt(sum r^2 / (m - n_params))`` floored by
        ``tolerances.sigma_floor``. With fewer than ``tolerances.min_noise_dof`` residual
        degrees of freedom the missing ones count as residuals of the prior noise level
        ``tolerances.prior_range_sigma`` (the scaled inverse chi-square prior of a Bayesian
        variance estimate, Gelman et al., "Bayesian Data Analysis", section 2.6): an exact fit
        of 5 points by 5 parameters no longer claims the 0.1 mm floor.
    source : str
        ``"sensor"`` or ``"residuals"``.
    """
    if sigma is not None:
        return float(sigma), "sensor"
    dof = max(residuals.size - n_params, 0)
    squares = float(np.sum(residuals * residuals))
    missing = max(int(tolerances.min_noise_dof) - dof, 0)
    squares += missing * float(tolerances.prior_range_sigma) ** 2
    estimate = float(np.sqrt(squares / (dof + missing))) if dof + missing > 0 else 0.0
    return max(estimate, float(tolerances.sigma_floor)), "residuals"


def few_residual_dof(n_inliers: int, n_params: int, tolerances: Tolerances) -> bool:
    """Whether a fit without a sensor sigma has too few residual degrees of freedom
    (``tolerances.min_noise_dof``) for a noise level of its own: then no point is rejected by
    a test on that level, and :func:`noise_level` leans on the prior."""
    return n_inliers - n_params < int(tolerances.min_noise_dof)


def stderr_of(variance: float) -> float:
    """Standard error from a variance: its root, or infinity when the variance is negative or
    not finite (a parameter the points do not determine, e.g. the radius of a nearly flat patch).

    Parameters
    ----------
    variance : float, metres^2 or radians^2

    Returns
    -------
    float
    """
    variance = float(variance)
    if not np.isfinite(variance) or variance < 0.0:
        return float("inf")
    return float(np.sqrt(variance))


def covariance_from_jacobian(jacobian: np.ndarray, sigma: float) -> np.ndarray:
    """Gauss-Newton covariance ``sigma^2 (J^T J)^-1`` (pseudo-inverse when rank deficient).

    Parameters
    ----------
    jacobian : ndarray, shape (m, p)
        Derivatives of the inlier residuals (metres) by the parameters.
    sigma : float, metres

    Returns
    -------
    ndarray, shape (p, p)
    """
    normal = jacobian.T @ jacobian
    try:
        inverse = np.linalg.inv(normal)
        if not np.all(np.isfinite(inverse)):
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        inverse = np.linalg.pinv(normal)
    return sigma * sigma * inverse


def local_normals(points: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Surface normals from the PCA of each point's ``k`` nearest neighbours (Hoppe et al. 1992).

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    k : int
        Neighbours including the point itself (clipped to ``[3, n]``).

    Returns
    -------
    normals : ndarray, shape (n, 3)
        Unit normals (sign arbitrary).
    flatness : ndarray, shape (n,)
        Smallest over middle eigenvalue of each neighbourhood (0 for a perfect plane patch).
    """
    n = len(points)
    k = int(min(max(k, 3), n))
    if n <= 600:
        squares = np.einsum("ij,ij->i", points, points)
        dist = squares[:, None] + squares[None, :] - 2.0 * (points @ points.T)
        np.fill_diagonal(dist, -1.0)  # each point is its own nearest neighbour
        index = np.argpartition(dist, k - 1, axis=1)[:, :k]
    else:
        from scipy.spatial import cKDTree

        _, index = cKDTree(points).query(points, k=k)
    hood = points[index]
    # The neighbourhoods' means as numpy's mean computes them (sum, then divide by the count),
    # without its per-call overhead.
    hood -= hood.sum(axis=1, keepdims=True) / k
    scatter = hood.transpose(0, 2, 1) @ hood
    values, vectors = np.linalg.eigh(scatter)
    flatness = values[:, 0] / np.maximum(values[:, 1], 1e-300)
    return vectors[:, :, 0], flatness


def arc_coverage_deg(angles: np.ndarray) -> float:
    """Angular coverage of directions about an axis: 360 degrees less the largest gap.

    Parameters
    ----------
    angles : ndarray, shape (n,), radians

    Returns
    -------
    float, degrees
    """
    if angles.size < 2:
        return 0.0
    ordered = np.sort(np.mod(angles, 2 * np.pi))
    gaps = np.diff(np.concatenate([ordered, ordered[:1] + 2 * np.pi]))
    return float(np.degrees(2 * np.pi - gaps.max()))


@dataclass(frozen=True)
class GeometricModel:
    """The three functions a geometric least-squares fit needs.

    ``residuals(state, points) -> (n,)`` metres; ``jacobian(state, points) -> (r (n,), J (n, p))``;
    ``update(state, delta (p,), points, weights) -> state``. ``state`` is any value.
    """

    residuals: Callable[[Any, np.ndarray], np.ndarray]
    jacobian: Callable[[Any, np.ndarray], tuple[np.ndarray, np.ndarray]]
    update: Callable[[Any, np.ndarray, np.ndarray, np.ndarray], Any]
    n_params: int


@dataclass(frozen=True)
class RobustFit:
    """What :func:`robust_geometric_fit` returns.

    Attributes
    ----------
    state : Any
        The model's final state (least squares on the inliers).
    residuals : ndarray, shape (n,), metres
        Every point's residual at ``state``.
    inliers : ndarray, shape (n,), bool
    jacobian : ndarray, shape (m, p)
        The inliers' Jacobian at ``state``.
    scale : float, metres
        The noise scale inliers were judged by.
    """

    state: Any
    residuals: np.ndarray
    inliers: np.ndarray
    jacobian: np.ndarray
    scale: float


def _newton_step(normal: np.ndarray, gradient: np.ndarray) -> np.ndarray:
    """The Gauss-Newton step ``-normal^-1 gradient``: a Cholesky solve (LAPACK ``dposv``, without
    the overhead of :func:`numpy.linalg.solve` on a 5 x 5 system), LU when the normal matrix is
    not numerically positive definite, least squares when it is singular."""
    _, solution, info = _dposv(normal, gradient)
    if info == 0:
        return -solution
    try:
        return -np.linalg.solve(normal, gradient)
    except np.linalg.LinAlgError:
        return -np.linalg.lstsq(normal, gradient, rcond=None)[0]


def gauss_newton(model, state, points, weigh, iterations, tolerance, current=None):
    """Gauss-Newton with step halving; ``weigh(residuals) -> weights`` is re-evaluated each step.

    Returns (state, residuals, jacobian); stops when a step lowers the weighted cost by less
    than ``tolerance`` times the cost. A step whose predicted decrease (of the linearised
    cost, ``g^T N^-1 g``) is already below that is not taken: it would move the state by a
    negligible fraction of its standard error (``tolerance`` is at most 1e-7 in the fits).
    """
    residuals, jacobian = model.jacobian(state, points) if current is None else current
    for _ in range(iterations):
        weights = weigh(residuals)
        if np.count_nonzero(weights) < model.n_params:
            break
        weighted_residuals = weights * residuals
        cost = float(weighted_residuals @ residuals)
        if cost <= 0.0:
            break
        normal = (jacobian.T * weights) @ jacobian
        gradient = jacobian.T @ weighted_residuals
        delta = _newton_step(normal, gradient)
        if tolerance > 0.0 and -float(gradient @ delta) <= tolerance * cost:
            break
        accepted = False
        for _ in range(8):
            trial = model.update(state, delta, points, weights)
            trial_residuals, trial_jacobian = model.jacobian(trial, points)
            trial_cost = float(weights @ (trial_residuals * trial_residuals))
            if math.isfinite(trial_cost) and trial_cost <= cost:
                accepted = True
                break
            delta = 0.5 * delta
        if not accepted:
            break
        state, residuals, jacobian = trial, trial_residuals, trial_jacobian
        if cost - trial_cost <= tolerance * cost:
            break
    return state, residuals, jacobian


def _best_inlier_set(residuals, mask, extent, floor):
    """The likeliest inlier set among those nested by |residual|, at least as large as ``mask``.

    Each candidate keeps the ``m`` points of smallest |r|, scored by :func:`mixture_score`
    (lowest wins). A 3-sigma test
    on a small-sample scale can reject a whole group of good but noisier shots (square-on shots
    among grazing ones); taken together they raise sigma enough to be explained, which a
    one-at-a-time test never sees. Background shots, centimetres to metres off, never pay.
    """
    order = np.argsort(np.abs(residuals))
    squares = np.cumsum(residuals[order] ** 2)
    n = residuals.size
    counts = np.arange(1, n + 1)
    variance = np.maximum(squares / counts, floor * floor)
    score = counts * (1.0 + np.log(2.0 * np.pi * variance))
    score += (n - counts) * 2.0 * np.log(max(extent, floor))
    first = int(np.count_nonzero(mask)) - 1
    best = first + int(np.argmin(score[first:]))
    chosen = np.zeros(n, dtype=bool)
    chosen[order[: best + 1]] = True
    return chosen | mask


#: Smallest relative noise variance of a shot (grazing, against square-on) the weights allow.
MIN_RELATIVE_VARIANCE = 0.05
#: Standard errors by which a fitted noise model's slope must exceed zero before weighting:
#: weights fitted to noise alone make a fit no better and its standard errors too small.
EVIDENCE = 1.0


def incidence_variance(residuals: np.ndarray, square_on: np.ndarray, mask) -> np.ndarray | None:
    """Each shot's noise variance relative to a square-on shot, from the residuals.

    A range finder's noise lies along its beam (range noise ``s_r``) and across it (angular
    noise ``s_a`` times the range ``R``), so a shot meeting the surface at incidence ``t`` is
    off it by ``s_r^2 cos^2 t + (R s_a)^2 sin^2 t = A + B cos^2 t`` in variance. ``A`` and ``B``
    are the least-squares line of the inliers' squared residuals on ``cos^2 t``; weighting by
    its inverse is feasible generalised least squares (Carroll & Ruppert 1988,
    "Transformation and Weighting in Regression").

    Parameters
    ----------
    residuals : ndarray, shape (n,), metres
    square_on : ndarray, shape (n,)
        ``cos^2`` of each shot's incidence (up to a common factor).
    mask : ndarray, shape (n,), bool
        Inliers.

    Returns
    -------
    ndarray, shape (n,), or None
        ``(A + B c) / (A + B)`` clipped to ``[MIN_RELATIVE_VARIANCE, 1]``; None when ``B`` is
        not ``EVIDENCE`` standard errors above zero (even noise) or the model is degenerate.
    """
    count = int(np.count_nonzero(mask))
    if count < 8:
        return None
    # The 2 x 2 normal equations of the line, solved in closed form.
    c = square_on[mask]
    squares = residuals[mask] ** 2
    sum_c, sum_cc = float(c.sum()), float(c @ c)
    det = count * sum_cc - sum_c * sum_c
    if not det > 0.0:
        return None
    sum_s, sum_cs = float(squares.sum()), float(c @ squares)
    level = (sum_cc * sum_s - sum_c * sum_cs) / det
    slope = (count * sum_cs - sum_c * sum_s) / det
    spread = squares - (level + slope * c)
    slope_var = float(spread @ spread) / max(count - 2, 1) * (count / det)
    top = level + slope
    if not (np.isfinite(top) and top > 0 and slope > EVIDENCE * np.sqrt(max(slope_var, 0.0))):
        return None
    return np.clip((level + slope * square_on) / top, MIN_RELATIVE_VARIANCE, 1.0)


#: Most points a batch of random-sample starts is scored on: a dense cloud is subsampled for
#: that (the scores are starts x points matrices), then the chosen start is refined on all.
SCORED_POINTS = 2000


def random_subset(values: np.ndarray, most: int, rng) -> np.ndarray:
    """``values`` (rows of an array) as they are when at most ``most``, else ``most`` of them
    drawn at random without replacement, in their original order."""
    if len(values) <= most:
        return values
    return values[np.sort(rng.choice(len(values), most, replace=False))]


def scoring_subset(points: np.ndarray, keep: int, rng) -> tuple[np.ndarray, int]:
    """The points (n, 3) metres to score random-sample starts on, and the trimmed count for
    them: all of them up to ``SCORED_POINTS``, else that many at random with ``keep`` scaled."""
    n = len(points)
    if n <= SCORED_POINTS:
        return points, keep
    return random_subset(points, SCORED_POINTS, rng), max(1, math.ceil(keep * SCORED_POINTS / n))


def median_spacing(points: np.ndarray) -> float:
    """Median nearest-neighbour distance of points (n, 3), metres."""
    if len(points) < 2:
        return 0.0
    if len(points) <= 600:
        squares = np.einsum("ij,ij->i", points, points)
        dist = squares[:, None] + squares[None, :] - 2.0 * (points @ points.T)
        np.fill_diagonal(dist, np.inf)
        return float(np.sqrt(max(quick_median(dist.min(axis=1)), 0.0)))
    from scipy.spatial import cKDTree

    distance, _ = cKDTree(points).query(points, k=2)
    return float(np.median(distance[:, 1]))


def quick_median(values: np.ndarray) -> float:
    """The median of a 1-D array without NaNs, as :func:`numpy.median` gives it (the middle
    value, or half the sum of the two middle ones) without its overhead."""
    size = values.size
    half = size // 2
    if size % 2:
        return float(np.partition(values, half)[half])
    part = np.partition(values, (half - 1, half))
    return float(0.5 * (part[half - 1] + part[half]))


def _likeliest_refit(model, state, points, mask, extent, floor, iterations):
    """Least squares on the 3-sigma inliers, on the likeliest nested set, and on every point;
    the refit with the best :func:`mixture_score` wins.

    A robust start on 20-30 points can settle on a subset that a five-parameter surface fits
    too well (a few tenths of a millimetre), so that good shots look like outliers; refitted
    with them, the whole set explains the data better. Returns (state, residuals, jacobian,
    mask).
    """
    residuals = model.residuals(state, points)
    masks = [mask, _best_inlier_set(residuals, mask, extent, floor), np.ones_like(mask)]
    best = None
    for index, candidate in enumerate(masks):
        if index and any(np.array_equal(candidate, other) for other in masks[:index]):
            continue
        weights = candidate.astype(np.float64)
        fitted = gauss_newton(model, state, points, lambda _r, w=weights: w, iterations, 1e-9)
        score = mixture_score(fitted[1], candidate, extent, floor)
        if np.isfinite(score) and (best is None or score < best[0]):
            best = (score, fitted, candidate)
    if best is None:
        return (state, residuals, model.jacobian(state, points)[1], mask)
    _, (state, residuals, jacobian), chosen = best
    return state, residuals, jacobian, chosen


def robust_geometric_fit(
    points: np.ndarray,
    starts: Sequence[Any],
    model: GeometricModel,
    *,
    kind: str,
    sigma: float | None = None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    start_iterations: int = 3,
    always_refine: int = 2,
    max_starts: int = 3,
    max_iterations: int = 50,
    start_costs: Sequence[float] | None = None,
) -> RobustFit:
    """Robust start selection, then least squares on the inliers (see the module docstring).

    The first start and the ``always_refine - 1`` others with the smallest least-trimmed-squares
    cost are refined (``start_iterations`` concentration steps each); further starts, in
    increasing order of that cost, only while it is below the best refined one, at most
    ``max_starts`` in all. The refined candidates are compared by their MSAC cost
    (Torr & Zisserman 2000: ``sum min(r^2, (c s)^2)`` with ``c = outlier_cutoff_sigma`` and
    ``s`` the smallest robust scale among them, or the sensor sigma if larger), which, unlike
    the trimmed cost, does not let a subset of the points win by fitting a few points less.

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    starts : sequence
        Initial model states (at least one); the first is the most trusted.
    model : GeometricModel
    kind : str
        Named in errors.
    sigma : float or None, metres
        Sensor range sigma: the inlier threshold is ``outlier_cutoff_sigma * sigma`` when given,
        else ``outlier_cutoff_sigma`` times :func:`residual_scale`.
    tolerances : Tolerances
    start_iterations : int
    always_refine : int
    max_starts : int
    max_iterations : int
    start_costs : sequence of float, optional
        Each start's least-trimmed-squares cost over ``keep_count(n)`` points, when the caller
        has it already (saves evaluating every start).

    Returns
    -------
    RobustFit

    Raises
    ------
    FitError
        No start gives finite residuals, or more than ``tolerances.max_outlier_fraction`` of
        the points are outliers to the best fit.
    """
    n = len(points)
    keep = keep_count(n, tolerances)
    floor = float(tolerances.sigma_floor)

    def trimmed(residuals):
        # A concentration step (Rousseeuw & Van Driessen 2006): least squares on the ``keep``
        # points closest to the current surface.
        weights = np.zeros(residuals.size)
        weights[np.argpartition(np.abs(residuals), keep - 1)[:keep]] = 1.0
        return weights

    ranked = []
    for order, start in enumerate(starts):
        if start_costs is None:
            cost = trimmed_cost(model.residuals(start, points), keep)
        else:
            cost = float(start_costs[order])
        if np.isfinite(cost):
            ranked.append((0.0 if order == 0 else cost, order, start))
    if not ranked:
        raise FitError(f"No {kind} fits these points; check that they lie on one {kind}.")
    ranked.sort(key=lambda item: (item[0], item[1]))
    refined = []
    bound = np.inf
    for cost, _, start in ranked:
        if len(refined) >= max_starts or (len(refined) >= always_refine and cost >= bound):
            break
        state, residuals, jacobian = gauss_newton(
            model, start, points, trimmed, start_iterations, 0.0
        )
        if not np.all(np.isfinite(residuals)):
            continue
        bound = min(bound, trimmed_cost(residuals, keep))
        refined.append((state, residuals, jacobian))
    if not refined:
        raise FitError(f"No {kind} fits these points; check that they lie on one {kind}.")
    reference = min(robust_scale(item[1], floor) for item in refined)
    if sigma is not None:
        reference = max(reference, float(sigma))
    cap = (tolerances.outlier_cutoff_sigma * reference) ** 2
    scores = [float(np.minimum(item[1] * item[1], cap).sum()) for item in refined]
    state, residuals, jacobian = refined[int(np.argmin(scores))]
    # Inliers, then plain least squares on them until the inlier set is stable; without a
    # sensor sigma, a larger inlier set that the data support better is taken once.
    mask = None
    rescued = sigma is not None
    for _ in range(8):
        if sigma is not None:
            scale = float(sigma)
        else:
            scale = residual_scale(residuals, floor, model.n_params)
        new_mask = np.abs(residuals) <= tolerances.outlier_cutoff_sigma * scale
        if sigma is None and few_residual_dof(n, model.n_params, tolerances):
            # Too few points for a noise level of their own: a 3-sigma test on it would throw
            # out good shots (and leave an exact fit claiming 0.1 mm).
            new_mask = np.ones(n, dtype=bool)
        if not rescued and not new_mask.all():
            rescued = True
            extent = float(np.linalg.norm(np.ptp(points, axis=0)))
            state, residuals, jacobian, new_mask = _likeliest_refit(
                model, state, points, new_mask, extent, floor, max_iterations
            )
        elif mask is not None and np.array_equal(new_mask, mask):
            break
        mask = new_mask
        kept = int(np.count_nonzero(mask))
        if n - kept > tolerances.max_outlier_fraction * n or kept < model.n_params:
            raise FitError(
                f"{n - kept} of {n} points are outliers to the best {kind} (more than "
                f"{tolerances.max_outlier_fraction:.0%}, or fewer than {model.n_params} left); "
                f"check that the points are one {kind}."
            )
        weights = mask.astype(np.float64)
        state, residuals, jacobian = gauss_newton(
            model,
            state,
            points,
            lambda _r, w=weights: w,
            max_iterations,
            1e-9,
            (residuals, jacobian),
        )
    return RobustFit(state, residuals, mask, jacobian[mask], scale)


def settled_fit(
    points: np.ndarray,
    state,
    model: GeometricModel,
    *,
    kind: str,
    sigma: float | None,
    tolerances: Tolerances,
) -> RobustFit | None:
    """One start settled without concentration steps: least squares on its inliers until they
    are stable (:func:`robust_geometric_fit` with that start alone), or None when it fails (too
    many outliers, no finite residuals). Used to compare starts from other basins."""
    try:
        return robust_geometric_fit(
            points,
            [state],
            model,
            kind=kind,
            sigma=sigma,
            tolerances=tolerances,
            start_iterations=0,
            always_refine=1,
            max_starts=1,
        )
    except FitError:
        return None
