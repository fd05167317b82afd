"""A column whose two seen faces hold only a few raster columns of shots between them.

Three vertical raster columns on two faces fit the corner between the first and the second or
between the second and the third exactly, and two on one face fit two faces meeting between
them: at any shot count the fit keeps its frame and must report axis and size standard errors
that cover the other splits (an independent review's bare columns came out 3-43 degrees
turned at +-0.1-0.3 degree; refusing them instead refused right answers twice as often as
wrong ones on the cuboid benchmark). The scans are ray cast here: a pan-tilt raster from a
station at the origin onto a box, range noise along the beams.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit.cuboid import fit_cuboid

SIGMA = 0.002  # metres, range noise
TILT_STEP_DEG = 0.7


def _box_hits(beams: np.ndarray, centre, rot, half) -> np.ndarray:
    """Range (m,) metres along each unit beam (m, 3) from the origin to a box (centre (3,),
    axes the columns of ``rot`` (3, 3), half sizes (3,) metres); nan for a miss (slabs)."""
    origin = -(centre @ rot)  # the station in the box's frame
    local = beams @ rot
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - origin) / local
        t2 = (half - origin) / local
    near = np.nanmax(np.minimum(t1, t2), axis=1)
    far = np.nanmin(np.maximum(t1, t2), axis=1)
    return np.where((far >= near) & (near > 0), near, np.nan)


def column_scan(size, distance, bearing_deg, yaw_deg, columns, seed, floor_margin=None):
    """A bare column's shots over a raster whose pan step puts about ``columns`` raster
    columns across its silhouette.

    With ``floor_margin`` (radians) the column stands on a floor (1.5 m below the station)
    and the window reaches that far past the silhouette on either side: the raster columns
    beside the column and the tilts below its foot hit the floor, as an operator's window
    does.

    Returns the shots (n, 3) metres, the true axes (3, 3) (rows), the number of raster columns
    that hit and the true size (3,) metres.
    """
    rng = np.random.default_rng(seed)
    size = np.asarray(size, dtype=np.float64)
    bearing = math.radians(bearing_deg)
    centre = np.array([distance * math.cos(bearing), distance * math.sin(bearing), 0.5 * size[2]])
    centre[2] -= 1.5  # the station 1.5 m above the column's foot
    yaw = bearing + math.radians(yaw_deg)
    rot = np.array(
        [[math.cos(yaw), -math.sin(yaw), 0.0], [math.sin(yaw), math.cos(yaw), 0.0], [0, 0, 1]]
    )
    # The silhouette's angular width: the box's corners' bearings.
    corners = np.array([[sx, sy] for sx in (-1, 1) for sy in (-1, 1)]) * size[:2] / 2
    plan = centre[:2] + corners @ rot[:2, :2].T
    bearings = np.arctan2(plan[:, 1], plan[:, 0])
    width = float(bearings.max() - bearings.min())
    step = width / columns
    pans = bearings.min() + step * (rng.uniform(0.1, 0.9) + np.arange(-2, columns + 2))
    top = math.atan2(size[2] - 1.5, distance)
    bottom = math.atan2(-1.5, distance)
    if floor_margin is not None:
        pans = np.arange(bearings.min() - floor_margin, bearings.max() + floor_margin, step)
        pans += step * rng.uniform(0.1, 0.9)
        bottom = math.atan2(-1.5, distance - size[:2].max()) - floor_margin
    tilts = np.arange(bottom, top, math.radians(TILT_STEP_DEG)) + 0.3 * math.radians(TILT_STEP_DEG)
    pan, tilt = (a.ravel() for a in np.meshgrid(pans, tilts))
    beams = np.column_stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)])
    ranges = _box_hits(beams, centre, rot, size / 2)
    on_box = np.isfinite(ranges)
    if floor_margin is not None:
        with np.errstate(divide="ignore"):
            to_floor = np.where(beams[:, 2] < 0, -1.5 / beams[:, 2], np.nan)
        ranges = np.where(on_box, ranges, to_floor)
    hit = np.isfinite(ranges)
    points = beams[hit] * (ranges[hit] + rng.normal(0.0, SIGMA, hit.sum()))[:, None]
    return points, rot.T, np.unique(pan[on_box]).size, size


def _axis_errors(result, truth_axes) -> tuple[np.ndarray, np.ndarray]:
    """Angle (3,) degrees from each fitted axis to its nearest true axis, and the fitted
    axes' standard errors (3,) degrees."""
    axes = np.asarray(result.primitive.axes)
    cosines = np.abs(axes @ truth_axes.T).max(axis=1)
    return np.degrees(np.arccos(np.clip(cosines, 0.0, 1.0))), np.asarray(
        result.stderr["axes_deg"], dtype=np.float64
    )


def assert_turn_covered(points, truth, seed) -> None:
    """Fit a column's shots (n, 3) metres from a station at the origin: refused, or every
    axis within three of its standard errors (and 0.5 degree) of the true axes (3, 3) (rows),
    the column's own (vertical) axis within 0.5 degree."""
    try:
        result = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
    except FitError:
        return  # refused is honest too
    error, se = _axis_errors(result, truth)
    assert np.all(error <= 3.0 * se + 0.5), (seed, error, se)
    # The column's own axis is still measured.
    vertical = int(np.argmax(np.abs(np.asarray(result.primitive.axes)[:, 2])))
    assert error[vertical] < 0.5


# (yaw of the column's frame from the line of sight, degrees; seed): a face seen at 10-35
# degrees, its neighbour at grazing incidence, as in the review's columns.
THREE_COLUMN_CASES = [(yaw, seed) for yaw in (12.0, 25.0, 38.0, 55.0, 70.0) for seed in (0, 1)]


def test_three_raster_columns_on_two_faces_are_fitted_with_the_other_split_as_their_error():
    widened = 0
    for yaw, seed in THREE_COLUMN_CASES:
        points, truth, hit_columns, size = column_scan((0.36, 0.43, 3.0), 10.0, 20.0, yaw, 3, seed)
        assert hit_columns == 3, (yaw, seed, hit_columns)
        assert points.shape[0] > SPARSE_LIMIT  # not the few-shot path
        # Not refused (an AmbiguousFrame would fail the test): the fit stands.
        result = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
        error, se = _axis_errors(result, truth)
        # Every axis's error within three of its standard errors (and a noise allowance).
        assert np.all(error <= 3.0 * se + 0.5), (yaw, seed, error, se)
        axes = np.asarray(result.primitive.axes)
        size_error = np.asarray(result.primitive.size) - size[np.abs(axes @ truth.T).argmax(1)]
        size_se = np.asarray(result.stderr["size"], dtype=np.float64)
        assert np.all(np.abs(size_error) <= 3.0 * size_se), (yaw, seed, size_error, size_se)
        # The column's own axis (its plumb) is still measured.
        vertical = int(np.argmax(np.abs(axes[:, 2])))
        assert error[vertical] < 0.5, (yaw, seed, error, se)
        widened += bool(se.max() > 5.0)
    # Three lines split either way fit exactly: most such columns' turn is that uncertain.
    assert widened >= len(THREE_COLUMN_CASES) // 2, widened


SPARSE_LIMIT = 16


@pytest.mark.parametrize("yaw", [15.0, 35.0, 60.0])
def test_two_raster_columns_report_the_turn_they_cannot_fix(yaw):
    """Two raster columns, one on each face or both on one: fitted as one face through both,
    its turn about them must be as uncertain as two faces meeting between them allow."""
    for seed in (0, 1, 2):
        points, truth, hit_columns, _ = column_scan((0.36, 0.43, 3.0), 10.0, -15.0, yaw, 2, seed)
        if hit_columns != 2:
            continue
        assert_turn_covered(points, truth, seed)


@pytest.mark.parametrize("yaw", [10.0, 25.0, 40.0, 55.0, 70.0])
def test_two_raster_columns_over_a_floor_report_the_turn_they_cannot_fix(yaw):
    """As above, the column standing on a floor that fills the window around it: the floor
    and the column's faces meet the two lines' plane otherwise than the two faces of a corner
    between them, and such a corner was once kept out for one shot more counted against it
    (a clutter benchmark's columns, 13-41 degrees turned at +-0.1-0.3 degree)."""
    for seed in range(6):
        points, truth, hit_columns, _ = column_scan(
            (0.4, 0.45, 3.0), 8.0, 10.0, yaw, 2, seed, floor_margin=math.radians(3.0)
        )
        if hit_columns != 2:
            continue
        assert_turn_covered(points, truth, seed)


@pytest.mark.parametrize("yaw", [20.0, 45.0])
def test_a_column_over_many_raster_columns_is_fitted_as_before(yaw):
    """Eight raster columns across two faces fix the frame: no rival, the frame to a degree."""
    points, truth, hit_columns, size = column_scan((0.36, 0.43, 3.0), 8.0, 10.0, yaw, 8, 3)
    assert hit_columns >= 7
    result = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
    error, se = _axis_errors(result, truth)
    assert np.all(error < 1.0), error
    assert np.all(error <= 3.0 * se + 0.1), (error, se)
    assert abs(result.primitive.size[2] - size[2]) < 0.1


# ----------------------------------------------------------------- which splits are fitted


def _corner_by_search(first, second, steps=20000):
    """The least RMS of two perpendicular lines through two 2-D point sets, by a search over
    the first line's direction (each line through its set's centroid at a given direction)."""
    best = math.inf
    for angle in np.linspace(0.0, math.pi, steps, endpoint=False):
        t = np.array([math.cos(angle), math.sin(angle)])
        n = np.array([-t[1], t[0]])
        sse = np.sum(((first - first.mean(axis=0)) @ n) ** 2)
        sse += np.sum(((second - second.mean(axis=0)) @ t) ** 2)
        best = min(best, sse)
    return math.sqrt(best / (first.shape[0] + second.shape[0]))


@pytest.mark.parametrize(
    ("turn_deg", "noise", "bend_deg", "seed"),
    [(0.0, 0.0, 0.0, 0), (33.0, 0.002, 0.0, 1), (-71.0, 0.005, 0.0, 2), (12.0, 0.001, 8.0, 3)],
)
def test_corner_fit_is_the_least_squares_corner(turn_deg, noise, bend_deg, seed):
    """corner_fit's RMS agrees with a brute-force search over directions, and its lines are
    perpendicular and through each set (``bend_deg`` turns the second set off square)."""
    from asbuilt.fit._cuboid_sparse import corner_fit

    rng = np.random.default_rng(seed)
    turn, bend = math.radians(turn_deg), math.radians(90.0 + bend_deg)
    u = np.array([math.cos(turn), math.sin(turn)])
    v = np.array([math.cos(turn + bend), math.sin(turn + bend)])
    first = rng.uniform(0.05, 0.4, (9, 1)) * u + rng.normal(0.0, noise, (9, 2))
    second = rng.uniform(0.05, 0.3, (7, 1)) * v + rng.normal(0.0, noise, (7, 2))
    rms, normals, offsets = corner_fit(first, second)
    assert rms == pytest.approx(_corner_by_search(first, second), rel=1e-3, abs=1e-9)
    assert abs(normals[0] @ normals[1]) < 1e-12
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    # Each line passes through its set's centroid.
    assert normals[0] @ first.mean(axis=0) == pytest.approx(offsets[0])
    assert normals[1] @ second.mean(axis=0) == pytest.approx(offsets[1])
    if noise == 0.0 and bend_deg == 0.0:
        assert rms < 1e-12


def test_splits_no_corner_fits_are_left_out_without_changing_the_fit(monkeypatch):
    """Columns over five raster columns: the splits whose lines no corner fits within the
    cutoff (or whose corner returns to the chosen split) are not fitted, and the fit, its
    standard errors included, is what fitting every split gives."""
    import asbuilt.fit._cuboid_sparse as sparse
    import asbuilt.fit._joint as joint

    counted = []
    split_frames = joint.line_split_frames

    def counting(*args):
        frames, lined, along = split_frames(*args)
        counted.append(len(frames))
        return frames, lined, along

    monkeypatch.setattr(joint, "line_split_frames", counting)
    fitted = {True: 0, False: 0}
    for yaw, seed in [(20.0, 0), (35.0, 1), (50.0, 2), (65.0, 3)]:
        points, _, hit_columns, _ = column_scan((0.36, 0.43, 3.0), 9.0, 5.0, yaw, 5, seed)
        assert 4 <= hit_columns <= 6, hit_columns
        results = {}
        for gated in (True, False):
            monkeypatch.setattr(sparse, "LINE_SPLIT_RMS", 1.0 if gated else math.inf)
            counted.clear()
            results[gated] = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
            fitted[gated] += sum(counted)
        for gated_value, every_value in [
            (results[True].primitive.center, results[False].primitive.center),
            (results[True].primitive.size, results[False].primitive.size),
            (results[True].stderr["axes_deg"], results[False].stderr["axes_deg"]),
            (results[True].stderr["size"], results[False].stderr["size"]),
        ]:
            assert np.allclose(gated_value, every_value, rtol=1e-9, atol=1e-12)
    assert fitted[True] < fitted[False], fitted


# Three scan-session point sets of the accuracy benchmark (20% edge outliers took the edge
# bisection shots) whose raster lines another split, 30-45 degrees away, fits as well.
RIVAL_CENTRES = json.loads((Path(__file__).parent / "split_rival_centres.json").read_text())


@pytest.mark.parametrize("case", RIVAL_CENTRES, ids=[case["key"] for case in RIVAL_CENTRES])
def test_a_rival_split_widens_the_centre_error_too(case, monkeypatch):
    """The centre's standard error takes in how far the rival split's box centre lies: it had
    stayed at the fit's own 2 mm beside size errors of 0.2-0.4 m and a 30-45 degree turn."""
    from asbuilt.fit import cuboid

    shifts = []
    spread = cuboid.rival_size_spread

    def spying(*args, **kwargs):
        sizes, shift = spread(*args, **kwargs)
        shifts.append(shift)
        return sizes, shift

    monkeypatch.setattr(cuboid, "rival_size_spread", spying)
    points = np.array(case["points"])
    result = fit_cuboid(points, sigma=SIGMA, viewpoint=np.array(case["station"]))
    assert shifts and max(shifts) > 0.05, shifts  # a rival box elsewhere
    assert result.stderr["center"] >= max(shifts)
    assert max(result.stderr["size"]) > 0.1 and max(result.stderr["axes_deg"]) > 20.0
    error = np.linalg.norm(np.asarray(result.primitive.center) - np.array(case["center"]))
    assert error <= 3.0 * result.stderr["center"]
