"""clash: overlap volumes against closed forms (Steinmetz solid, lens, slab of a cylinder)."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rules_builders import column, model, pipe

from asbuilt.model import Bend, Component, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.rules import check_model, loads_rules
from asbuilt.rules.clash import bounds, candidate_pairs, inside, overlap_volume


def volume(ga, gb, samples=1 << 14):
    return overlap_volume(ga, gb, bounds(ga), bounds(gb), samples)


def test_steinmetz_solid():
    r = 0.05
    a = Straight([-1, 0, 0], [1, 0, 0], r)
    b = Straight([0, -1, 0], [0, 1, 0], r)
    v, se, centroid = volume(a, b)
    truth = 16 * r**3 / 3
    assert abs(v - truth) < max(3 * se, 0.02 * truth)
    np.testing.assert_allclose(centroid, 0, atol=0.005)


def test_sphere_lens():
    r, d = 0.5, 0.6
    a, b = Sphere([0, 0, 0], r), Sphere([d, 0, 0], r)
    truth = np.pi * (4 * r + d) * (2 * r - d) ** 2 / 12
    v, se, _ = volume(a, b)
    assert abs(v - truth) < max(3 * se, 0.02 * truth)


def test_cylinder_through_box():
    r, w = 0.1, 0.3
    pipe_geom = Cylinder([0, 0, 0], [1, 0, 0], r, 4.0)
    box = Cuboid([0, 0, 0], np.eye(3), [w, 1.0, 1.0])
    v, se, _ = volume(pipe_geom, box)
    truth = np.pi * r**2 * w
    assert abs(v - truth) < max(3 * se, 0.02 * truth)


def test_disjoint_boxes_have_no_volume():
    a = Cuboid([0, 0, 0], np.eye(3), [1, 1, 1])
    b = Cuboid([2, 0, 0], np.eye(3), [1, 1, 1])
    assert volume(a, b)[0] == 0.0


@pytest.mark.parametrize(
    "geometry, point, expected",
    [
        (Straight([0, 0, 0], [1, 0, 0], 0.1), [0.5, 0.05, 0], True),
        (Straight([0, 0, 0], [1, 0, 0], 0.1), [1.05, 0, 0], False),
        (Bend([1, 0, 0], [0, 1, 0], [0, 0, 0], 0.1), [np.sqrt(0.5), np.sqrt(0.5), 0], True),
        (Bend([1, 0, 0], [0, 1, 0], [0, 0, 0], 0.1), [-np.sqrt(0.5), np.sqrt(0.5), 0], False),
        (Tee([0, 0, 0], [-1, 0, 0], [1, 0, 0], [0, 1, 0], 0.1, 0.05), [0, 0.5, 0.04], True),
        (Tee([0, 0, 0], [-1, 0, 0], [1, 0, 0], [0, 1, 0], 0.1, 0.05), [0, 0.5, 0.07], False),
        (
            Hull(
                np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
                [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            ),
            [0.1, 0.1, 0.1],
            True,
        ),
        (
            Plane([0, 0, 0], [0, 0, 1], [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
            [0.5, 0.5, 0.004],
            True,
        ),
        (
            Plane([0, 0, 0], [0, 0, 1], [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]),
            [0.5, 0.5, 0.006],
            False,
        ),
    ],
)
def test_inside(geometry, point, expected):
    assert bool(inside(geometry, np.array([point]))[0]) == expected


def test_clash_between_crossing_pipes_is_an_error():
    a = pipe("P1", [-1, 0, 1], [1, 0, 1], 0.1143)
    b = pipe("P2", [0, -1, 1.02], [0, 1, 1.02], 0.1143)
    (f,) = [f for f in check_model(model(a, b)) if f.slug == "clash"]
    assert f.severity == "error" and f.objects == ("P1", "P2")
    assert f.unit == "m3" and f.measured > 1e-4
    assert "cm3" in f.message


def test_pipes_clear_of_each_other_do_not_clash():
    a = pipe("P1", [-1, 0, 1], [1, 0, 1], 0.1143)
    b = pipe("P2", [0, -1, 1.116], [0, 1, 1.116], 0.1143)  # 1.7 mm of clearance
    assert not [f for f in check_model(model(a, b)) if f.slug == "clash"]


def test_touching_at_a_fitting_is_not_a_clash():
    r = 0.1143 / 2
    a = pipe("P1", [0, 0, 1], [1.848, 0, 1], 0.1143)
    elbow = Component(
        id="E1", type="elbow", geometry=Bend([1.848, 0, 1], [2, 0.152, 1], [1.848, 0.152, 1], r)
    )
    b = pipe("P2", [2, 0.152, 1], [2, 2, 1], 0.1143)
    assert not [f for f in check_model(model(a, elbow, b)) if f.slug == "clash"]


def test_min_volume_is_configurable():
    a = pipe("P1", [-1, 0, 1], [1, 0, 1], 0.1143)
    b = pipe("P2", [0, -1, 1.11], [0, 1, 1.11], 0.1143)  # a shallow graze
    config = loads_rules("[clash]\nmin_volume = 0.001")
    assert not [f for f in check_model(model(a, b), config) if f.slug == "clash"]


def brute_pairs(boxes):
    out = []
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            if np.all(boxes[i, 0] <= boxes[j, 1]) and np.all(boxes[j, 0] <= boxes[i, 1]):
                out.append((i, j))
    return out


def test_broad_phase_matches_brute_force():
    rng = np.random.default_rng(3)
    lo = rng.uniform(0, 10, (300, 3))
    boxes = np.stack([lo, lo + rng.uniform(0.05, 1.0, (300, 3))], axis=1)
    assert sorted(candidate_pairs(boxes)) == brute_pairs(boxes)


def test_thousand_objects_grid_has_no_clash():
    comps = []
    for i in range(10):
        for j in range(10):
            for k in range(10):
                c = [i * 0.5, j * 0.5, k * 0.5]
                comps.append(
                    Component(
                        id=f"B{i}-{j}-{k}",
                        type="cuboid",
                        geometry=Cuboid(c, np.eye(3), [0.3, 0.3, 0.3]),
                    )
                )
    config = loads_rules('select = ["clash"]')
    assert check_model(model(*comps), config) == ()


def test_pipe_resting_on_a_beam_within_fit_noise_is_not_an_error():
    from rules_builders import cuboid_fit

    # a beam along x, 0.3 m deep (its top at z = 1.0) and 0.5 m wide
    fit = cuboid_fit([0, 0, 0.85], [1, 0, 0], (0.3, 0.5, 3.0), center_se=0.002, size_se=0.002)
    beam = Component(id="B1", type="cuboid", geometry=fit.primitive, fit=fit)
    r = 0.1143 / 2
    # fitted 1.5 mm into the beam's top (z = 1.0) while the fits are good to ~2 mm
    resting = pipe(
        "P1",
        [0, -1.5, 1.0 + r - 0.0015],
        [0, 1.5, 1.0 + r - 0.0015],
        0.1143,
        center_se=0.002,
        radius_se=0.001,
    )
    (f,) = [f for f in check_model(model(beam, resting)) if f.slug == "clash"]
    assert f.severity == "warning" and f.unverifiable
    assert "within the fits' uncertainty" in f.message
    # 30 mm into it is a clash whatever the noise
    sunk = pipe(
        "P1",
        [0, -1.5, 1.0 + r - 0.03],
        [0, 1.5, 1.0 + r - 0.03],
        0.1143,
        center_se=0.002,
        radius_se=0.001,
    )
    (f,) = [f for f in check_model(model(beam, sunk)) if f.slug == "clash"]
    assert f.severity == "error"


@pytest.mark.parametrize(
    "geometry, point, erode, expected",
    [
        (Straight([0, 0, 0], [1, 0, 0], 0.1), [0.5, 0.095, 0], 0.0, True),
        (Straight([0, 0, 0], [1, 0, 0], 0.1), [0.5, 0.095, 0], 0.01, False),
        (Cuboid([0, 0, 0], np.eye(3), [1, 1, 1]), [0.495, 0, 0], 0.01, False),
        (Sphere([0, 0, 0], 1.0), [0.985, 0, 0], 0.01, True),
    ],
)
def test_inside_eroded(geometry, point, erode, expected):
    assert bool(inside(geometry, np.array([point]), erode=erode)[0]) == expected


@settings(max_examples=30, deadline=None)
@given(
    offset=st.tuples(*[st.floats(-0.9, 0.9)] * 3),
    size=st.tuples(*[st.floats(0.2, 1.5)] * 3),
)
def test_box_overlap_matches_the_exact_product(offset, size):
    a = Cuboid([0, 0, 0], np.eye(3), [1.0, 1.0, 1.0])
    b = Cuboid(offset, np.eye(3), size)
    lo = np.maximum(-0.5, np.array(offset) - 0.5 * np.array(size))
    hi = np.minimum(0.5, np.array(offset) + 0.5 * np.array(size))
    truth = float(np.prod(np.clip(hi - lo, 0, None)))
    v, se, _ = volume(a, b, samples=4096)
    assert abs(v - truth) <= 4 * se + 1e-9


def _eccentric_6x4():
    """NPS 6 x 4 eccentric reducer (OD 168.3 / 114.3 mm, H 140 mm), flat on top, at z = 1."""
    from asbuilt.model import Reducer

    r6, r4 = 0.08415, 0.05715
    return Reducer([0, 0, 1], [0.14, 0, 1 + r6 - r4], r6, r4, offset=[0, 0, r6 - r4])


def test_inside_an_eccentric_reducer_follows_its_oblique_axis():
    g = _eccentric_6x4()
    top = 1 + 0.08415
    points = np.array(
        [
            [0.139, 0, top - 0.001],  # just under the flat top at the small end: inside
            [0.139, 0, 1 - 0.05],  # 50 mm below the large end's axis, at the small end: outside
            [0.001, 0, 1 - 0.08],  # near the bottom of the large end: inside
            [0.07, 0, 1.0 + 0.0135 + 0.07],  # mid-length, 70 mm above the mid axis: inside
            [0.07, 0, 1.0 + 0.0135 - 0.0715],  # 71.5 mm below the mid axis (radius 70.65 mm)
        ]
    )
    assert inside(g, points).tolist() == [True, False, True, True, False]
    from asbuilt.rules.clash import member_ends

    assert member_ends(g) == pytest.approx(np.array([g.start, g.end]))


# Collinear pipes of one size (new-user audit: a pipe scanned twice under two ids, or two runs
# drawn 0.5 m over each other, raised no clash: each one's end lies inside the other, which the
# "ends into" exception took for a joint). NPS 4 (OD 114.3 mm, ASME B36.10M); the joint scale is
# max(1 OD, joint_distance 0.15 m) = 0.15 m.
OD4 = 0.1143


def clashes(*components, config=None):
    return [f for f in check_model(model(*components), config) if f.slug == "clash"]


def test_duplicate_scan_of_one_pipe_is_a_clash_with_a_suggestion():
    a = pipe("P1", [-1.5, 0, 1], [1.5, 0, 1], OD4)
    b = pipe("P2", [-1.5, 0.002, 1], [1.5, 0.002, 1.001], OD4)  # the same pipe, fitted again
    (f,) = clashes(a, b)
    assert f.code == "AB501" and f.severity == "error" and f.objects == ("P1", "P2")
    assert f.unit == "m" and f.measured == pytest.approx(3.0, abs=1e-3)
    assert "same axis" in f.message and "duplicate scan" in f.message
    assert "delete P2 or P1" in f.suggestions[0].description


def test_identical_pipes_whose_ends_touch_are_still_a_duplicate():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], OD4)
    b = pipe("P2", [2, 0, 1], [0, 0, 1], OD4)  # same ends, drawn the other way
    (f,) = clashes(a, b)
    assert f.measured == pytest.approx(2.0)


def test_partial_overlap_of_half_a_metre_is_a_clash():
    a = pipe("P1", [-1.5, 0, 1], [0.25, 0, 1], OD4)
    b = pipe("P2", [-0.25, 0, 1], [1.5, 0, 1], OD4)
    (f,) = clashes(a, b)
    assert f.measured == pytest.approx(0.5)
    assert f.allowed == pytest.approx(0.15)  # joint_distance beats one OD for NPS 4
    assert "P2 overlaps P1 over 0.50 m along the same axis" in f.message
    np.testing.assert_allclose(f.location, [0, 0, 1], atol=1e-9)


def test_short_pipe_wholly_inside_a_longer_one_is_a_clash():
    a = pipe("P1", [-1.5, 0, 1], [1.5, 0, 1], OD4)
    b = pipe("P2", [-0.05, 0, 1], [0.05, 0, 1], OD4)  # 0.1 m: shorter than the joint scale
    (f,) = clashes(a, b)
    assert "P2 lies wholly inside P1" in f.message


def test_butting_ends_are_no_clash():
    a = pipe("P1", [-1.5, 0, 1], [0, 0, 1], OD4)
    b = pipe("P2", [0, 0, 1], [1.5, 0, 1], OD4)
    assert not clashes(a, b)


@pytest.mark.parametrize("enters", [0.01, 0.1, 0.149])
def test_a_pipe_entering_the_next_within_the_joint_scale_is_no_clash(enters):
    a = pipe("P1", [-1.5, 0, 1], [enters, 0, 1], OD4)
    b = pipe("P2", [0, 0, 1], [1.5, 0, 1], OD4)
    assert not clashes(a, b)


def test_the_joint_scale_grows_with_the_diameter():
    od = 0.6096  # NPS 24: a 0.5 m overlap is within one OD (a bell or socket)
    a = pipe("P1", [-3, 0, 1], [0.25, 0, 1], od)
    b = pipe("P2", [-0.25, 0, 1], [3, 0, 1], od)
    assert not clashes(a, b)
    c = pipe("P3", [-0.4, 0, 1], [3, 0, 1], od)  # 0.65 m > 0.6096 m
    (f,) = clashes(a, c)
    assert f.allowed == pytest.approx(od)


def test_parallel_pipes_beside_each_other_are_a_volume_clash_not_a_duplicate():
    a = pipe("P1", [-1.5, 0, 1], [1.5, 0, 1], OD4)
    clear = pipe("P2", [-1.5, 0.2, 1], [1.5, 0.2, 1], OD4)
    assert not clashes(a, clear)
    # axes 70 mm apart (more than a radius: not one axis) and the solids overlap over the whole
    # length: neither end of either member is a joint (each end lies in the other only because
    # its side does), so the overlap is a clash measured in volume, not a duplicate
    beside = pipe("P2", [-1.5, 0.07, 1], [1.5, 0.07, 1], OD4)
    (f,) = clashes(a, beside)
    assert f.severity == "error" and f.unit == "m3" and "duplicate" not in f.message


def test_different_sizes_on_one_axis_are_not_a_duplicate():
    carrier = pipe("P1", [-1.5, 0, 1], [1.5, 0, 1], OD4)
    sleeve = pipe("P2", [-0.1, 0, 1], [0.1, 0, 1], 0.1683)  # NPS 6 sleeve through a wall
    assert all("duplicate" not in f.message for f in clashes(carrier, sleeve))


def test_duplicates_follow_the_clash_selection_and_severity():
    a = pipe("P1", [-1.5, 0, 1], [1.5, 0, 1], OD4)
    b = pipe("P2", [-1.5, 0, 1], [1.5, 0, 1], OD4)
    assert not clashes(a, b, config=loads_rules('ignore = ["clash"]'))
    (f,) = clashes(a, b, config=loads_rules('[clash]\nseverity = "warning"'))
    assert f.severity == "warning"


@pytest.mark.parametrize("kind", ["coupling", "elbow"])
def test_a_fitting_ending_inside_a_pipe_is_a_clash(kind):
    # a beam ending in a column is a connection; a fitting ends only at its ports, so a fitting
    # ending inside a pipe it does not join passes into it (was spared as a connection)
    r = OD4 / 2
    run = pipe("P1", [-1, 0, 1], [1, 0, 1], OD4)
    if kind == "coupling":
        geometry = Straight([0, -0.3, 1], [0, 0.01, 1], r)
    else:
        geometry = Bend([0.152, -0.142, 1], [0, 0.01, 1], [0, -0.142, 1], r)
    fitting = Component(id="F1", type=kind, geometry=geometry)
    (f,) = clashes(run, fitting)
    assert f.code == "AB501" and set(f.objects) == {"P1", "F1"}
    # the same solid as a pipe ending there is a branch framing in: a connection
    stub = pipe("P2", [0, -0.3, 1], [0, 0.01, 1], OD4)
    assert not clashes(run, stub)


@pytest.mark.parametrize(
    "length_se, centre_se, severity",
    [
        # the column's height known to 2 mm: a clash either way
        (0.002, 0.002, "error"),
        # its height (and so its 3-D centre) known to decimetres only, as when the scan window
        # stops short of its top: the faces the pipe passes through are still known to 2 mm
        (0.5, 0.25, "error"),
        # its height a lower bound (shots ran on past the window): infinite standard errors
        (np.inf, np.inf, "error"),
    ],
)
def test_a_pipe_through_a_column_is_a_clash_however_well_its_height_is_known(
    length_se, centre_se, severity
):
    import dataclasses

    from rules_builders import cuboid_fit

    # a 350 x 350 column 4 m high; an NPS 4 pipe straight through its middle
    fit = cuboid_fit([0, 0, 2.0], [0, 0, 1], (0.35, 0.35, 4.0))
    fit = dataclasses.replace(
        fit, stderr={**fit.stderr, "size": (0.002, 0.002, length_se), "center": centre_se}
    )
    col = Component(id="C1", type="cuboid", geometry=fit.primitive, fit=fit)
    through = pipe("P1", [-1.5, 0, 1.5], [1.5, 0, 1.5], 0.1143, center_se=0.002, radius_se=0.001)
    (f,) = [f for f in check_model(model(col, through)) if f.slug == "clash"]
    assert (f.severity, f.unverifiable) == (severity, False), f.message
    # the overlap is the pipe's section over the column's width: pi r^2 x 0.35 m
    assert f.measured == pytest.approx(np.pi * (0.1143 / 2) ** 2 * 0.35, rel=0.03)


def test_the_eroded_faces_of_a_box_are_per_axis():
    box = Cuboid([0, 0, 0], np.eye(3), [1.0, 1.0, 4.0])
    points = np.array([[0.45, 0, 0], [0, 0, 1.9], [0, 0, 1.7]])
    # shrunk 0.1 m across x and y, 0.25 m along z
    assert inside(box, points, erode=np.array([0.1, 0.1, 0.25])).tolist() == [False, False, True]


def test_an_insulated_pipe_clashes_at_its_cladding():
    # crossing pipes 30 mm apart: clear when bare, 20 mm into the other's 50 mm of lagging
    a = pipe("P1", [-1, 0, 1], [1, 0, 1], 0.1143)
    b = pipe("P2", [0, -1, 1.1443], [0, 1, 1.1443], 0.1143)
    assert not [f for f in check_model(model(a, b)) if f.slug == "clash"]
    lagged = dataclasses.replace(b, insulation=0.05)
    (found,) = [f for f in check_model(model(a, lagged)) if f.slug == "clash"]
    assert found.severity == "error" and found.objects == ("P1", "P2")
    assert "(insulation included)" in found.message


# Parallel pipes whose solids pass through each other (independent review 59, defect 2: an NPS 8
# and an NPS 6 with axes 150 mm apart, radii summing to 193.7 mm, gave no clash but an AB304
# weldolet suggestion; the same overlap crossing was an AB501 error). Each end of either lay in
# the other's solid only because its side did, and "a member ending in another" was taken for a
# connection. Outer radii from ASME B36.10M.
R4, R6, R8, R12 = 0.05715, 0.08415, 0.10955, 0.1619


def _lens_area(r1: float, r2: float, d: float) -> float:
    """Area (m2) common to two circles of radii ``r1``, ``r2`` whose centres are ``d`` apart."""
    a1 = r1**2 * np.arccos((d**2 + r1**2 - r2**2) / (2 * d * r1))
    a2 = r2**2 * np.arccos((d**2 + r2**2 - r1**2) / (2 * d * r2))
    kite = 0.5 * np.sqrt((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2))
    return float(a1 + a2 - kite)


def _tank(cid, radius, height):
    """A vertical storage tank (a cylinder kept as one, not a pipe), base at the origin."""
    from rules_builders import cylinder_fit

    fit = cylinder_fit([0, 0, 0.5 * height], [0, 0, 1], radius, height)
    return Component(id=cid, type="cylinder", geometry=fit.primitive, sources=(cid,), fit=fit)


def _parallel_cases():
    """(components, expected clash severity or None, closed-form overlap m3 or None)."""
    big = pipe("P1", [5, -1.1, 1.5], [5, 1.1, 1.5], 2 * R8)
    d = 0.15  # 43.7 mm of interpenetration
    lens = _lens_area(R8, R6, d)
    col = column("C1", [0, 0, 0], height=4.0, section=(0.35, 0.35))
    riser_x = 0.175 + R6  # touching the column's face at x = 0.175
    tilt = 2.2 * np.tan(np.radians(1.0))
    return {
        # clashes: the overlap runs along their length
        "side-by-side": (
            [big, pipe("P2", [5 + d, -1.1, 1.5], [5 + d, 1.1, 1.5], 2 * R6)],
            "error",
            lens * 2.2,
        ),
        "vertical-stack": (
            [big, pipe("P2", [5, -1.1, 1.5 + d], [5, 1.1, 1.5 + d], 2 * R6)],
            "error",
            lens * 2.2,
        ),
        "staggered": (  # side by side over 1 m only, each end beyond the other's
            [big, pipe("P2", [5 + d, 0.1, 1.5], [5 + d, 2.5, 1.5], 2 * R6)],
            "error",
            lens * 1.0,
        ),
        "one-axis-inside-the-other": (  # NPS 4's axis inside NPS 12's solid, walls crossing
            [
                pipe("P1", [5, -1.1, 1.5], [5, 1.1, 1.5], 2 * R12),
                pipe("P2", [5.14, -1.1, 1.5], [5.14, 1.1, 1.5], 2 * R4),
            ],
            "error",
            _lens_area(R12, R4, 0.14) * 2.2,
        ),
        "one-degree-apart": (
            [big, pipe("P2", [5 + d + tilt / 2, -1.1, 1.5], [5 + d - tilt / 2, 1.1, 1.5], 2 * R6)],
            "error",
            None,
        ),
        "riser-30-mm-into-a-column": (
            [col, pipe("P1", [riser_x - 0.03, 0, 0.5], [riser_x - 0.03, 0, 3.5], 2 * R6)],
            "error",
            None,
        ),
        # no clash: apart, touching, joined or nested
        "1-mm-apart": (
            [
                big,
                pipe(
                    "P2", [5 + R8 + R6 + 0.001, -1.1, 1.5], [5 + R8 + R6 + 0.001, 1.1, 1.5], 2 * R6
                ),
            ],
            None,
            None,
        ),
        "touching": (  # no volume in common: touching, below min_volume
            [big, pipe("P2", [5 + R8 + R6, -1.1, 1.5], [5 + R8 + R6, 1.1, 1.5], 2 * R6)],
            None,
            None,
        ),
        "riser-1-mm-off-a-column": (
            [col, pipe("P1", [riser_x + 0.001, 0, 0.5], [riser_x + 0.001, 0, 3.5], 2 * R6)],
            None,
            None,
        ),
        "in-line-butt-weld": (
            [big, pipe("P2", [5, 1.1, 1.5], [5, 3, 1.5], 2 * R8)],
            None,
            None,
        ),
        "in-line-butt-weld-offset-2-mm": (
            [big, pipe("P2", [5.002, 1.1, 1.5], [5.002, 3, 1.5], 2 * R8)],
            None,
            None,
        ),
        "smaller-pipe-entering-a-larger-in-line": (  # 50 mm into its end, on its axis
            [big, pipe("P2", [5, 1.05, 1.5], [5, 3, 1.5], 2 * R6)],
            None,
            None,
        ),
        "carrier-ending-in-a-casing": (  # nested: the casing's bore takes it
            [big, pipe("P2", [5.01, 0.3, 1.5], [5.01, 3, 1.5], 2 * R4)],
            None,
            None,
        ),
        "nozzle-through-a-tank-head": (  # parallel to the tank's axis, within its section
            [_tank("T1", 1.5, 4.0), pipe("N1", [0.8, 0, 3.95], [0.8, 0, 4.5], 2 * R4)],
            None,
            None,
        ),
    }


PARALLEL = _parallel_cases()


@pytest.mark.parametrize("case", list(PARALLEL))
def test_parallel_members_clash_when_their_solids_overlap_along_them(case):
    components, severity, truth = PARALLEL[case]
    found = clashes(*components)
    if severity is None:
        assert not found, found[0].message
        return
    (f,) = found
    assert (f.code, f.severity, f.unverifiable) == ("AB501", severity, False), f.message
    assert f.unit == "m3" and "duplicate" not in f.message
    if truth is not None:  # the lens of the two sections over the length they share
        assert abs(f.measured - truth) < max(3 * f.stderr, 0.03 * truth), (f.measured, truth)


def _square_branch(height: float, end_y: float = 0.0):
    """An NPS 4 run along x at z = 1 and an NPS 4 stub along y ending at ``end_y``, its axis
    ``height`` metres above the run's."""
    run = pipe("P1", [-1, 0, 1], [1, 0, 1], OD4)
    return run, pipe("P2", [0, -1, 1 + height], [0, end_y, 1 + height], OD4)


ANGLED = {
    # crossing pipes 20 mm apart (their axes): an error, as before
    "crossing": ([*_square_branch(0.02, 1.0)], "error"),
    # a square branch ending on the run's axis, its axis meeting the run's: a connection
    "branch-ending-in-the-run": ([*_square_branch(0.0, 0.01)], None),
    # a stub ending over the run, its axis 90 mm above the run's (radii sum 114.3 mm): its side,
    # not its axis, cuts 24 mm into the run, so it does not end in it (was spared as one)
    "stub-ending-beside-the-run": ([*_square_branch(0.09)], "error"),
    # the same stub clear of the run by 1 mm
    "stub-ending-1-mm-over-the-run": ([*_square_branch(OD4 + 0.001)], None),
}


@pytest.mark.parametrize("case", list(ANGLED))
def test_members_at_an_angle_keep_their_verdicts(case):
    components, severity = ANGLED[case]
    found = clashes(*components)
    assert [f.severity for f in found] == ([severity] if severity else []), [
        f.message for f in found
    ]


def test_a_tee_with_its_three_pipes_and_a_parallel_pipe_beside_it():
    """A tee joining three pipes at its ports is no clash; a pipe parallel to the header 1 mm
    clear of it is none either; the same pipe 30 mm into the header is a clash with it."""
    r, c = R6, 0.143  # NPS 6 equal tee, B16.9 C = M = 143 mm
    tee = Component(
        id="T1",
        type="tee",
        geometry=Tee([0, 0, 1], [-c, 0, 1], [c, 0, 1], [0, c, 1], r, r),
    )
    header = [pipe("P1", [-2, 0, 1], [-c, 0, 1], 2 * r), pipe("P2", [c, 0, 1], [2, 0, 1], 2 * r)]
    branch = pipe("P3", [0, c, 1], [0, 2, 1], 2 * r)
    assert not clashes(*header, tee, branch)
    beside = 2 * r + 0.001
    clear = pipe("P4", [-2, -beside, 1], [2, -beside, 1], 2 * r)
    assert not clashes(*header, tee, branch, clear)
    into = pipe("P4", [-2, -beside + 0.031, 1], [2, -beside + 0.031, 1], 2 * r)
    found = clashes(*header, tee, branch, into)
    assert {f.objects for f in found} >= {("P1", "P4"), ("P2", "P4")}
    assert all(f.severity == "error" for f in found)


def test_parallel_pipes_clash_at_their_insulation():
    """Clear of each other by 20 mm when bare; 50 mm of lagging on one takes up 30 mm of it."""
    a = pipe("P1", [-1.5, 0, 1], [1.5, 0, 1], OD4)
    b = pipe("P2", [-1.5, OD4 + 0.02, 1], [1.5, OD4 + 0.02, 1], OD4)
    assert not clashes(a, b)
    (f,) = clashes(a, dataclasses.replace(b, insulation=0.05))
    assert f.severity == "error" and "(insulation included)" in f.message
    assert not clashes(a, dataclasses.replace(b, insulation=0.019))
