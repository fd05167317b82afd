"""The cylinder fit's quick path: when the first axis starts' fit stands without the full search."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from fit_scans import angle_deg, raster_scan

from asbuilt.errors import FitError
from asbuilt.fit import cylinder as cylinder_module
from asbuilt.fit._common import local_normals
from asbuilt.fit._cylinder_model import MODEL
from asbuilt.fit._cylinder_quick import CLEAR_OF_CUTOFFS, quick_fit, rejected_are_background
from asbuilt.fit._cylinder_starts import axis_starts
from asbuilt.fit._robust import RobustFit, keep_count, refit_on
from asbuilt.fit.cylinder import fit_cylinder
from asbuilt.primitives import Cylinder
from asbuilt.tolerances import DEFAULT_TOLERANCES

SENSOR = np.zeros(3)
SIGMA = 0.002
CUTOFF = DEFAULT_TOLERANCES.outlier_cutoff_sigma * SIGMA


def _pipe(od, length_over_d, distance, axis):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return Cylinder([distance, 0.3 * distance, 0.5], axis, od / 2, od * length_over_d)


def _quick(points, view=SENSOR, sigma=SIGMA):
    """:func:`quick_fit` on ``points`` (n, 3) metres as the cylinder fit calls it (centred, with
    the normals' and principal axes' starts); ``view`` (3,) metres in the scan's frame."""
    offset = points.mean(axis=0)
    local = points - offset
    tolerances = DEFAULT_TOLERANCES
    axes = axis_starts(local, *local_normals(local, tolerances.normal_neighbours))
    keep = keep_count(len(local), tolerances)
    return quick_fit(local, axes, keep, sigma, None if view is None else view - offset, tolerances)


def _pushed(points, index, distance, view=SENSOR):
    """``points`` with shot ``index`` moved ``distance`` metres along its beam from ``view``
    (positive: farther)."""
    moved = points.copy()
    beam = moved[index] - view
    moved[index] += distance * beam / np.linalg.norm(beam)
    return moved


PIPE = _pipe(0.1143, 3, 4, [1, 0.4, 0.2])


@pytest.fixture
def clean(rng):
    """A clean 40-shot raster over ``PIPE``, an NPS 4 pipe 4 m away, shape (40, 3) metres."""
    return raster_scan(PIPE, SENSOR, 40, rng).points


def _quick_and_full(points, view, monkeypatch):
    """The fit of ``points`` (n, 3) metres as it is, and with every shortcut off (the quick
    path and the full search's background test): each a FitResult or the refusal's text;
    and what the quick path returned."""
    taken = []
    original = cylinder_module._quick_fit

    def recording(*args):
        taken.append(original(*args))
        return taken[-1]

    def outcome():
        try:
            return fit_cylinder(points, sigma=SIGMA, viewpoint=view)
        except FitError as error:
            return str(error)

    monkeypatch.setattr(cylinder_module, "_quick_fit", recording)
    quick = outcome()
    monkeypatch.setattr(cylinder_module, "_quick_fit", lambda *args: None)
    monkeypatch.setattr(cylinder_module, "rejected_are_background", lambda *args: False)
    full = outcome()
    monkeypatch.undo()
    return quick, full, taken[0] if taken else None


def _assert_same_fit(quick, full):
    if isinstance(full, str):  # refused (shots seen edge-on): refused alike
        assert quick == full
        return
    np.testing.assert_array_equal(quick.inliers, full.inliers)
    assert quick.primitive.radius == pytest.approx(full.primitive.radius, abs=1e-6)
    assert angle_deg(quick.primitive.axis, full.primitive.axis) < 1e-3
    assert quick.stderr["radius"] == pytest.approx(full.stderr["radius"], rel=1e-3)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("with_view", [False, True])
def test_the_quick_fit_of_a_clean_scan_is_the_full_search_fit(seed, with_view, monkeypatch):
    # Clean 40-shot scans take the quick fit (the first axis starts alone); it must settle on
    # the full search's minimum, to the convergence tolerance.
    rng = np.random.default_rng(seed)
    od = (0.0603, 0.1143, 0.2191, 0.3238, 0.6096, 0.1683)[seed]
    pipe = _pipe(od, (1, 3, 10)[seed % 3], 3.0 + seed, [1, 0.3 + 0.2 * seed, 0.2])
    points = raster_scan(pipe, SENSOR, 40, rng).points
    quick, full, taken = _quick_and_full(points, SENSOR if with_view else None, monkeypatch)
    assert taken is not None and not taken[2]
    _assert_same_fit(quick, full)


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("with_view", [False, True])
def test_a_quick_fit_rejecting_background_shots_is_the_full_search_fit(
    seed, with_view, monkeypatch
):
    # A fifth of the shots came back from behind the pipe (mixed returns and the wall, 5 cm to
    # 2 m beyond it along their beams). Where the shortcuts stand they must settle where the
    # full search does: the same inliers, and the same cylinder to the convergence tolerance.
    rng = np.random.default_rng(100 + seed)
    od = (0.0603, 0.1143, 0.2191, 0.3238, 0.6096, 0.1683, 0.1143, 0.2191)[seed]
    pipe = _pipe(od, (1, 3, 10)[seed % 3], 3.0 + seed, [1, 0.3 + 0.2 * seed, 0.2])
    sample = raster_scan(pipe, SENSOR, 40, rng, outlier_fraction=0.2)
    quick, full, taken = _quick_and_full(sample.points, SENSOR if with_view else None, monkeypatch)
    _assert_same_fit(quick, full)
    if taken is not None and taken[2]:
        assert not quick.inliers[sample.outliers].any()


def test_a_clean_scan_is_fitted_quickly_with_and_without_the_viewpoint(clean):
    for view in (SENSOR, None):
        found = _quick(clean, view)
        assert found is not None and found[0].inliers.all() and not found[2]


def test_a_shot_from_the_wall_behind_is_rejected_as_background(clean):
    walled = _pushed(clean, 7, 2.0)
    for view in (SENSOR, None):
        found = _quick(walled, view)
        assert found is not None and found[2]
        assert np.flatnonzero(~found[0].inliers).tolist() == [7]


@pytest.mark.parametrize("with_view", [False, True])
def test_shots_off_the_pipe_in_front_of_it_are_left_to_the_full_search(clean, with_view):
    # In front of the pipe and off it, a shot hit something else first (another pipe, or this
    # one if the fit is wrong): not background.
    front = _pushed(_pushed(clean, 7, -0.3), 20, -0.4)
    assert _quick(front, SENSOR if with_view else None) is None


def test_a_rejected_shot_near_the_pipe_is_left_to_the_full_search(clean):
    # A shot just beyond the inlier cutoff may be a good one that a nearby basin keeps. Moved
    # into the pipe across its axis (deeper along its beam than the surface).
    def sunk(depth):
        moved = clean.copy()
        rel = moved[7] - PIPE.center
        across = rel - (rel @ PIPE.axis) * PIPE.axis
        moved[7] -= depth * across / np.linalg.norm(across)
        return moved

    assert _quick(sunk(0.8 * CLEAR_OF_CUTOFFS * CUTOFF)) is None
    found = _quick(sunk(3.0 * CLEAR_OF_CUTOFFS * CUTOFF))
    assert found is not None and np.flatnonzero(~found[0].inliers).tolist() == [7]


def test_more_background_than_the_trimmed_cost_allows_is_left_to_the_full_search(clean):
    # 12 of 40 shots (30%) pushed behind: beyond the trimmed cost's design contamination.
    walled = clean
    for index in range(0, 40, 4)[:10]:
        walled = _pushed(walled, index, 1.5)
    assert _quick(walled) is not None  # 10 of 40: within it
    for index in (2, 6):
        walled = _pushed(walled, index, 1.5)
    assert _quick(walled) is None


def test_excess_noise_or_a_wrong_viewpoint_is_left_to_the_full_search(clean, rng):
    walled = _pushed(clean, 7, 2.0)
    # Noise five times the stated sigma fails the chi-square test.
    assert _quick(walled + rng.normal(0.0, 0.01, walled.shape)) is None
    # A viewpoint on the far side: the fit hides its own inliers behind itself.
    center = clean.mean(axis=0)
    assert _quick(walled, view=2 * center - SENSOR) is None


def test_a_thinner_pipe_sharing_a_wider_ones_near_side_is_left_to_the_full_search():
    # Four raster columns over an NPS 12 pipe: the first axes settle on a pipe of half its
    # radius that keeps three columns and rejects the fourth, 7-10 cm off it but in front of
    # its silhouette. The quick path refuses it; the full search finds the pipe.
    scan = json.loads((Path(__file__).parent / "thinner_pipe_on_the_near_side.json").read_text())
    points, station = np.array(scan["points"]), np.array(scan["station"])
    assert _quick(points, station, scan["range_sigma"]) is None
    fit = fit_cylinder(points, sigma=scan["range_sigma"], viewpoint=station)
    assert abs(fit.primitive.radius - scan["radius"]) <= 3.0 * fit.stderr["radius"]


def test_a_mixed_return_kept_inside_the_pipe_is_left_to_the_full_search(clean):
    # A shot near the silhouette whose return came from along its beam beyond the pipe's
    # surface: inside the pipe by 1.5 sigma, within the inlier cutoff, so a fit keeps it (and
    # comes out thin); the full search rejects it. One wall shot makes the fit reject a shot.
    # (Without the viewpoint, beams taken parallel catch such returns off the silhouette, 15 of
    # the 16 on the benchmark, but not this one at it: docs/fitting.md.)
    view = SENSOR
    walled = _pushed(clean, 7, 2.0)
    assert _quick(walled, view) is not None
    rel = clean - PIPE.center
    across = rel - np.outer(rel @ PIPE.axis, PIPE.axis)
    beams = (clean - SENSOR) / np.linalg.norm(clean - SENSOR, axis=1)[:, None]
    incidence = np.abs(
        np.einsum("ij,ij->i", beams, across / np.linalg.norm(across, axis=1)[:, None])
    )
    # The most grazing shot (other than the wall shot) that a push along its beam puts 1.5-2.5
    # sigma inside the pipe, pushed more than the cutoff.
    for silhouette in np.argsort(incidence):
        if silhouette == 7:
            continue
        for push in np.linspace(1.5 * CUTOFF, 0.06, 60):
            mixed = _pushed(walled, silhouette, push)
            inside = -float(PIPE.distance(mixed[silhouette : silhouette + 1])[0])
            if 1.5 * SIGMA <= inside <= 2.5 * SIGMA:
                break
        else:
            continue
        break
    else:
        pytest.fail("no push along a shot's beam lands 1.5-2.5 sigma inside the pipe")
    found = _quick(mixed, view)
    assert found is None or not found[0].inliers[silhouette]


def test_floor_shots_in_front_of_a_columns_foot_are_background():
    """A rejected shot whose beam passed the fitted pipe's end met no pipe: floor shots in front
    of a plumb column's foot lay "in front of" the infinite cylinder below the floor, and the
    quick fit was left to the full search."""
    rng = np.random.default_rng(11)
    view = np.array([0.0, 0.0, 1.5])
    pipe = Cylinder([4.0, 0.0, 0.5], [0.0, 0.0, 1.0], 0.1, 1.0)
    pan, z = np.meshgrid(np.radians(np.linspace(-1.2, 1.2, 5)), np.linspace(0.05, 0.95, 8))
    # Each beam's first crossing of the pipe (plumb: solve across the axis, z follows).
    across = np.column_stack([np.cos(pan.ravel()), np.sin(pan.ravel())])
    reach = 4.0 * across[:, 0] - np.sqrt(0.01 - (4.0 * across[:, 1]) ** 2)
    on_pipe = np.column_stack([across * reach[:, None], z.ravel()])
    floor = np.array([[3.5, -0.05, 0.0], [3.5, 0.0, 0.0], [3.5, 0.05, 0.0]])
    points = np.vstack([on_pipe, floor])
    beams = points - view
    points = (
        view
        + beams * (1 + rng.normal(0, SIGMA, len(points)) / np.linalg.norm(beams, axis=1))[:, None]
    )
    offset = points.mean(axis=0)
    local = points - offset
    mask = np.arange(len(points)) < len(on_pipe)
    state = (pipe.axis, pipe.center - offset, pipe.radius)
    start = RobustFit(state, MODEL.residuals(state, local), mask, np.zeros((0, 5)), SIGMA)
    robust = refit_on(MODEL, start, local, mask)
    assert rejected_are_background(robust, local, SIGMA, view - offset, DEFAULT_TOLERANCES)
