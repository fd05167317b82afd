"""The design file (``asbuilt check --design FILE``): what should have been built, and matching.

A design is a JSON document (docs/design-format.md)::

    {"format": "asbuilt-design", "version": 1, "units": "mm",
     "pipes":   [{"id": "D1", "nominal": "4", "start": [0, 0, 1000], "end": [2000, 0, 1000]}],
     "columns": [{"id": "C1", "base": [0, 5000, 0], "top": [0, 5000, 3000], "size": [300, 300],
                  "material": "steel"}],
     "boxes":   [{"id": "T1", "center": [4000, 0, 500], "size": [1000, 800, 1000]}]}

Lengths are converted to metres on loading. A pipe's ``nominal`` must be a size
:func:`asbuilt.catalog.parse_nominal` reads (``"6"``, ``6"``, ``NPS 6``, ``DN150``...); which
catalog size it names is settled when the design is checked against a model
(:mod:`asbuilt.rules.design`), where the catalog is known. :func:`match_design` pairs as-built components with
designed ones: compatible kinds only, the nearest first (an optimal assignment, Hungarian
method via scipy.optimize.linear_sum_assignment) within a matching radius; what is left on either
side is missing or extra.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from .catalog import parse_nominal
from .errors import DesignError
from .model import Component, Model, Straight
from .primitives import Cuboid, Cylinder
from .scan.load import MAX_COORDINATE_M
from .units import UNITS, unit_factor

__all__ = [
    "DesignedComponent",
    "Design",
    "DesignMatch",
    "load_design",
    "loads_design",
    "match_design",
    "DESIGN_KINDS",
]

#: Designed kinds and the as-built component types each may match.
DESIGN_KINDS = {
    "pipe": ("pipe", "cylinder", "coupling"),
    "column": ("cuboid", "cylinder"),
    "box": ("cuboid",),
}
_LISTS = {"pipes": "pipe", "columns": "column", "boxes": "box"}


@dataclass(frozen=True, eq=False)
class DesignedComponent:
    """One designed component, metres.

    Attributes
    ----------
    id : str
    kind : str
        ``"pipe"``, ``"column"`` or ``"box"``.
    start, end : ndarray, shape (3,), metres, or None
        Pipe ends; column base and top centres.
    center : ndarray, shape (3,), metres
        Mid-point (boxes: the centre).
    size : ndarray or None, metres
        Columns: section (2,) (one value for a round column's diameter); boxes: edges (3,).
    axes : ndarray, shape (3, 3), or None
        Box edge directions (rows); None means axis-aligned.
    nominal, material : str or None
        ``nominal`` as written in the file (any form :func:`asbuilt.catalog.parse_nominal`
        reads).
    where : str or None
        The entry in the design file (``"pipes[0] (D-P1)"``), for messages.
    """

    id: str
    kind: str
    center: np.ndarray
    start: np.ndarray | None = None
    end: np.ndarray | None = None
    size: np.ndarray | None = None
    axes: np.ndarray | None = None
    nominal: str | None = None
    material: str | None = None
    where: str | None = None

    @property
    def axis(self) -> np.ndarray | None:
        """Unit direction start to end (3,), or None for boxes."""
        if self.start is None:
            return None
        d = self.end - self.start
        return d / np.linalg.norm(d)

    @property
    def length(self) -> float | None:
        """Length start to end, metres, or None for boxes."""
        return None if self.start is None else float(np.linalg.norm(self.end - self.start))


@dataclass(frozen=True)
class Design:
    """A loaded design: its components (metres), the file's units and path."""

    components: tuple[DesignedComponent, ...]
    units: str = "m"
    source: str | None = None


@dataclass(frozen=True)
class DesignMatch:
    """Pairs of (designed, as-built component), plus designed components with no as-built
    counterpart (``missing``) and as-built ones with no designed counterpart (``extra``)."""

    pairs: tuple[tuple[DesignedComponent, Component], ...]
    missing: tuple[DesignedComponent, ...]
    extra: tuple[Component, ...]


def _vector(
    value, where: str, source, factor: float, size: int = 3, metres: bool = True
) -> np.ndarray:
    if (
        not isinstance(value, list)
        or len(value) != size
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ):
        raise DesignError(f"must be a list of {size} numbers", source=source, where=where)
    array = np.asarray(value, dtype=np.float64) * factor
    if not np.all(np.isfinite(array)):
        raise DesignError("must be finite numbers", source=source, where=where)
    if metres and np.abs(array).max() > MAX_COORDINATE_M:
        raise DesignError(
            f"{float(np.abs(array).max()):.3g} m is beyond any site (at most {MAX_COORDINATE_M:g} m);"
            ' check the number and the file\'s "units"',
            source=source,
            where=where,
        )
    return array


def _ident(raw: dict, where: str, source) -> str:
    ident = raw.get("id")
    if not isinstance(ident, str) or not ident:
        raise DesignError('needs an "id" string', source=source, where=where)
    bad = next((c for c in ident if not c.isprintable()), None)
    if bad is not None:
        raise DesignError(
            f'"id" holds a control character (\\u{ord(bad):04x}); use printable text',
            source=source,
            where=where,
        )
    if len(ident) > _MAX_ID_CHARACTERS:
        raise DesignError(
            f'"id" is {len(ident):,} characters long; use at most {_MAX_ID_CHARACTERS}',
            source=source,
            where=where,
        )
    return ident


#: Longest id accepted, in characters (the scan's limit: DXF names hold at most 255).
_MAX_ID_CHARACTERS = 255


def _nominal(value, where: str, source) -> str | None:
    """A pipe's ``nominal`` as text, refused when no catalog could read it as a size."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        raise DesignError('must be a size like "6", 6", NPS 6 or DN150', source=source, where=where)
    text = str(value).strip()
    if parse_nominal(text) is None:
        raise DesignError(
            f'{text!r} is not a pipe size; write it like "6", 6", NPS 6 or DN150',
            source=source,
            where=where,
        )
    return text


def _item(kind: str, raw, where: str, source, factor: float) -> DesignedComponent:
    if not isinstance(raw, dict):
        raise DesignError("must be an object", source=source, where=where)
    ident = _ident(raw, where, source)
    where = f"{where} ({ident})"
    allowed = {
        "pipe": {"id", "nominal", "start", "end", "label"},
        "column": {"id", "base", "top", "size", "material", "label"},
        "box": {"id", "center", "size", "axes", "label"},
    }[kind]
    unknown = sorted(set(raw) - allowed)
    if unknown:
        raise DesignError(
            f"unknown field {unknown[0]!r}; a {kind} has {', '.join(sorted(allowed))}",
            source=source,
            where=where,
        )

    def need(name):
        if name not in raw:
            raise DesignError(f'needs "{name}"', source=source, where=where)
        return raw[name]

    nominal = _nominal(raw.get("nominal"), f"{where}.nominal", source)
    if kind in ("pipe", "column"):
        a_name, b_name = ("start", "end") if kind == "pipe" else ("base", "top")
        start = _vector(need(a_name), f"{where}.{a_name}", source, factor)
        end = _vector(need(b_name), f"{where}.{b_name}", source, factor)
        if np.linalg.norm(end - start) <= 0:
            raise DesignError(f"{a_name} and {b_name} must differ", source=source, where=where)
        size = None
        if kind == "column":
            raw_size = need("size")
            n = len(raw_size) if isinstance(raw_size, list) else 0
            size = _vector(raw_size, f"{where}.size", source, factor, size=n if n in (1, 2) else 2)
            if np.any(size <= 0):
                raise DesignError("sizes must be positive", source=source, where=f"{where}.size")
        material = raw.get("material")
        if material is not None and material not in ("steel", "concrete"):
            raise DesignError(
                'must be "steel" or "concrete"', source=source, where=f"{where}.material"
            )
        return DesignedComponent(
            ident,
            kind,
            0.5 * (start + end),
            start,
            end,
            size,
            None,
            nominal,
            material,
            where,
        )
    center = _vector(need("center"), f"{where}.center", source, factor)
    size = _vector(need("size"), f"{where}.size", source, factor)
    if np.any(size <= 0):
        raise DesignError("sizes must be positive", source=source, where=f"{where}.size")
    axes = None
    if "axes" in raw:
        rows = raw["axes"]
        if not isinstance(rows, list) or len(rows) != 3:
            raise DesignError("must be 3 unit vectors", source=source, where=f"{where}.axes")
        axes = np.array([_vector(r, f"{where}.axes", source, 1.0, metres=False) for r in rows])
        if np.abs(axes @ axes.T - np.eye(3)).max() > 1e-6:
            raise DesignError("must be orthonormal", source=source, where=f"{where}.axes")
    return DesignedComponent(ident, kind, center, size=size, axes=axes, where=where)


def loads_design(text: str, *, source: str | None = None) -> Design:
    """A design from JSON text; ``source`` names it in errors.

    Raises
    ------
    DesignError
        Not JSON, wrong format tag, unknown units or fields, bad vectors, duplicate ids.
    """
    from ._text import loads_json

    try:
        doc = loads_json(text, DesignError, source=source)
    except json.JSONDecodeError as exc:
        raise DesignError(
            f"line {exc.lineno} column {exc.colno}: invalid JSON ({exc.msg}); fix the syntax there",
            source=source,
        ) from None
    except RecursionError:
        raise DesignError(
            "invalid JSON (nested too deeply); a design nests lists three levels at most",
            source=source,
        ) from None
    if not isinstance(doc, dict):
        raise DesignError("must be a JSON object", source=source)
    if doc.get("format", "asbuilt-design") != "asbuilt-design":
        raise DesignError(
            f'"format" must be "asbuilt-design", not {json.dumps(doc.get("format"))}; --design '
            "takes the intended layout (docs/design-format.md), not a scan or a model",
            source=source,
            where="format",
        )
    version = doc.get("version", 1)
    if isinstance(version, bool) or version != 1:
        raise DesignError("only version 1 is known", source=source, where="version")
    units = doc.get("units", "m")
    if not isinstance(units, str) or units not in UNITS:
        raise DesignError(
            f"unknown units {units!r}; use one of {', '.join(UNITS)}", source=source, where="units"
        )
    factor = unit_factor(units)
    unknown = sorted(set(doc) - {"format", "version", "units", "name", *_LISTS})
    if unknown:
        raise DesignError(
            f"unknown key {unknown[0]!r}; a design has pipes, columns, boxes",
            source=source,
            where=unknown[0],
        )
    items, seen = [], set()
    for key, kind in _LISTS.items():
        entries = doc.get(key, [])
        if not isinstance(entries, list):
            raise DesignError("must be a list", source=source, where=key)
        for i, raw in enumerate(entries):
            item = _item(kind, raw, f"{key}[{i}]", source, factor)
            if item.id in seen:
                raise DesignError(f"duplicate id {item.id!r}", source=source, where=f"{key}[{i}]")
            seen.add(item.id)
            items.append(item)
    return Design(tuple(items), units, source)


def load_design(path) -> Design:
    """Load a design file (see :func:`loads_design`); DesignError when unreadable or invalid."""
    from ._text import read_text

    source = str(path)
    text = read_text(
        path, DesignError, what="design file", missing="no such file; check the --design path"
    )
    return loads_design(text, source=source)


def built_axis(component: Component):
    """(centre (3,), unit axis (3,) or None) of an as-built component's geometry, metres."""
    g = component.geometry
    if isinstance(g, Straight):
        return 0.5 * (g.start + g.end), g.direction
    if isinstance(g, Cylinder):
        return np.array(g.center), np.array(g.axis)
    if isinstance(g, Cuboid):
        return np.array(g.center), np.array(g.axes[int(np.argmax(g.size))])
    return None, None


def _cost(designed: DesignedComponent, component: Component) -> float:
    if component.type not in DESIGN_KINDS[designed.kind]:
        return np.inf
    centre, axis = built_axis(component)
    if centre is None:
        return np.inf
    if designed.start is None:
        return float(np.linalg.norm(centre - designed.center))
    # distance of the as-built centre to the designed segment, plus a direction penalty
    d = designed.end - designed.start
    t = np.clip(np.dot(centre - designed.start, d) / np.dot(d, d), 0.0, 1.0)
    distance = float(np.linalg.norm(centre - (designed.start + t * d)))
    cos = abs(float(np.dot(axis, designed.axis))) if axis is not None else 1.0
    if cos < np.cos(np.radians(30.0)):
        return np.inf
    return distance + 0.1 * float(np.linalg.norm(centre - designed.center))


def match_design(model: Model, design: Design, radius: float = 0.5) -> DesignMatch:
    """Pair each designed component with the nearest compatible as-built one within ``radius``
    metres (optimal assignment); the rest are missing (designed) or extra (as-built pipes,
    cylinders and cuboids)."""
    built = [c for c in model.components if any(c.type in t for t in DESIGN_KINDS.values())]
    wanted = list(design.components)
    pairs, used_d, used_b = [], set(), set()
    if built and wanted:
        cost = np.array([[_cost(d, c) for c in built] for d in wanted])
        gated = np.where(cost <= radius, cost, 1e9)
        rows, cols = linear_sum_assignment(gated)
        for r, c in zip(rows, cols):
            if gated[r, c] < 1e9:
                pairs.append((wanted[r], built[c]))
                used_d.add(r)
                used_b.add(c)
    missing = tuple(d for i, d in enumerate(wanted) if i not in used_d)
    extra = tuple(c for i, c in enumerate(built) if i not in used_b)
    return DesignMatch(tuple(pairs), missing, extra)
