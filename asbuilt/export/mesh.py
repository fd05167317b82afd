"""STL and OBJ export through trimesh: plain triangle meshes, no colours.

STL holds one solid (every object's closed mesh, concatenated, binary STL); OBJ holds one
named object (``o <id>``) per component. Neither format declares a unit, so coordinates are
written in the model's output unit (``Model.units``, the scan's unit unless changed), z up as
in the scan frame.

Binary STL stores float32 coordinates: about 7 significant digits, so far from the origin (survey
coordinates) a vertex would be snapped to a coarse grid (0.5 m at 5,000 km). :func:`write_stl`
refuses such a model with an :class:`~asbuilt.errors.ExportError` rather than write it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from asbuilt import __version__
from asbuilt.errors import ExportError
from asbuilt.units import unit_factor

__all__ = ["write_stl", "write_obj", "trimesh_scene", "STL_RESOLUTION"]

#: Worst float32 rounding (metres) an STL may have: 0.1 mm, a tenth of the usual 1 mm survey
#: tolerance, so the STL is as good as the fit; more would silently move the geometry.
STL_RESOLUTION = 1e-4


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

    Raises
    ------
    ExportError
        When float32 cannot hold the coordinates to :data:`STL_RESOLUTION` (0.1 mm), before
        anything is written.
    """
    scene = trimesh_scene(cad, units=units)
    meshes = list(scene.geometry.values())
    _check_float32(meshes, units or cad.model.units, path)
    combined = (
        trimesh.util.concatenate(meshes)
        if meshes
        else trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
    )
    Path(path).write_bytes(trimesh.exchange.stl.export_stl(combined))


def _check_float32(meshes, unit: str, path) -> None:
    """Refuse coordinates that float32 cannot hold to :data:`STL_RESOLUTION`."""
    if not meshes:
        return
    largest = max(float(np.abs(mesh.vertices).max(initial=0.0)) for mesh in meshes)
    # Rounding to the nearest float32 moves a value by at most half its spacing.
    error = 0.5 * float(np.spacing(np.float32(largest))) * unit_factor(unit)
    if error > STL_RESOLUTION:
        raise ExportError(
            f"binary STL stores float32 coordinates, which {largest:.6g} {unit} from the origin "
            f"round by up to {error * 1000:.3g} mm; write .obj, .glb/.gltf, .step or .dxf "
            "(they keep full precision) or move the scan's origin near the objects",
            source=str(path),
        )


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
