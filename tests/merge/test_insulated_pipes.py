"""Insulated pipes: merging models the pipe inside its insulation (asbuilt.model.bare_cylinder)."""

from __future__ import annotations

import numpy as np
import pytest
from synthetic_pipes import Pipe, box_fit, report_of

from asbuilt.errors import FitError
from asbuilt.merge import merge_model
from asbuilt.model import model_from_fits

# ASME B36.10M outside diameters (independent of the catalog files): NPS 4 and NPS 8.
NPS4, NPS8 = 0.1143, 0.2191


def by_id(model):
    return {c.id: c for c in model.components}


@pytest.mark.parametrize(
    ("pipe_od", "thickness", "nominal"),
    [(NPS4, 0.05, "4"), (NPS4, 0.025, "4"), (NPS8, 0.1, "8"), (0.0603, 0.04, "2")],
)
def test_an_insulated_pipe_snaps_at_the_pipe_inside(pipe_od, thickness, nominal):
    cladding = pipe_od + 2 * thickness + 0.0008  # a fit a little off, as fits are
    pipe = Pipe("P1", (0, 0, 0), (2, 0, 0), cladding, insulation=thickness)
    comp = by_id(merge_model(report_of([pipe])))["P1"]
    assert comp.nominal == nominal
    assert comp.insulation == thickness
    assert comp.snap["od_fit"] == pytest.approx(cladding - 2 * thickness)
    assert f"fitted on {thickness * 1000:g} mm of insulation" in comp.snap["reason"]


def test_without_the_thickness_the_cladding_is_snapped():
    # the case the field exists for: a 4" pipe under 52.4 mm of lagging fits NPS 8
    pipe = Pipe("P1", (0, 0, 0), (2, 0, 0), NPS8 + 0.0005)
    comp = by_id(merge_model(report_of([pipe])))["P1"]
    assert (comp.nominal, comp.insulation) == ("8", 0.0)


def test_fittings_carry_the_thickest_insulation_of_their_pipes():
    clad = NPS4 + 0.1
    pipes = [
        Pipe("P1", (0, 0, 0), (1.8, 0, 0), clad, insulation=0.05),
        Pipe("P2", (2, 0.2, 0), (2, 2, 0), NPS4 + 0.06, insulation=0.03),
    ]
    model = merge_model(report_of(pipes))
    comps = by_id(model)
    assert [c.type for c in model.components] == ["pipe", "elbow", "pipe"]
    assert comps["P1"].insulation == 0.05 and comps["P2"].insulation == 0.03
    elbow = next(c for c in model.components if c.type == "elbow")
    assert elbow.insulation == 0.05
    assert elbow.nominal == "4"
    assert elbow.geometry.outer_radius == pytest.approx(NPS4 / 2)


def test_a_bare_pipe_joined_to_an_insulated_one_stays_bare():
    pipes = [
        Pipe("P1", (0, 0, 0), (1.8, 0, 0), NPS4 + 0.1, insulation=0.05),
        Pipe("P2", (2, 0.2, 0), (2, 2, 0), NPS4),
    ]
    comps = by_id(merge_model(report_of(pipes)))
    assert comps["P1"].nominal == comps["P2"].nominal == "4"
    assert comps["P2"].insulation == 0.0


def test_an_insulated_tank_is_modelled_inside_its_insulation():
    # 2 m across: no pipe size, kept as a cylinder
    tank = Pipe("T1", (0, 0, 0), (0, 0, 4), 2.1, label="vertical tank", insulation=0.05)
    comp = by_id(merge_model(report_of([tank])))["T1"]
    assert comp.type == "cylinder"
    assert comp.geometry.radius == pytest.approx(1.0)
    assert comp.insulation == 0.05
    assert comp.fit.primitive.radius == pytest.approx(1.05)  # the fit keeps what was measured


def test_the_unmerged_model_is_inside_the_insulation_too():
    report = report_of([Pipe("P1", (0, 0, 0), (2, 0, 0), NPS4 + 0.1, insulation=0.05)])
    comp = model_from_fits(report).components[0]
    assert comp.geometry.radius == pytest.approx(NPS4 / 2)
    assert comp.insulation == 0.05


@pytest.mark.parametrize("thickness", [0.06, 0.0575])
def test_insulation_not_thinner_than_the_fit_is_refused(thickness):
    report = report_of([Pipe("P1", (0, 0, 0), (2, 0, 0), 0.115, insulation=thickness)])
    with pytest.raises(FitError) as err:
        merge_model(report)
    assert err.value.where == "objects[0] (P1).insulation"
    assert "no pipe is left inside" in str(err.value)


def test_other_kinds_carry_no_insulation():
    obj, fit = box_fit()
    model = merge_model(report_of([Pipe("P1", (0, 0, 0), (2, 0, 0), NPS4)], extra=[(obj, fit)]))
    assert all(c.insulation == 0.0 for c in model.components)
    assert np.isfinite([c.insulation for c in model.components]).all()
