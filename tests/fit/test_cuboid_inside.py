"""Shots inside a fitted box (asbuilt.fit._cuboid_inside): a fit no beam can have measured is
refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit import fit_points
from asbuilt.fit._cuboid_inside import (
    INSIDE_SHARE,
    INSIDE_SHOTS,
    ShotsInside,
    shots_inside,
    too_many_inside,
)
from asbuilt.primitives import Cuboid

CUBE = Cuboid(np.zeros(3), np.eye(3), np.array([2.0, 2.0, 2.0]))


@pytest.mark.parametrize(
    "point, expected",
    [
        ([0.0, 0.0, 0.0], True),  # the centre
        ([0.99, 0.0, 0.0], True),  # 10 mm inside a face
        ([0.996, 0.0, 0.0], False),  # within the width of the face
        ([1.0, 0.0, 0.0], False),  # on the face
        ([1.5, 0.0, 0.0], False),  # outside
        ([0.99, 0.99, 0.99], True),  # 10 mm inside a corner
    ],
)
def test_a_shot_is_inside_when_deeper_than_the_width(point, expected):
    assert shots_inside(CUBE, np.array([point]), 0.006).tolist() == [expected]


def _cloud(n_inside: int, n_total: int) -> np.ndarray:
    rng = np.random.default_rng(n_inside * 1000 + n_total)
    inside = rng.uniform(-0.9, 0.9, (n_inside, 3))
    face = np.column_stack(
        [np.full(n_total - n_inside, -1.0), rng.uniform(-1, 1, (2, n_total - n_inside)).T]
    )
    return np.vstack([inside, face])


@pytest.mark.parametrize("total", [20, 40, 60, 100, 200])
def test_too_many_inside_is_a_count_and_a_share(total):
    fewest = max(INSIDE_SHOTS, int(np.ceil(INSIDE_SHARE * total)))
    none = np.zeros(total, dtype=bool)
    assert too_many_inside(CUBE, _cloud(fewest - 1, total), none, 0.006) == 0
    assert too_many_inside(CUBE, _cloud(fewest, total), none, 0.006) == fewest
    # The fit's inliers are not counted: they lie on its faces' fitted planes.
    kept = np.arange(total) == 0
    assert too_many_inside(CUBE, _cloud(fewest, total), kept, 0.006) == 0


def test_a_column_fitted_on_the_wall_behind_it_is_refused():
    """Clutter benchmark: a column 0.22 x 0.28 m across before a wall, 1 m of window around
    it, whose fit took the wall (a box 1.2 x 3.5 x 3.8 m with 16 of the 100 shots inside it).
    Refused, and not refitted at another noise level by the dispatcher."""
    data = json.loads(Path(__file__).with_name("wall_box_column.json").read_text())
    points, station = np.array(data["points"]), data["station"]
    with pytest.raises(ShotsInside, match="lie inside the fitted box"):
        fit_points("cuboid", points, sigma=data["sigma"], viewpoint=station)
    # Whatever the order of the shots (the fit's order is canonical).
    with pytest.raises(ShotsInside):
        fit_points("cuboid", points[::-1], sigma=data["sigma"], viewpoint=station)
    assert issubclass(ShotsInside, FitError)
