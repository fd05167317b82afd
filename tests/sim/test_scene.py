"""Scene loading: geometry expansion, unit conversion, truths, and one-line errors."""

import json

import numpy as np
import pytest

from asbuilt.errors import SceneError
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.sim.scene import load_scene, loads_scene, scene_from_dict


def test_loads_and_truths(scene_doc):
    scene = scene_from_dict(scene_doc, source="t.json")
    assert [o.id for o in scene.objects] == ["P1", "C1", "S1", "wall", "floor"]
    pipe = scene.object("P1").truth
    assert isinstance(pipe, Cylinder)
    assert pipe.radius == pytest.approx(0.05715)
    assert pipe.length == pytest.approx(2.0)
    column = scene.object("C1").truth
    assert isinstance(column, Cuboid)
    assert sorted(column.size) == pytest.approx([0.3, 0.4, 3.0])
    np.testing.assert_allclose(column.center, [2.0, 6.0, 1.5])
    assert isinstance(scene.object("S1").truth, Sphere)
    wall = scene.object("wall").truth
    assert isinstance(wall, Plane)
    np.testing.assert_allclose(wall.point, [0.0, 7.9, 2.0])  # the face towards -y
    assert not scene.object("wall").scan and scene.object("P1").scan
    assert [o.index for o in scene.objects] == list(range(5))


def test_units_are_converted_once(scene_doc):
    scene_doc["units"] = "mm"
    scene_doc["stations"][0]["position"] = [0.0, 0.0, 1500.0]
    scene_doc["objects"] = [
        {
            "id": "P",
            "kind": "cylinder",
            "geometry": {
                "type": "cylinder",
                "start": [-1000, 5000, 1000],
                "end": [1000, 5000, 1000],
                "od": 114.3,
            },
        }
    ]
    scene = scene_from_dict(scene_doc)
    assert scene.units == "mm"
    assert scene.object("P").truth.radius == pytest.approx(0.05715)
    assert scene.stations[0].range_sigma == pytest.approx(0.002)  # default stays 2 mm
    np.testing.assert_allclose(scene.stations[0].position, [0, 0, 1.5])


def test_pipe_run_stops_short_by_centre_to_end(scene_doc):
    scene_doc["objects"] = [
        {
            "id": "R",
            "kind": "cylinder",
            "nominal": '4"',
            "geometry": {
                "type": "pipe_run",
                "path": [[0, 5, 1], [2, 5, 1], [2, 5, 3], [4, 5, 3]],
                "od": 0.1143,
                "bend_radius": 0.152,
            },
        }
    ]
    scene = scene_from_dict(scene_doc)
    ids = [o.id for o in scene.objects]
    assert ids == ["R-1", "R-2", "R-3", "R-E1", "R-E2"]
    assert scene.links == (("R-1", "R-2"), ("R-2", "R-3"))
    lengths = [scene.object(i).truth.length for i in ("R-1", "R-2", "R-3")]
    # 90-degree elbows: centre-to-end = bend radius
    assert lengths == pytest.approx([2 - 0.152, 2 - 2 * 0.152, 2 - 0.152])
    assert not scene.object("R-E1").scan and scene.object("R-E1").kind is None
    # the elbow mesh fills the gap: a ray through its centre line's 45-degree point hits it
    # (bend centre (2 - 0.152, 1 + 0.152) in x, z)
    s = 0.152 * np.sqrt(0.5)
    hits = scene.raycast(np.array([1.848 + s, 0.0, 1.152 - s]), np.array([[0.0, 1.0, 0.0]]))
    assert hits.object_index[0] == ids.index("R-E1")
    assert hits.range[0] == pytest.approx(5.0 - 0.05715, abs=2e-3)


def test_mesh_file_and_elbow(tmp_path, scene_doc):
    obj = tmp_path / "box.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    scene_doc["objects"].append(
        {
            "id": "H",
            "kind": "hull",
            "geometry": {"type": "mesh", "file": "box.obj", "translate": [0, 10, 0], "scale": 2.0},
        }
    )
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene_doc))
    scene = load_scene(path)
    hull = scene.object("H").truth
    assert isinstance(hull, Hull)
    np.testing.assert_allclose(hull.vertices.max(axis=0), [2, 12, 2])


def test_mesh_file_scaled_to_metres_before_the_site_limit(tmp_path, scene_doc):
    """A mesh of a site far from the origin, given with ``scale`` 0.001 (a model in mm): its
    stored numbers pass the 1e8 m site limit only once scaled, and the limit judges metres."""
    far = 2e8  # stored units; 2e5 m once scaled
    obj = tmp_path / "far.obj"
    obj.write_text(
        f"v {far} 0 0\nv {far + 1000} 0 0\nv {far} 1000 0\nv {far} 0 1000\n"
        "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    )
    scene_doc["objects"].append(
        {"id": "H", "kind": "hull", "geometry": {"type": "mesh", "file": "far.obj", "scale": 0.001}}
    )
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene_doc))
    hull = load_scene(path).object("H").truth
    np.testing.assert_allclose(hull.vertices.max(axis=0), [far / 1000 + 1, 1, 1])


BAD = [
    (lambda d: d.update(units="furlong"), "units: unknown unit 'furlong'"),
    (lambda d: d.update(stations=[]), "stations: give a list"),
    (lambda d: d["objects"][0].pop("kind"), "objects[0] (P1): missing field 'kind'"),
    (
        lambda d: d["objects"][0]["geometry"].update(type="torus"),
        "objects[0] (P1).geometry.type: unknown geometry type 'torus'",
    ),
    (
        lambda d: d["objects"][0]["geometry"].update(start=[0, 0]),
        "objects[0] (P1).geometry.start: must be a list of 3 numbers",
    ),
    (
        lambda d: d["objects"][0]["geometry"].update(radius=0.05),
        "give exactly one of 'radius', 'diameter' or 'od'",
    ),
    (
        lambda d: d["objects"][0]["geometry"].update(od=-1),
        "objects[0] (P1).geometry.od: must be positive",
    ),
    (lambda d: d["objects"][0].update(points=3), "a cylinder needs at least 6 points"),
    (lambda d: d["objects"][0].update(station="S9"), "unknown station 'S9'"),
    (
        lambda d: d["objects"][4].update(scan=True, kind="plane"),
        "an unbounded ground plane cannot be scanned",
    ),
    (lambda d: d["objects"][1].update(id="P1"), "object ids must be unique"),
    (
        lambda d: d.update(links=[["P1", "nope"]]),
        "links[0]: 'nope' is not the id of an object in the scene",
    ),
    (lambda d: d.update(links=[["P1"]]), "links[0]: must be a pair of object ids, not ['P1']"),
    (lambda d: d["stations"][0].update(dropout=1.5), "stations[0].dropout: must be at most 0.9"),
    (
        lambda d: d["stations"][0].update(beam_divergence_mrad=3000),
        "stations[0].beam_divergence_mrad: must be at most 200, not 3000",
    ),
    (lambda d: d.update(format="asbuilt-scan"), "format: format is 'asbuilt-scan'"),
]


def _plate_and_run(units: str, scale: float) -> dict:
    """A plate without a thickness and a pipe run without a bend radius, lengths in ``units``
    (``scale`` of them to the metre)."""
    return {
        "format": "asbuilt-scene",
        "version": 1,
        "units": units,
        "stations": [{"id": "S1", "position": [0, 0, 1.5 * scale]}],
        "objects": [
            {
                "id": "W",
                "kind": "plane",
                "geometry": {
                    "type": "plate",
                    "center": [0, 5 * scale, 1 * scale],
                    "normal": [0, -1, 0],
                    "size": [2 * scale, 2 * scale],
                },
            },
            {
                "id": "R",
                "kind": "cylinder",
                "geometry": {
                    "type": "pipe_run",
                    "path": [
                        [-2 * scale, 3 * scale, 0.5 * scale],
                        [0, 3 * scale, 0.5 * scale],
                        [0, 3 * scale, 2.5 * scale],
                    ],
                    "od": 0.1143 * scale,
                },
            },
        ],
    }


@pytest.mark.parametrize(
    ("units", "scale"), [("mm", 1000.0), ("in", 1 / 0.0254), ("ft", 1 / 0.3048)]
)
def test_default_lengths_do_not_depend_on_the_units(units, scale):
    """A plate's default 10 mm thickness and a pipe run's default bend radius (3 pipe radii)
    came out 10 um and 0.35 mm in a millimetre scene: the defaults were scaled a second time."""
    metres = scene_from_dict(_plate_and_run("m", 1.0))
    other = scene_from_dict(_plate_and_run(units, scale))
    assert len(metres.objects) == len(other.objects)
    for a, b in zip(metres.objects, other.objects):
        assert a.id == b.id
        if isinstance(a.truth, Cylinder):
            assert b.truth.length == pytest.approx(a.truth.length, rel=1e-9)
            assert a.truth.length == pytest.approx(
                2 - 3 * 0.1143 / 2, rel=1e-9
            )  # cut back by the bend radius
    (plate,) = [o for o in other.objects if o.id == "W"]
    assert min(plate.shape.size) == pytest.approx(0.01)


@pytest.mark.parametrize("mutate, message", BAD)
def test_bad_scene_one_located_line(scene_doc, mutate, message):
    mutate(scene_doc)
    with pytest.raises(SceneError) as info:
        scene_from_dict(scene_doc, source="bad.json")
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith("bad.json: ")
    assert message in text


def test_bad_json_and_missing_file(tmp_path):
    with pytest.raises(SceneError, match=r"x.json: line 1 column \d+: invalid JSON"):
        loads_scene("{nope", source="x.json")
    with pytest.raises(SceneError, match="file not found"):
        load_scene(tmp_path / "missing.json")


# Found by mutation fuzzing (asbuilt simulate SCENE, 2,000 mutants of the spool and plant scenes
# and 1,000 of the plant's .obj mesh): each was a traceback and is now one located line.
_SPOOL = {
    "stations": [{"id": "S1", "position": [0.0, 0.0, 1.5]}],
    "objects": [
        {
            "id": "X",
            "kind": "cuboid",
            "geometry": {"type": "box", "center": [3, 0, 0], "size": [1, 1, 1]},
        }
    ],
}
_BIG = "1" + "0" * 400


def _with(geometry=None, **changes):
    doc = json.loads(json.dumps(_SPOOL))
    if geometry is not None:
        doc["objects"][0]["geometry"] = geometry
    for key, value in changes.items():
        if key == "points":
            doc["objects"][0]["points"] = value
        else:
            doc[key] = value
    return json.dumps(doc)


@pytest.mark.parametrize(
    "text, message",
    [
        (_with(units=["mm"]), "units: unknown unit ['mm']; use one of m, mm, cm, in, ft"),
        (
            _with().replace('"center": [3,', f'"center": [{_BIG},'),
            "objects[0] (X).geometry.center: must be finite",
        ),
        (
            _with(points=10**30),
            "objects[0] (X).points: must be at most 1,000,000 (the most a scan holds)",
        ),
        (
            _with(
                {"type": "member", "start": [1e308, 0, 0], "end": [-1e308, 0, 0], "section": [1, 1]}
            ),
            "objects[0] (X).geometry.start: 1e+308 m is beyond any site (at most 1e+08 m); check "
            'the number and the scene\'s "units"',
        ),
        (
            _with({"type": "cylinder", "start": [0, 0, 0], "end": [1e300, 0, 0], "od": 0.1}),
            "objects[0] (X).geometry.end: 1e+300 m is beyond any site (at most 1e+08 m); check "
            'the number and the scene\'s "units"',
        ),
        (
            _with(
                {
                    "type": "box",
                    "center": [3, 0, 0],
                    "size": [1, 1, 1],
                    "axes": [[0, 0, 0], [0, 1, 0], [0, 0, 1]],
                }
            ),
            "objects[0] (X).geometry.axes: rows must be non-zero finite vectors",
        ),
        (
            _with(
                {
                    "type": "box",
                    "center": [3, 0, 0],
                    "size": [1, 1, 1],
                    "axes": [[1, 0, 0], [0, 1], [0, 0, 1]],
                }
            ),
            "objects[0] (X).geometry.axes: must be three [x, y, z] rows",
        ),
        (
            _with(
                {
                    "type": "box",
                    "center": [3, 0, 0],
                    "size": [1, 1, 1],
                    "axes": [["a", 0, 0], [0, 1, 0], [0, 0, 1]],
                }
            ),
            "objects[0] (X).geometry.axes: must be three [x, y, z] rows",
        ),
        (
            _with(
                {
                    "type": "mesh",
                    "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
                    "faces": [[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 10**30]],
                }
            ),
            "objects[0] (X).geometry: 'vertices' must be [[x, y, z], ...] and 'faces' "
            "[[i, j, k], ...]",
        ),
        (
            _with({"type": "cylinder", "start": [0, 0, 0], "end": [1, 0, 0], "od": None}),
            "objects[0] (X).geometry: missing field 'od'",
        ),
        (
            "[" * 100_000,
            "invalid JSON (nested too deeply); a scene nests lists three levels at most",
        ),
        (
            _with(seed=0).replace('"seed": 0', '"seed": 1' + "0" * 5000),
            "seed: must be a non-negative integer, not inf",
        ),
    ],
    ids=[
        "units-list",
        "integer-400-digits",
        "points-beyond-a-scan",
        "member-beyond-any-site",
        "cylinder-beyond-any-site",
        "box-axes-zero-row",
        "box-axes-ragged",
        "box-axes-text",
        "mesh-face-index-overflow",
        "od-null",
        "nested-too-deeply",
        "integer-5000-digits",
    ],
)
def test_fuzzed_scenes_are_one_located_line(text, message):
    with pytest.raises(SceneError) as info:
        loads_scene(text, source="s.json")
    assert str(info.value) == f"s.json: {message}"
