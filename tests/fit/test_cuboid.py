"""Tests for asbuilt.fit.cuboid: known boxes recovered from simulated pan-tilt raster scans.

The sampler below is independent of the fit: a sensor 3-10 m away shoots a raster over the box's
angular window (cell-centred, the project's raster convention: the outer shots half a step
inside the silhouette), each beam leaves with angular noise, meets the box exactly (slab method)
and the point is reported along the *nominal* direction at the noisy range. Outliers are shots
pushed along their ray behind the object (edge grazes that hit the wall behind).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from fit_scans import shoot, sizes_in_true_order
from hypothesis import given, settings
from hypothesis import strategies as st

from asbuilt.errors import FitError
from asbuilt.fit import _joint
from asbuilt.fit.cuboid import fit_cuboid
from asbuilt.primitives import Cuboid
from asbuilt.tolerances import MIN_POINTS

SIGMA = 0.002
ANGLE_SIGMA = math.radians(0.01)


# --------------------------------------------------------------------------- sampler


def _rot_z(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _rotation(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Rows: a right-handed orthonormal frame from yaw/pitch/roll in degrees."""
    y, p, r = (math.radians(v) for v in (yaw, pitch, roll))
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    return (rz @ ry @ rx).T


def _directions(pan, tilt):
    return np.stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)], axis=-1)


def _ray_box(box: Cuboid, origin, dirs):
    """Distance along each ray (k, 3) to its first hit on the box, NaN on a miss (slab method)."""
    o = box.axes @ (origin - box.center)
    d = dirs @ box.axes.T
    half = 0.5 * box.size
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - o) / d
        t2 = (half - o) / d
    near = np.nanmax(np.minimum(t1, t2), axis=1)
    far = np.nanmin(np.maximum(t1, t2), axis=1)
    return np.where((near <= far) & (near > 0), near, np.nan)


def _window(box: Cuboid, sensor):
    """Pan (about pan0) and tilt extremes of the box seen from the sensor, densely sampled."""
    t = np.linspace(-0.5, 0.5, 41)
    samples = []
    for k in range(3):
        a, b = [j for j in range(3) if j != k]
        for sa in (-0.5, 0.5):
            for sb in (-0.5, 0.5):
                local = np.zeros((t.size, 3))
                local[:, k], local[:, a], local[:, b] = t, sa, sb
                samples.append(box.center + (local * box.size) @ box.axes)
    rel = np.concatenate(samples) - sensor
    mid = box.center - sensor
    pan0 = math.atan2(mid[1], mid[0])
    pan = np.angle(np.exp(1j * (np.arctan2(rel[:, 1], rel[:, 0]) - pan0)))
    tilt = np.arctan2(rel[:, 2], np.hypot(rel[:, 0], rel[:, 1]))
    return pan0, pan.min(), pan.max(), tilt.min(), tilt.max()


def scan_box(
    box: Cuboid,
    sensor,
    n_pan: int,
    n_tilt: int,
    rng,
    *,
    range_sigma: float = SIGMA,
    angle_sigma: float = ANGLE_SIGMA,
    outlier_fraction: float = 0.0,
):
    """Raster scan of a box: points (n, 3) metres and the outlier mask (n,)."""
    sensor = np.asarray(sensor, float)
    pan0, p_lo, p_hi, t_lo, t_hi = _window(box, sensor)
    pans = pan0 + p_lo + (np.arange(n_pan) + 0.5) / n_pan * (p_hi - p_lo)
    tilts = t_lo + (np.arange(n_tilt) + 0.5) / n_tilt * (t_hi - t_lo)
    pan, tilt = (a.ravel() for a in np.meshgrid(pans, tilts))
    nominal = _directions(pan, tilt)
    actual = _directions(
        pan + rng.normal(0.0, angle_sigma, pan.size), tilt + rng.normal(0.0, angle_sigma, pan.size)
    )
    rng_true = _ray_box(box, sensor, actual)
    hit = np.isfinite(rng_true)
    measured = rng_true[hit] + rng.normal(0.0, range_sigma, hit.sum())
    outliers = np.zeros(measured.size, bool)
    k = int(round(outlier_fraction * measured.size))
    if k:
        chosen = rng.choice(measured.size, k, replace=False)
        outliers[chosen] = True
        measured[chosen] += rng.uniform(0.05, 2.0, k)
    return sensor + measured[:, None] * nominal[hit], outliers


def column(width, depth, height, yaw_to_view, distance, rng=None, base=-1.0):
    """A vertical column seen from the origin at ``distance``; yaw relative to the view line."""
    rng = rng or np.random.default_rng(0)
    bearing = rng.uniform(-180, 180)
    los = np.array([math.cos(math.radians(bearing)), math.sin(math.radians(bearing)), 0.0])
    centre = distance * los + np.array([0.0, 0.0, base + 0.5 * height])
    axes = _rot_z(bearing + yaw_to_view)
    return Cuboid(center=centre, axes=axes, size=[width, depth, height])


def match(fitted: Cuboid, truth: Cuboid):
    """Relative size errors (3,) per true axis and the largest axis angle error (degrees)."""
    dots = np.abs(fitted.axes @ truth.axes.T)
    order = dots.argmax(axis=0)
    assert sorted(order.tolist()) == [0, 1, 2], "fitted axes do not match the true ones"
    angle = np.degrees(np.arccos(np.clip(dots[order, np.arange(3)], -1.0, 1.0))).max()
    return fitted.size[order] / truth.size - 1.0, float(angle), order


# --------------------------------------------------------------------------- recovery


@pytest.mark.parametrize(
    "width, depth, yaw, distance, seed",
    [
        (0.2, 0.25, 30.0, 4.0, 1),
        (0.4, 0.35, 45.0, 6.0, 2),
        (0.6, 0.5, 60.0, 9.0, 3),
        (0.3, 0.6, -40.0, 3.0, 4),
    ],
)
def test_vertical_column_two_faces(width, depth, yaw, distance, seed):
    rng = np.random.default_rng(seed)
    truth = column(width, depth, 3.0, yaw, distance, rng)
    points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
    result = fit_cuboid(points, sigma=SIGMA)
    err, angle, _ = match(result.primitive, truth)
    assert result.diagnostics["faces"] == 2
    assert np.all(np.abs(err) < 0.02), err
    assert angle < 0.5
    assert result.observed == (False, False, False)
    assert abs(result.primitive.axes[2, 2]) > 0.999  # the vertical axis is listed last
    assert result.sigma_source == "sensor" and result.sigma == SIGMA


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_pier_three_faces_seen_from_above(seed):
    rng = np.random.default_rng(seed)
    distance = rng.uniform(3.0, 8.0)
    top = -distance * math.tan(math.radians(rng.uniform(20, 35)))
    truth = column(0.4, 0.45, 1.2, rng.uniform(25, 65), distance, rng, base=top - 1.2)
    points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
    result = fit_cuboid(points, sigma=SIGMA)
    err, angle, _ = match(result.primitive, truth)
    assert result.diagnostics["faces"] == 3
    assert np.all(np.abs(err) < 0.02), err
    assert angle < 0.5


def test_horizontal_beam_seen_from_below():
    rng = np.random.default_rng(21)
    axes = _rotation(35.0, 0.0, 0.0)
    truth = Cuboid(center=[5.0, 1.0, 3.5], axes=axes, size=[2.0, 0.3, 0.5])
    points, _ = scan_box(truth, np.array([0.0, 0.0, 1.5]), 8, 6, rng)
    result = fit_cuboid(points, sigma=SIGMA, viewpoint=[0.0, 0.0, 1.5])
    err, angle, _ = match(result.primitive, truth)
    assert result.diagnostics["faces"] >= 2
    assert np.all(np.abs(err) < 0.02), err
    assert angle < 0.5


def test_tilted_box_three_faces():
    rng = np.random.default_rng(31)
    axes = _rotation(20.0, 25.0, 10.0)
    truth = Cuboid(center=[4.0, -2.0, -1.0], axes=axes, size=[0.5, 0.4, 0.6])
    points, _ = scan_box(truth, np.zeros(3), 7, 7, rng)
    result = fit_cuboid(points, sigma=SIGMA)
    err, angle, _ = match(result.primitive, truth)
    assert np.all(np.abs(err) < 0.02), err
    assert angle < 0.5


def test_noise_free_scan_is_recovered_exactly():
    truth = column(0.4, 0.3, 2.5, 40.0, 5.0, np.random.default_rng(5))
    points, _ = scan_box(
        truth, np.zeros(3), 6, 6, np.random.default_rng(5), range_sigma=0.0, angle_sigma=0.0
    )
    result = fit_cuboid(points)
    err, angle, _ = match(result.primitive, truth)
    assert np.all(np.abs(err) < 1e-3), err
    assert angle < 1e-6
    assert np.allclose(result.primitive.center, truth.center, atol=1e-3)
    assert result.rms < 1e-6


def test_paper_extent_without_the_silhouette_is_biased_low():
    """Without the raster window the far edges are bounded by the last points (the paper)."""
    truth = column(0.4, 0.3, 2.5, 40.0, 5.0, np.random.default_rng(6))
    points, _ = scan_box(
        truth, np.zeros(3), 6, 6, np.random.default_rng(6), range_sigma=0.0, angle_sigma=0.0
    )
    plain = fit_cuboid(points, silhouette=False, edge_pad=0.0)
    err, _, _ = match(plain.primitive, truth)
    assert np.all(err < 1e-9)  # never beyond the true edges
    assert err.min() < -0.05  # and noticeably short of them
    assert plain.diagnostics["silhouette"] == 0.0


# --------------------------------------------------------------------------- outliers


@pytest.mark.parametrize("seed", [41, 42, 43])
def test_twenty_percent_outliers_are_rejected(seed):
    rng = np.random.default_rng(seed)
    truth = column(0.4, 0.35, 3.0, 45.0, rng.uniform(3, 10), rng)
    points, bad = scan_box(truth, np.zeros(3), 6, 7, rng, outlier_fraction=0.2)
    result = fit_cuboid(points, sigma=SIGMA)
    err, angle, _ = match(result.primitive, truth)
    assert np.all(np.abs(err) < 0.02), err
    assert angle < 0.6
    assert not np.any(result.inliers[bad]), "an outlier was kept"
    assert np.mean(result.inliers[~bad]) > 0.9
    assert result.diagnostics["outliers"] == np.count_nonzero(~result.inliers)
    # Said in the notes as the other kinds say it (an audit found the cuboid silent).
    note = f"{np.count_nonzero(~result.inliers)} outlier point(s) rejected (beyond 3 x "
    assert any(text.startswith(note) for text in result.notes), result.notes


def test_residuals_are_plane_distances_for_inliers_and_box_distances_for_outliers():
    rng = np.random.default_rng(44)
    truth = column(0.4, 0.35, 3.0, 45.0, 6.0, rng)
    points, bad = scan_box(truth, np.zeros(3), 6, 7, rng, outlier_fraction=0.2)
    result = fit_cuboid(points, sigma=SIGMA)
    assert result.residuals.shape == (points.shape[0],)
    assert np.max(np.abs(result.residuals[result.inliers])) < 0.01
    out = ~result.inliers
    assert np.allclose(result.residuals[out], result.primitive.distance(points[out]))
    assert result.rms < 0.004 and result.max_residual < 0.01


def test_too_many_outliers_raise():
    rng = np.random.default_rng(45)
    truth = column(0.4, 0.35, 3.0, 45.0, 6.0, rng)
    points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
    junk = rng.uniform(-3, 3, size=(len(points), 3)) + truth.center
    with pytest.raises(FitError, match="outliers"):
        fit_cuboid(np.vstack([points[:15], junk]), sigma=SIGMA)


# --------------------------------------------------------------------------- faces, observed


def test_one_face_seen():
    truth = Cuboid(center=[6.0, 0.0, 0.0], axes=np.eye(3), size=[0.4, 0.5, 0.8])
    rng = np.random.default_rng(51)
    points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
    result = fit_cuboid(points, sigma=SIGMA)
    box = result.primitive
    assert result.diagnostics["faces"] == 1
    assert result.observed == (False, False, False)
    assert any("one face" in note for note in result.notes)
    # The depth is made up, and with it where the centre lies behind the face: a review's
    # one-face box had its centre 280 mm off at +-59 mm.
    assert math.isinf(result.stderr["center"])
    assert sum(math.isinf(se) for se in result.stderr["size"]) == 1
    # The face normal is the x axis; the face (x = 5.8) is the box's near side.
    normal_row = int(np.argmax(np.abs(box.axes[:, 0])))
    assert abs(box.axes[normal_row, 0]) > 0.9999
    near = box.center[0] - 0.5 * box.size[normal_row]
    assert near == pytest.approx(5.8, abs=0.002)
    widths = [box.size[k] for k in range(3) if k != normal_row]
    assert box.size[normal_row] == pytest.approx(min(widths))
    # The depth is assumed, not measured: no standard error (it claimed the range sigma, 2 mm,
    # for a 0.4 m depth set to 0.5 m; audit), and the diagnostics name it.
    assert result.diagnostics["assumed_size"] == normal_row
    assert result.stderr["size"][normal_row] == np.inf
    assert all(np.isfinite(result.stderr["size"][k]) for k in range(3) if k != normal_row)
    assert sorted(widths) == pytest.approx([0.5, 0.8], rel=0.1)


def test_opposite_faces_from_two_stations_are_observed():
    truth = column(0.4, 0.3, 2.0, 45.0, 5.0, np.random.default_rng(61))
    rng = np.random.default_rng(61)
    front, _ = scan_box(truth, np.zeros(3), 6, 6, rng)
    behind = 2 * truth.center - np.zeros(3)
    behind[2] = 0.0
    back, _ = scan_box(truth, behind, 6, 6, rng)
    result = fit_cuboid(np.vstack([front, back]), sigma=SIGMA)
    err, angle, order = match(result.primitive, truth)
    assert result.diagnostics["faces"] == 4
    observed = np.array(result.observed)[order]
    assert observed.tolist() == [True, True, False]
    assert np.all(np.abs(err[:2]) * truth.size[:2] < 0.003)  # between faces: millimetres
    assert angle < 0.3


def test_viewpoint_off_the_raster_disables_the_silhouette():
    rng = np.random.default_rng(71)
    truth = column(0.4, 0.35, 3.0, 45.0, 6.0, rng)
    points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
    assert fit_cuboid(points, sigma=SIGMA).diagnostics["silhouette"] == 1.0
    moved = fit_cuboid(points, sigma=SIGMA, viewpoint=[2.0, -3.0, 1.0])
    assert moved.diagnostics["silhouette"] == 0.0


# --------------------------------------------------------------------------- uncertainty


def test_standard_errors_scale_with_the_sensor_sigma():
    rng = np.random.default_rng(81)
    truth = column(0.4, 0.35, 3.0, 45.0, 6.0, rng)
    points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
    one = fit_cuboid(points, sigma=0.002)
    two = fit_cuboid(points, sigma=0.004)
    assert set(one.stderr) == {"size", "axes_deg", "center"}
    assert len(one.stderr["size"]) == 3
    assert len(one.stderr["axes_deg"]) == 3
    assert two.stderr["axes_deg"] == pytest.approx(np.multiply(2, one.stderr["axes_deg"]), rel=1e-6)
    # a size bounded by the points' extent also carries the gap past the last point, which
    # does not scale with the sensor: se^2 = sigma^2 * a + gap, the same gap at every sigma
    three = fit_cuboid(points, sigma=0.003)
    v1, v2, v3 = (np.array(r.stderr["size"]) ** 2 for r in (one, two, three))
    gap_12 = (4.0 * v1 - v2) / 3.0
    gap_13 = (2.25 * v1 - v3) / 1.25
    assert np.allclose(gap_12, gap_13, rtol=1e-6)
    assert not any(one.observed)
    assert np.all(np.sqrt(gap_12) > 0.01)  # a few centimetres: the raster's step here
    assert np.all(np.sqrt(gap_12) < 0.5 * one.primitive.size)
    free = fit_cuboid(points)
    assert free.sigma_source == "residuals"
    assert 0.0005 < free.sigma < 0.005
    assert free.covariance.shape == (5, 5)


def test_orientation_standard_error_matches_the_scatter():
    """Each axis's reported angular error (axes_deg, one per output axis) is within a factor 2
    of that axis's RMS direction error over repeated scans: a tall column's tilt (its long,
    vertical axis) is known several times better than its yaw (the two across it), and the
    plumb rule reads the tilt's own error."""
    truth = column(0.4, 0.4, 2.0, 45.0, 5.0, np.random.default_rng(91))
    errors, reported = [], []
    for seed in range(30):
        rng = np.random.default_rng(1000 + seed)
        points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
        result = fit_cuboid(points, sigma=SIGMA)
        axes = result.primitive.axes
        cosines = np.abs(axes @ truth.axes.T).max(axis=1)  # per fitted axis
        errors.append(np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0))))
        reported.append(result.stderr["axes_deg"])
    rms = np.sqrt(np.mean(np.square(errors), axis=0))
    median = np.median(reported, axis=0)
    assert np.all((0.5 < rms / median) & (rms / median < 2.0)), (rms, median)
    # the vertical axis (last) is the long one: its tilt error is the smallest
    assert median[2] < 0.5 * min(median[0], median[1]), median
    assert rms[2] < 0.5 * min(rms[0], rms[1]), rms


# --------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((MIN_POINTS["cuboid"] - 1, 3)) + np.arange(6)[:, None], "too few"),
        (np.outer(np.linspace(0, 1, 20), [1.0, 2.0, 3.0]), "one line"),
        (np.ones((20, 3)), "coincide"),
        (np.full((20, 3), np.nan), "finite"),
        (np.zeros((20, 2)), "shape"),
    ],
)
def test_degenerate_input_raises_fit_error(points, message):
    with pytest.raises(FitError, match=message):
        fit_cuboid(points)


def test_a_bad_viewpoint_raises_fit_error():
    rng = np.random.default_rng(7)
    points, _ = scan_box(column(0.4, 0.3, 2.0, 40.0, 5.0, rng), np.zeros(3), 6, 6, rng)
    with pytest.raises(FitError, match="viewpoint"):
        fit_cuboid(points, viewpoint=[0.0, 1.0])


# --------------------------------------------------------------------------- invariance


@settings(max_examples=15, deadline=None)
@given(turn=st.floats(-180, 180), shift=st.tuples(*[st.floats(-50, 50)] * 3))
def test_fit_is_invariant_under_turns_about_the_vertical_and_shifts(turn, shift):
    """The raster's pan and tilt stay a raster: the silhouette window is used both times."""
    rng = np.random.default_rng(101)
    truth = column(0.4, 0.3, 2.0, 40.0, 5.0, rng)
    points, _ = scan_box(truth, np.zeros(3), 6, 6, rng)
    _check_invariance(points, _rot_z(turn), np.asarray(shift), silhouette=True)


@settings(max_examples=15, deadline=None)
@given(
    yaw=st.floats(-180, 180),
    pitch=st.floats(-80, 80),
    roll=st.floats(-180, 180),
    shift=st.tuples(*[st.floats(-50, 50)] * 3),
)
def test_fit_is_invariant_under_rigid_motion(yaw, pitch, roll, shift):
    rng = np.random.default_rng(102)
    truth = column(0.4, 0.3, 2.0, 40.0, 5.0, rng)
    points, _ = scan_box(truth, np.zeros(3), 6, 6, rng)
    _check_invariance(points, _rotation(yaw, pitch, roll), np.asarray(shift), silhouette=False)


def _check_invariance(points, rot, move, silhouette):
    base = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3), silhouette=silhouette)
    moved = fit_cuboid(points @ rot.T + move, sigma=SIGMA, viewpoint=move, silhouette=silhouette)
    assert moved.diagnostics["silhouette"] == base.diagnostics["silhouette"] == float(silhouette)
    assert np.allclose(np.sort(moved.primitive.size), np.sort(base.primitive.size), atol=1e-6)
    assert np.allclose(moved.primitive.center, rot @ base.primitive.center + move, atol=1e-6)
    turned = base.primitive.axes @ rot.T
    assert np.allclose(np.abs(moved.primitive.axes @ turned.T).max(axis=1), 1.0, atol=1e-6)
    assert np.array_equal(moved.inliers, base.inliers)


# --------------------------------------------------------------------------- scan sessions


def session_scan(box: Cuboid, sensor, margins, rng, wanted=24, edge_pairs=4):
    """Points (n, 3) and the edge-shot mask (n,) of the acquisition session's algorithm
    (``asbuilt.drivers.session.scan_target``, default settings but ``edge_pairs``) shooting
    over an operator's window: the box's angular window widened on each side by ``margins``
    (4,) in steps of a ``wanted``-shot raster; beams with angular noise meet the box (the slab
    method above) or a wall 15 m away, ranges with noise, points along the nominal angles."""
    from asbuilt.drivers.plan import SessionSettings, Target, Window
    from asbuilt.drivers.session import Shot, grid, scan_target

    sensor = np.asarray(sensor, float)
    pan0, p_lo, p_hi, t_lo, t_hi = _window(box, sensor)
    rows, cols = grid(Window(p_lo, p_hi, t_lo, t_hi), wanted)[2]
    dp, dt = (p_hi - p_lo) / cols, (t_hi - t_lo) / rows
    window = Window(
        pan0 + p_lo - margins[0] * dp,
        pan0 + p_hi + margins[1] * dp,
        t_lo - margins[2] * dt,
        t_hi + margins[3] * dt,
    )

    def shoot(pan, tilt, phase):
        actual = _directions(
            np.array([pan + rng.normal(0.0, ANGLE_SIGMA)]),
            np.array([tilt + rng.normal(0.0, ANGLE_SIGMA)]),
        )
        hit = _ray_box(box, sensor, actual)[0]
        true = hit if np.isfinite(hit) else 15.0
        return Shot(pan, tilt, pan, tilt, true + rng.normal(0.0, SIGMA), None, 1, phase)

    settings = SessionSettings(edge_pairs=edge_pairs)
    result = scan_target(Target("C", "cuboid", window, points=wanted), shoot, settings)
    kept = [s for s, k in zip(result.shots, result.on_object) if k]
    pan = np.array([s.pan for s in kept])
    tilt = np.array([s.tilt for s in kept])
    ranges = np.array([s.range for s in kept])
    points = sensor + ranges[:, None] * _directions(pan, tilt)
    return points, np.array([s.phase == "edge" for s in kept])


def _session_cases():
    cases = []
    for seed in range(6):
        rng = np.random.default_rng(500 + seed)
        distance = rng.uniform(3.0, 9.0)
        if seed % 2:
            top = -distance * math.tan(math.radians(rng.uniform(20, 35)))
            truth = column(0.4, 0.35, 1.2, rng.uniform(25, 65), distance, rng, base=top - 1.2)
        else:
            truth = column(0.3, 0.4, 3.0, rng.uniform(25, 65), distance, rng, base=-1.5)
        cases.append((truth, rng.uniform(0.0, 1.0, 4), rng))
    return cases


def test_session_edge_shots_bound_the_unseen_edges():
    """Over an operator's window the raster's last lines stop up to a step short of the edges;
    the session's bisection shots pin them: sizes to about a percent, far better than the
    same scan without its edge shots, and the size's standard error says how well."""
    with_edges, without, pinned_se, raster_se = [], [], [], []
    for truth, margins, rng in _session_cases():
        points, edge = session_scan(truth, np.zeros(3), margins, rng)
        assert edge.sum() >= 4  # every side bisected, about half of the shots on the object
        fit = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
        err, _, order = match(fit.primitive, truth)
        with_edges.append(np.abs(err))
        se = np.asarray(fit.stderr["size"])[order]
        pinned_se.append(se)
        plain = fit_cuboid(points[~edge], sigma=SIGMA, viewpoint=np.zeros(3))
        plain_err, _, plain_order = match(plain.primitive, truth)
        without.append(np.abs(plain_err))
        raster_se.append(np.asarray(plain.stderr["size"])[plain_order])
    with_edges, without = np.array(with_edges), np.array(without)
    assert np.median(with_edges) < 0.01, with_edges
    # most boxes to a couple of percent on every side (a coarse raster can still leave a
    # narrow face with one column of shots, which the bisection shots do not cure)
    assert np.count_nonzero(with_edges.max(axis=1) < 0.02) >= 4, with_edges
    assert np.median(with_edges) < 0.5 * np.median(without)
    # the remaining gap: millimetres past a bisection's last hit, up to a raster step past a
    # raster line; the standard errors say so
    assert np.median(pinned_se) < 0.5 * np.median(raster_se)
    assert np.median(np.abs(without) * [t.size for t, _, _ in _session_cases()]) < 3 * np.median(
        raster_se
    )


def test_session_scan_from_a_station_off_the_origin_is_the_same_box():
    """The bisection shots are found from the viewpoint; moving everything keeps the fit."""
    truth, margins, rng = _session_cases()[0]
    points, _ = session_scan(truth, np.zeros(3), margins, rng)
    base = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
    move = np.array([10.0, -4.0, 2.0])
    moved = fit_cuboid(points + move, sigma=SIGMA, viewpoint=move)
    assert moved.primitive.size == pytest.approx(base.primitive.size, abs=1e-6)
    assert moved.primitive.center == pytest.approx(base.primitive.center + move, abs=1e-6)


@pytest.mark.parametrize("case", [1, 2, 3, 5])
def test_mixed_returns_at_the_edges_are_put_back_on_their_face(case):
    """Bisection shots grazing the edge return the wall's range or one in between; the fit
    rejects them but puts them back on their face along their beam, so they still pin it."""
    truth, margins, rng = _session_cases()[case]
    points, edge = session_scan(truth, np.zeros(3), margins, rng)
    clean = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
    mixed = points.copy()
    # up to 15 % of the points: the design limit for outliers is 20 %
    grazing = np.flatnonzero(edge)
    grazing = np.sort(rng.permutation(grazing)[: int(0.15 * len(points))])
    beams = mixed[grazing] / np.linalg.norm(mixed[grazing], axis=1)[:, None]
    mixed[grazing] += rng.uniform(0.05, 2.0, grazing.size)[:, None] * beams
    fit = fit_cuboid(mixed, sigma=SIGMA, viewpoint=np.zeros(3))
    rejected = np.count_nonzero(~fit.inliers[grazing])
    assert rejected >= 0.8 * grazing.size  # a push along a grazing beam can stay on the face
    # mended unless the raster shot a bisection leans on was rejected too
    assert fit.diagnostics["mended"] >= min(2, rejected)
    err, _, _ = match(fit.primitive, truth)
    clean_err, _, _ = match(clean.primitive, truth)
    # as good as the clean scan where every rejected shot was mended, never worse than the
    # scan without those shots at all
    dropped = fit_cuboid(np.delete(points, grazing, axis=0), sigma=SIGMA, viewpoint=np.zeros(3))
    dropped_err, _, _ = match(dropped.primitive, truth)
    assert np.all(np.abs(err) <= np.abs(dropped_err) + 0.005), (err, dropped_err)
    if fit.diagnostics["mended"] == rejected:
        assert np.all(np.abs(err) < np.abs(clean_err) + 0.01), (err, clean_err)


def _stored(name: str):
    """The scans of a stored test file next to this one, each with a readable id."""
    data = json.loads((Path(__file__).parent / name).read_text())
    scans = data["scans"]
    ids = [scan["source"].split("cell ")[1].split(" (")[0] for scan in scans]
    return pytest.mark.parametrize("scan", [dict(scan, file=data) for scan in scans], ids=ids)


def _fit_stored(scan, size_tolerance=None, rejected=0):
    """The fit of a stored scan (with the file's sensor sigma and viewpoint, either of them
    null for a scan without them), checked against the truth: every axis within 1 degree or 4
    standard errors, at most ``rejected`` shots rejected (None: not checked) and, with a
    ``size_tolerance``, every size within it (relative). Returns the fit."""
    data = scan["file"]
    fit = fit_cuboid(
        np.array(scan["points"]), sigma=data["range_sigma"], viewpoint=data["viewpoint"]
    )
    cosines = np.abs(np.asarray(scan["axes"]) @ fit.primitive.axes.T).max(axis=1)
    error = float(np.degrees(np.arccos(np.clip(cosines.min(), -1.0, 1.0))))
    assert error < max(1.0, 4 * max(fit.stderr["axes_deg"])), error
    if rejected is not None:
        assert fit.n_points - fit.n_inliers <= rejected
    if size_tolerance is not None:
        size_error = np.sort(fit.primitive.size) / np.sort(scan["size"]) - 1.0
        assert np.abs(size_error).max() < size_tolerance, size_error
    return fit


@_stored("narrow_columns_session.json")
def test_three_raster_columns_on_two_narrow_faces_take_the_corner_all_shots_support(scan):
    # Session scans (simulated, clean) of 0.2 m columns with two faces seen: the raster put
    # three columns of shots on them, which either corner explains, and the segmentation's
    # first hypothesis took the wrong one, rejecting the edge-bisection shots that disagree
    # (yaw errors of 3-14 degrees). Every shot must decide, not only the raster's.
    _fit_stored(scan, size_tolerance=0.03, rejected=1)


@_stored("session_window_sides.json")
def test_session_edge_shots_pin_the_raster_window_sides(scan):
    # Session scans (simulated, clean) of columns with 20 or 40 points. The edge bisection put
    # hits within 2 mm of each silhouette side, but the fit did not see them as pinning it: a
    # bisection's deepest hit within the line width of the raster column it started from was
    # counted on that column; a bisection that missed at every step, or whose last hit fell on
    # a fill raster's column, left its side at the raster's last line plus half a step (sizes
    # 16-38 % too large); a raster hit just past the edge (its pointing error) kept a pad of
    # half the raster's spacing although a bisection hit millimetres inside it pinned the edge
    # (18-21 %); and with a face carrying one raster column plus bisection hits, the first
    # frame was taken without comparing the other corner (2.6-7.8 degrees off).
    _fit_stored(scan, size_tolerance=0.03)


@_stored("boxes_with_background_shots.json")
def test_background_shots_never_make_a_back_face(scan):
    # Simulated raster scans (20% of the shots grazed an edge and hit the wall behind) where
    # the background shots lined up with a wrong frame's extra face: a back face opposite a
    # seen one, or a plane through the box (20-31 degrees off before). Seen from one
    # station, no face can face away.
    fit = _fit_stored(scan, size_tolerance=0.05, rejected=None)
    assert not any(fit.observed)  # one station sees no two opposite faces
    assert not fit.inliers[scan["outliers"]].any()


@_stored("single_column_faces.json")
def test_a_face_seen_as_one_raster_column_does_not_settle_the_frame(scan):
    # Clean simulated rasters over the exact window where one seen face got a single column
    # of shots: every shot is explained by the first frame, yet its direction about that
    # column is free, and another frame explains the shots better (2-5 degrees off before).
    _fit_stored(scan)


@_stored("session_late_first_faces.json")
def test_a_doubtful_fit_tries_every_first_face(scan):
    # Session scans (simulated, clean) whose right frame starts from the fourth to sixth
    # first-face hypothesis: the first frames explained most points and stopped the search,
    # and their fits rejected shots or were 5-27 degrees off.
    _fit_stored(scan, size_tolerance=0.03)


@_stored("session_pier_tops.json")
def test_a_pier_top_crossed_once_is_a_face_and_the_foot_stays_where_bisection_put_it(scan):
    # Session scans (simulated, clean) of 1.2 m piers seen from above at 20 points: the raster
    # crosses the top once, leaving it two shots (its direction is fixed by the two side
    # faces, so they are enough), and the bisection shots at the foot pin it to 2 mm, which
    # the raster window's half-step rule must not move (it put the foot 0.9 m lower). The
    # lengths were 5-75% long before.
    assert _fit_stored(scan, size_tolerance=0.03).diagnostics["faces"] == 3


@_stored("columns_without_sensor.json")
def test_without_the_sensor_the_noise_level_is_searched_not_guessed(scan):
    # Clean simulated rasters of columns fitted as for a scan with no sensor block (no sigma,
    # no viewpoint given; the raster's origin is then trusted as the viewpoint, as the station
    # stood there). The noise estimate from neighbourhood planes straddling the edges came out
    # up to ten times the noise (both faces taken as one plane: 9-42 degrees off, sizes 6-31%
    # off), or at the sigma floor (half the shots rejected), or so wide that no face was found.
    fit = _fit_stored(scan, size_tolerance=0.03, rejected=1)
    assert fit.sigma_source == "residuals"
    assert fit.diagnostics["faces"] >= 2
    assert 0.5e-3 < fit.sigma < 4e-3  # the simulated range noise is 2 mm


def test_without_a_viewpoint_raster_columns_do_not_make_four_faces():
    # Column C2 of the structural-bay sample, fitted with no sensor: its vertical raster
    # columns on two faces fit four planes in another frame as closely as two, and the fit
    # came out 85 x 131 mm with both across sizes "observed" (the column is 350 x 350 mm).
    scan = json.loads((Path(__file__).parents[2] / "samples" / "structural-bay.json").read_text())
    points = np.array(next(o["points"] for o in scan["objects"] if o["id"] == "C2"))
    fit = fit_cuboid(points)
    assert fit.diagnostics["faces"] == 2.0
    assert not any(fit.observed)
    seen = fit_cuboid(points, viewpoint=scan["sensor"]["position"])
    np.testing.assert_allclose(
        np.sort(fit.primitive.size)[-1], np.sort(seen.primitive.size)[-1], rtol=0.02
    )
    assert max(fit.primitive.size[:2]) == pytest.approx(max(seen.primitive.size[:2]), rel=0.02)


def test_without_a_sigma_the_noise_search_does_not_sink_below_the_noise():
    # A pipe (r 0.11 m) with 3 cm range noise fitted as a cuboid: the estimate's band fails,
    # narrower ones were implausible, and the search went on down to 0.7 mm, where faces of
    # three shots fit exactly (sigma 0.7 mm, a third of the shots rejected).
    from fit_scans import raster_scan

    from asbuilt.primitives import Cylinder

    axis = np.array([0.3, 0.2, 1]) / np.linalg.norm([0.3, 0.2, 1])
    pipe = Cylinder([5, 1, 1], axis, 0.11, 0.7)
    rng = np.random.default_rng(7)
    for _ in range(4):
        points = raster_scan(pipe, [0, 0, 2.0], 20, rng, sigma_range=0.03).points
        try:
            fit = fit_cuboid(points)
        except FitError:
            continue
        assert fit.sigma > 0.003


def test_a_dense_cloud_is_fitted_in_linear_memory():
    # 20,000 points on two faces of a 0.4 x 0.3 m column 5 m away: the pairwise steps sample
    # or sort instead of building 20,000 x 20,000 matrices, and the fit is still right.
    rng = np.random.default_rng(3)
    n = 10_000
    z = rng.uniform(-1.0, 1.0, 2 * n)
    front = np.column_stack([rng.uniform(-0.2, 0.2, n), np.full(n, -0.15), z[:n]])
    side = np.column_stack([np.full(n, -0.2), rng.uniform(-0.15, 0.15, n), z[n:]])
    points = np.vstack([front, side]) + np.array([1.0, 5.0, 1.0])
    points += rng.normal(0.0, 0.001, points.shape)
    result = fit_cuboid(points, sigma=0.001, viewpoint=np.zeros(3))
    size = sorted(result.primitive.size)
    assert size == pytest.approx([0.3, 0.4, 2.0], abs=0.005)
    assert result.inliers.mean() > 0.99


def _box_shots(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """40 shots (40, 3) metres spread at random over the three faces of a 0.6 x 0.5 x 0.7 m box
    (turned 30 degrees about z) that face a station at (0, 0, 1.2), with 2 mm range noise along
    the beams; and the station (3,)."""
    rng = np.random.default_rng(seed)
    station = np.array([0.0, 0.0, 1.2])
    turn = np.radians(30.0)
    rot = np.array(
        [[np.cos(turn), -np.sin(turn), 0.0], [np.sin(turn), np.cos(turn), 0.0], [0.0, 0.0, 1.0]]
    )
    centre, size = np.array([3.0, 3.0, -0.5]), np.array([0.6, 0.5, 0.7])
    shots = []
    for axis, count in zip(range(3), (14, 13, 13)):
        side = np.sign((station - centre) @ rot[:, axis])
        local = rng.uniform(-0.48, 0.48, (count, 3)) * size
        local[:, axis] = side * size[axis] / 2
        shots.append(centre + local @ rot.T)
    points = np.vstack(shots)
    beams = points - station
    beams /= np.linalg.norm(beams, axis=1)[:, None]
    return points + rng.normal(0.0, 0.002, (40, 1)) * beams, station


@pytest.mark.parametrize("seed", [4, 21, 66])
def test_a_clean_box_without_a_sigma_keeps_its_shots_wherever_it_stands(seed):
    # Without the sensor's sigma the noise-level search tries levels around its estimate; two
    # levels that settle on the same fit score the same up to rounding, and a rounding "gain"
    # or "loss" between them ended the search before the wider levels were tried. These
    # clean boxes lost 8-9 of their 40 shots, and the fit changed when the same shots were
    # given in site coordinates (an audit's box: 572 x 507 mm and 40 shots, or 530 x 514 mm
    # and 29).
    points, station = _box_shots(seed)
    here = fit_cuboid(points, viewpoint=station)
    assert here.inliers.all()
    shift = np.array([512345.678, 5412345.678, 123.4])
    there = fit_cuboid(points + shift, viewpoint=station + shift)
    assert np.sort(there.primitive.size) == pytest.approx(np.sort(here.primitive.size), abs=1e-6)
    assert there.inliers.all()


@pytest.mark.parametrize("seed", range(4))
def test_one_raster_column_on_a_grazing_side_face_is_that_face(seed):
    # An audit's ray-cast raster (7 x 6 shots over +-4.5 x +-5 degrees) of a 0.5 x 0.4 x 0.8 m
    # box 4.3 m away, turned 35 degrees: 24 shots on the front, one column of 6 on the side seen
    # at 76 degrees, 0.39 m behind the front plane (a raster step along that face). The side
    # face's shots were held to the front face's spacing (0.27 m) and rejected: 15 of 20 such
    # scans came out one face with the 6 shots thrown away, 3 as three faces 0.2 m short.
    rng = np.random.default_rng(100 + seed)
    turn = np.radians(35.0)
    rot = np.array(
        [[np.cos(turn), -np.sin(turn), 0.0], [np.sin(turn), np.cos(turn), 0.0], [0.0, 0.0, 1.0]]
    )
    centre, size = np.array([4.0, 1.5, 0.3]), np.array([0.5, 0.4, 0.8])
    box = Cuboid(centre, rot.T, size)
    aim_pan = np.arctan2(centre[1], centre[0])
    aim_tilt = np.arctan2(centre[2], np.hypot(centre[0], centre[1]))
    pan, tilt = np.meshgrid(
        aim_pan + np.radians(np.linspace(-4.5, 4.5, 7)),
        aim_tilt + np.radians(np.linspace(-5, 5, 6)),
    )
    points, hit = shoot(box, pan.ravel(), tilt.ravel(), rng, pointing_sigma=0.0)
    points = points[hit]
    result = fit_cuboid(points, sigma=0.002, viewpoint=np.zeros(3))
    assert result.diagnostics["faces"] == 2
    assert result.inliers.all()
    fitted, stderr, _ = sizes_in_true_order(result, rot)
    assert np.all(np.abs(fitted - size) <= 3.0 * np.asarray(stderr))


def test_a_face_with_seen_shots_beyond_it_is_not_added():
    # Independent ray caster, no sensor block: the noise-level search settled on a frame whose
    # third face (the "top") was one raster row across the column, 1.7 m below its highest
    # shots; those shots, inliers of the side faces, lay outside the box. A face may not close
    # a box on its own seen shots.
    scan = json.loads((Path(__file__).parent / "column_row_as_top.json").read_text())
    points = np.array(scan["points"]) * 0.001  # as the scan loader converts mm
    result = fit_cuboid(points)
    box = result.primitive
    local = (points[result.inliers] - box.center) @ np.asarray(box.axes).T
    beyond = np.abs(local) - 0.5 * np.asarray(box.size)
    assert beyond.max() < 3.0 * result.diagnostics["scale"] + 0.01
    assert max(box.size) > 3.2  # the shots span 3.2 m up the column


def test_a_first_frame_rejecting_only_background_is_the_exhaustive_choice(monkeypatch):
    # With the station known, a first frame whose rejected shots can only be background stands
    # without every other frame being fitted; it must be the frame the full comparison picks.
    stood = 0
    for seed in range(6):
        rng = np.random.default_rng(300 + seed)
        section = (0.2, 0.4, 0.6)[seed % 3]
        truth = column(section, 0.35, 3.0, (30.0, 45.0, 60.0)[seed % 3], 4 + seed, rng)
        points, _ = scan_box(truth, np.zeros(3), 6, 7, rng, outlier_fraction=0.2)
        taken, quick = _with_and_without_the_shortcut(points, monkeypatch)
        stood += any(taken)
    assert stood >= 4  # (5 of these 6 scans' rejected shots are all clear of the faces)


def test_a_raster_row_on_the_wall_behind_a_column_is_background(monkeypatch):
    # A raster row just above a column's top hits the wall behind it, every shot at about one
    # height: they lie in one plane across the column's axis, as a face left out (its top)
    # would, but metres off the box. The first frame still stands (the rule before took them
    # for a face and fitted every other frame), and it is the frame the full comparison picks.
    for seed in range(4):
        rng = np.random.default_rng(400 + seed)
        truth = column(0.4, 0.3, 3.0, (30.0, 50.0)[seed % 2], 5 + seed, rng)
        points, _ = scan_box(truth, np.zeros(3), 6, 7, rng)
        los = truth.center / np.linalg.norm(truth.center)
        wall = truth.center + 1.5 * los  # a wall 1.5 m behind the column, square to the view
        pan0, p_lo, p_hi, t_lo, t_hi = _window(truth, np.zeros(3))
        pan = pan0 + p_lo + (np.arange(6) + 0.5) / 6 * (p_hi - p_lo)  # the raster's pans
        beams = _directions(pan, np.full(6, t_hi + 0.3 * (t_hi - t_lo) / 7))
        on_wall = beams * ((wall @ los) / (beams @ los))[:, None]
        assert np.all(np.isnan(_ray_box(truth, np.zeros(3), beams)))  # they miss the column
        points = np.vstack([points, on_wall + rng.normal(0.0, SIGMA, on_wall.shape)])
        taken, quick = _with_and_without_the_shortcut(points, monkeypatch)
        assert taken == [True]
        assert np.count_nonzero(~quick.inliers) == len(on_wall)


def _with_and_without_the_shortcut(points, monkeypatch):
    """Fit ``points`` (n, 3) metres from the origin with the sensor's sigma, once as is and once
    with every first frame sent on to the exhaustive search; assert both fits are the same box
    and return what the background test said each time it was asked, and the fit."""
    original = _joint._rejected_are_background
    taken = []

    def recording(*args):
        taken.append(original(*args))
        return taken[-1]

    monkeypatch.setattr(_joint, "_rejected_are_background", recording)
    quick = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
    monkeypatch.setattr(_joint, "_rejected_are_background", lambda *args: False)
    full = fit_cuboid(points, sigma=SIGMA, viewpoint=np.zeros(3))
    monkeypatch.setattr(_joint, "_rejected_are_background", original)
    np.testing.assert_array_equal(quick.inliers, full.inliers)
    np.testing.assert_allclose(quick.primitive.size, full.primitive.size, atol=1e-9)
    np.testing.assert_allclose(quick.primitive.axes, full.primitive.axes, atol=1e-9)
    return taken, quick


def test_a_box_on_a_single_shot_is_no_fit():
    """A column before a wall, its window mostly wall (clutter benchmark scene): one frame
    discounted every other shot as background seen past its box and kept a single shot,
    sizes 0 and an orientation error of millions of degrees. Such a frame is no fit: the fit
    found is on the column's own shots, its turn about them stated as unknown."""
    data = json.loads(Path(__file__).with_name("one_shot_column.json").read_text())
    result = fit_cuboid(np.array(data["points"]), sigma=data["sigma"], viewpoint=data["station"])
    assert np.count_nonzero(result.inliers) >= 4
    axes, truth = np.asarray(result.primitive.axes), np.asarray(data["axes"])
    cosines = np.abs(axes @ truth.T).max(axis=1)
    error = np.degrees(np.arccos(np.clip(cosines, 0.0, 1.0)))
    assert np.all(error <= 3.0 * np.asarray(result.stderr["axes_deg"]) + 0.5), error
    assert np.all(np.asarray(result.primitive.size) > 0.1)
