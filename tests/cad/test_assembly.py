"""The CAD model: tree, names, colours by status, fused spools, progress, errors."""

from __future__ import annotations

import pytest
from cad_zoo import R4, W4, expected_volumes, zoo_model

from asbuilt.cad import build_assembly, fused_spool_solid, prepare
from asbuilt.cad.colours import KIND_COLOURS, STATUS_COLOURS
from asbuilt.errors import SolidBuildError
from asbuilt.model import Bend, Component, Model, Spool, Straight
from asbuilt.primitives import Plane, Sphere


def test_parts_keep_the_model_order_and_colours_follow_status(zoo_cad):
    ids = [part.id for part in zoo_cad.parts]
    assert ids == [c.id for c in zoo_cad.model.components]
    by_id = {part.id: part for part in zoo_cad.parts}
    assert by_id["C1"].colour == STATUS_COLOURS["error"] and by_id["C1"].status == "error"
    assert by_id["SP"].colour == STATUS_COLOURS["warning"]
    assert by_id["H"].colour == KIND_COLOURS["hull"] and by_id["H"].status == "info"
    assert by_id["P1"].colour == KIND_COLOURS["pipe"]


def test_colour_by_status_can_be_turned_off(zoo):
    cad = prepare(zoo, colour_by_status=False)
    assert {part.id: part.colour for part in cad.parts}["C1"] == KIND_COLOURS["cuboid"]


def test_groups_spools_first_then_scan_groups_then_ungrouped(zoo_cad):
    groups = zoo_cad.groups()
    assert list(groups) == ["S1", "S2", "frame", None]
    assert [p.id for p in groups["S1"]] == ["P1", "E1", "P2"]
    assert [p.id for p in groups[None]] == ["SP", "PL", "H"]


def test_assembly_tree_is_scan_group_object(zoo_cad):
    assembly = zoo_cad.assembly()
    assert assembly.name == "zoo"
    assert [child.name for child in assembly.children] == ["S1", "S2", "frame", "SP", "PL", "H"]
    spool = assembly.children[0]
    assert [leaf.name for leaf in spool.children] == ["P1", "E1", "P2"]
    assert zoo_cad.assembly() is assembly  # built once


@pytest.mark.parametrize(
    ("model_name", "sphere_group", "root", "groups"),
    [
        # A spool named like an ungrouped object.
        ("plant", None, "plant", {"S1": "S1 (group)"}),
        # A group named like one of its own members (samples/structural-bay.json has B2 in B2).
        ("plant", "S1", "plant", {"S1": "S1 (group)"}),
        # The scan named like a group and an object.
        ("S1", None, "S1 (scan)", {"S1": "S1 (group)"}),
    ],
)
def test_clashing_names_get_distinct_node_names(model_name, sphere_group, root, groups):
    model = Model(
        components=(
            Component("S1", "sphere", Sphere([0, 0, 0], 1.0), group=sphere_group),
            Component("P1", "pipe", Straight([3, 0, 0], [4, 0, 0], 0.05), spool="S1"),
        ),
        name=model_name,
    )
    cad = prepare(model)
    assert cad.name == root
    assert cad.group_node_names() == groups
    assembly = cad.assembly()
    assert assembly.name == root
    leaves = {name.split("/")[-1] for name in assembly.objects}
    assert {"S1", "P1"} <= leaves


def test_build_assembly_one_call(zoo):
    assembly = build_assembly(zoo)
    assert {"S1/P1", "S1/E1", "S2/T1", "frame/C1", "SP", "H"} <= set(assembly.objects)
    assert {name.split("/")[-1] for name in assembly.objects} >= {c.id for c in zoo.components}


def test_fused_spool_is_one_valid_solid_of_the_summed_volume(zoo):
    solid = fused_spool_solid(zoo, "S1")
    assert solid.isValid()
    volumes = expected_volumes()
    # Pipe, elbow and pipe only touch at their end faces: no overlap.
    assert solid.Volume() == pytest.approx(volumes["P1"] + volumes["E1"] + volumes["P2"], rel=1e-6)


def test_spool_with_a_gap_does_not_fuse_into_one_solid():
    model = Model(
        components=(
            Component("A", "pipe", Straight([0, 0, 0], [1, 0, 0], R4, W4), spool="G"),
            Component("B", "pipe", Straight([1.5, 0, 0], [2, 0, 0], R4, W4), spool="G"),
        ),
        spools=(Spool("G", ("A", "B")),),
    )
    with pytest.raises(SolidBuildError, match=r"^spool G: its 2 components do not fuse"):
        fused_spool_solid(model, "G")
    with pytest.raises(SolidBuildError, match="no components belong"):
        fused_spool_solid(model, "missing")


def test_progress_reports_every_solid(zoo):
    calls = []
    prepare(zoo, progress=lambda done, total: calls.append((done, total)))
    n = len(zoo.components)
    assert calls == [(i, n) for i in range(1, n + 1)]


def test_first_bad_object_is_named_with_the_scan_file():
    bad = Component("F9", "plane", Plane([0, 0, 0], [0, 0, 1]))
    model = zoo_model().replace(components=(*zoo_model().components, bad))
    with pytest.raises(SolidBuildError, match=r"^object F9: .*no outline"):
        prepare(model)


def test_duplicate_ids_are_refused():
    pipe = Component("P", "pipe", Straight([0, 0, 0], [1, 0, 0], 0.05))
    with pytest.raises(SolidBuildError, match="object P: two components share this id"):
        prepare(Model(components=(pipe, pipe)))


def test_plate_thickness_reaches_plates(zoo):
    thick = prepare(zoo, plate_thickness=0.05)
    plate = {p.id: p for p in thick.parts}["PL"]
    assert plate.solid.Volume() == pytest.approx(4.0 * 0.05)
    assert thick.mesh(plate).volume == pytest.approx(4.0 * 0.05)


def test_the_sample_spool_fuses_into_one_valid_solid():
    from pathlib import Path

    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    root = Path(__file__).resolve().parents[2]
    model = build_model(load_scan(root / "samples" / "spool.json"), check=False)
    cad = prepare(model)
    (spool,) = model.spools
    solid = cad.fused_spool(spool.id)
    assert solid.isValid()
    members = [p for p in cad.parts if p.group == spool.id]
    assert len(members) == len(spool.components)
    # Fittings meet pipes at end faces only, so the fused volume is the sum of the parts'.
    assert solid.Volume() == pytest.approx(sum(p.solid.Volume() for p in members), rel=1e-4)


def test_meshes_only_builds_no_solid_but_the_tees_and_gives_the_same_meshes(zoo, zoo_cad):
    """Mesh formats need no B-rep solids; the tee's mesh is tessellated from its solid."""
    import numpy as np

    meshes_only = prepare(zoo, solids=False)
    for part, full in zip(meshes_only.parts, zoo_cad.parts):
        assert (part.solid is None) == (part.component.type != "tee"), part.id
        assert (part.colour, part.status, part.group) == (full.colour, full.status, full.group)
        mesh, reference = meshes_only.mesh(part), zoo_cad.mesh(full)
        assert np.array_equal(mesh.vertices, reference.vertices), part.id
        assert np.array_equal(mesh.faces, reference.faces), part.id
    with pytest.raises(ValueError, match="meshes only"):
        meshes_only.assembly()
    with pytest.raises(ValueError, match="meshes only"):
        meshes_only.fused_spool("S1")


def _open_hull():
    from cad_zoo import hull_geometry

    hull = hull_geometry()
    return type(hull)(hull.vertices, hull.faces[1:])  # one triangle missing: not closed


@pytest.mark.parametrize(
    ("component", "message"),
    [
        (Component("F9", "plane", Plane([0, 0, 0], [0, 0, 1])), "no outline"),
        (Component("E9", "elbow", Bend([1, 0, 0], [-1, 0, 0], [0, 0, 0], 0.1)), "collinear"),
        (Component("E8", "elbow", Bend([1, 0, 0], [0, 1, 0], [0, 0, 0], 1.5)), "bend radius"),
        (Component("H9", "hull", None), "closed shell|validity check"),
    ],
    ids=["plate", "collinear bend", "tight bend", "open hull"],
)
def test_meshes_only_refuses_what_the_solids_refuse(component, message):
    """One line naming the object, with or without building the solids; the same line but for
    the open hull (the kernel sews it into a solid its validity check refuses)."""
    if component.geometry is None:
        component = Component(component.id, component.type, _open_hull())
    model = Model(components=(component,))
    errors = []
    for solids in (True, False):
        with pytest.raises(SolidBuildError, match=rf"^object {component.id}: .*{message}") as info:
            prepare(model, solids=solids)
        errors.append(str(info.value))
    assert errors[0] == errors[1] or component.type == "hull"
