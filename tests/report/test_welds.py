"""Butt welds in the take-off (asbuilt.report.welds): one weld wherever two piping components'
ends meet, at the smaller end's size, counted by size with diameter-inches, per spool with its
open ends, and shown in the JSON and HTML reports."""

from __future__ import annotations

import sys
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
import pytest
from report_helpers import OD4, WALL4, known_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "merge"))
from synthetic_pipes import Pipe, report_of  # noqa: E402

from asbuilt.catalog import load_catalog  # noqa: E402
from asbuilt.merge import merge_model  # noqa: E402
from asbuilt.model import Component, Model, Reducer, Spool, Straight  # noqa: E402
from asbuilt.primitives import Cuboid  # noqa: E402
from asbuilt.report.takeoff import take_off  # noqa: E402
from asbuilt.report.welds import piping_ends, summarise_welds, welds_of  # noqa: E402

# ASME B36.10M outside diameters (m) by NPS
OD = {"4": 0.1143, "6": 0.1683, "8": 0.2191}


def _merged(pipes):
    return merge_model(report_of(pipes))


# Spools merging builds from pipes laid out in a plane, with the welds and open ends a pipe
# fitter counts on the drawing: each fitting is welded at every end, an in-line joint is one
# weld, and the spool's free pipe ends are open.
CASES = {
    "elbow": (
        [
            Pipe("P1", (0, 0, 0), (2, 0, 0), OD["6"]),
            Pipe("P2", (2.4, 0.4, 0), (2.4, 2.4, 0), OD["6"]),
        ],
        {"NPS 6": 2},
        2,
    ),
    "tee": (
        [
            Pipe("P1", (0, 0, 0), (1.85, 0, 0), OD["6"]),
            Pipe("P2", (2.15, 0, 0), (4, 0, 0), OD["6"]),
            Pipe("P3", (2, 0.15, 0), (2, 2, 0), OD["6"]),
        ],
        {"NPS 6": 3},
        3,
    ),
    "cross": (
        [
            Pipe("P1", (0, 0, 0), (1.85, 0, 0), OD["6"]),
            Pipe("P2", (2.15, 0, 0), (4, 0, 0), OD["6"]),
            Pipe("P3", (2, 0.15, 0), (2, 2, 0), OD["4"]),
            Pipe("P4", (2, -0.15, 0), (2, -2, 0), OD["4"]),
        ],
        {"NPS 6": 2, "NPS 4": 2},
        4,
    ),
    "reducer": (
        [Pipe("P1", (0, 0, 0), (2, 0, 0), OD["6"]), Pipe("P2", (2.2, 0, 0), (4, 0, 0), OD["4"])],
        {"NPS 6": 1, "NPS 4": 1},
        2,
    ),
    "in line": (
        [Pipe("P1", (0, 0, 0), (2, 0, 0), OD["8"]), Pipe("P2", (2.02, 0, 0), (4, 0, 0), OD["8"])],
        {"NPS 8": 1},
        2,
    ),
}


@pytest.mark.parametrize("case", list(CASES))
def test_welds_of_merged_spools(case):
    pipes, by_size, open_ends = CASES[case]
    model = _merged(pipes)
    t = take_off(model)
    assert {w.size: w.count for w in t.welds} == by_size
    assert t.weld_count == sum(by_size.values())
    inches = sum(float(size.split()[1]) * n for size, n in by_size.items())
    assert t.diameter_inches == pytest.approx(inches)
    assert t.welds_without_nps == 0
    (spool,) = t.spools
    assert (spool.welds, spool.diameter_inches, spool.open_ends) == (
        t.weld_count,
        pytest.approx(inches),
        open_ends,
    )
    # a spool without loops: one weld fewer than it has components
    assert spool.welds == len(spool.components) - 1


def test_the_known_spool_has_two_nps4_welds():
    t = take_off(known_model())
    ((weld),) = t.welds
    assert (weld.size, weld.count, weld.diameter_inches) == ("NPS 4", 2, 8.0)
    assert weld.joints == ("P1/P1-P2", "P1-P2/P2")
    assert weld.od == pytest.approx(OD4)
    (spool,) = t.spools
    assert (spool.welds, spool.open_ends) == (2, 2)


def test_side_by_side_pipes_and_a_touching_support_make_no_weld():
    r = OD4 / 2
    comps = (
        Component("P1", "pipe", Straight([0, 0, 0], [1, 0, 0], r, WALL4), spool="S1"),
        Component("P2", "pipe", Straight([0, 0.3, 0], [1, 0.3, 0], r, WALL4), spool="S2"),
        # a steel support whose face touches P1's end: not a piping component
        Component("C1", "cuboid", Cuboid([1.1, 0, 0], np.eye(3), [0.2, 0.2, 0.2])),
    )
    t = take_off(Model(components=comps, catalog="asme-b36.10m"))
    assert (t.weld_count, t.welds, t.diameter_inches) == (0, (), None)
    assert [(sp.welds, sp.open_ends) for sp in t.spools] == [(0, 2), (0, 2)]


def test_a_size_without_nps_has_no_diameter_inches():
    od = 0.120  # no ASME B36.10M size
    comps = (
        Component("P1", "pipe", Straight([0, 0, 0], [1, 0, 0], od / 2, 0.005), spool="S1"),
        Component("P2", "pipe", Straight([1, 0, 0], [2, 0, 0], od / 2, 0.005), spool="S1"),
        Component("P3", "pipe", Straight([2, 0, 0], [3, 0, 0], OD4 / 2, WALL4), spool="S1"),
    )
    t = take_off(
        Model(components=comps, catalog="asme-b36.10m", spools=(Spool("S1", ("P1", "P2", "P3")),))
    )
    sizes = {w.size: (w.count, w.diameter_inches) for w in t.welds}
    # P2-P3 is welded at the smaller end, 114.3 mm: NPS 4
    assert sizes == {"OD 120.0 mm": (1, None), "NPS 4": (1, 4.0)}
    assert (t.weld_count, t.diameter_inches, t.welds_without_nps) == (2, 4.0, 1)
    assert t.spools[0].diameter_inches == 4.0


def test_a_dn_catalog_gives_nps_from_its_nps_column():
    # EN 10220 lists DN 100 at 114.3 mm with NPS 4 (catalogs/en-10220.csv)
    comps = (
        Component("P1", "pipe", Straight([0, 0, 0], [1, 0, 0], OD4 / 2, 0.0), spool="S1"),
        Component("P2", "pipe", Straight([1, 0, 0], [2, 0, 0], OD4 / 2, 0.0), spool="S1"),
    )
    summary = summarise_welds(Model(components=comps), load_catalog("en-10220"))
    ((weld),) = summary.welds
    assert (weld.nominal, weld.nps) == ("100", 4.0)
    assert summary.diameter_inches == 4.0


def test_a_reducer_is_welded_at_each_end_at_that_ends_size():
    reducer = Reducer([0, 0, 0], [0.14, 0, 0], OD["6"] / 2, OD["4"] / 2)
    ends = piping_ends(Component("R1", "reducer", reducer))
    assert [od for _, od in ends] == pytest.approx([OD["6"], OD["4"]])
    comps = (
        Component("P1", "pipe", Straight([-1, 0, 0], [0, 0, 0], OD["6"] / 2, 0.0071)),
        Component("R1", "reducer", reducer),
        Component("P2", "pipe", Straight([0.14, 0, 0], [1, 0, 0], OD["4"] / 2, WALL4)),
    )
    welds, open_ends = welds_of(comps, load_catalog("asme-b36.10m"))
    assert sorted((w.components, w.nominal) for w in welds) == [
        (("P1", "R1"), "6"),
        (("P2", "R1"), "4"),
    ]
    assert open_ends == {}  # no spool named


def test_samples_spools_have_one_weld_fewer_than_components(plant_model):
    t = take_off(plant_model)
    assert t.spools
    for spool in t.spools:
        assert spool.welds == len(spool.components) - 1
        assert spool.open_ends >= 2


def test_welds_in_the_json_and_html_reports():
    from asbuilt.report._html_takeoff import _takeoff
    from asbuilt.report.data import report_data
    from asbuilt.report.json_report import report_document

    data = report_data(known_model(), generated=datetime(2026, 1, 1, tzinfo=timezone.utc))
    document = report_document(data)
    assert document["takeoff"]["welds"] == [
        {
            "size": "NPS 4",
            "nominal": "4",
            "od": pytest.approx(OD4),
            "nps": 4.0,
            "count": 2,
            "diameter_inches": 8.0,
            "joints": ["P1/P1-P2", "P1-P2/P2"],
        }
    ]
    totals = document["takeoff"]["totals"]
    assert (totals["weld_count"], totals["diameter_inches"], totals["welds_without_nps"]) == (
        2,
        8.0,
        0,
    )
    assert document["takeoff"]["spools"][0]["welds"] == 2
    page = _takeoff(data)
    assert "<h3>Butt welds by size</h3>" in page and '<table class="welds">' in page
    assert '<tr class="total"><td colspan="2">Total</td><td class="num">2</td>' in page
