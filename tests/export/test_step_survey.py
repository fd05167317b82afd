"""STEP at survey coordinates (5,000 km north, 500 km east): solids read back right side out.

Coordinates of ~5e9 mm are beyond what a reader working in millimetres can classify with its
1e-7 precision, so straight pipes and reducers used to come back inside out (negative volume).
Truth: the zoo's volumes from closed-form formulas (tests/cad/cad_zoo.py).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from cad_zoo import expected_volumes, zoo_model  # loaded by conftest.py

from asbuilt.cad import prepare
from asbuilt.export.step import read_step, write_step
from asbuilt.model import Model

#: The shift of the audit's survey scan: UTM-like easting/northing and a height, metres.
SURVEY_OFFSET = np.array([500_000.0, 5_000_000.0, 250.0])
_POSITIONS = ("start", "end", "center", "run_start", "run_end", "branch_end", "point", "outline")


def _shifted(geometry, offset):
    changes = {
        f.name: np.asarray(getattr(geometry, f.name)) + offset
        for f in dataclasses.fields(geometry)
        if f.name in (*_POSITIONS, "vertices")
    }
    return dataclasses.replace(geometry, **changes)


@pytest.fixture(scope="module")
def survey_step(tmp_path_factory):
    zoo = zoo_model()
    components = tuple(
        dataclasses.replace(c, geometry=_shifted(c.geometry, SURVEY_OFFSET)) for c in zoo.components
    )
    model = Model(components=components, units="m", name="survey", spools=zoo.spools)
    path = tmp_path_factory.mktemp("survey") / "survey.step"
    write_step(prepare(model), path)
    return path


def test_volumes_are_positive_and_equal_the_formulas(survey_step):
    expected = expected_volumes()
    solids = {s.name: s for s in read_step(survey_step)}
    assert set(solids) == set(expected)
    for name, volume in expected.items():
        assert solids[name].volume == pytest.approx(volume * 1e9, rel=1e-5), name
        assert solids[name].valid, name


def test_placed_in_the_survey_frame(survey_step):
    """Flattened by a plain reader in metres: every solid valid, right side out, in place."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_Reader
    from OCP.TopAbs import TopAbs_SOLID
    from OCP.TopExp import TopExp_Explorer

    previous = Interface_Static.CVal_s("xstep.cascade.unit")
    Interface_Static.SetCVal_s("xstep.cascade.unit", "M")
    try:
        reader = STEPControl_Reader()
        reader.ReadFile(str(survey_step))
        reader.TransferRoots()
        shape = reader.OneShape()
    finally:
        Interface_Static.SetCVal_s("xstep.cascade.unit", previous)
    explorer = TopExp_Explorer(shape, TopAbs_SOLID)
    volumes = []
    while explorer.More():
        solid = explorer.Current()
        assert BRepCheck_Analyzer(solid).IsValid()
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(solid, props)
        volumes.append(props.Mass())
        explorer.Next()
    assert len(volumes) == len(expected_volumes())
    assert sum(volumes) == pytest.approx(sum(expected_volumes().values()), rel=1e-5)
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    low = np.array(box.Get()[:3])
    # The zoo spans x 0..10 m, y -1..2 m, z -0.1..3 m about its origin: its box starts near the offset.
    assert np.all(np.abs(low - SURVEY_OFFSET) < 10.0)
