"""Crosses in every export: the model document (and its schema) round trip, the PCF ``CROSS``
block, the IFC junction with four ports, DXF centrelines, and an end-to-end ``asbuilt model`` of
a simulated cross scan (``asbuilt simulate``) to .step, .glb, .dxf, .pcf, .ifc and .json."""

from __future__ import annotations

import json
import sys
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "merge"))
from synthetic_pipes import Pipe, report_of  # noqa: E402

from asbuilt.cli import main  # noqa: E402
from asbuilt.export import export_model  # noqa: E402
from asbuilt.export.dxf import _centrelines  # noqa: E402
from asbuilt.export.model_json import (  # noqa: E402
    dumps_model,
    loads_model_document,
    model_from_document,
    model_schema,
)
from asbuilt.export.pcf import pcf_text  # noqa: E402
from asbuilt.merge import merge_model  # noqa: E402
from asbuilt.model import Cross  # noqa: E402

NPS6, NPS4 = 0.1683, 0.1143


@pytest.fixture(scope="module")
def model():
    """A 6 x 4 reducing cross at (2, 0, 0): run P1-P2 along x, outlets P3 (+y), P4 (-y)."""
    pipes = [
        Pipe("P1", (0, 0, 0), (1.85, 0, 0), NPS6),
        Pipe("P2", (2.15, 0, 0), (4, 0, 0), NPS6),
        Pipe("P3", (2, 0.15, 0), (2, 2, 0), NPS4),
        Pipe("P4", (2, -0.15, 0), (2, -2, 0), NPS4),
    ]
    return merge_model(report_of(pipes, links=[("P1", "P2"), ("P3", "P4")]))


def _cross(model):
    (cross,) = [c for c in model.components if c.type == "cross"]
    return cross


def test_the_model_document_round_trips_a_cross(model):
    text = dumps_model(model)
    document = loads_model_document(text)
    (entry,) = [c for c in document["components"] if c["type"] == "cross"]
    assert entry["shape"] == "cross" and len(entry["outlets"]) == 2
    jsonschema = pytest.importorskip("jsonschema")
    jsonschema.validate(json.loads(text), model_schema())
    again = _cross(model_from_document(document))
    g, h = _cross(model).geometry, again.geometry
    assert isinstance(h, Cross)
    for name in ("center", "run_start", "run_end", "branch_start", "branch_end"):
        assert np.allclose(getattr(g, name), getattr(h, name), atol=1e-9)
    for name in ("outer_radius", "branch_outer_radius", "wall", "branch_wall"):
        assert getattr(h, name) == pytest.approx(getattr(g, name))
    assert again.snap["connects"] == ["P1", "P2", "P3", "P4"]


def test_a_document_cross_missing_an_outlet_is_refused(model):
    document = loads_model_document(dumps_model(model))
    (entry,) = [c for c in document["components"] if c["type"] == "cross"]
    entry["outlets"] = entry["outlets"][:1]
    with pytest.raises(Exception, match="outlets"):
        model_from_document(document)


def test_pcf_writes_a_cross_block_with_two_branch_points(model):
    text = pcf_text(model).replace("\r\n", "\n")  # PCF lines end CR LF
    block = text[text.index("\nCROSS\n") + 1 :].split("\n")
    body = [line.strip() for line in block[1:8]]
    assert body == [
        "END-POINT 1857.0 0.0 0.0 6",
        "END-POINT 2143.0 0.0 0.0 6",
        "CENTRE-POINT 2000.0 0.0 0.0",
        "BRANCH1-POINT 2000.0 130.0 0.0 4",
        "BRANCH2-POINT 2000.0 -130.0 0.0 4",
        "SKEY CRBW",
        "ITEM-CODE CROSS-6X4IN-STD",
    ]
    assert "COMPONENT-ATTRIBUTE1 P1-P2-P3-P4" in block[8]


def test_dxf_draws_the_run_and_the_outlet_line(model):
    g = _cross(model).geometry
    (run, run_od), (outlets, outlet_od) = _centrelines(g)
    assert np.allclose(run, [g.run_start, g.run_end]) and np.allclose(
        outlets, [g.branch_start, g.branch_end]
    )
    assert (run_od, outlet_od) == (2 * g.outer_radius, 2 * g.branch_outer_radius)


@pytest.mark.skipif(find_spec("ifcopenshell") is None, reason="ifcopenshell is not installed")
def test_ifc_writes_a_junction_pipe_fitting_with_four_ports(model, tmp_path):
    import ifcopenshell

    path = tmp_path / "cross.ifc"
    export_model(model, path)
    ifc = ifcopenshell.open(str(path))
    (fitting,) = [e for e in ifc.by_type("IfcPipeFitting") if e.Name == _cross(model).id]
    assert fitting.PredefinedType == "JUNCTION"
    ports = [p for rel in fitting.IsNestedBy for p in rel.RelatedObjects]
    assert len(ports) == 4
    connected = [p for p in ports if p.ConnectedTo or p.ConnectedFrom]
    assert len(connected) == 4


SCENE = {
    "format": "asbuilt-scene",
    "version": 1,
    "units": "m",
    "name": "cross",
    "seed": 3,
    "points": 40,
    "stations": [
        {"id": "S1", "position": [3.5, 3.0, 2.5], "range_sigma": 0.002},
        {"id": "S2", "position": [0.5, -3.0, 2.5], "range_sigma": 0.002},
    ],
    "objects": [
        {"id": "P1", "kind": "cylinder", "nominal": '6"', "group": "X-1",
         "geometry": {"type": "cylinder", "start": [0, 0, 1], "end": [1.82, 0, 1], "od": NPS6}},
        {"id": "P2", "kind": "cylinder", "nominal": '6"', "group": "X-1",
         "geometry": {"type": "cylinder", "start": [2.18, 0, 1], "end": [4, 0, 1], "od": NPS6}},
        {"id": "P3", "kind": "cylinder", "nominal": '4"', "group": "X-1",
         "geometry": {"type": "cylinder", "start": [2, 0.16, 1], "end": [2, 2, 1], "od": NPS4}},
        {"id": "P4", "kind": "cylinder", "nominal": '4"', "group": "X-1",
         "geometry": {"type": "cylinder", "start": [2, -0.16, 1], "end": [2, -2, 1], "od": NPS4}},
        {"id": "floor", "scan": False, "geometry": {"type": "ground"}},
    ],
}  # fmt: skip


def test_a_simulated_cross_scan_models_to_every_format(tmp_path):
    scene, scan = tmp_path / "cross.scene.json", tmp_path / "scan.json"
    scene.write_text(json.dumps(SCENE))
    assert main(["simulate", str(scene), "--out", str(scan)]) == 0
    outs = [tmp_path / f"cross{suffix}" for suffix in (".json", ".step", ".glb", ".dxf", ".pcf")]
    args = ["model", str(scan), "--quiet"]
    for out in outs:
        args += ["--out", str(out)]
    assert main(args) == 0
    assert all(out.stat().st_size > 0 for out in outs)
    document = json.loads(outs[0].read_text())
    (cross,) = [c for c in document["components"] if c["type"] == "cross"]
    assert cross["id"] == "P1-P2-P3-P4" and cross["spool"] == "X-1"
    assert not [c for c in document["components"] if c["snap"].get("loose_ends")]
    assert "\nCROSS\n" in outs[4].read_text().replace("\r\n", "\n")
    # the STEP file reads back as valid solids, the cross among them
    import cadquery as cq
    from OCP.BRepCheck import BRepCheck_Analyzer

    shape = cq.importers.importStep(str(outs[1])).val()
    assert BRepCheck_Analyzer(shape.wrapped).IsValid()
    assert b"P1-P2-P3-P4" in outs[1].read_bytes()
