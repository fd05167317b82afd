"""The scene simulator: exact ray casting and the pan-tilt range finder sensor model.

``load_scene(path)`` reads a scene description (``docs/scene-format.md``); ``Scene.raycast``
casts rays against every object (analytic primitives, triangle meshes, occlusion included);
``simulate_scan(scene, seed=...)`` aims the ideal pan-tilt range finder at each object and
returns an ``asbuilt-scan`` document.
"""

from .raycast import RayHits, angles_from_direction, direction_from_angles, raycast
from .scene import Scene, SceneObject, Station, load_scene, loads_scene, scene_from_dict

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
]
