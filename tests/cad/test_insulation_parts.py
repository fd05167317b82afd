"""Insulation parts in the CAD model: a jacket around each insulated component, no overlap."""

from __future__ import annotations

import dataclasses
import math

import pytest
from cad_zoo import R3, R4, frustum, zoo_components

from asbuilt.cad import prepare
from asbuilt.cad.colours import KIND_COLOURS
from asbuilt.model import Model, Spool

T = 0.05  # 50 mm of lagging


def insulated_model() -> Model:
    components = []
    for comp in zoo_components():
        if comp.type in ("pipe", "elbow", "tee", "reducer", "cylinder"):
            comp = dataclasses.replace(comp, insulation=T)
        components.append(comp)
    return Model(
        components=tuple(components),
        name="lagged",
        spools=(Spool("S1", ("P1", "E1", "P2"), 2.0),),
    )


@pytest.fixture(scope="module")
def cad():
    return prepare(insulated_model(), colour_by_status=False)


def test_each_insulated_component_is_followed_by_its_jacket(cad):
    ids = [part.id for part in cad.parts]
    assert ids[:6] == ["P1", "P1 insulation", "E1", "E1 insulation", "P2", "P2 insulation"]
    jackets = [part for part in cad.parts if part.insulation]
    assert [p.component.id for p in jackets] == ["P1", "E1", "P2", "T1", "R1", "CY"]
    for part in jackets:
        assert part.kind == "insulation"
        assert part.colour == KIND_COLOURS["insulation"] and part.colour[3] < 1
        assert part.group == next(p.group for p in cad.parts if p.id == part.component.id)


@pytest.mark.parametrize(
    ("part_id", "expected"),
    [
        # hand formulas: an annulus of the cladding around the pipe's outside, times its length
        ("P1 insulation", math.pi * ((R4 + T) ** 2 - R4**2) * 1.0),
        # Pappus: the annulus swept along the quarter circle of radius 0.2 m
        ("E1 insulation", math.pi * ((R4 + T) ** 2 - R4**2) * 0.2 * math.pi / 2),
        ("CY insulation", math.pi * ((0.15 + T) ** 2 - 0.15**2) * 3.0),
        ("R1 insulation", frustum(R4 + T, R3 + T, 0.15) - frustum(R4, R3, 0.15)),
    ],
)
def test_jacket_volumes_match_hand_formulas(cad, part_id, expected):
    part = next(p for p in cad.parts if p.id == part_id)
    assert part.solid.Volume() == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("component_id", ["P1", "E1", "T1", "R1", "CY"])
def test_the_jacket_wraps_the_component_without_overlapping_it(cad, component_id):
    own = next(p for p in cad.parts if p.id == component_id)
    jacket = next(p for p in cad.parts if p.id == f"{component_id} insulation")
    common = own.solid.intersect(jacket.solid).Volume()
    assert common < 1e-6 * jacket.solid.Volume()
    # together they fill the envelope: a solid of the grown outside
    union = own.solid.fuse(jacket.solid).Volume()
    assert union == pytest.approx(own.solid.Volume() + jacket.solid.Volume(), rel=1e-4)


def test_a_spool_fuses_its_components_not_their_insulation(cad):
    bare = prepare(dataclasses.replace(insulated_model(), components=zoo_components()))
    assert cad.fused_spool("S1").Volume() == pytest.approx(bare.fused_spool("S1").Volume())


def test_assembly_and_meshes_hold_the_jackets(cad):
    leaves = [leaf.name for leaf in cad.assembly().children[0].children]
    assert leaves == ["P1", "P1 insulation", "E1", "E1 insulation", "P2", "P2 insulation"]
    meshes_only = prepare(insulated_model(), solids=False)
    for solid_part, mesh_part in zip(cad.parts, meshes_only.parts):
        assert solid_part.id == mesh_part.id
        volume = meshes_only.mesh(mesh_part).volume
        assert volume == pytest.approx(solid_part.solid.Volume(), rel=0.02)


def test_a_jacket_name_taken_by_a_component_gets_a_suffix():
    comps = zoo_components()
    comps[0] = dataclasses.replace(comps[0], insulation=T)
    comps[-1] = dataclasses.replace(comps[-1], id="P1 insulation")
    cad = prepare(Model(components=tuple(comps)), solids=False)
    assert [p.id for p in cad.parts if p.insulation] == ["P1 insulation (2)"]
