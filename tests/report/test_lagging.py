"""Insulation in the take-off (asbuilt.report.lagging): insulated centreline length, cladding
area and insulation volume by thickness and size, per spool, and in the CSV, JSON and HTML
reports. Truth values are the hand formulas of a cylinder shell, a torus section and a cone
frustum, written independently of the module's Pappus form where one exists."""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
from datetime import datetime, timezone

import numpy as np
import pytest
from report_helpers import LR4, OD4, ROOT, WALL4, known_model

from asbuilt.model import Bend, Component, Cross, Model, Reducer, Spool, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder
from asbuilt.report.lagging import insulated_part, summarise_insulation
from asbuilt.report.takeoff import take_off

OD6 = 0.1683  # ASME B36.10M NPS 6
T = 0.05  # 50 mm of lagging
STAMP = datetime(2026, 1, 1, tzinfo=timezone.utc)


def _part(geometry, t=T, type_="pipe"):
    return insulated_part(Component("X", type_, geometry, insulation=t))


def test_a_straight_is_a_cylindrical_shell():
    r, length = OD4 / 2, 2.0
    part = _part(Straight([0, 0, 0], [length, 0, 0], r, WALL4))
    assert part.thickness == T and part.length == pytest.approx(length)
    assert part.area == pytest.approx(2 * math.pi * (r + T) * length)
    assert part.volume == pytest.approx(math.pi * ((r + T) ** 2 - r**2) * length)
    # 114.3 mm pipe under 50 mm: cladding OD 214.3 mm, 0.6732 m2 and 0.02581 m3 per metre
    assert part.area / length == pytest.approx(0.67324, abs=1e-5)
    assert part.volume / length == pytest.approx(0.025809, abs=1e-6)


def test_a_90_degree_elbow_is_a_quarter_torus_shell():
    r = OD4 / 2
    bend = Bend([LR4, 0, 0], [0, LR4, 0], [0, 0, 0], r, WALL4)
    part = _part(bend, type_="elbow")
    # a whole torus: surface 4 pi^2 R a, volume 2 pi^2 R a^2; a quarter of each
    assert part.length == pytest.approx(LR4 * math.pi / 2)
    assert part.area == pytest.approx(4 * math.pi**2 * LR4 * (r + T) / 4)
    assert part.volume == pytest.approx(2 * math.pi**2 * LR4 * ((r + T) ** 2 - r**2) / 4)


def test_a_reducing_elbow_has_its_mean_radius():
    r1, r2 = OD6 / 2, OD4 / 2
    bend = Bend([0.229, 0, 0], [0, 0.229, 0], [0, 0, 0], r1, outer_radius_end=r2)
    part = _part(bend, type_="elbow")
    rm = (r1 + r2) / 2
    # the section's area pi (2 r t + t^2) is linear in r, which is linear in the angle
    assert part.volume == pytest.approx(math.pi * (2 * rm * T + T * T) * 0.229 * math.pi / 2)
    assert part.area == pytest.approx(2 * math.pi * (rm + T) * 0.229 * math.pi / 2)


def _frustum(a, b, h):
    """Cone frustum volume from its end areas: h/3 (A1 + A2 + sqrt(A1 A2))."""
    a1, a2 = math.pi * a * a, math.pi * b * b
    return h / 3 * (a1 + a2 + math.sqrt(a1 * a2))


def test_a_reducer_is_a_frustum_shell():
    r1, r2, h = OD6 / 2, OD4 / 2, 0.140  # B16.9 NPS 6 x 4: H 140 mm
    part = _part(Reducer([0, 0, 0], [h, 0, 0], r1, r2, 0.007), type_="reducer")
    big1, big2 = r1 + T, r2 + T
    slant = math.sqrt(h * h + (big1 - big2) ** 2)
    assert part.length == pytest.approx(h)
    assert part.area == pytest.approx(math.pi * (big1 + big2) * slant)
    assert part.volume == pytest.approx(_frustum(big1, big2, h) - _frustum(r1, r2, h))
    # an eccentric one of the same sizes has the same volume (Cavalieri)
    offset = [0, r1 - r2, 0]
    eccentric = _part(Reducer([0, 0, 0], [h, r1 - r2, 0], r1, r2, 0.007, offset), type_="reducer")
    assert eccentric.volume == pytest.approx(part.volume)
    assert eccentric.length == pytest.approx(h)


def test_a_tee_counts_its_run_and_the_outlet_beyond_the_run_cladding():
    r, c, t = OD6 / 2, 0.143, 0.01  # B16.9 NPS 6 tee: C = M = 143 mm
    rb = OD4 / 2
    tee = Tee([0, 0, 0], [-c, 0, 0], [c, 0, 0], [0, c, 0], r, rb)
    part = _part(tee, t, "tee")
    beyond = c - (r + t)
    assert part.length == pytest.approx(2 * c + beyond)
    assert part.area == pytest.approx(
        2 * math.pi * (r + t) * 2 * c + 2 * math.pi * (rb + t) * beyond
    )
    assert part.volume == pytest.approx(
        math.pi * ((r + t) ** 2 - r * r) * 2 * c + math.pi * ((rb + t) ** 2 - rb * rb) * beyond
    )
    # a cross has two such outlets
    cross = Cross([0, 0, 0], [-c, 0, 0], [c, 0, 0], [0, -c, 0], [0, c, 0], r, rb)
    assert _part(cross, t, "cross").length == pytest.approx(2 * c + 2 * beyond)
    # 50 mm on an NPS 4 tee (C 105 mm): the outlet ends inside the run's cladding
    small = Tee([0, 0, 0], [-0.105, 0, 0], [0.105, 0, 0], [0, 0.105, 0], OD4 / 2, OD4 / 2)
    assert _part(small, T, "tee").length == pytest.approx(0.21)


def test_a_lateral_outlet_leaves_the_run_cladding_further_out():
    r, t, reach = OD6 / 2, 0.02, 0.4
    way = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)  # 45 degrees
    lateral = Tee([0, 0, 0], [-0.3, 0, 0], [0.3, 0, 0], reach * way, r, r)
    beyond = reach - (r + t) / math.sin(math.radians(45))
    assert _part(lateral, t, "tee").length == pytest.approx(0.6 + beyond)


def test_a_tank_counts_its_side_only():
    tank = Cylinder([0, 0, 1.5], [0, 0, 1], 1.0, 3.0)
    part = _part(tank, 0.1, "cylinder")
    assert part.area == pytest.approx(2 * math.pi * 1.1 * 3.0)
    assert part.volume == pytest.approx(math.pi * (1.1**2 - 1.0) * 3.0)


def test_bare_and_unwrappable_components_have_no_insulation():
    assert _part(Straight([0, 0, 0], [1, 0, 0], 0.05), 0.0) is None
    box = Cuboid([0, 0, 0], np.eye(3), [1, 1, 1])
    assert insulated_part(Component("B", "cuboid", box)) is None
    summary = summarise_insulation(known_model())
    assert (summary.by_size, summary.length, summary.area, summary.volume) == ((), 0, 0, 0)
    assert summary.spool_length == {"SP-1": 0.0}


def _lagged(model: Model, thickness: dict[str, float]) -> Model:
    """The model with the given components insulated (id -> thickness, metres)."""
    components = tuple(
        dataclasses.replace(c, insulation=thickness.get(c.id, 0.0)) for c in model.components
    )
    return dataclasses.replace(model, components=components)


def _known_lagged() -> Model:
    # the known spool under 50 mm, and the tank under 100 mm
    return _lagged(known_model(), {"P1": T, "P1-P2": T, "P2": T, "TK1": 0.1})


def test_the_takeoff_groups_by_thickness_and_size():
    t = take_off(_known_lagged())
    r = OD4 / 2
    arc = LR4 * math.pi / 2
    pipe = [q for q in t.insulation if q.size == "NPS 4"]
    tank = [q for q in t.insulation if q.size == "OD 2000.0 mm"]
    assert [q.size for q in t.insulation] == ["NPS 4", "OD 2000.0 mm"]  # thinnest first
    ((pipe),), ((tank),) = pipe, tank
    assert (pipe.thickness, pipe.fittings, pipe.components) == (T, 1, ("P1", "P1-P2", "P2"))
    assert pipe.length == pytest.approx(2.0 + arc)
    assert pipe.area == pytest.approx(2 * math.pi * (r + T) * (2.0 + arc))
    assert pipe.volume == pytest.approx(math.pi * ((r + T) ** 2 - r * r) * (2.0 + arc))
    assert (tank.thickness, tank.fittings, tank.components) == (0.1, 0, ("TK1",))
    assert t.insulated_length == pytest.approx(2.0 + arc + 3.0)
    assert t.insulation_area == pytest.approx(pipe.area + 2 * math.pi * 1.1 * 3.0)
    assert t.insulation_volume == pytest.approx(pipe.volume + tank.volume)
    assert t.insulated_fittings == 1
    (spool,) = t.spools
    assert spool.insulated_length == pytest.approx(2.0 + arc)
    assert {row.id: row.insulation for row in t.rows} == {
        "P1": T,
        "P1-P2": T,
        "P2": T,
        "C1": 0.0,
        "TK1": 0.1,
    }


def test_two_thicknesses_of_one_size_are_two_rows_largest_size_first():
    def pipe(pid, y, length, nominal, spool, t=0.0):
        od = {"4": OD4, "6": OD6}[nominal]
        straight = Straight([0, y, 0], [length, y, 0], od / 2)
        return Component(pid, "pipe", straight, spool=spool, nominal=nominal, insulation=t)

    comps = (
        pipe("A", 0, 1, "4", "S1", 0.04),
        pipe("B", 1, 2, "4", "S1", 0.05),
        pipe("C", 2, 3, "6", "S2", 0.04),
        pipe("D", 3, 1, "6", "S2"),
    )
    spools = (Spool("S1", ("A", "B")), Spool("S2", ("C", "D")))
    t = take_off(Model(components=comps, catalog="asme-b36.10m", spools=spools))
    assert [(q.thickness, q.size, q.length) for q in t.insulation] == [
        (0.04, "NPS 6", pytest.approx(3.0)),
        (0.04, "NPS 4", pytest.approx(1.0)),
        (0.05, "NPS 4", pytest.approx(2.0)),
    ]
    assert [sp.insulated_length for sp in t.spools] == [pytest.approx(3.0), pytest.approx(3.0)]
    assert t.insulated_fittings == 0


def test_a_bare_scan_has_no_insulation():
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    t = take_off(build_model(load_scan(ROOT / "samples" / "spool.json")))
    assert t.insulation == ()
    assert (t.insulated_length, t.insulation_area, t.insulation_volume) == (0.0, 0.0, 0.0)
    assert all(sp.insulated_length == 0.0 for sp in t.spools)
    assert all(row.insulation == 0.0 for row in t.rows)


def test_insulation_in_the_json_report_follows_the_schema():
    import jsonschema

    from asbuilt.report.data import report_data
    from asbuilt.report.json_report import dumps_report, report_schema

    validator = jsonschema.Draft202012Validator(report_schema())
    document = json.loads(dumps_report(report_data(_known_lagged(), generated=STAMP)))
    assert [f"{list(e.path)}: {e.message}" for e in validator.iter_errors(document)] == []
    takeoff = document["takeoff"]
    assert [(q["thickness"], q["size"], q["fittings"]) for q in takeoff["insulation"]] == [
        (T, "NPS 4", 1),
        (0.1, "OD 2000.0 mm", 0),
    ]
    arc = LR4 * math.pi / 2
    totals = takeoff["totals"]
    assert totals["insulated_length"] == pytest.approx(5.0 + arc)
    assert totals["insulated_fittings"] == 1
    assert totals["insulation_volume"] == pytest.approx(
        sum(q["volume"] for q in takeoff["insulation"])
    )
    assert takeoff["spools"][0]["insulated_length"] == pytest.approx(2.0 + arc)
    assert {c["id"]: c["insulation"] for c in document["components"]}["TK1"] == 0.1
    # a bare model: no rows, zero totals, still valid
    bare = json.loads(dumps_report(report_data(known_model(), generated=STAMP)))
    assert list(validator.iter_errors(bare)) == []
    assert bare["takeoff"]["insulation"] == []
    assert bare["takeoff"]["totals"]["insulation_area"] == 0.0
    # a row with a zero thickness is no insulation row
    bare["takeoff"]["insulation"] = [dict(document["takeoff"]["insulation"][0], thickness=0)]
    assert len(list(validator.iter_errors(bare))) == 1


def test_the_csv_appends_the_insulation_thickness_in_mm():
    from asbuilt.report.data import report_data
    from asbuilt.report.table_csv import COLUMNS, csv_text

    assert COLUMNS[-1] == "insulation_mm"
    text = csv_text(report_data(_known_lagged(), generated=STAMP))
    rows = {row["id"]: row["insulation_mm"] for row in csv.DictReader(io.StringIO(text))}
    assert rows == {"P1": "50.0", "P1-P2": "50.0", "P2": "50.0", "C1": "0.0", "TK1": "100.0"}


def test_the_html_takeoff_has_an_insulation_table_only_when_insulated():
    from asbuilt.report._html_takeoff import _takeoff
    from asbuilt.report.data import report_data

    page = _takeoff(report_data(_known_lagged(), generated=STAMP))
    assert "<h3>Insulation by thickness and size</h3>" in page
    assert '<table class="insulation">' in page
    assert '<th class="num">Insulated (m)</th>' in page  # the spools table's column
    arc = LR4 * math.pi / 2
    assert f'<tr><td class="num">50.0</td><td>NPS 4</td><td class="num">{2 + arc:,.3f}</td>' in page
    assert (
        f'<tr class="total"><td colspan="2">Total</td><td class="num">{5 + arc:,.3f}</td>' in page
    )
    bare = _takeoff(report_data(known_model(), generated=STAMP))
    assert "Insulat" not in bare


def test_the_insulated_page_is_well_formed():
    from report_helpers import check_html

    from asbuilt.report.data import report_data
    from asbuilt.report.html import html_text

    check_html(html_text(report_data(_known_lagged(), generated=STAMP)))


def test_the_html_components_table_has_an_insulation_column_only_when_insulated():
    import re

    from asbuilt.report.data import report_data
    from asbuilt.report.html import _components

    page = _components(report_data(_known_lagged(), generated=STAMP), {})
    heads = re.findall(r"<th[^>]*>([^<]*)</th>", page)
    assert heads[-2:] == ["Insulation (mm)", "Findings"]
    # each row's thickness in mm, in the column before the findings; a bare row's cell empty
    cells = {
        row_id: re.findall(r"<td[^>]*>(.*?)</td>", row)[-2]
        for row_id, row in re.findall(r'<tr id="([^"]+)">(.*?)</tr>', page)
    }
    assert cells == {
        "obj-P1": "50.0",
        "obj-P1-P2": "50.0",
        "obj-P2": "50.0",
        "obj-C1": "",
        "obj-TK1": "100.0",
    }
    bare = _components(report_data(known_model(), generated=STAMP), {})
    assert "Insulation" not in bare
