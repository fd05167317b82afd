"""IFC4 export (``.ifc``) with ifcopenshell: piping as IfcPipeSegment / IfcPipeFitting, the rest by label.

Written from the :class:`asbuilt.model.Model` itself (no CAD kernel): the spatial structure is
IfcProject > IfcSite > IfcBuilding > IfcBuildingStorey, lengths in metres (SI units, angles in
radians), and every component becomes one element named by its id, described by its label and
placed at its own anchor point (so coordinates stay precise far from the origin):

* pipes -> IfcPipeSegment RIGIDSEGMENT, couplings -> IfcPipeFitting CONNECTOR: a circle (or
  circle-hollow when the wall is known) profile extruded along the centreline;
* elbows -> IfcPipeFitting BEND: the profile revolved about the bend axis;
* tees -> IfcPipeFitting JUNCTION: run and branch cylinders united, bores cut (a CSG tree);
* crosses -> IfcPipeFitting JUNCTION too (IFC4's IfcPipeFittingTypeEnum: a junction is a
  fitting where two or more flow paths meet, a tee or a cross): run and outlet cylinders (the
  outlet through both sides) united, bores cut, with four ports;
* reducers -> IfcPipeFitting TRANSITION: a closed triangulated face set (concentric or
  eccentric, from :func:`asbuilt.cad.meshgen.tube_mesh`);
* fitted primitives -> by the words of their label: tank/vessel IfcTank, column IfcColumn, beam
  IfcBeam, wall IfcWall, chimney/stack IfcChimney, pipe IfcPipeSegment; else planes IfcPlate and
  anything else IfcBuildingElementProxy. Cylinders and cuboids are extruded profiles, spheres
  CSG spheres, plates and hulls triangulated face sets.

Each element carries the property set ``Asbuilt_Component`` (type, size, schedule, spool, fit
RMS and standard errors, compliance status and finding codes); pipes and fittings also
``Pset_PipeSegmentTypeCommon`` / ``Pset_PipeFittingTypeCommon`` (status EXISTING, diameters) and
``Qto_PipeSegmentBaseQuantities`` / ``Qto_PipeFittingBaseQuantities``. Spools become
IfcDistributionSystem groups (IfcRelAssignsToGroup), other scan groups IfcGroup. Piping ends get
IfcDistributionPort ports (nested with IfcRelNests), and ports at the same point of two
components are joined by IfcRelConnectsPorts. Surface colours follow
:mod:`asbuilt.cad.colours` (kind, or red/amber for error/warning findings).

ifcopenshell is an optional dependency (``pip install 'asbuilt[ifc]'``); it is imported only when
an IFC file is written, and its absence is a one-line :class:`asbuilt.errors.ExportError`.
"""

from __future__ import annotations

import dataclasses
import re
import uuid
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from asbuilt import __version__
from asbuilt.cad.colours import KIND_COLOURS, colour_for, component_status
from asbuilt.errors import ExportError
from asbuilt.export._ifc_geometry import (
    _centreline_length,
    _outer_radius,
    _perpendicular,
    _piping_ends,
    _wall,
)
from asbuilt.insulation import jacket
from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

__all__ = [
    "INSTALL_HINT",
    "JOIN_TOLERANCE",
    "ifc_class_for",
    "ifc_document",
    "import_ifcopenshell",
    "write_ifc",
]

#: What to install when ifcopenshell is missing (the optional ``ifc`` extra).
INSTALL_HINT = "pip install 'asbuilt[ifc]'"

#: Two piping ends closer than this (metres) are one joint and their ports are connected: merging
#: makes joined ends share their coordinates exactly, and 1 mm absorbs the rounding of a model
#: read back from a file while staying far below any pipe's radius (ends of different joints are
#: at least a pipe diameter apart).
JOIN_TOLERANCE = 1e-3

#: Extra length (metres) of a tee's bores beyond its ends, so the boolean cut never has to
#: resolve coplanar end faces (the cut removes only air beyond the ends).
BORE_OVERRUN = 1e-3

#: Piping types -> (IFC class, PredefinedType).
_PIPING = {
    "pipe": ("IfcPipeSegment", "RIGIDSEGMENT"),
    "coupling": ("IfcPipeFitting", "CONNECTOR"),
    "elbow": ("IfcPipeFitting", "BEND"),
    "tee": ("IfcPipeFitting", "JUNCTION"),
    "cross": ("IfcPipeFitting", "JUNCTION"),
    "reducer": ("IfcPipeFitting", "TRANSITION"),
}

#: Label words (prefixes, case-insensitive) -> (IFC class, PredefinedType), first match wins.
_LABEL_CLASSES = (
    (("tank", "vessel"), ("IfcTank", "NOTDEFINED")),
    (("column", "post", "pillar"), ("IfcColumn", "COLUMN")),
    (("beam", "girder", "joist"), ("IfcBeam", "BEAM")),
    (("wall",), ("IfcWall", "NOTDEFINED")),
    (("chimney", "stack"), ("IfcChimney", "NOTDEFINED")),
    (("pipe",), ("IfcPipeSegment", "RIGIDSEGMENT")),
)

#: A fixed namespace for the GlobalIds, so the same model gives the same ids in every run.
_GUID_NAMESPACE = uuid.UUID("5b0f9c0e-2f0a-4d7e-9a55-6c1f1e0a1b2c")


def import_ifcopenshell():
    """The ifcopenshell module (and its ``api`` subpackages), or a one-line ExportError.

    Raises
    ------
    ExportError
        ``writing IFC needs the ifcopenshell package: pip install 'asbuilt[ifc]'``.
    """
    try:
        import ifcopenshell
        import ifcopenshell.api.aggregate
        import ifcopenshell.api.context
        import ifcopenshell.api.geometry
        import ifcopenshell.api.group
        import ifcopenshell.api.project
        import ifcopenshell.api.pset
        import ifcopenshell.api.root
        import ifcopenshell.api.spatial
        import ifcopenshell.api.style
        import ifcopenshell.api.system
        import ifcopenshell.api.unit
        import ifcopenshell.guid
    except ImportError:
        raise ExportError(f"writing IFC needs the ifcopenshell package: {INSTALL_HINT}") from None
    return ifcopenshell


def ifc_class_for(component: Component) -> tuple[str, str]:
    """The IFC entity and PredefinedType for a component (piping by type, the rest by label).

    Returns
    -------
    (str, str)
        E.g. ``("IfcPipeFitting", "BEND")`` or ``("IfcColumn", "COLUMN")``.
    """
    if component.type in _PIPING:
        return _PIPING[component.type]
    words = re.findall(r"[a-z]+", (component.label or "").lower())
    for prefixes, target in _LABEL_CLASSES:
        if any(word.startswith(prefixes) for word in words):
            return target
    if component.type == "plane":
        return ("IfcPlate", "NOTDEFINED")
    return ("IfcBuildingElementProxy", "NOTDEFINED")


class _Writer:
    """Builds one IFC4 file for a model; ``f`` is the ifcopenshell file."""

    def __init__(self, ifcopenshell, model: Model, plate_thickness: float):
        self.ios = ifcopenshell
        self.api = ifcopenshell.api
        self.model = model
        self.plate_thickness = plate_thickness
        self.f = ifcopenshell.file(schema="IFC4")
        self.styles: dict = {}
        self.status = component_status(model.findings)
        self.codes: dict[str, list[str]] = {}
        for finding in model.findings:
            for object_id in finding.objects:
                self.codes.setdefault(object_id, []).append(finding.code)
        self._catalog = None
        self._catalog_loaded = False
        self.named_guids: set[str] = set()

    # -- small builders -------------------------------------------------------------------
    def guid(self, *parts: str) -> str:
        key = "/".join((self.model.name or "scan", *parts))
        value = self.ios.guid.compress(uuid.uuid5(_GUID_NAMESPACE, key).hex)
        self.named_guids.add(value)
        return value

    def stable_guids(self) -> None:
        """Give the relationships and property sets ifcopenshell made (random GlobalIds) ids from
        their class and place in the file, so the same model gives the same GlobalIds in every run."""
        for entity in self.f.by_type("IfcRoot"):
            if entity.GlobalId not in self.named_guids:
                entity.GlobalId = self.guid(entity.is_a(), str(entity.id()))

    def point(self, xyz) -> object:
        return self.f.createIfcCartesianPoint([float(c) for c in xyz])

    def direction(self, xyz) -> object:
        return self.f.createIfcDirection([float(c) for c in xyz])

    def axis2(self, location, axis=None, ref=None) -> object:
        """An IfcAxis2Placement3D at ``location`` (3,) m with local z ``axis``, x ``ref``."""
        return self.f.createIfcAxis2Placement3D(
            self.point(location),
            None if axis is None else self.direction(axis),
            None if ref is None else self.direction(ref),
        )

    def circle_profile(self, radius: float, wall: float) -> object:
        origin = self.f.createIfcAxis2Placement2D(self.f.createIfcCartesianPoint([0.0, 0.0]))
        if wall > 0:
            return self.f.createIfcCircleHollowProfileDef(
                "AREA", None, origin, float(radius), float(wall)
            )
        return self.f.createIfcCircleProfileDef("AREA", None, origin, float(radius))

    def extruded_tube(self, start, direction, length, radius, wall) -> object:
        """A circle (hollow when ``wall`` > 0) extruded from ``start`` (3,) m along the unit
        ``direction`` (3,) by ``length`` m."""
        return self.f.createIfcExtrudedAreaSolid(
            self.circle_profile(radius, wall),
            self.axis2(start, direction, _perpendicular(direction)),
            self.direction([0.0, 0.0, 1.0]),
            float(length),
        )

    def face_set(self, mesh, anchor: np.ndarray) -> object:
        """A closed IfcTriangulatedFaceSet from a Mesh (welded), coordinates relative to
        ``anchor`` (3,) m."""
        vertices, faces = mesh.merged()
        points = self.f.createIfcCartesianPointList3D((vertices - anchor).tolist())
        return self.f.createIfcTriangulatedFaceSet(points, None, True, (faces + 1).tolist(), None)

    def style_for(self, component: Component) -> object:
        status = self.status.get(component.id)
        key = status if status in ("error", "warning") else component.type
        return self.surface_style(key, colour_for(component.type, status))

    def surface_style(self, key: str, rgba) -> object:
        """The one IfcSurfaceStyle named ``key`` (made on first use) of colour ``rgba`` (0..1)."""
        if key not in self.styles:
            r, g, b, a = rgba
            colour = self.f.createIfcColourRgb(None, float(r), float(g), float(b))
            shading = self.f.createIfcSurfaceStyleShading(colour, float(1.0 - a))
            self.styles[key] = self.f.createIfcSurfaceStyle(key, "BOTH", [shading])
        return self.styles[key]

    # -- geometry ---------------------------------------------------------------------------
    def shape(self, component: Component) -> tuple[np.ndarray, str, list]:
        """``(anchor (3,) m, representation type, items)`` of a component's body, the items
        in coordinates relative to the anchor."""
        g = component.geometry
        if isinstance(g, Straight):
            return (
                g.start,
                "SweptSolid",
                [self.extruded_tube(np.zeros(3), g.direction, g.length, g.outer_radius, g.wall)],
            )
        if isinstance(g, Cylinder):
            start, end = g.ends
            axis = (end - start) / np.linalg.norm(end - start)
            return (
                start,
                "SweptSolid",
                [self.extruded_tube(np.zeros(3), axis, g.length, g.radius, 0.0)],
            )
        if isinstance(g, Bend) and g.reducing:
            from asbuilt.cad.meshgen import mesh_for

            # ends of two sizes: no profile revolves into it, so its faceted tube
            mesh = mesh_for(g, plate_thickness=0.0)
            return g.center, "Tessellation", [self.face_set(mesh, g.center)]
        if isinstance(g, Bend):
            return g.center, "SweptSolid", [self.bend(g)]
        if isinstance(g, Tee | Cross):
            return g.center, "CSG", [self.tee(g)]
        if isinstance(g, Reducer):
            return g.start, "Tessellation", [self.face_set(self.reducer_mesh(g), g.start)]
        if isinstance(g, Cuboid):
            return g.center, "SweptSolid", [self.box(g)]
        if isinstance(g, Sphere):
            sphere = self.f.createIfcSphere(self.axis2([0.0, 0.0, 0.0]), float(g.radius))
            return g.center, "CSG", [sphere]
        if isinstance(g, Plane):
            from asbuilt.cad.meshgen import plate_mesh

            if len(g.outline) < 3:
                raise ExportError(
                    "cannot write its plate: the plane has no outline (a bounded plate needs at "
                    "least 3 outline points); refit it with points spread over the surface",
                    where=f"object {component.id}",
                )
            return (
                g.point,
                "Tessellation",
                [self.face_set(plate_mesh(g, self.plate_thickness), g.point)],
            )
        if isinstance(g, Hull):
            from asbuilt.cad.meshgen import hull_mesh

            anchor = g.vertices.mean(axis=0)
            return anchor, "Tessellation", [self.face_set(hull_mesh(g), anchor)]
        raise ExportError(
            f"no IFC geometry for a {type(g).__name__}", where=f"object {component.id}"
        )

    def bend(self, g: Bend) -> object:
        """The bend's section revolved about its axis; placed at the bend centre."""
        radial = g.start - g.center
        normal = np.cross(radial, g.end - g.center)
        normal /= np.linalg.norm(normal)
        x = radial / np.linalg.norm(radial)
        tangent = np.cross(normal, x)
        # The section lies in the plane at the start spanned by -x (towards the centre) and the
        # bend normal; the revolution axis, in that plane's coordinates, passes through the
        # centre (bend radius along -x) along the normal (the section's local y).
        position = self.axis2(radial, tangent, -x)
        axis = self.f.createIfcAxis1Placement(
            self.point([g.bend_radius, 0.0, 0.0]), self.direction([0.0, 1.0, 0.0])
        )
        return self.f.createIfcRevolvedAreaSolid(
            self.circle_profile(g.outer_radius, g.wall),
            position,
            axis,
            float(np.radians(g.angle_deg)),
        )

    def tee(self, g: Tee | Cross) -> object:
        """Run and branch cylinders united, their bores (when the wall is known) cut out;
        coordinates relative to the tee's centre. A cross's outlet cylinder runs from one
        outlet end through the centre to the other."""
        start, end, branch = g.run_start - g.center, g.run_end - g.center, g.branch_end - g.center
        run_length = float(np.linalg.norm(end - start))
        run_dir = (end - start) / run_length
        # the outlet cylinder starts at the centre (a tee) or at the first outlet end (a cross)
        origin = g.branch_start - g.center if isinstance(g, Cross) else np.zeros(3)
        overrun = BORE_OVERRUN if isinstance(g, Cross) else 0.0
        branch_length = float(np.linalg.norm(branch - origin))
        branch_dir = (branch - origin) / branch_length
        outer = self.f.createIfcBooleanResult(
            "UNION",
            self.extruded_tube(start, run_dir, run_length, g.outer_radius, 0.0),
            self.extruded_tube(origin, branch_dir, branch_length, g.branch_outer_radius, 0.0),
        )
        if g.wall <= 0:
            return outer
        bores = self.f.createIfcBooleanResult(
            "UNION",
            self.extruded_tube(
                start - BORE_OVERRUN * run_dir,
                run_dir,
                run_length + 2 * BORE_OVERRUN,
                g.outer_radius - g.wall,
                0.0,
            ),
            self.extruded_tube(
                origin - overrun * branch_dir,
                branch_dir,
                branch_length + BORE_OVERRUN + overrun,
                g.branch_outer_radius - g.branch_wall,
                0.0,
            ),
        )
        return self.f.createIfcBooleanResult("DIFFERENCE", outer, bores)

    @staticmethod
    def reducer_mesh(g: Reducer):
        """The reducer's closed tube mesh: end rings perpendicular to the run, the end ring's
        centre moved sideways by the offset (eccentric) or not (concentric)."""
        from asbuilt.cad.meshgen import tube_mesh

        u = _perpendicular(g.direction)
        v = np.cross(g.direction, u)
        return tube_mesh(
            np.array([g.start, g.end]),
            np.array([u, u]),
            np.array([v, v]),
            np.array([g.outer_radius_start, g.outer_radius_end]),
            np.array([g.wall_start, g.wall_end]),
        )

    def box(self, g: Cuboid) -> object:
        """A rectangle ``size[0]`` x ``size[1]`` extruded ``size[2]`` along the third axis,
        centred on the cuboid's centre."""
        axes = np.asarray(g.axes)
        size = np.asarray(g.size)
        origin = self.f.createIfcAxis2Placement2D(self.f.createIfcCartesianPoint([0.0, 0.0]))
        profile = self.f.createIfcRectangleProfileDef(
            "AREA", None, origin, float(size[0]), float(size[1])
        )
        return self.f.createIfcExtrudedAreaSolid(
            profile,
            self.axis2(-0.5 * size[2] * axes[2], axes[2], axes[0]),
            self.direction([0.0, 0.0, 1.0]),
            float(size[2]),
        )

    # -- properties -------------------------------------------------------------------------
    def catalog(self):
        if not self._catalog_loaded:
            self._catalog_loaded = True
            from asbuilt.catalog import model_catalog

            # A user catalog file (recorded by the model) wins over a shipped one of its name.
            self._catalog = model_catalog(self.model)[0]
        return self._catalog

    def nominal_diameter(self, component: Component) -> float | None:
        """The catalog's DN of the component's nominal size, metres (None when unknown)."""
        catalog = self.catalog()
        if catalog is None or component.nominal is None:
            return None
        try:
            dn = catalog.size(component.nominal).dn
        except (KeyError, ValueError, LookupError):
            return None
        return None if dn is None else dn / 1000.0

    def insulation(self, component: Component, element, storey) -> object | None:
        """The IfcCovering INSULATION around an insulated component (its jacket,
        :func:`asbuilt.insulation.jacket`), related to its element by IfcRelCoversBldgElements;
        None when it is bare."""
        geometry = jacket(component)
        if geometry is None:
            return None
        api, f = self.api, self.f
        name = f"{component.id} insulation"
        covering = api.root.create_entity(
            f, ifc_class="IfcCovering", predefined_type="INSULATION", name=name
        )
        covering.GlobalId = self.guid("insulation", component.id)
        anchor, kind, items = self.shape(dataclasses.replace(component, geometry=geometry))
        covering.ObjectPlacement = f.createIfcLocalPlacement(
            storey.ObjectPlacement, self.axis2(anchor)
        )
        representation = f.createIfcShapeRepresentation(self.body, "Body", kind, items)
        api.geometry.assign_representation(f, product=covering, representation=representation)
        style = self.surface_style("insulation", KIND_COLOURS["insulation"])
        api.style.assign_representation_styles(
            f, shape_representation=representation, styles=[style]
        )
        pset = api.pset.add_pset(f, product=covering, name="Asbuilt_Component")
        api.pset.edit_pset(
            f,
            pset=pset,
            properties={
                "ComponentType": "insulation",
                "InsulationThickness": f.createIfcPositiveLengthMeasure(component.insulation),
                "Covers": component.id,
            },
        )
        relation = api.root.create_entity(f, ifc_class="IfcRelCoversBldgElements")
        relation.RelatingBuildingElement = element
        relation.RelatedCoverings = [covering]
        return covering

    def asbuilt_properties(self, component: Component) -> dict:
        g = component.geometry
        props: dict = {"ComponentType": component.type}
        radius = _outer_radius(g)
        if radius is not None:
            props["OuterDiameter"] = self.f.createIfcPositiveLengthMeasure(2 * radius)
        wall = _wall(g)
        if wall:
            props["WallThickness"] = self.f.createIfcPositiveLengthMeasure(wall)
        if isinstance(g, Reducer):
            props["OuterDiameterEnd"] = self.f.createIfcPositiveLengthMeasure(
                2 * g.outer_radius_end
            )
            if g.wall_end:
                props["WallThicknessEnd"] = self.f.createIfcPositiveLengthMeasure(g.wall_end)
            props["Eccentric"] = g.eccentric
        if isinstance(g, Tee | Cross):
            props["BranchOuterDiameter"] = self.f.createIfcPositiveLengthMeasure(
                2 * g.branch_outer_radius
            )
            if g.branch_wall:
                props["BranchWallThickness"] = self.f.createIfcPositiveLengthMeasure(g.branch_wall)
        if isinstance(g, Bend) and g.reducing:
            radius_end, wall_end = g.radii[1], g.walls[1]
            props["OuterDiameterEnd"] = self.f.createIfcPositiveLengthMeasure(2 * radius_end)
            if wall_end:
                props["WallThicknessEnd"] = self.f.createIfcPositiveLengthMeasure(wall_end)
        if isinstance(g, Bend):
            props["BendRadius"] = self.f.createIfcPositiveLengthMeasure(g.bend_radius)
            props["BendAngle"] = self.f.createIfcPlaneAngleMeasure(float(np.radians(g.angle_deg)))
        for name, value in (
            ("NominalSize", component.nominal),
            ("Schedule", component.schedule),
            ("Spool", component.spool),
            ("Group", component.group),
            ("Catalog", self.model.catalog if component.nominal else None),
            ("SnapStatus", component.snap.get("status") if component.snap else None),
            ("Sources", ", ".join(component.sources) or None),
        ):
            if value:
                props[name] = str(value)
        fit = component.fit
        if fit is not None:
            if np.isfinite(fit.rms):
                props["FitRMS"] = self.f.createIfcLengthMeasure(fit.rms)
            props["FitPoints"] = fit.n_points
            props["FitInliers"] = fit.n_inliers
            props["FitMethod"] = fit.method
            for key, value in _stderr_items(fit.stderr):
                if key.endswith("_deg"):
                    props[f"StdErr_{key[:-4]}"] = self.f.createIfcPlaneAngleMeasure(
                        float(np.radians(value))
                    )
                else:
                    props[f"StdErr_{key}"] = self.f.createIfcLengthMeasure(value)
        if component.insulation:
            props["InsulationThickness"] = self.f.createIfcPositiveLengthMeasure(
                component.insulation
            )
        props["ComplianceStatus"] = self.status.get(component.id) or "ok"
        codes = self.codes.get(component.id)
        if codes:
            props["FindingCodes"] = ", ".join(sorted(set(codes)))
        return props

    def pipe_sets(self, element, component: Component, ifc_class: str) -> None:
        """The standard's pset and quantities for a pipe segment or fitting."""
        g = component.geometry
        radius = _outer_radius(g)
        wall = _wall(g)
        segment = ifc_class == "IfcPipeSegment"
        props: dict = {"Status": "EXISTING"}
        if segment and radius is not None:
            props["OuterDiameter"] = 2 * radius
            if wall:
                props["InnerDiameter"] = 2 * (radius - wall)
            dn = self.nominal_diameter(component)
            if dn is not None:
                props["NominalDiameter"] = dn
        name = "Pset_PipeSegmentTypeCommon" if segment else "Pset_PipeFittingTypeCommon"
        pset = self.api.pset.add_pset(self.f, product=element, name=name)
        self.api.pset.edit_pset(self.f, pset=pset, properties=props)
        quantities: dict = {}
        length = _centreline_length(g)
        if length is not None:
            quantities["Length"] = length
        if radius is not None:
            gross = float(np.pi * radius**2)
            quantities["GrossCrossSectionArea"] = gross
            inner = radius - wall if wall else 0.0
            quantities["NetCrossSectionArea"] = gross - float(np.pi * inner**2) if wall else gross
            if length is not None:
                quantities["OuterSurfaceArea"] = float(2 * np.pi * radius * length)
        name = "Qto_PipeSegmentBaseQuantities" if segment else "Qto_PipeFittingBaseQuantities"
        qto = self.api.pset.add_qto(self.f, product=element, name=name)
        self.api.pset.edit_qto(self.f, qto=qto, properties=quantities)

    # -- the document -----------------------------------------------------------------------
    def build(self):
        api, f = self.api, self.f
        name = self.model.name or "scan"
        project = api.root.create_entity(f, ifc_class="IfcProject", name=name)
        project.GlobalId = self.guid("project")
        lengths = api.unit.add_si_unit(f, unit_type="LENGTHUNIT")
        area = api.unit.add_si_unit(f, unit_type="AREAUNIT")
        volume = api.unit.add_si_unit(f, unit_type="VOLUMEUNIT")
        angle = api.unit.add_si_unit(f, unit_type="PLANEANGLEUNIT")
        api.unit.assign_unit(f, units=[lengths, area, volume, angle])
        model_context = api.context.add_context(f, context_type="Model")
        self.body = api.context.add_context(
            f,
            context_type="Model",
            context_identifier="Body",
            target_view="MODEL_VIEW",
            parent=model_context,
        )
        site = api.root.create_entity(f, ifc_class="IfcSite", name="site")
        building = api.root.create_entity(f, ifc_class="IfcBuilding", name=name)
        storey = api.root.create_entity(f, ifc_class="IfcBuildingStorey", name="as built")
        for entity, key in ((site, "site"), (building, "building"), (storey, "storey")):
            entity.GlobalId = self.guid(key)
        api.aggregate.assign_object(f, products=[site], relating_object=project)
        api.aggregate.assign_object(f, products=[building], relating_object=site)
        api.aggregate.assign_object(f, products=[storey], relating_object=building)
        for entity in (site, building, storey):
            api.geometry.edit_object_placement(f, product=entity)
        elements = {}
        coverings = []
        for component in self.model.components:
            elements[component.id] = self.element(component, storey)
            covering = self.insulation(component, elements[component.id], storey)
            if covering is not None:
                coverings.append(covering)
        if elements:
            api.spatial.assign_container(
                f, products=list(elements.values()) + coverings, relating_structure=storey
            )
        self.groups(elements, building)
        self.ports(elements)
        self.stable_guids()
        return f

    def element(self, component: Component, storey) -> object:
        api, f = self.api, self.f
        ifc_class, predefined = ifc_class_for(component)
        element = api.root.create_entity(
            f, ifc_class=ifc_class, predefined_type=predefined, name=component.id
        )
        element.GlobalId = self.guid("element", component.id)
        element.Description = component.label
        if ifc_class == "IfcBuildingElementProxy":
            element.ObjectType = component.type
        anchor, kind, items = self.shape(component)
        element.ObjectPlacement = f.createIfcLocalPlacement(
            storey.ObjectPlacement, self.axis2(anchor)
        )
        representation = f.createIfcShapeRepresentation(self.body, "Body", kind, items)
        api.geometry.assign_representation(f, product=element, representation=representation)
        api.style.assign_representation_styles(
            f, shape_representation=representation, styles=[self.style_for(component)]
        )
        pset = api.pset.add_pset(f, product=element, name="Asbuilt_Component")
        api.pset.edit_pset(f, pset=pset, properties=self.asbuilt_properties(component))
        if ifc_class in ("IfcPipeSegment", "IfcPipeFitting"):
            self.pipe_sets(element, component, ifc_class)
        return element

    def groups(self, elements: Mapping, building) -> None:
        """Spools as IfcDistributionSystem, other scan groups as IfcGroup."""
        api, f = self.api, self.f
        in_spool = set()
        for spool in self.model.spools:
            members = [elements[c] for c in spool.components if c in elements]
            if not members:
                continue
            system = api.system.add_system(f, ifc_class="IfcDistributionSystem")
            system.GlobalId = self.guid("spool", spool.id)
            system.Name = spool.id
            system.Description = "spool"
            system.PredefinedType = "NOTDEFINED"
            api.system.assign_system(f, products=members, system=system)
            f.createIfcRelServicesBuildings(
                self.guid("services", spool.id), None, None, None, system, [building]
            )
            pset = api.pset.add_pset(f, product=system, name="Asbuilt_Spool")
            api.pset.edit_pset(
                f,
                pset=pset,
                properties={"PipeLength": f.createIfcLengthMeasure(spool.pipe_length)},
            )
            in_spool.update(spool.components)
        by_group: dict[str, list] = {}
        for component in self.model.components:
            if component.group and component.id not in in_spool:
                by_group.setdefault(component.group, []).append(elements[component.id])
        for group_name, members in by_group.items():
            group = api.group.add_group(f, name=group_name)
            group.GlobalId = self.guid("group", group_name)
            api.group.assign_group(f, products=members, group=group)

    def ports(self, elements: Mapping) -> None:
        """A port at every piping end (nested in its element), joined ends connected."""
        api, f = self.api, self.f
        ends: list[tuple[np.ndarray, object]] = []
        for component in self.model.components:
            element = elements[component.id]
            if element.is_a() not in ("IfcPipeSegment", "IfcPipeFitting"):
                continue
            for index, (point, outward) in enumerate(_piping_ends(component.geometry)):
                port = api.system.add_port(f, element=element)
                port.GlobalId = self.guid("port", component.id, str(index))
                port.Name = f"{component.id}/{index}"
                port.PredefinedType = "PIPE"
                port.FlowDirection = "NOTDEFINED"
                port.ObjectPlacement = f.createIfcLocalPlacement(
                    element.ObjectPlacement,
                    self.axis2(
                        point - _anchor_of(element),
                        outward,
                        _perpendicular(outward),
                    ),
                )
                ends.append((point, port))
        if len(ends) < 2:
            return
        from scipy.spatial import cKDTree

        points = np.array([point for point, _ in ends])
        pairs = sorted(
            cKDTree(points).query_pairs(JOIN_TOLERANCE, output_type="ndarray").tolist(),
            key=lambda pair: float(np.linalg.norm(points[pair[0]] - points[pair[1]])),
        )
        used: set[int] = set()
        for a, b in pairs:
            port_a, port_b = ends[a][1], ends[b][1]
            if a in used or b in used or _owner(port_a) == _owner(port_b):
                continue
            used.update((a, b))
            api.system.connect_port(f, port1=port_a, port2=port_b)


def _anchor_of(element) -> np.ndarray:
    """The element's placement origin (3,) m (its local placement's location)."""
    return np.array(element.ObjectPlacement.RelativePlacement.Location.Coordinates, float)


def _owner(port):
    return port.Nests[0].RelatingObject if port.Nests else None


def _stderr_items(stderr: Mapping) -> list[tuple[str, float]]:
    """Flat ``(name, value)`` pairs of a fit's standard errors (vectors get ``_1``, ``_2``...)."""
    items = []
    for key, value in stderr.items():
        values = np.atleast_1d(np.asarray(value, dtype=float))
        if values.size == 1:
            if np.isfinite(values[0]):
                items.append((key, float(values[0])))
            continue
        base, suffix = (key[:-4], "_deg") if key.endswith("_deg") else (key, "")
        for i, v in enumerate(values, 1):
            if np.isfinite(v):
                items.append((f"{base}_{i}{suffix}", float(v)))
    return items


def ifc_document(model: Model, *, plate_thickness: float | None = None):
    """The IFC4 file (an ``ifcopenshell.file``) for ``model``.

    Parameters
    ----------
    model : asbuilt.model.Model
        Metres, scan frame (z up, which is IFC's up as well).
    plate_thickness : float, metres, optional
        Thickness of plates made from planes (default ``Tolerances.plate_thickness``).

    Raises
    ------
    ExportError
        ifcopenshell is not installed, or an object has no geometry IFC can carry (a plane
        without outline).
    """
    ifcopenshell = import_ifcopenshell()
    if plate_thickness is None:
        from asbuilt.tolerances import DEFAULT_TOLERANCES

        plate_thickness = DEFAULT_TOLERANCES.plate_thickness
    writer = _Writer(ifcopenshell, model, float(plate_thickness))
    document = writer.build()
    document.header.file_name.name = f"{model.name or 'scan'}.ifc"
    document.header.file_name.originating_system = f"asbuilt {__version__}"
    document.header.file_name.preprocessor_version = f"IfcOpenShell {ifcopenshell.version}"
    return document


def write_ifc(model: Model, path, *, plate_thickness: float | None = None) -> None:
    """Write ``model`` as IFC4 (STEP physical file) to ``path``.

    Parameters
    ----------
    model : asbuilt.model.Model
        Metres, scan frame.
    path : str or Path
        Written directly; callers stage it for atomicity (:mod:`asbuilt.export`).
    plate_thickness : float, metres, optional
        Thickness of plates made from planes (default ``Tolerances.plate_thickness``).

    Raises
    ------
    ExportError
        ifcopenshell is not installed (nothing is written), or see :func:`ifc_document`.
    """
    document = ifc_document(model, plate_thickness=plate_thickness)
    Path(path).write_text(document.to_string(), encoding="utf-8")
