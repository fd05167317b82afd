"""STEP round trips through the OpenCASCADE reader: names, tree, solids, volumes, colours, mm."""

from __future__ import annotations

import itertools
import math
import re
from pathlib import Path

import numpy as np
import pytest

from asbuilt.cad import prepare
from asbuilt.cad.colours import KIND_COLOURS, STATUS_COLOURS
from asbuilt.errors import ExportError
from asbuilt.export import export_model
from asbuilt.export.step import declared_length_unit, p21_escape, read_step, write_step
from asbuilt.model import Component, Model, Straight


@pytest.fixture(scope="module")
def step_file(zoo_cad, tmp_path_factory):
    path = tmp_path_factory.mktemp("step") / "zoo.step"
    write_step(zoo_cad, path)
    return path


def test_same_solids_names_and_volumes_within_0_1_percent(zoo_cad, step_file):
    solids = read_step(step_file)
    assert [s.name for s in solids] == [part.id for part in zoo_cad.parts]
    assert all(s.solids == 1 for s in solids)
    for part, read in zip(zoo_cad.parts, solids):
        in_memory_mm3 = part.solid.Volume() * 1e9
        assert read.volume == pytest.approx(in_memory_mm3, rel=1e-3), part.id


def test_tree_is_scan_group_object(step_file):
    paths = {s.name: s.path for s in read_step(step_file)}
    assert paths["P1"] == ("zoo", "S1", "P1")
    assert paths["T1"] == ("zoo", "S2", "T1")
    assert paths["C1"] == ("zoo", "frame", "C1")
    assert paths["SP"] == ("zoo", "SP")


def test_colours_are_by_kind_and_status(step_file):
    colours = {s.name: s.colour for s in read_step(step_file)}
    assert colours["P1"][:3] == pytest.approx(KIND_COLOURS["pipe"][:3], abs=1e-6)
    assert colours["C1"][:3] == pytest.approx(STATUS_COLOURS["error"][:3], abs=1e-6)
    assert colours["SP"][:3] == pytest.approx(STATUS_COLOURS["warning"][:3], abs=1e-6)


def test_golden_the_file_declares_millimetres_and_ap214(step_file):
    text = step_file.read_text(encoding="latin-1")
    assert "SI_UNIT(.MILLI.,.METRE.)" in text
    assert "AUTOMOTIVE_DESIGN" in text  # the AP214 schema name
    assert declared_length_unit(step_file) == "mm"
    for name in ("P1", "E1", "T1", "C1", "H"):
        assert f"PRODUCT('{name}','{name}'" in text


def test_header_names_the_final_file_not_the_temporary_one(zoo, tmp_path):
    path = tmp_path / "plant model.step"
    export_model(zoo, path)
    header = path.read_text(encoding="latin-1").split("ENDSEC;")[0]
    assert "FILE_NAME('plant model.step'" in header
    assert ".part" not in header
    assert "'asbuilt " in header and "as-built model: zoo" in header


def test_ap242_schema(zoo_cad, tmp_path):
    path = tmp_path / "zoo.stp"
    write_step(zoo_cad, path, schema="AP242")
    text = path.read_text(encoding="latin-1")
    assert "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING" in text
    assert declared_length_unit(path) == "mm"
    assert len(read_step(path)) == len(zoo_cad.parts)


def test_unknown_schema_is_refused(zoo_cad, tmp_path):
    with pytest.raises(ExportError, match="unknown STEP schema 'AP203'"):
        write_step(zoo_cad, tmp_path / "x.step", schema="AP203")


@pytest.mark.parametrize("units", ["m", "mm", "in"])
def test_millimetres_whatever_the_scan_units(units, tmp_path):
    pipe = Component("P1", "pipe", Straight([0, 0, 0], [0.5, 0, 0], 0.05))
    model = Model(components=(pipe,), units=units, name="one")
    path = tmp_path / "one.step"
    export_model(model, path)
    assert declared_length_unit(path) == "mm"
    (solid,) = read_step(path)
    assert solid.volume == pytest.approx(math.pi * 50.0**2 * 500.0, rel=1e-6)


def test_reading_leaves_the_kernel_unit_setting_alone(zoo_cad, tmp_path):
    from OCP.Interface import Interface_Static

    before = Interface_Static.CVal_s("xstep.cascade.unit")
    write_step(prepare(Model(components=zoo_cad.model.components[:1])), tmp_path / "a.step")
    read_step(tmp_path / "a.step")
    assert Interface_Static.CVal_s("xstep.cascade.unit") == before


def test_not_a_step_file(tmp_path):
    path = tmp_path / "bad.step"
    path.write_text("hello")
    with pytest.raises(ExportError, match="not a readable STEP file"):
        read_step(path)


UNICODE_IDS = ('Säule 1 "Nord" – Ø300', "储罐 TK-1", "col 2 'west' \\ x")
UNICODE_GROUP = 'Struktur – Halle "A" / Achse 1'
UNICODE_SCAN = "Anlage Ü – Nord"


def _unicode_model() -> Model:
    components = tuple(
        Component(
            name,
            "pipe",
            Straight([i, 0, 0], [i + 0.5, 0, 0], 0.05),
            group=UNICODE_GROUP if i else None,
        )
        for i, name in enumerate(UNICODE_IDS)
    )
    return Model(components=components, units="m", name=UNICODE_SCAN)


def _xcaf_names(path) -> list[tuple[str, str]]:
    """(instance name, product name) of every node, read by OpenCASCADE's XCAF reader."""
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDF import TDF_Label, TDF_LabelSequence
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    reader = STEPCAFControl_Reader()
    reader.SetNameMode(True)
    reader.ReadFile(str(path))
    doc = TDocStd_Document(TCollection_ExtendedString("XmlXCAF"))
    reader.Transfer(doc)
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())

    def name(label):
        if not label.IsAttribute(TDataStd_Name.GetID_s()):
            return ""
        attr = TDataStd_Name()
        label.FindAttribute(TDataStd_Name.GetID_s(), attr)
        return attr.Get().ToExtString()

    found = []

    def visit(label):
        components = TDF_LabelSequence()
        tool.GetComponents_s(label, components)
        for i in range(1, components.Length() + 1):
            comp = components.Value(i)
            ref = TDF_Label()
            tool.GetReferredShape_s(comp, ref)
            found.append((name(comp), name(ref)))
            if tool.IsAssembly_s(ref):
                visit(ref)

    roots = TDF_LabelSequence()
    tool.GetFreeShapes(roots)
    for i in range(1, roots.Length() + 1):
        found.append(("", name(roots.Value(i))))
        visit(roots.Value(i))
    return found


def test_unicode_names_survive_the_round_trip(tmp_path):
    path = tmp_path / "unicode.step"
    write_step(prepare(_unicode_model()), path)
    names = _xcaf_names(path)
    products = [product for _, product in names]
    assert products[0] == UNICODE_SCAN
    assert set(UNICODE_IDS) | {UNICODE_GROUP} <= set(products)
    assert all(instance == product for instance, product in names[1:])
    paths = {s.name: s.path for s in read_step(path)}
    assert paths[UNICODE_IDS[1]] == (UNICODE_SCAN, UNICODE_GROUP, UNICODE_IDS[1])
    # The file holds the names with ISO 10303-21 directives (储 U+50A8, 罐 U+7F50), not as
    # raw UTF-8 nor as their Latin-1 reading ("SÃ¤ule", U+00C3).
    text = path.read_bytes().decode("ascii")
    assert "PRODUCT('\\X2\\50A87F50\\X0\\ TK-1'" in text
    assert "00C3" not in text


# Names a strict ISO 10303-21 reader must get as 7-bit ASCII: Latin-1 letters, CJK, a
# character beyond the Basic Multilingual Plane, apostrophes and backslashes, and a name whose
# UTF-8 form is longer than the writer's 72-byte line (it breaks such strings across lines).
ESCAPE_IDS = (
    "Rohrleitung Ø100",
    "Pumpe ü 泵",
    "𝔸 axis",
    "it's a \\ and Ø",
    "泵" * 30 + " P-101",
)
#: The same names as ISO 10303-21 encodes them, written out from the Unicode code points (Ø
#: U+00D8, ü U+00FC, 泵 U+6CF5, 𝔸 U+1D538) and the standard's rules: \X2\ + four hex digits
#: per BMP character + \X0\, \X4\ + eight per character beyond it + \X0\, '' and \\.
ESCAPED = (
    "'Rohrleitung \\X2\\00D8\\X0\\100'",
    "'Pumpe \\X2\\00FC\\X0\\ \\X2\\6CF5\\X0\\'",
    "'\\X4\\0001D538\\X0\\ axis'",
    "'it''s a \\\\ and \\X2\\00D8\\X0\\'",
    "'\\X2\\" + "6CF5" * 30 + "\\X0\\ P-101'",
)


@pytest.fixture(scope="module")
def escaped_step(tmp_path_factory):
    components = tuple(
        Component(name, "pipe", Straight([i, 0, 0], [i + 0.5, 0, 0], 0.05), group="Grüppe")
        for i, name in enumerate(ESCAPE_IDS)
    )
    model = Model(components=components, units="m", name="Anlage Ü")
    path = tmp_path_factory.mktemp("escape") / "Säule Ø.step"
    export_model(model, path)
    return path


def test_the_file_is_pure_ascii_with_iso_10303_21_directives(escaped_step):
    data = escaped_step.read_bytes()
    assert data.isascii()
    text = data.decode("ascii").replace("\n", "")  # line breaks are not significant
    for escaped in ESCAPED:
        assert f"PRODUCT({escaped},{escaped}," in text
    assert "PRODUCT('Gr\\X2\\00FC\\X0\\ppe'" in text
    # The header too: the file's own name and the model's name.
    assert "FILE_NAME('S\\X2\\00E4\\X0\\ule \\X2\\00D8\\X0\\.step'" in text
    assert "'as-built model: Anlage \\X2\\00DC\\X0\\'" in text


def test_the_ocp_reader_decodes_the_exact_names(escaped_step):
    names = _xcaf_names(escaped_step)
    assert sorted(product for _, product in names) == sorted([*ESCAPE_IDS, "Grüppe", "Anlage Ü"])
    assert {s.name for s in read_step(escaped_step)} == set(ESCAPE_IDS)
    assert all(s.path[:2] == ("Anlage Ü", "Grüppe") for s in read_step(escaped_step))


def test_p21_escape_leaves_ascii_alone():
    assert p21_escape("P-101 'a' \\ b") == "P-101 'a' \\ b"
    assert p21_escape("Ø𝔸泵") == "\\X2\\00D8\\X0\\\\X4\\0001D538\\X0\\\\X2\\6CF5\\X0\\"


def test_group_instances_are_named_by_their_group(step_file):
    text = step_file.read_text(encoding="latin-1")
    usages = re.findall(r"NEXT_ASSEMBLY_USAGE_OCCURRENCE\('[^']*','([^']*)'", text)
    assert {"S1", "S2", "frame"} <= set(usages)
    assert not [name for name in usages if name.isdigit()]


def test_every_solid_reads_back_valid(step_file):
    """Every kind of the zoo passes the kernel's validity check after the round trip."""
    invalid = [s.name for s in read_step(step_file) if not s.valid]
    assert invalid == []


def test_equal_tees_read_back_valid(tmp_path):
    """Equal tees (the spool sample's NPS 6 tee, fitted numbers) at several places: the run's
    closed face holds the branch hole, which readers used to rebuild into intersecting wires."""
    from asbuilt.model import Tee

    center = np.array([-0.49980842, 5.00044658, 1.00063383])
    run = np.array([0.143, 0.000016, 0.0])
    tees = []
    for i, shift in enumerate(itertools.product([0.0, 0.1, 0.2, 0.3], [0.0, 0.35])):
        c = center + [*shift, 0.0]
        geometry = Tee(c, c - run, c + run, c + [0.0, 0.0, -0.143], 0.08415, 0.08415, 0.00711)
        tees.append(Component(f"T{i}", "tee", geometry))
    cad = prepare(Model(components=tuple(tees), units="m", name="tees"))
    path = tmp_path / "tees.step"
    write_step(cad, path)
    solids = read_step(path)
    assert [s.name for s in solids if not s.valid] == []
    for part, read in zip(cad.parts, solids):
        assert read.volume == pytest.approx(part.solid.Volume() * 1e9, rel=1e-6)


def _turned_frame(tilt_deg: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A horizontal run axis ``tilt_deg`` off x and two unit vectors across it."""
    tilt = math.radians(tilt_deg)
    axis = np.array([math.cos(tilt), math.sin(tilt), 0.0])
    across = np.cross(axis, [0.0, 0.0, 1.0])
    across /= np.linalg.norm(across)
    return axis, across, np.cross(axis, across)


def _round_trip_invalid(tmp_path, components) -> list[str]:
    """Write ``components`` to STEP, read the file back (OpenCASCADE's XCAF reader) and name the
    solids the kernel's check (``BRepCheck_Analyzer``) finds invalid; volumes must match."""
    cad = prepare(Model(components=tuple(components), units="m", name="turns"))
    path = tmp_path / "turns.step"
    write_step(cad, path)
    solids = read_step(path)
    assert [s.name for s in solids] == [part.id for part in cad.parts]
    for part, read in zip(cad.parts, solids):
        assert read.volume == pytest.approx(part.solid.Volume() * 1e9, rel=1e-3), part.id
    return [s.name for s in solids if not s.valid]


@pytest.mark.parametrize(
    ("run_nps", "branch_nps"),
    [("1/8", "1/8"), ("3/8", "3/8"), ("1", "1"), ("2", "2"), ("4", "4"), ("4", "1/8")],
)
def test_tees_read_back_valid_in_every_orientation(tmp_path, run_nps, branch_nps):
    """STD tees with the run 1 and 5 degrees off x and the branch at 8 turns about it: readers
    rebuilt the run face holding the branch hole into intersecting wires wherever the kernel's
    choice of seam fell along the hole (NPS 4 and smaller, up to half of the turns)."""
    from asbuilt.catalog import fitting_dims, load_catalog
    from asbuilt.model import Tee

    catalog = load_catalog("asme-b36.10m")
    sizes = {size.nominal: size for size in catalog.sizes}
    run, branch = sizes[run_nps], sizes[branch_nps]
    dims = fitting_dims(catalog, run, run.od)
    # each end's own STD wall, as merging builds them
    wall, branch_wall = catalog.wall(run_nps, "STD"), catalog.wall(branch_nps, "STD")
    tees = []
    for tilt in (1.0, 5.0):
        axis, across, up = _turned_frame(tilt)
        for turn in range(0, 360, 45):
            out = math.cos(math.radians(turn)) * up + math.sin(math.radians(turn)) * across
            c = np.array([len(tees) * 0.5, 5.0, 1.0])
            geometry = Tee(
                c,
                c - dims.tee_run * axis,
                c + dims.tee_run * axis,
                c + dims.tee_outlet * out,
                run.od / 2,
                branch.od / 2,
                wall,
                branch_wall,
            )
            tees.append(Component(f"T{tilt}/{turn}", "tee", geometry))
    assert _round_trip_invalid(tmp_path, tees) == []


def test_elbows_and_reducers_read_back_valid_in_every_orientation(tmp_path):
    """NPS 1/2 and 4 STD long-radius elbows, reducing elbows (1/2 x 1/4, 4 x 2) and reducers
    (concentric and eccentric, flat side at each turn) with the run 1 degree off x: valid after
    the round trip too."""
    from asbuilt.catalog import fitting_dims, load_catalog
    from asbuilt.model import Bend, Reducer

    catalog = load_catalog("asme-b36.10m")
    sizes = {size.nominal: size for size in catalog.sizes}
    parts = []
    axis, across, up = _turned_frame(1.0)
    for large, small in (("1/2", "1/4"), ("4", "2")):
        big, little = sizes[large], sizes[small]
        radius = fitting_dims(catalog, big, big.od).bend_radius
        wall = catalog.wall(small, "STD")
        for turn in range(0, 360, 45):
            out = math.cos(math.radians(turn)) * up + math.sin(math.radians(turn)) * across
            c = np.array([len(parts) * 0.5, 5.0, 1.0])
            bend = Bend(c - radius * out, c + radius * axis, c, big.od / 2, wall)
            parts.append(Component(f"E{large}/{turn}", "elbow", bend))
            offset = (big.od - little.od) / 2 * out if turn % 90 else np.zeros(3)
            # the large end's STD wall at the start, the small end's at the end
            reducer = Reducer(
                c,
                c + big.od * axis + offset,
                big.od / 2,
                little.od / 2,
                catalog.wall(large, "STD"),
                offset,
                wall,
            )
            parts.append(Component(f"R{large}/{turn}", "reducer", reducer))
            # a reducing elbow: each end the size and STD wall of its pipe (swept, not revolved)
            c = np.array([len(parts) * 0.5, 5.0, 1.0])
            reducing = Bend(
                c - radius * out,
                c + radius * axis,
                c,
                big.od / 2,
                catalog.wall(large, "STD"),
                little.od / 2,
                wall,
            )
            parts.append(Component(f"RE{large}/{turn}", "elbow", reducing))
    assert _round_trip_invalid(tmp_path, parts) == []


def test_spool_sample_reads_back_valid(tmp_path):
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    model = build_model(load_scan(Path(__file__).parents[2] / "samples" / "spool.json"))
    cad = prepare(model)
    path = tmp_path / "spool.step"
    write_step(cad, path)
    solids = read_step(path)
    assert {part.component.type for part in cad.parts} >= {"pipe", "elbow", "tee", "reducer"}
    assert len(solids) == len(cad.parts)
    assert [s.name for s in solids if not s.valid] == []
    assert all(s.volume > 0 for s in solids)


def _circle_radii_by_centre(path) -> list[tuple[np.ndarray, float]]:
    """(centre (3,) mm, radius mm) of every circular edge in a STEP file, as read back."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.GeomAbs import GeomAbs_Circle
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    reader = STEPControl_Reader()
    assert reader.ReadFile(str(path)) == 1  # IFSelect_RetDone
    reader.TransferRoots()
    found = []
    explorer = TopExp_Explorer(reader.OneShape(), TopAbs_EDGE)
    while explorer.More():
        curve = BRepAdaptor_Curve(TopoDS.Edge_s(explorer.Current()))
        if curve.GetType() == GeomAbs_Circle:
            circle = curve.Circle()
            loc = circle.Location()
            found.append((np.array([loc.X(), loc.Y(), loc.Z()]), circle.Radius()))
        explorer.Next()
    return found


def test_the_bore_runs_on_without_a_step_at_every_weld_of_reducers_and_tees(tmp_path, spool_6x4x2):
    """Read back from STEP, the circles at each weld of the reducer and the tee are the outside
    and one bore (the pipe's = the fitting's): 1.09 mm (6 x 4 reducer's large end) and 3.20 mm
    (tee run) steps when fittings took the thinner of the two pipes' walls throughout."""
    model = spool_6x4x2
    path = tmp_path / "spool.step"
    write_step(prepare(model), path)
    circles = _circle_radii_by_centre(path)
    # ASME B36.10M SCH 40: OD 168.3 / 114.3 / 60.3 mm, wall 7.11 / 6.02 / 3.91 mm
    bores = {"6": 168.3 / 2 - 7.11, "4": 114.3 / 2 - 6.02, "2": 60.3 / 2 - 3.91}
    ods = {"6": 168.3 / 2, "4": 114.3 / 2, "2": 60.3 / 2}
    fittings = [c for c in model.components if c.type in ("reducer", "tee")]
    assert sorted(c.type for c in fittings) == ["reducer", "tee"]
    welds = 0
    for comp in fittings:
        g = comp.geometry
        if comp.type == "reducer":
            ends = [(g.start, "6"), (g.end, "4")]
        else:
            ends = [(g.run_start, "6"), (g.run_end, "6"), (g.branch_end, "2")]
        for point, nps in ends:
            at = sorted(
                {round(r, 6) for c, r in circles if np.linalg.norm(c - point * 1000) < 1e-3}
            )
            assert at == pytest.approx([bores[nps], ods[nps]], abs=1e-5), (comp.id, nps)
            welds += 1
    assert welds == 5
    assert [s.name for s in read_step(path) if not s.valid] == []


def _end_radii(path, point, normal) -> list[float]:
    """Radii (mm) of the closed curves of a STEP file, as read back, that lie in the plane
    through ``point`` (3,) mm across ``normal`` (3,) and round it at a constant distance (circles
    or the B-spline circles of swept faces), equal ones (within 1 um) once, smallest first."""
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_EDGE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    reader = STEPControl_Reader()
    assert reader.ReadFile(str(path)) == 1  # IFSelect_RetDone
    reader.TransferRoots()
    radii = []
    explorer = TopExp_Explorer(reader.OneShape(), TopAbs_EDGE)
    while explorer.More():
        curve = BRepAdaptor_Curve(TopoDS.Edge_s(explorer.Current()))
        params = np.linspace(curve.FirstParameter(), curve.LastParameter(), 64)
        xyz = np.array(
            [[curve.Value(u).X(), curve.Value(u).Y(), curve.Value(u).Z()] for u in params]
        )
        across = np.abs((xyz - point) @ normal)
        distance = np.linalg.norm(xyz - point, axis=1)
        if across.max() < 1e-4 and np.ptp(distance) < 1e-3:
            radii.append(float(distance.mean()))
        explorer.Next()
    merged = []
    for radius in sorted(radii):
        if not merged or radius - merged[-1] > 1e-3:
            merged.append(radius)
    return merged


def test_an_elbow_between_two_sizes_has_each_pipes_circles_at_its_welds(tmp_path, elbow_6x4):
    """Read back from STEP, each weld of an NPS 6 x 4 SCH 40 elbow has exactly two radii, its
    pipe's outside and bore, shared by the pipe and the elbow (it had the NPS 6 OD and the NPS 4
    wall at both ends: 77.04, 78.13 and 84.15 mm at the NPS 6 weld); the spool still fuses into
    one valid solid of the parts' summed volume."""
    model = elbow_6x4
    path = tmp_path / "elbow.step"
    cad = prepare(model)
    write_step(cad, path)
    # ASME B36.10M SCH 40 (catalogs/asme-b36.10m.csv): OD 168.3 / 114.3 mm, wall 7.11 / 6.02 mm
    expected = {"P1": [168.3 / 2 - 7.11, 168.3 / 2], "P2": [114.3 / 2 - 6.02, 114.3 / 2]}
    elbow = model.component("P1-P2").geometry
    for pipe_id, want in expected.items():
        pipe = model.component(pipe_id).geometry
        (point,) = [
            p
            for p in (elbow.start, elbow.end)
            if min(np.linalg.norm(p - pipe.start), np.linalg.norm(p - pipe.end)) < 1e-9
        ]
        at = _end_radii(path, point * 1000, pipe.direction)
        assert at == pytest.approx(want, abs=1e-4), pipe_id
    assert [s.name for s in read_step(path) if not s.valid] == []
    (spool,) = model.spools
    fused = cad.fused_spool(spool.id)
    assert fused.isValid() and len(fused.Solids()) == 1
    total = sum(part.solid.Volume() for part in cad.parts)
    assert fused.Volume() == pytest.approx(total, rel=1e-6)
