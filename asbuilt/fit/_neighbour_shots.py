"""A pipe's inliers that lie on a neighbour's surface: the window took in the neighbour.

Private helper of :func:`asbuilt.fit.fit`. A raster window over a pipe in a rack also takes in
the pipe in front of it or beside it, one raster line of its shots or more. Three raster lines
fit a circle whatever they lie on, so two lines on the pipe and one on its neighbour fit a
cylinder to the noise, confidently and wrong (an independent review's racks: NPS 6 and NPS 4
pipes fitted r 308 and 231 mm, then snapped to NPS 24 and NPS 18 without a finding). Nothing in
one object's shots tells the neighbour's line from the pipe's own: the scan's other objects do.
The neighbour, fitted from its own shots, predicts where its surface lies; the pipe's fit only
passed through those shots because it was fitted to them.

:func:`without_neighbour_shots` therefore tests every cylinder fit ``A`` against every other
fitted solid ``B`` (cylinder, cuboid, sphere) of the scan:

- ``B`` explains its own inliers to the noise (RMS within ``FIT_RMS_NOISES`` of the sensor's
  sigma, else of the prior range noise): a poor fit's surface predicts nothing;
- the inliers of ``A`` within ``B``'s inlier cutoff of ``B``'s surface, and (a cylinder ``B``)
  within its fitted length and a radius past its ends, are ``B``'s candidates; there must be
  ``FEWEST_SHOTS`` or more (a raster line);
- ``A`` and ``B`` are not one pipe (axes within ``SAME_LINE_DEG``, each through the other
  within half its radius, radii within ``SAME_RADIUS`` of each other: contiguous pieces of one
  run share their surface by nature);
- ``B`` is clean: no fit but ``A`` holds ``FEWEST_SHOTS`` of ``B``'s inliers on its surface (a
  neighbour itself fitted through a third pipe's shots predicts nothing), and when ``A``'s
  surface holds them, ``A`` is not changed by ``B``'s test in turn (two fits each held by the
  other's shots: which one took in its neighbour the shots cannot tell, and both stay);
- ``A`` fitted again without the candidates either is refused, or explains the shots left to
  the noise as ``B`` must and passes within its own cutoff of fewer than half of the
  candidates: the candidates were what held ``A`` where it was. A pipe resting
  on ``B``, whose shots along the contact lie on both surfaces, is fitted again through them
  and stays as it was.

``A`` is then replaced by that refit, the candidates left out as another object's shots
(``diagnostics[NEIGHBOUR_SHOTS]``, which the ``outliers`` rule does not count), or, when the
refit is refused, ``A`` is refused with the refit's reason and the neighbour named. The test
runs again over the changed report (a refit pipe can be a clean neighbour in turn) for at most
``ROUNDS`` rounds. A pipe fused from two stations' views (:mod:`asbuilt.fit._stations`) is
not fitted again: its shots were seen from two viewpoints, which one fit cannot take. Lengths
in metres.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import fit_cutoff
from asbuilt.fit.result import NEIGHBOUR_SHOTS, FitFailure, FitReport, ObjectFit
from asbuilt.primitives import Cuboid, Cylinder, Sphere
from asbuilt.tolerances import Tolerances

__all__ = [
    "FEWEST_SHOTS",
    "FIT_RMS_NOISES",
    "ROUNDS",
    "SAME_LINE_DEG",
    "SAME_RADIUS",
    "neighbour_candidates",
    "without_neighbour_shots",
]

#: Fewest inliers on a neighbour's surface that can be one raster line of it.
FEWEST_SHOTS = 3
#: Axes within this many degrees, each through the other within half its radius, and radii
#: within ``SAME_RADIUS`` of the larger: one pipe's run, whose pieces share their surface.
SAME_LINE_DEG = 3.0
SAME_RADIUS = 0.25
#: Rounds of the test over the changed report.
ROUNDS = 3
#: A fit whose inliers' RMS is above this many times the noise (the sensor's sigma, else the
#: prior range noise) explains its own shots no better than a poor fit (the ``poor-fit`` rule's
#: default): as a neighbour it predicts nothing, and as a refit it is no better than the fit.
FIT_RMS_NOISES = 2.0

_SOLIDS = (Cylinder, Cuboid, Sphere)


def _explains_own_shots(result, sigma, tolerances: Tolerances) -> bool:
    """Whether a fit explains its inliers to the noise (``FIT_RMS_NOISES``)."""
    noise = float(sigma) if sigma is not None else float(tolerances.prior_range_sigma)
    return bool(result.rms <= FIT_RMS_NOISES * max(noise, float(tolerances.sigma_floor)))


def _one_line(first: Cylinder, second: Cylinder) -> bool:
    """Whether two cylinders are one pipe's run (the module docstring's test)."""
    angle = np.degrees(np.arccos(min(abs(float(first.axis @ second.axis)), 1.0)))
    if angle > SAME_LINE_DEG:
        return False
    larger = max(float(first.radius), float(second.radius))
    if abs(float(first.radius) - float(second.radius)) > SAME_RADIUS * larger:
        return False
    for here, there in ((first, second), (second, first)):
        offset = there.center - here.center
        across = offset - (offset @ here.axis) * here.axis
        if float(np.linalg.norm(across)) > 0.5 * float(here.radius):
            return False
    return True


def neighbour_candidates(fit: ObjectFit, other: ObjectFit, sigma, tolerances) -> np.ndarray:
    """Which of ``fit``'s points, shape (n,) bool, are inliers of it lying on ``other``'s
    fitted surface (within ``other``'s inlier cutoff; a cylinder within its length and a radius
    past each end); all False when ``other`` is no solid, or is the same pipe's run."""
    points = np.asarray(fit.object.points, dtype=np.float64)
    none = np.zeros(len(points), dtype=bool)
    mine, theirs = fit.result.primitive, other.result.primitive
    if not isinstance(theirs, _SOLIDS) or not _explains_own_shots(other.result, sigma, tolerances):
        return none
    if isinstance(mine, Cylinder) and isinstance(theirs, Cylinder) and _one_line(mine, theirs):
        return none
    cutoff = fit_cutoff(other.result, sigma, tolerances)
    on = fit.result.inliers & (np.abs(theirs.distance(points)) <= cutoff)
    if isinstance(theirs, Cylinder) and on.any():
        along = (points - theirs.center) @ theirs.axis
        on &= np.abs(along) <= 0.5 * float(theirs.length) + float(theirs.radius)
    return on


def without_neighbour_shots(report: FitReport, refit, tolerances: Tolerances) -> FitReport:
    """``report`` with every cylinder fit held by a clean neighbour's shots (module docstring)
    fitted again without them, or refused.

    Parameters
    ----------
    report : FitReport
        The scan's fits.
    refit : callable
        ``refit(obj)`` fits a :class:`~asbuilt.scan.model.ScanObject` as
        :func:`asbuilt.fit.fit_object` does (the scan's sigma and the object's viewpoint),
        returning an :class:`ObjectFit` or raising :class:`FitError`.
    tolerances : Tolerances
        ``outlier_cutoff_sigma`` and ``sigma_floor`` set the surfaces' cutoffs.
    """
    sigma = report.scan.sensor.range_sigma
    for _ in range(ROUNDS):
        changed = _one_round(report, refit, sigma, tolerances)
        if changed is None:
            return report
        report = changed
    return report


def _one_round(report: FitReport, refit, sigma, tolerances) -> FitReport | None:
    """The report after every change one pass finds, or None when it finds none."""
    fits = list(report.fits)
    held = {
        (a, b): neighbour_candidates(fits[a], fits[b], sigma, tolerances)
        for a in range(len(fits))
        for b in range(len(fits))
        if a != b
    }
    # The fits each fit has a raster line of its inliers on: a neighbour that itself lies on
    # a third fit's surface may be fitted through that fit's shots, and predicts nothing.
    leans_on: dict[int, set[int]] = {a: set() for a in range(len(fits))}
    for (a, b), on in held.items():
        if np.count_nonzero(on) >= FEWEST_SHOTS:
            leans_on[a].add(b)
    proposed: dict[int, tuple[int, ObjectFit | FitFailure]] = {}
    for a, item in enumerate(fits):
        if item.requested != "cylinder" or not isinstance(item.result.primitive, Cylinder):
            continue
        if "fused_with" in item.object.extra:
            continue  # two stations' views fitted as one: no one viewpoint to fit them again
        for b in sorted(leans_on[a]):
            if not leans_on[b] <= {a}:
                continue
            outcome = _without(item, fits[b], held[(a, b)], refit, sigma, tolerances)
            if outcome is not None:
                proposed[a] = (b, outcome)
                break
    # Two fits each held by the other's shots, each refit without them: which one took in its
    # neighbour the shots cannot tell, and both stay as they were.
    replaced = {
        a: outcome
        for a, (b, outcome) in proposed.items()
        if not (b in proposed and proposed[b][0] == a)
    }
    if not replaced:
        return None
    kept = tuple(
        replaced.get(a, item)
        for a, item in enumerate(fits)
        if not isinstance(replaced.get(a), FitFailure)
    )
    failures = report.failures + tuple(
        outcome for outcome in replaced.values() if isinstance(outcome, FitFailure)
    )
    return dataclasses.replace(report, fits=kept, failures=failures)


def _without(item: ObjectFit, other: ObjectFit, on, refit, sigma, tolerances):
    """``item`` fitted again without its shots ``on`` (n,) bool of ``other``'s surface: the new
    :class:`ObjectFit`, a :class:`FitFailure` when that fit is refused, or None when the refit
    still passes through most of them (they were ``item``'s own)."""
    obj = item.object
    points = np.asarray(obj.points, dtype=np.float64)
    rest = ~on
    subset = dataclasses.replace(
        obj,
        points=points[rest],
        measurements=None if obj.measurements is None else obj.measurements[rest],
    )
    count = int(np.count_nonzero(on))
    said = (
        f"{count} of its shots lie on {other.object.id}'s surface, which {other.object.id}'s"
        " own shots fit: the window took in its neighbour"
    )
    try:
        again = refit(subset)
    except FitError as exc:
        error = FitError(
            f"{said}. Without them: {exc.message}",
            source=exc.source,
            where=exc.where,
        )
        return FitFailure(object=obj, error=error)
    result = again.result
    if not _explains_own_shots(result, sigma, tolerances):
        return None  # the shots left are no cylinder without those: they were its own
    cutoff = fit_cutoff(result, sigma, tolerances)
    if int(np.count_nonzero(np.abs(result.primitive.distance(points[on])) <= cutoff)) * 2 >= count:
        return None
    inliers = np.zeros(len(points), dtype=bool)
    inliers[rest] = result.inliers
    diagnostics = {**result.diagnostics, NEIGHBOUR_SHOTS: float(count)}
    note = f"{said}; they were left out and the rest fitted again."
    fitted = dataclasses.replace(
        result,
        residuals=result.primitive.distance(points),
        inliers=inliers,
        diagnostics=diagnostics,
        notes=(*result.notes, note),
    )
    return dataclasses.replace(item, result=fitted)
