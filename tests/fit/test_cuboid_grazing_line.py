"""A column seen on two faces without the station: the grazing face's one raster line.

The scan is ray-cast here, independently of ``asbuilt.sim``: a 0.4 x 0.4 x 4 m column 7 m
from a station that is not the scan frame's origin (so no viewpoint is known), turned so that
one face is seen at 70-76 degrees incidence. A cell-centred raster of 7 pan columns x 6 tilt
rows over the silhouette window widened by 15% a side puts four columns on the near face and
a single column on the grazing face, whose far edge lies a whole raster step (0.3 m along
that face) beyond the window. Nothing measures where that edge is: the size is an extent
bound (``observed`` False) whose standard error must cover the truth, as it does when the
station is given (the raster silhouette). Before the fix, the single line's shots, which
share one coordinate across the face, were taken as raster lines spaced by their noise: the
size stopped at the line (0.15-0.2 m for 0.4 m) with a 2 mm standard error (z -70 to -130).
Without the station the shots cannot be read as a raster at all, so such a size is now a lower
bound (standard error infinite, ``asbuilt.fit._cuboid_reach``); its value still follows the
grazing face's step (``_cuboid_sizes._corner_step``) and agrees with the station's fit.
"""

from __future__ import annotations

import numpy as np
import pytest
from fit_scans import cell_centres, corner_angles, shoot, sizes_in_true_order

from asbuilt.fit.cuboid import fit_cuboid
from asbuilt.primitives import Cuboid

HALF = np.array([0.2, 0.2, 2.0])  # the column's half sizes, metres
DISTANCE = 7.0  # station to column, metres
STATION = np.array([3.5, -1.0, 1.5])  # the station in the scan frame, metres
RANGE_SIGMA = 0.002  # metres


def scan(turn_deg: float, seed: int):
    """Points (n, 3) in the scan frame and the column's rotation (3, 3; columns its axes)."""
    rng = np.random.default_rng(seed)
    a = np.radians(turn_deg)
    rot = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
    centre = np.array([0.0, DISTANCE, 0.0])  # from the station
    column = Cuboid(centre, rot.T, 2.0 * HALF)
    pans, tilts = corner_angles(column)
    margin = 0.15 * np.ptp(pans)
    pan, tilt = np.meshgrid(
        cell_centres(pans.min() - margin, pans.max() + margin, 7),
        cell_centres(tilts.min(), tilts.max(), 6),
    )
    points, hit = shoot(column, pan.ravel(), tilt.ravel(), rng)
    return points[hit] + STATION, rot


@pytest.mark.parametrize("turn_deg, seed", [(16.0, 2), (18.0, 0), (20.0, 1), (160.0, 3)])
@pytest.mark.parametrize("sigma", [RANGE_SIGMA, None])
def test_grazing_single_line_size_is_an_honest_extent_bound(turn_deg, seed, sigma):
    points, rot = scan(turn_deg, seed)
    local = (points - STATION - [0.0, DISTANCE, 0.0]) @ rot
    grazing = np.abs(np.abs(local[:, 0]) - HALF[0]) < 0.01
    # The scene is what the test is about: one raster column on the grazing face, whose far
    # edge is over 0.15 m beyond it.
    assert np.ptp(local[grazing, 1]) < 0.03 and np.count_nonzero(grazing) >= 5
    assert HALF[1] - local[grazing, 1].max() > 0.15
    result = fit_cuboid(points, sigma=sigma)
    size, stderr, observed = sizes_in_true_order(result, rot)
    assert not observed[:2].any()
    assert np.all(np.abs(size - 2 * HALF) <= 3.0 * stderr)
    # Not confidently wrong: the grazing size's standard error is a raster step's, not the noise.
    assert stderr[1] > 0.05


def test_with_the_station_given_the_fit_agrees():
    # The station gives the raster silhouette, which bounds the same edge half a step beyond
    # the line; without it, the step comes from the near face's lines across the corner.
    points, rot = scan(18.0, 0)
    with_station = sizes_in_true_order(
        fit_cuboid(points, sigma=RANGE_SIGMA, viewpoint=STATION), rot
    )
    without = sizes_in_true_order(fit_cuboid(points, sigma=RANGE_SIGMA), rot)
    # Sizes across the column (the length's ends are placed differently: silhouette vs extent).
    assert without[0][:2] == pytest.approx(with_station[0][:2], abs=0.03)
    # Without the station nothing says the shots are a raster reaching the edges: the sizes
    # are lower bounds (before: standard errors within 30% of the station's), the station's
    # fit keeps its finite ones.
    assert np.all(np.isfinite(with_station[1][:2]))
    assert np.all(np.isinf(without[1][:2]))
