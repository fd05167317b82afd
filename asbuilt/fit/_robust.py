"""The robust geometric least-squares scheme the primitive fits share.

The fits in :mod:`asbuilt.fit.plane`, :mod:`.sphere` and :mod:`.cylinder` give a
:class:`GeometricModel` (residuals, Jacobian, update) to :func:`robust_geometric_fit`:

1. the starts are ranked by their least-trimmed-squares cost (Rousseeuw 1984; the sum of the
   ``h`` smallest squared residuals, ``h`` = the points less the design contamination); the
   first start and the best few are refined by concentration steps (Rousseeuw & Van Driessen
   2006: Gauss-Newton on the ``h`` points closest to the current surface) and compared by their
   MSAC cost (Torr & Zisserman 2000);
2. points within ``outlier_cutoff_sigma`` noise scales of the winner are the inliers (the sensor
   sigma, else :func:`~asbuilt.fit._common.residual_scale`), and the final estimate is plain
   geometric least squares on the inliers only (so clean data gets the efficient estimate),
   repeated until the inlier set is stable; without a sensor sigma, the likeliest of a few
   nested inlier sets is taken once (:func:`~asbuilt.fit._mixture.mixture_score`), so that a
   small-sample scale does not reject good shots.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg.lapack import dposv as _dposv

from asbuilt.errors import FitError
from asbuilt.fit._common import diagonal_extent, few_residual_dof, residual_scale, robust_scale
from asbuilt.fit._mixture import mixture_score
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = [
    "DESIGN_CONTAMINATION",
    "GeometricModel",
    "RobustFit",
    "best_inlier_set",
    "gauss_newton",
    "keep_count",
    "likelier",
    "refit_on",
    "robust_geometric_fit",
    "settled_fit",
    "trimmed_cost",
]


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
        # ndarray.dot of two vectors: the same BLAS dot product as ``@``, at half its call
        # overhead (numpy's per-call cost, not the arithmetic, dominates on 40 rows).
        cost = float(weighted_residuals.dot(residuals))
        if cost <= 0.0:
            break
        normal = (jacobian.T * weights) @ jacobian
        gradient = jacobian.T @ weighted_residuals
        delta = _newton_step(normal, gradient)
        if tolerance > 0.0 and -float(gradient.dot(delta)) <= tolerance * cost:
            break
        accepted = False
        for _ in range(8):
            trial = model.update(state, delta, points, weights)
            trial_residuals, trial_jacobian = model.jacobian(trial, points)
            trial_cost = float(weights.dot(trial_residuals * trial_residuals))
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


def best_inlier_set(residuals, mask, extent, floor):
    """The likeliest inlier set among those nested by |residual|, at least as large as ``mask``.

    Each candidate keeps the ``m`` points of smallest |r|, scored by :func:`mixture_score`
    (lowest wins). A 3-sigma test
    on a small-sample scale can reject a whole group of good but noisier shots (square-on shots
    among grazing ones); taken together they raise sigma enough to be explained, which a
    one-at-a-time test never sees. Background shots, centimetres to metres off, never pay.
    """
    # np.argsort, np.cumsum and np.argmin as methods, without their wrappers' overhead.
    order = np.abs(residuals).argsort()
    squares = (residuals[order] ** 2).cumsum()
    n = residuals.size
    counts = np.arange(1, n + 1)
    variance = np.maximum(squares / counts, floor * floor)
    score = counts * (1.0 + np.log(2.0 * np.pi * variance))
    score += (n - counts) * 2.0 * np.log(max(extent, floor))
    first = int(np.count_nonzero(mask)) - 1
    best = first + int(score[first:].argmin())
    chosen = np.zeros(n, dtype=bool)
    chosen[order[: best + 1]] = True
    return chosen | mask


def _likeliest_refit(model, state, points, mask, extent, floor, iterations):
    """Least squares on the 3-sigma inliers, on the likeliest nested set, and on every point;
    the refit with the best :func:`mixture_score` wins.

    A robust start on 20-30 points can settle on a subset that a five-parameter surface fits
    too well (a few tenths of a millimetre), so that good shots look like outliers; refitted
    with them, the whole set explains the data better. Returns (state, residuals, jacobian,
    mask).
    """
    residuals = model.residuals(state, points)
    masks = [mask, best_inlier_set(residuals, mask, extent, floor), np.ones_like(mask)]
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
    memo: dict | None = None,
    first_current: tuple[np.ndarray, np.ndarray] | None = None,
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
    memo : dict, optional
        Kept by a caller that calls again on the same points with the same settings and some of
        the same start objects (the cylinder fit's robust choice, then again with polished
        starts added): a start already refined, and the least squares from a refined candidate
        already chosen, are taken from it instead of computed again (the same result).
    first_current : (ndarray, ndarray), optional
        ``model.jacobian(starts[0], points)`` when the caller has it already (a start it has
        just settled itself).

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
        weights[np.abs(residuals).argpartition(keep - 1)[:keep]] = 1.0
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
    for index, (cost, order, start) in enumerate(ranked):
        if len(refined) >= max_starts or (len(refined) >= always_refine and cost >= bound):
            break
        if memo is not None and id(start) in memo:
            # Kept with the start itself, so that its id is not reused while the memo lives.
            candidate = memo[id(start)][1]
        else:
            current = first_current if order == 0 else None
            candidate = gauss_newton(model, start, points, trimmed, start_iterations, 0.0, current)
            if memo is not None:
                memo[id(start)] = (start, candidate)
        state, residuals, jacobian = candidate
        if not np.isfinite(residuals).all():
            continue
        refined.append(candidate)
        # The bound is read only before another start is refined (none after the last one,
        # as in every one-start settle).
        if len(refined) < max_starts and index + 1 < len(ranked):
            bound = min(bound, trimmed_cost(residuals, keep))
    if not refined:
        raise FitError(f"No {kind} fits these points; check that they lie on one {kind}.")
    chosen = refined[0]
    if len(refined) > 1:
        reference = min(robust_scale(item[1], floor) for item in refined)
        if sigma is not None:
            reference = max(reference, float(sigma))
        cap = (tolerances.outlier_cutoff_sigma * reference) ** 2
        scores = [float(np.minimum(item[1] * item[1], cap).sum()) for item in refined]
        chosen = refined[int(np.argmin(scores))]
    if memo is not None and ("chosen", id(chosen)) in memo:
        return memo["chosen", id(chosen)][1]
    state, residuals, jacobian = chosen
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
            extent = diagonal_extent(points)
            state, residuals, jacobian, new_mask = _likeliest_refit(
                model, state, points, new_mask, extent, floor, max_iterations
            )
        elif mask is not None and (new_mask == mask).all():  # np.array_equal, same shapes
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
    fit = RobustFit(state, residuals, mask, jacobian[mask], scale)
    if memo is not None:
        memo["chosen", id(chosen)] = (chosen, fit)
    return fit


def settled_fit(
    points: np.ndarray,
    state,
    model: GeometricModel,
    *,
    kind: str,
    sigma: float | None,
    tolerances: Tolerances,
    current: tuple[np.ndarray, np.ndarray] | None = None,
) -> RobustFit | None:
    """One start settled without concentration steps: least squares on its inliers until they
    are stable (:func:`robust_geometric_fit` with that start alone), or None when it fails (too
    many outliers, no finite residuals). Used to compare starts from other basins. ``current``:
    ``model.jacobian(state, points)`` when the caller has it already."""
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
            first_current=current,
        )
    except FitError:
        return None


def likelier(first, second, points, tolerances: Tolerances) -> bool:
    """Whether robust fit ``first`` explains the points better than ``second``: mixture
    likelihood of Gaussian inliers (own sigma) and uniform outliers over the points' extent."""
    extent = diagonal_extent(points)
    floor = tolerances.sigma_floor
    one = mixture_score(first.residuals, first.inliers, extent, floor)
    two = mixture_score(second.residuals, second.inliers, extent, floor)
    return one < two


def refit_on(model: GeometricModel, robust: RobustFit, points: np.ndarray, mask) -> RobustFit:
    """Least squares on the points ``mask`` (n,) bool keeps, from ``robust``'s state: the fit
    after shots it had taken as inliers were rejected (a station cannot see them)."""
    weights = mask.astype(np.float64)
    state, residuals, jacobian = gauss_newton(
        model, robust.state, points, lambda _r, w=weights: w, 50, 1e-9
    )
    return RobustFit(state, residuals, mask, jacobian[mask], robust.scale)
