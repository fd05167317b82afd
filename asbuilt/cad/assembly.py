"""The CAD model of an as-built model: one solid per component, grouped, coloured, tessellated.

:func:`prepare` builds every solid once (the expensive part) into a :class:`CadModel`, which the
exporters share: the assembly for STEP, the meshes for glTF, DXF, STL and OBJ. The tree is
*scan > group > object*: a component's group is its spool when merging made one, else the
scan's ``group`` name; ungrouped components hang from the root.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass, field

import cadquery as cq

from asbuilt.errors import SolidBuildError
from asbuilt.insulation import jacket
from asbuilt.model import Component, Model

from .colours import KIND_COLOURS, colour_for, component_status
from .mesh import LINEAR_DEFLECTION, Mesh, tessellate
from .meshgen import mesh_for
from .solids import (
    build_error,
    check_geometry,
    check_solid,
    place,
    placed_solid,
    split_closed_faces,
)

__all__ = ["CadPart", "CadModel", "prepare", "build_assembly", "fused_spool_solid"]


@dataclass(frozen=True, eq=False)
class CadPart:
    """One component's solid (metres), colour (RGBA 0..1), worst finding severity and group.

    ``solid`` is in place (scan frame); ``local`` is the same solid built about ``origin``
    ((3,) metres), which the assembly places by a transform (:func:`asbuilt.cad.solids.placed_solid`).
    Both are None when the model was prepared for meshes only (``prepare(..., solids=False)``)
    and the part's mesh needs no solid (all but tees).
    """

    component: Component
    solid: cq.Solid | None
    colour: tuple[float, float, float, float]
    status: str | None = None
    group: str | None = None
    local: cq.Solid | None = None
    origin: tuple[float, float, float] = (0.0, 0.0, 0.0)
    jacket: object = None
    name: str | None = None

    @property
    def id(self) -> str:
        """The part's name in every file: the component's id, or for an insulation part
        ``name`` (e.g. ``"P1 insulation"``)."""
        return self.name or self.component.id

    @property
    def insulation(self) -> bool:
        """True for the insulation around ``component`` (its ``jacket`` geometry), not the
        component itself."""
        return self.jacket is not None

    @property
    def kind(self) -> str:
        """What the part is, for colours, layers and names: ``"insulation"`` or the
        component's type."""
        return "insulation" if self.insulation else self.component.type

    @property
    def geometry(self):
        """The geometry the part's solid and mesh are made from (metres): the jacket of an
        insulation part, else the component's."""
        return self.jacket if self.insulation else self.component.geometry


def group_of(component: Component) -> str | None:
    """The tree node a component hangs from: its spool, else its scan group, else None."""
    return component.spool or component.group


@dataclass(eq=False)
class CadModel:
    """Every component's solid, ready for the exporters.

    Attributes
    ----------
    model : Model
    parts : tuple of CadPart
        In the model's component order.
    name : str
        The root node's name (the model's name, else ``"scan"``).
    plate_thickness : float, metres
    """

    model: Model
    parts: tuple[CadPart, ...]
    name: str
    plate_thickness: float
    _meshes: dict = field(default_factory=dict, repr=False)
    _assembly: cq.Assembly | None = field(default=None, repr=False)

    def groups(self) -> dict[str | None, list[CadPart]]:
        """Parts by group name, spools first in the model's order, then the scan's groups in order
        of first appearance; the key ``None`` holds the ungrouped parts."""
        order: dict[str | None, list[CadPart]] = {spool.id: [] for spool in self.model.spools}
        for part in self.parts:
            order.setdefault(part.group, []).append(part)
        return {key: parts for key, parts in order.items() if parts}

    def group_node_names(self) -> dict[str, str]:
        """Each group's node name in the tree: the group's name, made distinct from the root's
        and every component id by a ``" (group)"`` suffix when they clash (a CadQuery assembly
        needs unique names along each path, and readers of the files are spared ambiguity)."""
        taken = {self.name} | {part.id for part in self.parts}
        names = {}
        for group in self.groups():
            if group is None:
                continue
            name = group
            while name in taken:
                name = f"{name} (group)"
            taken.add(name)
            names[group] = name
        return names

    def mesh(self, part: CadPart) -> Mesh:
        """The part's triangle mesh (metres), made on first use and then reused.

        Computed in closed form (:mod:`asbuilt.cad.meshgen`) for every geometry but tees,
        whose solid the kernel tessellates (0.5 mm chord deviation, 0.25 rad between facets).
        """
        mesh = self._meshes.get(part.id)
        if mesh is None:
            mesh = mesh_for(part.geometry, plate_thickness=self.plate_thickness)
            if mesh is None:
                mesh = tessellate(part.solid, LINEAR_DEFLECTION)
            self._meshes[part.id] = mesh
        return mesh

    def _need_solids(self) -> None:
        if any(part.solid is None for part in self.parts):
            raise ValueError("this CadModel was prepared for meshes only (solids=False)")

    def assembly(self) -> cq.Assembly:
        """The CadQuery assembly (built once): root > group > object, each leaf named by its id
        and coloured by kind or status; its solids are local, placed by the leaf's location,
        with closed faces split (for files, not for booleans)."""
        self._need_solids()
        if self._assembly is None:
            self._assembly = _assemble(self)
        return self._assembly

    def fused_spool(self, spool_id: str) -> cq.Solid:
        """The spool's components fused into one valid solid (metres); SolidBuildError when they
        do not form one connected solid."""
        self._need_solids()
        members = [part for part in self.parts if part.group == spool_id and not part.insulation]
        if not members:
            raise SolidBuildError("no components belong to this spool", where=f"spool {spool_id}")
        shape: cq.Shape = members[0].solid
        if len(members) > 1:
            shape = shape.fuse(*(part.solid for part in members[1:])).clean()
        try:
            return check_solid(shape, spool_id)
        except SolidBuildError as exc:
            raise SolidBuildError(
                f"its {len(members)} components do not fuse into one valid solid ({exc.message}); "
                "check that they touch",
                where=f"spool {spool_id}",
            ) from None


def _cq_colour(colour) -> cq.Color:
    return cq.Color(*(float(c) for c in colour))


def _add(node: cq.Assembly, part: CadPart) -> None:
    """Add a leaf: the part's local solid placed at its origin (its solid as is without one),
    closed faces split so STEP readers rebuild them valid (:func:`split_closed_faces`)."""
    colour = _cq_colour(part.colour)
    if part.local is None:
        node.add(split_closed_faces(part.solid), name=part.id, color=colour)
    else:
        local = split_closed_faces(part.local)
        node.add(local, name=part.id, color=colour, loc=cq.Location(cq.Vector(*part.origin)))


def _assemble(cad: CadModel) -> cq.Assembly:
    root = cq.Assembly(name=cad.name)
    node_names = cad.group_node_names()
    for group, parts in cad.groups().items():
        if group is None:
            for part in parts:
                _add(root, part)
            continue
        node = cq.Assembly(name=node_names[group])
        for part in parts:
            _add(node, part)
        root.add(node)
    return root


def prepare(
    model: Model,
    *,
    plate_thickness: float | None = None,
    colour_by_status: bool = True,
    progress: Callable[[int, int], None] | None = None,
    solids: bool = True,
) -> CadModel:
    """Build every component's solid once (or, with ``solids=False``, only its mesh).

    Parameters
    ----------
    model : Model
        Metres, scan frame.
    plate_thickness : float, metres, optional
        Thickness of plates made from planes (default ``Tolerances.plate_thickness``).
    colour_by_status : bool
        Colour components with error findings red and warnings amber.
    progress : callable(done, total), optional
        Called after each solid (for a progress display).
    solids : bool
        False for outputs that need only :meth:`CadModel.mesh` (glTF, DXF, STL, OBJ): each
        part gets its closed-form mesh and no B-rep solid (``solid`` and ``local`` None), but
        tees, whose mesh is tessellated from their solid. Sewing a dense hull's solid takes
        seconds to minutes, its mesh milliseconds. A geometry no solid can be built from is
        refused all the same (:func:`asbuilt.cad.solids.check_geometry`); the kernel's
        validity check of the solid itself is skipped. :meth:`CadModel.assembly` and
        :meth:`CadModel.fused_spool` then raise ValueError.

    Raises
    ------
    SolidBuildError
        Naming the first object whose solid cannot be built.
    """
    from asbuilt.tolerances import DEFAULT_TOLERANCES

    thickness = DEFAULT_TOLERANCES.plate_thickness if plate_thickness is None else plate_thickness
    status = component_status(model.findings) if colour_by_status else {}
    ids = [component.id for component in model.components]
    if len(set(ids)) != len(ids):
        duplicate = next(i for i in ids if ids.count(i) > 1)
        raise SolidBuildError(
            "two components share this id; ids must be unique", where=f"object {duplicate}"
        )
    parts = []
    total = len(model.components)
    source = model.scan.source if model.scan is not None else None
    meshes: dict[str, Mesh] = {}
    for done, component in enumerate(model.components, start=1):
        local, origin = None, (0.0, 0.0, 0.0)
        try:
            mesh = None if solids else _mesh_only(component, thickness)
            if mesh is None:
                local, origin = placed_solid(component, plate_thickness=thickness)
            else:
                meshes[component.id] = mesh
        except SolidBuildError as exc:
            if source is None or exc.source is not None:
                raise
            raise SolidBuildError(exc.message, source=source, where=exc.where) from None
        state = status.get(component.id)
        if state is None:
            state = next((status[s] for s in component.sources if s in status), None)
        parts.append(
            CadPart(
                component=component,
                solid=None if local is None else place(local, origin),
                colour=colour_for(component.type, state),
                status=state,
                group=group_of(component),
                local=local,
                origin=tuple(float(v) for v in origin),
            )
        )
        jacket, jacket_mesh = _jacket_part(parts[-1], ids, thickness, solids)
        if jacket is not None:
            parts.append(jacket)
            ids.append(jacket.id)
            if jacket_mesh is not None:
                meshes[jacket.id] = jacket_mesh
        if progress is not None:
            progress(done, total)
    name = model.name or "scan"
    while name in ids:
        name = f"{name} (scan)"
    return CadModel(
        model=model,
        parts=tuple(parts),
        name=name,
        plate_thickness=float(thickness),
        _meshes=meshes,
    )


def _jacket_part(
    part: CadPart, taken: list[str], thickness: float, solids: bool
) -> tuple[CadPart | None, Mesh | None]:
    """The insulation part around ``part`` (after it, in its group) and, prepared for meshes
    only, its closed-form mesh; ``(None, None)`` when bare.

    Named ``"<id> insulation"`` (made unique among ``taken``), translucent, never recoloured
    by findings (they are the component's). Its solid, when solids are built, is the jacket's:
    a tee's always, as the tee's own mesh comes from its solid.
    """
    geometry = jacket(part.component)
    if geometry is None:
        return None, None
    name = f"{part.id} insulation"
    while name in taken:
        name += " (2)"
    mesh = None if solids else mesh_for(geometry, plate_thickness=thickness)
    local, origin = None, (0.0, 0.0, 0.0)
    if mesh is None:
        shell = dataclasses.replace(part.component, id=name, geometry=geometry)
        local, origin = placed_solid(shell, plate_thickness=thickness)
    jacket_part = CadPart(
        component=part.component,
        solid=None if local is None else place(local, origin),
        colour=KIND_COLOURS["insulation"],
        group=part.group,
        local=local,
        origin=tuple(float(v) for v in origin),
        jacket=geometry,
        name=name,
    )
    return jacket_part, mesh


def _mesh_only(component: Component, thickness: float) -> Mesh | None:
    """The component's closed-form mesh, its geometry checked as its solid's builder would; None
    when only the kernel can mesh it (a tee: the caller builds its solid)."""
    check_geometry(component, plate_thickness=thickness)
    try:
        mesh = mesh_for(component.geometry, plate_thickness=thickness)
    except Exception as exc:
        raise build_error(component, exc) from None
    if mesh is not None and not mesh.volume > 0:
        raise SolidBuildError(
            "its solid encloses no volume; check its fitted size and refit it",
            where=f"object {component.id}",
        )
    return mesh


def build_assembly(
    model: Model, *, plate_thickness: float | None = None, colour_by_status: bool = True
) -> cq.Assembly:
    """The model as a CadQuery assembly: root (the scan) > group (spool) > object (named by id).

    Parameters
    ----------
    model : Model
    plate_thickness : float, metres, optional
    colour_by_status : bool
        Errors red, warnings amber, others by kind (:mod:`asbuilt.cad.colours`).
    """
    return prepare(
        model, plate_thickness=plate_thickness, colour_by_status=colour_by_status
    ).assembly()


def fused_spool_solid(
    model: Model, spool_id: str, *, plate_thickness: float | None = None
) -> cq.Solid:
    """One valid solid fusing the components of spool ``spool_id`` (metres).

    Raises
    ------
    SolidBuildError
        When the spool has no components or they do not fuse into one solid.
    """
    return prepare(model, plate_thickness=plate_thickness).fused_spool(spool_id)
