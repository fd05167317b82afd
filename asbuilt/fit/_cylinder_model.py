"""The cylinder's least-squares model and the refinements of a settled fit.

The state is ``(axis (3,), centre on the axis (3,) metres, radius metres)``; :data:`MODEL`
gives its orthogonal residuals ``|P_perp (p - c)| - r``, their analytic Jacobian over five
parameters (two axis tilts, two across-axis centre offsets, the radius) and the update
(Lukacs, Marshall & Martin 1998; Eberly, "Fitting 3D data with a cylinder"). The refinements
act on a fit once it is chosen: shots on the far side of a pipe seen from one side are
rejected (:func:`drop_far_side`) and the inliers refitted with weights from a fitted incidence
noise model (:func:`incidence_weighted`).
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._common import basis_floats, incidence_variance, orthonormal_basis
from asbuilt.fit._robust import GeometricModel, RobustFit, gauss_newton, refit_on
from asbuilt.tolerances import Tolerances

__all__ = [
    "MODEL",
    "rms",
    "stacked",
    "angles_about",
    "mean_direction",
    "WEIGHTED_NOISE_RATIO",
    "ONE_SIDED",
    "FAR_SIDE_DEG",
    "facing",
    "drop_far_side",
    "incidence_weighted",
    "flip_covariance",
]


# State: (axis (3,), centre on the axis (3,), radius).

_FRAME_CACHE: dict[bytes, tuple] = {}


def _frame(axis: np.ndarray):
    """``(frame, u_and_v)`` for an axis: the (3, 3) matrix whose columns are ``axis, u, v``
    (``u, v`` its :func:`~asbuilt.fit._common.orthonormal_basis`), and ``u, v`` as Python
    floats (six of them, for :func:`_update`'s scalar arithmetic). Gauss-Newton asks for the
    same axis several times (the Jacobian at a state, then the update from it), so the last few
    frames are remembered."""
    key = axis.tobytes()
    found = _FRAME_CACHE.get(key)
    if found is None:
        values = axis.tolist()
        floats = basis_floats(*values)
        # One array from the floats (the rows axis, u, v, transposed: the same values and
        # memory layout as three arrays stacked, so the same products): most Jacobians are at
        # a new axis.
        frame = np.array((values, floats[:3], floats[3:])).T
        found = (frame, floats)
        if len(_FRAME_CACHE) >= 8:
            _FRAME_CACHE.clear()
        _FRAME_CACHE[key] = found
    return found


def _residuals(state, points):
    axis, center, radius = state
    across = (points - center) @ _frame(axis)[0][:, 1:]
    return np.sqrt(np.einsum("ij,ij->i", across, across)) - radius


#: Per point count, an (n, 5) array whose last column is the Jacobian's constant -1 (the
#: radius column): copying it costs less than filling that column of a new array.
_JACOBIAN_TEMPLATES: dict[int, np.ndarray] = {}


def _jacobian(state, points):
    axis, center, radius = state
    # Rows of the transposed product: one-dimensional views (numpy's per-call cost on (n, 2)
    # views is paid per row), each an integer index, cheaper than a column's tuple index.
    local = ((points - center) @ _frame(axis)[0]).T
    along, across_u, across_v = local[0], local[1], local[2]
    rho = across_u * across_u
    rho += across_v * across_v
    np.sqrt(rho, out=rho)
    np.maximum(rho, 1e-300, out=rho)
    count = len(points)
    template = _JACOBIAN_TEMPLATES.get(count)
    if template is None:
        if len(_JACOBIAN_TEMPLATES) >= 8:
            _JACOBIAN_TEMPLATES.clear()
        template = _JACOBIAN_TEMPLATES[count] = np.full((count, 5), -1.0)
    jac = template.copy()
    columns = jac.T
    tilt_u, tilt_v, shift_u, shift_v = columns[0], columns[1], columns[2], columns[3]
    minus = np.negative(rho)
    # Positional outputs: the ``out=`` keyword costs an argument parse per call.
    np.divide(across_u, minus, shift_u)  # -(eu, ev)
    np.divide(across_v, minus, shift_v)
    np.multiply(shift_u, along, tilt_u)  # -along (eu, ev)
    np.multiply(shift_v, along, tilt_v)
    rho -= radius
    return rho, jac


def _centroid(points: np.ndarray, weights: np.ndarray) -> tuple[float, float, float]:
    """The centroid of ``points`` (n, 3) metres weighted by ``weights`` (n,), as floats (the
    plain mean when the weights sum to zero)."""
    # (No memo of the last call's arrays: it saved a fraction of a percent and would go stale
    # silently the day a caller changed a weights array in place.)
    total = float(np.add.reduce(weights))  # weights.sum(), without its Python wrapper
    if total > 0:
        # Divided as Python floats: the same correctly rounded quotients as numpy's, without
        # an array operation. ndarray.dot: the same BLAS product as ``@``, less overhead.
        sx, sy, sz = weights.dot(points).tolist()
        return sx / total, sy / total, sz / total
    return tuple(points.mean(axis=0).tolist())


def _update(state, delta, points, weights):
    axis, center, radius = state
    ux, uy, uz, vx, vy, vz = _frame(axis)[1]
    d0, d1, d2, d3, d4 = delta.tolist()
    # Python floats: the same operations in the same order as on the arrays (so the same
    # rounding), without a numpy call per operation on 3-vectors.
    ax, ay, az = axis.tolist()
    ax, ay, az = ax + d0 * ux + d1 * vx, ay + d0 * uy + d1 * vy, az + d0 * uz + d1 * vz
    norm = (ax * ax + ay * ay + az * az) ** 0.5
    ax, ay, az = ax / norm, ay / norm, az / norm
    cx, cy, cz = center.tolist()
    cx, cy, cz = cx + d2 * ux + d3 * vx, cy + d2 * uy + d3 * vy, cz + d2 * uz + d3 * vz
    # Slide the centre along the axis to the weighted centroid's foot (residuals unchanged),
    # which keeps the axis tilts and the centre offsets uncorrelated.
    gx, gy, gz = _centroid(points, weights)
    slide = (gx - cx) * ax + (gy - cy) * ay + (gz - cz) * az
    new_axis = np.array((ax, ay, az))
    new_center = np.array((cx + slide * ax, cy + slide * ay, cz + slide * az))
    return new_axis, new_center, abs(radius + d4)


MODEL = GeometricModel(_residuals, _jacobian, _update, 5)


def rms(values: np.ndarray) -> float:
    """Root mean square of a 1-D array (0 when empty)."""
    return float(np.sqrt(values @ values / max(values.size, 1)))


def stacked(states) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axes (s, 3), centres (s, 3) and radii (s,) of a list of states."""
    return (
        np.array([state[0] for state in states]),
        np.array([state[1] for state in states]),
        np.array([state[2] for state in states]),
    )


def angles_about(axis: np.ndarray, center: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Each point's direction about the axis through ``center`` (3,) metres, in radians,
    shape (m,), measured in the frame ``orthonormal_basis(axis)``; ``points`` (m, 3) metres."""
    u, v = orthonormal_basis(axis)
    rel = points - center
    return np.arctan2(rel @ v, rel @ u)


def mean_direction(angles: np.ndarray) -> np.ndarray:
    """The mean of the unit vectors at ``angles`` (m,) radians: ``(mean cos, mean sin)``, shape
    (2,), summed and divided as :meth:`numpy.ndarray.mean` does."""
    count = angles.size
    return np.array([np.cos(angles).sum() / count, np.sin(angles).sum() / count])


#: Largest noise level, as a fraction of the radius, at which the inliers are weighted by
#: incidence. Range noise lies along the beam; on a curved surface seen obliquely its sideways
#: part (second order, about noise / radius of the first) biases an orthogonal fit's radius
#: low, and weighting the oblique shots up doubles that bias and makes the standard error too
#: small (measured: NPS 2-10 pipes seen by four raster columns within 55 degrees, 2-5 mm range
#: noise). Above 1% the even-weighted fit is the safer one.
WEIGHTED_NOISE_RATIO = 0.01


#: Mean resultant length of the inliers' directions about the axis above which they are taken as
#: seen from one side (one station): 0.64 for a 180 degree arc, 0.74 for 150, 0 all round.
ONE_SIDED = 0.5


#: Angle from the seen side's mean direction beyond which a point faces away from it.
FAR_SIDE_DEG = 95.0


def facing(robust: RobustFit, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each of ``points``' (n, 3) metres direction about the fit's axis (:func:`angles_about`,
    (n,) radians) and its inliers' mean direction (:func:`mean_direction`, (2,)): what
    :func:`drop_far_side` and :func:`incidence_weighted` ask of one fit."""
    axis, center, _ = robust.state
    angles = angles_about(axis, center, points)
    return angles, mean_direction(angles[robust.inliers])


def drop_far_side(
    robust: RobustFit, points: np.ndarray, tolerances: Tolerances, seen=None
) -> RobustFit:
    """Reject inliers on the far side of a pipe seen from one side, and refit without them.

    A station sees at most the half of a pipe that faces it. A shot that passed the pipe and hit
    the wall behind can land within millimetres of the *far* side of the (infinite) cylinder,
    where its distance alone cannot tell it from a surface point; there it would decide the
    radius. When the inliers' directions about the axis are concentrated (mean resultant length
    above ``ONE_SIDED``, circular statistics: Mardia & Jupp 2000), inliers more than
    ``FAR_SIDE_DEG`` from their mean direction are rejected and the fit is redone by least
    squares on the rest. ``seen``: :func:`facing` of ``robust`` when the caller has it already.
    """
    angles, mean = facing(robust, points) if seen is None else seen
    kept = robust.inliers
    resultant = float(np.hypot(*mean))
    if resultant <= ONE_SIDED:
        return robust
    offset = np.angle(np.exp(1j * (angles - np.arctan2(mean[1], mean[0]))))
    far = kept & (np.abs(offset) > np.radians(FAR_SIDE_DEG))
    if not far.any():
        return robust
    mask = kept & ~far
    if np.count_nonzero(mask) <= MODEL.n_params:
        return robust
    return refit_on(MODEL, robust, points, mask)


def incidence_weighted(
    robust: RobustFit, points: np.ndarray, seen=None
) -> tuple[RobustFit, np.ndarray]:
    """Refit the inliers by weighted least squares with a fitted incidence noise model.

    For a pipe seen from one side by a distant station, the cosine of a shot's incidence is
    proportional to ``cos(phi - phi0)``, ``phi`` its direction about the axis and ``phi0`` the
    seen side's mean direction; :func:`asbuilt.fit._common.incidence_variance` fits the noise
    model ``A + B cos^2`` and the fit is redone with weights ``1 / (A + B cos^2)``. At 3 m the
    grazing shots are several times more precise than square-on ones and weighting brings the
    radius error of a 0.6 m pipe from about 1.2 to about 1.05 times the Cramer-Rao bound
    (measured). With even noise (as at 10 m), a pipe seen all round, or a noise level above
    ``WEIGHTED_NOISE_RATIO`` of the radius (thin pipes, where the range noise's sideways part
    biases the radius and weighting would make that worse) the weights are 1.

    Returns the refitted RobustFit (same inliers) and each point's variance relative to a
    square-on shot, shape (n,). ``seen``: :func:`facing` of ``robust`` when the caller has it
    already.
    """
    n = len(points)
    uniform = np.ones(n)
    axis, center, radius = robust.state
    if robust.scale > WEIGHTED_NOISE_RATIO * radius:
        return robust, uniform
    angles, mean = facing(robust, points) if seen is None else seen
    kept = robust.inliers
    if float(np.hypot(*mean)) <= ONE_SIDED or np.count_nonzero(kept) < 8:
        return robust, uniform
    square_on = np.cos(angles - np.arctan2(mean[1], mean[0])) ** 2
    relative = incidence_variance(robust.residuals, square_on, kept)
    if relative is None:
        return robust, uniform
    weights = np.where(kept, 1.0 / relative, 0.0)
    # With every point an inlier, the fit's Jacobian is the full one at its state.
    current = (robust.residuals, robust.jacobian) if kept.all() else None
    state, residuals, jacobian = gauss_newton(
        MODEL, robust.state, points, lambda _r, w=weights: w, 6, 1e-7, current
    )
    return RobustFit(state, residuals, kept, jacobian[kept], robust.scale), relative


def flip_covariance(covariance, axis, oriented):
    """Express the covariance in the basis of the oriented (possibly negated) axis."""
    u_old, v_old = orthonormal_basis(axis)
    u_new, v_new = orthonormal_basis(oriented)
    rotation = np.array([[u_new @ u_old, u_new @ v_old], [v_new @ u_old, v_new @ v_old]])
    transform = np.eye(5)
    transform[0:2, 0:2] = -rotation
    transform[2:4, 2:4] = rotation
    return transform @ covariance @ transform.T
