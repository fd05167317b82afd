"""The pan-tilt sensor model: raster, noise statistics, dropouts, mixed returns, determinism."""

import math

import numpy as np
import pytest

from asbuilt.sim.raycast import direction_from_angles
from asbuilt.sim.scene import scene_from_dict
from asbuilt.sim.sensor import (
    EDGE_INSET,
    angular_window,
    fire,
    operator_margins,
    operator_window,
    plan_raster,
    raster_angles,
    scan_object,
    shoot,
)


def plate_scene(yaw_deg=0.0, **station):
    """A 4 m x 4 m plate 5 m in front of the station (turned by yaw about z), nothing else."""
    normal = [-math.cos(math.radians(yaw_deg)), -math.sin(math.radians(yaw_deg)), 0.0]
    return scene_from_dict(
        {
            "units": "m",
            "stations": [{"id": "S", "position": [0, 0, 0], **station}],
            "objects": [
                {
                    "id": "W",
                    "kind": "plane",
                    "geometry": {
                        "type": "plate",
                        "center": [5.0, 0, 0],
                        "normal": normal,
                        "size": [4.0, 4.0],
                        "thickness": 0.1,
                    },
                }
            ],
        }
    )


def front_face(scene, shots):
    """The shots that landed on the plate's front face (not its thin edges)."""
    return shots.subset(shots.normals @ scene.objects[0].truth.normal > 0.999)


def normal_errors(scene, shots):
    return scene.objects[0].truth.distance(shots.points)


def test_raster_covers_window_serpentine():
    pan, tilt = raster_angles((0.0, 0.0, 0.2, 0.1), 5, 3)
    assert pan.shape == (15,)
    assert pan[:5].tolist() == sorted(pan[:5].tolist())
    assert pan[5:10].tolist() == sorted(pan[5:10].tolist(), reverse=True)
    assert tilt[0] > tilt[-1]
    # cell-centred: the outer shots are half a step (0.2 / 5 / 2) inside the window
    assert pan.min() == pytest.approx(-0.08) and pan.max() == pytest.approx(0.08)
    assert sorted(set(np.round(tilt, 9))) == pytest.approx([-1 / 30, 0.0, 1 / 30])


def test_angular_window_of_sphere():
    scene = scene_from_dict(
        {
            "units": "m",
            "stations": [{"position": [0, 0, 0]}],
            "objects": [
                {
                    "id": "B",
                    "kind": "sphere",
                    "geometry": {"type": "sphere", "center": [0, 10, 0], "radius": 1.0},
                }
            ],
        }
    )
    pan0, tilt0, pan_ext, tilt_ext = angular_window(scene.objects[0].shape, np.zeros(3))
    assert pan0 == pytest.approx(np.pi / 2, abs=1e-3)
    assert tilt0 == pytest.approx(0.0, abs=1e-3)
    # the silhouette's half-angle is asin(r / d)
    assert 0.5 * pan_ext == pytest.approx(math.asin(0.1), rel=0.02)
    assert 0.5 * tilt_ext == pytest.approx(math.asin(0.1), rel=0.02)


@pytest.mark.parametrize("n", [20, 30, 40])
def test_plan_raster_lands_about_n(scene_doc, n):
    scene = scene_from_dict(scene_doc)
    for target in (0, 1, 2):
        pan, tilt, hits = plan_raster(scene, target, scene.stations[0], n)
        assert n <= hits <= 1.35 * n + 2
        shots = scan_object(scene, target, n_points=n, rng=np.random.default_rng(3), exact=True)
        assert len(shots) == n


def test_same_seed_same_shots(scene_doc):
    scene = scene_from_dict(scene_doc)
    a = scan_object(scene, 0, rng=np.random.default_rng(42))
    b = scan_object(scene, 0, rng=np.random.default_rng(42))
    c = scan_object(scene, 0, rng=np.random.default_rng(43))
    np.testing.assert_array_equal(a.points, b.points)
    assert a.points.shape != c.points.shape or not np.array_equal(a.points, c.points)


def test_range_noise_statistics_head_on():
    scene = plate_scene(range_sigma=0.002, angular_sigma_deg=0.0, mixed_return=0.0)
    shots = front_face(scene, scan_object(scene, 0, n_points=900, rng=np.random.default_rng(0)))
    err = normal_errors(scene, shots)
    # the normal error is the range error times cos(incidence) (close to 1 here)
    cos_i = np.abs(np.einsum("ij,ij->i", shots.normals, shots.directions))
    expected = 0.002 * np.sqrt(np.mean(cos_i**2))
    assert abs(err.mean()) < 4 * expected / np.sqrt(len(err))
    assert err.std() == pytest.approx(expected, rel=0.12)


@pytest.mark.parametrize("yaw", [40.0, 60.0])
def test_pointing_noise_moves_points_off_an_inclined_surface(yaw):
    sigma_a = math.radians(0.05)
    scene = plate_scene(yaw, range_sigma=0.0, angular_sigma_deg=0.05, mixed_return=0.0)
    shots = front_face(scene, scan_object(scene, 0, n_points=900, rng=np.random.default_rng(1)))
    err = normal_errors(scene, shots)
    # first order: the point moves across the beam by range * e; its normal component is
    # range * e * sin(incidence) (pan noise, the plate is turned about the vertical axis):
    # the sigma_eff of benchmarks/crb.py with no range noise
    cos_i = np.abs(np.einsum("ij,ij->i", shots.normals, shots.directions))
    sin_i = np.sqrt(1 - cos_i**2)
    predicted = np.sqrt(np.mean((shots.true_range * sigma_a * sin_i) ** 2))
    assert err.std() == pytest.approx(predicted, rel=0.12)


def test_dropout_rate():
    scene = plate_scene(dropout=0.3, mixed_return=0.0)
    station = scene.stations[0]
    pan, tilt, hits = plan_raster(scene, 0, station, 2000)
    shots = shoot(scene, 0, station, pan, tilt, np.random.default_rng(2))
    kept = len(shots) / hits
    sd = math.sqrt(0.3 * 0.7 / hits)
    assert abs(kept - 0.7) < 4 * sd


def edge_scene(with_background: bool):
    objects = [
        {
            "id": "P",
            "kind": "cylinder",
            "geometry": {
                "type": "cylinder",
                "start": [-1.0, 5.0, 0.0],
                "end": [1.0, 5.0, 0.0],
                "od": 0.2,
            },
        }
    ]
    if with_background:
        objects.append(
            {
                "id": "wall",
                "scan": False,
                "geometry": {
                    "type": "plate",
                    "center": [0, 7.0, 0],
                    "normal": [0, -1, 0],
                    "size": [10, 10],
                },
            }
        )
    return scene_from_dict(
        {
            "units": "m",
            "stations": [
                {
                    "position": [0, 0, 0],
                    "mixed_return": 1.0,
                    "beam_divergence_mrad": 4.0,
                    "range_sigma": 0.001,
                }
            ],
            "objects": objects,
        }
    )


def test_mixed_returns_land_between_object_and_background():
    scene = edge_scene(True)
    shots = scan_object(scene, 0, n_points=400, rng=np.random.default_rng(4))
    assert shots.edge.any() and not shots.edge.all()
    np.testing.assert_array_equal(shots.mixed, shots.edge)  # probability 1
    m = shots.mixed
    assert np.all(shots.range[m] > shots.true_range[m] - 0.005)
    assert np.all(shots.range[m] < shots.background_range[m] + 0.005)
    # both kinds occur: full background returns and in-between ones
    at_wall = np.abs(shots.range[m] - shots.background_range[m]) < 0.005
    assert at_wall.any() and not at_wall.all()
    clean = ~m
    assert np.abs(shots.range[clean] - shots.true_range[clean]).max() < 0.006


def test_mixed_return_with_nothing_behind_is_a_dropout():
    scene = edge_scene(False)
    station = scene.stations[0]
    pan, tilt, _ = plan_raster(scene, 0, station, 400)
    full = shoot(scene, 0, station, pan, tilt, np.random.default_rng(5))
    assert not full.mixed.any() and not full.edge.any()
    assert full.planned == len(pan)
    # the same raster with a wall behind keeps the edge shots as mixed returns
    with_wall = shoot(
        edge_scene(True), 0, edge_scene(True).stations[0], pan, tilt, np.random.default_rng(5)
    )
    assert len(with_wall) == len(full) + with_wall.mixed.sum()


def test_mixed_return_probability():
    scene = scene_from_dict(
        {
            "units": "m",
            "stations": [{"position": [0, 0, 0], "mixed_return": 0.4, "beam_divergence_mrad": 6.0}],
            "objects": [
                {
                    "id": "B",
                    "kind": "cuboid",
                    "geometry": {"type": "box", "center": [0, 5, 0], "size": [0.3, 0.3, 0.3]},
                },
                {
                    "id": "bg",
                    "scan": False,
                    "geometry": {"type": "ground", "point": [0, 9, 0], "normal": [0, 1, 0]},
                },
            ],
        }
    )
    shots = scan_object(scene, 0, n_points=3000, rng=np.random.default_rng(6))
    edges = shots.edge.sum()
    assert edges > 200
    rate = shots.mixed.sum() / edges
    assert abs(rate - 0.4) < 4 * math.sqrt(0.24 / edges)


def test_points_use_nominal_angles(scene_doc):
    scene = scene_from_dict(scene_doc)
    shots = scan_object(scene, 1, rng=np.random.default_rng(7))
    recomputed = scene.stations[0].position + shots.range[:, None] * direction_from_angles(
        shots.pan, shots.tilt
    )
    np.testing.assert_allclose(shots.points, recomputed)


def test_hidden_object_raises(scene_doc):
    scene_doc["objects"].insert(
        0,
        {
            "id": "screen",
            "scan": False,
            "geometry": {
                "type": "plate",
                "center": [0, 2.0, 1.5],
                "normal": [0, -1, 0],
                "size": [20, 10],
            },
        },
    )
    scene = scene_from_dict(scene_doc)
    with pytest.raises(ValueError, match="too few shots land on it"):
        scan_object(scene, 1)


# --------------------------------------------------------------------------- operator window


def test_operator_margins_are_four_uniforms_in_one_step():
    margins = np.array([operator_margins(np.random.default_rng(s)) for s in range(400)])
    assert margins.shape == (400, 4)
    assert margins.min() >= 0.0 and margins.max() < 1.0
    # uniform on [0, 1): mean 1/2, variance 1/12, the four sides independent
    assert abs(margins.mean() - 0.5) < 4 * math.sqrt(1 / 12 / margins.size)
    assert abs(margins.var() - 1 / 12) < 0.01
    assert np.abs(np.corrcoef(margins.T) - np.eye(4)).max() < 0.2
    np.testing.assert_array_equal(
        operator_margins(np.random.default_rng(9)), operator_margins(np.random.default_rng(9))
    )


@pytest.mark.parametrize(
    "margins", [(0.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 1.0), (0.3, 0.9, 0.6, 0.1), (1, 1, 1, 1)]
)
@pytest.mark.parametrize("dims", [(5, 5), (9, 6)])
def test_operator_window_margins_are_steps_of_the_final_raster(margins, dims):
    window = (0.4, -0.1, 0.2, 0.1)
    marked = operator_window(window, *dims, margins)
    pan, tilt = raster_angles(marked, *dims)
    pan_step = marked[2] / (dims[0] - 1 + 2 * EDGE_INSET)
    tilt_step = marked[3] / (dims[1] - 1 + 2 * EDGE_INSET)
    # the raster's own spacing is the step the margins are measured in
    assert np.diff(np.unique(np.round(pan, 12))) == pytest.approx(pan_step)
    assert np.diff(np.unique(np.round(tilt, 12))) == pytest.approx(tilt_step)
    sides = np.array(
        [
            (window[0] - 0.5 * window[2]) - (marked[0] - 0.5 * marked[2]),
            (marked[0] + 0.5 * marked[2]) - (window[0] + 0.5 * window[2]),
            (window[1] - 0.5 * window[3]) - (marked[1] - 0.5 * marked[3]),
            (marked[1] + 0.5 * marked[3]) - (window[1] + 0.5 * window[3]),
        ]
    )
    steps = np.array([pan_step, pan_step, tilt_step, tilt_step])
    np.testing.assert_allclose(sides / steps, margins, atol=1e-12)
    # the outer shots sit (margin - inset) steps beyond the silhouette window
    assert pan.max() - (window[0] + 0.5 * window[2]) == pytest.approx(
        (margins[1] - EDGE_INSET) * pan_step
    )


@pytest.mark.parametrize("margins", [(-0.1, 0, 0, 0), (0, 0, 1.2, 0), (0, 0, 0)])
def test_operator_window_rejects_bad_margins(margins):
    with pytest.raises(ValueError, match="margins"):
        operator_window((0.0, 0.0, 0.1, 0.1), 5, 5, margins)


def test_operator_window_scan_is_deterministic_and_on_the_object(scene_doc):
    scene = scene_from_dict(scene_doc)
    for target in (0, 1, 2):
        a = scan_object(scene, target, rng=np.random.default_rng(4), operator_window=True)
        b = scan_object(scene, target, rng=np.random.default_rng(4), operator_window=True)
        np.testing.assert_array_equal(a.points, b.points)
        exact = scan_object(scene, target, rng=np.random.default_rng(4))
        assert not np.array_equal(a.pan, exact.pan)
        # every recorded shot met the aimed-at object: its surface point is on the object
        truth = scene.objects[target].truth
        assert np.abs(truth.distance(a.surface_points)).max() < 1e-6


@pytest.mark.parametrize("n", [20, 30, 40])
def test_operator_window_still_lands_about_n(scene_doc, n):
    scene = scene_from_dict(scene_doc)
    for target in (0, 1, 2):
        margins = operator_margins(np.random.default_rng(n + target))
        pan, tilt, hits = plan_raster(scene, target, scene.stations[0], n, margins=margins)
        assert n <= hits <= 1.35 * n + 2
        shots = scan_object(
            scene,
            target,
            n_points=n,
            rng=np.random.default_rng(3),
            exact=True,
            operator_window=True,
        )
        assert len(shots) == n


def test_operator_window_edge_falls_between_last_hit_and_first_miss():
    """Head-on plate, no pointing noise: the gap from the last hit column to the plate's edge
    spans 0 to 1 raster step over operators, where the exact window always leaves half a step."""
    scene = plate_scene(angular_sigma_deg=0.0, range_sigma=0.0, mixed_return=0.0, dropout=0.0)
    station = scene.stations[0]
    edge = math.atan2(2.0, 4.95)  # the front face's right edge (y = -2 m, x = 4.95 m)
    gaps = []
    for seed in range(60):
        margins = operator_margins(np.random.default_rng(seed))
        pan, tilt, _ = plan_raster(scene, 0, station, 30, margins=margins)
        step = np.diff(np.unique(np.round(pan, 12))).min()
        hit = scene.raycast(station.position, direction_from_angles(pan, tilt)).object_index == 0
        gaps.append((edge - (-pan[hit].min())) / step)
    gaps = np.array(gaps)
    assert gaps.min() > -0.05 and gaps.max() < 1.05
    assert gaps.min() < 0.25 and gaps.max() > 0.75
    pan, tilt, _ = plan_raster(scene, 0, station, 30)
    step = np.diff(np.unique(np.round(pan, 12))).min()
    assert (edge - (-pan.min())) / step == pytest.approx(EDGE_INSET, abs=1e-9)


# --------------------------------------------------------------------------- single beams


@pytest.mark.parametrize("with_background", [True, False])
def test_fire_measures_whatever_each_beam_meets(with_background):
    scene = edge_scene(with_background)
    # straight at the pipe, just above it (the wall or nothing), and far off to the side
    pan = np.radians([90.0, 90.0, 60.0])
    tilt = np.radians([0.0, 3.0, 0.0])
    got = fire(scene, scene.stations[0], pan, tilt, np.random.default_rng(0))
    assert got.object_index[0] == 0
    assert got.range[0] == pytest.approx(4.9, abs=0.005)  # 5 m to the axis, radius 0.1
    assert got.surface_points[0] == pytest.approx([0.0, 4.9, 0.0], abs=0.01)
    if with_background:
        assert got.object_index[1] == 1 and got.object_index[2] == 1
        assert got.range[1] == pytest.approx(7.0 / math.cos(math.radians(3.0)), abs=0.005)
    else:
        assert np.all(got.object_index[1:] == -1)
        assert np.all(np.isnan(got.range[1:])) and np.all(np.isinf(got.true_range[1:]))
        assert np.all(np.isnan(got.surface_points[1:]))


def test_fire_draws_a_fixed_stream_and_matches_shoot_on_the_object():
    """Seven random numbers a beam, as shoot draws them: the same beams give the same ranges."""
    scene = edge_scene(True)
    station = scene.stations[0]
    pan, tilt, _ = plan_raster(scene, 0, station, 30)
    shots = shoot(scene, 0, station, pan, tilt, np.random.default_rng(9))
    got = fire(scene, station, pan, tilt, np.random.default_rng(9))
    on = got.object_index == 0
    np.testing.assert_array_equal(np.flatnonzero(on & np.isfinite(got.range)), shots.index)
    np.testing.assert_allclose(got.range[shots.index], shots.range)
    one_by_one = np.random.default_rng(9)
    singles = [fire(scene, station, [p], [t], one_by_one).range[0] for p, t in zip(pan, tilt)]
    assert np.isfinite(singles).sum() == np.isfinite(got.range).sum()
