"""Scan to as-built model in one call: fit, merge, check (what ``asbuilt model`` runs).

Every stage is a pure function of the previous one's output; this module only chains them:
:func:`asbuilt.fit.fit` (one primitive per scanned object), :func:`asbuilt.merge.merge_model`
(pipes snapped to catalog sizes and joined into spools with fittings), and
:func:`asbuilt.rules.check_model` (compliance findings). NumPy/SciPy only: no CAD kernel.

An object whose fit is refused does not stop the others: it is left out of the model and
becomes an error finding (:data:`~asbuilt.findings.FIT_REFUSED_CODE`, ``fit-refused``) that
keeps its measured points (:func:`fit_refused_findings`); :func:`recheck` keeps those findings
when a model is checked again. So does an insulated cylinder whose ``insulation`` is as thick as
its fitted radius or thicker (:func:`asbuilt.model.without_pipeless_insulation`): no pipe is left
inside to model, but the rest of the scan is.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path

import numpy as np

from asbuilt.findings import FIT_REFUSED_CODE, FIT_REFUSED_SLUG, Finding, Suggestion
from asbuilt.fit.result import FitFailure, FitReport
from asbuilt.model import (
    Model,
    insulation_refused,
    model_from_fits,
    without_pipeless_insulation,
)
from asbuilt.scan.model import Scan, kind_phrase
from asbuilt.tolerances import Tolerances
from asbuilt.units import note_in_units

__all__ = [
    "build_model",
    "catalog_file",
    "fit_refused_finding",
    "fit_refused_findings",
    "recheck",
    "refused_findings",
    "relink",
]


def fit_refused_finding(failure: FitFailure, units: str = "m") -> Finding:
    """The error finding for an object whose fit was refused.

    Parameters
    ----------
    failure : FitFailure
        The object (points shape (n, 3) metres) and its located FitError.
    units : str
        The scan's units: for inches or feet the message tells its lengths in inches and feet
        (:func:`asbuilt.units.note_in_units`), as the other findings do.

    Returns
    -------
    Finding
        Code :data:`~asbuilt.findings.FIT_REFUSED_CODE`, slug ``fit-refused``, severity
        ``error``, the object's id; the message is the fit's one-line reason (which says what to
        do); ``location`` the points' mean (3,) metres; one suggestion (not applied by
        ``--fix``) to rescan, whose ``change`` keeps the measured points:
        ``{"object": id, "kind": kind, "points": [[x, y, z], ...]}`` in metres, scan frame.
    """
    obj = failure.object
    points = np.asarray(obj.points, dtype=np.float64)
    kept = f"its {len(points)} measured points are kept with this finding"
    if insulation_refused(failure):
        # the points fit; the thickness given is what leaves nothing to model
        what = f"fitted as {kind_phrase(obj.kind)}, but not in the model: {failure.message}"
        todo = f"check {obj.id}'s insulation thickness and the file's units; {kept}"
    else:
        what = f"{_not_fitted(obj.kind)}, so it is not in the model: {failure.message}"
        todo = f"rescan {obj.id}; {kept}"
    keep = Suggestion(todo, {"object": obj.id, "kind": obj.kind, "points": points.tolist()}, False)
    return Finding(
        code=FIT_REFUSED_CODE,
        slug=FIT_REFUSED_SLUG,
        severity="error",
        objects=(obj.id,),
        message=note_in_units(what, units),
        location=points.mean(axis=0) if len(points) else None,
        suggestions=(keep,),
    )


def _not_fitted(kind: str) -> str:
    return "not fitted (kind auto)" if kind == "auto" else f"not fitted as {kind_phrase(kind)}"


def fit_refused_findings(report: FitReport) -> tuple[Finding, ...]:
    """One :func:`fit_refused_finding` per refused object of ``report``, in the scan's order."""
    return tuple(fit_refused_finding(failure, report.scan.units) for failure in report.failures)


def recheck(model: Model, config=None, design=None, *, catalog=None) -> tuple[Finding, ...]:
    """Check ``model`` against the rules again, keeping the ``fit-refused`` findings it records.

    :func:`asbuilt.rules.check_model` judges the components only; an object whose fit was
    refused is not one of them, so a re-check (``asbuilt check MODEL.json``, ``--fix``, a
    report with other rules) would forget it without this.

    Parameters
    ----------
    model : Model
        Lengths metres; ``model.findings`` may hold ``fit-refused`` findings.
    config, design, catalog
        As :func:`asbuilt.rules.check_model` takes them (None: its defaults).

    Returns
    -------
    tuple of Finding
        Sorted as :func:`asbuilt.rules.sort_findings` sorts.
    """
    from asbuilt.rules import check_model, sort_findings

    options = {"catalog": catalog} if catalog is not None else {}
    found = check_model(model, config, design, **options)
    return sort_findings((*refused_findings(model), *found))


def refused_findings(model: Model) -> tuple[Finding, ...]:
    """The ``fit-refused`` findings ``model`` records (objects not in it)."""
    return tuple(f for f in model.findings if f.code == FIT_REFUSED_CODE)


def catalog_file(catalog) -> str | None:
    """The absolute path of a catalog read from a user's file; None for a shipped catalog.

    A model records it (:attr:`~asbuilt.model.Model.catalog_file`) so that reports and exports
    made later read the same file: the catalog's name alone may name no shipped catalog, or a
    shipped one with other data.

    Parameters
    ----------
    catalog : Catalog
        As loaded by :func:`asbuilt.catalog.load_catalog`.
    """
    from asbuilt.catalog import catalog_names, load_catalog

    if catalog.name in catalog_names() and load_catalog(catalog.name) is catalog:
        return None  # the shipped one (load_catalog caches shipped catalogs)
    path = Path(catalog.path) if catalog.path else None
    return str(path.resolve()) if path is not None and path.is_file() else None


def build_model(
    scan: Scan,
    *,
    catalog=None,
    tolerances: Tolerances | None = None,
    schedule: str | None = None,
    elbow_radius: str = "long",
    rules=None,
    design=None,
    merge: bool = True,
    check: bool = True,
    progress: Callable[[int, int, str], None] | None = None,
) -> Model:
    """Fit every object of ``scan``, merge the pipes into spools, check the result.

    Parameters
    ----------
    scan : Scan
        Points in metres.
    catalog : str, Path or Catalog, optional
        Pipe catalog for snapping sizes (name or file); default the merger's (ASME B36.10M).
    tolerances : Tolerances, optional
        Numerical tolerances for fitting and merging. Default: the rules file's (its
        ``[tolerances]`` table over :data:`~asbuilt.tolerances.DEFAULT_TOLERANCES`), so that
        ``asbuilt model --rules F`` and ``asbuilt check --rules F`` merge alike.
    schedule : str, optional
        Pipe wall schedule (e.g. ``"STD"``, ``"40"``): pipes become hollow solids.
    elbow_radius : {"long", "short"}
        ASME B16.9 elbow radius for the fittings merging places.
    rules : str, Path or RulesConfig, optional
        Compliance rules; default the shipped rules.
    design : str, Path or Design, optional
        A design to compare with (design-deviation rules).
    merge : bool
        Merge pipes into spools; False keeps one component per fitted object.
    check : bool
        Run the compliance rules (findings go into ``model.findings``).
    progress : callable(done, total, object_id), optional
        Called after each object is fitted.

    Returns
    -------
    Model
        Metres, scan frame; ``findings`` sorted by severity; ``catalog`` names the catalog
        (unmerged too, when one is given); ``catalog_file`` set when the catalog came from a
        user's file. An object whose fit was refused is not among the
        components: it is an error finding ``fit-refused`` (also with ``check=False``), and
        ``model.fits.failures`` holds its FitError.

    Raises
    ------
    FitError, CatalogError, RulesConfigError, DesignError
        Located one-line errors for bad input; a FitError
        (:class:`~asbuilt.fit.NothingFittedError`) only when no object could be fitted.
    """
    from asbuilt.fit import fit
    from asbuilt.merge import resolve_catalog
    from asbuilt.rules import RulesConfig, load_rules

    config = rules if isinstance(rules, RulesConfig) else load_rules(rules)
    if tolerances is None:
        tolerances = config.tolerances
    if merge or catalog is not None:
        catalog = resolve_catalog(catalog)  # once: the merge, the rules and the model share it
    report = _modelled(fit(scan, tolerances, progress=progress, words=config.label_words))
    if merge:
        model = _merged(report, catalog, tolerances, schedule, elbow_radius, config.label_words)
    else:
        model = model_from_fits(report)
        if catalog is not None:  # the size rules judge against it: the model must say which
            model = model.replace(catalog=catalog.name, catalog_file=catalog_file(catalog))
    model = model.replace(findings=fit_refused_findings(report))
    if check:
        model = model.replace(findings=recheck(model, config, design, catalog=catalog))
    return model


def _modelled(report: FitReport) -> FitReport:
    """``report`` with the objects whose insulation leaves no pipe inside refused
    (:func:`~asbuilt.model.without_pipeless_insulation`); as for fits, nothing left to model is
    bad input (:class:`~asbuilt.fit.NothingFittedError`)."""
    from asbuilt.fit import NothingFittedError

    refused = without_pipeless_insulation(report)
    if refused is not report and not refused.fits:  # an empty scan stays an empty model
        raise NothingFittedError(list(refused.failures))
    return refused


def _merged(report: FitReport, catalog, tolerances, schedule, elbow_radius, words) -> Model:
    """The merged model of ``report`` (its scan and fits attached; no findings yet), pipes told
    from vessels by ``words`` (:class:`asbuilt.merge.LabelWords`)."""
    from asbuilt.merge import merge_model

    model = merge_model(
        _without_refused_links(report),
        catalog=catalog,
        tolerances=tolerances,
        schedule=schedule,
        elbow_radius=elbow_radius,
        words=words,
    )
    return model.replace(catalog_file=catalog_file(catalog), scan=report.scan, fits=report)


def _spool_of(model: Model, object_id: str) -> str | None:
    for comp in model.components:
        if object_id in comp.sources and comp.spool:
            return comp.spool
    return None


def _model_schedule(model: Model) -> str | None:
    """The one wall schedule of the model's pipes, else None (merging then builds solid pipes)."""
    schedules = {c.schedule for c in model.components if c.type == "pipe"}
    return schedules.pop() if len(schedules) == 1 else None


def _model_elbow_radius(model: Model) -> str:
    """``"short"`` when the model's elbows are short radius (bend radius about one OD, ASME
    B16.9; long radius is 1.5 OD), else ``"long"``."""
    from asbuilt.model import Bend

    ratios = [
        c.geometry.bend_radius / (2.0 * c.geometry.outer_radius)
        for c in model.components
        if c.type == "elbow" and isinstance(c.geometry, Bend)
    ]
    return "short" if ratios and max(ratios) < 1.25 else "long"


def relink(
    model: Model,
    links,
    *,
    catalog=None,
    tolerances: Tolerances | None = None,
    rules=None,
    design=None,
) -> Model:
    """``model`` merged again with scan links added: accepting a suggestion to link two pipes
    (a ``"link"`` change, :data:`asbuilt.rules.fixes.LINK_FIELD`).

    Parameters
    ----------
    model : Model
        A merged model with its scan (``model.scan``; a model document stores it). Its fits are
        kept when it has them (links do not change a fit), else the scan is fitted again.
    links : iterable of (str, str)
        Scan object ids to link.
    catalog : str, Path or Catalog, optional
        Default the model's (its user file, else its name). The pipes' schedule and the
        elbows' radius (long or short) are the model's.
    tolerances, rules, design
        As for :func:`build_model`.

    Returns
    -------
    Model
        Merged and checked again.

    Raises
    ------
    SuggestionError
        The model has no scan, a link names an object the scan does not have, or merging does
        not join a linked pair even so (the finding's suggestion was wrong: its reason is in
        the model's notes).
    """
    from asbuilt.errors import SuggestionError
    from asbuilt.fit import fit
    from asbuilt.merge import resolve_catalog
    from asbuilt.rules import RulesConfig, load_rules

    scan = model.scan
    if scan is None:
        raise SuggestionError(
            "linking objects needs the scan, and this model does not store it; check the scan "
            "file itself"
        )
    links = [tuple(str(x) for x in pair) for pair in links]
    ids = {obj.id for obj in scan.objects}
    for a, b in links:
        for oid in (a, b):
            if oid not in ids:
                raise SuggestionError(f"cannot link {a} and {b}: the scan has no object {oid}")
    new = tuple(p for p in links if p not in scan.links and p[::-1] not in scan.links)
    scan = dataclasses.replace(scan, links=scan.links + new)
    config = rules if isinstance(rules, RulesConfig) else load_rules(rules)
    if tolerances is None:
        tolerances = config.tolerances
    catalog = resolve_catalog(
        catalog if catalog is not None else (model.catalog_file or model.catalog)
    )
    if model.fits is not None:
        report = dataclasses.replace(model.fits, scan=scan)
    else:
        report = _modelled(fit(scan, tolerances, words=config.label_words))
    relinked = _merged(
        report,
        catalog,
        tolerances,
        _model_schedule(model),
        _model_elbow_radius(model),
        config.label_words,
    )
    relinked = relinked.replace(findings=fit_refused_findings(report))
    for a, b in links:
        spool = _spool_of(relinked, a)
        if spool is None or spool != _spool_of(relinked, b):
            raise SuggestionError(
                f"linking {a} and {b} does not join them: merging finds no elbow or in-line "
                "joint between their ends; scan both up to their ends instead"
            )
    return relinked.replace(findings=recheck(relinked, config, design, catalog=catalog))


def _without_refused_links(report: FitReport) -> FitReport:
    """``report`` with the scan's links to refused objects left out, for merging: such a link
    can join nothing (the object has no geometry), and the ``fit-refused`` finding says why."""
    refused = {failure.object.id for failure in report.failures}
    scan = report.scan
    if not refused or not any(a in refused or b in refused for a, b in scan.links):
        return report
    links = tuple(link for link in scan.links if not refused.intersection(link))
    return dataclasses.replace(report, scan=dataclasses.replace(scan, links=links))
