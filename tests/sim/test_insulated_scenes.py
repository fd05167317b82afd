"""Insulated pipes in scenes: the beams hit the cladding, the scan says how thick it is, the
truth stays the bare pipe, and modelling the scan finds the pipe inside."""

import json

import numpy as np
import pytest

from asbuilt.cli import main
from asbuilt.errors import SceneError
from asbuilt.primitives import Cylinder
from asbuilt.scan import loads_scan
from asbuilt.sim.scene import ELBOW_CLADDING_ROOM, scene_from_dict
from asbuilt.sim.simulate import dumps_scan, simulate_scan

OD4 = 0.1143  # NPS 4, ASME B36.10M
T = 0.05


def _axis_distance(points, cylinder: Cylinder) -> np.ndarray:
    rel = np.asarray(points) - cylinder.center
    return np.linalg.norm(rel - np.outer(rel @ cylinder.axis, cylinder.axis), axis=1)


def test_points_on_the_cladding_truth_bare(scene_doc):
    scene_doc["objects"][0]["insulation"] = T
    scene = scene_from_dict(scene_doc)
    pipe = scene.object("P1")
    assert pipe.insulation == T
    assert pipe.truth.radius == pytest.approx(OD4 / 2)  # the bare pipe
    assert pipe.shape.radius == pytest.approx(OD4 / 2 + T)  # what the beams hit
    doc = simulate_scan(scene, seed=1)
    (obj,) = [o for o in doc["objects"] if o["id"] == "P1"]
    r = _axis_distance(obj["points"], pipe.truth)
    assert len(r) >= 25
    assert np.median(np.abs(r - (OD4 / 2 + T))) < 0.003  # range sigma 2 mm
    assert np.min(r) > OD4 / 2 + T - 0.01  # none reaches the bare pipe
    # the others are untouched and carry no insulation
    assert all("insulation" not in o for o in doc["objects"] if o["id"] != "P1")


@pytest.mark.parametrize(("units", "factor"), [("m", 1.0), ("mm", 1e-3), ("in", 0.0254)])
def test_scan_carries_the_thickness_in_its_units(scene_doc, units, factor):
    scene_doc["units"] = units
    scene_doc["stations"][0]["position"] = [0.0, 0.0, 1.5 / factor]
    geo = scene_doc["objects"][0]["geometry"]
    geo.update(start=[-1.0 / factor, 5.0 / factor, 1.0 / factor])
    geo.update(end=[1.0 / factor, 5.0 / factor, 1.0 / factor], od=OD4 / factor)
    scene_doc["objects"] = scene_doc["objects"][:1]
    scene_doc["objects"][0]["insulation"] = T / factor
    doc = simulate_scan(scene_from_dict(scene_doc), seed=2)
    assert doc["objects"][0]["insulation"] == pytest.approx(T / factor, rel=1e-5)  # 6 digits
    scan = loads_scan(dumps_scan(doc), source="sim.json")
    assert scan.object("P1").insulation == pytest.approx(T, rel=1e-5)


def test_zero_insulation_changes_nothing(scene_doc):
    bare = dumps_scan(simulate_scan(scene_from_dict(scene_doc), seed=3))
    scene_doc["objects"][0]["insulation"] = 0
    assert dumps_scan(simulate_scan(scene_from_dict(scene_doc), seed=3)) == bare


def _run_doc(insulation=T, od=OD4, units="m") -> dict:
    """An NPS 4 pipe run along x then up, with its elbow, from a station 5 m away."""
    return {
        "format": "asbuilt-scene",
        "units": units,
        "seed": 11,
        "points": 30,
        "stations": [
            {"id": "S1", "position": [0.0, 0.0, 1.5], "dropout": 0.02, "mixed_return": 0.5}
        ],
        "objects": [
            {
                "id": "L",
                "kind": "cylinder",
                "group": "L-1",
                "insulation": insulation,
                "geometry": {
                    "type": "pipe_run",
                    "path": [[-1.5, 5.0, 1.0], [1.0, 5.0, 1.0], [1.0, 5.0, 3.0]],
                    "od": od,
                    "bend_radius": 0.152,
                },
            },
            {"id": "floor", "scan": False, "geometry": {"type": "ground"}},
        ],
    }


def test_pipe_run_elbows_clad_truths_bare():
    scene = scene_from_dict(_run_doc())
    for leg in ("L-1", "L-2"):
        obj = scene.object(leg)
        assert obj.truth.radius == pytest.approx(OD4 / 2)
        assert obj.shape.radius == pytest.approx(OD4 / 2 + T)
    elbow = scene.object("L-E1")
    # same parametrisation: each cladding vertex lies T outside its bare vertex
    grown = np.linalg.norm(elbow.shape.vertices - elbow.truth.vertices, axis=1)[
        :-2
    ]  # not the cap centres
    np.testing.assert_allclose(grown, T, atol=1e-9)
    # a thick lagging on a tight bend is mitred to a share of the bend radius
    thick = scene_from_dict(_run_doc(insulation=0.2)).object("L-E1")
    grown = np.linalg.norm(thick.shape.vertices - thick.truth.vertices, axis=1)[
        :-2
    ]  # not the cap centres
    np.testing.assert_allclose(grown, ELBOW_CLADDING_ROOM * 0.152 - OD4 / 2, atol=1e-9)
    # the straights still stop short of the corner by the elbow's centre-to-end
    assert scene.object("L-1").truth.length == pytest.approx(2.5 - 0.152)


def test_elbow_geometry_is_clad():
    doc = _run_doc()
    doc["objects"].append(
        {
            "id": "E9",
            "scan": False,
            "insulation": T,
            "geometry": {
                "type": "elbow",
                "from": [0, 8, 1],
                "corner": [1, 8, 1],
                "to": [1, 8, 2],
                "bend_radius": 0.152,
                "od": OD4,
            },
        }
    )
    elbow = scene_from_dict(doc).object("E9")
    grown = np.linalg.norm(elbow.shape.vertices - elbow.truth.vertices, axis=1)[
        :-2
    ]  # not the cap centres
    np.testing.assert_allclose(grown, T, atol=1e-9)


def test_model_snaps_the_pipe_inside(tmp_path, capsys):
    """50 mm of lagging on NPS 4: the cladding is 214 mm across (NPS 8 by its size); modelled
    with the thickness the pipes and the elbow come out NPS 4 and carry it."""
    scene = scene_from_dict(_run_doc())
    doc = simulate_scan(scene)
    assert [o["insulation"] for o in doc["objects"]] == [T, T]
    scan = tmp_path / "lagged.json"
    scan.write_text(dumps_scan(doc))
    out = tmp_path / "model.json"
    assert main(["model", str(scan), "--out", str(out), "--quiet"]) == 0
    model = json.loads(out.read_text())
    pipes = [c for c in model["components"] if c["type"] == "pipe"]
    assert sorted(c["source"] for c in pipes) == ["L-1", "L-2"]
    assert {c["type"] for c in model["components"]} >= {"pipe", "elbow"}
    for comp in model["components"]:
        assert comp["nominal"] == "4"
        assert comp["insulation"] == pytest.approx(T)
    for pipe in pipes:
        assert pipe["od"] == pytest.approx(OD4)
    # the same points without the thickness are taken for a far bigger pipe
    for obj in doc["objects"]:
        del obj["insulation"]
    scan.write_text(dumps_scan(doc))
    assert main(["model", str(scan), "--out", str(out), "--quiet"]) == 0
    bare = json.loads(out.read_text())
    assert {c["nominal"] for c in bare["components"] if c["type"] == "pipe"} != {"4"}


BAD = [
    (lambda o: o.update(insulation=-0.01), "objects[0] (P1).insulation: must be at least 0"),
    (lambda o: o.update(insulation="50 mm"), "objects[0] (P1).insulation: must be a number"),
    (lambda o: o.update(insulation=True), "objects[0] (P1).insulation: must be a number"),
    (
        lambda o: o.update(insulation=50),
        "objects[0] (P1).insulation: 50 m is thicker than any pipe insulation (at most 0.5 m)",
    ),
    (
        lambda o: o.update(insulation=0.05, kind="auto"),
        'objects[0] (P1).insulation: the scan carries insulation on a cylinder only, not on kind "auto"',
    ),
    (
        lambda o: o.update(
            insulation=0.05,
            geometry={"type": "sphere", "center": [0, 5, 1], "diameter": 0.6},
        ),
        "objects[0] (P1).insulation: insulation wraps a pipe, not geometry type 'sphere'",
    ),
    (
        lambda o: o.update(
            insulation=0.05,
            geometry={"type": "tank", "base": [0, 5, 0], "height": 3, "diameter": 2},
        ),
        "not geometry type 'tank'; use it on cylinder, pipe_run, elbow or remove it",
    ),
]


@pytest.mark.parametrize("mutate, message", BAD)
def test_bad_insulation_one_located_line(scene_doc, mutate, message):
    mutate(scene_doc["objects"][0])
    with pytest.raises(SceneError) as info:
        scene_from_dict(scene_doc, source="bad.json")
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith("bad.json: ")
    assert message in text


def test_unscanned_insulated_cylinder_is_fine(scene_doc):
    """Background pipes (a tee's run, say) may be clad too; any kind is moot when unscanned."""
    scene_doc["objects"][0].update(insulation=0.05, scan=False, kind="auto")
    scene = scene_from_dict(scene_doc)
    assert scene.object("P1").shape.radius == pytest.approx(OD4 / 2 + 0.05)


def test_the_simulator_mitres_elbow_cladding_as_cad_draws_it():
    # a copy (the simulator does not import the model package), kept equal here
    from asbuilt.insulation import JACKET_ROOM
    from asbuilt.sim.scene import ELBOW_CLADDING_ROOM

    assert ELBOW_CLADDING_ROOM == JACKET_ROOM
