"""Take-off numbers against values computed by hand (and one catalog table value)."""

import math

import numpy as np
import pytest
from report_helpers import LR4, OD4, WALL4, known_model

from asbuilt.model import Bend, Component, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cylinder, Hull, Plane, Sphere
from asbuilt.report.takeoff import DENSITIES, pipe_weight_per_metre, take_off


def test_nps4_std_weight_matches_the_b36_10m_table():
    # ASME B36.10M lists NPS 4 STD (114.3 x 6.02 mm) plain end at 16.07 kg/m.
    assert pipe_weight_per_metre(0.1143, 0.00602) == pytest.approx(16.07, abs=0.01)
    # The standard's own constant: 0.0246615 (D - t) t kg/m with D, t in mm.
    assert pipe_weight_per_metre(0.1143, 0.00602) == pytest.approx(
        0.0246615 * (114.3 - 6.02) * 6.02, rel=1e-5
    )


@pytest.mark.parametrize(
    ("od_mm", "wall_mm", "table_kg_m"),
    [  # ASME B36.10M plain-end masses (STD and XS rows)
        (60.3, 3.91, 5.44),
        (88.9, 5.49, 11.29),
        (168.3, 7.11, 28.26),
        (219.1, 8.18, 42.55),
        (114.3, 8.56, 22.32),
    ],
)
def test_weights_match_table_rows(od_mm, wall_mm, table_kg_m):
    assert pipe_weight_per_metre(od_mm / 1000, wall_mm / 1000) == pytest.approx(
        table_kg_m, abs=0.011
    )


def test_weight_is_vectorised():
    values = pipe_weight_per_metre(np.array([0.1143, 0.1683]), np.array([0.00602, 0.00711]))
    assert values.shape == (2,)


@pytest.fixture(scope="module")
def known():
    return take_off(known_model())


def test_pipe_line_of_the_known_spool(known):
    (line,) = known.pipes
    assert (line.nominal, line.schedule, line.size, line.count) == ("4", "STD", "NPS 4", 2)
    assert line.length == pytest.approx(2.0)
    assert line.length_ft == pytest.approx(2.0 / 0.3048)  # 6.562 ft
    assert line.od == pytest.approx(OD4)
    assert line.wall == pytest.approx(WALL4)
    assert line.weight_per_m == pytest.approx(7850 * math.pi * (OD4 - WALL4) * WALL4)
    assert line.weight == pytest.approx(2 * 16.0755, abs=0.01)
    assert line.area == pytest.approx(math.pi * OD4 * 2.0)
    assert known.pipe_length == pytest.approx(2.0)
    assert known.pipe_weight == pytest.approx(line.weight)
    assert known.material == "carbon steel"
    assert known.density == DENSITIES["carbon steel"] == 7850


def test_elbow_counted_by_size_and_angle(known):
    (elbow,) = known.fittings
    assert (elbow.type, elbow.size, elbow.schedule, elbow.angle_deg, elbow.count) == (
        "elbow",
        "NPS 4",
        "STD",
        90,
        1,
    )
    assert elbow.bend_radius == pytest.approx(LR4)


def test_column_and_tank_volumes_and_areas(known):
    solids = {s.id: s for s in known.solids}
    column = solids["C1"]
    assert column.volume == pytest.approx(0.4 * 0.4 * 3.0)  # 0.48 m3
    assert column.area == pytest.approx(2 * (0.16 + 1.2 + 1.2))  # 5.12 m2
    assert column.category == "member"
    tank = solids["TK1"]
    assert tank.volume == pytest.approx(math.pi * 1.0**2 * 3.0)
    assert tank.area == pytest.approx(2 * math.pi * 1.0 * 3.0 + 2 * math.pi * 1.0**2)
    assert tank.category == "tank/vessel"
    assert known.volumes == pytest.approx({"member": 0.48, "tank/vessel": 3 * math.pi})


def test_rows_one_per_component_with_units(known):
    rows = {r.id: r for r in known.rows}
    assert list(rows) == ["P1", "P1-P2", "P2", "C1", "TK1"]
    assert (rows["P1"].quantity_unit, rows["P1"].quantity) == ("m", pytest.approx(1.0))
    assert rows["P1"].weight == pytest.approx(16.0755, abs=0.001)
    assert (rows["P1-P2"].quantity_unit, rows["P1-P2"].quantity) == ("ea", 1.0)
    assert rows["P1-P2"].length is None
    assert (rows["C1"].quantity_unit, rows["C1"].quantity) == ("m3", pytest.approx(0.48))
    assert rows["C1"].length == pytest.approx(3.0)
    assert rows["TK1"].length == pytest.approx(3.0)
    assert known.counts == {"pipe": 2, "elbow": 1, "cuboid": 1, "cylinder": 1}


def test_no_weight_without_density_or_wall():
    plain = known_model()
    copper = plain.replace(catalog="astm-b88")  # copper: no density listed
    assert take_off(copper).pipes[0].weight is None
    assert take_off(copper, density=8940).pipes[0].weight == pytest.approx(
        8940 * math.pi * (OD4 - WALL4) * WALL4 * 2
    )
    solid = Model(components=(Component("P9", "pipe", Straight([0, 0, 0], [3, 0, 0], 0.05)),))
    (line,) = take_off(solid).pipes
    assert line.wall is None and line.weight is None
    assert line.size == "OD 100.0 mm"  # not snapped: labelled by its fitted OD


def test_findings_on_rows_worst_first():
    from report_helpers import many_findings

    model = known_model()
    model = model.replace(findings=many_findings(model))
    rows = {r.id: r for r in take_off(model).rows}
    assert rows["P1"].findings == ("AB900", "AB901", "AB902")  # error, warning, info
    assert rows["P1"].severity == "error"
    assert rows["P1-P2"].severity == "error"  # (1 + 2) % 3 == 0 -> AB902 is its error
    assert rows["P1-P2"].findings[0] == "AB902"


def test_reducer_and_reducing_tee_sizes():
    comps = (
        Component(
            "R1",
            "reducer",
            Reducer([0, 0, 0], [0.14, 0, 0], 0.08415, 0.05715),
            nominal="6",
            schedule="STD",
            snap={"sizes": ["6", "4"]},
        ),
        Component(
            "R2",
            "reducer",
            Reducer([0, 1, 0], [0.14, 1, 0], 0.08415, 0.05715),
            nominal="6",
            schedule="STD",
        ),  # sizes from the catalog by OD
        Component(
            "R3",
            "reducer",
            Reducer([0, 4, 0], [0.14, 4, 0.027], 0.08415, 0.05715, offset=[0, 0, 0.027]),
            nominal="6",
            schedule="STD",
            snap={"sizes": ["6", "4"]},
        ),  # eccentric (flat on top), bought as its own item
        Component(
            "T1",
            "tee",
            Tee([0, 2, 0], [-0.14, 2, 0], [0.14, 2, 0], [0, 2.14, 0], 0.08415, 0.05715),
            nominal="6",
        ),
        Component(
            "T2",
            "tee",
            Tee([0, 3, 0], [-0.14, 3, 0], [0.14, 3, 0], [0, 3.14, 0], 0.08415, 0.08415),
            nominal="6",
        ),
    )
    t = take_off(Model(components=comps, catalog="asme-b36.10m"))
    sizes = sorted((f.type, f.size, f.count) for f in t.fittings)
    assert sizes == [
        ("concentric reducer", "NPS 6 x 4", 2),
        ("eccentric reducer", "NPS 6 x 4", 1),
        ("tee", "NPS 6", 1),
        ("tee", "NPS 6 x 4", 1),
    ]
    assert [f.type for f in t.fittings] == [
        "tee",
        "tee",
        "concentric reducer",
        "eccentric reducer",
    ]
    assert {r.id: r.type for r in t.rows}["R3"] == "reducer"  # the component type is unchanged


def test_sphere_plane_and_hull_quantities():
    cube = np.array([[x, y, z] for x in (0, 2) for y in (0, 2) for z in (0, 2)], float)
    from scipy.spatial import ConvexHull

    hull = ConvexHull(cube)
    faces = hull.simplices.copy()
    centre = cube.mean(axis=0)
    for f in faces:  # wind outward
        a, b, c = cube[f]
        if np.dot(np.cross(b - a, c - a), a - centre) < 0:
            f[[1, 2]] = f[[2, 1]]
    square = np.array([[0, 0, 0], [3, 0, 0], [3, 0, 2], [0, 0, 2]], float)
    comps = (
        Component("S1", "sphere", Sphere([0, 0, 5], 0.5)),
        Component("W1", "plane", Plane([1.5, 0, 1], [0, -1, 0], square)),
        Component("H1", "hull", Hull(cube, faces)),
    )
    t = take_off(Model(components=comps))
    solids = {s.id: s for s in t.solids}
    assert solids["S1"].volume == pytest.approx(4 / 3 * math.pi * 0.125)
    assert solids["S1"].area == pytest.approx(4 * math.pi * 0.25)
    assert solids["W1"].volume is None and solids["W1"].area == pytest.approx(6.0)
    assert solids["H1"].volume == pytest.approx(8.0)
    assert solids["H1"].area == pytest.approx(24.0)
    rows = {r.id: r for r in t.rows}
    assert (rows["W1"].quantity_unit, rows["W1"].quantity) == ("m2", pytest.approx(6.0))
    assert (rows["H1"].quantity_unit, rows["H1"].quantity) == ("m3", pytest.approx(8.0))


def test_cylinder_quantity_for_unmerged_pipes():
    comp = Component("P1", "cylinder", Cylinder([0, 0, 0], [1, 0, 0], 0.1, 2.0))
    (solid,) = take_off(Model(components=(comp,))).solids
    assert solid.volume == pytest.approx(math.pi * 0.01 * 2.0)
    assert solid.dimensions == pytest.approx((0.2, 2.0))


def test_empty_model():
    t = take_off(Model(components=()))
    assert (t.pipes, t.fittings, t.solids, t.rows, t.pipe_length) == ((), (), (), (), 0.0)


def test_spool_totals(known):
    (spool,) = known.spools
    assert (spool.id, spool.pipes, spool.fittings, spool.sizes) == (
        "SP-1",
        2,
        {"elbow": 1},
        ("NPS 4",),
    )
    assert spool.pipe_length == pytest.approx(2.0)
    assert spool.pipe_weight == pytest.approx(2 * 16.0755, abs=0.01)
    assert spool.components == ("P1", "P1-P2", "P2")


def test_spool_findings_and_unlisted_spools():
    from report_helpers import many_findings

    model = known_model()
    model = model.replace(findings=many_findings(model), spools=())  # spools not listed
    (spool,) = take_off(model).spools
    assert spool.id == "SP-1" and spool.pipes == 2
    assert set(spool.findings) == {"AB900", "AB901", "AB902"}


def _without_wall(model, ids):
    """The model with the pipes ``ids`` of unknown schedule and wall (no weight)."""
    import dataclasses

    comps = tuple(
        dataclasses.replace(c, schedule=None, geometry=dataclasses.replace(c.geometry, wall=0.0))
        if c.id in ids
        else c
        for c in model.components
    )
    return model.replace(components=comps)


def test_pipe_weight_total_says_which_pipes_it_leaves_out(known):
    """Audit D7: a partial total says how many pipes it leaves out; none is null, not 0.0."""
    from asbuilt.report import report_data
    from asbuilt.report.json_report import report_document

    # P2 has no wall: the total is P1's 1 m of NPS 4 STD, 16.08 kg (B36.10M: 16.07 kg/m)
    partial = take_off(_without_wall(known_model(), {"P2"}))
    assert partial.pipe_weight == pytest.approx(16.0755, abs=0.01)
    assert partial.pipes_without_weight == 1
    (spool,) = partial.spools
    assert spool.pipe_weight == pytest.approx(16.0755, abs=0.01)
    assert spool.pipes_without_weight == 1
    none = report_data(_without_wall(known_model(), {"P1", "P2"}))
    assert none.takeoff.pipe_weight is None and none.takeoff.pipes_without_weight == 2
    totals = report_document(none)["takeoff"]["totals"]
    assert totals["pipe_weight"] is None and totals["pipes_without_weight"] == 2
    assert known.pipes_without_weight == 0


def test_pipe_weight_total_in_the_page():
    from asbuilt.report import report_data
    from asbuilt.report.html import html_text

    text = html_text(report_data(_without_wall(known_model(), {"P2"})))
    total = text.split('<table class="pipes">', 1)[1].split('<tr class="total">', 1)[1]
    assert '>16.1<br><span class="muted">without 1 pipe</span></td>' in total.split("</tr>")[0]
    assert "1 of 2 pipes have no weight and are not in the total" in text
    text = html_text(report_data(_without_wall(known_model(), {"P1", "P2"})))
    assert "No pipe has a weight: their wall thickness is not known" in text


def test_a_reducing_elbow_names_both_sizes():
    """An elbow joining NPS 6 (start, OD 168.3 mm) to NPS 4 (end, 114.3 mm) was taken off as
    "NPS 6", like an equal 6 inch elbow; it is bought as a 6 x 4 reducing elbow. An elbow whose
    ends differ only in wall is still one size."""
    r = 0.229
    comps = (
        Component(
            "E1",
            "elbow",
            Bend([r, 0, 0], [0, r, 0], [0, 0, 0], 0.08415, 0.00711, 0.05715, 0.00602),
            nominal="6",
            schedule="STD",
        ),
        Component(
            "E2",
            "elbow",
            Bend([r, 0, 2], [0, r, 2], [0, 0, 2], 0.08415, 0.00711),
            nominal="6",
            schedule="STD",
        ),
        Component(
            "E3",
            "elbow",
            Bend([r, 0, 4], [0, r, 4], [0, 0, 4], 0.08415, 0.00711, None, 0.01097),
            nominal="6",
            schedule="STD",
        ),
        Component(
            "E4",
            "elbow",
            Bend([r, 0, 6], [0, r, 6], [0, 0, 6], 0.05715, 0.00602, 0.08415, 0.00711),
            nominal="4",
        ),  # smaller end first: still named large x small
    )
    t = take_off(Model(components=comps, catalog="asme-b36.10m"))
    rows = {row.id: row.size for row in t.rows}
    assert rows == {"E1": "NPS 6 x 4", "E2": "NPS 6", "E3": "NPS 6", "E4": "NPS 6 x 4"}
    sizes = sorted((f.size, f.count) for f in t.fittings)
    assert ("NPS 6", 2) in sizes and ("NPS 6 x 4", 1) in sizes


def test_a_lateral_is_counted_apart_from_tees_by_its_angle():
    # merging builds a lateral (wye) as a tee-shaped component and records its angle in snap;
    # bought as a lateral, it must not be counted with the square tees of its size
    def tee(cid, y, snap=None):
        return Component(
            cid,
            "tee",
            Tee([0, y, 0], [-0.14, y, 0], [0.14, y, 0], [0, y + 0.14, 0], 0.05715, 0.05715),
            nominal="4",
            schedule="40",
            snap=snap or {},
        )

    lateral = {"standard": False, "angle_deg": 44.8, "status": "fitting"}
    comps = (tee("T1", 0), tee("L1", 1, lateral), tee("L2", 2, dict(lateral, angle_deg=60.2)))
    t = take_off(Model(components=comps, catalog="asme-b36.10m"))
    assert [(f.type, f.size, f.angle_deg, f.components) for f in t.fittings] == [
        ("tee", "NPS 4", None, ("T1",)),
        ("lateral", "NPS 4", 45, ("L1",)),
        ("lateral", "NPS 4", 60, ("L2",)),
    ]
    assert {r.id: r.type for r in t.rows}["L1"] == "tee"  # the component type is unchanged


def test_a_spool_counts_its_laterals_apart_from_its_tees():
    # the per-spool summary counted a 45 degree lateral under "tee", as the purchasing list
    # once did
    def tee(cid, y, snap=None):
        geometry = Tee([0, y, 0], [-0.14, y, 0], [0.14, y, 0], [0, y + 0.14, 0], 0.05715, 0.05715)
        return Component(cid, "tee", geometry, nominal="4", spool="S1", snap=snap or {})

    lateral = {"standard": False, "angle_deg": 44.8, "status": "fitting"}
    comps = (tee("T1", 0), tee("L1", 1, lateral), tee("L2", 2, lateral))
    (spool,) = take_off(Model(components=comps, catalog="asme-b36.10m")).spools
    assert dict(spool.fittings) == {"tee": 1, "lateral": 2}
