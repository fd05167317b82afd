"""Scan to as-built model in one call: fit, merge, check (what ``asbuilt model`` runs).

Every stage is a pure function of the previous one's output; this module only chains them:
:func:`asbuilt.fit.fit` (one primitive per scanned object), :func:`asbuilt.merge.merge_model`
(pipes snapped to catalog sizes and joined into spools with fittings), and
:func:`asbuilt.rules.check_model` (compliance findings). NumPy/SciPy only: no CAD kernel.
"""

from __future__ import annotations

from collections.abc import Callable

from asbuilt.model import Model, model_from_fits
from asbuilt.scan.model import Scan
from asbuilt.tolerances import Tolerances

__all__ = ["build_model"]


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
        Metres, scan frame; ``findings`` sorted by severity.

    Raises
    ------
    FitError, CatalogError, RulesConfigError, DesignError
        Located one-line errors for bad input.
    """
    from asbuilt.fit import fit
    from asbuilt.merge import merge_model
    from asbuilt.rules import RulesConfig, check_model, load_rules

    config = rules if isinstance(rules, RulesConfig) else load_rules(rules)
    if tolerances is None:
        tolerances = config.tolerances
    report = fit(scan, tolerances, progress=progress)
    if merge:
        model = merge_model(
            report,
            catalog=catalog,
            tolerances=tolerances,
            schedule=schedule,
            elbow_radius=elbow_radius,
        )
    else:
        model = model_from_fits(report)
    if check:
        findings = check_model(model, config, design, catalog=catalog)
        model = model.replace(findings=tuple(findings))
    return model
