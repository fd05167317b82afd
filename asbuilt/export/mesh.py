"""STL and OBJ export through trimesh: plain triangle meshes, no colours.

STL holds one solid (every object's closed mesh, concatenated, binary STL); OBJ holds one
named object (``o <id>``) per component. Neither format declares a unit, so coordinates are
written in the model's output unit (``Model.units``, the scan's unit unless changed), z up as
in the scan frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from asbuilt import __version__
from asbuilt.units import unit_factor

__all__ = ["write_stl", "write_obj", "trimesh_scene"]


def trimesh_scene(cad, *, units: str | None = None) -> trimesh.Scene:
    """A trimesh scene with one closed mesh per object, node and geometry named by its id.

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
    units : str, optional
        Output unit (``"m"``, ``"mm"``...); default the model's ``units``.
    """
    unit = units or cad.model.units
    scale = 1.0 / unit_factor(unit)
    scene = trimesh.Scene()
    for part in cad.parts:
        vertices, faces = cad.mesh(part).merged()
        mesh = trimesh.Trimesh(vertices * scale, faces, process=False)
        scene.add_geometry(mesh, node_name=part.id, geom_name=part.id)
    scene.units = unit
    return scene


def write_stl(cad, path, *, units: str | None = None) -> None:
    """Write every object's mesh as one binary STL solid (coordinates in ``units``).

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
    path : str or Path
        Written directly; callers stage it for atomicity.
    units : str, optional
        Default the model's ``units``.
    """
    scene = trimesh_scene(cad, units=units)
    meshes = list(scene.geometry.values())
    combined = (
        trimesh.util.concatenate(meshes)
        if meshes
        else trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    )
    Path(path).write_bytes(trimesh.exchange.stl.export_stl(combined))


def write_obj(cad, path, *, units: str | None = None) -> None:
    """Write one named OBJ object per component (coordinates in ``units``, no materials).

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
    path : str or Path
        Written directly; callers stage it for atomicity.
    units : str, optional
        Default the model's ``units``.
    """
    scene = trimesh_scene(cad, units=units)
    unit = units or cad.model.units
    text = trimesh.exchange.obj.export_obj(
        scene,
        include_normals=False,
        include_color=False,
        include_texture=False,
        write_texture=False,
        return_texture=False,
        header=f"asbuilt {__version__}: {cad.name}, units {unit}, z up",
    )
    Path(path).write_text(text, encoding="utf-8")
