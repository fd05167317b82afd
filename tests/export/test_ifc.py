"""IFC4 export: entity mapping, names, property sets, units, geometry, ports, groups, validation.

Truth values: the zoo's sizes and volumes from closed-form formulas (tests/cad/cad_zoo.py), NPS 4
= DN 100, OD 114.3 mm, STD wall 6.02 mm (ASME B36.10M, /work/shared/reference/standards.md), the
colour table (asbuilt/cad/colours.py). The file is read back with ifcopenshell and checked with
its schema validator including the EXPRESS where rules.
"""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from importlib.util import find_spec
from pathlib import Path

import numpy as np
import pytest
from cad_zoo import R3, R4, W3, W4, expected_volumes, frustum, rotation_z, zoo_model

from asbuilt.cad.colours import STATUS_COLOURS, colour_for
from asbuilt.cli import main
from asbuilt.errors import ExportError
from asbuilt.export import export_model, export_models
from asbuilt.model import Component, Model, Reducer, Spool, Straight
from asbuilt.primitives import Cuboid, Cylinder, Plane

ROOT = Path(__file__).resolve().parents[2]

needs_ifc = pytest.mark.skipif(
    find_spec("ifcopenshell") is None,
    reason="ifcopenshell is not installed (the optional 'ifc' extra: pip install 'asbuilt[ifc]')",
)

#: Eccentric reducer: run along +x, the small end stepped down so both bottoms are flush.
ECC_START = np.array([3.5, 0.0, 0.0])
ECC_OFFSET = np.array([0.0, 0.0, -(R4 - R3)])
ECC_LENGTH = 0.15


def extra_components() -> list[Component]:
    """Labelled fitted objects, a coupling and an eccentric reducer added to the zoo."""
    return [
        Component(
            "ER",
            "reducer",
            Reducer(
                ECC_START, ECC_START + [ECC_LENGTH, 0, 0] + ECC_OFFSET, R4, R3, 0.0, ECC_OFFSET
            ),
        ),
        Component("CP", "coupling", Straight([0, 3, 0], [0.1, 3, 0], R4, W4)),
        Component(
            "COL",
            "cuboid",
            Cuboid([10, 0, 1.5], np.eye(3), [0.3, 0.3, 3.0]),
            label="Column A1",
        ),
        Component(
            "BM",
            "cuboid",
            Cuboid([10, 2, 3.1], rotation_z(90), [2.0, 0.2, 0.3]),
            label="beam 1, west",
        ),
        Component(
            "TK", "cylinder", Cylinder([12, 0, 2], [0, 0, 1], 1.5, 4.0), label="vertical tank"
        ),
        Component(
            "WL",
            "plane",
            Plane([14, 0, 1.5], [1, 0, 0], [[14, -2, 0], [14, 2, 0], [14, 2, 3], [14, -2, 3]]),
            label="wall behind the structure",
        ),
    ]


def ifc_model() -> Model:
    zoo = zoo_model()
    return zoo.replace(
        components=zoo.components + tuple(extra_components()),
        spools=zoo.spools + (Spool("S2", ("T1", "R1"), pipe_length=0.0),),
    )


#: Component id -> (IFC class, PredefinedType).
EXPECTED_CLASSES = {
    "P1": ("IfcPipeSegment", "RIGIDSEGMENT"),
    "P2": ("IfcPipeSegment", "RIGIDSEGMENT"),
    "E1": ("IfcPipeFitting", "BEND"),
    "T1": ("IfcPipeFitting", "JUNCTION"),
    "R1": ("IfcPipeFitting", "TRANSITION"),
    "ER": ("IfcPipeFitting", "TRANSITION"),
    "CP": ("IfcPipeFitting", "CONNECTOR"),
    "CY": ("IfcBuildingElementProxy", "NOTDEFINED"),
    "C1": ("IfcBuildingElementProxy", "NOTDEFINED"),
    "SP": ("IfcBuildingElementProxy", "NOTDEFINED"),
    "H": ("IfcBuildingElementProxy", "NOTDEFINED"),
    "PL": ("IfcPlate", "NOTDEFINED"),
    "COL": ("IfcColumn", "COLUMN"),
    "BM": ("IfcBeam", "BEAM"),
    "TK": ("IfcTank", "NOTDEFINED"),
    "WL": ("IfcWall", "NOTDEFINED"),
}


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    path = tmp_path_factory.mktemp("ifc") / "zoo.ifc"
    result = export_model(ifc_model(), path)
    return path, result


@pytest.fixture(scope="module")
def ifc(written):
    import ifcopenshell

    return ifcopenshell.open(str(written[0]))


@pytest.fixture(scope="module")
def elements(ifc):
    return {e.Name: e for e in ifc.by_type("IfcElement")}


@pytest.fixture(scope="module")
def shapes(elements):
    """Each element's triangulated geometry in world coordinates (ifcopenshell.geom), metres."""
    import ifcopenshell.geom

    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    # 0.2 mm chords, 0.1 rad between facets: volumes within 0.1% of the true solids.
    settings.set("mesher-linear-deflection", 2e-4)
    settings.set("mesher-angular-deflection", 0.1)
    return {
        name: ifcopenshell.geom.create_shape(settings, element).geometry
        for name, element in elements.items()
    }


def _vertices(geometry) -> np.ndarray:
    return np.asarray(geometry.verts, dtype=float).reshape(-1, 3)


def _psets(element) -> dict:
    import ifcopenshell.util.element

    return ifcopenshell.util.element.get_psets(element)


@needs_ifc
def test_written_through_the_registry(written):
    path, result = written
    assert result.name == "IFC"
    assert result.objects == len(EXPECTED_CLASSES)
    assert path.read_text(encoding="utf-8").startswith("ISO-10303-21;")
    assert "FILE_SCHEMA(('IFC4'))" in path.read_text(encoding="utf-8")


@needs_ifc
@pytest.mark.parametrize(("name", "expected"), sorted(EXPECTED_CLASSES.items()))
def test_entity_class_and_predefined_type(elements, name, expected):
    element = elements[name]
    assert (element.is_a(), element.PredefinedType) == expected


@needs_ifc
def test_one_element_per_component_named_by_id_described_by_label(ifc, elements):
    model = ifc_model()
    assert len(ifc.by_type("IfcElement")) == len(model.components)
    for component in model.components:
        assert elements[component.id].Description == component.label
    counts = {}
    for ifc_class, _ in EXPECTED_CLASSES.values():
        counts[ifc_class] = counts.get(ifc_class, 0) + 1
    for ifc_class, count in counts.items():
        assert len(ifc.by_type(ifc_class)) == count, ifc_class


@needs_ifc
def test_units_are_metres_and_radians(ifc):
    import ifcopenshell.util.unit

    assert ifc.schema == "IFC4"
    assert ifcopenshell.util.unit.calculate_unit_scale(ifc) == 1.0
    units = {u.UnitType: u for u in ifc.by_type("IfcProject")[0].UnitsInContext.Units}
    assert (units["LENGTHUNIT"].Name, units["LENGTHUNIT"].Prefix) == ("METRE", None)
    assert (units["PLANEANGLEUNIT"].Name, units["PLANEANGLEUNIT"].Prefix) == ("RADIAN", None)


@needs_ifc
def test_spatial_structure(ifc, elements):
    import ifcopenshell.util.element

    (project,) = ifc.by_type("IfcProject")
    (site,) = ifc.by_type("IfcSite")
    (building,) = ifc.by_type("IfcBuilding")
    (storey,) = ifc.by_type("IfcBuildingStorey")
    assert project.Name == "zoo"
    assert ifcopenshell.util.element.get_aggregate(site) == project
    assert ifcopenshell.util.element.get_aggregate(building) == site
    assert ifcopenshell.util.element.get_aggregate(storey) == building
    for element in elements.values():
        assert ifcopenshell.util.element.get_container(element) == storey


@needs_ifc
def test_pipe_segment_psets_and_quantities(elements):
    psets = _psets(elements["P1"])
    common = psets["Pset_PipeSegmentTypeCommon"]
    assert common["Status"] == "EXISTING"
    assert common["OuterDiameter"] == pytest.approx(0.1143)
    assert common["InnerDiameter"] == pytest.approx(0.1143 - 2 * 0.00602)
    assert common["NominalDiameter"] == pytest.approx(0.100)  # NPS 4 = DN 100
    qto = psets["Qto_PipeSegmentBaseQuantities"]
    assert qto["Length"] == pytest.approx(1.0)
    assert qto["GrossCrossSectionArea"] == pytest.approx(math.pi * R4**2)
    assert qto["NetCrossSectionArea"] == pytest.approx(math.pi * (R4**2 - (R4 - W4) ** 2))
    assert qto["OuterSurfaceArea"] == pytest.approx(2 * math.pi * R4 * 1.0)
    own = psets["Asbuilt_Component"]
    assert own["NominalSize"] == "4"
    assert own["Schedule"] == "STD"
    assert own["Spool"] == "S1"
    assert own["OuterDiameter"] == pytest.approx(0.1143)
    assert own["WallThickness"] == pytest.approx(0.00602)
    assert own["ComplianceStatus"] == "ok"


@needs_ifc
def test_fitting_psets_and_quantities(elements):
    elbow = _psets(elements["E1"])
    assert elbow["Pset_PipeFittingTypeCommon"]["Status"] == "EXISTING"
    # A 90 degree bend of radius 0.2 m: centreline arc 0.1 pi.
    assert elbow["Qto_PipeFittingBaseQuantities"]["Length"] == pytest.approx(0.1 * math.pi)
    assert elbow["Asbuilt_Component"]["BendRadius"] == pytest.approx(0.2)
    assert elbow["Asbuilt_Component"]["BendAngle"] == pytest.approx(math.pi / 2)
    reducer = _psets(elements["ER"])["Asbuilt_Component"]
    assert reducer["Eccentric"] is True
    assert reducer["OuterDiameterEnd"] == pytest.approx(2 * R3)
    # each end's own STD wall (NPS 4 6.02 mm, NPS 3 5.49 mm), the NPS 4 end's in the quantities
    r1 = _psets(elements["R1"])
    assert r1["Asbuilt_Component"]["Eccentric"] is False
    assert r1["Asbuilt_Component"]["WallThickness"] == pytest.approx(W4)
    assert r1["Asbuilt_Component"]["WallThicknessEnd"] == pytest.approx(W3)
    net = r1["Qto_PipeFittingBaseQuantities"]["NetCrossSectionArea"]
    assert net == pytest.approx(math.pi * (R4**2 - (R4 - W4) ** 2))
    tee = _psets(elements["T1"])["Asbuilt_Component"]
    assert (tee["WallThickness"], tee["BranchWallThickness"]) == pytest.approx((W4, W3))


@pytest.mark.parametrize(
    ("name", "status", "codes"),
    [
        ("C1", "error", "AB101"),
        ("SP", "warning", "AB201"),
        ("H", "info", "AB301"),
        ("CY", "ok", None),
    ],
)
@needs_ifc
def test_compliance_status_and_finding_codes(elements, name, status, codes):
    own = _psets(elements[name])["Asbuilt_Component"]
    assert own["ComplianceStatus"] == status
    assert own.get("FindingCodes") == codes


@needs_ifc
def test_fit_data_in_the_pset(tmp_path):
    """A fitted model: RMS and standard errors of the fit are carried (metres, radians)."""
    import ifcopenshell

    from asbuilt.fit import fit
    from asbuilt.model import model_from_fits
    from asbuilt.scan import load_scan

    report = fit(load_scan(ROOT / "samples" / "structural-bay.json"))
    model = model_from_fits(report)
    export_model(model, tmp_path / "bay.ifc")
    f = ifcopenshell.open(str(tmp_path / "bay.ifc"))
    for item in report.fits:
        element = next(e for e in f.by_type("IfcElement") if e.Name == item.object.id)
        own = _psets(element)["Asbuilt_Component"]
        assert own["FitRMS"] == pytest.approx(item.result.rms)
        assert own["FitPoints"] == item.result.n_points
        for key, value in item.result.stderr.items():
            values = np.atleast_1d(value)
            if key.endswith("_deg") and values.size == 1:
                assert own[f"StdErr_{key[:-4]}"] == pytest.approx(math.radians(values[0]))
            elif values.size == 1:
                assert own[f"StdErr_{key}"] == pytest.approx(values[0])
    # Labelled "column A1".. and "beam 1, west"..: columns and beams.
    classes = {e.Name: e.is_a() for e in f.by_type("IfcElement")}
    assert classes == {
        **dict.fromkeys(("C1", "C2", "C3", "C4"), "IfcColumn"),
        **dict.fromkeys(("B1", "B2", "B3", "B4"), "IfcBeam"),
    }


@needs_ifc
def test_volumes_equal_the_formulas(shapes):
    import ifcopenshell.util.shape

    expected = expected_volumes()
    expected["ER"] = frustum(R4, R3, ECC_LENGTH)  # Cavalieri: an oblique frustum keeps its volume
    expected["CP"] = math.pi * (R4**2 - (R4 - W4) ** 2) * 0.1
    expected["COL"] = 0.3 * 0.3 * 3.0
    expected["BM"] = 2.0 * 0.2 * 0.3
    expected["TK"] = math.pi * 1.5**2 * 4.0
    expected["WL"] = 4.0 * 3.0 * 0.010
    for name, volume in expected.items():
        measured = ifcopenshell.util.shape.get_volume(shapes[name])
        assert measured == pytest.approx(volume, rel=2e-3), name


#: The audit's survey shift (UTM-like easting/northing and a height), metres.
SURVEY_OFFSET = np.array([500_000.0, 5_000_000.0, 250.0])
_POSITIONS = ("start", "end", "center", "run_start", "run_end", "branch_end", "point", "outline")


@needs_ifc
def test_survey_coordinates_keep_the_solids(tmp_path):
    """5,000 km north: each element is placed at its own anchor, so the solids come back whole
    and in place (volumes summed about the shift, as doubles cannot resolve mm3 at 5e6 m)."""
    import ifcopenshell
    import ifcopenshell.geom

    def shifted(geometry):
        return dataclasses.replace(
            geometry,
            **{
                f.name: np.asarray(getattr(geometry, f.name)) + SURVEY_OFFSET
                for f in dataclasses.fields(geometry)
                if f.name in (*_POSITIONS, "vertices")
            },
        )

    zoo = zoo_model()
    model = zoo.replace(
        components=tuple(
            dataclasses.replace(c, geometry=shifted(c.geometry)) for c in zoo.components
        )
    )
    export_model(model, tmp_path / "survey.ifc")
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    settings.set("mesher-linear-deflection", 2e-4)
    settings.set("mesher-angular-deflection", 0.1)
    expected = expected_volumes()
    # The lowest corner of some solids, from the zoo's definitions (metres, before the shift).
    low = {
        "P1": [0.0, -R4, -R4],
        "E1": [1.0, -R4, -R4],
        "T1": [2.8, -R4, -R4],
        "R1": [3.2, -R4, -R4],
        "SP": [6.5, -0.5, 0.5],
        "PL": [7.0, -1.0, -0.005],
        "CY": [4.85, -0.15, 0.0],
    }
    document = ifcopenshell.open(str(tmp_path / "survey.ifc"))  # kept: elements need it alive
    for element in document.by_type("IfcElement"):
        geometry = ifcopenshell.geom.create_shape(settings, element).geometry
        vertices = _vertices(geometry) - SURVEY_OFFSET
        tri = vertices[np.asarray(geometry.faces).reshape(-1, 3)]
        volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
        assert volume == pytest.approx(expected[element.Name], rel=2e-3), element.Name
        if element.Name in low:
            assert vertices.min(axis=0) == pytest.approx(low[element.Name], abs=1e-3)


@needs_ifc
def test_pipe_length_and_diameter_from_the_geometry(shapes):
    """P2 runs along +y from (1.2, 0.2, 0) to (1.2, 1.2, 0) with OD 114.3 mm."""
    vertices = _vertices(shapes["P2"])
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    assert high[1] - low[1] == pytest.approx(1.0, abs=1e-9)
    assert low[1] == pytest.approx(0.2, abs=1e-9)
    # Across the axis the facets' vertices lie on the circle: the extent is the OD within the
    # 0.2 mm chord deviation asked for.
    assert high[0] - low[0] == pytest.approx(2 * R4, abs=4e-4)
    assert high[2] - low[2] == pytest.approx(2 * R4, abs=4e-4)
    assert 0.5 * (high[[0, 2]] + low[[0, 2]]) == pytest.approx([1.2, 0.0], abs=1e-9)


@needs_ifc
@needs_ifc
def test_a_reducing_elbow_has_each_ends_size_and_wall(tmp_path, elbow_6x4):
    """NPS 6 x 4 SCH 40 (ASME B36.10M: OD 168.3 / 114.3 mm, wall 7.11 / 6.02 mm): a faceted
    tube with the volume of radii changing evenly with the angle (Pappus), and both ends'
    sizes in the asbuilt pset; the file passes the schema and where-rule validators."""
    import ifcopenshell
    import ifcopenshell.geom
    import ifcopenshell.util.shape
    import ifcopenshell.validate

    path = tmp_path / "elbow.ifc"
    export_model(elbow_6x4, path)
    f = ifcopenshell.open(str(path))
    (elbow,) = [e for e in f.by_type("IfcPipeFitting") if e.Name == "P1-P2"]
    props = _psets(elbow)["Asbuilt_Component"]
    assert (props["OuterDiameter"], props["OuterDiameterEnd"]) == pytest.approx((0.1683, 0.1143))
    assert (props["WallThickness"], props["WallThicknessEnd"]) == pytest.approx((0.00711, 0.00602))
    g = elbow_6x4.component("P1-P2").geometry
    angle = math.radians(g.angle_deg)

    def tube(a, b):
        return math.pi * g.bend_radius * angle * (a * a + a * b + b * b) / 3

    (r1, r2), (w1, w2) = g.radii, g.walls
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    shape = ifcopenshell.geom.create_shape(settings, elbow).geometry
    volume = ifcopenshell.util.shape.get_volume(shape)
    assert volume == pytest.approx(tube(r1, r2) - tube(r1 - w1, r2 - w2), rel=2e-3)
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(f, logger, express_rules=True)
    assert logger.statements == []


def test_bend_and_tee_in_place(shapes):
    bend = _vertices(shapes["E1"])
    # Elbow from (1, 0, 0) to (1.2, 0.2, 0) about (1, 0.2, 0): outer fibre reaches x = 1.2 + R4.
    assert bend[:, 0].min() == pytest.approx(1.0, abs=1e-9)
    assert bend[:, 0].max() == pytest.approx(1.2 + R4, abs=4e-4)
    assert bend[:, 1].min() == pytest.approx(-R4, abs=4e-4)
    tee = _vertices(shapes["T1"])
    assert tee[:, 0].min() == pytest.approx(2.8, abs=1e-9)
    assert tee[:, 0].max() == pytest.approx(3.2, abs=1e-9)
    assert tee[:, 2].max() == pytest.approx(0.25, abs=1e-9)


@needs_ifc
def test_eccentric_reducer_is_flat_on_one_side(shapes):
    vertices = _vertices(shapes["ER"])
    start = vertices[np.isclose(vertices[:, 0], ECC_START[0])]
    end = vertices[np.isclose(vertices[:, 0], ECC_START[0] + ECC_LENGTH)]
    # Flat side (the bottom): both ends reach down to -R4; the tops differ by the radii's step.
    assert start[:, 2].min() == pytest.approx(-R4, abs=1e-3)
    assert end[:, 2].min() == pytest.approx(-R4, abs=1e-3)
    assert start[:, 2].max() - end[:, 2].max() == pytest.approx(2 * (R4 - R3), abs=2e-3)


@needs_ifc
def test_spools_are_distribution_systems_and_groups(ifc):
    systems = {s.Name: s for s in ifc.by_type("IfcDistributionSystem")}
    assert set(systems) == {"S1", "S2"}

    def members(group):
        return {o.Name for rel in group.IsGroupedBy for o in rel.RelatedObjects}

    assert members(systems["S1"]) == {"P1", "E1", "P2"}
    assert members(systems["S2"]) == {"T1", "R1"}
    plain = {g.Name: g for g in ifc.by_type("IfcGroup") if g.is_a() == "IfcGroup"}
    assert members(plain["frame"]) == {"CY", "C1"}
    for system in systems.values():
        assert system.ServicesBuildings[0].RelatedBuildings[0].is_a("IfcBuilding")


@needs_ifc
def test_ports_nested_at_the_ends_and_joined(ifc, elements):
    import ifcopenshell.util.placement

    ports_per = {"P1": 2, "P2": 2, "E1": 2, "T1": 3, "R1": 2, "ER": 2, "CP": 2}
    for name, count in ports_per.items():
        nested = [p for rel in elements[name].IsNestedBy for p in rel.RelatedObjects]
        assert len(nested) == count, name
        assert all(p.is_a("IfcDistributionPort") and p.PredefinedType == "PIPE" for p in nested)
    for name in ("CY", "C1", "COL"):
        assert not elements[name].IsNestedBy
    # Port P1/1 sits at P1's end (1, 0, 0), pointing out along +x.
    port = next(p for p in ifc.by_type("IfcDistributionPort") if p.Name == "P1/1")
    matrix = ifcopenshell.util.placement.get_local_placement(port.ObjectPlacement)
    assert matrix[:3, 3] == pytest.approx([1.0, 0.0, 0.0])
    assert matrix[:3, 2] == pytest.approx([1.0, 0.0, 0.0])

    def owner(p):
        return p.Nests[0].RelatingObject.Name

    joints = {
        frozenset((owner(r.RelatingPort), owner(r.RelatedPort)))
        for r in ifc.by_type("IfcRelConnectsPorts")
    }
    # P1-E1 at (1,0,0), E1-P2 at (1.2,0.2,0), T1-R1 at (3.2,0,0); ER and CP touch nothing.
    assert joints == {frozenset(("P1", "E1")), frozenset(("E1", "P2")), frozenset(("T1", "R1"))}


@needs_ifc
@pytest.mark.parametrize(
    ("name", "colour"),
    [
        ("P1", colour_for("pipe")),
        ("E1", colour_for("elbow")),
        ("C1", STATUS_COLOURS["error"]),
        ("SP", STATUS_COLOURS["warning"]),
        ("H", colour_for("hull")),
    ],
)
def test_colours_by_kind_and_status(elements, name, colour):
    (representation,) = elements[name].Representation.Representations
    (styled,) = [s for item in representation.Items for s in item.StyledByItem]
    (style,) = styled.Styles
    (shading,) = style.Styles
    rgb = shading.SurfaceColour
    assert (rgb.Red, rgb.Green, rgb.Blue) == pytest.approx(colour[:3])
    assert shading.Transparency == pytest.approx(1.0 - colour[3])


@needs_ifc
def test_schema_validator_finds_no_errors(written):
    """Entity types, attribute types, enumerations, aggregate and inverse cardinalities."""
    import ifcopenshell.validate

    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(str(written[0]), logger)
    assert logger.statements == []


@pytest.mark.slow  # the EXPRESS where rules are evaluated in Python: 4-9 s for this file
@needs_ifc
def test_where_rules_validator_finds_no_errors(written):
    import ifcopenshell.validate

    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(str(written[0]), logger, express_rules=True)
    assert logger.statements == []


@needs_ifc
def test_same_model_same_global_ids(tmp_path, ifc):
    import ifcopenshell

    export_model(ifc_model(), tmp_path / "again.ifc")
    again = ifcopenshell.open(str(tmp_path / "again.ifc"))
    ids = sorted(e.GlobalId for e in ifc.by_type("IfcRoot"))
    assert sorted(e.GlobalId for e in again.by_type("IfcRoot")) == ids
    assert len(set(ids)) == len(ids)


@needs_ifc
def test_plane_without_outline_is_one_line(tmp_path):
    model = Model(components=(Component("W9", "plane", Plane([0, 0, 0], [0, 0, 1])),))
    with pytest.raises(ExportError, match=r"w\.ifc: object W9: cannot write its plate"):
        export_model(model, tmp_path / "w.ifc")
    assert list(tmp_path.iterdir()) == []


@needs_ifc
def test_cli_writes_ifc(tmp_path, capsys):
    import ifcopenshell

    out = tmp_path / "spool.ifc"
    assert main(["model", str(ROOT / "samples" / "spool.json"), "--out", str(out)]) == 0
    f = ifcopenshell.open(str(out))
    fittings = {e.PredefinedType for e in f.by_type("IfcPipeFitting")}
    assert {"BEND", "JUNCTION", "TRANSITION"} <= fittings
    assert f.by_type("IfcRelConnectsPorts")
    assert f.by_type("IfcDistributionSystem")


def test_missing_ifcopenshell_is_one_clear_line_and_nothing_written(tmp_path, monkeypatch):
    for name in [m for m in sys.modules if m == "ifcopenshell" or m.startswith("ifcopenshell.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "ifcopenshell", None)  # makes `import ifcopenshell` fail
    with pytest.raises(ExportError) as caught:
        export_models(zoo_model(), [tmp_path / "a.json", tmp_path / "a.ifc"])
    assert str(caught.value) == (
        f"{tmp_path / 'a.ifc'}: writing IFC needs the ifcopenshell package: "
        "pip install 'asbuilt[ifc]'"
    )
    assert list(tmp_path.iterdir()) == []


def test_missing_ifcopenshell_cli_exit_2(tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "ifcopenshell", None)
    out = tmp_path / "spool.ifc"
    assert main(["model", str(ROOT / "samples" / "spool.json"), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].endswith(
        "writing IFC needs the ifcopenshell package: pip install 'asbuilt[ifc]'"
    )
    assert list(tmp_path.iterdir()) == []


def test_importing_asbuilt_and_the_ifc_module_does_not_load_ifcopenshell():
    code = (
        "import sys, asbuilt, asbuilt.export, asbuilt.export.ifc, asbuilt.fit; "
        "assert 'ifcopenshell' not in sys.modules, 'ifcopenshell loaded'; "
        "assert 'cadquery' not in sys.modules, 'cadquery loaded'"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=ROOT)


@needs_ifc
def test_nominal_diameter_from_the_models_own_catalog_file(tmp_path):
    """A user catalog recorded by the model wins over the shipped catalog of the same name."""
    import ifcopenshell

    lines = (ROOT / "catalogs" / "asme-b36.10m.csv").read_text(encoding="utf-8").splitlines()
    edited = [
        line.replace("4,100,", "4,101,", 1) if line.startswith("4,100,") else line for line in lines
    ]
    assert edited != lines
    user = tmp_path / "mine.csv"
    user.write_text("\n".join(edited) + "\n", encoding="utf-8")
    zoo = zoo_model()
    model = zoo.replace(components=zoo.components[:1], catalog_file=str(user))
    export_model(model, tmp_path / "p.ifc")
    document = ifcopenshell.open(str(tmp_path / "p.ifc"))
    (pipe,) = document.by_type("IfcPipeSegment")
    assert _psets(pipe)["Pset_PipeSegmentTypeCommon"]["NominalDiameter"] == pytest.approx(0.101)


@needs_ifc
def test_insulation_is_a_covering_of_its_element(tmp_path):
    """An insulated component's jacket is an IfcCovering INSULATION, related to its element
    (IfcRelCoversBldgElements), of the jacket's volume; the element says the thickness too."""
    import ifcopenshell
    import ifcopenshell.geom
    import ifcopenshell.util.element
    import ifcopenshell.util.shape
    import ifcopenshell.validate

    t = 0.05
    lagged = {"P1", "E1", "CY"}
    model = zoo_model()
    model = model.replace(
        components=tuple(
            dataclasses.replace(c, insulation=t) if c.id in lagged else c for c in model.components
        )
    )
    path = tmp_path / "lagged.ifc"
    export_model(model, path)
    f = ifcopenshell.open(str(path))
    coverings = {c.Name: c for c in f.by_type("IfcCovering")}
    assert set(coverings) == {f"{name} insulation" for name in lagged}
    covered = {
        rel.RelatedCoverings[0].Name: rel.RelatingBuildingElement.Name
        for rel in f.by_type("IfcRelCoversBldgElements")
    }
    assert covered == {f"{name} insulation": name for name in lagged}
    settings = ifcopenshell.geom.settings()
    settings.set("use-world-coords", True)
    settings.set("mesher-linear-deflection", 2e-4)
    settings.set("mesher-angular-deflection", 0.1)
    ring = math.pi * ((R4 + t) ** 2 - R4**2)
    expected = {
        "P1 insulation": ring * 1.0,
        "E1 insulation": ring * 0.2 * math.pi / 2,  # Pappus, bend radius 0.2 m
        "CY insulation": math.pi * ((0.15 + t) ** 2 - 0.15**2) * 3.0,
    }
    for name, volume in expected.items():
        covering = coverings[name]
        assert covering.PredefinedType == "INSULATION"
        shape = ifcopenshell.geom.create_shape(settings, covering).geometry
        assert ifcopenshell.util.shape.get_volume(shape) == pytest.approx(volume, rel=2e-3)
        props = ifcopenshell.util.element.get_psets(covering)["Asbuilt_Component"]
        assert props["InsulationThickness"] == pytest.approx(t)
    pipe = next(e for e in f.by_type("IfcPipeSegment") if e.Name == "P1")
    assert ifcopenshell.util.element.get_psets(pipe)["Asbuilt_Component"][
        "InsulationThickness"
    ] == pytest.approx(t)
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(str(path), logger)
    assert logger.statements == []
