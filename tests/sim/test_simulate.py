"""simulate_scan: a valid, deterministic asbuilt-scan document the loader accepts."""

import json

import numpy as np
import pytest

from asbuilt.errors import SceneError
from asbuilt.scan import loads_scan
from asbuilt.sim.raycast import direction_from_angles
from asbuilt.sim.scene import scene_from_dict
from asbuilt.sim.simulate import default_decimals, dumps_scan, simulate_scan


def test_document_shape_and_loader_accepts(scene_doc):
    scene = scene_from_dict(scene_doc)
    doc = simulate_scan(scene, seed=1)
    assert doc["format"] == "asbuilt-scan" and doc["version"] == 1 and doc["units"] == "m"
    assert [o["id"] for o in doc["objects"]] == ["P1", "C1", "S1"]
    assert doc["sensor"] == {"position": [0.0, 0.0, 1.5], "range_sigma": 0.002}
    scan = loads_scan(dumps_scan(doc), source="sim.json")
    pipe = scan.object("P1")
    assert pipe.kind == "cylinder" and pipe.nominal == '4"' and pipe.group == "G1"
    assert scan.object("C1").label == "column"
    for obj in scan.objects:
        assert 25 <= len(obj.points) <= 40
        truth = scene.object(obj.id).truth
        d = truth.distance(obj.points)
        assert np.median(np.abs(d)) < 0.004  # range sigma 2 mm; edges may add outliers
        assert obj.measurements.shape == (len(obj.points), 3)


def test_measurements_reproduce_points(scene_doc):
    scene = scene_from_dict(scene_doc)
    doc = simulate_scan(scene, seed=2)
    station = np.array(doc["sensor"]["position"])
    for obj in doc["objects"]:
        m = np.array(obj["measurements"])
        pts = station + m[:, 2:3] * direction_from_angles(np.radians(m[:, 0]), np.radians(m[:, 1]))
        np.testing.assert_allclose(pts, obj["points"], atol=2e-4)


def test_deterministic_per_seed(scene_doc):
    scene = scene_from_dict(scene_doc)
    a = dumps_scan(simulate_scan(scene, seed=9))
    b = dumps_scan(simulate_scan(scene, seed=9))
    c = dumps_scan(simulate_scan(scene, seed=10))
    assert a == b and a != c
    assert json.loads(a)["simulation"]["seed"] == 9
    # the scene's own seed is the default
    assert simulate_scan(scene)["simulation"]["seed"] == 5


def test_objects_draw_independently(scene_doc):
    scene = scene_from_dict(scene_doc)
    full = simulate_scan(scene, seed=3)
    scene_doc["objects"][2]["scan"] = False  # drop the ball: the others are unchanged
    fewer = simulate_scan(scene_from_dict(scene_doc), seed=3)
    assert fewer["objects"] == full["objects"][:2]


@pytest.mark.parametrize("units", ["mm", "in", "ft"])
def test_written_in_scene_units(scene_doc, units):
    scene = scene_from_dict(scene_doc)
    metres = simulate_scan(scene, seed=4, exact=True)
    factor = {"mm": 1e-3, "in": 0.0254, "ft": 0.3048}[units]

    def convert(value):
        return (np.array(value) / factor).tolist()

    scene_doc["units"] = units
    scene_doc["stations"][0]["position"] = convert([0.0, 0.0, 1.5])
    for obj in scene_doc["objects"]:
        geo = obj["geometry"]
        for key in ("start", "end", "center", "point"):
            if key in geo:
                geo[key] = convert(geo[key])
        for key in ("od", "diameter", "thickness"):
            if key in geo:
                geo[key] = geo[key] / factor
        for key in ("section", "size"):
            if key in geo:
                geo[key] = convert(geo[key])
    other = simulate_scan(scene_from_dict(scene_doc), seed=4, exact=True)
    assert other["units"] == units
    scan = loads_scan(dumps_scan(other))
    for obj, ref in zip(scan.objects, metres["objects"]):
        np.testing.assert_allclose(obj.points, ref["points"], atol=2e-4)
    assert scan.sensor.range_sigma == pytest.approx(0.002)


def test_points_override_and_exact(scene_doc):
    doc = simulate_scan(scene_from_dict(scene_doc), points=20, exact=True)
    assert [len(o["points"]) for o in doc["objects"]] == [20, 20, 20]


def test_second_station_is_recorded(scene_doc):
    scene_doc["stations"].append({"id": "S2", "position": [3.0, 0.0, 1.5]})
    scene_doc["objects"][1]["station"] = "S2"
    doc = simulate_scan(scene_from_dict(scene_doc), seed=1)
    column = doc["objects"][1]
    assert column["station"] == [3.0, 0.0, 1.5]
    m = np.array(column["measurements"])
    pts = np.array([3.0, 0, 1.5]) + m[:, 2:3] * direction_from_angles(
        np.radians(m[:, 0]), np.radians(m[:, 1])
    )
    np.testing.assert_allclose(pts, column["points"], atol=2e-4)
    assert "station" not in doc["objects"][0]


def test_unscannable_object_is_a_scene_error(scene_doc):
    scene_doc["objects"].insert(
        0,
        {
            "id": "screen",
            "scan": False,
            "geometry": {
                "type": "plate",
                "center": [0, 2.0, 1.5],
                "normal": [0, -1, 0],
                "size": [20, 10],
            },
        },
    )
    with pytest.raises(SceneError) as info:
        simulate_scan(scene_from_dict(scene_doc, source="s.json"))
    assert str(info.value).startswith("s.json: objects (P1): too few shots land on it")


def test_default_decimals():
    assert [default_decimals(u) for u in ("m", "cm", "mm", "in", "ft")] == [4, 2, 1, 3, 4]
