"""Alignment rules: limits computed by hand from AISC 303 (H/500), ACI 117-10 and IPC 704.1."""

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from rules_builders import B36, column, model, pipe, tilted

from asbuilt.fit.result import rotation_covariance
from asbuilt.pipeline import build_model
from asbuilt.primitives import Cuboid
from asbuilt.rules import check_model, load_rules, loads_rules
from asbuilt.rules.alignment import tilt_components
from asbuilt.scan.load import loads_scan


def only(findings, slug):
    return [f for f in findings if f.slug == slug]


def run(*components, config=None):
    return check_model(model(*components), config or load_rules(), catalog=B36)


# -- out-of-plumb --------------------------------------------------------------------------------

H = 3.0
STEEL = H / 500  # 6 mm


def lean_deg(lean_m, height=H):
    return float(np.degrees(np.arctan(lean_m / height)))


@pytest.mark.parametrize(
    "lean_m, axes_deg, expected",
    [
        (0.0, 0.02, None),  # plumb, well measured
        (0.005, 0.02, None),  # 5 mm < 6 mm
        (0.0069, 0.02, "unverifiable"),  # over by 0.9 mm < 2 x 1.05 mm
        (0.0085, 0.02, "error"),  # over by 2.5 mm > 2 x 1.05 mm
        (0.0, 0.1, "unverifiable"),  # +-5.2 mm: cannot resolve 6 mm (the paper's sparse case)
        (0.030, 0.1, "error"),  # a clear 1:100 lean is an error even from a sparse scan
    ],
)
def test_steel_column_plumb_edges(lean_m, axes_deg, expected):
    comp = column("C1", [0, 0, 0], lean_deg(lean_m), H, axes_deg=axes_deg)
    found = only(run(comp), "out-of-plumb")
    if expected is None:
        assert not found
        return
    (f,) = found
    assert f.measured == pytest.approx(lean_m, abs=1e-9)
    assert f.allowed == pytest.approx(STEEL)
    assert f.stderr == pytest.approx(H * np.radians(axes_deg))
    assert f.unit == "m"
    if expected == "error":
        assert f.severity == "error" and not f.unverifiable
        assert "1:500" in f.message and "AISC 303" in f.message
    else:
        assert f.severity == "warning" and f.unverifiable
        assert f.message.startswith("cannot verify out-of-plumb:")
        assert "second face" in f.suggestions[0].description


@pytest.mark.parametrize(
    "label, height, lean_m, allowed",
    [
        ("concrete column", 3.0, 0.0085, 0.009),  # 0.3% x 3 m = 9 mm: passes where steel fails
        ("RC pier", 12.0, 0.026, 0.025),  # 0.3% x 12 m = 36 mm, capped at 25 mm
        ("steel HSS", 3.0, 0.0085, 0.006),
    ],
)
def test_material_from_label(label, height, lean_m, allowed):
    comp = column("C1", [0, 0, 0], lean_deg(lean_m, height), height, axes_deg=0.001, label=label)
    found = only(run(comp), "out-of-plumb")
    if lean_m <= allowed:
        assert not found
    else:
        assert found[0].allowed == pytest.approx(allowed)


def test_default_material_from_rules_file():
    comp = column("C1", [0, 0, 0], lean_deg(0.0085), H, axes_deg=0.001)
    config = loads_rules('[general]\ndefault_material = "concrete"')
    assert not only(run(comp, config=config), "out-of-plumb")


def test_plumb_uses_the_measured_axis_not_the_regularised_one():
    from dataclasses import replace

    from asbuilt.primitives import Cuboid

    comp = column("C1", [0, 0, 0], lean_deg(0.02), H, axes_deg=0.01)
    snapped = Cuboid(center=[0, 0, 1.5], axes=np.eye(3), size=[0.3, 0.3, H])
    comp = replace(comp, geometry=snapped)  # merging made it vertical; the fit still leans
    assert only(run(comp), "out-of-plumb")[0].severity == "error"


def test_far_off_vertical_is_not_a_column():
    comp = column("C1", [0, 0, 0], 30.0, H, axes_deg=0.01)
    assert not only(run(comp), "out-of-plumb")


def test_vertical_pipe_reports_only_clear_leans():
    stub = pipe("P1", [0, 0, 0], [0, 0.0, 1.0], 0.1143, axis_deg=0.3)  # unresolvable
    bent = pipe("P2", [1, 0, 0], [1.05, 0, 1.0], 0.1143, axis_deg=0.3)  # 50 mm in 1 m
    found = only(run(stub, bent), "out-of-plumb")
    assert [f.objects for f in found] == [("P2",)]


# -- misaligned-axis -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    "angle, expected",
    [(1.0, None), (1.99, None), (3.0, "warning"), (9.9, "warning"), (10.5, None), (45.0, None)],
)
def test_misaligned_off_vertical(angle, expected):
    comp = column("C1", [0, 0, 0], angle, H, axes_deg=0.05)
    found = only(run(comp), "misaligned-axis")
    if expected is None:
        assert not found
    else:
        (f,) = found
        assert f.measured == pytest.approx(angle)
        assert "off vertical" in f.message
        # measured to 0.05 degree: a lean that was built, which --fix alone must not undo
        assert not f.suggestions[0].unambiguous
        assert f.suggestions[0].change["field"] == "rotation"


@pytest.mark.parametrize(
    "angle, axes_deg, unambiguous",
    [(3.0, 0.05, False), (3.0, 0.9, False), (3.0, 1.1, True), (6.0, 1.9, False), (6.0, 2.1, True)],
)
def test_a_free_components_rotation_is_automatic_only_within_three_standard_errors(
    angle, axes_deg, unambiguous
):
    # merging's rule (asbuilt.merge.regularize.SNAP_SIGMA = 3): beyond three standard errors
    # the deviation is measured, not noise
    (f,) = only(run(column("C1", [0, 0, 0], angle, H, axes_deg=axes_deg)), "misaligned-axis")
    assert f.suggestions[-1].change["field"] == "rotation"
    assert f.suggestions[-1].unambiguous is unambiguous


def test_misaligned_uncertain_angle_is_unverifiable():
    comp = column("C1", [0, 0, 0], 2.5, H, axes_deg=0.5)
    (f,) = only(run(comp), "misaligned-axis")
    assert f.unverifiable


def test_misaligned_off_horizontal():
    end = np.array([3 * np.cos(np.radians(4)), 0, 1 + 3 * np.sin(np.radians(4))])
    (f,) = only(run(pipe("P1", [0, 0, 1], end, 0.1143, axis_deg=0.1)), "misaligned-axis")
    assert "off horizontal" in f.message and f.measured == pytest.approx(4.0)


def test_misaligned_in_plan_between_joined_pipes():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", axis_deg=0.1)
    t = np.radians(86.0)
    b = pipe(
        "P2",
        [2.05, 0, 1],
        [2.05 + 2 * np.cos(t), 2 * np.sin(t), 1],
        0.1143,
        nominal="4",
        axis_deg=0.1,
    )
    (f,) = only(run(a, b), "misaligned-axis")
    assert f.objects == ("P1", "P2")
    assert f.measured == pytest.approx(4.0)
    assert "plan" in f.message


def test_in_plan_check_can_be_switched_off():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", axis_deg=0.1)
    t = np.radians(86.0)
    b = pipe("P2", [2.05, 0, 1], [2.05 + 2 * np.cos(t), 2 * np.sin(t), 1], 0.1143, nominal="4")
    config = loads_rules("[misaligned-axis]\ncompare_in_plan = false")
    assert not only(run(a, b, config=config), "misaligned-axis")


def test_snap_tolerance_comes_from_the_rules_file():
    comp = column("C1", [0, 0, 0], 3.0, H, axes_deg=0.05)
    config = loads_rules("[general]\nangle_snap_deg = 4.0")
    assert not only(run(comp, config=config), "misaligned-axis")


# -- slope ---------------------------------------------------------------------------------------


def sloped(cid, slope, nominal="4", axis_deg=0.02, label=None):
    length = 4.0
    return pipe(
        cid,
        [0, 0, 1],
        [length, 0, 1 + slope * length],
        0.1143,
        nominal=nominal,
        axis_deg=axis_deg,
        label=label,
    )


def test_slope_is_silent_without_a_spec():
    assert not only(run(sloped("P1", 0.0)), "slope")


@pytest.mark.parametrize(
    "slope, axis_deg, expected",
    [
        (0.012, 0.02, None),
        (0.010, 0.02, None),
        (0.0095, 0.02, "unverifiable"),
        (0.005, 0.02, "error"),
        (0.020, 0.5, "unverifiable"),  # 2 x 8.7 mm/m > 10 mm/m: cannot verify 1%
    ],
)
def test_required_slope(slope, axis_deg, expected):
    config = loads_rules("[slope]\nrequired = 0.01")
    found = only(run(sloped("P1", slope, axis_deg=axis_deg), config=config), "slope")
    if expected is None:
        assert not found
    else:
        (f,) = found
        assert f.unverifiable == (expected == "unverifiable")
        assert f.measured == pytest.approx(slope, rel=1e-6)


@pytest.mark.parametrize(
    "nominal, slope, flagged",
    [("2", 0.015, True), ("4", 0.015, False), ("8", 0.006, False), ("8", 0.003, True)],
)
def test_ipc_704_by_size(nominal, slope, flagged):
    config = loads_rules("[slope]\nuse_ipc_704 = true")
    found = only(run(sloped("P1", slope, nominal=nominal), config=config), "slope")
    assert bool(found) == flagged


def test_slope_keywords_limit_the_rule_to_drains():
    config = loads_rules('[slope]\nrequired = 0.01\nkeywords = ["drain"]')
    pipes = [
        sloped("P1", 0.0),
        sloped("P2", 0.0, label="drain line"),
        sloped("P3", 0.0, label="raindrain"),  # a word of its own, not "drain"
        sloped("P4", 0.0, label="vent header (no drainage slope)"),
        sloped("P5", 0.0, label="roof-drain 2"),
    ]
    found = only(run(*pipes, config=config), "slope")
    assert [f.objects for f in found] == [("P2",), ("P5",)]


@pytest.mark.parametrize(
    "slope, axis_deg, message",
    [
        (0.005, 0.02, "slope 0.50% (known to +- 0.03%) is below the required drainage slope 1.00%"),
        # at least the required slope, but known too loosely to say so: not "below"
        (0.012, 0.3, "slope 1.20% (known to +- 0.52%) cannot be told from the required drainage"),
    ],
)
def test_slope_messages_say_what_the_numbers_say(slope, axis_deg, message):
    config = loads_rules("[slope]\nrequired = 0.01")
    (f,) = only(run(sloped("P1", slope, axis_deg=axis_deg), config=config), "slope")
    assert message in f.message  # an unverifiable one is prefixed "cannot verify slope: "
    assert f.message.endswith("(the rules file's slope.required)")


def test_tilted_helper_is_a_unit_vector():
    assert np.linalg.norm(tilted(3.0, 40.0)) == pytest.approx(1.0)


@pytest.mark.parametrize("axis_deg, merge_again", [(0.1, False), (1.5, True)])
def test_plan_misalignment_through_an_elbow_is_found_but_not_auto_fixed(axis_deg, merge_again):
    from asbuilt.model import Bend, Component

    t = np.radians(94.0)  # the second pipe turns 94 degrees instead of 90
    r = 0.152
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", axis_deg=axis_deg)
    d = np.array([np.cos(t), np.sin(t), 0.0])
    # a bend of radius r from P1's end turning through t onto P2's direction
    bend_centre = np.array([2.0, r, 1.0])
    bend_end = bend_centre + r * np.array([np.sin(t), -np.cos(t), 0.0])
    elbow = Component(
        id="E1", type="elbow", geometry=Bend([2, 0, 1], bend_end, bend_centre, 0.1143 / 2)
    )
    b = pipe("P2", bend_end, bend_end + 2 * d, 0.1143, nominal="4", axis_deg=axis_deg)
    (f,) = only(run(a, elbow, b), "misaligned-axis")
    assert f.objects == ("P1", "P2") and f.measured == pytest.approx(4.0)
    assert not any(s.unambiguous for s in f.suggestions)
    # merging regularises within 3 combined standard errors whatever the snap angle: at 0.14
    # degrees combined, 4 degrees is measured and a larger angle_snap_deg would change nothing
    advice = [s.description for s in f.suggestions if "angle_snap_deg" in s.description]
    assert advice == (
        [
            "if it is meant to be regular, merge again with [general] angle_snap_deg = "
            "5 (now 2) so merging regularises it and rebuilds its joints"
        ]
        if merge_again
        else []
    )
    assert "turn P2 4" in f.suggestions[-1].description


def test_pieces_of_one_fitted_pipe_give_one_plumb_finding():
    from dataclasses import replace

    from asbuilt.model import Straight

    whole = pipe("P1", [0, 0, 0], [0.1, 0, 2.0], 0.1143, axis_deg=0.05)  # 50 mm in 1 m
    lower = replace(whole, id="P1a", geometry=Straight([0, 0, 0], [0.05, 0, 1.0], 0.05715))
    upper = replace(whole, id="P1b", geometry=Straight([0.05, 0, 1.0], [0.1, 0, 2.0], 0.05715))
    (f,) = only(run(lower, upper), "out-of-plumb")
    assert f.objects == ("P1a", "P1b")


@pytest.mark.parametrize(
    "label, allowed, standard",
    [
        ("concrete column", 0.003 * 3.96, "ACI 117-10"),  # 11.9 mm: an 11.5 mm lean passes
        ("steel column", 3.96 / 500, "AISC 303-16"),  # 7.9 mm
        ("round pier", 0.003 * 3.96, "ACI 117-10"),  # a concrete keyword names a column too
        ("carbon steel riser", 3.96 / 500, "pipe_ratio"),  # a steel pipe stays a pipe
    ],
)
def test_round_columns_are_judged_as_columns_of_their_material(label, allowed, standard):
    # A cylinder leaning 11.5 mm and 20 mm over 3.96 m, well measured.
    for lean in (0.0115, 0.020):
        comp = pipe("C1", [0, 0, 0], [lean, 0, 3.96], 0.3, axis_deg=0.001, label=label)
        found = only(run(comp), "out-of-plumb")
        if lean <= allowed:
            assert not found
            continue
        (f,) = found
        assert f.allowed == pytest.approx(allowed, rel=1e-3)
        assert standard in f.message


# The cuboid fit's stderr["axes_deg"] may be one value or one per axis of the primitive (the lead's
# change: the angular standard error of each axis's direction, degrees, in the order of
# Cuboid.axes). The plumb rule must use the long (vertical) axis's own value: by hand, a 8.5 mm
# lean over 3 m is over the 6 mm limit by 2.5 mm; the long axis's 0.02 deg is +-1.05 mm (error),
# the short axes' 0.5 deg would be +-26 mm (unverifiable).
@pytest.mark.parametrize("long_index", [0, 1, 2])
def test_plumb_uses_the_long_axis_standard_error_of_a_per_axis_tuple(long_index):
    base = column("C1", [0, 0, 0], lean_deg(0.0085), H)
    prim = base.fit.primitive
    order = [0, 1]
    order.insert(long_index, 2)  # where the long axis (row 2 of the builder's) goes
    moved = Cuboid(
        center=prim.center, axes=np.asarray(prim.axes)[order], size=np.asarray(prim.size)[order]
    )
    per_axis = [0.5, 0.5, 0.5]
    per_axis[long_index] = 0.02
    fit = dataclasses.replace(
        base.fit, primitive=moved, stderr={**base.fit.stderr, "axes_deg": tuple(per_axis)}
    )
    comp = dataclasses.replace(base, geometry=moved, fit=fit)
    (f,) = only(run(comp), "out-of-plumb")
    assert f.measured == pytest.approx(0.0085, abs=1e-9)
    assert f.stderr == pytest.approx(H * np.radians(0.02))
    assert f.severity == "error" and not f.unverifiable


def test_plumb_accepts_a_scalar_and_a_list_of_axes_deg_alike():
    scalar = column("C1", [0, 0, 0], lean_deg(0.0069), H, axes_deg=0.02)
    listed = column("C1", [0, 0, 0], lean_deg(0.0069), H, axes_deg=[0.02, 0.02, 0.02])
    (a,) = only(run(scalar), "out-of-plumb")
    (b,) = only(run(listed), "out-of-plumb")
    assert a.stderr == pytest.approx(b.stderr) == pytest.approx(H * np.radians(0.02))
    assert a.unverifiable and b.unverifiable


@pytest.mark.parametrize(
    "nominal, slope, flagged", [("50", 0.015, True), ("150", 0.008, True), ("200", 0.006, False)]
)
def test_ipc_704_by_the_nps_of_a_dn_size(nominal, slope, flagged):
    # EN 10220's DN 50 / 150 / 200 are NPS 2 / 6 / 8: 2%, 1% and 0.5% (IPC 704.1). The bare DN
    # number was read as an NPS, so DN 150 asked only 0.5% and DN 50 1%.
    config = loads_rules("[slope]\nuse_ipc_704 = true")
    pipe_ = sloped("P1", slope, nominal=nominal)
    found = check_model(model(pipe_), config, catalog="en-10220")
    assert bool(only(found, "slope")) == flagged


def test_a_lean_just_over_the_limit_never_reads_as_equal_to_it():
    # 6.01 mm over 3 m (allowed 6.0 mm) read "leans 6.0 mm ..., allowed 6.0 mm"
    comp = column("C1", [0, 0, 0], lean_deg(STEEL + 0.00001), H, axes_deg=0.00001)
    (f,) = only(run(comp), "out-of-plumb")
    assert f.severity == "error"
    assert f.message.startswith("leans 6.01 mm over 3.00 m (1:499), allowed 6.00 mm (1:500")


@pytest.mark.parametrize(
    "lean_mm, se_mm, default, silenced",
    [
        # a steel column 3 m high, allowed 3000 / 500 = 6 mm (AISC 303-16 7.13.1.1)
        (7.0, 2.0, ("warning", True), None),  # over the limit, but within 2 s of it
        (1.0, 4.0, ("warning", True), None),  # 2 s = 8 mm: the scan cannot resolve 6 mm
        (20.0, 1.0, ("error", False), ("error", False)),  # a violation is never silenced
        (2.0, 1.0, None, None),  # a pass
    ],
)
def test_report_unverifiable_false_silences_every_unverifiable_finding(
    lean_mm, se_mm, default, silenced
):
    angle = float(np.degrees(np.arctan(lean_mm / 3000.0)))
    built = model(column("C1", [0, 0, 0], angle, 3.0, axes_deg=np.degrees(se_mm / 3000.0)))

    def plumb(config):
        found = [f for f in check_model(built, config) if f.slug == "out-of-plumb"]
        return (found[0].severity, found[0].unverifiable) if found else None

    assert plumb(load_rules()) == default
    assert plumb(loads_rules("[general]\nreport_unverifiable = false")) == silenced


def _tank(label, lean, height=12.0, *, group=None, kind="cylinder", axis_deg=0.001):
    """A 6 m storage tank leaning ``lean`` metres over ``height``, kept as a cylinder."""
    comp = pipe("T1", [0, 0, 0], [lean, 0, height], 6.0, axis_deg=axis_deg, label=label)
    return dataclasses.replace(comp, type=kind, group=group)


@pytest.mark.parametrize("label", ["crude tank", "TK-101", "tk101", "Tank-2A", "TANKS"])
def test_storage_tanks_are_judged_by_api_650(label):
    # API 650 7.5.2: 1/200 of the height, 60 mm over 12 m; a 50 mm lean passes, 70 mm does not
    # (against the pipe limit of 1/500, 24 mm, both would fail).
    assert not only(run(_tank(label, 0.050)), "out-of-plumb")
    (f,) = only(run(_tank(label, 0.070)), "out-of-plumb")
    assert f.allowed == pytest.approx(12.0 / 200, rel=1e-3)
    assert "(1:200, API 650 7.5.2)" in f.message
    assert f.severity == "error"


@pytest.mark.parametrize(
    "label, group, kind, allowed",
    [
        ("TK-101", None, "pipe", 12.0 / 500),  # a merged pipe is no tank, whatever it says
        ("4in-TK-101 fill", None, "cylinder", 12.0 / 500),  # the tag inside a line's name
        ("tanker bay", None, "cylinder", 12.0 / 500),  # not the word
        ("shell", "tank farm", "cylinder", 12.0 / 200),  # the group names it
    ],
)
def test_what_is_a_tank(label, group, kind, allowed):
    (f,) = only(run(_tank(label, 0.100, group=group, kind=kind)), "out-of-plumb")
    assert f.allowed == pytest.approx(allowed, rel=1e-3)


def test_tank_keywords_and_ratio_come_from_the_rules_file():
    config = loads_rules('[general]\ntank_keywords = ["silo"]\n[out-of-plumb]\ntank_ratio = 400')
    (f,) = only(run(_tank("cement silo", 0.050), config=config), "out-of-plumb")
    assert f.allowed == pytest.approx(12.0 / 400, rel=1e-3)
    (f,) = only(run(_tank("crude tank", 0.050), config=config), "out-of-plumb")
    assert f.allowed == pytest.approx(12.0 / 500, rel=1e-3)  # no longer a tank: the pipe limit


def test_a_tank_lean_the_shots_cannot_resolve_is_reported_unverifiable():
    # Unlike a pipe (no standard: only clear leans), a tank has a limit to verify.
    (f,) = only(run(_tank("TK-7", 0.065, axis_deg=0.3)), "out-of-plumb")
    assert f.unverifiable


# -- out-of-plumb, per direction: a box column seen on one face ---------------------------------
# One seen face measures the column's tilt across it (toward the station) to a few hundredths of
# a degree and its turn in the face's plane to degrees. The fit gives the rotation's covariance
# in its axes' frame (diagnostics rotation_deg_* / rotation_corr_*); the rule judges the lean per
# direction. By hand, H = 3 m, steel allows 6 mm: a 1:100 lean is 30 mm; across the face its
# standard error is 3 m x 0.03 deg = 1.6 mm (counted sqrt(2) times: 2.2 mm; 30 - 2 x 2.2 = 25.6
# mm > 6 mm, an error), sideways 3 m x 5.6 deg = 293 mm (30 mm is nothing beside it).


def one_face_column(lean_ratio, toward, rotation_deg=(0.03, 5.6, 0.17), assumed=1):
    """A 3 m steel column, axes x, y, z, leaning 1:``lean_ratio`` toward axis ``toward`` (0 or
    1); axis ``assumed`` is the seen face's normal (its depth assumed)."""
    lean = 0.0 if lean_ratio is None else 1.0 / lean_ratio
    axis = np.array([0.0, 0.0, 1.0])
    axis[toward] = lean
    axis /= np.linalg.norm(axis)
    comp = column("C1", [0, 0, 0], height=H)
    e0 = np.array([1.0, 0.0, 0.0]) if toward == 1 else np.cross([0.0, 1.0, 0.0], axis)
    e0 = e0 - (e0 @ axis) * axis
    e0 /= np.linalg.norm(e0)
    axes = np.array([e0, np.cross(axis, e0), axis])
    prim = Cuboid(center=0.5 * H * axis, axes=axes, size=(0.3, 0.3, H))
    total = float(np.hypot(rotation_deg[0], rotation_deg[1]))  # the long axis's direction error
    diagnostics = {
        "faces": 1.0,
        "rotation_deg_0": rotation_deg[0],
        "rotation_deg_1": rotation_deg[1],
        "rotation_deg_2": rotation_deg[2],
        "rotation_corr_01": 0.0,
        "rotation_corr_02": 0.0,
        "rotation_corr_12": 0.0,
    }
    if assumed is not None:
        diagnostics["assumed_size"] = float(assumed)
    fit = dataclasses.replace(
        comp.fit,
        primitive=prim,
        stderr={**comp.fit.stderr, "axes_deg": (5.6, 0.17, total)},
        diagnostics=diagnostics,
    )
    return dataclasses.replace(comp, geometry=prim, fit=fit)


@pytest.mark.parametrize(
    "lean_ratio, toward, severity, words",
    [
        (100, 1, "error", "toward the station (across its one seen face) alone it leans 30.0 mm"),
        (50, 1, "error", "toward the station (across its one seen face) alone it leans 60.0 mm"),
        (400, 1, "warning", "toward the station it leans 7.5 mm +- 1.6 mm (1:400)"),
        (100, 0, "warning", "the sideways lean, along the face, is not measured (known to +- 29"),
        (None, 1, "warning", "plumb toward the station to 1:675 (4.4 mm at most)"),
        (2000, 1, "warning", "plumb toward the station to 1:505 (5.9 mm at most)"),
    ],
)
def test_a_one_face_column_is_judged_by_the_direction_it_measured(
    lean_ratio, toward, severity, words
):
    (f,) = only(run(one_face_column(lean_ratio, toward)), "out-of-plumb")
    assert f.severity == severity
    assert words in f.message
    if severity == "error":
        # the verdict's standard error: the component's, counted sqrt(2) times
        assert f.stderr == pytest.approx(np.sqrt(2) * H * np.radians(0.03), rel=1e-3)
        assert f.measured - 2 * f.stderr > f.allowed
    else:
        assert f.message.startswith("cannot verify out-of-plumb:")


@pytest.mark.parametrize("lean_mm", [0.0, 4.0, 8.0, 12.0, 16.0, 20.0, 30.0])
@pytest.mark.parametrize("toward", [0, 1])
def test_a_column_known_alike_in_every_direction_is_judged_as_before(lean_mm, toward):
    # Rotation errors of 0.1 deg about both horizontal axes: the long axis's error is their
    # root sum of squares, 0.141 deg (7.4 mm over 3 m), the whole lean's as before; each
    # direction's 0.1 deg counted sqrt(2) times is the same, so no verdict changes.
    ratio = None if lean_mm == 0 else H * 1000 / lean_mm
    comp = one_face_column(ratio, toward, rotation_deg=(0.1, 0.1, 0.1), assumed=None)
    old = dataclasses.replace(comp, fit=dataclasses.replace(comp.fit, diagnostics={"faces": 2.0}))
    new_f, old_f = only(run(comp), "out-of-plumb"), only(run(old), "out-of-plumb")
    assert [(f.severity, f.message) for f in new_f] == [(f.severity, f.message) for f in old_f]


_SCENES = json.loads((Path(__file__).parent / "one_face_columns.json").read_text())


@pytest.mark.parametrize("name", sorted(_SCENES))
def test_review_columns_seen_on_one_face(name):
    """An independent review's ray-cast box columns seen face-on (/tmp/review61, scenes 00-16;
    its own ray caster, 2 mm and 0.01 degree noise): leans along the face's normal are errors,
    leans in the face's plane and plumb columns are 'cannot verify' warnings that say what was
    measured. The truth axis is the review's; the component the fit measured best must agree
    with the truth's along that direction within 3 of its standard errors."""
    case = _SCENES[name]
    scan = loads_scan(json.dumps(case["scan"]))
    built = build_model(scan)
    (comp,) = built.components
    found = only(check_model(built, load_rules()), "out-of-plumb")
    (f,) = found
    components, variances, across = tilt_components(comp)
    assert across
    truth = np.asarray(case["truth_axis"])
    fitted = comp.fit.primitive
    axes = np.asarray(fitted.axes)
    long = int(np.argmax(fitted.size))
    others = [k for k in range(3) if k != long]
    # the truth's tilt toward the fit's other axes, along the same principal directions
    truth_c = np.array([-(axes[k] - (axes[k] @ truth) * truth) @ [0, 0, 1.0] for k in others])
    jac = np.array([-(axes @ np.cross(axes[k], [0, 0, 1.0])) for k in others])
    cov = jac @ rotation_covariance(comp.fit.diagnostics) @ jac.T
    directions = np.linalg.eigh(0.5 * (cov + cov.T))[1]
    truth_best = float(directions[:, 0] @ truth_c)
    assert abs(abs(components[0]) - abs(truth_best)) < 3 * np.sqrt(variances[0]) + 2e-4
    if case["expected"] == "error":
        assert f.severity == "error"
        assert "toward the station (across its one seen face) alone it leans" in f.message
    else:
        assert f.severity == "warning" and f.message.startswith("cannot verify out-of-plumb:")
        assert "the sideways lean, along the face, is not measured" in f.message
    if case["expected"] == "plumb":
        assert "plumb toward the station to 1:" in f.message
