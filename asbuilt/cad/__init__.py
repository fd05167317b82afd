"""The CAD layer: the only place (with :mod:`asbuilt.export`) that imports CadQuery/OCP.

``solid_for(component)`` builds one valid solid; ``prepare(model)`` builds them all once into a
:class:`CadModel` (assembly, meshes, fused spools) that the exporters share;
``build_assembly(model)`` and ``fused_spool_solid(model, spool_id)`` are the one-call forms.
Colours live in :mod:`asbuilt.cad.colours` (plain data): importing that submodule alone does
not load CadQuery, because the names below are resolved lazily (PEP 562).
"""

from __future__ import annotations

from importlib import import_module

_LAZY = {
    "CadModel": "asbuilt.cad.assembly",
    "CadPart": "asbuilt.cad.assembly",
    "build_assembly": "asbuilt.cad.assembly",
    "fused_spool_solid": "asbuilt.cad.assembly",
    "prepare": "asbuilt.cad.assembly",
    "Mesh": "asbuilt.cad.mesh",
    "tessellate": "asbuilt.cad.mesh",
    "check_solid": "asbuilt.cad.solids",
    "solid_for": "asbuilt.cad.solids",
}

__all__ = list(_LAZY)


def __getattr__(name: str):
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'asbuilt.cad' has no attribute {name!r}") from None
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value
