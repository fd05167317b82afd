"""--fix semantics: accept every unambiguous suggestion; re-checking finds none of what it fixed."""

import numpy as np
import pytest
from rules_builders import B36, column, model, pipe
from test_sizes import scan_with_hint

from asbuilt.rules import apply_fixes, apply_suggestions, check_model, choose_suggestions
from asbuilt.rules.fixes import rotate_geometry


def slugs(findings):
    return sorted(f.slug for f in findings)


def fix_and_recheck(built):
    before = check_model(built, catalog=B36)
    fixed, changes = apply_fixes(built, before)
    after = check_model(fixed, catalog=B36)
    return before, fixed, changes, after


def accept_and_recheck(built, *choices):
    """As --accept CHOICE --fix: apply exactly the suggestions chosen."""
    before = check_model(built, catalog=B36)
    fixed, changes = apply_suggestions(built, choose_suggestions(before, choices))
    after = check_model(fixed, catalog=B36)
    return before, fixed, changes, after


@pytest.mark.parametrize("angle", [3.0, 6.0, 9.0])
def test_misaligned_column_is_made_vertical(angle):
    built = model(column("C1", [0, 0, 0], angle, 3.0, axes_deg=0.05))
    # a measured lean (60-180 standard errors) is not undone by accepting everything
    assert fix_and_recheck(built)[2] == []
    before, fixed, changes, after = accept_and_recheck(built, "misaligned-axis@C1")
    assert "misaligned-axis" in slugs(before)
    assert "misaligned-axis" not in slugs(after)
    geom = fixed.component("C1").geometry
    long_axis = geom.axes[int(np.argmax(geom.size))]
    assert abs(long_axis[2]) == pytest.approx(1.0)
    np.testing.assert_allclose(geom.center, built.component("C1").geometry.center)
    assert len(changes) == 1 and changes[0].startswith("C1: make C1's axis vertical")
    (corr,) = fixed.component("C1").corrections
    assert corr.size == pytest.approx(angle) and corr.unit == "deg"
    # the column still leans as measured: the fix changed the model, not the measurement
    assert "out-of-plumb" in slugs(after)


def test_misaligned_horizontal_pipe_is_levelled():
    t = np.radians(5)
    built = model(
        pipe(
            "P1",
            [0, 0, 1],
            [2 * np.cos(t), 0, 1 + 2 * np.sin(t)],
            0.1143,
            nominal="4",
            axis_deg=0.1,
        )
    )
    assert fix_and_recheck(built)[2] == []  # 5 degrees measured to 0.1: as built
    before, fixed, _, after = accept_and_recheck(built, "AB201@P1")
    assert "misaligned-axis" in slugs(before) and "misaligned-axis" not in slugs(after)
    geom = fixed.component("P1").geometry
    assert geom.start[2] == pytest.approx(geom.end[2])
    assert geom.length == pytest.approx(2.0)


def test_plan_misalignment_is_fixed():
    t = np.radians(85.0)
    built = model(
        pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", axis_deg=0.1),
        pipe(
            "P2",
            [2.05, 0, 1],
            [2.05 + 2 * np.cos(t), 2 * np.sin(t), 1],
            0.1143,
            nominal="4",
            axis_deg=0.1,
        ),
    )
    before, fixed, _, after = accept_and_recheck(built, "AB201@P1,P2")
    assert "misaligned-axis" in slugs(before) and "misaligned-axis" not in slugs(after)
    np.testing.assert_allclose(fixed.component("P2").geometry.direction, [0, 1, 0], atol=1e-9)


def test_contiguous_size_is_shared():
    built = model(
        pipe(
            "P1",
            [0, 0, 1],
            [2, 0, 1],
            0.1143,
            nominal="4",
            od_fit=0.1146,
            status="snapped",
            od_stderr=0.0004,
        ),
        pipe(
            "P2",
            [2.05, 0, 1],
            [4, 0, 1],
            0.0889,
            nominal="3",
            od_fit=0.1010,  # a poor fit: its window (15 mm) holds NPS 3 and the shared NPS 4
            status="snapped",
            od_stderr=0.005,
        ),
    )
    before, fixed, changes, after = fix_and_recheck(built)
    assert "contiguous-diameter-mismatch" in slugs(before)
    assert "contiguous-diameter-mismatch" not in slugs(after)
    p2 = fixed.component("P2")
    assert p2.nominal == "4" and 2 * p2.geometry.outer_radius == pytest.approx(0.1143)
    assert p2.snap["status"] == "snapped"
    assert any("P2" in c and "NPS 4" in c for c in changes)


def test_hint_mismatch_fix_keeps_the_fitted_size():
    built = model(pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143), scan=scan_with_hint("P1", '3"'))
    before, fixed, _, after = fix_and_recheck(built)
    assert "hint-mismatch" in slugs(before) and "hint-mismatch" not in slugs(after)
    assert fixed.component("P1").nominal == "4"
    assert fixed.component("P1").snap["hint_rejected"] is True


def test_hint_mismatch_fix_leaves_an_insulated_pipe_alone():
    """A 4" pipe under 50 mm of lagging fits NPS 8: the hint stays, and so does the warning."""
    built = model(pipe("P1", [0, 0, 1], [2, 0, 1], 0.2191), scan=scan_with_hint("P1", '4"'))
    before, fixed, changes, after = fix_and_recheck(built)
    assert "hint-mismatch" in slugs(before) and "hint-mismatch" in slugs(after)
    assert changes == []
    assert not (fixed.component("P1").snap or {}).get("hint_rejected")


def test_ambiguous_suggestions_are_not_applied():
    built = model(pipe("P3", [0, 0, 1], [2, 0, 1], 0.1182, status="no-size"))
    before, fixed, changes, after = fix_and_recheck(built)
    assert changes == []
    assert slugs(before) == slugs(after)
    assert fixed.component("P3").nominal is None


def test_rotation_is_rigid():
    from asbuilt.model import Bend

    bend = Bend([1, 0, 0], [0, 1, 0], [0, 0, 0], 0.05)
    t = np.radians(30)
    r = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    turned = rotate_geometry(bend, r, [0, 0, 0])
    assert turned.bend_radius == pytest.approx(1.0)
    assert turned.angle_deg == pytest.approx(90.0)
    np.testing.assert_allclose(turned.start, [np.cos(t), np.sin(t), 0])


def test_rotating_an_eccentric_reducer_turns_its_offset():
    from asbuilt.model import Reducer

    r6, r4 = 0.08415, 0.05715
    g = Reducer([0, 0, 1], [0.14, 0, 1 + r6 - r4], r6, r4, offset=[0, 0, r6 - r4])
    quarter = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # 90 degrees about x
    turned = rotate_geometry(g, quarter, [0, 0, 1])
    assert turned.offset == pytest.approx([0, -(r6 - r4), 0])
    assert turned.end == pytest.approx([0.14, -(r6 - r4), 1])
    assert turned.direction == pytest.approx([1, 0, 0])
    assert turned.flat_side == pytest.approx([0, -1, 0])


def test_size_fix_takes_the_new_sizes_wall():
    """A pipe re-sized by --fix gets the catalog's wall of its new size and schedule, not the
    wall of the size it had: an NPS 3 STD pipe made NPS 4 has NPS 4 STD's 6.02 mm wall (its old
    5.49 mm one gave the take-off a wrong weight and the exports a wrong bore)."""
    import dataclasses

    def with_wall(component, wall):
        g = dataclasses.replace(component.geometry, wall=wall)
        return dataclasses.replace(component, geometry=g, schedule="STD")

    built = model(
        with_wall(
            pipe(
                "P1",
                [0, 0, 1],
                [2, 0, 1],
                0.1143,
                nominal="4",
                od_fit=0.1146,
                status="snapped",
                od_stderr=0.0004,
            ),
            0.00602,
        ),
        with_wall(
            pipe(
                "P2",
                [2.05, 0, 1],
                [4, 0, 1],
                0.0889,
                nominal="3",
                od_fit=0.1010,
                status="snapped",
                od_stderr=0.005,
            ),
            0.00549,
        ),
    )
    before = check_model(built, catalog=B36)
    fixed, _ = apply_fixes(built, before, catalog="asme-b36.10m")
    p2 = fixed.component("P2")
    assert p2.nominal == "4"
    assert p2.geometry.wall == pytest.approx(0.00602)
    assert fixed.component("P1").geometry.wall == pytest.approx(0.00602)  # not re-sized


def test_size_fix_without_a_catalog_wall_builds_solid():
    """With no catalog at hand (or no wall listed for the new size in the pipe's schedule) a
    re-sized pipe is solid, as merging builds such a size, rather than keeping a wall of
    another size."""
    import dataclasses

    from asbuilt.findings import Finding, Suggestion

    p = pipe("P1", [0, 0, 1], [2, 0, 1], 0.0889, nominal="3")
    p = dataclasses.replace(
        p, geometry=dataclasses.replace(p.geometry, wall=0.00549), schedule="STD"
    )
    change = {"object": "P1", "field": "nominal", "value": "4", "od": 0.1143}
    finding = Finding(
        "AB104",
        "contiguous-diameter-mismatch",
        "error",
        ("P1",),
        "x",
        suggestions=(Suggestion("make P1 NPS 4", change, unambiguous=True),),
    )
    fixed, _ = apply_fixes(model(p), [finding])
    assert fixed.component("P1").geometry.wall == 0.0


@pytest.mark.parametrize(
    ("other_schedule", "expected_schedule", "expected_wall"),
    [
        ("XS", "XS", 0.00953),  # the model's pipes were built to XS: NPS 5 XS
        (None, "STD", 0.00655),  # no other pipe tells: the catalog's default (STD)
    ],
)
def test_an_unsnapped_pipe_given_a_size_takes_the_models_schedule(
    other_schedule, expected_schedule, expected_wall
):
    """A pipe merging left unsnapped has no schedule; accepting a size for it must build it as
    merging builds that size (the schedule the model's pipes have, else the catalog's default),
    not as a solid bar without a weight (seen in review: NPS 5 with wall 0). Walls: ASME
    B36.10M, NPS 5 STD 6.55 mm, XS 9.53 mm."""
    import dataclasses

    from asbuilt.findings import Finding, Suggestion

    loose = pipe("P5", [0, 0, 1], [2, 0, 1], 0.1287, nominal=None)
    assert loose.schedule is None
    others = []
    if other_schedule:
        p4 = pipe("P4", [0, 3, 1], [2, 3, 1], 0.0889, nominal="3")
        others.append(dataclasses.replace(p4, schedule=other_schedule))
    change = {"object": "P5", "field": "nominal", "value": "5", "od": 0.1413}
    finding = Finding(
        "AB101",
        "nonstandard-diameter",
        "error",
        ("P5",),
        "x",
        suggestions=(Suggestion("use NPS 5", change, unambiguous=False),),
    )
    fixed, _ = apply_suggestions(
        model(loose, *others), [(finding, finding.suggestions[0])], catalog="asme-b36.10m"
    )
    p5 = fixed.component("P5")
    assert (p5.nominal, p5.schedule) == ("5", expected_schedule)
    assert p5.geometry.wall == pytest.approx(expected_wall)
    assert p5.geometry.outer_radius == pytest.approx(0.1413 / 2)
