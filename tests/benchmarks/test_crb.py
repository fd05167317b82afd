"""The Cramer-Rao bounds of benchmarks/crb.py against independent derivations."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import crb  # noqa: E402

from asbuilt.primitives import Cylinder, Sphere  # noqa: E402


def test_plane_bound_equals_weighted_least_squares_covariance():
    # z = a x + b y + c with independent normal noise is a linear model: the weighted least
    # squares covariance (X^T W X)^-1 is the exact Cramer-Rao bound; the normal tilts are a, b.
    rng = np.random.default_rng(0)
    xy = rng.uniform(-1, 1, size=(30, 2))
    points = np.column_stack([xy, np.zeros(30)])
    sigma = rng.uniform(0.001, 0.004, size=30)
    design = np.column_stack([xy - xy.mean(axis=0), np.ones(30)])
    cov = np.linalg.inv(design.T @ (design / sigma[:, None] ** 2))
    bound = crb.plane_bounds(points, [0, 0, 1], sigma)
    assert bound["normal"] == pytest.approx(np.sqrt(cov[0, 0] + cov[1, 1]), rel=1e-9)
    assert bound["offset"] == pytest.approx(np.sqrt(cov[2, 2]), rel=1e-9)


def _numeric_cylinder_bounds(points, center, axis, radius, sigma):
    """The same Fisher information from finite differences of Cylinder.distance."""
    u, v = crb.perpendicular_basis(axis)

    def dist(theta):
        r, a, b, s, t = theta
        ax = axis + a * u + b * v
        ax = ax / np.linalg.norm(ax)
        cyl = Cylinder(center=center + s * u + t * v, axis=ax, radius=radius + r, length=1.0)
        return cyl.distance(points)

    h = 1e-6
    jac = np.column_stack([(dist(h * e) - dist(-h * e)) / (2 * h) for e in np.eye(5)])
    cov = np.linalg.inv(jac.T @ (jac / sigma[:, None] ** 2))
    return np.sqrt(cov[0, 0]), np.sqrt(cov[1, 1] + cov[2, 2])


def test_cylinder_bound_matches_numeric_jacobian():
    rng = np.random.default_rng(1)
    axis = np.array([1.0, 0.2, 0.1])
    axis /= np.linalg.norm(axis)
    center = np.array([5.0, 1.0, 0.5])
    radius = 0.1
    u, v = crb.perpendicular_basis(axis)
    phi = rng.uniform(-1.2, 1.2, 40)  # a partial arc, as a range finder sees it
    h = rng.uniform(-0.5, 0.5, 40)
    points = (
        center + np.outer(h, axis) + radius * (np.outer(np.cos(phi), u) + np.outer(np.sin(phi), v))
    )
    sigma = rng.uniform(0.0015, 0.003, 40)
    radius_bound, axis_bound = _numeric_cylinder_bounds(points, center, axis, radius, sigma)
    bound = crb.cylinder_bounds(points, center, axis, radius, sigma)
    assert bound["radius"] == pytest.approx(radius_bound, rel=1e-4)
    assert bound["axis"] == pytest.approx(axis_bound, rel=1e-4)


def test_sphere_full_coverage_closed_form():
    # Points spread evenly over the whole sphere with one sigma: I = n/sigma^2 diag(1, 1/3 I3),
    # so the radius bound is sigma / sqrt(n).
    k = np.arange(400) + 0.5
    z = 1 - 2 * k / 400
    phi = np.pi * (1 + 5**0.5) * k
    s = np.sqrt(1 - z**2)
    unit = np.column_stack([s * np.cos(phi), s * np.sin(phi), z])
    center = np.array([1.0, 2.0, 3.0])
    points = center + 0.5 * unit
    bound = crb.sphere_bounds(points, center, np.full(400, 0.002))
    assert bound["radius"] == pytest.approx(0.002 / 20, rel=0.01)
    assert Sphere(center=center, radius=0.5).distance(points) == pytest.approx(0, abs=1e-12)


def test_sigma_eff_limits():
    station = np.zeros(3)
    points = np.array([[5.0, 0, 0], [5.0, 0, 0]])
    head_on = np.array([[-1.0, 0, 0], [0.0, -1, 0]])  # facing the beam; grazing (side-on)
    s = crb.sigma_eff(points, head_on, station, 0.002, 1e-3)
    assert s[0] == pytest.approx(0.002)
    assert s[1] == pytest.approx(5.0 * 1e-3)


def test_cuboid_bound_shrinks_with_more_points():
    rng = np.random.default_rng(2)
    centre = np.zeros(3)

    def face_points(n):
        a = np.column_stack([np.full(n, -0.2), rng.uniform(-0.2, 0.2, n), rng.uniform(-1, 1, n)])
        b = np.column_stack([rng.uniform(-0.2, 0.2, n), np.full(n, -0.2), rng.uniform(-1, 1, n)])
        normals = np.vstack([np.tile([-1.0, 0, 0], (n, 1)), np.tile([0, -1.0, 0], (n, 1))])
        return np.vstack([a, b]), normals

    p1, n1 = face_points(15)
    p2, n2 = face_points(60)
    b1 = crb.cuboid_bounds(p1, n1, centre, np.full(len(p1), 0.002))
    b2 = crb.cuboid_bounds(p2, n2, centre, np.full(len(p2), 0.002))
    assert b1["faces"] == b2["faces"] == 2
    assert b2["orientation"] == pytest.approx(b1["orientation"] / 2, rel=0.35)
