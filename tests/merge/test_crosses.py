"""Crosses (merge.crosses): four pipe ends meeting at one point, two opposite pairs on one line.

ASME B16.9 tabulates crosses with tees, so a cross has the tee's C (run) and M (outlet) of its
run and outlet sizes: NPS 4 straight C = M = 105 mm (catalogs/asme-b16.9.csv), NPS 6 x 4
C 143, M 130 mm (Table 8, catalogs/asme-b16.9-tees.toml). Simulated pipes (synthetic_pipes):
the run along x split at x = 2, the outlets along y, every end 0.15 m short of the centre.
"""

from __future__ import annotations

import numpy as np
import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.merge.spool import connection_mismatches
from asbuilt.model import Cross
from asbuilt.rules import check_model

NPS = {"2": 0.0603, "4": 0.1143, "6": 0.1683}


def _cross_pipes(run_od, outlet_od, outlet_x=(2.0, 2.0), outlet_od2=None, run_y=(0.0, 0.0)):
    """Run P1, P2 along x with their ends 0.15 m from (2, 0, 0) (``run_y`` moves each sideways),
    outlets P3 (+y) and P4 (-y) at x = ``outlet_x``."""
    return [
        Pipe("P1", (0, run_y[0], 0), (1.85, run_y[0], 0), run_od),
        Pipe("P2", (2.15, run_y[1], 0), (4, run_y[1], 0), run_od),
        Pipe("P3", (outlet_x[0], 0.15, 0), (outlet_x[0], 2, 0), outlet_od),
        Pipe("P4", (outlet_x[1], -0.15, 0), (outlet_x[1], -2, 0), outlet_od2 or outlet_od),
    ]


def _fittings(model):
    return [c for c in model.components if c.type not in ("pipe",)]


def _notes(model, pipe):
    return next(c for c in model.components if c.id == pipe).snap.get("merge_notes") or []


CASES = [
    pytest.param("4", "4", 0.105, 0.105, id="equal-nps4"),
    pytest.param("6", "4", 0.143, 0.130, id="reducing-6x4"),
]
LINKS = [
    pytest.param([], id="unlinked"),
    pytest.param([("P1", "P2"), ("P3", "P4")], id="opposite-linked"),
    pytest.param([("P1", "P3"), ("P2", "P3"), ("P1", "P4")], id="star-linked"),
]


@pytest.mark.parametrize("links", LINKS)
@pytest.mark.parametrize(("run", "outlet", "c", "m"), CASES)
def test_four_pipes_at_one_point_make_one_cross_of_the_tees_c_and_m(run, outlet, c, m, links):
    model = merge_model(report_of(_cross_pipes(NPS[run], NPS[outlet]), links=links))
    (cross,) = _fittings(model)
    g = cross.geometry
    assert cross.type == "cross" and isinstance(g, Cross)
    connects = cross.snap["connects"]
    # the run is the larger pair; of equal pairs, either
    pairs = [connects[:2], connects[2:]] if run != outlet else sorted([connects[:2], connects[2:]])
    assert pairs == [["P1", "P2"], ["P3", "P4"]] and cross.nominal == run
    assert cross.snap["standard"] is True
    # the run is the larger pair, C either side of the centre; both outlets M, on one line
    assert g.outer_radius == pytest.approx(NPS[run] / 2)
    assert g.branch_outer_radius == pytest.approx(NPS[outlet] / 2)
    assert np.linalg.norm(g.run_start - g.center) == pytest.approx(c, abs=1e-6)
    assert np.linalg.norm(g.run_end - g.center) == pytest.approx(c, abs=1e-6)
    assert np.linalg.norm(g.branch_start - g.center) == pytest.approx(m, abs=1e-6)
    assert np.linalg.norm(g.branch_end - g.center) == pytest.approx(m, abs=1e-6)
    run_dir = g.run_end - g.run_start
    assert abs(float(run_dir @ (g.branch_end - g.branch_start))) < 1e-9
    # every pipe meets one of its four ports, end point and direction
    connections, bad = connection_mismatches(model.components)
    assert connections == 4 and not bad
    assert not [c for c in model.components if c.snap.get("loose_ends")]
    assert not [f for f in check_model(model) if f.code in ("AB302", "AB304", "AB501", "AB105")]


@pytest.mark.parametrize(("run", "outlet"), [("4", "4"), ("6", "4")])
def test_a_cross_has_the_dimensions_of_the_tee_of_its_pair(run, outlet):
    """The cross and the tee merging builds from the same pipes less P4 share C and M."""
    pipes = _cross_pipes(NPS[run], NPS[outlet])
    (cross,) = _fittings(merge_model(report_of(pipes)))
    (tee,) = _fittings(merge_model(report_of(pipes[:3])))
    assert tee.type == "tee"
    ct, tt = cross.geometry, tee.geometry
    assert np.linalg.norm(ct.run_end - ct.center) == pytest.approx(
        np.linalg.norm(tt.run_end - tt.center), abs=1e-9
    )
    assert np.linalg.norm(ct.branch_start - ct.center) == pytest.approx(
        np.linalg.norm(tt.branch_end - tt.center), abs=1e-9
    )
    assert cross.snap["dimensions"] == tee.snap["dimensions"]


def test_a_pipe_running_through_is_split_by_the_cross():
    pipes = [Pipe("P1", (0, 0, 0), (4, 0, 0), NPS["4"]), *_cross_pipes(NPS["4"], NPS["4"])[2:]]
    model = merge_model(report_of(pipes))
    (cross,) = _fittings(model)
    assert cross.type == "cross" and cross.snap["connects"] == ["P1.1", "P1.2", "P3", "P4"]
    assert connection_mismatches(model.components) == (4, [])


def test_a_run_of_two_sizes_is_a_cross_of_the_larger_and_a_reducer():
    pipes = _cross_pipes(NPS["6"], NPS["4"])
    pipes[1] = Pipe("P2", (2.15, 0, 0), (4, 0, 0), NPS["4"])
    model = merge_model(report_of(pipes))
    kinds = sorted(c.type for c in _fittings(model))
    assert kinds == ["cross", "reducer"]
    (cross,) = [c for c in _fittings(model) if c.type == "cross"]
    assert cross.nominal == "6" and cross.geometry.outer_radius == pytest.approx(NPS["6"] / 2)
    assert connection_mismatches(model.components)[1] == []


@pytest.mark.parametrize("links", [[], [("P3", "P4"), ("P1", "P2")]], ids=["unlinked", "linked"])
def test_outlets_off_one_line_keep_the_tee_and_say_why(links):
    """P4 60 mm along the run from P3's line (the NPS 4 skew tolerance is 29 mm)."""
    model = merge_model(
        report_of(_cross_pipes(NPS["4"], NPS["4"], outlet_x=(2.0, 2.06)), links=links)
    )
    (tee,) = _fittings(model)
    assert tee.type == "tee" and tee.snap["connects"] == ["P1", "P2", "P3"]
    (note,) = [n for n in _notes(model, "P4") if "cross" in n]
    assert "their axes are 60 mm apart" in note and "within 29 mm" in note
    assert "the tee P1-P2-P3 is kept and P4 is not joined there" in note
    found = [f for f in check_model(model) if f.code in ("AB302", "AB304")]
    assert len(found) == 1 and "P4" in found[0].objects


def test_a_run_pair_off_one_line_is_no_cross():
    """P2 60 mm to the side of P1's line: the outlets P3, P4 are the straight pair."""
    model = merge_model(report_of(_cross_pipes(NPS["4"], NPS["4"], run_y=(0.0, 0.06))))
    (tee,) = _fittings(model)
    assert tee.type == "tee" and tee.snap["connects"][:2] == ["P3", "P4"]
    loose = tee.snap["connects"][2]
    other = ({"P1", "P2"} - {loose}).pop()
    assert any("60 mm apart" in n and "no cross is built" in n for n in _notes(model, other))


def test_outlets_of_two_sizes_make_a_tee_of_the_larger_and_say_why():
    pipes = _cross_pipes(NPS["6"], NPS["4"], outlet_od2=0.0889)  # P4 NPS 3
    model = merge_model(report_of(pipes))
    (tee,) = _fittings(model)
    assert tee.type == "tee" and tee.snap["connects"] == ["P1", "P2", "P3"]
    (note,) = [n for n in _notes(model, "P4") if "cross" in n]
    assert "outlets P3 and P4 are of different sizes (OD 114.3 and 88.9 mm" in note
    assert "the tee P1-P2-P3 is built and P4 is not joined there" in note


def test_a_reducing_cross_of_a_pair_b16_9_does_not_make_is_ab105():
    """NPS 6 reduces on the outlet to 5 down to 2 1/2 only: a 6 x 2 cross is not made."""
    model = merge_model(report_of(_cross_pipes(NPS["6"], NPS["2"])))
    (cross,) = _fittings(model)
    assert cross.type == "cross"
    (f,) = [f for f in check_model(model) if f.code == "AB105"]
    assert f.objects[0] == cross.id and set(f.objects[1:]) == {"P1", "P2", "P3", "P4"}
    assert f.message.startswith(f"the cross {cross.id} joins an NPS 6 run to two NPS 2 outlets")
    assert "a reducing cross" in f.message
