"""The few catalog facts the rules need, read through one small adapter.

:class:`SizeTable` holds a pipe catalog's sizes (nominal, DN, outside diameter in metres) and,
when known, the 90 degree long-radius elbow centre-to-end of each size. :func:`size_table` builds
one from a :class:`SizeTable`, a catalog object of :mod:`asbuilt.catalog`, or a catalog name.
:meth:`SizeTable.find` reads a size written any way :func:`asbuilt.catalog.parse_nominal`
understands (``6"``, ``NPS 6``, ``DN150``...) as one of the table's sizes, and
:meth:`SizeTable.nps_of` gives a size's NPS (from the catalog's ``nps`` column when it has one),
so that NPS-based tolerances apply to DN catalogs too. :func:`reducing_tee_made` says whether
a fittings catalog makes a reducing-outlet tee of two sizes (the list shipped beside it as
``catalogs/<fittings>-tees.toml``), as :func:`asbuilt.merge.reducers.reducer_made` does for
reducers.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from fractions import Fraction
from functools import cache
from importlib import resources

import numpy as np

from asbuilt.catalog import parse_nominal, size_by_system

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["SizeTable", "size_table", "nps_value", "tee_outlets", "reducing_tee_made"]


def nps_value(nominal: str) -> float | None:
    """The numeric value of a nominal size written like ``"1 1/2"``, ``"1-1/2"`` or ``"4"``."""
    text = str(nominal).strip().replace("-", " ")
    try:
        return float(sum(Fraction(part) for part in text.split()))
    except (ValueError, ZeroDivisionError):
        return None


@dataclass(frozen=True)
class SizeTable:
    """A pipe catalog's sizes.

    Attributes
    ----------
    standard : str
        The catalog's standard, for messages (``"ASME B36.10M"``).
    designation : str
        How sizes are written (``"NPS"``, ``"DN"``...).
    sizes : tuple of (str, int or None, float)
        ``(nominal, dn, od)``, the OD in metres, sorted by OD.
    elbow_lr : dict
        Nominal to the 90 degree long-radius elbow centre-to-end, metres (may be empty).
    tee_run : dict
        Nominal to the equal tee's centre-to-end of run C, metres (may be empty).
    reducer : dict
        Nominal of the large end to the concentric reducer's length H, metres (may be empty).
    nps : dict
        Nominal to the nominal pipe size in inches, from the catalog's ``nps`` column (may be
        empty: an NPS table's nominals are then read as NPS, see :meth:`nps_of`).
    fittings : str or None
        The name of the fittings catalog that goes with the pipe catalog (``"asme-b16.9"``),
        which says which reducing tees are made (:func:`reducing_tee_made`).
    fittings_standard : str or None
        That fittings catalog's standard, for messages (``"ASME B16.9"``).
    """

    standard: str
    designation: str
    sizes: tuple[tuple[str, int | None, float], ...]
    elbow_lr: dict = field(default_factory=dict)
    nps: dict = field(default_factory=dict)
    tee_run: dict = field(default_factory=dict)
    reducer: dict = field(default_factory=dict)
    fittings: str | None = None
    fittings_standard: str | None = None

    def __post_init__(self):
        object.__setattr__(self, "sizes", tuple(sorted(self.sizes, key=lambda s: s[2])))

    def label(self, nominal: str) -> str:
        """``"NPS 4"`` for nominal ``"4"``."""
        return f"{self.designation} {nominal}".strip()

    def nps_of(self, nominal: str) -> float | None:
        """The NPS (inches) of the table's size ``nominal``: its catalog ``nps`` value, else the
        nominal itself read as a number in an NPS table; None when unknown (a DN size of a
        catalog without an ``nps`` column)."""
        if nominal in self.nps:
            return float(self.nps[nominal])
        return nps_value(nominal) if self.designation.upper() == "NPS" else None

    def find(self, text) -> str | None:
        """The table's nominal of a size written ``text``, or None when it names no size here.

        ``text`` is the table's own nominal (``"150"``), or any form
        :func:`asbuilt.catalog.parse_nominal` reads: ``6"`` and ``NPS 6`` by NPS, ``DN150`` by
        DN, a bare number in the table's designation first (DN for a DN table, else NPS), then
        the other. A schedule or rating after the size is ignored.
        """
        if text is None:
            return None
        text = str(text).strip()
        for nominal, _, _ in self.sizes:
            if nominal == text:
                return nominal
        hint = parse_nominal(text)
        if hint is None:
            return None

        def by_dn(value):
            return next(
                (n for n, dn, _ in self.sizes if dn is not None and abs(dn - value) < 1e-6), None
            )

        def by_nps(value):
            return next(
                (
                    n
                    for n, _, _ in self.sizes
                    if (nps := self.nps_of(n)) is not None and abs(nps - value) < 1e-6
                ),
                None,
            )

        return size_by_system(hint, self.designation, by_nps, by_dn)

    def od(self, nominal: str) -> float | None:
        """The OD (metres) of a nominal size or an operator's hint (``4"``, ``NPS 4``, ``DN100``),
        read as :meth:`find` reads it; None when it names no size of the table."""
        found = self.find(nominal)
        return None if found is None else next(od for n, _, od in self.sizes if n == found)

    def nominal_for(self, od: float) -> str | None:
        """The nominal size whose OD equals ``od`` within 0.05 mm."""
        for nominal, _, size_od in self.sizes:
            if abs(size_od - od) < 5e-5:
                return nominal
        return None

    def nearest(self, od: float, count: int = 2) -> list[tuple[str, float, float]]:
        """The ``count`` sizes nearest to ``od`` (metres): ``(nominal, od, od - size od)``."""
        ranked = sorted(self.sizes, key=lambda s: abs(s[2] - od))[: max(int(count), 0)]
        return [(n, s, od - s) for n, _, s in ranked]

    def within(self, od: float, tolerance: float) -> list[tuple[str, float]]:
        """Sizes whose OD is within ``tolerance`` metres of ``od``: ``(nominal, od)``."""
        return [(n, s) for n, _, s in self.sizes if abs(s - od) <= tolerance]


def _from_catalog(catalog) -> SizeTable | None:
    """Conversion of an :class:`asbuilt.catalog.Catalog` (sizes in metres, fittings by size)."""
    rows = getattr(catalog, "sizes", None)
    if not rows:
        return None
    sizes, elbows, nps, tees, reducers = [], {}, {}, {}, {}
    fitting = getattr(catalog, "fitting", None)
    for row in rows:
        nominal, od = getattr(row, "nominal", None), getattr(row, "od", None)
        if nominal is None or od is None:
            continue
        dn = getattr(row, "dn", None)
        sizes.append((str(nominal), None if dn is None else int(dn), float(od)))
        if getattr(row, "nps", None) is not None:
            nps[str(nominal)] = float(row.nps)
        fit_row = fitting(row) if callable(fitting) else None
        dims = (getattr(fit_row, "dims", None) or {}) if fit_row else {}
        for column, into in (("elbow90_lr", elbows), ("tee_run", tees), ("reducer", reducers)):
            value = dims.get(column)
            if value is not None and np.isfinite(value):
                into[str(nominal)] = float(value)
    if not sizes:
        return None
    standard = getattr(catalog, "standard", None) or getattr(catalog, "name", "the catalog")
    designation = getattr(catalog, "designation", None) or "NPS"
    fitting_table = getattr(catalog, "fitting_table", None)
    fittings_name = getattr(fitting_table, "name", None) or getattr(catalog, "fittings_name", None)
    fittings_standard = getattr(fitting_table, "standard", None) or fittings_name
    return SizeTable(
        str(standard),
        str(designation),
        tuple(sizes),
        elbows,
        nps,
        tee_run=tees,
        reducer=reducers,
        fittings=None if fittings_name is None else str(fittings_name),
        fittings_standard=None if fittings_standard is None else str(fittings_standard),
    )


def size_table(catalog) -> SizeTable | None:
    """A :class:`SizeTable` from a SizeTable, a catalog object or a catalog name (None if none)."""
    if catalog is None or isinstance(catalog, SizeTable):
        return catalog
    if isinstance(catalog, (str, os.PathLike)):
        from asbuilt.catalog import load_catalog

        catalog = load_catalog(catalog)
    table = _from_catalog(catalog)
    if table is not None and not np.all(np.isfinite([s[2] for s in table.sizes])):
        return None
    return table


@cache
def tee_outlets(fittings: str | None) -> dict[str, frozenset[str]] | None:
    """The ``{run: outlets}`` of the reducing-outlet tees the shipped fittings table
    ``fittings`` (its name) makes, or None when no tee list ships with it."""
    if not fittings:
        return None
    resource = resources.files("asbuilt.catalogs") / f"{fittings}-tees.toml"
    if not resource.is_file():
        return None
    table = tomllib.loads(resource.read_text(encoding="utf-8"))
    return {run: frozenset(outlets) for run, outlets in table.get("outlets", {}).items()}


def reducing_tee_made(fittings: str | None, run: str | None, outlet: str | None) -> bool | None:
    """Whether the fittings table ``fittings`` makes a reducing-outlet tee of run ``run`` and
    outlet ``outlet`` (nominal names of its pipe catalog); None when it cannot be told (no tee
    list, a size unknown, or a run the list does not cover)."""
    table = tee_outlets(fittings)
    if table is None or run is None or outlet is None or run not in table:
        return None
    return outlet in table[run]
