"""Small scenes shared by the simulator tests."""

import copy

import pytest


def base_scene() -> dict:
    """A pipe, a column, a ball, a wall behind them and the floor; station at the origin."""
    return {
        "format": "asbuilt-scene",
        "version": 1,
        "units": "m",
        "name": "test scene",
        "seed": 5,
        "points": 30,
        "stations": [{"id": "S1", "position": [0.0, 0.0, 1.5]}],
        "objects": [
            {
                "id": "P1",
                "kind": "cylinder",
                "nominal": '4"',
                "group": "G1",
                "geometry": {
                    "type": "cylinder",
                    "start": [-1.0, 5.0, 1.0],
                    "end": [1.0, 5.0, 1.0],
                    "od": 0.1143,
                },
            },
            {
                "id": "C1",
                "kind": "cuboid",
                "label": "column",
                "geometry": {
                    "type": "member",
                    "start": [2.0, 6.0, 0.0],
                    "end": [2.0, 6.0, 3.0],
                    "section": [0.3, 0.4],
                },
            },
            {
                "id": "S1",
                "kind": "sphere",
                "geometry": {"type": "sphere", "center": [-2.0, 6.0, 1.5], "diameter": 0.6},
            },
            {
                "id": "wall",
                "scan": False,
                "geometry": {
                    "type": "plate",
                    "center": [0.0, 8.0, 2.0],
                    "normal": [0, -1, 0],
                    "size": [12.0, 4.0],
                    "thickness": 0.2,
                },
            },
            {"id": "floor", "scan": False, "geometry": {"type": "ground"}},
        ],
        "links": [],
    }


@pytest.fixture
def scene_doc():
    return copy.deepcopy(base_scene())
