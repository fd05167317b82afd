"""Pipe and fitting catalogs: standard sizes read from CSV files (metres inside).

One CSV file per standard (``catalogs/<name>.csv``, installed as the package
``asbuilt.catalogs``); a user's own file in the same format is accepted by path. The format
(documented in ``docs/catalogs.md``): ``# key: value`` header lines (``name``, ``title``,
``standard``, ``kind`` = ``pipe`` or ``fittings``, ``units`` = ``mm``/``in``/``m``, and
optionally ``material``, ``designation``, ``fittings``, ``default_schedule``, ``note``), then a
CSV table with a header row. Pipe tables have ``nominal``, ``od``, ``source`` and optionally
``dn``, ``nps`` and ``wall_<SCHEDULE>`` columns; fitting tables have ``nominal``, ``source`` and
the dimension columns of :data:`FITTING_COLUMNS`. Every row carries its ``source``.

A malformed file raises :class:`~asbuilt.errors.CatalogError` naming the file, the line and
the column.
"""

from __future__ import annotations

import csv
import functools
import io
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType

from .errors import CatalogError, quoted
from .nominal import NominalHint, parse_nominal, parse_number, size_by_system
from .units import UNITS

__all__ = [
    "DEFAULT_CATALOG",
    "FITTING_COLUMNS",
    "PipeSize",
    "FittingSize",
    "FittingDims",
    "NominalHint",
    "Catalog",
    "catalog_names",
    "load_catalog",
    "model_catalog",
    "parse_nominal",
    "size_by_system",
    "fitting_dims",
]

#: The catalog used when none is given.
DEFAULT_CATALOG = "asme-b36.10m"

#: Outside diameters (metres) a pipe catalog's rows may have: the smallest standard tube (NPS
#: 1/8, 10.3 mm; 6 mm instrument tubing) to beyond the largest (NPS 96 and EN 10220's 2.54 m),
#: with margin. Outside, the numbers are almost surely in another unit than the header says (a
#: millimetre table under "units: m" is 60,300 mm pipes, and nothing would ever snap to it).
PLAUSIBLE_PIPE_OD = (0.003, 6.0)

#: Dimension columns of a fittings table (lengths in the file's units), ASME B16.9 letters:
#: 90 degree long-radius elbow centre-to-end A (= its bend radius), 45 degree long-radius elbow
#: centre-to-end B, 90 degree short-radius elbow centre-to-end, equal tee run C and outlet M,
#: concentric reducer length H (by the large end).
FITTING_COLUMNS = (
    "elbow90_lr",
    "elbow45_lr",
    "elbow90_sr",
    "tee_run",
    "tee_outlet",
    "reducer",
)

_HEADER_KEYS = {
    "name",
    "title",
    "standard",
    "kind",
    "units",
    "material",
    "designation",
    "fittings",
    "default_schedule",
    "note",
}
_KINDS = ("pipe", "fittings")
_PIPE_FIXED = ("nominal", "dn", "nps", "od", "source")
_MM = 1e-3


@dataclass(frozen=True)
class PipeSize:
    """One standard pipe size.

    Attributes
    ----------
    nominal : str
        The catalog's designation of the size (``"4"``, ``"1 1/2"`` for NPS; ``"100"`` for DN).
    od : float
        Outside diameter, metres.
    walls : Mapping[str, float]
        Wall thickness in metres by upper-case schedule name (``"STD"``, ``"40"``, ``"10S"``...).
    nps : float or None
        Nominal pipe size in inches, when known.
    dn : int or None
        Metric nominal diameter, when known.
    source : str
        Where the row's numbers come from.
    line : int
        Line of the catalog file (for messages).
    """

    nominal: str
    od: float
    walls: Mapping[str, float] = field(default_factory=dict)
    nps: float | None = None
    dn: int | None = None
    source: str = ""
    line: int = 0

    def wall(self, schedule: str) -> float | None:
        """Wall thickness (metres) for ``schedule`` (case-insensitive), None when not listed."""
        return self.walls.get(schedule.upper())


@dataclass(frozen=True)
class FittingSize:
    """Butt-weld fitting dimensions for one size; every length in metres or None when absent.

    See :data:`FITTING_COLUMNS` for the meaning of each dimension.
    """

    nominal: str
    nps: float | None
    dn: int | None
    od: float | None
    dims: Mapping[str, float]
    source: str = ""
    line: int = 0


@dataclass(frozen=True)
class FittingDims:
    """The fitting dimensions merging uses for one pipe size (metres).

    ``bend_radius`` is the centre-line radius of elbows (long or short radius as asked);
    ``tee_run``/``tee_outlet`` the equal tee's centre-to-end of run and outlet;
    ``reducer_length`` the concentric reducer's length by its large end; ``elbow45_end`` the
    long-radius 45 degree elbow's centre-to-end (also when short radius is asked: ASME B16.9 has
    no short-radius 45 degree elbow), ``elbow45_notes`` what a 45 degree elbow's record should
    say about it; ``source`` is the fittings catalog's name, or ``"rule"`` when a rule of thumb
    stood in (see :func:`fitting_dims`); ``notes`` say which values came from a rule.
    """

    bend_radius: float
    tee_run: float
    tee_outlet: float
    reducer_length: float
    source: str
    notes: tuple[str, ...] = ()
    elbow45_end: float | None = None
    elbow45_notes: tuple[str, ...] = ()


@dataclass(frozen=True, eq=False)
class Catalog:
    """A loaded catalog: header fields and its sizes (sorted by outside diameter).

    Attributes
    ----------
    name, title, standard, kind, material, designation : str
    units : str
        Unit of the file's lengths (the data here are metres).
    fittings_name : str or None
        Name (or path) of the fittings catalog that goes with a pipe catalog.
    default_schedule : str or None
    sizes : tuple of PipeSize
        Pipe catalogs only, by increasing OD.
    fittings : tuple of FittingSize
        Fitting catalogs only.
    path : str
        The file it was read from.
    fitting_table : Catalog or None
        The fittings catalog loaded for a pipe catalog, if it names one.
    note : str
    """

    name: str
    title: str
    standard: str
    kind: str
    units: str
    material: str = ""
    designation: str = ""
    fittings_name: str | None = None
    default_schedule: str | None = None
    sizes: tuple[PipeSize, ...] = ()
    fittings: tuple[FittingSize, ...] = ()
    path: str = ""
    fitting_table: Catalog | None = None
    note: str = ""
    schedule_columns: tuple[str, ...] = ()

    @property
    def schedules(self) -> tuple[str, ...]:
        """Every schedule with a wall in at least one size, in column order."""
        listed = {name for size in self.sizes for name in size.walls}
        return tuple(name for name in self.schedule_columns if name in listed)

    @property
    def od_range(self) -> tuple[float, float]:
        """Smallest and largest outside diameter, metres."""
        if not self.sizes:
            raise ValueError(f"catalog {self.name} has no pipe sizes")
        return self.sizes[0].od, self.sizes[-1].od

    def label(self, nominal: str) -> str:
        """A display label such as ``NPS 4`` or ``DN 100``."""
        prefix = self.designation or ""
        return f"{prefix} {nominal}".strip()

    def size(self, nominal: str) -> PipeSize:
        """The size designated ``nominal`` (exact catalog text, or any hint :func:`parse_nominal`
        understands); KeyError when the catalog has none."""
        for size in self.sizes:
            if size.nominal == nominal:
                return size
        found = self.match_hint(parse_nominal(nominal)) if nominal else None
        if found is None:
            raise KeyError(nominal)
        return found

    def match_hint(self, hint: NominalHint | None) -> PipeSize | None:
        """The size an operator's hint names, or None (not parseable or not in the catalog)."""
        if hint is None:
            return None

        def by_nps(value):
            return next(
                (s for s in self.sizes if s.nps is not None and abs(s.nps - value) < 1e-6), None
            )

        def by_dn(value):
            return next(
                (s for s in self.sizes if s.dn is not None and abs(s.dn - value) < 1e-6), None
            )

        return size_by_system(hint, self.designation, by_nps, by_dn)

    def wall(self, nominal: str, schedule: str) -> float | None:
        """Wall thickness in metres of size ``nominal`` in ``schedule``; None when not listed."""
        return self.size(nominal).wall(schedule)

    def nearest(self, od: float, count: int = 2) -> tuple[PipeSize, ...]:
        """The ``count`` sizes whose OD is nearest ``od`` (metres), nearest first."""
        return tuple(sorted(self.sizes, key=lambda s: abs(s.od - od))[:count])

    def fitting(self, size: PipeSize) -> FittingSize | None:
        """The row of :attr:`fitting_table` for a pipe size (matched by NPS, then DN)."""
        table = self.fitting_table
        if table is None:
            return None
        for row in table.fittings:
            if size.nps is not None and row.nps is not None and abs(row.nps - size.nps) < 1e-6:
                return row
        for row in table.fittings:
            if size.dn is not None and row.dn is not None and row.dn == size.dn:
                return row
        return None


# ----------------------------------------------------------------------------------------------
# loading


def catalog_names() -> list[str]:
    """Names of the catalogs shipped with asbuilt (pipe and fittings), sorted."""
    root = resources.files("asbuilt.catalogs")
    return sorted(
        entry.name[: -len(".csv")] for entry in root.iterdir() if entry.name.endswith(".csv")
    )


def _looks_like_path(name: str) -> bool:
    return name.endswith(".csv") or "/" in name or "\\" in name or _is_file(Path(name))


def _is_dir(path: Path) -> bool:
    """``path.is_dir()``, False for a name the system refuses (too long, NUL byte...)."""
    try:
        return path.is_dir()
    except (OSError, ValueError):
        return False


def _is_file(path: Path) -> bool:
    """``path.is_file()``, False for a name the system refuses (too long, NUL byte...)."""
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False


def load_catalog(name_or_path) -> Catalog:
    """Load a shipped catalog by name (see :func:`catalog_names`) or a user's CSV file by path.

    A pipe catalog whose header names ``fittings`` gets that fittings catalog loaded as
    :attr:`Catalog.fitting_table` (a name, or a path relative to the catalog file).

    Raises
    ------
    CatalogError
        Unknown name, unreadable file, or malformed content (naming file, line and column).
    """
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or _looks_like_path(text):
        return _load_path(str(Path(text).resolve()), text)
    return _load_packaged(text)


def model_catalog(model, catalog=None):
    """The catalog ``model`` was built with, for the readers of a model (reports, exports):
    size labels, walls, DN and NPS values, the material.

    Parameters
    ----------
    model : asbuilt.model.Model
    catalog : Catalog, str or Path, optional
        The catalog the model was built with, when the caller has it (a name or path is
        loaded; its errors are raised). Default: the model's ``catalog_file`` when it records
        one (a user's catalog file), else the shipped catalog its ``catalog`` names.

    Returns
    -------
    (Catalog or None, str or None)
        The catalog, and when the model names a catalog that cannot be read, one line saying
        so (a report then shows nominal sizes without walls, weights or catalog labels).
    """
    if isinstance(catalog, Catalog):
        return catalog, None
    if catalog is not None:
        return load_catalog(catalog), None
    if model.catalog_file:
        try:
            return load_catalog(Path(model.catalog_file)), None
        except CatalogError as exc:
            return None, f"the model's catalog file cannot be read ({exc})"
    if model.catalog:
        try:
            return load_catalog(model.catalog), None
        except CatalogError:
            return None, (
                f"catalog {quoted(model.catalog)} is no shipped catalog and the model does not "
                "record its file (made before the file was recorded); build the model again "
                "from the scan with --catalog FILE"
            )
    return None, None


@functools.cache
def _load_packaged(name: str) -> Catalog:
    names = catalog_names()
    if name not in names and _is_dir(Path(name)):
        # a folder named without a slash: "unknown catalog" would hide what went wrong
        return _load_path(str(Path(name).resolve()), name)
    if name not in names:
        raise CatalogError(
            f"unknown catalog {quoted(name)}; use one of {', '.join(names)} or a CSV file path"
        )
    resource = resources.files("asbuilt.catalogs") / f"{name}.csv"
    content = resource.read_text(encoding="utf-8")
    catalog = parse_catalog(content, source=f"{name}.csv")
    return _attach_fittings(catalog, base=None)


def _load_path(resolved: str, shown: str, *, attach: bool = True) -> Catalog:
    from ._text import read_text

    # Spreadsheets save "CSV UTF-8" with a byte order mark: read_text drops it. Messages name
    # the file as the user gave it (``shown``), not as resolved.
    def error(message, source):
        return CatalogError(message, source=shown)

    content = read_text(
        resolved,
        error,
        what="catalog",
        missing="catalog file not found; check the path",
        kind="CSV" if str(resolved).endswith(".csv") else "TOML",
    )
    catalog = parse_catalog(content, source=shown)
    if not attach:  # a fittings table: its own 'fittings' header is not followed (no cycles)
        return catalog
    return _attach_fittings(catalog, base=Path(resolved).parent)


def _attach_fittings(catalog: Catalog, base: Path | None) -> Catalog:
    ref = catalog.fittings_name
    if catalog.kind != "pipe" or not ref:
        return catalog
    if base is not None and _is_file(base / ref):
        table = _load_path(str((base / ref).resolve()), str(base / ref), attach=False)
    elif _looks_like_path(ref) and base is not None:
        raise CatalogError(
            f"fittings catalog {quoted(ref)} not found beside the catalog",
            source=catalog.path,
            where="header 'fittings'",
        )
    else:
        try:
            table = _load_packaged(ref)
        except CatalogError:
            raise CatalogError(
                f"unknown fittings catalog {quoted(ref)}; use one of {', '.join(catalog_names())}",
                source=catalog.path,
                where="header 'fittings'",
            ) from None
    if table.kind != "fittings":
        raise CatalogError(
            f"{quoted(ref)} is a {table.kind} catalog, not a fittings catalog",
            source=catalog.path,
            where="header 'fittings'",
        )
    return Catalog(**{**_fields(catalog), "fitting_table": table})


def _fields(catalog: Catalog) -> dict:
    return {name: getattr(catalog, name) for name in catalog.__dataclass_fields__}


def _nominal_key(nominal: str):
    """What makes two nominal sizes the same: their number when they are one (``4`` and
    ``4.0``, ``1 1/2`` and ``1.5``), else their text in upper case (``DN100``)."""
    value = parse_number(nominal)
    return round(value, 9) if value is not None else nominal.strip().upper()


def _number(cell: str, *, source: str, line: int, column: str, scale: float) -> float | None:
    cell = cell.strip()
    if not cell:
        return None
    try:
        value = float(cell)
    except ValueError:
        raise CatalogError(
            f"{quoted(cell)} is not a number; write a plain number like 114.3",
            source=source,
            where=f"line {line}, column {quoted(column)}",
        ) from None
    if not math.isfinite(value) or value <= 0:
        raise CatalogError(
            f"{quoted(cell)} must be a positive number",
            source=source,
            where=f"line {line}, column {quoted(column)}",
        )
    return round(value * scale, 12)


def parse_catalog(content: str, *, source: str = "<catalog>") -> Catalog:
    """Parse catalog CSV text (see the module docstring); ``source`` names it in errors."""
    header: dict[str, str] = {}
    table_lines: list[tuple[int, str]] = []
    for number, line in enumerate(content.splitlines(), start=1):
        stripped = line.strip()
        if not stripped:
            continue
        if stripped.startswith("#"):
            if table_lines:
                continue  # comments inside the table are allowed and ignored
            body = stripped[1:].strip()
            if ":" not in body:
                continue
            key, value = (part.strip() for part in body.split(":", 1))
            key = key.lower()
            if key not in _HEADER_KEYS:
                raise CatalogError(
                    f"unknown header key {quoted(key)}; use {', '.join(sorted(_HEADER_KEYS))}",
                    source=source,
                    where=f"line {number}",
                )
            header[key] = value
            continue
        table_lines.append((number, line))
    for key in ("name", "kind", "units"):
        if not header.get(key):
            raise CatalogError(f"missing header line '# {key}: ...'", source=source, where="header")
    kind = header["kind"].lower()
    if kind not in _KINDS:
        raise CatalogError(
            f"kind must be pipe or fittings, not {quoted(header['kind'])}",
            source=source,
            where="header 'kind'",
        )
    units = header["units"]
    if units not in UNITS:
        raise CatalogError(
            f"units must be one of {', '.join(UNITS)}, not {quoted(units)}",
            source=source,
            where="header 'units'",
        )
    scale = UNITS[units]
    if not table_lines:
        raise CatalogError("no table: add a header row and one row per size", source=source)
    rows = list(csv.reader(io.StringIO("\n".join(text for _, text in table_lines))))
    columns = [c.strip().lower() for c in rows[0]]
    col_line = table_lines[0][0]
    for required in ("nominal", "source") + (("od",) if kind == "pipe" else ()):
        if required not in columns:
            raise CatalogError(
                f"missing column {required!r}", source=source, where=f"line {col_line}"
            )
    allowed = set(_PIPE_FIXED) | (set(FITTING_COLUMNS) if kind == "fittings" else set())
    for column in columns:
        if column in allowed or (kind == "pipe" and column.startswith("wall_") and len(column) > 5):
            continue
        raise CatalogError(
            f"unknown column {quoted(column)}; use nominal, dn, nps, od, source, "
            + ("wall_<schedule>" if kind == "pipe" else ", ".join(FITTING_COLUMNS)),
            source=source,
            where=f"line {col_line}, column {quoted(column)}",
        )
    if len(set(columns)) != len(columns):
        raise CatalogError("a column appears twice", source=source, where=f"line {col_line}")

    sizes: list[PipeSize] = []
    fittings: list[FittingSize] = []
    seen: dict[str, int] = {}
    for (line_no, _), cells in zip(table_lines[1:], rows[1:]):
        if len(cells) != len(columns):
            raise CatalogError(
                f"{len(cells)} cells but {len(columns)} columns",
                source=source,
                where=f"line {line_no}",
            )
        row = {col: cell.strip() for col, cell in zip(columns, cells)}
        nominal = row["nominal"]
        if not nominal:
            raise CatalogError(
                "empty nominal size", source=source, where=f"line {line_no}, column 'nominal'"
            )
        # "4" and "4.0", "1 1/2" and "1.5" name one size: a hint would match either row
        key = _nominal_key(nominal)
        if key in seen:
            raise CatalogError(
                f"nominal size {quoted(nominal)} repeats line {seen[key]}",
                source=source,
                where=f"line {line_no}, column 'nominal'",
            )
        seen[key] = line_no
        if not row["source"]:
            raise CatalogError(
                "every row needs its source (standard and table it comes from)",
                source=source,
                where=f"line {line_no}, column 'source'",
            )
        dn = _number(row.get("dn", ""), source=source, line=line_no, column="dn", scale=1.0)
        nps = None
        if row.get("nps"):
            nps = parse_number(row["nps"])
            if nps is None:
                raise CatalogError(
                    f"{quoted(row['nps'])} is not a size in inches (e.g. 4 or 1 1/2)",
                    source=source,
                    where=f"line {line_no}, column 'nps'",
                )
        designation = header.get("designation", "").upper()
        if nps is None and designation != "DN":
            nps = parse_number(nominal)
        if dn is None and designation == "DN":
            dn = _number(nominal, source=source, line=line_no, column="nominal", scale=1.0)
        od = _number(row.get("od", ""), source=source, line=line_no, column="od", scale=scale)
        if kind == "pipe":
            if od is None:
                raise CatalogError(
                    "empty outside diameter", source=source, where=f"line {line_no}, column 'od'"
                )
            low, high = PLAUSIBLE_PIPE_OD
            if not low <= od <= high:
                raise CatalogError(
                    f"an outside diameter of {od * 1000:.4g} mm is no pipe's (expected "
                    f"{low * 1000:g} mm to {high:g} m once in metres); check the header's "
                    f"'units: {units}' against the numbers",
                    source=source,
                    where=f"line {line_no}, column 'od'",
                )
            walls = {}
            for column in columns:
                if column.startswith("wall_"):
                    wall = _number(
                        row[column], source=source, line=line_no, column=column, scale=scale
                    )
                    if wall is not None:
                        if wall >= od / 2:
                            raise CatalogError(
                                "the wall must be thinner than half the OD",
                                source=source,
                                where=f"line {line_no}, column {quoted(column)}",
                            )
                        walls[column[5:].upper()] = wall
            sizes.append(
                PipeSize(
                    nominal=nominal,
                    od=od,
                    walls=MappingProxyType(walls),
                    nps=nps,
                    dn=int(dn) if dn else None,
                    source=row["source"],
                    line=line_no,
                )
            )
        else:
            dims = {}
            for column in FITTING_COLUMNS:
                if column in row:
                    value = _number(
                        row[column], source=source, line=line_no, column=column, scale=scale
                    )
                    if value is not None:
                        dims[column] = value
            fittings.append(
                FittingSize(
                    nominal=nominal,
                    nps=nps,
                    dn=int(dn) if dn else None,
                    od=od,
                    dims=MappingProxyType(dims),
                    source=row["source"],
                    line=line_no,
                )
            )
    if kind == "pipe":
        if not sizes:
            raise CatalogError("the table has no sizes", source=source)
        sizes.sort(key=lambda s: s.od)
        for a, b in zip(sizes, sizes[1:]):
            if abs(a.od - b.od) < 1e-9:
                raise CatalogError(
                    f"sizes {quoted(a.nominal)} (line {a.line}) and {quoted(b.nominal)} have the same OD",
                    source=source,
                    where=f"line {b.line}, column 'od'",
                )
    default_schedule = header.get("default_schedule") or None
    return Catalog(
        name=header["name"],
        title=header.get("title", ""),
        standard=header.get("standard", ""),
        kind=kind,
        units=units,
        material=header.get("material", ""),
        designation=header.get("designation", ""),
        fittings_name=header.get("fittings") or None,
        default_schedule=default_schedule.upper() if default_schedule else None,
        sizes=tuple(sizes),
        fittings=tuple(fittings),
        path=source,
        note=header.get("note", ""),
        schedule_columns=tuple(c[5:].upper() for c in columns if c.startswith("wall_")),
    )


# ----------------------------------------------------------------------------------------------
# fitting dimensions


def fitting_dims(
    catalog: Catalog, size: PipeSize | None, od: float, elbow_radius: str = "long"
) -> FittingDims:
    """Fitting dimensions for one pipe size, from the catalog's fittings table or by rule.

    Parameters
    ----------
    catalog : Catalog
        The pipe catalog (its :attr:`Catalog.fitting_table` is used when it has the size).
    size : PipeSize or None
        The snapped size; None when the pipe did not snap (then only rules apply).
    od : float
        Outside diameter, metres (used by the rules).
    elbow_radius : {"long", "short"}

    Returns
    -------
    FittingDims
        Rules of thumb where the table has no value (ASME B16.9 proportions): bend radius
        1.5 x nominal bore long / 1.0 x short (nominal bore = NPS inches or DN mm, else the
        OD), tee centre-to-end of run and outlet = OD, reducer length = OD of the large end.
    """
    if elbow_radius not in ("long", "short"):
        raise ValueError(f"elbow_radius must be 'long' or 'short', not {quoted(elbow_radius)}")
    row = catalog.fitting(size) if size is not None else None
    dims = dict(row.dims) if row is not None else {}
    notes: list[str] = []
    basis = "nominal bore"
    if size is not None and size.nps is not None:
        bore = size.nps * 0.0254
    elif size is not None and size.dn is not None:
        bore = size.dn * _MM
    else:
        bore = od
        basis = "OD (no nominal size)"
    factor = 1.5 if elbow_radius == "long" else 1.0
    column = "elbow90_lr" if elbow_radius == "long" else "elbow90_sr"
    radius = dims.get(column)
    if radius is None and elbow_radius == "short" and "elbow90_lr" in dims:
        radius = dims["elbow90_lr"]
        notes.append("no short-radius elbow in the table for this size: long radius used")
    if radius is None:
        radius = factor * bore
        notes.append(f"bend radius by rule {factor:g} x {basis}")
    radius = max(radius, 0.5 * od * 1.01)
    tee_run = dims.get("tee_run")
    tee_outlet = dims.get("tee_outlet", tee_run)
    if tee_run is None:
        tee_run = tee_outlet = od
        notes.append("tee centre-to-end by rule = OD")
    reducer = dims.get("reducer")
    if reducer is None:
        reducer = od
        notes.append("reducer length by rule = large-end OD")
    source = catalog.fitting_table.name if row is not None and catalog.fitting_table else "rule"
    elbow45 = dims.get("elbow45_lr")
    elbow45_notes: tuple[str, ...] = ()
    if elbow_radius == "short":
        # ASME B16.9 has no short-radius 45 degree elbow: a 45 is the long-radius one, B from
        # the table, else the long-radius rule R tan(22.5 degrees)
        if elbow45 is None:
            long_radius = dims.get("elbow90_lr") or 1.5 * bore
            elbow45 = max(long_radius, 0.5 * od * 1.01) * math.tan(math.radians(22.5))
        elbow45_notes = ("no short-radius 45 degree elbow in ASME B16.9: long-radius 45 used",)
    return FittingDims(
        bend_radius=radius,
        tee_run=tee_run,
        tee_outlet=tee_outlet,
        reducer_length=reducer,
        source=source,
        notes=tuple(notes),
        elbow45_end=elbow45,
        elbow45_notes=elbow45_notes,
    )
