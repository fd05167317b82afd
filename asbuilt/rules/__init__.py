"""Compliance checking: a spell checker for as-built models.

::

    from asbuilt.rules import check_model, load_rules, apply_fixes, RULES
    findings = check_model(model)                    # shipped rules (asbuilt/data/rules.toml)
    findings = check_model(model, load_rules("project-rules.toml"), design="design.json")
    fixed, changes = apply_fixes(model, findings)    # accept every unambiguous suggestion
    chosen = choose_suggestions(findings, ["AB101@P5:2"])  # or the ones the user picks
    fixed, changes = apply_suggestions(model, chosen)

Findings are data (:class:`asbuilt.findings.Finding`), sorted by severity then position. Each
rule is uncertainty-aware: a violation is an error only when it exceeds the allowed value by more
than ``k_sigma`` (2) standard errors; a measurement too uncertain to decide gives an
``unverifiable`` warning that says what to scan. docs/rules.md documents every rule.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from asbuilt.findings import SEVERITIES, Finding
from asbuilt.model import Model

from . import alignment, clash, joints, quality, sizes
from . import design as design_rules
from ._catalog import SizeTable, size_table
from ._context import Context
from .accept import choose_suggestions, finding_key
from .config import RulesConfig, load_rules, loads_rules
from .fixes import apply_fixes, apply_suggestions
from .registry import RULES, Rule, match_rules, rule
from .waivers import apply_waivers

__all__ = [
    "RULES",
    "Rule",
    "RulesConfig",
    "SizeTable",
    "load_rules",
    "loads_rules",
    "check_model",
    "apply_fixes",
    "apply_suggestions",
    "choose_suggestions",
    "finding_key",
    "sort_findings",
    "rule",
    "match_rules",
]

_NEEDS_TABLE = {"sizes", "joints"}
_FAMILIES = {
    "sizes": sizes,
    "alignment": alignment,
    "joints": joints,
    "quality": quality,
    "clash": clash,
}
_DESIGN_SLUGS = ("design-deviation", "missing-component", "extra-component")


def _sort_key(finding: Finding):
    loc = finding.location
    position = (0, *np.round(loc, 6)) if loc is not None else (1, 0.0, 0.0, 0.0)
    return (SEVERITIES.index(finding.severity), position, finding.code, finding.objects)


def sort_findings(findings) -> tuple[Finding, ...]:
    """Findings sorted by severity (errors first), then position (x, y, z), code and objects."""
    return tuple(sorted(findings, key=_sort_key))


def _built_with(model: Model):
    """The catalog ``model`` was built with (:func:`asbuilt.catalog.model_catalog`: its recorded
    user file first, else the shipped catalog it names), or None when it names none.

    Raises
    ------
    CatalogError
        The model names a catalog that cannot be read: its size rules need it.
    """
    from asbuilt.catalog import model_catalog
    from asbuilt.errors import CatalogError

    found, problem = model_catalog(model)
    if problem is None:
        return found
    if model.catalog_file:
        what = f"its catalog file {model.catalog_file} cannot be read"
    else:
        what = f"it names catalog {model.catalog!r}, no shipped one, without recording its file"
    raise CatalogError(
        f"the model's sizes cannot be checked: {what}; give the catalog with --catalog FILE"
    )


def check_model(
    model: Model, config: RulesConfig | None = None, design=None, *, catalog=None
) -> tuple[Finding, ...]:
    """Check a model against the rules.

    Parameters
    ----------
    model : Model
        Lengths in metres; pipes ideally merged and snapped (``component.snap``).
    config : RulesConfig or path, optional
        From :func:`load_rules` (a path is loaded with it); None uses the shipped defaults.
    design : asbuilt.design.Design or path, optional
        The design to compare with (``design-deviation``, ``missing-component``,
        ``extra-component`` run only with one).
    catalog : SizeTable, catalog object or catalog name, optional
        The pipe catalog for the size rules; defaults to the one the model was built with
        (its recorded catalog file, else the shipped catalog ``model.catalog`` names).

    Returns
    -------
    tuple of Finding
        Sorted by severity, then position.

    Raises
    ------
    CatalogError
        No ``catalog`` is given and the model names one that cannot be read (a user's catalog
        whose file it does not record, or a recorded file that is gone).
    """
    if config is None or isinstance(config, (str, Path)):
        config = load_rules(config)
    if design is not None and isinstance(design, (str, Path)):
        from asbuilt.design import load_design

        design = load_design(design)
    table = size_table(catalog if catalog is not None else _built_with(model))
    ctx = Context(model=model, config=config, design=design, catalog=table)
    for r in config.active_rules():
        if r.slug in _DESIGN_SLUGS:
            continue
        check = _FAMILIES[r.family].CHECKS[r.slug]
        if r.family in _NEEDS_TABLE:
            check(ctx, table)
        else:
            check(ctx)
    if design is not None and any(config.is_active(s) for s in _DESIGN_SLUGS):
        design_rules.CHECKS["design-deviation"](ctx)
    if not config.waivers:
        return sort_findings(ctx.findings)
    ran = [
        r.slug for r in config.active_rules() if design is not None or r.slug not in _DESIGN_SLUGS
    ]
    ids = [c.id for c in model.components]
    return sort_findings(apply_waivers(ctx.findings, config.waivers, ran, ids))
