"""Shared numerics for the primitive fits: validation, frames, robust scales, normals, noise.

Everything here is a pure numpy function on float64 arrays in metres. The robust least-squares
scheme the fits share is in :mod:`asbuilt.fit._robust`.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import chdtri

from asbuilt.errors import FitError
from asbuilt.fit._mixture import mixture_score
from asbuilt.fit._small_linalg import eigh, eigvalsh, inv, svd
from asbuilt.scan.model import kind_phrase
from asbuilt.tolerances import MIN_POINTS, Tolerances

__all__ = [
    "FreshGenerator",
    "fit_cutoff",
    "radius_text",
    "extent_of",
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
    "noise_level",
    "covariance_from_jacobian",
    "stderr_of",
    "mixture_score",
    "incidence_variance",
    "MIN_RELATIVE_VARIANCE",
    "EVIDENCE",
    "local_normals",
    "row_norms",
    "within_noise",
    "arc_coverage_deg",
    "TUKEY_C",
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
    if not np.isfinite(array).all():
        raise FitError("The points must be finite (a coordinate is NaN or infinite).")
    need = MIN_POINTS[kind]
    if len(array) < need:
        what = kind_phrase(kind)
        raise FitError(
            f"{what[0].upper()}{what[1:]} needs at least {need} points, got {len(array)}; "
            "measure more points."
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
    _, singular, vt = svd(centred)
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


def extent_of(points: np.ndarray, axis: np.ndarray | None = None) -> float:
    """Twice the largest distance of ``points`` (m, 3) metres from their centroid, metres: the
    span a fit's radius is weighed against to call it nearly a plane over them.

    With a cylinder's unit ``axis`` (3,), the distances are measured across it (the points
    projected on the plane normal to the axis): a cylinder curves only across its axis, so a
    strip of floor many metres long but a metre wide is a nearly flat patch of a 40 m
    cylinder laid along it, however long the strip.
    """
    # points.mean(axis=0), np.outer and np.max's arithmetic, without their overhead.
    centred = points - points.sum(axis=0) / len(points)
    if axis is not None:
        centred = centred - (centred @ axis)[:, None] * axis
    return 2.0 * float(np.sqrt(np.maximum.reduce(np.einsum("ij,ij->i", centred, centred))))


def radius_text(radius: float) -> str:
    """A fitted radius (metres) for a message: millimetres under a metre, else metres (a
    plane fitted as a cylinder can be kilometres wide)."""
    return f"{radius * 1000:.0f} mm" if radius < 1.0 else f"{radius:.4g} m"


def row_norms(vectors: np.ndarray) -> np.ndarray:
    """Lengths (k,) of the rows of ``vectors`` (k, d): ``np.linalg.norm(vectors, axis=1)``'s
    own arithmetic (the sum of squares along the row, then its root), without its Python
    overhead (the cuboid and cylinder searches call this thousands of times a fit)."""
    return np.sqrt(np.add.reduce(vectors * vectors, axis=1))


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
    magnitudes = np.abs(residuals)  # a fresh array, partitioned in place
    half = size // 2
    if size % 2:
        magnitudes.partition(half)
        median = float(magnitudes[half])
    else:
        magnitudes.partition((half - 1, half))
        median = 0.5 * float(magnitudes[half - 1] + magnitudes[half])
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


def fit_cutoff(result, sigma: float | None, tolerances: Tolerances) -> float:
    """A finished fit's inlier cutoff, metres: ``tolerances.outlier_cutoff_sigma`` noise
    levels, the noise the sensor's ``sigma`` (metres) when given, else the fit's own
    ``result.sigma``, floored at ``tolerances.sigma_floor``."""
    noise = float(sigma) if sigma is not None else float(result.sigma)
    return float(tolerances.outlier_cutoff_sigma) * max(noise, float(tolerances.sigma_floor))


def within_noise(residuals: np.ndarray, sigma: float, n_params: int, tail: float) -> bool:
    """Whether residuals (m,) metres pass the chi-square test at noise ``sigma`` (metres) with
    ``m - n_params`` degrees of freedom and upper tail probability ``tail``: a fit in a wrong
    basin that still keeps its shots within the inlier threshold fits them worse than the
    noise allows. False without a degree of freedom."""
    dof = residuals.size - n_params
    return dof > 0 and float(residuals @ residuals) <= sigma * sigma * chdtri(dof, tail)


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


#: Least ratio of J's smallest singular value to its largest for ``(J^T J)^-1`` to be taken
#: directly: the normal matrix's condition number is the square of J's, and inverting it loses
#: that many digits (1e-7: condition 1e14, a few correct digits left of 16). A well-posed fit is
#: at 1e-1 to 1e-2; a sphere or cylinder fitted to a nearly flat patch (its radius and the
#: centre's depth move together) at 1e-8 to 1e-15, where the inverse is rounding noise.
_WELL_POSED = 1e-7
#: Singular values of J below this fraction of the largest are rounding, not information: the
#: direction they belong to gets the variance of this floor (undetermined, not zero).
_SINGULAR_FLOOR = 1e-15


def covariance_from_jacobian(jacobian: np.ndarray, sigma: float) -> np.ndarray:
    """Gauss-Newton covariance ``sigma^2 (J^T J)^-1``.

    When ``J^T J`` is singular or too ill-conditioned to invert (its condition number is the
    square of J's), the covariance comes from the SVD of J itself, ``V diag(s^-2) V^T``
    (Golub and Van Loan, Matrix Computations, 5.3), so a direction the points barely determine
    keeps its large variance. A pseudo-inverse would give such a direction zero variance: a
    13 km sphere fitted to a flat wall reported its radius to +-0.2 mm.

    Parameters
    ----------
    jacobian : ndarray, shape (m, p)
        Derivatives of the inlier residuals (metres) by the parameters.
    sigma : float, metres

    Returns
    -------
    ndarray, shape (p, p)
        Finite; a direction J does not determine at all gets the variance of a singular value
        ``_SINGULAR_FLOOR`` times J's largest (far beyond any size a fit reports).
    """
    p = jacobian.shape[1]
    normal = jacobian.T @ jacobian
    # J's singular values squared, to the rounding of the largest (ample for the 1e-14 test).
    squares = eigvalsh(normal)
    if jacobian.shape[0] >= p and squares[0] > _WELL_POSED**2 * squares[-1]:
        return sigma * sigma * inv(normal)
    _, values, rows = svd(jacobian, full_matrices=True)
    largest = values[0] if values.size and values[0] > 0 else 1.0
    # Rows of V beyond the singular values (fewer residuals than parameters) are undetermined.
    values = np.concatenate([values, np.zeros(p - values.size)])
    values = np.maximum(values, _SINGULAR_FLOOR * largest)
    return sigma * sigma * ((rows.T / values**2) @ rows)


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
        index = dist.argpartition(k - 1, axis=1)[:, :k]
    else:
        from scipy.spatial import cKDTree

        _, index = cKDTree(points).query(points, k=k)
    hood = points[index]
    # The neighbourhoods' means as numpy's mean computes them (sum, then divide by the count),
    # without its per-call overhead.
    hood -= hood.sum(axis=1, keepdims=True) / k
    scatter = hood.transpose(0, 2, 1) @ hood
    values, vectors = eigh(scatter)
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
    ordered = np.mod(angles, 2 * np.pi)
    ordered.sort()  # np.sort's order, in place on the fresh array
    closed = np.concatenate([ordered, ordered[:1] + 2 * np.pi])
    gaps = closed[1:] - closed[:-1]  # np.diff's differences, without its overhead
    return float(np.degrees(2 * np.pi - gaps.max()))


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


def column_medians(points: np.ndarray) -> np.ndarray:
    """The median of each column of ``points`` (n, d), shape (d,): ``np.median(points,
    axis=0)`` (the middle row of the sorted columns, or half the sum of the two middle ones)
    without its overhead, which is most of its cost on a few dozen points."""
    size = len(points)
    half = size // 2
    part = points.copy()
    if size % 2:
        part.partition(half, axis=0)
        return part[half]
    part.partition((half - 1, half), axis=0)
    return 0.5 * (part[half - 1] + part[half])


def diagonal_extent(points: np.ndarray) -> float:
    """The diagonal of the box around ``points`` (n, 3) metres, without strays
    (:func:`_strays`): ``np.linalg.norm(np.ptp(points, axis=0))``'s arithmetic, without its
    overhead.

    It is the range over which the mixture scores spread their uniform outliers
    (:func:`asbuilt.fit._mixture.mixture_score`). One stray return kilometres off (a floor hit
    7.4 km away among a tank's shots and the wall's behind it) made that range 370 times the
    scene's, each outlier 12 units of ``-2 ln L`` dearer, and the likeliest inlier set took in
    the wall 3 m behind the tank: the noise came out at 2.7 m and the refit at it lost the tank.
    """
    span = points.max(axis=0) - points.min(axis=0)
    extent = float(np.sqrt(span.dot(span)))
    if len(points) < 4:
        return extent
    kept = _strays(points)
    if kept is None:
        return extent
    rest = points[kept]
    span = rest.max(axis=0) - rest.min(axis=0)
    return float(np.sqrt(span.dot(span)))


def _strays(points: np.ndarray):
    """The mask (n,) bool of ``points`` (n, 3) metres without their strays, or None when there
    are none: a stray is a point farther from every other point than the diagonal of the box
    around those others (a lone return far past a scene that it alone makes wider). Only a point
    on a side of the box can be one; they are taken out one at a time, farthest first, while
    any is left (at most a quarter of the points)."""
    n = len(points)
    # Most point sets have no stray, told at once: the box around the others spans at least the
    # whole box's diagonal less the point's distance to its nearest neighbour, so a point whose
    # nearest neighbour lies within half that diagonal (0.49 of it, against rounding) is no
    # stray. Every fit that scores a mixture asks (about 100 us for the loop below on 40 points,
    # 4% of a cylinder fit with outliers).
    sides = np.concatenate([points.argmin(axis=0), points.argmax(axis=0)])
    offsets = points[None, :, :] - points[sides][:, None, :]  # (6, n, 3)
    gaps = np.einsum("kij,kij->ki", offsets, offsets)
    gaps[np.arange(len(sides)), sides] = np.inf
    span = points.max(axis=0) - points.min(axis=0)
    if float(gaps.min(axis=1).max()) <= (0.49 * 0.49) * float(span.dot(span)):
        return None
    kept = np.ones(n, dtype=bool)
    for _ in range(n // 4):
        rest = points[kept]
        index = np.flatnonzero(kept)
        sides = np.unique(np.concatenate([rest.argmin(axis=0), rest.argmax(axis=0)]))
        best, gap = -1, 0.0
        for side in sides:
            others = np.delete(rest, side, axis=0)
            offsets = others - rest[side]
            nearest = float(np.sqrt(np.einsum("ij,ij->i", offsets, offsets).min()))
            span = others.max(axis=0) - others.min(axis=0)
            if nearest > float(np.sqrt(span.dot(span))) and nearest > gap:
                best, gap = int(index[side]), nearest
        if best < 0:
            break
        kept[best] = False
    return None if kept.all() else kept


def quick_median(values: np.ndarray) -> float:
    """The median of a 1-D array without NaNs, as :func:`numpy.median` gives it (the middle
    value, or half the sum of the two middle ones) without its overhead."""
    size = values.size
    half = size // 2
    part = values.copy()  # partitioned in place: np.partition's copy without its dispatch
    if size % 2:
        part.partition(half)
        return float(part[half])
    part.partition((half - 1, half))
    return float(0.5 * (part[half - 1] + part[half]))


#: The integer draws :class:`FreshGenerator` remembers, by seed and the draws before each.
_DRAWS: dict = {}


class FreshGenerator:
    """``np.random.default_rng(seed)`` for code that only draws integers from it
    (``integers(low, high, size)``, positionally): the same arrays in the same order, each
    remembered by the seed and the draws before it. The cylinder fit seeds fresh generators
    with the shot count several times a fit (its starts, the faces it looks for); seeding one
    costs more than the draws."""

    __slots__ = ("_seed", "_history")

    def __init__(self, seed: int):
        self._seed = int(seed)
        self._history: tuple = ()

    def integers(self, low, high=None, size=None) -> np.ndarray:
        """:meth:`numpy.random.Generator.integers` (int64), a fresh copy each call."""
        draw = (low, high, size)
        key = (self._seed, self._history, draw)
        found = _DRAWS.get(key)
        if found is None:
            rng = np.random.default_rng(self._seed)
            for earlier in self._history:
                rng.integers(*earlier)
            found = rng.integers(*draw)
            if len(_DRAWS) >= 64:
                _DRAWS.clear()
            _DRAWS[key] = found
        self._history = (*self._history, draw)
        return found.copy()
