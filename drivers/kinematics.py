"""The kinematic chain of a range finder on a pan-tilt unit, with its calibration parameters.

A measurement (unit pan angle, unit tilt angle, raw range) becomes a point in the scan frame::

    P = T_base * Rz(pan) * [ t_tilt + Rx(tau) * Ry(-tilt) * ( o_laser + (s * range + r0) * d ) ]
    pan  = sign_p * k_p * pan_unit  + pan0          (likewise tilt)
    d    = Rz(dh) * Ry(-dv) * x_hat

(the chain in /work/shared/reference/protocols.md: z up the pan axis, x forward, positive tilt
looks up). ``T_base = (R, t)`` with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` places the unit in the scan
frame. The same chain drives the device simulators (with their own "true" calibration), so a
calibration estimated from simulated shots can be checked against the injected one.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace

import numpy as np

__all__ = [
    "Calibration",
    "PARAMETERS",
    "forward",
    "beam",
    "aim",
    "rotation_base",
]

#: Scalar parameter names (vector components as ``name.x``), in the order calibration uses them.
PARAMETERS = (
    "pan_scale",
    "pan_zero",
    "tilt_scale",
    "tilt_zero",
    "tilt_axis_offset.x",
    "tilt_axis_offset.y",
    "tilt_axis_offset.z",
    "tilt_axis_skew",
    "laser_offset.x",
    "laser_offset.y",
    "laser_offset.z",
    "beam_horizontal",
    "beam_vertical",
    "range_offset",
    "range_scale",
    "base_position.x",
    "base_position.y",
    "base_position.z",
    "base_rotation.roll",
    "base_rotation.pitch",
    "base_rotation.yaw",
)

_COMPONENTS = {"x": 0, "y": 1, "z": 2, "roll": 0, "pitch": 1, "yaw": 2}


def _vec3(value, name: str) -> tuple[float, float, float]:
    arr = np.asarray(value, dtype=float).reshape(-1)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be 3 finite numbers, got {value!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


@dataclass(frozen=True)
class Calibration:
    """Parameters of the chain; metres and radians.

    Attributes
    ----------
    pan_sign, tilt_sign : int
        +1 or -1: whether a positive unit angle turns left (pan) / up (tilt) in the scan frame.
    pan_scale, tilt_scale : float
        Ratio of true to nominal angle per count (1 for a unit that keeps its resolution).
    pan_zero, tilt_zero : float
        Radians added after sign and scale (the unit's zero is not the frame's x axis).
    tilt_axis_offset : (3,) metres
        Tilt axis origin from the pan axis origin (PTU-D46: about 0.047 m up).
    tilt_axis_skew : float
        Radians; rotation of the tilt axis about x (non-orthogonal axes).
    laser_offset : (3,) metres
        Lever arm: the laser's origin from the tilt axis, in the tilted frame.
    beam_horizontal, beam_vertical : float
        Radians; beam misalignment dh (about z) and dv (about -y) from the tilted x axis.
    range_offset : float
        Metres added to the scaled range (r0).
    range_scale : float
        Multiplies the raw range (s).
    base_position : (3,) metres
        Pan axis origin in the scan frame.
    base_rotation : (3,) radians
        Roll, pitch, yaw of the unit's base in the scan frame (R = Rz(yaw) Ry(pitch) Rx(roll)).
    """

    pan_sign: int = 1
    pan_scale: float = 1.0
    pan_zero: float = 0.0
    tilt_sign: int = 1
    tilt_scale: float = 1.0
    tilt_zero: float = 0.0
    tilt_axis_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    tilt_axis_skew: float = 0.0
    laser_offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    beam_horizontal: float = 0.0
    beam_vertical: float = 0.0
    range_offset: float = 0.0
    range_scale: float = 1.0
    base_position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    base_rotation: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("pan_sign", "tilt_sign"):
            if getattr(self, name) not in (1, -1):
                raise ValueError(f"{name} must be +1 or -1, got {getattr(self, name)!r}")
        for name in ("tilt_axis_offset", "laser_offset", "base_position", "base_rotation"):
            object.__setattr__(self, name, _vec3(getattr(self, name), name))
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float) and not np.isfinite(value):
                raise ValueError(f"{f.name} must be finite, got {value!r}")
        if self.pan_scale <= 0 or self.tilt_scale <= 0 or self.range_scale <= 0:
            raise ValueError("pan_scale, tilt_scale and range_scale must be positive")

    def get(self, name: str) -> float:
        """One scalar parameter by its :data:`PARAMETERS` name (e.g. ``"laser_offset.z"``)."""
        field_name, _, comp = name.partition(".")
        value = getattr(self, field_name)
        return float(value[_COMPONENTS[comp]]) if comp else float(value)

    def to_vector(self, names=PARAMETERS) -> np.ndarray:
        """The named parameters as a float array, shape (len(names),)."""
        return np.array([self.get(n) for n in names], dtype=float)

    def with_vector(self, names, values) -> Calibration:
        """A copy with the named parameters set from ``values`` (same order as ``names``)."""
        changes: dict = {}
        for name, value in zip(names, np.asarray(values, dtype=float)):
            field_name, _, comp = name.partition(".")
            if field_name not in {f.name for f in fields(self)}:
                raise KeyError(name)
            if comp:
                vec = list(changes.get(field_name, getattr(self, field_name)))
                vec[_COMPONENTS[comp]] = float(value)
                changes[field_name] = tuple(vec)
            else:
                changes[field_name] = float(value)
        return replace(self, **changes)

    def physical_angles(self, pan, tilt) -> tuple[np.ndarray, np.ndarray]:
        """Unit angles (rad, any shape) to the chain's pan and tilt (rad, same shape)."""
        pan = np.asarray(pan, dtype=float)
        tilt = np.asarray(tilt, dtype=float)
        return (
            self.pan_sign * self.pan_scale * pan + self.pan_zero,
            self.tilt_sign * self.tilt_scale * tilt + self.tilt_zero,
        )

    def unit_angles(self, pan, tilt) -> tuple[np.ndarray, np.ndarray]:
        """Inverse of :meth:`physical_angles`."""
        pan = np.asarray(pan, dtype=float)
        tilt = np.asarray(tilt, dtype=float)
        return (
            (pan - self.pan_zero) / (self.pan_sign * self.pan_scale),
            (tilt - self.tilt_zero) / (self.tilt_sign * self.tilt_scale),
        )


def _rz(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack(
        [np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2
    )


def _ry(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack(
        [np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2
    )


def _rx(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack(
        [np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2
    )


def rotation_base(calibration: Calibration) -> np.ndarray:
    """The base rotation ``Rz(yaw) Ry(pitch) Rx(roll)``, shape (3, 3)."""
    roll, pitch, yaw = (np.asarray(v) for v in calibration.base_rotation)
    return _rz(yaw) @ _ry(pitch) @ _rx(roll)


def _beam_direction(calibration: Calibration) -> np.ndarray:
    dh, dv = calibration.beam_horizontal, calibration.beam_vertical
    return np.array([np.cos(dh) * np.cos(dv), np.sin(dh) * np.cos(dv), np.sin(dv)])


def beam(calibration: Calibration, pan, tilt) -> tuple[np.ndarray, np.ndarray]:
    """The ray the range finder measures along, for unit angles.

    Parameters
    ----------
    calibration : Calibration
    pan, tilt : array_like, shape (n,) or scalar, radians
        Unit angles.

    Returns
    -------
    origins : ndarray, shape (n, 3), metres
        Where the measured distance ``s * range + r0`` starts, scan frame.
    directions : ndarray, shape (n, 3)
        Unit beam directions, scan frame.
    """
    pan_p, tilt_p = calibration.physical_angles(np.atleast_1d(pan), np.atleast_1d(tilt))
    pan_p, tilt_p = np.broadcast_arrays(pan_p, tilt_p)
    head = _rz(pan_p) @ _rx(np.full_like(pan_p, calibration.tilt_axis_skew)) @ _ry(-tilt_p)
    t_tilt = np.asarray(calibration.tilt_axis_offset)
    o_laser = np.asarray(calibration.laser_offset)
    base = np.asarray(calibration.base_position)
    r_base = rotation_base(calibration)
    origins = base + np.einsum("ij,nj->ni", r_base, np.einsum("nij,j->ni", _rz(pan_p), t_tilt))
    origins = origins + np.einsum("ij,nj->ni", r_base, np.einsum("nij,j->ni", head, o_laser))
    directions = np.einsum(
        "ij,nj->ni", r_base, np.einsum("nij,j->ni", head, _beam_direction(calibration))
    )
    return origins, directions


def forward(calibration: Calibration, pan, tilt, rng) -> np.ndarray:
    """Points from unit angles and raw ranges.

    Parameters
    ----------
    calibration : Calibration
    pan, tilt : array_like, shape (n,), radians
        Unit angles (counts times the unit's resolution).
    rng : array_like, shape (n,), metres
        Raw ranges as the range finder reports them.

    Returns
    -------
    ndarray, shape (n, 3), metres
        Points in the scan frame.
    """
    origins, directions = beam(calibration, pan, tilt)
    dist = (
        calibration.range_scale * np.atleast_1d(np.asarray(rng, dtype=float))
        + calibration.range_offset
    )
    return origins + dist[:, None] * directions


def _az_el(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.arctan2(v[:, 1], v[:, 0]), np.arctan2(v[:, 2], np.hypot(v[:, 0], v[:, 1]))


def aim(calibration: Calibration, points, iterations: int = 30) -> tuple[np.ndarray, np.ndarray]:
    """Unit angles whose beam passes through each point (inverse kinematics).

    Fixed-point iteration: start from the direction seen from the pan axis origin, then turn
    pan and tilt by the azimuth/elevation difference between the wanted direction (from the
    current beam origin to the point) and the current beam, until the change is below 1e-12 rad.
    Converges whenever the offsets are small next to the distance (centimetres against metres).

    Parameters
    ----------
    calibration : Calibration
    points : array_like, shape (n, 3), metres
        Targets in the scan frame.

    Returns
    -------
    pan, tilt : ndarray, shape (n,), radians
        Unit angles (before rounding to counts).
    """
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    r_base = rotation_base(calibration)
    local = (pts - np.asarray(calibration.base_position)) @ r_base  # R^T (P - t)
    pan_p, tilt_p = _az_el(local)
    for _ in range(iterations):
        pan_u, tilt_u = calibration.unit_angles(pan_p, tilt_p)
        origins, directions = beam(calibration, pan_u, tilt_u)
        want = (pts - origins) @ r_base
        have = directions @ r_base
        az_w, el_w = _az_el(want)
        az_h, el_h = _az_el(have)
        d_az = np.angle(np.exp(1j * (az_w - az_h)))
        d_el = el_w - el_h
        pan_p = pan_p + d_az
        tilt_p = tilt_p + d_el
        if np.max(np.abs(d_az)) < 1e-12 and np.max(np.abs(d_el)) < 1e-12:
            break
    return calibration.unit_angles(pan_p, tilt_p)
