"""PCF export: the piping of the model as an ISOGEN piping component file, for isometrics.

A piping component file (PCF, Alias/Hexagon ISOGEN) is plain text: a header of units, then one
``PIPELINE-REFERENCE`` block per pipeline and one block per component, each with its end points
(centres of the ends, with the nominal bore), its centre or branch points and its symbol key
(SKEY). Stress and isometric tools (ISOGEN, CAESAR II, AutoPIPE, START-PROF...) read it.

Written here:

* header ``ISOGEN-FILES ISOGEN.FLS``, ``UNITS-BORE`` (``INCH`` for NPS catalogs, ``MM`` for DN
  ones), ``UNITS-CO-ORDS MM`` and the other unit records;
* one pipeline per spool (``PIPELINE-REFERENCE`` the spool id; ``ATTRIBUTE1`` its group);
* ``PIPE`` (pipes and couplings), ``ELBOW`` (``CENTRE-POINT`` the intersection of the end
  tangents, as ISOGEN expects, and ``ANGLE`` in hundredths of a degree), ``TEE`` (run ends,
  ``CENTRE-POINT``, ``BRANCH1-POINT``), ``REDUCER-CONCENTRIC`` and ``REDUCER-ECCENTRIC`` (with
  ``FLAT-DIRECTION``: ``UP``, ``DOWN``, ``EAST``, ``WEST``, ``NORTH`` or ``SOUTH``, taking the
  scan frame's x, y, z as east, north, up);
* ``ITEM-CODE`` per component (type, bores, schedule) and a ``MATERIALS`` section describing
  each item code; the asbuilt component id as ``COMPONENT-ATTRIBUTE1``. A fitting merging
  built in a form its standard does not make (``snap["standard"]`` false: an elbow cut to 60
  degrees, a tee with an oblique outlet) gets its own item code (``ELBOW-6IN-STD-60DEG-NONSTD``)
  and a description saying so, never the catalog fitting's.

Objects that are not piping (columns, tanks, walls) are not written: PCF has no records for
them. Coordinates are millimetres with 0.1 mm resolution; text is ASCII, the encoding ISOGEN
reads: accented letters lose their accents (``Ä`` -> ``A``), other characters become ``?``.
Names that identify something (pipeline references, groups, component ids) and are not plain
ASCII also get ``~`` and 8 hex digits of a hash of the whole name (``LINE-Ä`` ->
``LINE-A~...``), so two names never collapse into one (``LINE-Ä`` and ``LINE-Ö`` were both
``LINE-?``) and a name is written the same in every file.
"""

from __future__ import annotations

import hashlib
import math
import unicodedata
from dataclasses import dataclass, field

import numpy as np

from asbuilt.catalog import PipeSize, model_catalog
from asbuilt.errors import ExportError
from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee

__all__ = ["pcf_text", "write_pcf", "PCF_COMPONENTS"]

#: Model component type -> PCF component identifier (reducers are split by eccentricity).
PCF_COMPONENTS = {
    "pipe": "PIPE",
    "coupling": "PIPE",
    "elbow": "ELBOW",
    "tee": "TEE",
    "cross": "CROSS",
    "reducer": "REDUCER-CONCENTRIC",
}

#: ISOGEN symbol keys of butt-welded fittings (the ``BW`` suffix: butt weld ends).
_SKEY = {
    "ELBOW": "ELBW",
    "TEE": "TEBW",
    "CROSS": "CRBW",
    "REDUCER-CONCENTRIC": "RCBW",
    "REDUCER-ECCENTRIC": "REBW",
}

#: PCF directions of a flat side, and the scan-frame unit vector each names (x east, y north).
_DIRECTIONS = {
    "EAST": (1.0, 0.0, 0.0),
    "WEST": (-1.0, 0.0, 0.0),
    "NORTH": (0.0, 1.0, 0.0),
    "SOUTH": (0.0, -1.0, 0.0),
    "UP": (0.0, 0.0, 1.0),
    "DOWN": (0.0, 0.0, -1.0),
}

#: Two ODs (metres) that differ by less than this are the same catalog size.
_SAME_OD = 1e-4
_INDENT = "    "


def _ascii(text: object) -> str:
    """One line of ASCII text (ISOGEN reads ASCII; line breaks would start new records).

    Letters lose their accents (compatibility decomposition, NFKD, without the combining marks:
    ``Säule`` -> ``Saule``, ``ﬁ`` -> ``fi``); characters with no ASCII form become ``?``.
    """
    decomposed = unicodedata.normalize("NFKD", str(text))
    stripped = "".join(c for c in decomposed if not unicodedata.combining(c))
    flat = " ".join(stripped.split())
    return flat.encode("ascii", "replace").decode("ascii")


@dataclass
class _Identifiers:
    """Names that identify pipelines, groups and components, written as distinct ASCII words.

    A plain ASCII name (one line) is written as it is; any other gets its ASCII form
    (:func:`_ascii`) and ``~`` plus 8 hex digits of the SHA-256 of the name, so distinct names
    stay distinct after accents and other characters are dropped, and the same name is
    written the same in every file (the digest depends on the name alone). Should that still
    meet a name already written for another, the digest is lengthened.
    """

    written: dict[str, str] = field(default_factory=dict)
    taken: set[str] = field(default_factory=set)

    def __call__(self, name: object) -> str:
        name = str(name)
        if name in self.written:
            return self.written[name]
        plain = _ascii(name)
        candidates = [plain] if plain == name else []
        digest = hashlib.sha256(name.encode("utf-8", "surrogatepass")).hexdigest()
        candidates += [f"{plain}~{digest[:n]}" for n in (8, 16, 64)]
        result = next((c for c in candidates if c not in self.taken), candidates[-1])
        self.written[name] = result
        self.taken.add(result)
        return result


def _mm(point: np.ndarray) -> str:
    """A point (3,) metres as PCF coordinates in millimetres."""
    return " ".join(f"{1000.0 * float(v):.1f}" for v in point)


@dataclass(frozen=True)
class _Bores:
    """How nominal bores are written: the catalog (or None) and its bore unit."""

    catalog: object | None
    unit: str  # "INCH" or "MM"

    def size(self, component: Component, od: float) -> PipeSize | None:
        """The catalog size of an end with outside diameter ``od`` (metres), if known."""
        if self.catalog is None:
            return None
        if component.nominal is not None:
            try:
                named = self.catalog.size(component.nominal)
            except KeyError:
                named = None
            if named is not None and abs(named.od - od) < _SAME_OD:
                return named
        nearest = self.catalog.nearest(od, 1)
        if nearest and abs(nearest[0].od - od) < _SAME_OD:
            return nearest[0]
        return None

    def bore(self, component: Component, od: float) -> str:
        """The nominal bore of an end as PCF writes it; the OD itself when no size matches."""
        size = self.size(component, od)
        if size is not None:
            if self.unit == "INCH" and size.nps is not None:
                return f"{size.nps:g}"
            if self.unit == "MM" and size.dn is not None:
                return f"{size.dn:d}"
        # Not snapped to a catalog size: the outside diameter, in the bore unit.
        value = od / 0.0254 if self.unit == "INCH" else od * 1000.0
        return f"{value:.3f}".rstrip("0").rstrip(".")


def _bores(model: Model) -> _Bores:
    catalog = model_catalog(model)[0]  # None: bores from the ODs
    unit = "INCH"
    if catalog is not None and catalog.designation.upper() == "DN":
        unit = "MM"
    return _Bores(catalog, unit)


def _corner(bend: Bend) -> np.ndarray:
    """The intersection of an elbow's end tangents (3,) metres: ISOGEN's CENTRE-POINT."""
    a, b = bend.start - bend.center, bend.end - bend.center
    half = math.radians(bend.angle_deg) / 2.0
    middle = a + b
    return bend.center + middle / np.linalg.norm(middle) * bend.bend_radius / math.cos(half)


def _flat_direction(reducer: Reducer) -> str:
    side = reducer.flat_side
    return max(_DIRECTIONS, key=lambda name: float(np.dot(side, _DIRECTIONS[name])))


def _nonstandard(component: Component) -> bool:
    """Whether merging built the fitting in a form its standard does not make (an elbow cut
    to 60 degrees, a tee with an oblique outlet: ``snap["standard"]`` False)."""
    return (component.snap or {}).get("standard") is False


def _item_code(component: Component, identifier: str, bores: list[str], unit: str) -> str:
    size = "X".join(bores) + ("IN" if unit == "INCH" else "MM")
    schedule = f"-{component.schedule}" if component.schedule else ""
    extra = ""
    if _nonstandard(component):
        # its own item code: a material take-off must not count it as the catalog fitting
        angle = (component.snap or {}).get("angle_deg")
        extra = (f"-{round(float(angle)):d}DEG" if angle is not None else "") + "-NONSTD"
    return _ascii(f"{identifier}-{size}{schedule}{extra}").replace(" ", "")


def _records(component: Component, bores: _Bores) -> tuple[str, list[str], list[str]] | None:
    """(identifier, record lines, bores) of one piping component, or None if not piping."""
    g = component.geometry
    identifier = PCF_COMPONENTS.get(component.type)
    if identifier is None:
        return None
    if isinstance(g, Straight):
        bore = bores.bore(component, 2 * g.outer_radius)
        return (
            identifier,
            [f"END-POINT {_mm(g.start)} {bore}", f"END-POINT {_mm(g.end)} {bore}"],
            [bore],
        )
    if isinstance(g, Bend):
        # a reducing elbow's ends are of two sizes: each END-POINT has its own bore
        first, second = (bores.bore(component, 2 * radius) for radius in g.radii)
        lines = [
            f"END-POINT {_mm(g.start)} {first}",
            f"END-POINT {_mm(g.end)} {second}",
            f"CENTRE-POINT {_mm(_corner(g))}",
            f"SKEY {_SKEY[identifier]}",
            f"ANGLE {round(100 * g.angle_deg):d}",
        ]
        return identifier, lines, [first] if first == second else [first, second]
    if isinstance(g, (Tee, Cross)):
        # a cross is the TEE record with a second outlet, BRANCH2-POINT (see the module docstring)
        run = bores.bore(component, 2 * g.outer_radius)
        branch = bores.bore(component, 2 * g.branch_outer_radius)
        lines = [
            f"END-POINT {_mm(g.run_start)} {run}",
            f"END-POINT {_mm(g.run_end)} {run}",
            f"CENTRE-POINT {_mm(g.center)}",
            *(f"BRANCH{k}-POINT {_mm(end)} {branch}" for k, end in enumerate(g.outlets, 1)),
            f"SKEY {_SKEY[identifier]}",
        ]
        return identifier, lines, [run] if branch == run else [run, branch]
    if isinstance(g, Reducer):
        first = bores.bore(component, 2 * g.outer_radius_start)
        second = bores.bore(component, 2 * g.outer_radius_end)
        eccentric = bool(getattr(g, "eccentric", False))
        identifier = "REDUCER-ECCENTRIC" if eccentric else "REDUCER-CONCENTRIC"
        lines = [
            f"END-POINT {_mm(g.start)} {first}",
            f"END-POINT {_mm(g.end)} {second}",
            f"SKEY {_SKEY[identifier]}",
        ]
        if eccentric:
            lines.append(f"FLAT-DIRECTION {_flat_direction(g)}")
        return identifier, lines, [first, second]
    return None


def _description(component: Component, identifier: str, bores: list[str], unit: str) -> str:
    words = identifier.replace("-", " ")
    size = " x ".join(bores) + (" in" if unit == "INCH" else " mm")
    schedule = f", SCH {component.schedule}" if component.schedule else ""
    made = ""
    if _nonstandard(component):
        angle = (component.snap or {}).get("angle_deg")
        made = (f", {float(angle):.0f} deg" if angle is not None else "") + (
            f", {(component.snap or {}).get('dimensions')}"
        )
    return _ascii(f"{words}, {size}{schedule}{made}")


def pcf_text(model: Model) -> str:
    """The PCF text of the model's piping (see the module docstring).

    Parameters
    ----------
    model : asbuilt.model.Model
        Metres, scan frame (x east, y north, z up).

    Raises
    ------
    ExportError
        The model has no piping (pipes, elbows, tees, reducers, couplings) to write.
    """
    bores = _bores(model)
    by_id = {component.id: component for component in model.components}
    pipelines: list[tuple[str, str | None, list[Component]]] = []
    placed: set[str] = set()
    for spool in model.spools:
        members = [by_id[i] for i in spool.components if i in by_id]
        members = [c for c in members if c.type in PCF_COMPONENTS]
        if members:
            pipelines.append((spool.id, members[0].group, members))
            placed.update(c.id for c in members)
    loose = [c for c in model.components if c.type in PCF_COMPONENTS and c.id not in placed]
    for component in loose:  # piping merging did not put in a spool: a pipeline each
        pipelines.append((component.id, component.group, [component]))
    if not pipelines:
        raise ExportError(
            "the model has no piping (pipes, elbows, tees, reducers) to write as PCF; "
            "write the other objects to STEP, glTF or DXF"
        )

    lines = [
        "ISOGEN-FILES ISOGEN.FLS",
        f"UNITS-BORE {bores.unit}",
        "UNITS-CO-ORDS MM",
        "UNITS-WEIGHT KGS",
        "UNITS-BOLT-DIA MM",
        "UNITS-BOLT-LENGTH MM",
    ]
    materials: dict[str, str] = {}
    names = _Identifiers()
    # Plain ASCII names first, so one never yields its place to a name that needed a digest.
    for name in sorted(
        {reference for reference, _, _ in pipelines}
        | {group for _, group, _ in pipelines if group}
        | {c.id for _, _, members in pipelines for c in members},
        key=lambda name: (_ascii(name) != name, name),
    ):
        names(name)
    for reference, group, members in pipelines:
        lines.append(f"PIPELINE-REFERENCE {names(reference)}")
        if model.name:
            lines.append(f"{_INDENT}PROJECT-IDENTIFIER {_ascii(model.name)}")
        if group:
            lines.append(f"{_INDENT}ATTRIBUTE1 {names(group)}")
        for component in members:
            written = _records(component, bores)
            if written is None:  # piping type with another shape: no PCF records for it
                continue
            identifier, records, sizes = written
            code = _item_code(component, identifier, sizes, bores.unit)
            materials.setdefault(code, _description(component, identifier, sizes, bores.unit))
            lines.append(identifier)
            lines.extend(_INDENT + record for record in records)
            lines.append(f"{_INDENT}ITEM-CODE {code}")
            lines.append(f"{_INDENT}COMPONENT-ATTRIBUTE1 {names(component.id)}")
    lines.append("MATERIALS")
    for code, description in materials.items():
        lines.append(f"ITEM-CODE {code}")
        lines.append(f"{_INDENT}DESCRIPTION {description}")
    return "\r\n".join(lines) + "\r\n"


def write_pcf(model: Model, path) -> None:
    """Write the model's piping as a PCF file to ``path`` (see :func:`pcf_text`).

    Parameters
    ----------
    model : asbuilt.model.Model
    path : str or Path
        Written directly; callers stage it for atomicity (:mod:`asbuilt.export`).
    """
    with open(path, "w", encoding="ascii", newline="") as stream:
        stream.write(pcf_text(model))
