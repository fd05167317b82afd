"""DXF export (ezdxf): 3D meshes per object plus 2D plan and elevation views, in millimetres.

Model space holds, all in millimetres (``$INSUNITS`` = 4):

* each object's tessellated solid as a polyface mesh (a POLYLINE with the polyface flag, DXF's
  3D mesh since R12, which common readers such as the npm dxf-parser read while they skip MESH
  entities; one per 10,000 triangles) on its own kind/size/group layer, e.g.
  ``P-PIPE-NPS4-S1`` (piping), ``ASBUILT-CUBOID-COLUMNS`` (fitted objects); components with
  findings carry the status colour (error red, warning amber) as true colour;
* a plan view (XY, drawn at z = 0) on the layers ``PLAN-CENTRELINE``, ``PLAN-OUTLINE`` and
  ``PLAN-TEXT``;
* an elevation view (XZ, looking along +Y) drawn in the drawing's XY plane below the plan, on
  ``ELEV-CENTRELINE``, ``ELEV-OUTLINE`` and ``ELEV-TEXT``.

Pipes, bends, reducers, tees and fitted cylinders get centrelines; every other object gets the
outline of its projection (the convex hull of its mesh, a circle for spheres). Object ids are
TEXT entities in both views.
"""

from __future__ import annotations

import hashlib
import io
import re

import ezdxf
import ezdxf.bbox
import numpy as np
from ezdxf import colors as dxf_colors
from scipy.spatial import ConvexHull, QhullError

from asbuilt import __version__
from asbuilt.cad.colours import KIND_COLOURS, rgb255
from asbuilt.model import Bend, Cross, Reducer, Straight, Tee
from asbuilt.primitives import Cylinder, Sphere

__all__ = [
    "dxf_document",
    "dxf_text",
    "write_dxf",
    "layer_name",
    "VIEW_LAYERS",
    "PIPING_TYPES",
    "MAX_LAYER_NAME",
]

#: Component types drawn on ``P-`` (piping) layers; the others go on ``ASBUILT-`` layers.
PIPING_TYPES = ("pipe", "elbow", "tee", "cross", "reducer", "coupling")

#: The 2D view layers with their ACI colour and linetype.
VIEW_LAYERS = {
    "PLAN-CENTRELINE": (1, "CENTER"),
    "PLAN-OUTLINE": (7, "Continuous"),
    "PLAN-TEXT": (3, "Continuous"),
    "ELEV-CENTRELINE": (1, "CENTER"),
    "ELEV-OUTLINE": (7, "Continuous"),
    "ELEV-TEXT": (3, "Continuous"),
}

_MM = 1000.0
#: AutoCAD's longest layer name (AutoCAD 2000 and later): longer ones are refused or truncated
#: by readers, so longer names are shortened here.
MAX_LAYER_NAME = 255
#: Hex digits of the hash that keeps shortened layer names apart (32 bits: a clash is ~1e-9 likely
#: even for hundreds of long group names).
_HASH_DIGITS = 8
_INVALID = re.compile(r"[<>/\\\":;?*|=',`\s]+")


def _clean(text: str) -> str:
    return _INVALID.sub("_", text.strip()).strip("_").upper() or "X"


def layer_name(component, group: str | None, kind: str | None = None) -> str:
    """The 3D layer of a component: discipline, kind, nominal size, group.

    ``P-PIPE-NPS4-S1`` for a 4" pipe of spool S1, ``P-ELBOW-NPS4`` for an ungrouped elbow,
    ``ASBUILT-CUBOID-COLUMNS`` for a cuboid of group "columns"; ``kind`` ``"insulation"`` for
    the insulation around a component (``P-INSULATION-NPS4-S1``, on its own layer so it can be
    hidden). Characters DXF forbids in layer names become ``_`` (``1-1/2`` -> ``NPS1-1_2``).
    Names longer than 255 characters (a long group name) keep their first 246 and end in ``~``
    and 8 hex digits of a hash of the whole.
    """
    prefix = "P" if component.type in PIPING_TYPES else "ASBUILT"
    parts = [prefix, (kind or component.type).upper()]
    if component.nominal:
        parts.append("NPS" + _clean(str(component.nominal)))
    if group:
        parts.append(_clean(group))
    return _shortened("-".join(parts))


def _shortened(name: str) -> str:
    """``name`` itself when it fits :data:`MAX_LAYER_NAME`, else its head and ``~`` with a hash of
    the whole name (deterministic, and distinct for distinct names)."""
    if len(name) <= MAX_LAYER_NAME:
        return name
    digest = hashlib.sha256(name.encode("utf-8")).hexdigest()[:_HASH_DIGITS].upper()
    return f"{name[: MAX_LAYER_NAME - _HASH_DIGITS - 1]}~{digest}"


#: Triangles per polyface: face records index vertices with 16-bit integers (at most 32767
#: vertices), and 10,000 triangles have at most 30,000.
_POLYFACE_TRIANGLES = 10_000

#: A polyface's vertex and face records (DXF reference, VERTEX: flags 64 + 128 = 192 for a
#: polyface vertex, 128 for a face record whose 71-73 are 1-based vertex indices). The owner
#: (330) is the POLYLINE, as AutoCAD writes it.
_VERTEX = (
    "  0\nVERTEX\n  5\n{}\n330\n{}\n100\nAcDbEntity\n  8\n{}\n100\nAcDbVertex\n"
    "100\nAcDbPolyFaceMeshVertex\n 10\n{!r}\n 20\n{!r}\n 30\n{!r}\n 70\n192\n"
)
_FACE = (
    "  0\nVERTEX\n  5\n{}\n330\n{}\n100\nAcDbEntity\n  8\n{}\n{}100\nAcDbFaceRecord\n"
    " 10\n0.0\n 20\n0.0\n 30\n0.0\n 70\n128\n 71\n{}\n 72\n{}\n 73\n{}\n"
)
_SEQEND = re.compile(r"  0\nSEQEND\n  5\n([0-9A-F]+)\n")


def _add_polyfaces(msp, vertices: np.ndarray, faces: np.ndarray, attribs: dict) -> dict:
    """Add a triangle mesh (vertices (n, 3) mm, faces (m, 3) indices) as polyface meshes
    (POLYLINE with the polyface flag), one per :data:`_POLYFACE_TRIANGLES` triangles.

    The POLYLINE entities are added empty; their vertex and face records are returned as DXF
    text keyed by the handle of each polyline's SEQEND, to be spliced in by :func:`dxf_text`.
    ezdxf spends ~0.1 ms creating and ~0.2 ms writing each record, which made DXF the slowest
    export (1.6 s for a 52-object plant); the text takes a few microseconds a record.

    Returns
    -------
    dict of str to str
        SEQEND handle -> the records that precede it.
    """
    doc = msp.doc
    layer = attribs["layer"]
    colour = f"420\n{attribs['true_color']}\n" if "true_color" in attribs else ""
    records = {}
    for first in range(0, len(faces), _POLYFACE_TRIANGLES):
        chunk = faces[first : first + _POLYFACE_TRIANGLES]
        used, local = np.unique(chunk, return_inverse=True)
        local = local.reshape(chunk.shape) + 1  # face records count vertices from 1
        polyface = msp.add_polyface(dxfattribs=attribs)
        polyface.update_count(len(used), len(chunk))
        owner = polyface.dxf.handle
        text = [
            _VERTEX.format(doc.entitydb.next_handle(), owner, layer, x, y, z)
            for x, y, z in vertices[used].tolist()
        ]
        text += [
            _FACE.format(doc.entitydb.next_handle(), owner, layer, colour, a, b, c)
            for a, b, c in local.tolist()
        ]
        records[polyface.seqend.dxf.handle] = "".join(text)
    return records


def _nearest_aci(rgb: tuple[int, int, int]) -> int:
    table = np.array([dxf_colors.int2rgb(v) for v in dxf_colors.DXF_DEFAULT_COLORS[1:256]])
    return int(np.argmin(((table - np.array(rgb)) ** 2).sum(axis=1))) + 1


def _centrelines(geometry) -> list[tuple[np.ndarray, float]]:
    """Centreline polylines of a piping geometry or fitted cylinder, each (k, 3) metres with the
    outside diameter (metres) of the part it runs in; [] for other shapes."""
    if isinstance(geometry, Straight):
        return [(np.array([geometry.start, geometry.end]), 2 * geometry.outer_radius)]
    if isinstance(geometry, Reducer):
        diameter = 2 * max(geometry.outer_radius_start, geometry.outer_radius_end)
        return [(np.array([geometry.start, geometry.end]), diameter)]
    if isinstance(geometry, Cylinder):
        return [(np.array(geometry.ends), 2 * geometry.radius)]
    if isinstance(geometry, Tee):
        return [
            (np.array([geometry.run_start, geometry.run_end]), 2 * geometry.outer_radius),
            (np.array([geometry.center, geometry.branch_end]), 2 * geometry.branch_outer_radius),
        ]
    if isinstance(geometry, Cross):
        return [
            (np.array([geometry.run_start, geometry.run_end]), 2 * geometry.outer_radius),
            (
                np.array([geometry.branch_start, geometry.branch_end]),
                2 * geometry.branch_outer_radius,
            ),
        ]
    if isinstance(geometry, Bend):
        diameter = 2 * geometry.outer_radius
        a = geometry.start - geometry.center
        b = geometry.end - geometry.center
        angle = np.radians(geometry.angle_deg)
        steps = max(2, int(np.ceil(geometry.angle_deg / 5.0)) + 1)
        t = np.linspace(0.0, 1.0, steps)[:, None] * angle
        # Slerp between the two radius vectors (both of length bend_radius).
        sin = np.sin(angle)
        if sin < 1e-12:
            return [(np.array([geometry.start, geometry.end]), diameter)]
        points = (np.sin(angle - t) * a + np.sin(t) * b) / sin
        return [(geometry.center + points, diameter)]
    return []


def _seen_end_on(flat: np.ndarray, line: np.ndarray, diameter: float) -> bool:
    """Whether a straight centreline ``line`` (2, 3) mm, projected to ``flat`` (2, 2) mm, is
    seen (nearly) end-on: its projection is under 1 mm, or shorter than both the part's
    ``diameter`` (mm) and half its true length (it runs steeper than 60 degrees to the view
    and lies inside its own outline). A fitted vertical tank is never exactly vertical: its
    plan centreline was a 2 mm dash where the 3 m circle belongs."""
    if len(flat) > 2:
        return False
    seen = float(np.linalg.norm(flat[-1] - flat[0]))
    true = float(np.linalg.norm(line[-1] - line[0]))
    return seen <= 1.0 or seen < min(diameter, 0.5 * true)


def _outline(points2d: np.ndarray) -> np.ndarray:
    """Convex outline (k, 2) of projected points; a 2-point segment when they are collinear."""
    try:
        hull = ConvexHull(points2d)
        return points2d[hull.vertices]
    except (QhullError, ValueError):
        centre = points2d.mean(axis=0)
        rel = points2d - centre
        _, _, vt = np.linalg.svd(rel, full_matrices=False)
        s = rel @ vt[0]
        return np.array([points2d[np.argmin(s)], points2d[np.argmax(s)]])


def _drawing(cad) -> tuple[ezdxf.document.Drawing, dict]:
    """The drawing with empty polyfaces, and their records (see :func:`_add_polyfaces`)."""
    doc = ezdxf.new("R2018", setup=True, units=ezdxf.units.MM)
    doc.header["$MEASUREMENT"] = 1
    doc.header["$LTSCALE"] = 20.0
    doc.header["$PROJECTNAME"] = cad.name
    msp = doc.modelspace()
    for name, (colour, linetype) in VIEW_LAYERS.items():
        doc.layers.add(name, color=colour, linetype=linetype)

    records = {}
    parts = cad.parts
    meshes = [cad.mesh(part) for part in parts]
    if meshes:
        every = np.concatenate([mesh.vertices for mesh in meshes]) * _MM
        low, high = every.min(axis=0), every.max(axis=0)
    else:
        low = high = np.zeros(3)
    extent = float(max(np.max(high - low), 1000.0))
    text_height = max(25.0, extent / 150.0)
    gap = max(1000.0, 0.15 * extent)
    # The elevation is drawn below the plan: drawing y = z - elevation_shift.
    elevation_shift = high[2] - low[1] + gap

    def plan(points):  # (k, 3) mm -> (k, 2)
        return points[:, :2]

    def elevation(points):
        return np.stack([points[:, 0], points[:, 2] - elevation_shift], axis=1)

    msp.add_text(
        "PLAN (XY)", height=2 * text_height, dxfattribs={"layer": "PLAN-TEXT"}
    ).set_placement((low[0], high[1] + 2 * text_height))
    msp.add_text(
        "ELEVATION (XZ, looking +Y)", height=2 * text_height, dxfattribs={"layer": "ELEV-TEXT"}
    ).set_placement((low[0], high[2] - elevation_shift + 2 * text_height))

    for part, mesh in zip(parts, meshes):
        layer = layer_name(part.component, part.group, part.kind)
        if layer not in doc.layers:
            rgb = rgb255(KIND_COLOURS.get(part.kind, (0.5, 0.5, 0.5, 1.0)))
            entry = doc.layers.add(layer, color=_nearest_aci(rgb))
            entry.rgb = rgb
        attribs = {"layer": layer}
        if part.status in ("error", "warning"):
            attribs["true_color"] = dxf_colors.rgb2int(rgb255(part.colour))
        vertices, faces = mesh.merged()
        records.update(_add_polyfaces(msp, vertices * _MM, faces, attribs))
        if part.insulation:
            continue  # the views draw the component's centreline and label once

        lines = [(line * _MM, d * _MM) for line, d in _centrelines(part.component.geometry)]
        points = mesh.vertices * _MM
        for project, prefix in ((plan, "PLAN"), (elevation, "ELEV")):
            view_attribs = {"layer": f"{prefix}-CENTRELINE"}
            outline_attribs = {"layer": f"{prefix}-OUTLINE"}
            if part.status in ("error", "warning"):
                view_attribs["true_color"] = attribs["true_color"]
                outline_attribs["true_color"] = attribs["true_color"]
            drawn = False
            for line, diameter in lines:
                flat = project(line)
                if not _seen_end_on(flat, line, diameter):
                    msp.add_lwpolyline(flat.tolist(), dxfattribs=view_attribs)
                    drawn = True
            geometry = part.component.geometry
            if isinstance(geometry, Sphere):
                centre = project(geometry.center[None, :] * _MM)[0]
                msp.add_circle(tuple(centre), geometry.radius * _MM, dxfattribs=outline_attribs)
            elif not drawn or not lines:
                outline = _outline(project(points))
                msp.add_lwpolyline(
                    outline.tolist(), close=len(outline) > 2, dxfattribs=outline_attribs
                )
            anchor = project(0.5 * (points.min(axis=0) + points.max(axis=0))[None, :])[0]
            msp.add_text(
                part.id, height=text_height, dxfattribs={"layer": f"{prefix}-TEXT"}
            ).set_placement((anchor[0], anchor[1] + 0.5 * text_height))
    _set_extents(doc, (low, high) if meshes else None)
    doc.ezdxf_metadata()["CREATED_BY"] = f"asbuilt {__version__}"
    return doc, records


def dxf_text(cad) -> tuple[str, ezdxf.document.Drawing]:
    """The DXF file's text (millimetres, see the module docstring) and the drawing without its
    polyface records, whose :meth:`~ezdxf.document.Drawing.encode` encodes the text.

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
        Meshes in metres; converted to millimetres here.
    """
    doc, records = _drawing(cad)
    return _spliced(doc, records), doc


def _spliced(doc, records: dict) -> str:
    """The text of ``doc`` with each polyface's ``records`` spliced in before its SEQEND."""
    stream = io.StringIO()
    doc.write(stream)

    def splice(match: re.Match) -> str:
        return records.get(match.group(1), "") + match.group(0)

    text, spliced = _SEQEND.subn(splice, stream.getvalue())
    if spliced < len(records):  # pragma: no cover - ezdxf changed how it writes SEQEND
        raise RuntimeError("DXF export: a polyface's SEQEND was not found in ezdxf's output")
    return text


def dxf_document(cad) -> ezdxf.document.Drawing:
    """The DXF drawing of a CAD model (millimetres), as read back from :func:`dxf_text`.

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
        Meshes in metres; converted to millimetres here.
    """
    return ezdxf.read(io.StringIO(dxf_text(cad)[0]))


#: The viewport's aspect ratio assumed when fitting the drawing's width (a 4:3 window; wider ones
#: show a margin) and the margin around the drawing.
_VIEW_ASPECT = 4 / 3
_VIEW_MARGIN = 1.1


def _set_extents(doc, mesh_box) -> None:
    """Record the model space's extents ($EXTMIN/$EXTMAX) and centre the *Active viewport on them.

    ezdxf writes the header's extents from the model space layout's ``extmin``/``extmax`` on
    save, so those are set: ezdxf's bounding box of the 2D views and text, and ``mesh_box``,
    the meshes' (low, high) corners (each (3,) mm) or None, since the polyfaces are still empty.
    """
    msp = doc.modelspace()
    box = ezdxf.bbox.extents(msp.query("LWPOLYLINE CIRCLE TEXT"), fast=True)
    if mesh_box is not None:
        box.extend([tuple(float(v) for v in corner) for corner in mesh_box])
    if not box.has_data:
        doc.set_modelspace_vport(height=10_000)
        return
    low, high = (tuple(float(v) for v in box.extmin), tuple(float(v) for v in box.extmax))
    msp.dxf.extmin = low
    msp.dxf.extmax = high
    doc.header["$EXTMIN"] = low
    doc.header["$EXTMAX"] = high
    width, height = high[0] - low[0], high[1] - low[1]
    doc.set_modelspace_vport(
        height=_VIEW_MARGIN * max(height, width / _VIEW_ASPECT, 1.0),
        center=(0.5 * (low[0] + high[0]), 0.5 * (low[1] + high[1])),
    )


def write_dxf(cad, path) -> None:
    """Write the CAD model as DXF R2018 to ``path`` (millimetres).

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
    path : str or Path
        Written directly; callers stage it for atomicity (:mod:`asbuilt.export`).
    """
    text, doc = dxf_text(cad)
    with open(path, "wb") as stream:
        stream.write(doc.encode(text))
