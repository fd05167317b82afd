"""Automatic kind: fit a plane, sphere, cylinder and cuboid, keep the one the evidence favours.

Criterion
---------
The Bayesian information criterion (Schwarz 1978), ``-2 ln L + p ln n``, of each candidate's
orthogonal residuals (each shot's distance to the surface the fit returns,
:func:`surface_residuals`: for a cuboid, to the box, not to its faces' infinite planes), with
outliers handled the same way for every model (a mixture of Gaussian inliers and uniform
outliers, as in Torr's robust GRIC, Torr 1998, "Geometric motion segmentation and model
selection"). ``p`` is the number of parameters the residuals fix
(:func:`parameter_count`: plane 3, sphere 4, cylinder 5, a cuboid its orientation and one
offset per seen face) and ``n`` the number of points.

* Sensor sigma ``s`` known: ``-2 ln L = sum_i min((r_i / s)^2, c^2)`` (+ a constant common to all
  models), ``c`` = ``tolerances.outlier_cutoff_sigma``: a point beyond ``c s`` costs every model
  the same.
* Unknown: first each model's inliers are taken as Gaussian with its own maximum-likelihood
  sigma ``s_k^2 = sum_inliers r^2 / m_k`` and its rejected points as uniform over the points'
  extent ``W`` (bounding-box diagonal), mixed in their maximum-likelihood proportions:
  ``-2 ln L = m_k (1 + ln(2 pi s_k^2)) + (n - m_k) 2 ln W - 2 (m_k ln(m_k / n) + (n - m_k)
  ln(1 - m_k / n))`` (only ``s_k / W`` matters, so no unit enters; without the proportions
  a box split into flat patches of a sphere, fitting 60% of the shots to 0.2 mm, led). The
  best model that may be chosen by that score gives the noise level (its degrees-of-freedom-
  corrected inlier sigma), and the models are then compared as
  with a known sigma. The second step matters with 20-40 points: a model whose inlier test
  happened to reject a few good points (3 sigma of a small-sample scale) must not lose to one
  that kept them merely because their outlier decisions differ.

A more complex model must win by *strong* evidence, a BIC difference of at least 6 (Kass &
Raftery 1995: 0-2 barely worth mentioning, 2-6 positive, 6-10 strong): among the candidates
within 6 of the best, the simplest (fewest fitted parameters; between equals, fewest
parameters in all, so a cylinder before a two-face cuboid) is chosen. With 20-40 points a flat
wall otherwise passes for a 1 km sphere now and then (a chance drop of the residuals by a few
sigma^2), while real curved or boxy objects win by tens to hundreds. A cuboid seen on one face
is left to the plane; one that saw two opposite faces, which no single station sees, only
wins by strong evidence over every other kind (a box scanned from two stations).

With the station known, the chosen fit may have traded foreground for background: kept as its
surface shots that another candidate sees past (farther from the station than every shot that
one keeps, :func:`seen_past`), and left out shots in front that the other keeps. A left-out
shot costs every model the same, so on every shot the trade is free: a tank's raster column and
the wall's next one lie on one plane seen at 74-79 degrees, a box with that "face" leaves the
tank's other column out, and its grazing face's small orthogonal residuals beat the tank's
cylinder. The candidates are then scored again on the shots in front of that background
(:func:`traded_background`), where a box has to explain the tank's shots.
"""

from __future__ import annotations

import dataclasses
import inspect
import math

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import require_spread, row_norms, validate_points
from asbuilt.fit._mixture import mixing_cost
from asbuilt.fit.result import FitResult
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = [
    "fit_auto",
    "CANDIDATES",
    "PARAMETERS",
    "WEAK_EVIDENCE",
    "information_scores",
    "parameter_count",
    "seen_past",
    "surface_residuals",
    "traded_background",
    "ONE_FACE_CUBOID",
    "RIVAL_PREFIX",
]

#: Kinds tried, simplest first.
CANDIDATES = ("plane", "sphere", "cylinder", "cuboid")
#: Free parameters of each kind's surface: a cuboid has at most 9 (centre, orientation, sizes),
#: of which the BIC counts those its residuals depend on (:func:`parameter_count`).
PARAMETERS = {"plane": 3, "sphere": 4, "cylinder": 5, "cuboid": 9}
#: BIC difference a more complex model must beat to be chosen ("strong", Kass & Raftery 1995).
WEAK_EVIDENCE = 6.0
#: A sphere or cylinder whose radius is over this many times the points' extent (bounding-box
#: diagonal) is a plane with a trace of curvature, not an object the shots outline: it is not
#: preferred as the simpler kind over a better-scoring one. An independent review's pipes at
#: 10 m (a 1.7 m strip of 27 shots over a 91-degree arc) went to spheres of 41 and 57 m
#: radius, "simpler" than the cylinder that scored 2.4-3.4 better.
FLAT_RADIUS_EXTENTS = 5.0
#: Diagnostics key prefix of a kind that explains the points almost as well with as many fitted
#: parameters (``auto_rival_cuboid``: its BIC minus the chosen kind's).
RIVAL_PREFIX = "auto_rival_"
#: Diagnostics key (1.0) of a plane chosen where the cuboid fit saw one face only: the shots
#: cannot tell a wall or plate from a box seen face-on (a column's front), whose depth they do
#: not measure. The "ambiguous-kind" rule reports it when the label names a box-like object.
ONE_FACE_CUBOID = "auto_one_face_cuboid"


def _fitter(kind: str):
    """The fit function of a kind, imported on use (the cuboid fit may not be installed)."""
    if kind == "plane":
        from asbuilt.fit.plane import fit_plane

        return fit_plane
    if kind == "sphere":
        from asbuilt.fit.sphere import fit_sphere

        return fit_sphere
    if kind == "cylinder":
        from asbuilt.fit.cylinder import fit_cylinder

        return fit_cylinder
    from asbuilt.fit.cuboid import fit_cuboid

    return fit_cuboid


def parameter_count(kind: str, result: FitResult) -> int:
    """The parameters a fit's residuals depend on, which the BIC penalises.

    A plane, sphere or cylinder: all of them (3, 4, 5). A cuboid: its orientation (3; 2 when
    one face is seen, whose turn about its normal the residuals do not fix) and one offset per
    seen face (its ``faces`` diagnostic); the sizes along axes with at most one seen face are
    set from the points' extent, not fitted to their residuals. A cuboid result without that
    diagnostic counts all 9.
    """
    if kind != "cuboid":
        return PARAMETERS[kind]
    faces = int(result.diagnostics.get("faces", 0))
    if not 1 <= faces <= 6:
        return PARAMETERS["cuboid"]
    return min(faces + (2 if faces == 1 else 3), PARAMETERS["cuboid"])


def surface_residuals(kind: str, result: FitResult, points: np.ndarray) -> np.ndarray:
    """Each shot's orthogonal distance (n,) metres to the surface a fit claims, as scored here.

    A plane's, sphere's and cylinder's residuals are that already. A cuboid fit reports an
    inlier's distance to its face's *infinite* plane: a shot it took for a face but that lies
    beyond the box's edge (in front of the neighbouring face, where a pipe bulges past the
    corner of a box laid over its arc) then costs millimetres while it is centimetres off the
    box. Scored so, a box over 5 raster lines of a 0.5-1 m pipe explained shots 10-200 mm off
    its surface to 0.1-2.5 mm (chi-square 31.7 against 82.4 to its surface): the criterion
    compares surfaces, so the box is scored by its distance to the box.
    """
    if kind != "cuboid":
        return np.asarray(result.residuals, dtype=np.float64)
    return result.primitive.distance(points)


def _one_face(result: FitResult) -> bool:
    """Whether a cuboid fit saw a single face (its ``faces`` diagnostic)."""
    return int(result.diagnostics.get("faces", 0)) == 1


def information_scores(
    results: dict[str, FitResult],
    sigma: float | None,
    extent: float,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    shots=None,
) -> dict[str, float]:
    """BIC of each fit of the same points (see the module docstring).

    Parameters
    ----------
    results : dict of kind -> FitResult
        Fits of the same ``n`` points.
    sigma : float or None, metres
        The sensor's range sigma, or None to use each model's own inlier sigma.
    extent : float, metres
        Width ``W`` of the uniform outlier density (the points' bounding-box diagonal).
    tolerances : Tolerances
        ``outlier_cutoff_sigma`` truncates residuals when ``sigma`` is known;
        ``sigma_floor`` floors the estimated sigmas.
    shots : array_like, shape (n,), bool, optional
        Score the fits on these shots only (every fit's residuals and inliers restricted to
        them, ``n`` their count); all of them by default.

    Returns
    -------
    dict of kind -> float
    """
    scores = {}
    cutoff = tolerances.outlier_cutoff_sigma
    for kind, result in results.items():
        residuals = np.asarray(result.residuals, dtype=np.float64)
        kept = np.asarray(result.inliers, dtype=bool)
        if shots is not None:
            residuals, kept = residuals[shots], kept[shots]
        n = residuals.size
        if sigma is not None:
            scaled = residuals / sigma
            data = float(np.minimum(scaled * scaled, cutoff * cutoff).sum())
        else:
            inliers = residuals[kept]
            m = inliers.size
            variance = max(float(np.mean(inliers * inliers)), tolerances.sigma_floor**2)
            data = m * (1.0 + math.log(2.0 * math.pi * variance))
            data += (n - m) * 2.0 * math.log(max(extent, tolerances.sigma_floor))
            data += mixing_cost((m, n - m))
        scores[kind] = data + parameter_count(kind, result) * math.log(n)
    return scores


def _choice(scores, candidates, counts, flat=()) -> tuple[str, str, list[str]]:
    """The best-scoring candidate, the chosen one and those within ``WEAK_EVIDENCE`` of the best.

    ``scores`` and ``counts`` (:func:`parameter_count`) map kinds to their BIC and fitted
    parameters; ``candidates`` are the kinds that may be chosen; ``flat`` kinds (a sphere or
    cylinder far wider than the points, :data:`FLAT_RADIUS_EXTENTS`) are chosen only when they
    score best, never as the simpler of two close kinds.
    """
    eligible = {kind: scores[kind] for kind in candidates}
    best = min(eligible, key=lambda kind: (eligible[kind], counts[kind]))
    close = [kind for kind in eligible if eligible[kind] <= eligible[best] + WEAK_EVIDENCE]
    # Fewest fitted parameters first; between equals, the kind that claims less (a cuboid's
    # sizes beyond its seen faces come from the points' extent, unverified), then the score.
    simplest = [kind for kind in close if kind == best or kind not in flat]
    chosen = min(simplest, key=lambda kind: (counts[kind], PARAMETERS[kind], scores[kind]))
    return best, chosen, close


def seen_past(result: FitResult, points: np.ndarray, viewpoint, cutoff: float) -> np.ndarray:
    """Which shots a fit leaves out lie farther from the station than every shot it keeps.

    Such a shot is background seen past the object (a wall behind a tank that a beam beside it
    reached), by more than twice ``cutoff`` beyond the farthest kept shot (as the cuboid fit's
    own background test, :func:`asbuilt.fit._cuboid_background.seen_past`).

    Parameters
    ----------
    result : FitResult
        A fit of ``points``.
    points : ndarray, shape (n, 3), metres
    viewpoint : array_like, shape (3,), metres
        The station.
    cutoff : float, metres
        The inlier cutoff.

    Returns
    -------
    ndarray, shape (n,), bool
    """
    kept = np.asarray(result.inliers, dtype=bool)
    if not kept.any():
        return np.zeros(kept.shape, dtype=bool)
    ranges = row_norms(points - np.asarray(viewpoint, dtype=np.float64))
    return ~kept & (ranges > ranges[kept].max() + 2.0 * cutoff)


def traded_background(results, scores, candidates, chosen: str, points, viewpoint, cutoff: float):
    """A fit that explains as its surface shots the chosen fit should have left as background.

    The witness is a candidate fit whose left-out shots are all background seen past it
    (:func:`seen_past`: it explains the scan as one object before a background), some of which
    the ``chosen`` fit keeps as its surface while it leaves out, in front of them, shots the
    witness keeps. The two fits trade foreground for background: a tank's raster column and the
    wall's next column lie on one plane seen at grazing incidence (a "face" no range test tells
    from a box's side), and a box with that face leaves the tank's other column out. The
    maximum-likelihood criterion counts a left-out shot the same whatever it is, so the trade
    costs the box nothing and the plane's small grazing residuals win it. Scored on the
    witness's foreground, the box has to explain the tank's shots.

    Parameters
    ----------
    results : dict of kind -> FitResult
        Fits of ``points``.
    scores : dict of kind -> float
        Their scores on every shot (:func:`information_scores`).
    candidates : list of str
        The kinds that may be chosen (a witness is one of them).
    chosen : str
        The kind the criterion chose on every shot.
    points : ndarray, shape (n, 3), metres
    viewpoint : array_like, shape (3,), metres
    cutoff : float, metres
        The inlier cutoff (criterion's noise level times ``outlier_cutoff_sigma``).

    Returns
    -------
    tuple of (str, ndarray of shape (n,), bool) or None
        The witness of lowest score and the shots it sees past; None when no candidate is one.
    """
    kept = np.asarray(results[chosen].inliers, dtype=bool)
    foreground_left = ~kept & ~seen_past(results[chosen], points, viewpoint, cutoff)
    if not foreground_left.any():
        return None
    for kind in sorted(candidates, key=lambda kind: scores[kind]):
        if kind == chosen:
            continue
        own = np.asarray(results[kind].inliers, dtype=bool)
        past = seen_past(results[kind], points, viewpoint, cutoff)
        if not np.array_equal(~own, past):
            continue  # it leaves out a shot in front of its background
        if (kept & past).any() and (foreground_left & own).any():
            return kind, past
    return None


def fit_auto(
    points, *, sigma=None, tolerances: Tolerances = DEFAULT_TOLERANCES, viewpoint=None
) -> FitResult:
    """Fit every candidate kind and return the one a robust BIC prefers, saying why.

    Algorithm: plane, sphere, cylinder and cuboid fits of the same points, compared by the
    Bayesian information criterion (Schwarz 1978) of their orthogonal residuals with outliers
    scored alike for every model (as in Torr's GRIC, 1998), preferring the simplest model
    unless the evidence against it is strong (a BIC difference of 6, Kass & Raftery 1995);
    see the module docstring.

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
    sigma : float, optional, metres
        The sensor's range sigma; the common noise level of the criterion when given.
    tolerances : Tolerances
    viewpoint : array_like, shape (3,), metres, optional
        Where the shots were taken from; passed to the candidate fits that use it.

    Returns
    -------
    FitResult
        The chosen kind's own result, with a note giving every candidate's score (or why it
        could not be fitted) and the reason for the choice appended to ``notes`` (and, when
        they were scored on the shots in front of a background, which and why).

    Raises
    ------
    FitError
        Too few, identical or collinear points, or no candidate kind fits.
    """
    pts = validate_points(points, "auto")
    require_spread(pts, "auto", 2)
    results: dict[str, FitResult] = {}
    failures: dict[str, str] = {}
    for kind in CANDIDATES:
        try:
            fitter = _fitter(kind)
        except ImportError:
            failures[kind] = "not available"
            continue
        try:
            options = {"sigma": sigma, "tolerances": tolerances}
            if viewpoint is not None and "viewpoint" in inspect.signature(fitter).parameters:
                options["viewpoint"] = viewpoint
            results[kind] = fitter(pts, **options)
        except FitError as exc:
            # Some fits name their kind first ("cuboid: the 7 shots ..."); the notes name it.
            failures[kind] = exc.message.removeprefix(f"{kind}: ")
    if not results:
        reasons = "; ".join(f"{kind}: {why.rstrip('.')}" for kind, why in failures.items())
        raise FitError(f"No kind fits these points ({reasons}); choose a kind or hull.")
    extent = float(np.linalg.norm(np.ptp(pts, axis=0)))
    # Every kind judged by its shots' distances to the surface it returns (a cuboid's own
    # residuals are to its faces' infinite planes); the returned result keeps its own.
    judged = {}
    for kind, result in results.items():
        residuals = surface_residuals(kind, result, pts)
        # A shot kept for a face but beyond the box's edge by more than the fit's own inlier
        # cutoff is no inlier of the box: without a sigma it is scored as an outlier, not let
        # inflate the box's noise level (which made a 49 mm sphere the noise's "leader").
        kept = np.asarray(result.inliers, dtype=bool)
        if kind == "cuboid":
            noise = max(float(result.sigma), tolerances.sigma_floor)
            kept = kept & (np.abs(residuals) <= tolerances.outlier_cutoff_sigma * noise)
        judged[kind] = dataclasses.replace(result, residuals=residuals, inliers=kept)
    counts = {kind: parameter_count(kind, result) for kind, result in results.items()}
    # Kinds that may be chosen, in CANDIDATES order (every fitted one is scored and named).
    candidates = [kind for kind in CANDIDATES if kind in results]
    opposite = False
    if "plane" in results and "cuboid" in results and _one_face(results["cuboid"]):
        # A cuboid seen on one face is that face's plane. Its depth is made up (not measured),
        # and points behind the face (a plate's edge, the wall beyond) fall inside it and seem
        # to fit: the plane stands for it.
        candidates.remove("cuboid")
    elif "cuboid" in results and any(results["cuboid"].observed or ()) and len(results) > 1:
        # Two opposite faces seen: no single station sees both. Unless the box beats every
        # other kind by strong evidence (a box scanned from two stations), the raster lines
        # of another surface (a tank's) were split among four planes.
        candidates.remove("cuboid")
        opposite = True

    def scored(candidates, shots=None):
        if sigma is not None:
            return (
                information_scores(judged, float(sigma), extent, tolerances, shots),
                f"noise sigma {float(sigma) * 1000:.3g} mm",
                float(sigma),
            )
        own = information_scores(judged, None, extent, tolerances, shots)
        leader = min(candidates, key=lambda kind: (own[kind], counts[kind]))
        noise = max(float(results[leader].sigma), float(tolerances.sigma_floor))
        return (
            information_scores(judged, noise, extent, tolerances, shots),
            f"sigma {noise * 1000:.3g} mm from the {leader} fit",
            noise,
        )

    flat = {
        kind: float(results[kind].primitive.radius) / extent
        for kind in ("sphere", "cylinder")
        if kind in results and results[kind].primitive.radius > FLAT_RADIUS_EXTENTS * extent
    }
    scores, basis, noise = scored(candidates)
    if opposite and scores["cuboid"] + WEAK_EVIDENCE < min(scores[k] for k in candidates):
        candidates = [kind for kind in CANDIDATES if kind in results]
        if sigma is None:  # the noise level may now come from the cuboid
            scores, basis, noise = scored(candidates)
        opposite = False
    best, chosen, close = _choice(scores, candidates, counts, flat)
    traded = None
    if viewpoint is not None:
        cutoff = tolerances.outlier_cutoff_sigma * noise
        traded = traded_background(results, scores, candidates, chosen, pts, viewpoint, cutoff)
    if traded is not None:
        # The chosen fit took shots another fit sees past as its surface and left out shots
        # in front that the other explains: judged on every shot, the background counts for
        # the chosen fit. Both are judged on the shots in front of that background.
        witness, past = traded
        swapped = chosen
        scores, basis, noise = scored(candidates, ~past)
        best, chosen, close = _choice(scores, candidates, counts, flat)
    others = ", ".join(
        f"{kind} {scores[kind]:.1f}" for kind in CANDIDATES if kind in scores and kind != chosen
    )
    why = f"auto chose {chosen}: BIC {scores[chosen]:.1f}"
    if others:
        why += f" (lower is better; {others})"
    why += f"; {basis}."
    if traded is not None:
        why += (
            f" Scored on the {int(np.count_nonzero(~past))} shots in front of the"
            f" {int(np.count_nonzero(past))} the {witness} fit sees past (farther than every"
            f" shot it keeps): the {swapped} fit took some of those as its surface and left out"
            f" shots in front that the {witness} explains."
        )
    if chosen != best:
        simpler = "simpler" if counts[chosen] < counts[best] else "less claiming"
        why += (
            f" {best} scored {scores[chosen] - scores[best]:.1f} lower, not strong evidence"
            f" (< {WEAK_EVIDENCE:g}); the {simpler} {chosen} is preferred."
        )
    passed = [
        kind
        for kind in close
        if kind in flat
        and kind != best
        and (counts[kind], PARAMETERS[kind])
        < (
            counts[chosen],
            PARAMETERS[chosen],
        )
    ]
    for kind in passed:
        why += (
            f" The {kind} (radius {results[kind].primitive.radius:.3g} m, {flat[kind]:.0f} times"
            " the points' extent) is a plane's trace of curvature, not an object these shots"
            " outline: it is not preferred as the simpler kind."
        )
    one_face = False
    if "cuboid" in scores and "cuboid" not in candidates:
        if opposite:
            why += (
                " The cuboid fit saw two opposite faces, which no single station sees, and is"
                " not better by strong evidence: it is not chosen (set the kind to cuboid for a"
                " box scanned from both sides)."
            )
        else:
            why += " The cuboid fit saw one face only: the plane stands for it."
            one_face = chosen == "plane"
    rivals = [kind for kind in close if kind != chosen and counts[kind] == counts[chosen]]
    if rivals:
        why += (
            f" A {' or '.join(rivals)} explains the points almost as well with as many "
            f"parameters (BIC within {WEAK_EVIDENCE:g}): these shots cannot tell them apart; "
            "set the object's kind if you know it."
        )
    notes = [why]
    for kind, reason in failures.items():
        notes.append(f"auto could not fit a {kind}: {reason}")
    result = results[chosen]
    # The rivals as data too (the scan-quality rule "ambiguous-kind" reports them): each one's
    # BIC minus the chosen kind's.
    diagnostics = dict(result.diagnostics)
    for kind in rivals:
        diagnostics[f"{RIVAL_PREFIX}{kind}"] = float(scores[kind] - scores[chosen])
    if one_face:
        diagnostics[ONE_FACE_CUBOID] = 1.0
    return dataclasses.replace(
        result, notes=tuple(result.notes) + tuple(notes), diagnostics=diagnostics
    )
