"""Scan to as-built model in one call: fit, merge, check (what ``asbuilt model`` runs).

Every stage is a pure function of the previous one's output; this module only chains them:
:func:`asbuilt.fit.fit` (one primitive per scanned object), :func:`asbuilt.merge.merge_model`
(pipes snapped to catalog sizes and joined into spools with fittings), and
:func:`asbuilt.rules.check_model` (compliance findings). NumPy/SciPy only: no CAD kernel.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib import import_module
from pathlib import Path

from asbuilt.model import Model, model_from_fits
from asbuilt.scan.model import Scan
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

__all__ = ["build_model", "stage_available"]


def _optional(module: str, name: str):
    """``module.name``, or None when the module is not part of this build."""
    try:
        return getattr(import_module(module), name)
    except ModuleNotFoundError as exc:
        if exc.name is not None and module.startswith(exc.name):
            return None
        raise


def stage_available(stage: str) -> bool:
    """Whether the optional stage ``"merge"`` or ``"rules"`` is part of this build."""
    if stage == "merge":
        return _optional("asbuilt.merge", "merge_model") is not None
    if stage == "rules":
        return _optional("asbuilt.rules", "check_model") is not None
    raise ValueError(f"unknown stage {stage!r}; use 'merge' or 'rules'")


def build_model(
    scan: Scan,
    *,
    catalog=None,
    tolerances: Tolerances = DEFAULT_TOLERANCES,
    schedule: str | None = None,
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
    tolerances : Tolerances
    schedule : str, optional
        Pipe wall schedule (e.g. ``"STD"``, ``"40"``): pipes become hollow solids.
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

    report = fit(scan, tolerances, progress=progress)
    merge_model = _optional("asbuilt.merge", "merge_model") if merge else None
    if merge_model is not None:
        model = merge_model(report, catalog=catalog, tolerances=tolerances, schedule=schedule)
    else:
        model = model_from_fits(report)
    check_model = _optional("asbuilt.rules", "check_model") if check else None
    if check_model is not None:
        config = rules
        if isinstance(rules, (str, Path)):
            config = import_module("asbuilt.rules").load_rules(rules)
        options = {"catalog": catalog} if catalog is not None else {}
        model = model.replace(findings=tuple(check_model(model, config, design, **options)))
    return model
