"""Free-space evidence of range shots: a beam reaches its point through empty space.

A range finder's shot is the *first* surface its beam meets. A fitted solid that the beam would
have entered well before the shot's point cannot be the surface the shot hit, however close the
point lies to it: such a point sits on the solid's far side, seen through the solid. On sparse
scans of long thin pipes an orthogonal-distance fit can explain 20 shots better with a thinner,
tilted cylinder that wraps some shots round its far side; the beams give it away. This is the
free-space (visibility) constraint of range-image registration and surface reconstruction
(Curless & Levoy 1996, "A volumetric method for building complex models from range images";
Hoppe et al. 1992 use the same sign convention for the sensor side), used here as a penalty in
the choice between candidate fits.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import diagonal_extent, robust_scale, row_norms, tukey_weights
from asbuilt.fit._mixture import mixing_cost, mixture_score
from asbuilt.fit._robust import GeometricModel, RobustFit, gauss_newton, settled_fit
from asbuilt.tolerances import Tolerances

__all__ = [
    "beam_entries",
    "beyond_first_surface",
    "cylinder_beam_excess",
    "edge_on_degrees",
    "excess_and_beyond",
    "one_side_could_see",
    "reconsidered",
    "visible_score",
]

#: Gauss-Newton steps that bring a seed into its basin (:func:`_settle`); least squares on the
#: inliers converges from there.
SETTLE_ITERATIONS = 10
#: Forward-difference step of the beam excess's Jacobian (radians and metres).
_DIFFERENCE_STEP = 1e-6


def _beam_crossings(axis, center, radius, points: np.ndarray, viewpoint):
    """Where the beams from ``viewpoint`` to ``points`` cross infinite cylinders: ``(lengths,
    a, b, discriminant)``, each beam at range ``t`` along its unit direction lying
    ``a t^2 + b t + c`` (squared distance from the axis less the radius squared) from the
    surface; ``lengths`` (n,) the shots' ranges, metres, the rest (s, n) (shapes and units as
    in :func:`cylinder_beam_excess`)."""
    view = np.asarray(viewpoint, dtype=np.float64)
    # np.atleast_2d and np.atleast_1d's views, without their overhead.
    axes, centers = np.asarray(axis), np.asarray(center)
    if axes.ndim == 1:
        axes = axes[None]
    if centers.ndim == 1:
        centers = centers[None]
    radii = np.asarray(radius, dtype=np.float64).reshape(-1)
    beams = points - view
    lengths = np.sqrt(np.einsum("ij,ij->i", beams, beams))
    directions = beams / np.maximum(lengths, 1e-300)[:, None]
    start = view - centers
    start_across = start - np.einsum("ij,ij->i", start, axes)[:, None] * axes
    # With across = d - (d.a) a and start_across perpendicular to a: |across|^2 = 1 - (d.a)^2
    # and across.start_across = d.start_across.
    along = axes @ directions.T  # (s, n)
    a = 1.0 - along * along
    b = 2.0 * (start_across @ directions.T)
    c = np.einsum("ij,ij->i", start_across, start_across) - radii * radii
    return lengths, a, b, b * b - 4.0 * a * c[:, None]


def cylinder_beam_excess(axis, center, radius, points: np.ndarray, viewpoint) -> np.ndarray:
    """How far each shot's beam ran inside an infinite cylinder before reaching the shot.

    The beam from ``viewpoint`` to a point crosses the cylinder along a chord (if at all). A point
    on the near half of its chord was reachable (excess 0); a point beyond the chord's middle
    lies ``2 (t - t_mid)`` past it, capped at the chord's length (a point on the far side, or
    behind the cylinder, was reached only through the whole chord). Near the silhouette the
    chord is short, so noise on grazing shots costs little.

    Parameters
    ----------
    axis : ndarray, shape (3,) or (s, 3)
        Unit axis (of each of ``s`` cylinders).
    center : ndarray, shape (3,) or (s, 3), metres
        A point on the axis.
    radius : float or ndarray, shape (s,), metres
    points : ndarray, shape (n, 3), metres
    viewpoint : array_like, shape (3,), metres
        Where the shots were taken from.

    Returns
    -------
    ndarray, shape (n,) or (s, n), metres
        Non-negative; 0 where the beam misses the cylinder or the point is on the near half.
    """
    excess = _excess(*_beam_crossings(axis, center, radius, points, viewpoint))
    return excess[0] if np.ndim(axis) == 1 else excess


def _excess(lengths, a, b, discriminant) -> np.ndarray:
    """:func:`cylinder_beam_excess`, shape (s, n) metres, from :func:`_beam_crossings`."""
    excess = np.zeros(a.shape)
    hit = (discriminant > 0.0) & (a > 1e-24)
    if hit.any():
        a_hit = a[hit]
        middle = -b[hit] / (2.0 * a_hit)
        chord = np.sqrt(discriminant[hit]) / a_hit
        reach = lengths[np.nonzero(hit)[1]]  # each hit's own range (rows are cylinders)
        excess[hit] = (2.0 * (reach - middle)).clip(0.0, chord)
    return excess


def beyond_first_surface(axis, center, radius, points: np.ndarray, viewpoint) -> np.ndarray:
    """How far each shot lies beyond the first point of an infinite cylinder its beam met,
    along the beam, metres, shape (n,); negative in front of it.

    A beam that enters the cylinder meets it at its entry point; one that misses it passes
    closest to its surface where it passes closest to its axis, the silhouette. A shot that
    grazed the cylinder and came back from what lies behind it, or a mixed return between the
    two, lies beyond that point (up to the range noise); a shot well in front of it, and off
    the cylinder, hit something else first.

    Parameters
    ----------
    axis : ndarray, shape (3,)
        Unit axis.
    center : ndarray, shape (3,), metres
        A point on the axis.
    radius : float, metres
    points : ndarray, shape (n, 3), metres
    viewpoint : array_like, shape (3,), metres
        Where the shots were taken from.
    """
    return _beyond(*_beam_crossings(axis, center, radius, points, viewpoint))


def excess_and_beyond(axis, center, radius, points: np.ndarray, viewpoint, span=None):
    """:func:`cylinder_beam_excess` and :func:`beyond_first_surface` of one cylinder (``axis``
    (3,), ``center`` (3,) metres, ``radius`` metres), each shape (n,) metres, from one
    computation of where the beams cross it.

    ``span``: ``(low, high)`` metres along ``axis`` from ``center``, where the pipe is known to
    be (a fitted pipe's kept shots), or None for an infinite cylinder. A beam whose crossing of
    the infinite cylinder (its chord through it, or where a beam that misses it passes closest
    to its axis) lies wholly outside the span met no pipe: excess 0 and beyond ``inf``. A
    column's wall shots above its top, or a pipe's past its free end, passed the pipe's end;
    counted against the infinite cylinder they were "seen through" it.
    """
    crossings = _beam_crossings(axis, center, radius, points, viewpoint)
    excess = _excess(*crossings)[0]
    # The chord's terms once, for what lies beyond its entry and for its ends along the axis.
    middle, half_chord = _chord(*crossings[1:])
    entry = middle - half_chord
    beyond = crossings[0] - entry
    if span is not None:
        low, high = _chord_ends(axis, center, points, viewpoint, entry, middle + half_chord)
        missed = (high < span[0]) | (low > span[1])
        excess[missed] = 0.0
        beyond[missed] = np.inf
    return excess, beyond


def beam_entries(axis, center, radius, points: np.ndarray, viewpoint) -> np.ndarray:
    """Where each beam from ``viewpoint`` ((3,) metres) to ``points`` ((n, 3) metres) enters
    one infinite cylinder (``axis`` (3,), ``center`` (3,) metres, ``radius`` metres), or for a
    beam that misses it where it passes nearest its axis: shape (n, 3), metres."""
    view = np.asarray(viewpoint, dtype=np.float64)
    crossings = _beam_crossings(axis, center, radius, points, view)
    middle, half_chord = _chord(*crossings[1:])
    directions = (points - view) / np.maximum(crossings[0], 1e-300)[:, None]
    return view + (middle - half_chord)[:, None] * directions


def _chord_ends(axis, center, points: np.ndarray, viewpoint, near, far):
    """Where each beam from ``viewpoint`` to ``points`` (n, 3) metres crosses one infinite
    cylinder, along ``axis`` from ``center``: ``(low, high)``, each (n,) metres, the ends of its
    chord through the cylinder, or for a beam that misses it the point where it passes closest
    to its axis (low and high the same). ``near`` and ``far`` (n,) metres along each beam: the
    chord's ends, or both that closest point (:func:`excess_and_beyond`)."""
    view = np.asarray(viewpoint, dtype=np.float64)
    axis = np.asarray(axis, dtype=np.float64)
    beams = points - view
    directions = beams / np.maximum(row_norms(beams), 1e-300)[:, None]
    start = float((view - np.asarray(center, dtype=np.float64)) @ axis)
    slope = directions @ axis  # along the axis per metre of beam
    one = start + near * slope
    other = start + far * slope
    return np.minimum(one, other), np.maximum(one, other)


def _chord(a, b, discriminant) -> tuple[np.ndarray, np.ndarray]:
    """Where each beam passes nearest one cylinder's axis and half its chord through the
    cylinder (0 for a beam that misses it), each (n,) metres along the beam, from
    :func:`_beam_crossings`' ``a``, ``b``, ``discriminant`` (1, n)."""
    twice = 2.0 * np.maximum(a[0], 1e-24)  # beams along the axis: never nearer it, nor through it
    return -b[0] / twice, np.sqrt(np.maximum(discriminant[0], 0.0)) / twice


def _beyond(lengths, a, b, discriminant) -> np.ndarray:
    """:func:`beyond_first_surface`, shape (n,) metres, from :func:`_beam_crossings` of one
    cylinder."""
    # Nearest the axis at -b / 2a; a beam passing within the radius enters half a chord earlier.
    middle, half_chord = _chord(a, b, discriminant)
    return lengths - (middle - half_chord)


def edge_on_degrees(axis, center, points: np.ndarray, viewpoint) -> np.ndarray:
    """Incidence of each shot's beam on a cylinder, measured across the axis, in degrees.

    The angle between the cylinder's outward normal at the point and the beam's part across the
    axis: 0 for a shot square on the pipe's front, 90 for one grazing its silhouette. Measured
    across the axis, so a pipe seen obliquely along its length keeps its square-on front shots
    near 0 (the full 3-D incidence of every shot would approach 90 degrees there).

    Parameters
    ----------
    axis : ndarray, shape (3,)
        Unit axis.
    center : ndarray, shape (3,), metres
        A point on the axis.
    points : ndarray, shape (n, 3), metres
    viewpoint : array_like, shape (3,), metres

    Returns
    -------
    ndarray, shape (n,), degrees
        In [0, 90]; NaN for a shot on the axis or whose beam runs within about 6 degrees of the
        axis (seen end-on, its angle across the axis is not defined).
    """
    axis = np.asarray(axis, dtype=np.float64)
    rel = points - center
    radial = rel - (rel @ axis)[:, None] * axis  # np.outer, without its wrapper
    beams = points - np.asarray(viewpoint, dtype=np.float64)
    across = beams - (beams @ axis)[:, None] * axis
    radial_length = np.sqrt(np.einsum("ij,ij->i", radial, radial))
    across_length = np.sqrt(np.einsum("ij,ij->i", across, across))
    beam_length = np.sqrt(np.einsum("ij,ij->i", beams, beams))
    with np.errstate(divide="ignore", invalid="ignore"):
        cosine = np.abs(np.einsum("ij,ij->i", radial, across)) / (radial_length * across_length)
        # cosine.clip(0.0, 1.0)'s values (NaN kept), without the method's Python overhead.
        angle = np.degrees(np.arccos(np.minimum(np.maximum(cosine, 0.0), 1.0)))
    angle[(across_length <= 0.1 * beam_length) | (radial_length <= 0.0)] = np.nan
    return angle


def one_side_could_see(
    angles: np.ndarray, seen_fraction: float, edge_on_deg: float, steps: int = 180
) -> bool:
    """Whether one distant station could have seen shots at these angles about a cylinder's
    axis: from some direction, at least ``seen_fraction`` of them lie on the facing half, and
    the median of their incidences there is below ``edge_on_deg``.

    A pipe scanned from one unknown station passes; a "pipe" fitted through a thin pipe's front
    shots and the wall shots behind it (two clusters on opposite sides) does not: from any
    direction either half its shots face away, or all are seen edge-on.

    Parameters
    ----------
    angles : ndarray, shape (m,), radians
        Each shot's angle about the axis, from any fixed direction across it.
    seen_fraction : float
    edge_on_deg : float, degrees
    steps : int
        Directions tried, evenly round the axis.
    """
    if angles.size == 0:
        return False
    directions = np.linspace(0.0, 2.0 * np.pi, steps, endpoint=False)
    cosines = np.cos(angles[None, :] - directions[:, None])  # (steps, m)
    facing = cosines > 0.0
    limit = np.cos(np.radians(edge_on_deg))
    for row, front in zip(cosines, facing):
        if np.mean(front) >= seen_fraction and np.median(row[front]) > limit:
            return True
    return False


def visible_score(residuals: np.ndarray, excess: np.ndarray, scale: float, cutoff: float) -> float:
    """MSAC cost (Torr & Zisserman 2000) of a fit with free-space violations counted as error.

    Each point costs ``min((r^2 + e^2) / s^2, cutoff^2)``: ``r`` its orthogonal residual, ``e`` its
    beam excess (:func:`cylinder_beam_excess`), ``s`` the noise level. With ``e = 0`` this is the
    truncated-quadratic likelihood of Gaussian inliers among uniform outliers, so a fit that
    explains the shots only by placing some behind its own surface pays for them as outliers.

    Parameters
    ----------
    residuals : ndarray, shape (n,), metres
    excess : ndarray, shape (n,), metres
    scale : float, metres
    cutoff : float
        In units of ``scale``.

    Returns
    -------
    float
        Lower is better.
    """
    squares = (residuals * residuals + excess * excess) / (scale * scale)
    return float(np.minimum(squares, cutoff * cutoff).sum())


def _with_beams(model: GeometricModel, excess) -> GeometricModel:
    """``model`` with each point's beam excess appended to its residuals: ``(2n,)`` metres.

    The excess is piecewise smooth; its Jacobian is taken by forward differences (all the
    perturbed states in one ``excess`` call).
    """

    def residuals(state, points):
        return np.concatenate([model.residuals(state, points), excess([state], points)[0]])

    def jacobian(state, points):
        orthogonal, orthogonal_jacobian = model.jacobian(state, points)
        uniform = np.ones(len(points))
        moved = [state] + [
            model.update(state, step, points, uniform)
            for step in _DIFFERENCE_STEP * np.eye(model.n_params)
        ]
        beyond, *shifted = excess(moved, points)
        beyond_jacobian = (np.array(shifted).T - beyond[:, None]) / _DIFFERENCE_STEP
        return np.concatenate([orthogonal, beyond]), np.vstack(
            [orthogonal_jacobian, beyond_jacobian]
        )

    def update(state, delta, points, weights):
        return model.update(state, delta, points, weights[: len(points)])

    return GeometricModel(residuals, jacobian, update, model.n_params)


def _settle(model: GeometricModel, seed, points: np.ndarray, excess, scale: float):
    """Bring a seed into its basin of the free-space-aware cost: Gauss-Newton on each point's
    orthogonal residual and beam excess together (:func:`_with_beams`), Tukey-weighted (Beaton &
    Tukey 1974) on their combined size at the larger of the noise level and its MAD scale
    (re-estimated each step, so that a seed centimetres off still sees its inliers).

    Without the excess in the cost a seed near the true pipe can slide into a thinner cylinder
    that hides shots behind itself, and no later choice could bring it back.
    """
    n = len(points)

    def weigh(stacked):
        size = np.hypot(stacked[:n], stacked[n:])
        weights = tukey_weights(size, max(scale, robust_scale(size, scale)))
        return np.concatenate([weights, weights])

    state, _, _ = gauss_newton(
        _with_beams(model, excess), seed, points, weigh, SETTLE_ITERATIONS, 1e-6
    )
    return state


def reconsidered(
    robust: RobustFit | None,
    points: np.ndarray,
    seeds: Sequence[Any],
    model: GeometricModel,
    excess: Callable[[Any, np.ndarray], np.ndarray] | None,
    *,
    kind: str,
    sigma: float | None,
    tolerances: Tolerances,
    thorough: bool = True,
) -> RobustFit:
    """The robust fit, or a fit settled from another seed that the shots' beams (or, without a
    viewpoint, the likelihood) favour.

    A robust fit's choice among starts is made on trimmed subsets, before the least-squares
    refinement; on 20 shots a five-parameter surface can fit a subset so closely that the wrong
    basin wins. Here every seed is settled the same way (:func:`_settle` on residuals and beam
    excess together, then least squares on the 3-sigma inliers as in
    :func:`asbuilt.fit._robust.robust_geometric_fit`), and the settled fits, the robust one among
    them, are compared by :func:`visible_score`: their MSAC cost with each point's beam excess
    added to its residual.

    Parameters
    ----------
    robust : RobustFit or None
        The fit so far; None when the robust choice failed (then ``sigma`` is required).
    points : ndarray, shape (n, 3), metres
    seeds : sequence
        Model states to settle.
    model : GeometricModel
    excess : callable or None
        ``excess(states, points) -> (s, n)`` metres, the beam excess of each point for each of a
        list of states (one call for the several states a differenced Jacobian needs). None
        when the viewpoint is unknown: then the settled fits are compared by their likelihood
        with each fit's own noise level (Gaussian inliers, uniform outliers over the points'
        extent, in their mixing proportions: :func:`~asbuilt.fit._mixture.mixture_score` plus
        :func:`~asbuilt.fit._mixture.mixing_cost`). The MSAC cost at the robust fit's scale
        cannot tell a fit of 2 mm from one of 13 mm when that scale is the wrong fit's own.
    kind : str
        Named in errors (which are caught: a seed that cannot be settled is skipped).
    sigma : float or None, metres
        The sensor's range sigma; else the robust fit's scale sets the noise level.
    tolerances : Tolerances
    thorough : bool
        Whether a settled fit that hides inliers behind itself is settled again with the beams
        in the cost (:func:`_settle`), and a settled fit that rejected shots is also refitted
        to every shot; several times slower.

    Returns
    -------
    RobustFit
        ``robust`` itself unless another settled fit scores lower.

    Raises
    ------
    FitError
        ``robust`` is None and no seed settles with enough inliers.
    """
    if robust is None and sigma is None:
        raise ValueError("Without a robust fit the sensor's sigma must set the noise level.")
    scale = max(float(sigma) if sigma is not None else robust.scale, tolerances.sigma_floor)
    cutoff = tolerances.outlier_cutoff_sigma
    best, best_score = None, np.inf
    uniform = np.ones(len(points))

    extent = diagonal_extent(points)
    floor = float(tolerances.sigma_floor)

    def consider(fit) -> np.ndarray | None:
        """Keep ``fit`` if it scores best so far; its points' beam excess (n,) metres."""
        nonlocal best, best_score
        if fit is None:
            return None
        if excess is None:
            beyond = np.zeros(len(points))
            kept = int(np.count_nonzero(fit.inliers))
            score = mixture_score(fit.residuals, fit.inliers, extent, floor)
            score += mixing_cost((kept, len(points) - kept))
        else:
            beyond = excess([fit.state], points)[0]
            score = visible_score(fit.residuals, beyond, scale, cutoff)
        if score < best_score:
            best, best_score = fit, score
        return beyond

    def refined(state, current=None):
        return settled_fit(
            points, state, model, kind=kind, sigma=sigma, tolerances=tolerances, current=current
        )

    consider(robust)
    for seed in seeds:
        # The plain robust settle first; only a fit that hides inliers behind itself is
        # settled again with the beams in the cost (slower: a differenced Jacobian).
        state, residuals, jacobian = gauss_newton(
            model,
            seed,
            points,
            lambda r: tukey_weights(r, max(scale, robust_scale(r, scale))),
            SETTLE_ITERATIONS,
            1e-6,
        )
        fit = refined(state, (residuals, jacobian))  # the settle's Jacobian at its state
        beyond = consider(fit)
        hides = fit is None or bool((beyond[fit.inliers] > cutoff * scale).any())
        if thorough and fit is not None and not fit.inliers.all():
            # A good shot just beyond the 3-sigma test can send the refit into a basin where
            # it stays an outlier (a thinner pipe through the other shots); the fit of every
            # shot is a candidate too.
            whole, residuals, jacobian = gauss_newton(
                model, fit.state, points, lambda r: uniform, SETTLE_ITERATIONS, 1e-6
            )
            consider(refined(whole, (residuals, jacobian)))
        if thorough and hides and excess is not None:
            consider(refined(_settle(model, seed, points, excess, scale)))
    if best is None:
        raise FitError(f"No {kind} explains most of these points; check that they are one {kind}.")
    return best
