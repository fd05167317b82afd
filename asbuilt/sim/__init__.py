"""The scene simulator: exact ray casting and the pan-tilt range finder sensor model.

``load_scene(path)`` reads a scene description (``docs/scene-format.md``); ``Scene.raycast``
casts rays against every object (analytic primitives, triangle meshes, occlusion included);
``simulate_scan(scene, seed=...)`` aims the ideal pan-tilt range finder at each object and
returns an ``asbuilt-scan`` document (``dumps_scan`` serialises it).
"""

from .raycast import RayHits, angles_from_direction, direction_from_angles, raycast
from .scene import Scene, SceneObject, Station, load_scene, loads_scene, scene_from_dict
from .sensor import Shots, scan_object
from .simulate import dumps_scan, simulate_scan

__all__ = [
    "RayHits",
    "raycast",
    "direction_from_angles",
    "angles_from_direction",
    "Scene",
    "SceneObject",
    "Station",
    "load_scene",
    "loads_scene",
    "scene_from_dict",
    "Shots",
    "scan_object",
    "simulate_scan",
    "dumps_scan",
]
