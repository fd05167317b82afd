"""asbuilt: sparse laser range points of construction objects to as-built CAD.

The library API never prints. The main entry points::

    import asbuilt
    scan = asbuilt.load_scan("samples/spool.json")   # validated, metres inside
    report = asbuilt.fit(scan)                         # one FitResult per object
    data = asbuilt.fit_report_to_dict(report)          # what `asbuilt fit --json` prints

Importing :mod:`asbuilt` is cheap: fitting and scan loading use numpy/scipy only, and the CAD
kernel (CadQuery) is imported only by :mod:`asbuilt.cad` and :mod:`asbuilt.export`. The
subpackages are attributes without importing them first (``asbuilt.scan.scan_schema()``,
``asbuilt.rules.check_model``); each is imported when first used.
"""

from __future__ import annotations

import os as _os
from importlib import import_module

__version__ = "0.1.0"

# A wheel installs the repository's top-level drivers/ and catalogs/ folders as the subpackages
# asbuilt.drivers and asbuilt.catalogs. In a source checkout (editable install, or tests run
# from the repository) they stand beside this package instead, so look there too.
_root = _os.path.dirname(_os.path.dirname(_os.path.abspath(__file__)))
if _os.path.isfile(_os.path.join(_root, "pyproject.toml")) and _os.path.isfile(
    _os.path.join(_root, "drivers", "__init__.py")
):
    __path__.append(_root)  # noqa: F821 (the package's own __path__)

# Lazy attributes: name -> module that defines it (PEP 562), so `import asbuilt` stays fast.
_LAZY = {
    "load_scan": "asbuilt.scan",
    "loads_scan": "asbuilt.scan",
    "Scan": "asbuilt.scan",
    "ScanObject": "asbuilt.scan",
    "fit": "asbuilt.fit",
    "fit_object": "asbuilt.fit",
    "fit_points": "asbuilt.fit",
    "FitResult": "asbuilt.fit",
    "FitReport": "asbuilt.fit",
    "fit_report_to_dict": "asbuilt.fit.output",
    "Tolerances": "asbuilt.tolerances",
    "DEFAULT_TOLERANCES": "asbuilt.tolerances",
    "AsbuiltError": "asbuilt.errors",
    "Model": "asbuilt.model",
    "model_from_fits": "asbuilt.model",
}

#: The documented subpackages and modules (docs/architecture.md), reachable after a plain
#: ``import asbuilt`` (``asbuilt.scan.scan_schema()``) and imported on first use, so that
#: ``import asbuilt`` stays cheap and only ``asbuilt.cad`` / ``asbuilt.export`` load CadQuery.
_SUBMODULES = frozenset(
    {
        "atomic",
        "cad",
        "catalog",
        "catalogs",
        "cli",
        "design",
        "drivers",
        "errors",
        "export",
        "findings",
        "fit",
        "merge",
        "model",
        "pipeline",
        "primitives",
        "report",
        "rules",
        "scan",
        "sim",
        "tolerances",
        "units",
    }
)

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name]), name)
    elif name in _SUBMODULES:
        value = import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module 'asbuilt' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY, *_SUBMODULES})
