"""Cramer-Rao lower bounds for geometric fits of sparse pan-tilt range finder points.

Derivation
----------
A shot with nominal angles (pan, tilt) meets the surface at the true point ``S = R d'`` along
the actual beam ``d' = d(pan + e_p, tilt + e_t)``; the device reports range ``R + e_r`` and the
nominal angles, so the recorded point is ``P = (R + e_r) d`` with ``d = d(pan, tilt)``. To
first order

    P - S = e_r d - R (e_p cos(tilt) u_pan + e_t u_tilt),

with ``u_pan = (-sin pan, cos pan, 0)`` and ``u_tilt = (-sin tilt cos pan, -sin tilt sin pan,
cos tilt)`` the unit directions in which pan and tilt move the beam. Only the component along the
surface normal ``n`` moves the point off the surface; the tangential components slide it along
the surface (where along the surface the beam lands is a nuisance that carries no information
about the shape to first order). The orthogonal displacement is therefore Gaussian with variance

    sigma_eff^2 = sigma_r^2 (n.d)^2 + (R sigma_a)^2 (cos^2(tilt) (n.u_pan)^2 + (n.u_tilt)^2),

which, since ``(n.d)^2 + (n.u_pan)^2 + (n.u_tilt)^2 = 1``, is the familiar
``sigma_r^2 cos^2(theta) + (R sigma_a)^2 sin^2(theta)`` (theta the incidence angle) up to the
``cos^2(tilt)`` factor on the pan part. The tests of the sensor model (``tests/sim``) check this
variance against simulated points.

The model for the data is then ``dist(P_i; theta) ~ N(0, sigma_eff_i^2)`` where ``dist`` is the
signed orthogonal distance to the surface with parameters ``theta``. The Fisher information is
the standard geometric-fit one (Kanatani 1996, "Statistical Optimization for Geometric
Computation", ch. 7; Chernov 2010, "Circular and Linear Regression", ch. 2)

    I = sum_i J_i^T J_i / sigma_eff_i^2,    J_i = d dist(S_i; theta) / d theta at the truth,

and ``Cov(theta_hat) >= I^-1`` for any unbiased estimator. Parameters (all derivatives
analytic, below):

* cylinder: radius, two axis tilts (rotations of the axis about two perpendiculars), two
  centre offsets across the axis (5 parameters);
* sphere: radius and centre (4);
* plane: two normal tilts and the offset (3);
* cuboid: three small rotations of the box frame and one offset per seen face.

Bounds reported: radius ``sqrt((I^-1)_rr)``; axis or normal ``sqrt(trace of the angle block)``
(the RMS of the angle between estimate and truth, radians); cuboid orientation likewise over its
3x3 rotation block.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "sigma_eff",
    "cylinder_bounds",
    "sphere_bounds",
    "plane_bounds",
    "cuboid_bounds",
    "perpendicular_basis",
]


def perpendicular_basis(axis) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors, each shape (3,), completing ``axis`` (3,) to an orthonormal frame."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


def sigma_eff(points, normals, station, sigma_r: float, sigma_a: float) -> np.ndarray:
    """Standard deviation of each point's displacement along the surface normal.

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
        True surface points.
    normals : array_like, shape (n, 3)
        Unit surface normals there.
    station : array_like, shape (3,), metres
        Beam origin.
    sigma_r : float, metres
        Range noise.
    sigma_a : float, radians
        Pan and tilt pointing noise (each).

    Returns
    -------
    ndarray, shape (n,), metres
    """
    rel = np.asarray(points, float) - np.asarray(station, float)
    rng = np.linalg.norm(rel, axis=1)
    d = rel / rng[:, None]
    pan = np.arctan2(d[:, 1], d[:, 0])
    tilt = np.arctan2(d[:, 2], np.hypot(d[:, 0], d[:, 1]))
    u_pan = np.stack([-np.sin(pan), np.cos(pan), np.zeros_like(pan)], axis=1)
    u_tilt = np.stack(
        [-np.sin(tilt) * np.cos(pan), -np.sin(tilt) * np.sin(pan), np.cos(tilt)], axis=1
    )
    n = np.asarray(normals, float)

    def dot(a, b):
        return np.einsum("ij,ij->i", a, b)

    var = sigma_r**2 * dot(n, d) ** 2 + (rng * sigma_a) ** 2 * (
        np.cos(tilt) ** 2 * dot(n, u_pan) ** 2 + dot(n, u_tilt) ** 2
    )
    return np.sqrt(var)


def _inverse_information(jacobian: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    weighted = jacobian / sigma[:, None]
    info = weighted.T @ weighted
    return np.linalg.pinv(info, rcond=1e-12)


def cylinder_bounds(points, center, axis, radius, sigma) -> dict:
    """Bounds for a cylinder fit.

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
        True surface points (on the lateral surface).
    center : array_like, shape (3,), metres
        A point of the true axis (the pivot of the axis tilts; the bounds do not depend on it).
    axis : array_like, shape (3,)
        True unit axis.
    radius : float, metres
    sigma : array_like, shape (n,), metres
        Each point's normal-displacement standard deviation (:func:`sigma_eff`).

    Returns
    -------
    dict
        ``radius`` (metres) and ``axis`` (radians, RMS angle) lower bounds.
    """
    p = np.asarray(points, float)
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    u, v = perpendicular_basis(a)
    w = p - np.asarray(center, float)
    h = w @ a
    radial = w - np.outer(h, a)
    n = radial / np.linalg.norm(radial, axis=1)[:, None]
    nu, nv = n @ u, n @ v
    jac = np.column_stack([-np.ones(len(p)), -h * nu, -h * nv, -nu, -nv])
    cov = _inverse_information(jac, np.asarray(sigma, float))
    return {"radius": float(np.sqrt(cov[0, 0])), "axis": float(np.sqrt(cov[1, 1] + cov[2, 2]))}


def sphere_bounds(points, center, sigma) -> dict:
    """Bounds for a sphere fit: ``radius`` (metres) and ``center`` (metres, RMS 3D).

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
        True surface points.
    center : array_like, shape (3,), metres
    sigma : array_like, shape (n,), metres
    """
    p = np.asarray(points, float)
    w = p - np.asarray(center, float)
    n = w / np.linalg.norm(w, axis=1)[:, None]
    jac = np.column_stack([-np.ones(len(p)), -n])
    cov = _inverse_information(jac, np.asarray(sigma, float))
    return {"radius": float(np.sqrt(cov[0, 0])), "center": float(np.sqrt(np.trace(cov[1:, 1:])))}


def plane_bounds(points, normal, sigma) -> dict:
    """Bounds for a plane fit: ``normal`` (radians, RMS angle) and ``offset`` (metres).

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
        True surface points.
    normal : array_like, shape (3,)
    sigma : array_like, shape (n,), metres
    """
    p = np.asarray(points, float)
    u, v = perpendicular_basis(normal)
    w = p - p.mean(axis=0)
    jac = np.column_stack([w @ u, w @ v, -np.ones(len(p))])
    cov = _inverse_information(jac, np.asarray(sigma, float))
    return {"normal": float(np.sqrt(cov[0, 0] + cov[1, 1])), "offset": float(np.sqrt(cov[2, 2]))}


def cuboid_bounds(points, normals, center, sigma) -> dict:
    """Bounds for a cuboid's orientation from points on its seen faces.

    Parameters
    ----------
    points : array_like, shape (n, 3), metres
        True surface points.
    normals : array_like, shape (n, 3)
        Outward unit normal of the face each point lies on (points on the same face share it).
    center : array_like, shape (3,), metres
        The box centre (pivot of the rotations).
    sigma : array_like, shape (n,), metres

    Returns
    -------
    dict
        ``orientation`` (radians, RMS rotation angle) and ``faces`` (number of seen faces).
    """
    p = np.asarray(points, float)
    n = np.asarray(normals, float)
    keys = np.round(n, 6)
    faces, label = np.unique(keys, axis=0, return_inverse=True)
    label = np.asarray(label).ravel()
    w = p - np.asarray(center, float)
    jac_rot = np.cross(n, w)  # d dist / d omega = n x (p - c)
    jac_off = np.zeros((len(p), len(faces)))
    jac_off[np.arange(len(p)), label] = -1.0
    cov = _inverse_information(np.hstack([jac_rot, jac_off]), np.asarray(sigma, float))
    return {"orientation": float(np.sqrt(np.trace(cov[:3, :3]))), "faces": int(len(faces))}
