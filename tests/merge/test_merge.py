"""merge_model end to end on synthetic fits: fittings, consistency, classification, spools."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from synthetic_pipes import Pipe, box_fit, cylinder_fit, report_of

from asbuilt.errors import CatalogError
from asbuilt.merge import merge_model
from asbuilt.merge.spool import connection_mismatches, ports
from asbuilt.model import Bend, Reducer, Tee
from asbuilt.scan.model import ScanObject
from asbuilt.tolerances import DEFAULT_TOLERANCES

NPS4 = 0.1143


def by_id(model):
    return {c.id: c for c in model.components}


def assert_consistent(model, connections):
    found, bad = connection_mismatches(model.components, tolerance=1e-4)
    assert bad == []
    assert found == connections


def l_spool(od=0.1150):
    return [Pipe("P1", (0, 0, 0), (1.8, 0, 0), od), Pipe("P2", (2, 0.2, 0), (2, 2, 0), od)]


def test_elbow_geometry_from_the_catalog():
    model = merge_model(report_of(l_spool()))
    comps = by_id(model)
    assert [c.type for c in model.components] == ["pipe", "elbow", "pipe"]
    elbow = comps["P1-P2"]
    assert isinstance(elbow.geometry, Bend)
    assert elbow.geometry.bend_radius == pytest.approx(0.152)  # B16.9 NPS 4 long radius
    assert elbow.geometry.angle_deg == pytest.approx(90.0)
    assert elbow.geometry.outer_radius == pytest.approx(NPS4 / 2)
    assert elbow.geometry.wall == pytest.approx(0.00602)  # STD
    assert elbow.geometry.start == pytest.approx([2 - 0.152, 0, 0], abs=1e-9)
    assert elbow.geometry.end == pytest.approx([2, 0.152, 0], abs=1e-9)
    assert elbow.geometry.center == pytest.approx([2 - 0.152, 0.152, 0], abs=1e-9)
    assert (elbow.nominal, elbow.schedule, elbow.spool) == ("4", "STD", "S1")
    assert elbow.sources == () and elbow.snap["connects"] == ["P1", "P2"]
    p1, p2 = comps["P1"], comps["P2"]
    assert p1.geometry.end == pytest.approx(elbow.geometry.start)
    assert p2.geometry.start == pytest.approx(elbow.geometry.end)
    assert p1.geometry.start == pytest.approx([0, 0, 0], abs=1e-9)
    assert_consistent(model, 2)


def test_short_radius_on_request():
    model = merge_model(report_of(l_spool()), elbow_radius="short")
    assert by_id(model)["P1-P2"].geometry.bend_radius == pytest.approx(0.102)
    with pytest.raises(ValueError):
        merge_model(report_of(l_spool()), elbow_radius="tight")


@pytest.mark.parametrize("angle", [30.0, 45.0, 60.0, 95.0])
def test_bends_of_any_angle(angle):
    a = math.radians(angle)
    d = np.array([math.cos(a), math.sin(a), 0.0])
    p = np.array([2.0, 0, 0])
    gap = 0.152 * math.tan(a / 2) + 0.05  # the scan stops 5 cm short of the elbow's ends
    pipes = [
        Pipe("P1", (0, 0, 0), (2 - gap, 0, 0), NPS4),
        Pipe("P2", tuple(p + gap * d), tuple(p + 2 * d), NPS4),
    ]
    model = merge_model(report_of(pipes))
    bend = by_id(model)["P1-P2"].geometry
    assert bend.angle_deg == pytest.approx(angle, abs=1e-6)
    # the elbow's ends are R tan(theta/2) from the meeting point (45: the catalog's B = 64 mm)
    reach = 0.064 if angle == 45.0 else 0.152 * math.tan(a / 2)
    assert np.linalg.norm(bend.start - p) == pytest.approx(reach, abs=1e-9)
    assert np.linalg.norm(bend.end - p) == pytest.approx(reach, abs=1e-9)
    assert_consistent(model, 2)


def test_tee_at_a_joint_and_in_the_middle_of_a_pipe():
    at_joint = merge_model(
        report_of(
            [
                Pipe("P1", (0, 0, 0), (1.9, 0, 0), NPS4),
                Pipe("P2", (2.1, 0, 0), (4, 0, 0), NPS4),
                Pipe("P3", (2, 0.15, 0), (2, 2, 0), NPS4),
            ]
        )
    )
    tee = by_id(at_joint)["P1-P2-P3"]
    assert isinstance(tee.geometry, Tee)
    assert tee.geometry.center == pytest.approx([2, 0, 0], abs=1e-9)
    assert np.linalg.norm(tee.geometry.run_end - tee.geometry.center) == pytest.approx(0.105)
    assert np.linalg.norm(tee.geometry.branch_end - tee.geometry.center) == pytest.approx(0.105)
    assert_consistent(at_joint, 3)

    middle = merge_model(
        report_of(
            [Pipe("P1", (0, 0, 0), (4, 0, 0), NPS4), Pipe("P3", (2, 0.15, 0), (2, 2, 0), NPS4)]
        )
    )
    comps = by_id(middle)
    assert set(comps) == {"P1.1", "P1.2", "P1.1-P1.2-P3", "P3"}
    assert comps["P1.1"].sources == ("P1",) and comps["P1.2"].sources == ("P1",)
    assert comps["P1.1"].geometry.length + comps["P1.2"].geometry.length == pytest.approx(4 - 0.21)
    assert_consistent(middle, 3)


def test_reducer_and_butt_weld():
    model = merge_model(
        report_of(
            [
                Pipe("P1", (0, 0, 0), (1.9, 0, 0), NPS4),
                Pipe("P2", (2.1, 0, 0), (4, 0, 0), 0.0889),
                Pipe("P3", (4.2, 0, 0), (6, 0, 0), 0.0889),
            ]
        )
    )
    comps = by_id(model)
    reducer = comps["P1-P2"]
    assert reducer.type == "reducer" and isinstance(reducer.geometry, Reducer)
    g = reducer.geometry
    assert np.linalg.norm(g.end - g.start) == pytest.approx(0.102)  # B16.9 NPS 4 reducer H
    assert (g.outer_radius_start, g.outer_radius_end) == pytest.approx((NPS4 / 2, 0.0889 / 2))
    assert g.start == pytest.approx([2 - 0.051, 0, 0], abs=1e-9)
    # one size in line 0.2 m apart: a butt weld in the gap's middle, no "coupling"
    assert "P2-P3" not in comps
    assert comps["P2"].geometry.end == pytest.approx([4.1, 0, 0], abs=1e-9)
    assert comps["P3"].geometry.start == pytest.approx([4.1, 0, 0], abs=1e-9)
    assert model.spools[0].pipe_length == pytest.approx(
        sum(c.geometry.length for c in model.components if c.type == "pipe")
    )
    assert_consistent(model, 3)  # reducer (2 ends) and the butt weld


def test_butt_joint_meets_at_the_midpoint_without_a_fitting():
    model = merge_model(
        report_of(
            [Pipe("P1", (0, 0, 0), (2.0, 0, 0), NPS4), Pipe("P2", (2.003, 0, 0), (4, 0, 0), NPS4)]
        )
    )
    assert [c.type for c in model.components] == ["pipe", "pipe"]
    p1, p2 = model.components
    assert p1.geometry.end == pytest.approx(p2.geometry.start)
    assert p1.geometry.end[0] == pytest.approx(2.0015)
    assert_consistent(model, 1)


def test_trimming_is_recorded_in_millimetres():
    p1 = by_id(merge_model(report_of(l_spool())))["P1"]
    trim = [c for c in p1.corrections if c.what.endswith("at end")]
    assert len(trim) == 1 and trim[0].unit == "mm"
    assert trim[0].what == "extended at end"
    assert trim[0].size == pytest.approx(48.0, abs=1e-6)  # 1.8 m -> 2 - 0.152 m


def test_diameter_snap_record():
    p1 = by_id(merge_model(report_of(l_spool(od=0.1150))))["P1"]
    snap = p1.snap
    assert snap["status"] == "snapped" and snap["od_catalog"] == pytest.approx(NPS4)
    assert snap["od_fit"] == pytest.approx(0.1150)
    assert snap["od_stderr"] == pytest.approx(0.001)
    assert snap["candidates"][0]["nominal"] == "4"
    assert p1.geometry.outer_radius == pytest.approx(NPS4 / 2)
    corr = next(c for c in p1.corrections if c.what == "diameter snapped")
    assert (corr.before, corr.after, corr.unit) == (
        pytest.approx(0.1150),
        pytest.approx(NPS4),
        "mm",
    )
    assert corr.size == pytest.approx(0.7)


def test_unsnapped_pipe_keeps_its_fitted_diameter_and_is_solid():
    model = merge_model(report_of([Pipe("P1", (0, 0, 0), (2, 0, 0), 0.0990, se_radius=0.0001)]))
    pipe = model.components[0]
    assert pipe.type == "pipe" and pipe.snap["status"] == "no-size"
    assert pipe.geometry.outer_radius == pytest.approx(0.0495)
    assert pipe.geometry.wall == 0.0 and pipe.nominal is None and pipe.schedule is None
    assert "no size of asme-b36.10m" in pipe.snap["reason"]


def test_axis_regularisation_is_recorded():
    # 0.95 degrees off level, with an axis known to 0.5 degrees: noise, made level
    pipes = [
        Pipe("P1", (0, 0, 0), (1.8, 0, 0.03), NPS4, se_axis_deg=0.5),
        Pipe("P2", (2, 0.2, 0), (2, 2, 0), NPS4),
    ]
    p1 = by_id(merge_model(report_of(pipes)))["P1"]
    corr = next(c for c in p1.corrections if c.what.startswith("axis regularised"))
    assert "horizontal" in corr.what and corr.unit == "deg"
    assert corr.size == pytest.approx(math.degrees(math.atan2(0.03, 1.8)))
    assert p1.geometry.direction[2] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    ("label", "group", "od", "kind"),
    [
        ("storage tank", None, 0.300, "cylinder"),
        (None, "Column C-3", 0.3238, "cylinder"),
        ("chimney", None, 0.6, "cylinder"),
        (None, None, 3.0, "cylinder"),  # far beyond the largest pipe
        ("cooling water", None, 0.3238, "pipe"),
        ("NPS 8 line from the tank", "Tank farm", 0.2191, "pipe"),
        ("tank drain", None, 0.0603, "pipe"),
        (None, "tank farm", 0.0603, "cylinder"),
        ("vertical tank", "SP-1 line", 0.0603, "cylinder"),
        (None, None, 0.0103, "pipe"),
        # Equipment tags name vessels (a 48 in tank would otherwise be an NPS 48 pipe) ...
        ("TK-101", None, 1.2192, "cylinder"),
        ("V-101A", None, 1.0668, "cylinder"),
        ("receiver", None, 1.0, "cylinder"),
        # ... but not within a line number (a vent line's "V"), nor a bare letter and number.
        ('4"-V-1001-A1', None, 0.1143, "pipe"),
        ("D100", None, 0.1143, "pipe"),
    ],
)
def test_which_cylinders_are_pipes(label, group, od, kind):
    pipes = [Pipe("X1", (0, 0, 0), (0, 0, 3), od, label=label, group=group)]
    comp = merge_model(report_of(pipes)).components[0]
    assert comp.type == kind
    if kind == "cylinder":
        assert comp.snap["status"] == "not-pipe" and comp.snap["reason"]
        assert comp.geometry.radius == pytest.approx(od / 2)  # unchanged fit


def test_a_linked_cylinder_is_a_pipe_even_outside_the_catalog_range():
    pipes = [Pipe("A", (0, 0, 0), (1.6, 0, 0), 1.5), Pipe("B", (2, 0.2, 0), (2, 2, 0), 0.1143)]
    model = merge_model(report_of(pipes, links=[("A", "B")]))
    assert by_id(model)["A"].type == "pipe"


def test_other_primitives_pass_through_in_order():
    obj, res = box_fit()
    model = merge_model(report_of(l_spool(), extra=[(obj, res)]))
    assert [c.id for c in model.components] == ["P1", "P1-P2", "P2", "C1"]
    box = by_id(model)["C1"]
    assert box.type == "cuboid" and box.geometry is res.primitive and box.spool is None
    assert model.catalog == "asme-b36.10m" and model.units == "m"
    assert model.scan is not None and model.fits is not None


@pytest.mark.parametrize(
    ("hint", "agrees", "status", "nominal"),
    [
        ('4"', True, "snapped", "4"),
        ("DN100", True, "snapped", "4"),
        ("NPS 6", False, "snapped", "4"),
        ("huge", None, "snapped", "4"),
    ],
)
def test_operator_hints(hint, agrees, status, nominal):
    pipes = l_spool()
    pipes[0].nominal = hint
    comps = by_id(merge_model(report_of(pipes)))
    assert comps["P1"].snap["hint"]["agrees"] is agrees
    assert "hint" not in comps["P2"].snap
    assert (comps["P1"].snap["status"], comps["P1"].nominal) == (status, nominal)


def test_hint_settles_an_ambiguous_run():
    pipes = [Pipe("P1", (0, 0, 0), (2, 0, 0), 0.1080, se_radius=0.002, nominal='3 1/2"')]
    pipe = merge_model(report_of(pipes)).components[0]
    assert pipe.snap["status"] == "hint" and pipe.nominal == "3 1/2"
    assert {c["nominal"] for c in pipe.snap["candidates"]} == {"3 1/2", "4"}


@pytest.mark.parametrize(
    ("catalog", "schedule", "wall", "used"),
    [
        (None, None, 0.00602, "STD"),
        (None, "80", 0.00856, "80"),
        (None, "xs", 0.00856, "XS"),
        ("asme-b36.19m", None, 0.00305, "10S"),
    ],
)
def test_schedules(catalog, schedule, wall, used):
    model = merge_model(report_of(l_spool()), catalog=catalog, schedule=schedule)
    pipe = model.components[0]
    assert (pipe.geometry.wall, pipe.schedule) == (pytest.approx(wall), used)


def test_unknown_schedule_and_catalog_are_user_errors():
    with pytest.raises(CatalogError, match="schedule 'SCH99' is not in catalog asme-b36.10m"):
        merge_model(report_of(l_spool()), schedule="SCH99")
    with pytest.raises(CatalogError, match="unknown catalog"):
        merge_model(report_of(l_spool()), catalog="nope")
    with pytest.raises(CatalogError, match="fittings catalog"):
        merge_model(report_of(l_spool()), catalog="asme-b16.9")


def test_copper_uses_rule_fittings():
    pipes = [
        Pipe("P1", (0, 0, 0), (1.8, 0, 0), 0.05398),
        Pipe("P2", (2, 0.2, 0), (2, 2, 0), 0.05398),
    ]
    model = merge_model(report_of(pipes), catalog="astm-b88")
    elbow = by_id(model)["P1-P2"]
    assert elbow.nominal == "2" and elbow.schedule == "L"
    assert elbow.geometry.bend_radius == pytest.approx(1.5 * 2 * 0.0254)
    assert elbow.snap["dimensions"] == "rule"
    assert_consistent(model, 2)


def test_spools_take_the_group_name_or_a_number():
    pipes = l_spool() + [
        Pipe("Q1", (10, 0, 0), (11.8, 0, 0), NPS4, group="line-7"),
        Pipe("Q2", (12, 0.2, 0), (12, 2, 0), NPS4, group="line-7"),
    ]
    for p in pipes[:2]:
        p.group = "mixed" if p.id == "P1" else None
    model = merge_model(report_of(pipes))
    assert [s.id for s in model.spools] == ["S1", "line-7"]
    assert model.spools[1].components == ("Q1", "Q1-Q2", "Q2")
    assert by_id(model)["Q1-Q2"].spool == "line-7"


def test_a_fitting_that_does_not_fit_is_reported_not_built():
    # a 0.2 m pipe between two NPS 12 elbows (each needs 0.457 m)
    od = 0.3238
    pipes = [
        Pipe("A", (0, 0, 0), (1.4, 0, 0), od),
        Pipe("B", (1.5, 0.05, 0), (1.5, 0.25, 0), od),
        Pipe("C", (1.55, 0.3, 0), (3, 0.3, 0), od),
    ]
    model = merge_model(report_of(pipes, links=[("A", "B"), ("B", "C")]))
    b = by_id(model)["B"]
    assert any("would not fit" in note for note in b.snap["merge_notes"])
    for comp in model.components:
        if comp.type == "pipe":
            assert comp.geometry.length > 0


def test_ports_of_each_geometry():
    model = merge_model(
        report_of(
            [
                Pipe("P1", (0, 0, 0), (1.9, 0, 0), NPS4),
                Pipe("P2", (2.1, 0, 0), (4, 0, 0), NPS4),
                Pipe("P3", (2, 0.15, 0), (2, 1.8, 0), NPS4),
                Pipe("P4", (2.2, 2, 0), (4, 2, 0), NPS4),
            ]
        )
    )
    kinds = {c.type: len(ports(c)) for c in model.components}
    assert kinds == {"pipe": 2, "tee": 3, "elbow": 2}
    obj = ScanObject(id="Z", kind="cylinder", points=np.zeros((6, 3)))
    assert obj and ports(model.components[0])[0][1] == pytest.approx([-1, 0, 0])


def rotation(a, b, c):
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return rz @ ry @ rx


@settings(max_examples=25, deadline=None)
@given(
    angles=st.tuples(st.floats(0, 6.28), st.floats(-1.5, 1.5), st.floats(0, 6.28)),
    shift=st.tuples(st.floats(-50, 50), st.floats(-50, 50), st.floats(-5, 5)),
    noise=st.floats(0, 0.003),
)
def test_any_pose_gives_consistent_geometry(angles, shift, noise):
    """A Z-shaped spool with a tee and a reducer, rigidly moved and with end-point noise."""
    rot = rotation(*angles)
    rng = np.random.default_rng(0)
    raw = [
        ("P1", (0, 0, 0), (1.8, 0, 0), 0.1143),
        ("P2", (2, 0.2, 0), (2, 2.8, 0), 0.1143),
        ("P3", (2.2, 3, 0), (3.9, 3, 0), 0.1143),
        ("P4", (4.1, 3, 0), (6, 3, 0), 0.0889),
        ("P5", (2, 1.5, 0.15), (2, 1.5, 1.5), 0.0889),
    ]
    pipes = []
    for pid, a, b, od in raw:
        a = rot @ np.array(a, float) + shift + rng.normal(0, noise, 3)
        b = rot @ np.array(b, float) + shift + rng.normal(0, noise, 3)
        pipes.append(Pipe(pid, tuple(a), tuple(b), od))
    model = merge_model(report_of(pipes))
    types = sorted(c.type for c in model.components)
    assert types.count("elbow") == 2 and types.count("reducer") == 1 and types.count("tee") == 1
    found, bad = connection_mismatches(model.components, tolerance=1e-4)
    assert bad == [] and found == 9
    assert len(model.spools) == 1


def test_cylinder_fit_helper_is_a_real_fit_result():
    res = cylinder_fit((0, 0, 0), (1, 0, 0), 0.1)
    assert res.primitive.length == pytest.approx(1.0) and res.stderr["radius"] == 0.0005
    assert DEFAULT_TOLERANCES.angle_snap_deg == 2.0


@settings(max_examples=25, deadline=None)
@given(
    angle=st.floats(15, 98),  # elbows turn at most 90 + intended_angle_deg (10) degrees
    twist=st.floats(0, 6.28),
    yaw=st.floats(0, 6.28),
    nps_od=st.sampled_from([0.0603, 0.1143, 0.2191, 0.3238]),
)
# 2.1 degrees off square: one pipe made horizontal must not then make the pair square.
@example(angle=87.875, twist=0.0, yaw=0.0, nps_od=0.0603)
def test_bends_of_any_angle_in_any_plane_connect_exactly(angle, twist, yaw, nps_od):
    """Two pipes meeting at an arbitrary angle in an arbitrarily tilted plane."""
    a = np.radians(angle)
    reach = 1.5 * nps_od * np.tan(a / 2) + 0.05  # the scan stops short of the bend's ends
    d1 = np.array([1.0, 0, 0])
    d2 = np.array([np.cos(a), np.sin(a) * np.cos(twist), np.sin(a) * np.sin(twist)])
    rot = rotation(yaw, 0.3, 0.0)
    p = np.array([5.0, 1.0, 2.0])
    length = max(2.0, 4 * reach)
    pipes = [
        Pipe("A", tuple(p - rot @ d1 * length), tuple(p - rot @ d1 * reach), nps_od),
        Pipe("B", tuple(p + rot @ d2 * reach), tuple(p + rot @ d2 * length), nps_od),
    ]
    model = merge_model(report_of(pipes))
    assert [c.type for c in model.components] == ["pipe", "elbow", "pipe"]
    assert model.components[1].geometry.angle_deg == pytest.approx(angle, abs=2.0 + 1e-6)
    assert connection_mismatches(model.components, tolerance=1e-4) == (2, [])


def test_a_long_chain_is_one_spool_with_every_joint_exact():
    """400 pipes zigzagging in one spool: the sparse alignment path, exact joints throughout."""
    rng = np.random.default_rng(3)
    corner = np.zeros(3)
    pipes = []
    for k in range(400):
        d = np.array([1.0, 0, 0]) if k % 2 == 0 else np.array([0, 1.0, 0])
        start = corner + (0.19 if k else 0.0) * d + rng.normal(0, 0.002, 3)
        end = corner + 1.81 * d + rng.normal(0, 0.002, 3)
        pipes.append(Pipe(f"P{k}", tuple(start), tuple(end), NPS4))
        corner = corner + 2 * d
    model = merge_model(report_of(pipes))
    assert len(model.spools) == 1
    assert sum(c.type == "elbow" for c in model.components) == 399
    assert connection_mismatches(model.components, tolerance=1e-4) == (798, [])


def test_a_report_without_pipes_passes_through():
    obj, res = box_fit()
    model = merge_model(report_of([], extra=[(obj, res)]))
    assert [c.id for c in model.components] == ["C1"] and model.spools == ()
    assert model.catalog == "asme-b36.10m"
    assert merge_model(report_of([])).components == ()
