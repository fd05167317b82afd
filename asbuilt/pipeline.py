"""Scan to as-built model in one call: fit, merge, check (what ``asbuilt model`` runs).

Every stage is a pure function of the previous one's output; this module only chains them:
:func:`asbuilt.fit.fit` (one primitive per scanned object), :func:`asbuilt.merge.merge_model`
(pipes snapped to catalog sizes and joined into spools with fittings), and
:func:`asbuilt.rules.check_model` (compliance findings). NumPy/SciPy only: no CAD kernel.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from asbuilt.model import Model, model_from_fits
from asbuilt.scan.model import Scan
from asbuilt.tolerances import Tolerances

__all__ = ["build_model", "catalog_file"]


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
        Metres, scan frame; ``findings`` sorted by severity; ``catalog_file`` set when the
        catalog came from a user's file.

    Raises
    ------
    FitError, CatalogError, RulesConfigError, DesignError
        Located one-line errors for bad input.
    """
    from asbuilt.fit import fit
    from asbuilt.merge import merge_model, resolve_catalog
    from asbuilt.rules import RulesConfig, check_model, load_rules

    config = rules if isinstance(rules, RulesConfig) else load_rules(rules)
    if tolerances is None:
        tolerances = config.tolerances
    if merge or catalog is not None:
        catalog = resolve_catalog(catalog)  # once: the merge, the rules and the model share it
    report = fit(scan, tolerances, progress=progress)
    if merge:
        model = merge_model(
            report,
            catalog=catalog,
            tolerances=tolerances,
            schedule=schedule,
            elbow_radius=elbow_radius,
        )
        model = model.replace(catalog_file=catalog_file(catalog))
    else:
        model = model_from_fits(report)
    if check:
        findings = check_model(model, config, design, catalog=catalog)
        model = model.replace(findings=tuple(findings))
    return model
