"""DXF: audit-clean, millimetres, one layer per kind/size/group, meshes and 2D views."""

from __future__ import annotations

from collections import Counter

import ezdxf
import numpy as np
import pytest
from ezdxf.lldxf.validator import is_valid_layer_name

from asbuilt.cad.colours import STATUS_COLOURS, rgb255
from asbuilt.export.dxf import VIEW_LAYERS, dxf_document, layer_name, write_dxf
from asbuilt.model import Component, Straight


def _counts(doc) -> Counter:
    return Counter((e.dxf.layer, e.dxftype()) for e in doc.modelspace())


@pytest.fixture(scope="module")
def written(zoo_cad, tmp_path_factory):
    path = tmp_path_factory.mktemp("dxf") / "zoo.dxf"
    write_dxf(zoo_cad, path)
    return path


def test_audit_has_no_errors_and_reopens_with_the_same_layers_and_counts(zoo_cad, written):
    in_memory = dxf_document(zoo_cad)
    doc = ezdxf.readfile(written)
    auditor = doc.audit()
    assert not auditor.has_errors, [str(e) for e in auditor.errors]
    assert {layer.dxf.name for layer in doc.layers} == {
        layer.dxf.name for layer in in_memory.layers
    }
    assert _counts(doc) == _counts(in_memory)


def test_units_are_millimetres(written):
    doc = ezdxf.readfile(written)
    assert doc.header["$INSUNITS"] == 4
    assert doc.header["$MEASUREMENT"] == 1


def _polyfaces(doc) -> list:
    return [e for e in doc.modelspace() if e.dxftype() == "POLYLINE" and e.is_poly_face_mesh]


def test_one_polyface_per_object_on_kind_size_group_layers(zoo_cad, written):
    doc = ezdxf.readfile(written)
    assert not doc.modelspace().query("MESH")  # skipped by many readers
    polyfaces = _polyfaces(doc)
    assert len(polyfaces) == len(zoo_cad.parts)
    layers = [m.dxf.layer for m in polyfaces]
    assert layers == [
        "P-PIPE-NPS4-S1",
        "P-ELBOW-NPS4-S1",
        "P-PIPE-NPS4-S1",
        "P-TEE-S2",
        "P-REDUCER-S2",
        "ASBUILT-CYLINDER-FRAME",
        "ASBUILT-CUBOID-FRAME",
        "ASBUILT-SPHERE",
        "ASBUILT-PLANE",
        "ASBUILT-HULL",
    ]


def test_polyfaces_are_the_model_in_millimetres(zoo_cad, written):
    """Vertices span the mesh's box and the faces enclose its volume (divergence theorem)."""
    doc = ezdxf.readfile(written)
    polyfaces = _polyfaces(doc)
    assert len(polyfaces) == len(zoo_cad.parts)
    for part, entity in zip(zoo_cad.parts, polyfaces):
        tri = _triangles(entity)
        points = tri.reshape(-1, 3)
        expected = zoo_cad.mesh(part)
        assert points.min(axis=0) == pytest.approx(expected.vertices.min(axis=0) * 1e3, abs=1e-6)
        assert points.max(axis=0) == pytest.approx(expected.vertices.max(axis=0) * 1e3, abs=1e-6)
        volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
        assert volume == pytest.approx(expected.volume * 1e9, rel=1e-6), part.id


def test_findings_colour_the_entities(written):
    doc = ezdxf.readfile(written)
    cuboid = next(e for e in _polyfaces(doc) if e.dxf.layer.startswith("ASBUILT-CUBOID"))
    assert cuboid.rgb == rgb255(STATUS_COLOURS["error"])


def _triangles(polyface) -> np.ndarray:
    """A polyface's triangles (k, 3, 3) from its records: vertices first (flags 64 + 128),
    then face records (flag 128 only) with 1-based indices vtx0..vtx2 (negative: edge hidden)."""
    points, faces = [], []
    for vertex in polyface.vertices:
        if vertex.dxf.flags & ezdxf.const.VTX_3D_POLYGON_MESH_VERTEX:
            points.append(tuple(vertex.dxf.location))
        else:
            faces.append([abs(vertex.dxf.get(f"vtx{k}")) - 1 for k in range(3)])
    return np.array(points)[np.array(faces)]


def test_large_meshes_are_split_into_polyfaces_of_at_most_32767_vertices(tmp_path, monkeypatch):
    """Face records index vertices with 16-bit integers; the split is tested at a small size."""
    from asbuilt.export import dxf

    assert 3 * dxf._POLYFACE_TRIANGLES <= 32767
    monkeypatch.setattr(dxf, "_POLYFACE_TRIANGLES", 50)
    doc = ezdxf.new("R2018")
    rng = np.random.default_rng(3)
    vertices = rng.uniform(0, 1000, size=(200, 3))
    faces = rng.integers(0, len(vertices), size=(120, 3))
    records = dxf._add_polyfaces(doc.modelspace(), vertices, faces, {"layer": "X"})
    path = tmp_path / "big.dxf"
    path.write_bytes(doc.encode(dxf._spliced(doc, records)))
    reread = ezdxf.readfile(path)
    assert not reread.audit().has_errors
    polyfaces = _polyfaces(reread)
    assert [p.dxf.n_count for p in polyfaces] == [50, 50, 20]
    assert all(p.dxf.m_count <= 150 for p in polyfaces)
    triangles = np.concatenate([_triangles(p) for p in polyfaces])
    assert triangles == pytest.approx(vertices[faces], abs=1e-9)


def test_plan_and_elevation_views_with_centrelines_outlines_and_ids(zoo_cad, written):
    doc = ezdxf.readfile(written)
    msp = doc.modelspace()
    for layer in VIEW_LAYERS:
        assert layer in doc.layers
    # Centrelines seen in plan: P1, E1, P2, R1 and T1's run (its branch and the column CY are
    # vertical and collapse to points); in elevation: P1, E1, T1's run and branch, R1 and CY
    # (P2 runs along y and collapses).
    for prefix, count in (("PLAN", 5), ("ELEV", 6)):
        texts = {e.dxf.text for e in msp.query(f'TEXT[layer=="{prefix}-TEXT"]')}
        assert {part.id for part in zoo_cad.parts} <= texts
        centrelines = msp.query(f'LWPOLYLINE[layer=="{prefix}-CENTRELINE"]')
        assert len(centrelines) == count
    # The vertical column gets its outline (a 300 mm circle's polygon) in plan instead.
    outlines = msp.query('LWPOLYLINE[layer=="PLAN-OUTLINE"]')
    column = [
        e
        for e in outlines
        if np.allclose(np.mean([p[:2] for p in e.get_points()], axis=0), [5000, 0], atol=1.0)
    ]
    assert len(column) == 1 and column[0].closed
    assert doc.layers.get("PLAN-CENTRELINE").dxf.linetype == "CENTER"
    # The elbow's plan centreline is a quarter arc of radius 200 mm about (1000, 200).
    elbow = [e for e in msp.query('LWPOLYLINE[layer=="PLAN-CENTRELINE"]') if len(e) > 2]
    points = np.array([p[:2] for p in elbow[0].get_points()])
    assert np.linalg.norm(points - [1000, 200], axis=1) == pytest.approx(200.0, abs=1e-6)
    # A sphere is a circle in both views.
    circles = msp.query("CIRCLE")
    assert sorted(c.dxf.layer for c in circles) == ["ELEV-OUTLINE", "PLAN-OUTLINE"]
    assert all(c.dxf.radius == pytest.approx(500.0) for c in circles)


@pytest.mark.parametrize(
    ("type_", "nominal", "group", "expected"),
    [
        ("pipe", "4", "S1", "P-PIPE-NPS4-S1"),
        ("pipe", "4", None, "P-PIPE-NPS4"),
        ("elbow", "1-1/2", "line 7", "P-ELBOW-NPS1-1_2-LINE_7"),
        ("cuboid", None, "columns", "ASBUILT-CUBOID-COLUMNS"),
        ("cylinder", None, None, "ASBUILT-CYLINDER"),
    ],
)
def test_layer_names(type_, nominal, group, expected):
    component = Component("X", type_, Straight([0, 0, 0], [1, 0, 0], 0.05), nominal=nominal)
    name = layer_name(component, group)
    assert name == expected
    assert is_valid_layer_name(name)


def _drawn_points(doc) -> np.ndarray:
    """Every vertex, polyline point, text insert and circle bound of the model space (mm)."""
    points = []
    for entity in doc.modelspace():
        kind = entity.dxftype()
        if kind == "MESH":
            points.extend(tuple(v) for v in entity.vertices)
        elif kind == "POLYLINE":
            points.extend(tuple(v.dxf.location) for v in entity.vertices)
        elif kind == "LWPOLYLINE":
            points.extend((x, y, 0.0) for x, y in entity.get_points("xy"))
        elif kind == "TEXT":
            points.append(tuple(entity.dxf.insert))
        elif kind == "CIRCLE":
            c, r = entity.dxf.center, entity.dxf.radius
            points.extend([(c.x - r, c.y - r, c.z), (c.x + r, c.y + r, c.z)])
    return np.array(points, dtype=float)


def test_extents_and_view_cover_the_drawing(written):
    doc = ezdxf.readfile(written)
    low = np.array(doc.header["$EXTMIN"], dtype=float)
    high = np.array(doc.header["$EXTMAX"], dtype=float)
    points = _drawn_points(doc)
    assert np.all(low <= points.min(axis=0) + 1e-6)
    assert np.all(high >= points.max(axis=0) - 1e-6)
    # ...and no more than the texts' widths beyond them (not the 1e20 "unset" values).
    assert np.all(points.min(axis=0) - low < 2000.0)
    assert np.all(high - points.max(axis=0) < 2000.0)
    (active,) = doc.viewports.get("*Active")
    centre = np.array(tuple(active.dxf.center)[:2], dtype=float)
    assert centre == pytest.approx(0.5 * (low[:2] + high[:2]))
    assert active.dxf.height >= high[1] - low[1]


def test_long_group_names_give_distinct_layers_within_255_characters(tmp_path):
    from asbuilt.cad import prepare
    from asbuilt.model import Model

    groups = ["Halle A " + "x" * 300 + " Achse 1", "Halle A " + "x" * 300 + " Achse 2"]
    components = tuple(
        Component(f"P{i}", "pipe", Straight([i, 0, 0], [i + 1, 0, 0], 0.05), group=group)
        for i, group in enumerate(groups)
    )
    names = [layer_name(c, c.group) for c in components]
    assert all(len(name) <= 255 for name in names)  # AutoCAD's limit
    assert names[0] != names[1]
    assert names[0].startswith("P-PIPE-HALLE_A_XXX")
    assert names == [layer_name(c, c.group) for c in components]  # deterministic
    short = Component("S", "pipe", Straight([0, 0, 0], [1, 0, 0], 0.05))
    assert layer_name(short, "S1") == "P-PIPE-S1"  # short names unchanged
    path = tmp_path / "long.dxf"
    write_dxf(prepare(Model(components=components, units="m", name="long")), path)
    doc = ezdxf.readfile(path)
    assert not doc.audit().has_errors
    layers = {layer.dxf.name for layer in doc.layers}
    assert set(names) <= layers and all(len(name) <= 255 for name in layers)


_DXF_PARSER_SCRIPT = """
const DxfParser = require(require('path').join(process.argv[1], 'dxf-parser'));
const text = require('fs').readFileSync(process.argv[2], 'utf8');
const doc = new DxfParser().parseSync(text);
const out = doc.entities.filter((e) => e.type === 'POLYLINE' && e.isPolyfaceMesh).map((e) => {
  const points = e.vertices.filter((v) => v.faceA === undefined);
  const faces = e.vertices.filter((v) => v.faceA !== undefined);
  let volume = 0;  // divergence theorem over the triangles, mm^3
  for (const f of faces) {
    const [a, b, c] = [f.faceA, f.faceB, f.faceC].map((i) => points[Math.abs(i) - 1]);
    volume += (a.x * (b.y * c.z - b.z * c.y) - a.y * (b.x * c.z - b.z * c.x)
               + a.z * (b.x * c.y - b.y * c.x)) / 6;
  }
  return {layer: e.layer, faces: faces.length, volume: volume};
});
console.log(JSON.stringify(out));
"""


def test_web_dxf_parser_reads_every_object(zoo_cad, written):
    """npm dxf-parser (used by web viewers such as three-dxf) drops MESH entities silently; it
    reads polyface meshes. Set ASBUILT_NODE_MODULES to a node_modules with dxf-parser."""
    import json
    import os
    import shutil
    import subprocess
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    candidates = [os.environ.get("ASBUILT_NODE_MODULES"), root / ".ci" / "node" / "node_modules"]
    modules = next(
        (Path(c) for c in candidates if c and (Path(c) / "dxf-parser" / "package.json").is_file()),
        None,
    )
    node = shutil.which("node")
    if node is None or modules is None:
        pytest.skip("node or the npm package dxf-parser not found (set ASBUILT_NODE_MODULES)")
    result = subprocess.run(
        [node, "-e", _DXF_PARSER_SCRIPT, str(modules), str(written)],
        capture_output=True,
        text=True,
        timeout=60,
        check=True,
    )
    read = json.loads(result.stdout)
    assert [entry["layer"] for entry in read] == [
        layer_name(part.component, part.group) for part in zoo_cad.parts
    ]
    for entry, part in zip(read, zoo_cad.parts):
        assert entry["faces"] == len(zoo_cad.mesh(part).merged()[1])
        assert entry["volume"] == pytest.approx(zoo_cad.mesh(part).volume * 1e9, rel=1e-6)
