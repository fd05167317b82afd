"""Convex hulls: closed, outward-wound, residuals, planar sets extruded, errors."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit.hull import fit_hull
from asbuilt.tolerances import DEFAULT_TOLERANCES


def _closed_and_outward(hull) -> float:
    """Assert every edge is shared by exactly two faces in opposite directions; return volume."""
    edges = {}
    for face in hull.faces:
        for a, b in ((face[0], face[1]), (face[1], face[2]), (face[2], face[0])):
            edges[(a, b)] = edges.get((a, b), 0) + 1
    for (a, b), count in edges.items():
        assert count == 1 and edges.get((b, a)) == 1
    tri = hull.vertices[hull.faces]
    volume = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6.0
    assert volume > 0  # counter-clockwise seen from outside
    return volume


def test_hull_of_a_cube_with_interior_points():
    corners = np.array(list(itertools.product([0.0, 2.0], repeat=3))) + [1, 2, 3]
    interior = np.array([[2.0, 3.0, 4.0], [1.5, 2.5, 4.5]])
    fit = fit_hull(np.vstack([corners, interior]))
    hull = fit.primitive
    assert fit.kind == "hull" and len(hull.vertices) == 8 and len(hull.faces) == 12
    assert _closed_and_outward(hull) == pytest.approx(8.0)
    np.testing.assert_allclose(fit.residuals[:8], 0, atol=1e-12)
    np.testing.assert_allclose(fit.residuals[8:], [-1.0, -0.5])
    assert fit.inliers.all() and fit.stderr == {} and fit.covariance is None
    assert fit.diagnostics["volume"] == pytest.approx(8.0)
    assert fit.diagnostics["extruded"] == 0.0


def test_a_wall_seen_from_one_side_becomes_a_closed_plate_behind_it():
    rng = np.random.default_rng(3)
    points = np.column_stack([np.full(30, 5.0), rng.uniform(-2, 2, 30), rng.uniform(0, 3, 30)])
    fit = fit_hull(points)
    hull = fit.primitive
    _closed_and_outward(hull)
    thickness = DEFAULT_TOLERANCES.plate_thickness
    # Extruded away from the station at the origin: x from 5 to 5 + thickness.
    assert hull.vertices[:, 0].min() == pytest.approx(5.0)
    assert hull.vertices[:, 0].max() == pytest.approx(5.0 + thickness)
    np.testing.assert_allclose(fit.residuals[fit.residuals > -1e-9], 0)
    assert np.all(fit.residuals <= 0) and np.all(fit.residuals >= -1e-9)
    assert fit.diagnostics["extruded"] == 1.0
    assert any("extruded" in note for note in fit.notes)


def test_a_small_part_is_not_taken_for_a_plane():
    """Points of a 6 x 6 x 3 mm part (0.02 mm noise) were "nearly planar" against the 10 mm plate
    thickness and extruded 10 mm: a hull of 276 mm^3 for 43 mm^3 of part."""
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(1)
    directions = rng.normal(size=(40, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    points = [0.08, 0.05, 0.005] + directions * [0.003, 0.003, 0.0015]
    points += rng.normal(scale=2e-5, size=points.shape)
    fit = fit_hull(points, sigma=2e-5)
    assert fit.diagnostics["extruded"] == 0.0
    assert _closed_and_outward(fit.primitive) == pytest.approx(ConvexHull(points).volume)
    np.testing.assert_allclose(np.ptp(fit.primitive.vertices, axis=0), np.ptp(points, axis=0))


def test_a_small_flat_part_is_padded_in_proportion_to_its_size():
    rng = np.random.default_rng(2)
    points = np.column_stack(
        [np.full(30, 1.0), rng.uniform(0, 0.005, 30), rng.uniform(0, 0.004, 30)]
    )
    fit = fit_hull(points)
    assert fit.diagnostics["extruded"] == 1.0
    depth = np.ptp(fit.primitive.vertices[:, 0])
    # At most PAD_RATIO (5%) of its width (4-5 mm), not the 10 mm plate thickness.
    assert 0.0001 < depth <= 0.05 * np.ptp(points, axis=0).max()
    _closed_and_outward(fit.primitive)


def test_a_noisy_wall_is_still_planar_and_becomes_a_plate():
    """Its thickness is the sensor's noise (3 mm sigma), so it is flat: a plate behind it."""
    rng = np.random.default_rng(4)
    n = 200
    points = np.column_stack(
        [5.0 + rng.normal(scale=0.003, size=n), rng.uniform(-2, 2, n), rng.uniform(0, 3, n)]
    )
    fit = fit_hull(points, sigma=0.003)
    assert fit.diagnostics["extruded"] == 1.0
    assert fit.primitive.vertices[:, 0].max() == pytest.approx(
        points[:, 0].max() + DEFAULT_TOLERANCES.plate_thickness, abs=0.01
    )


def test_the_sensor_sigma_is_reported():
    points = np.array(list(itertools.product([0.0, 1.0], repeat=3)))
    assert fit_hull(points, sigma=0.003).sigma == 0.003
    assert fit_hull(points).sigma_source == "residuals"


@pytest.mark.parametrize(
    "points, message",
    [
        (np.zeros((3, 3)), "at least 4 points"),
        (np.ones((5, 3)), "identical"),
        (np.outer(np.arange(5.0), [1, 2, 0]), "collinear"),
    ],
)
def test_degenerate_points_raise(points, message):
    with pytest.raises(FitError, match=message):
        fit_hull(points)
