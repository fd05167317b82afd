"""Fitting: one primitive per scan object, chosen by the object's ``kind``.

This module only dispatches; each primitive's algorithm lives in its own module and is imported
on first use: :func:`asbuilt.fit.plane.fit_plane`, :func:`asbuilt.fit.sphere.fit_sphere`,
:func:`asbuilt.fit.cylinder.fit_cylinder`, :func:`asbuilt.fit.cuboid.fit_cuboid`,
:func:`asbuilt.fit.hull.fit_hull` and :func:`asbuilt.fit.auto.fit_auto` (each
``(points (n, 3) m, *, sigma=None, tolerances=DEFAULT_TOLERANCES) -> FitResult``).

>>> import asbuilt                                 # doctest: +SKIP
>>> report = asbuilt.fit(asbuilt.load_scan("samples/spool.json"))
>>> report.get("P1").result.primitive.radius     # metres
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import sys
import types
from collections.abc import Callable
from importlib import import_module

import numpy as np

from asbuilt.errors import FitError, located
from asbuilt.fit._background_count import with_background_count
from asbuilt.fit._common import extent_of, radius_text, validate_points
from asbuilt.fit._curvature import (  # noqa: F401 (CURVATURE_TAIL: asbuilt.fit's, documented)
    CURVATURE_TAIL,
    curvature_measured,
)
from asbuilt.fit._edge_brackets import edge_brackets, widen_pinned
from asbuilt.fit._neighbour_shots import without_neighbour_shots
from asbuilt.fit._noise_levels import _fit_with_noise
from asbuilt.fit._object_words import named_failure, named_report
from asbuilt.fit._small_linalg import eigvalsh
from asbuilt.fit._stations import fuse_station_views
from asbuilt.fit._window import beyond_window, open_ends
from asbuilt.fit.result import FitFailure, FitReport, FitResult, ObjectFit
from asbuilt.labels import DEFAULT_WORDS, LabelWords
from asbuilt.primitives import as_points, as_vector
from asbuilt.scan.load import PLAUSIBLE_RANGE_SIGMA
from asbuilt.scan.model import KINDS, Scan, ScanObject, kind_phrase
from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS, Tolerances

__all__ = [
    "FITTERS",
    "fit",
    "fit_object",
    "fit_points",
    "FitResult",
    "ObjectFit",
    "FitFailure",
    "FitReport",
    "NothingFittedError",
]

#: kind -> (module, function) of the fit that handles it; imported lazily by :func:`fitter_for`.
FITTERS: dict[str, tuple[str, str]] = {
    "plane": ("asbuilt.fit.plane", "fit_plane"),
    "sphere": ("asbuilt.fit.sphere", "fit_sphere"),
    "cylinder": ("asbuilt.fit.cylinder", "fit_cylinder"),
    "cuboid": ("asbuilt.fit.cuboid", "fit_cuboid"),
    "hull": ("asbuilt.fit.hull", "fit_hull"),
    "auto": ("asbuilt.fit.auto", "fit_auto"),
}

#: Called after each object is fitted with (objects done, objects in all, object id).
Progress = Callable[[int, int, str], None]


def fitter_for(kind: str) -> Callable[..., FitResult]:
    """The fit function for ``kind`` (one of :data:`asbuilt.scan.KINDS`).

    Raises
    ------
    FitError
        ``kind`` is not a known kind.
    """
    try:
        module, name = FITTERS[kind]
    except (KeyError, TypeError):
        raise FitError(
            f"unknown kind {kind!r}; use one of {', '.join(KINDS)}", where="kind"
        ) from None
    return getattr(import_module(module), name)


def fit_points(
    kind: str,
    points,
    *,
    sigma: float | None = None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    viewpoint=None,
) -> FitResult:
    """Fit one primitive of ``kind`` to points.

    Parameters
    ----------
    kind : str
        One of :data:`asbuilt.scan.KINDS`; ``"auto"`` lets :func:`asbuilt.fit.auto.fit_auto`
        choose.
    points : array_like, shape (n, 3), metres
        Measured points.
    sigma : float, optional, metres
        Range noise of the sensor (1e-5 to 0.1 m, as a scan's ``sensor.range_sigma``); when
        None the fit estimates it from its residuals.
    tolerances : Tolerances, optional
        Numerical tolerances passed to the fit (None: the defaults).
    viewpoint : array_like, shape (3,), metres, optional
        The sensor's position, passed to the fits that use it (the cuboid fit places unseen
        edges from the raster's angular window as seen from there).

    Returns
    -------
    FitResult
        The primitive (metres), residuals shape (n,) metres, inliers shape (n,) bool and
        standard errors. The algorithm is the one documented by the kind's fit function (and
        named in ``FitResult.method``).

    Raises
    ------
    FitError
        Unknown kind, a ``sigma`` outside 1e-5 to 0.1 m or not a number, a viewpoint that is
        not 3 finite numbers, or the points cannot define the primitive (a numerical failure of
        linear algebra included).
    """
    # The fits handle infinities and NaNs themselves (a start whose residuals overflow is
    # dropped): numpy's floating-point warnings would only print noise around one result.
    try:
        with np.errstate(all="ignore"):
            return _fit_points(kind, points, sigma, tolerances, viewpoint)
    except np.linalg.LinAlgError as exc:
        raise FitError(
            f"Fitting {kind_phrase(kind)} failed numerically ({exc}); check the points' "
            "coordinates and units.",
            where="points",
        ) from None


def _fit_points(kind: str, points, sigma, tolerances, viewpoint) -> FitResult:
    """:func:`fit_points`, within its floating-point error state."""
    function = fitter_for(kind)
    try:
        array = as_points(points)
    except ValueError as exc:
        raise FitError(str(exc), where="points") from None
    if tolerances is None:
        tolerances = DEFAULT_TOLERANCES
    if sigma is not None:
        sigma = _checked_sigma(sigma)
    if viewpoint is not None:
        try:
            viewpoint = as_vector(viewpoint, "viewpoint")
        except ValueError as exc:
            raise FitError(str(exc), where="viewpoint") from None
    if len(array) < 3:
        # Too few for any kind, said before the spread checks below take 1-2 points for a line
        # or fail on none ("failed numerically"); from three up each fitter says what its kind
        # needs (a cuboid's depends on the faces its shots show).
        validate_points(array, kind)
    # The centred points, for the spread check and the canonical order alike.
    centred = array - array.sum(axis=0) / len(array)  # array.mean(axis=0), less overhead
    if kind != "hull":
        if sigma is not None:
            _require_spread_beyond_noise(array, kind, LINE_SPREAD_SIGMAS * sigma, centred=centred)
        else:
            # No sensor sigma: one prior sigma across the line, so that a head stuck on one
            # spot (shots scattered along its beam only) is refused while a 10 mm tube is not.
            prior = float(tolerances.prior_range_sigma)
            _require_spread_beyond_noise(array, kind, prior, True, centred)
    options = {}
    if viewpoint is not None and _accepts_viewpoint(function):
        options["viewpoint"] = viewpoint
    distinct, row_of = _canonical_rows(array, centred)
    repeats = len(array) - len(distinct)
    if repeats and len(distinct) < MIN_POINTS[kind]:
        what = kind_phrase(kind)
        raise FitError(
            f"{what[0].upper()}{what[1:]} needs at least {MIN_POINTS[kind]} distinct points, "
            f"got {len(distinct)} ({repeats} of the {len(array)} points repeat others exactly); "
            "measure more points.",
            where="points",
        )
    result = _fit_with_noise(kind, function, distinct, sigma, tolerances, options)
    if kind != "auto":  # auto weighs each kind's fit itself, an undetermined one included
        _refuse_unknown_radius(result, distinct)
    notes = [_prior_noise(result, tolerances) if sigma is None else None, _undetermined(result)]
    result = dataclasses.replace(
        result, residuals=result.residuals[row_of], inliers=result.inliers[row_of]
    )
    result = with_background_count(result, array, viewpoint, sigma, tolerances)
    if repeats:
        notes.append(
            f"{repeats} point(s) repeat other points exactly and were counted once (the same "
            "rows twice in the file, e.g. a scan merged with itself); the standard errors are "
            "those of the distinct points."
        )
    for note in notes:
        if note is not None:
            result = dataclasses.replace(result, notes=(*result.notes, note))
    return result


def _canonical_rows(points: np.ndarray, centred=None) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``points`` (n, 3) metres in one canonical order, shape (m, 3), and
    for each of the n rows the index of its distinct row, shape (n,) int. ``centred``:
    ``points - points.mean(axis=0)`` when the caller has it already.

    The fits draw random samples by index (RANSAC hypotheses, starts), so the order of the rows
    would otherwise choose which samples they see: the same shots written in another order (two
    stations' files merged, a converter's sort) could settle on another outlier set, a size a
    few millimetres off. Sorted by distance from the points' centroid, every order of the same
    shots gives the same fit, and a rigid motion or a change of scale leaves the order as it
    is (a sort by coordinate would not: the fits must not depend on the frame either).
    Coordinates break exact ties of distance (points placed symmetrically by construction).

    Exactly repeated coordinates are one measurement written twice (a scan file merged with
    itself, copied rows): a second shot at the same angles re-measures the range and differs in
    the stored digits (except on a coarsely rounded file, where counting it once only makes the
    standard errors slightly conservative). Counted twice, they would shrink the standard errors
    by up to sqrt(2) for no new information.
    """
    if centred is None:
        centred = points - points.mean(axis=0)
    distance = np.einsum("ij,ij->i", centred, centred)
    order = distance.argsort()
    ordered_distance = distance[order]
    if (ordered_distance[1:] > ordered_distance[:-1]).all():
        # No two distances equal (nearly every scan): the distance alone gives lexsort's order
        # below, and no row repeats another; lexsort's four keys cost more than the fit's
        # checks around it.
        row_of = np.empty(len(points), dtype=np.intp)
        row_of[order] = np.arange(len(points))
        return points[order], row_of
    # np.lexsort's last key sorts first: distance, then x, y, z
    order = np.lexsort((*points.T[::-1], distance))
    ordered = points[order]
    first = np.ones(len(points), dtype=bool)
    first[1:] = (ordered[1:] != ordered[:-1]).any(axis=1)
    row_of = np.empty(len(points), dtype=np.intp)
    row_of[order] = first.cumsum() - 1
    return ordered[first], row_of


def _checked_sigma(sigma) -> float:
    """``sigma`` as float metres, or FitError when it is no range finder's noise."""
    try:
        value = float(sigma)
    except (TypeError, ValueError):
        raise FitError(f"must be a number in metres, not {sigma!r}", where="sigma") from None
    low, high = PLAUSIBLE_RANGE_SIGMA
    if not low <= value <= high:  # also False for NaN
        raise FitError(
            f"{value:g} m is not a range finder's noise; give it in metres, {low:g} to {high:g}, "
            "or None to estimate it from the residuals",
            where="sigma",
        )
    return value


def _prior_noise(result: FitResult, tolerances: Tolerances) -> str | None:
    """A note when a fit without a sensor sigma had too few residual degrees of freedom for a
    noise level of its own (:func:`asbuilt.fit._common.noise_level` then leans on the prior)."""
    from asbuilt.fit._common import few_residual_dof

    if result.sigma_source != "residuals" or result.covariance is None:
        return None
    n_params = int(result.covariance.shape[0])
    if not few_residual_dof(result.n_inliers, n_params, tolerances):
        return None
    # Said only when true: a fit that took shots as background before its noise level was
    # known (auto's far-side test, a cylinder's hidden shots) has rejected some.
    rejected = "no point was rejected as an outlier, and " if result.inliers.all() else ""
    return (
        f"{result.n_inliers} points for {n_params} parameters leave too few to estimate the "
        f"noise: {rejected}the standard errors assume a "
        f"{tolerances.prior_range_sigma * 1000:g} mm range noise for the missing degrees of "
        "freedom; give the scan's sensor.range_sigma, or take more shots."
    )


#: Points whose RMS spread across their best line is at most this many range sigmas are taken
#: as shots of a line: pure noise scatters them by about one sigma across it (more with the
#: pointing noise), while the thinnest pipe worth fitting spreads its shots by about a third
#: of its diameter (7 mm for a 21 mm NPS 1/2 pipe).
LINE_SPREAD_SIGMAS = 2.0


#: An object whose points span less than this (metres) and lie on a line within the noise is
#: a stuck head's shots at one spot or a scan in metres declared in millimetres: the refusal
#: names both.
UNIT_SLIP_EXTENT = 0.05


def _require_spread_beyond_noise(
    points: np.ndarray, kind: str, limit: float, assumed: bool = False, centred=None
) -> None:
    """Raise FitError when the points (n, 3) metres lie within ``limit`` (metres; the range
    noise times ``LINE_SPREAD_SIGMAS``, or the prior noise when the scan gives no sigma and
    ``assumed``) of one line: no surface is measured, whatever primitive the fit would return
    (a cylinder of a few millimetres around the line, a plane turned anyhow about it).
    ``centred``: ``points - points.mean(axis=0)`` when the caller has it already."""
    if centred is None:
        centred = points - points.mean(axis=0)
    # RMS spread along the principal directions, largest first: the roots of the scatter
    # matrix's eigenvalues (the centred points' singular values / sqrt(n), at a third the cost).
    scatter = centred.T @ centred / len(points)
    spread = np.sqrt(np.maximum(eigvalsh(scatter)[::-1], 0.0))
    if spread[1] <= limit:
        what = kind_phrase(kind)
        noise = (
            f"the {limit * 1000:.3g} mm noise assumed without a sensor sigma"
            if assumed
            # the limit itself, then how it is made: "within the range noise (3.5 mm)" above
            # "RMS 6.96 mm" read as a contradiction (the limit is twice the noise)
            else f"{limit * 1000:.3g} mm ({LINE_SPREAD_SIGMAS:g} x the range noise, "
            f"{limit / LINE_SPREAD_SIGMAS * 1000:.3g} mm)"
        )
        extent = float((points.max(axis=0) - points.min(axis=0)).max())
        units = (
            f" The whole object spans {extent * 1000:.3g} mm: a pan-tilt head stuck on one"
            ' spot, or a file whose numbers are metres (or feet) under other "units".'
            if extent < UNIT_SLIP_EXTENT
            else ""
        )
        raise FitError(
            f"The points lie within {noise} of one line (RMS {spread[1] * 1000:.3g} mm across "
            f"it); {what} needs points spread over its surface"
            + (
                " (give sensor.range_sigma if the range finder is more precise)."
                if assumed
                else "."
            )
            + units,
            where="points",
        )


#: A fit whose size is known only to more than this fraction of itself (one standard error),
#: or whose axis only to more than ``UNDETERMINED_AXIS_DEG``, is reported as not determined by
#: its points (the weak-geometry compliance rule flags far milder cases).
UNDETERMINED_RELATIVE = 0.5
UNDETERMINED_AXIS_DEG = 30.0


#: A cylinder or sphere whose radius' standard error exceeds this fraction of the radius is
#: refused, not reported: its points lie on a nearly flat strip or cap, and the least-squares
#: radius can be anything up to kilometres (a 60 mm pipe 10 m away seen by two shots a raster
#: row came out r 4.3 km with an infinite standard error), which no CAD model should carry.
#: Between ``UNDETERMINED_RELATIVE`` and this the fit stands with a note.
REFUSED_RELATIVE = 1.0


#: A radius over this many times the extent of the fit's inliers (across a cylinder's axis,
#: where it curves) makes them a nearly flat patch of it, where their plane is the rival
#: :func:`_refuse_unknown_radius` compares.
_PLANE_LIKE_RADIUS = 3.0


def _refuse_unknown_radius(result: FitResult, points: np.ndarray) -> None:
    """Raise FitError when the fit's radius is not known to within its own size
    (``REFUSED_RELATIVE``), or when, wider than ``_PLANE_LIKE_RADIUS`` times its inliers'
    extent (across a cylinder's axis: :func:`asbuilt.fit._common.extent_of`), it does not
    explain them (``points`` (n, 3) metres, the rows of ``result``)
    significantly more closely than their plane does.

    The second test is the first without its linearisation: a curvature ``k`` known to
    ``s_k`` lowers the sum of squares below the plane's by about ``(k / s_k)^2 sigma^2``, and
    ``s_k / k`` is the radius's relative standard error. On a flat patch the Gauss-Newton
    search can stop at a radius of kilometres whose local standard error looks small (a 3 m
    wall fitted r 11.5 km +-19%, with a larger sum of squares than its plane). The decrease
    must pass the tests of :func:`asbuilt.fit._curvature.curvature_measured` (chi-square at
    the noise level, F against the shots' scatter when wider, at tail ``CURVATURE_TAIL``, and
    again without the shots farthest off the plane).
    """
    radius = getattr(result.primitive, "radius", None)
    stderr = (result.stderr or {}).get("radius")
    if radius is None or stderr is None:
        return
    best = radius_text(radius)
    if stderr > REFUSED_RELATIVE * radius:
        spread = "+-inf" if not np.isfinite(stderr) else f"+-{stderr / radius:.0%}"
        why = f"one standard error {spread}"
    else:
        kept = points[result.inliers]
        if len(kept) < 4 or not result.sigma > 0:
            return
        across = getattr(result.primitive, "axis", None)  # a cylinder's; None for a sphere
        if radius <= _PLANE_LIKE_RADIUS * extent_of(kept, across):
            return  # curved over the points: their plane is no rival
        params = len(result.covariance) if result.covariance is not None else 4
        if curvature_measured(kept, result.residuals[result.inliers], result.sigma, params):
            return
        why = "a plane fits the points about as closely"
    reach = (result.diagnostics or {}).get("radius_reach")
    shape = (
        f"they lie on two lines along it, which radii up to {reach * 1000:.0f} mm fit as well."
        " Take a third raster line across it"
        if reach is not None
        else "they lie on a nearly flat strip or patch of it (a wall, or the flat or dished end"
        " of a drum or tank seen end-on, not its side). Shoot across more of its surface (a"
        " drum's side from a station beside it)"
    )
    raise FitError(
        f"These points do not determine the {result.kind}'s radius (best fit r {best}, {why}): "
        f"{shape}, or check its kind.",
        where="points",
    )


def _undetermined(result: FitResult) -> str | None:
    """A note when the points do not determine the fitted primitive (standard errors of the
    order of the values themselves), else None."""
    stderr, primitive = result.stderr or {}, result.primitive
    reasons = []
    radius = getattr(primitive, "radius", None)
    if radius is not None and stderr.get("radius") is not None:
        if not stderr["radius"] <= UNDETERMINED_RELATIVE * radius:
            reasons.append(f"radius +-{stderr['radius'] / radius:.0%}")
    sizes = getattr(primitive, "size", None)
    if sizes is not None and stderr.get("size") is not None:
        observed = result.observed if result.observed is not None else (True,) * len(sizes)
        relative = [se / size for se, size, seen in zip(stderr["size"], sizes, observed) if seen]
        if relative and not max(relative) <= UNDETERMINED_RELATIVE:
            reasons.append(f"size +-{max(relative):.0%}")
    axis_deg = stderr.get("axis_deg")
    if axis_deg is not None and not axis_deg <= UNDETERMINED_AXIS_DEG:
        reasons.append(f"axis +-{axis_deg:.0f} deg")
    # A cuboid's three rotations: seven shots on one face can leave it turned anyhow in-plane.
    turns = [float(v) for v in stderr.get("axes_deg") or () if v is not None]
    if turns and not max(turns) <= UNDETERMINED_AXIS_DEG:
        reasons.append(f"orientation +-{max(turns):.0f} deg")
    if not reasons:
        return None
    return (
        f"These points do not determine the {result.kind} (one standard error: "
        f"{', '.join(reasons)}); measure more of its surface, or check its kind."
    )


@functools.cache
def _accepts_viewpoint(function) -> bool:
    return "viewpoint" in inspect.signature(function).parameters


def fit_object(
    obj: ScanObject,
    *,
    sigma: float | None = None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    viewpoint=None,
) -> ObjectFit:
    """Fit the primitive a scan object asks for.

    Parameters
    ----------
    obj : ScanObject
        Its ``points`` shape (n, 3) metres and ``kind``.
    sigma : float, optional, metres
        Sensor range noise (usually ``scan.sensor.range_sigma``).
    tolerances : Tolerances
        Numerical tolerances.
    viewpoint : array_like, shape (3,), metres, optional
        The sensor's position (usually ``scan.sensor.position``).

    Returns
    -------
    ObjectFit
        The object, its :class:`FitResult` and the requested kind.

    Raises
    ------
    FitError
        Located at the object, e.g. ``objects[2] (P3): <why the fit failed>``.
    """
    try:
        result = fit_points(
            obj.kind, obj.points, sigma=sigma, tolerances=tolerances, viewpoint=viewpoint
        )
        brackets = edge_brackets(obj)
        if brackets is not None:
            # A bound an edge-bisection hit pins lies within the bracket the session ended on.
            result = widen_pinned(result, obj.points, *brackets, viewpoint)
        beyond = beyond_window(obj)
        if beyond is not None:
            # A size an acquisition session saw run on past the window is a lower bound.
            view = None if viewpoint is None else np.asarray(viewpoint, dtype=np.float64)
            result = open_ends(result, obj.points, beyond, view)
    except FitError as exc:
        # a field of the scan's object as the scan loader names it: "objects[3] (P4).points"
        object_field = exc.where in ("points", "kind")
        where = f"{obj.where}.{exc.where}" if object_field else located(None, obj.where, exc.where)
        raise FitError(exc.message, source=exc.source, where=where) from exc
    return ObjectFit(object=obj, result=result, requested=obj.kind)


#: At most this many other refused objects are named in the error when no object of a scan
#: could be fitted (a line a person reads; the count says how many there are in all).
NAMED_FAILURES = 5


def fit(
    scan: Scan,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    *,
    progress: Progress | None = None,
    strict: bool = False,
    words: LabelWords = DEFAULT_WORDS,
) -> FitReport:
    """Fit every object of a scan, in the scan's order.

    An object whose fit is refused (points seen edge-on, shots no primitive of its kind
    explains...) does not stop the others: it is recorded in ``FitReport.failures`` with its
    located one-line :class:`~asbuilt.errors.FitError`, and the other objects are fitted.

    Parameters
    ----------
    scan : Scan
        A loaded scan (points in metres); ``scan.sensor.range_sigma`` (metres), when given, is
        the noise level every fit uses, and each object's station (else ``scan.sensor.position``)
        the viewpoint.
    tolerances : Tolerances
        Numerical tolerances.
    progress : callable, optional
        Called as ``progress(done, total, object_id)`` after each object, fitted or refused
        (for progress bars).
    strict : bool
        Raise the first refused object's FitError at once instead of recording it (the
        behaviour before failures were recorded).
    words : LabelWords
        The vocabulary that marks a cylinder as a vessel or structure by its label or group
        (a rules file's :attr:`~asbuilt.rules.RulesConfig.label_words`): its notes and refusal
        then name it by its noun ("the far side of the tank"), not "pipe".

    Returns
    -------
    FitReport
        One :class:`ObjectFit` per fitted object and one :class:`FitFailure` per refused one.

    Raises
    ------
    FitError
        Located at the scan file and object (``scan.json: objects[2] (P3): ...``): with
        ``strict``, the first refused object; without, only when *no* object could be fitted
        (the first object's reason, and how many others were refused too).
    """
    sigma = scan.sensor.range_sigma
    fits, failures = [], []
    total = len(scan.objects)
    for done, obj in enumerate(scan.objects, start=1):
        try:
            fits.append(
                fit_object(
                    obj, sigma=sigma, tolerances=tolerances, viewpoint=obj.viewpoint(scan.sensor)
                )
            )
        except FitError as exc:
            error = FitError(exc.message, source=scan.source, where=exc.where)
            failure = FitFailure(object=obj, error=error)
            if strict:
                raise named_failure(failure, words).error from exc
            failures.append(failure)
        if progress is not None:
            progress(done, total, obj.id)
    if failures and not fits:
        raise NothingFittedError([named_failure(f, words) for f in failures])
    report = FitReport(scan=scan, fits=tuple(fits), failures=tuple(failures))
    # Linked objects that are one pipe seen from two stations are fitted as one.
    report = fuse_station_views(report, tolerances)

    def refit(obj: ScanObject) -> ObjectFit:
        try:
            return fit_object(
                obj, sigma=sigma, tolerances=tolerances, viewpoint=obj.viewpoint(scan.sensor)
            )
        except FitError as exc:
            raise FitError(exc.message, source=scan.source, where=exc.where) from exc

    # A pipe fitted through a raster line of its neighbour's shots is fitted again without it.
    report = without_neighbour_shots(report, refit, tolerances)
    return named_report(report, words)


class NothingFittedError(FitError):
    """No object of a scan could be fitted: the first refused object's located error, naming
    the others; ``failures`` holds every :class:`FitFailure` (the CLI prints each one's line)."""

    def __init__(self, failures: list[FitFailure]):
        first = failures[0].error
        others = [f.object.id for f in failures[1:]]
        message = first.message
        if others:
            named = ", ".join(others[:NAMED_FAILURES])
            if len(others) > NAMED_FAILURES:
                named += ", ..."
            if len(others) == 1:
                others_were = f"the other object ({named}) was"
            else:
                others_were = f"the {len(others)} other objects ({named}) were"
            message += f" No object of the scan could be fitted: {others_were} refused too."
        super().__init__(message, source=first.source, where=first.where)
        self.failures = tuple(failures)


class _CallableModule(types.ModuleType):
    """``asbuilt.fit`` is both this subpackage and the function :func:`fit`.

    Importing any ``asbuilt.fit.*`` module binds the *module* to ``asbuilt.fit``, so the module
    itself must be callable for ``asbuilt.fit(scan)`` (the documented API) to keep working.
    """

    def __call__(
        self, scan: Scan, tolerances: Tolerances = DEFAULT_TOLERANCES, **kwargs
    ) -> FitReport:
        return fit(scan, tolerances, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
