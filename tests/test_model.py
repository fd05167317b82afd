"""The model's value objects: the reducer's eccentricity (ASME B16.9 eccentric reducers)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from asbuilt.model import Reducer, Tee

# NPS 6 x 4: OD 168.3 and 114.3 mm (ASME B36.10M), H = 140 mm (ASME B16.9)
R6, R4, H = 0.16830 / 2, 0.11430 / 2, 0.140


def test_concentric_by_default():
    r = Reducer([0, 0, 1], [H, 0, 1], R6, R4)
    assert not r.eccentric
    assert r.flat_side is None
    assert r.offset.tolist() == [0.0, 0.0, 0.0]
    assert r.length == pytest.approx(H)
    assert r.direction == pytest.approx([1, 0, 0])


@pytest.mark.parametrize(
    ("start_radius", "end_radius", "step", "flat"),
    [
        (R6, R4, R6 - R4, [0, 0, 1]),  # large to small, small end raised: flat on top
        (R6, R4, R4 - R6, [0, 0, -1]),
        (R4, R6, R6 - R4, [0, 0, -1]),  # small to large, large end raised: flat on bottom
        (R4, R6, R4 - R6, [0, 0, 1]),
    ],
)
def test_eccentric_run_length_and_flat_side(start_radius, end_radius, step, flat):
    offset = [0, 0, step]
    r = Reducer([1, 2, 1], [1 + H, 2, 1 + step], start_radius, end_radius, offset=offset)
    assert r.eccentric
    assert r.length == pytest.approx(H)
    assert r.direction == pytest.approx([1, 0, 0])
    assert r.flat_side == pytest.approx(flat)
    # both outsides flush on the flat side: start + R_start f == end + R_end f along the run
    f = np.asarray(flat, float)
    top_start = r.start + start_radius * f
    top_end = r.end + end_radius * f
    assert (top_end - top_start) - H * r.direction == pytest.approx([0, 0, 0], abs=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"end": [H, 0, 0.030], "offset": [0, 0, 0.030]},
            "The reducer offset (30.000 mm) must not exceed the difference of the end radii "
            "(27.000 mm).",
        ),
        (
            {"end": [H + 0.01, 0, 0.027], "offset": [0.01, 0, 0.027]},
            "The reducer offset must be perpendicular to the run (end - start - offset).",
        ),
        (
            {"end": [0, 0, 0.027], "offset": [0, 0, 0.027]},
            "A reducer needs distinct start and end points along its run.",
        ),
        ({"offset": [0, 0]}, "The reducer offset must have shape (3,), not (2,)."),
        ({"offset": [0, 0, np.nan]}, "The reducer offset must be finite."),
    ],
)
def test_invalid_offsets_are_refused_with_one_clear_message(kwargs, message):
    args = {"start": [0, 0, 0], "end": [H, 0, 0], "outer_radius_start": R6}
    args.update(outer_radius_end=R4, **kwargs)
    with pytest.raises(ValueError) as caught:
        Reducer(**args)
    assert str(caught.value) == message


def test_replace_keeps_the_offset():
    r = Reducer([0, 0, 0], [H, 0, R6 - R4], R6, R4, offset=[0, 0, R6 - R4])
    moved = dataclasses.replace(r, start=r.start + 5, end=r.end + 5)
    assert moved.eccentric and moved.offset == pytest.approx(r.offset)


# NPS 6 / 4 / 2 SCH 40 walls (ASME B36.10M): 7.11, 6.02 and 3.91 mm
W6, W4, W2, R2 = 0.00711, 0.00602, 0.00391, 0.0603 / 2


def test_a_reducer_has_a_wall_at_each_end_and_one_wall_sets_both():
    r = Reducer([0, 0, 0], [H, 0, 0], R6, R4, wall_start=W6, wall_end=W4)
    assert (r.wall_start, r.wall_end) == (W6, W4)
    one = Reducer([0, 0, 0], [H, 0, 0], R6, R4, W4)
    assert (one.wall_start, one.wall_end) == (W4, W4)
    assert dataclasses.replace(r, wall_end=0.005).wall_start == W6


def test_a_tee_has_a_run_wall_and_a_branch_wall():
    t = Tee([0, 0, 0], [-0.1, 0, 0], [0.1, 0, 0], [0, 0.1, 0], R6, R2, W6, W2)
    assert (t.wall, t.branch_wall) == (W6, W2)
    one = Tee([0, 0, 0], [-0.1, 0, 0], [0.1, 0, 0], [0, 0.1, 0], R6, R2, W2)
    assert (one.wall, one.branch_wall) == (W2, W2)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (
            lambda: Reducer([0, 0, 0], [H, 0, 0], R6, R4, wall_start=R6),
            "The wall start must be thinner than the outer radius start (0 means solid).",
        ),
        (
            # the large end's wall is too thick for the small end
            lambda: Reducer([0, 0, 0], [H, 0, 0], R6, R4, wall_start=0.06),
            "The wall end must be thinner than the outer radius end (0 means solid).",
        ),
        (
            lambda: Reducer([0, 0, 0], [H, 0, 0], R6, R4, wall_start=W6, wall_end=-1),
            "The wall end must be a non-negative finite number, not -1.",
        ),
        (
            lambda: Tee([0, 0, 0], [-0.1, 0, 0], [0.1, 0, 0], [0, 0.1, 0], R6, R2, R6),
            "The wall must be thinner than the outer radius (0 means solid).",
        ),
        (
            lambda: Tee([0, 0, 0], [-0.1, 0, 0], [0.1, 0, 0], [0, 0.1, 0], R6, R2, W6, R2),
            "The branch wall must be thinner than the branch outer radius (0 means solid).",
        ),
        (
            lambda: Reducer([0, 0, 0], [H, 0, 0], R6, R4, wall_start=W6, wall_end=0),
            "A reducer's walls must be both 0 (solid) or both positive.",
        ),
        (
            lambda: Tee([0, 0, 0], [-0.1, 0, 0], [0.1, 0, 0], [0, 0.1, 0], R6, R2, 0, W2),
            "A tee's walls must be both 0 (solid) or both positive.",
        ),
    ],
)
def test_walls_are_checked_against_their_own_ends(make, message):
    with pytest.raises(ValueError) as caught:
        make()
    assert str(caught.value) == message


def test_a_bend_has_a_size_and_wall_at_each_end_and_one_sets_both():
    from asbuilt.model import Bend

    c, radius = np.zeros(3), 0.229
    start, end = np.array([radius, 0, 0]), np.array([0, radius, 0])
    reducing = Bend(start, end, c, R6, W6, R4, W4)
    assert (reducing.radii, reducing.walls, reducing.reducing) == ((R6, R4), (W6, W4), True)
    one = Bend(start, end, c, R6, W6)
    assert (one.radii, one.walls, one.reducing) == ((R6, R6), (W6, W6), False)
    # an end equal to the start is one size, and stays so when the start is resized
    same = Bend(start, end, c, R6, W6, R6, W6)
    assert (same.outer_radius_end, same.wall_end, same.reducing) == (None, None, False)
    resized = dataclasses.replace(same, outer_radius=R4, wall=W4)
    assert (resized.radii, resized.walls) == ((R4, R4), (W4, W4))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (
            {"outer_radius_end": R4, "wall": 0.06},
            "The wall end must be thinner than the outer radius end (0 means solid).",
        ),
        ({"outer_radius_end": -1.0}, "The outer radius end must be a non-negative finite number"),
        ({"wall_end": 0.0}, "A bend's walls must be both 0 (solid) or both positive."),
    ],
)
def test_a_bends_end_wall_is_checked_against_its_own_end(kwargs, message):
    from asbuilt.model import Bend

    args = {"outer_radius": R6, "wall": W6, **kwargs}
    with pytest.raises(ValueError) as caught:
        Bend([0.229, 0, 0], [0, 0.229, 0], [0, 0, 0], **args)
    assert str(caught.value).startswith(message)
