"""Synthetic pan-tilt range-finder scans of known primitives, for the fit tests.

:func:`raster_scan` casts a raster of rays from a sensor position at a primitive (exact
ray/primitive intersection, first hit only), perturbs the beam direction by the angular noise
and the range by the range noise (the point is reported along the *nominal* direction, as a real
pan-tilt unit does), and can push a fraction of the shots along their ray onto "the wall behind"
(edge outliers). It is deterministic for a given ``numpy.random.Generator``.

Generic on purpose: any fit test (cylinder, sphere, plane, cuboid) may use it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asbuilt.primitives import Cuboid, Cylinder, Plane, Sphere


@dataclass(frozen=True)
class Sample:
    """A simulated scan.

    Attributes
    ----------
    points : ndarray, shape (n, 3), metres
        Measured points (noise and outliers included).
    exact : ndarray, shape (n, 3), metres
        Where each nominal ray meets the surface (no noise).
    outliers : ndarray, shape (n,), bool
        Shots pushed onto the background.
    sensor : ndarray, shape (3,), metres
    """

    points: np.ndarray
    exact: np.ndarray
    outliers: np.ndarray
    sensor: np.ndarray


def _ray_cylinder(c: Cylinder, origin, dirs):
    a = c.axis
    w = origin - c.center
    d_perp = dirs - np.outer(dirs @ a, a)
    w_perp = w - (w @ a) * a
    qa = np.einsum("ij,ij->i", d_perp, d_perp)
    qb = 2.0 * d_perp @ w_perp
    qc = w_perp @ w_perp - c.radius**2
    disc = qb * qb - 4 * qa * qc
    with np.errstate(invalid="ignore", divide="ignore"):
        t = (-qb - np.sqrt(disc)) / (2 * qa)
    along = (w @ a) + t * (dirs @ a)
    ok = (disc > 0) & (t > 0) & (np.abs(along) <= 0.5 * c.length)
    return np.where(ok, t, np.nan)


def _ray_sphere(s: Sphere, origin, dirs):
    w = origin - s.center
    b = dirs @ w
    disc = b * b - (w @ w - s.radius**2)
    with np.errstate(invalid="ignore"):
        t = -b - np.sqrt(disc)
    return np.where((disc > 0) & (t > 0), t, np.nan)


def _ray_plane(p: Plane, origin, dirs):
    denom = dirs @ p.normal
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((p.point - origin) @ p.normal) / denom
    hit = origin + t[:, None] * dirs
    inside = np.ones(len(dirs), bool)
    ring = p.outline
    for k in range(len(ring)):
        edge = ring[(k + 1) % len(ring)] - ring[k]
        inside &= (np.cross(edge, hit - ring[k]) @ p.normal) >= 0
    return np.where((t > 0) & inside & np.isfinite(t), t, np.nan)


def _ray_cuboid(b: Cuboid, origin, dirs):
    o = (origin - b.center) @ b.axes.T
    d = dirs @ b.axes.T
    half = 0.5 * b.size
    with np.errstate(divide="ignore", invalid="ignore"):
        t1 = (-half - o) / d
        t2 = (half - o) / d
    near = np.nanmax(np.minimum(t1, t2), axis=1)
    far = np.nanmin(np.maximum(t1, t2), axis=1)
    return np.where((near <= far) & (near > 0), near, np.nan)


def cast(primitive, origin, dirs) -> np.ndarray:
    """Range along each unit ray (m, 3) from ``origin`` (3,) to the primitive, NaN on a miss."""
    table = {
        "cylinder": _ray_cylinder,
        "sphere": _ray_sphere,
        "plane": _ray_plane,
        "cuboid": _ray_cuboid,
    }
    return table[primitive.kind](primitive, np.asarray(origin, float), dirs)


def _surface_samples(primitive) -> np.ndarray:
    if primitive.kind == "cylinder":
        u = np.cross(primitive.axis, [1.0, 0, 0])
        if np.linalg.norm(u) < 0.1:
            u = np.cross(primitive.axis, [0, 1.0, 0])
        u /= np.linalg.norm(u)
        v = np.cross(primitive.axis, u)
        phi, s = np.meshgrid(np.linspace(0, 2 * np.pi, 72), np.linspace(-0.5, 0.5, 9))
        phi, s = phi.ravel(), s.ravel() * primitive.length
        return (
            primitive.center
            + primitive.radius * (np.outer(np.cos(phi), u) + np.outer(np.sin(phi), v))
            + np.outer(s, primitive.axis)
        )
    if primitive.kind == "sphere":
        k = np.arange(400) + 0.5
        z = 1 - 2 * k / 400
        phi = np.pi * (1 + 5**0.5) * k
        r = np.sqrt(1 - z * z)
        return primitive.center + primitive.radius * np.column_stack(
            [r * np.cos(phi), r * np.sin(phi), z]
        )
    if primitive.kind == "plane":
        return np.asarray(primitive.outline)
    return primitive.corners


def directions(pan, tilt):
    """Unit beam directions (n, 3) of pan and tilt angles (n,) in radians (pan about +z from
    +x, tilt up from the horizontal)."""
    return np.column_stack([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)])


#: The benchmark's pointing noise, 0.01 degree, in radians.
_POINTING_SIGMA = float(np.radians(0.01))


def corner_angles(box: Cuboid) -> tuple[np.ndarray, np.ndarray]:
    """Pan and tilt (8,) radians of a box's corners seen from the origin (its silhouette
    window is their span)."""
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    corners = box.center + (signs * 0.5 * np.asarray(box.size)) @ np.asarray(box.axes)
    pans = np.arctan2(corners[:, 1], corners[:, 0])
    return pans, np.arctan2(corners[:, 2], np.hypot(corners[:, 0], corners[:, 1]))


def cell_centres(low: float, high: float, count: int) -> np.ndarray:
    """The centres (count,) of ``count`` equal cells spanning [low, high]."""
    edges = np.linspace(low, high, count + 1)
    return 0.5 * (edges[1:] + edges[:-1])


def shoot(
    primitive,
    pan,
    tilt,
    rng,
    *,
    range_sigma=0.002,
    pointing_sigma=_POINTING_SIGMA,
    miss_range=None,
):
    """Shots from the origin at ``primitive`` along nominal ``pan``, ``tilt`` (m,) radians.

    Each beam is off its nominal direction by the pointing noise, ray-cast (:func:`cast`), its
    range noisy, and recorded at the nominal angles, as a pan-tilt range finder records it.
    ``miss_range(true_dirs (m, 3)) -> (m,)`` metres gives the range of a beam that misses (a
    wall behind); without it a miss is NaN. Returns points (m, 3) metres and hit (m,) bool.
    """
    true_dirs = directions(
        pan + rng.normal(0.0, pointing_sigma, pan.size),
        tilt + rng.normal(0.0, pointing_sigma, tilt.size),
    )
    entry = cast(primitive, np.zeros(3), true_dirs)
    hit = np.isfinite(entry)
    reach = entry if miss_range is None else np.where(hit, entry, miss_range(true_dirs))
    reach = reach + rng.normal(0.0, range_sigma, reach.size)
    return directions(pan, tilt) * reach[:, None], hit


def raster_scan(
    primitive,
    sensor,
    n_points: int,
    rng: np.random.Generator,
    *,
    sigma_range: float = 0.002,
    sigma_angle_deg: float = 0.01,
    outlier_fraction: float = 0.0,
    outlier_push: tuple[float, float] = (0.05, 2.0),
    arc_deg: float | None = None,
) -> Sample:
    """Simulate ``n_points`` raster shots from ``sensor`` (3,) m at a primitive.

    ``arc_deg`` (cylinders) keeps only hits within +-arc/2 of the sensor's direction about the
    axis. Outliers (``round(outlier_fraction * n)`` random shots) are pushed along their ray by a
    uniform distance in ``outlier_push`` metres.
    """
    sensor = np.asarray(sensor, float)
    rel = _surface_samples(primitive) - sensor
    pan = np.arctan2(rel[:, 1], rel[:, 0])
    pan0 = np.arctan2(rel[:, 1].mean(), rel[:, 0].mean())
    pan = pan0 + np.angle(np.exp(1j * (pan - pan0)))
    tilt = np.arctan2(rel[:, 2], np.hypot(rel[:, 0], rel[:, 1]))
    box = (pan.min(), pan.max(), tilt.min(), tilt.max())
    keep_arc = None
    if arc_deg is not None and primitive.kind == "cylinder":
        a = primitive.axis
        to_sensor = sensor - primitive.center
        to_sensor = to_sensor - (to_sensor @ a) * a
        to_sensor /= np.linalg.norm(to_sensor)

        def keep_arc(hits):
            radial = hits - primitive.center
            radial = radial - np.outer(radial @ a, a)
            radial /= np.linalg.norm(radial, axis=1)[:, None]
            return radial @ to_sensor >= np.cos(np.radians(arc_deg / 2))

    for m in range(3, 400):
        pans, tilts = np.meshgrid(np.linspace(box[0], box[1], m), np.linspace(box[2], box[3], m))
        pans, tilts = pans.ravel(), tilts.ravel()
        ranges = cast(primitive, sensor, directions(pans, tilts))
        hit = np.isfinite(ranges)
        if keep_arc is not None:
            hit[hit] = keep_arc(sensor + ranges[hit, None] * directions(pans[hit], tilts[hit]))
        if hit.sum() >= n_points:
            break
    index = np.flatnonzero(hit)
    if len(index) < n_points:
        raise ValueError("The sensor cannot see the primitive (does the axis point at it?).")
    index = index[np.round(np.linspace(0, len(index) - 1, n_points)).astype(int)]
    pans, tilts = pans[index], tilts[index]
    nominal = directions(pans, tilts)
    exact = sensor + ranges[index, None] * nominal
    sa = np.radians(sigma_angle_deg)
    measured = cast(
        primitive,
        sensor,
        directions(pans + rng.normal(0, sa, n_points), tilts + rng.normal(0, sa, n_points)),
    )
    measured = np.where(np.isfinite(measured), measured, ranges[index])
    measured = measured + rng.normal(0, sigma_range, n_points)
    outliers = np.zeros(n_points, bool)
    count = int(round(outlier_fraction * n_points))
    if count:
        outliers[rng.choice(n_points, count, replace=False)] = True
        measured[outliers] += rng.uniform(*outlier_push, count)
    points = sensor + measured[:, None] * nominal
    return Sample(points, exact, outliers, sensor)


def random_rotation(rng: np.random.Generator) -> np.ndarray:
    """A uniformly random 3x3 rotation matrix (QR of a Gaussian matrix, sign-fixed)."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def angle_deg(a, b) -> float:
    """Angle between two sign-free directions, degrees."""
    c = abs(float(np.dot(a, b))) / (np.linalg.norm(a) * np.linalg.norm(b))
    return float(np.degrees(np.arccos(min(1.0, c))))


def sizes_in_true_order(result, rot):
    """A cuboid fit's sizes (3,) metres, their standard errors (3,) metres and observed flags
    (3,) bool, in the order of the true axes (the columns of ``rot`` (3, 3))."""
    axes = np.array(result.primitive.axes)
    order = np.abs(axes @ rot).argmax(axis=0)
    return (
        np.asarray(result.primitive.size)[order],
        np.asarray(result.stderr["size"])[order],
        np.asarray(result.observed)[order],
    )
