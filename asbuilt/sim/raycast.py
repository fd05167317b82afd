"""Exact ray casting against analytic shapes and triangle meshes (vectorised numpy).

Every shape answers the same question for a batch of rays: the smallest positive distance
``t`` along each (unit) direction at which the ray enters or leaves the shape's surface, and
the outward unit normal there. :func:`raycast` takes the nearest hit over a tuple of shapes,
which is what makes objects occlude each other.

Algorithms
----------
* Box: the slab method (Kay & Kajiya 1986) in the box's local frame.
* Cylinder: the quadratic of the ray against the infinite lateral surface, clipped to the axis
  segment, plus the two end caps as bounded planes.
* Sphere: the quadratic ``|o + t d - c|^2 = r^2``.
* Plane: an unbounded (two-sided) plane, ``t = n.(p - o) / n.d``.
* Mesh: Moller & Trumbore (1997) ray-triangle test over every triangle, after an
  axis-aligned bounding-box slab test that skips rays that cannot hit the mesh.

All lengths are metres. Directions are normalised on entry.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

__all__ = [
    "RayHits",
    "Shape",
    "SphereShape",
    "CylinderShape",
    "BoxShape",
    "PlaneShape",
    "MeshShape",
    "raycast",
    "direction_from_angles",
    "angles_from_direction",
]

#: Hits closer than this along a ray (metres) are ignored, so a ray starting on a surface leaves it.
T_MIN = 1e-9


def _rays(origins, directions) -> tuple[np.ndarray, np.ndarray]:
    o = np.asarray(origins, dtype=np.float64)
    d = np.asarray(directions, dtype=np.float64)
    if o.ndim == 1:
        o = np.broadcast_to(o, d.shape)
    if o.ndim != 2 or o.shape[1] != 3 or d.shape != o.shape:
        raise ValueError(
            f"origins and directions must both have shape (n, 3), not {o.shape} and {d.shape}"
        )
    norm = np.linalg.norm(d, axis=1)
    if np.any(norm == 0) or not np.all(np.isfinite(d)) or not np.all(np.isfinite(o)):
        raise ValueError("ray directions must be finite and non-zero, origins finite")
    return o, d / norm[:, None]


def direction_from_angles(pan, tilt) -> np.ndarray:
    """Unit beam directions of the ideal pan-tilt chain.

    Parameters
    ----------
    pan, tilt : array_like, shape (n,), radians
        Pan about +z from +x (counter-clockwise seen from above), tilt up from the xy plane.

    Returns
    -------
    ndarray, shape (n, 3)
        ``(cos tilt cos pan, cos tilt sin pan, sin tilt)``.
    """
    pan = np.asarray(pan, dtype=np.float64)
    tilt = np.asarray(tilt, dtype=np.float64)
    ct = np.cos(tilt)
    return np.stack([ct * np.cos(pan), ct * np.sin(pan), np.sin(tilt)], axis=-1)


def angles_from_direction(directions) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`direction_from_angles`.

    Parameters
    ----------
    directions : array_like, shape (n, 3)
        Any non-zero vectors.

    Returns
    -------
    pan, tilt : ndarray, shape (n,), radians
        Pan in (-pi, pi], tilt in [-pi/2, pi/2].
    """
    d = np.asarray(directions, dtype=np.float64)
    horizontal = np.hypot(d[..., 0], d[..., 1])
    return np.arctan2(d[..., 1], d[..., 0]), np.arctan2(d[..., 2], horizontal)


@dataclass(frozen=True, eq=False)
class RayHits:
    """The nearest hit of each ray.

    Attributes
    ----------
    range : ndarray, shape (n,), metres
        Distance from the ray origin to the hit; ``inf`` where the ray hits nothing.
    object_index : ndarray, shape (n,), int
        Index of the shape (scene object) hit; ``-1`` for a miss.
    cos_incidence : ndarray, shape (n,)
        ``|cos|`` of the angle between the ray and the surface normal (1 = head-on,
        0 = grazing); ``0`` for a miss.
    normal : ndarray, shape (n, 3)
        Outward unit surface normal at the hit; zeros for a miss.
    """

    range: np.ndarray
    object_index: np.ndarray
    cos_incidence: np.ndarray
    normal: np.ndarray

    @property
    def hit(self) -> np.ndarray:
        """Boolean mask, shape (n,), of rays that hit something."""
        return self.object_index >= 0

    def points(self, origins, directions) -> np.ndarray:
        """Hit points, shape (n, 3) metres (``nan`` rows for misses)."""
        o, d = _rays(origins, directions)
        rng = np.where(np.isfinite(self.range), self.range, np.nan)
        return o + rng[:, None] * d


class Shape(ABC):
    """A surface that rays can hit. Subclasses implement :meth:`intersect`."""

    @abstractmethod
    def intersect(self, origins: np.ndarray, directions: np.ndarray):
        """Nearest positive hit of each ray.

        Parameters
        ----------
        origins : ndarray, shape (n, 3), metres
        directions : ndarray, shape (n, 3), unit vectors

        Returns
        -------
        t : ndarray, shape (n,), metres (``inf`` for a miss)
        normal : ndarray, shape (n, 3), outward unit normal at the hit (zeros for a miss)
        """

    @abstractmethod
    def bounds(self) -> np.ndarray:
        """Axis-aligned bounds, shape (2, 3) metres (min row, max row); may be infinite."""

    @abstractmethod
    def sample_surface(self) -> np.ndarray:
        """Points, shape (k, 3) metres, outlining the shape (for angular windows)."""


def _nearest(*candidates: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Pick, per ray, the smallest ``t`` among several (t, normal) candidates."""
    ts = np.stack([c[0] for c in candidates])
    best = np.argmin(ts, axis=0)
    rows = np.arange(ts.shape[1])
    normals = np.stack([c[1] for c in candidates])[best, rows]
    t = ts[best, rows]
    normals[~np.isfinite(t)] = 0.0
    return t, normals


def _positive(t: np.ndarray) -> np.ndarray:
    return np.where(np.isfinite(t) & (t > T_MIN), t, np.inf)


@dataclass(frozen=True, eq=False)
class SphereShape(Shape):
    """Sphere: ``center`` shape (3,) metres, ``radius`` metres."""

    center: np.ndarray
    radius: float

    def intersect(self, origins, directions):
        w = origins - self.center
        b = np.einsum("ij,ij->i", w, directions)
        c = np.einsum("ij,ij->i", w, w) - self.radius**2
        disc = b * b - c
        ok = disc >= 0
        root = np.sqrt(np.where(ok, disc, 0.0))
        t1 = _positive(np.where(ok, -b - root, np.inf))
        t2 = _positive(np.where(ok, -b + root, np.inf))
        t = np.minimum(t1, t2)
        normal = (origins + np.where(np.isfinite(t), t, 0.0)[:, None] * directions) - self.center
        normal /= self.radius
        normal[~np.isfinite(t)] = 0.0
        return t, normal

    def bounds(self):
        return np.stack([self.center - self.radius, self.center + self.radius])

    def sample_surface(self):
        return _fibonacci_sphere(200) * self.radius + self.center


def _fibonacci_sphere(n: int) -> np.ndarray:
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (1 + 5**0.5) * k
    s = np.sqrt(1 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=1)


def _perpendicular_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    return u, np.cross(axis, u)


@dataclass(frozen=True, eq=False)
class CylinderShape(Shape):
    """Closed right circular cylinder from ``start`` to ``end`` (shape (3,), metres), ``radius``.

    ``capped=False`` leaves the ends open (a pipe seen from outside is indistinguishable).
    """

    start: np.ndarray
    end: np.ndarray
    radius: float
    capped: bool = True

    @property
    def axis(self) -> np.ndarray:
        v = np.asarray(self.end, float) - np.asarray(self.start, float)
        return v / np.linalg.norm(v)

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.asarray(self.end, float) - np.asarray(self.start, float)))

    def intersect(self, origins, directions):
        axis, length, r = self.axis, self.length, self.radius
        w = origins - self.start
        h0 = w @ axis
        hd = directions @ axis
        w_perp = w - h0[:, None] * axis
        d_perp = directions - hd[:, None] * axis
        a = np.einsum("ij,ij->i", d_perp, d_perp)
        b = np.einsum("ij,ij->i", d_perp, w_perp)
        c = np.einsum("ij,ij->i", w_perp, w_perp) - r * r
        disc = b * b - a * c
        ok = (a > 1e-18) & (disc >= 0)
        safe_a = np.where(ok, a, 1.0)
        root = np.sqrt(np.where(ok, disc, 0.0))
        candidates = []
        for sign in (-1.0, 1.0):
            t = np.where(ok, (-b + sign * root) / safe_a, np.inf)
            t = _positive(t)
            h = h0 + np.where(np.isfinite(t), t, 0.0) * hd
            t = np.where((h >= 0) & (h <= length), t, np.inf)
            radial = w_perp + np.where(np.isfinite(t), t, 0.0)[:, None] * d_perp
            candidates.append((t, radial / r))
        if self.capped:
            safe_hd = np.where(np.abs(hd) > 1e-18, hd, 1.0)
            for level, outward in ((0.0, -axis), (length, axis)):
                t = np.where(np.abs(hd) > 1e-18, (level - h0) / safe_hd, np.inf)
                t = _positive(t)
                radial = w_perp + np.where(np.isfinite(t), t, 0.0)[:, None] * d_perp
                inside = np.einsum("ij,ij->i", radial, radial) <= r * r
                t = np.where(inside, t, np.inf)
                candidates.append((t, np.broadcast_to(outward, origins.shape).copy()))
        return _nearest(*candidates)

    def bounds(self):
        s, e = np.asarray(self.start, float), np.asarray(self.end, float)
        ext = self.radius * np.sqrt(np.clip(1.0 - self.axis**2, 0.0, 1.0))
        return np.stack([np.minimum(s, e) - ext, np.maximum(s, e) + ext])

    def sample_surface(self):
        u, v = _perpendicular_basis(self.axis)
        phi = np.linspace(0, 2 * np.pi, 72, endpoint=False)
        ring = self.radius * (np.outer(np.cos(phi), u) + np.outer(np.sin(phi), v))
        heights = np.linspace(0.0, self.length, 9)
        return np.concatenate([self.start + ring + h * self.axis for h in heights])


@dataclass(frozen=True, eq=False)
class BoxShape(Shape):
    """Oriented box: ``center`` (3,) m, ``axes`` (3, 3) rows = local edge directions, ``size`` (3,) m."""

    center: np.ndarray
    axes: np.ndarray
    size: np.ndarray

    def intersect(self, origins, directions):
        axes = np.asarray(self.axes, float)
        half = 0.5 * np.asarray(self.size, float)
        o = (origins - self.center) @ axes.T
        d = directions @ axes.T
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / d
            t1 = (-half - o) * inv
            t2 = (half - o) * inv
        # A ray parallel to a slab is inside it for every t or for none.
        parallel = d == 0
        inside_slab = np.abs(o) <= half
        lo = np.where(parallel, np.where(inside_slab, -np.inf, np.inf), np.minimum(t1, t2))
        hi = np.where(parallel, np.where(inside_slab, np.inf, -np.inf), np.maximum(t1, t2))
        t_near = lo.max(axis=1)
        t_far = hi.min(axis=1)
        hit = t_near <= t_far
        use_far = hit & (t_near <= T_MIN)
        t = np.where(use_far, t_far, t_near)
        t = np.where(hit, _positive(t), np.inf)
        axis_index = np.where(use_far, np.argmin(hi, axis=1), np.argmax(lo, axis=1))
        rows = np.arange(len(t))
        sign = np.where(use_far, np.sign(d[rows, axis_index]), -np.sign(d[rows, axis_index]))
        sign = np.where(sign == 0, 1.0, sign)
        normal = sign[:, None] * axes[axis_index]
        normal[~np.isfinite(t)] = 0.0
        return t, normal

    def corners(self) -> np.ndarray:
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
        return self.center + (signs * 0.5 * np.asarray(self.size, float)) @ np.asarray(self.axes)

    def bounds(self):
        c = self.corners()
        return np.stack([c.min(axis=0), c.max(axis=0)])

    def sample_surface(self):
        g = np.linspace(-0.5, 0.5, 5)
        grid = np.array([[x, y, z] for x in g for y in g for z in g])
        grid = grid[np.abs(grid).max(axis=1) == 0.5]
        return self.center + (grid * np.asarray(self.size, float)) @ np.asarray(self.axes)


@dataclass(frozen=True, eq=False)
class PlaneShape(Shape):
    """Unbounded two-sided plane through ``point`` (3,) m with unit ``normal`` (3,).

    The returned normal faces the ray origin (a floor seen from above points up).
    """

    point: np.ndarray
    normal: np.ndarray

    def intersect(self, origins, directions):
        n = np.asarray(self.normal, float)
        dn = directions @ n
        safe = np.where(np.abs(dn) > 1e-15, dn, 1.0)
        t = np.where(np.abs(dn) > 1e-15, ((self.point - origins) @ n) / safe, np.inf)
        t = _positive(t)
        side = np.where(dn > 0, -1.0, 1.0)
        normal = side[:, None] * n
        normal[~np.isfinite(t)] = 0.0
        return t, normal

    def bounds(self):
        return np.array([[-np.inf] * 3, [np.inf] * 3])

    def sample_surface(self):
        u, v = _perpendicular_basis(np.asarray(self.normal, float))
        return self.point + np.array([u, -u, v, -v]) * 1e3


@dataclass(frozen=True, eq=False)
class MeshShape(Shape):
    """Triangle mesh: ``vertices`` (k, 3) metres, ``faces`` (m, 3) int (counter-clockwise outside).

    Normals come from the winding; a badly wound mesh gives inward normals but correct ranges.
    """

    vertices: np.ndarray
    faces: np.ndarray

    def intersect(self, origins, directions, chunk: int = 2_000_000):
        n = len(origins)
        t_best = np.full(n, np.inf)
        normal = np.zeros((n, 3))
        lo, hi = self.bounds()
        candidates = np.flatnonzero(_slab_hits(origins, directions, lo, hi))
        if candidates.size == 0:
            return t_best, normal
        tri = np.asarray(self.vertices, float)[np.asarray(self.faces)]
        v0 = tri[:, 0]
        e1 = tri[:, 1] - v0
        e2 = tri[:, 2] - v0
        face_normals = np.cross(e1, e2)
        face_normals /= np.maximum(np.linalg.norm(face_normals, axis=1), 1e-300)[:, None]
        step = max(1, chunk // max(1, len(tri)))
        for begin in range(0, candidates.size, step):
            idx = candidates[begin : begin + step]
            o = origins[idx][:, None, :]
            d = directions[idx][:, None, :]
            p = np.cross(d, e2[None])
            det = np.einsum("ijk,jk->ij", p, e1)
            ok = np.abs(det) > 1e-15
            inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
            s = o - v0[None]
            u = np.einsum("ijk,ijk->ij", s, p) * inv
            q = np.cross(s, e1[None])
            v = np.einsum("ijk,ijk->ij", d, q) * inv
            t = np.einsum("jk,ijk->ij", e2, q) * inv
            good = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > T_MIN)
            t = np.where(good, t, np.inf)
            best = np.argmin(t, axis=1)
            tb = t[np.arange(len(idx)), best]
            t_best[idx] = tb
            normal[idx] = np.where(np.isfinite(tb)[:, None], face_normals[best], 0.0)
        return t_best, normal

    def bounds(self):
        v = np.asarray(self.vertices, float)
        return np.stack([v.min(axis=0), v.max(axis=0)])

    def sample_surface(self):
        return np.asarray(self.vertices, float)


def _slab_hits(origins, directions, lo, hi) -> np.ndarray:
    """Boolean (n,): rays that meet the axis-aligned box [lo, hi] at some t >= 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / directions
        t1 = (lo - origins) * inv
        t2 = (hi - origins) * inv
    parallel = directions == 0
    inside = (origins >= lo) & (origins <= hi)
    lo = np.where(parallel, np.where(inside, -np.inf, np.inf), np.minimum(t1, t2))
    hi = np.where(parallel, np.where(inside, np.inf, -np.inf), np.maximum(t1, t2))
    t_near = lo.max(axis=1)
    t_far = hi.min(axis=1)
    return (t_near <= t_far + 1e-12) & (t_far >= 0)


def raycast(shapes, origins, directions, *, exclude=None) -> RayHits:
    """Nearest hit of each ray over every shape (occlusion included).

    Parameters
    ----------
    shapes : sequence of Shape
        The scene; ``object_index`` in the result indexes this sequence.
    origins : array_like, shape (n, 3) or (3,), metres
        Ray origins (one point is broadcast to every ray).
    directions : array_like, shape (n, 3)
        Ray directions (normalised here).
    exclude : int or array_like of int, shape (n,), optional
        A shape index each ray ignores (``-1`` ignores none), e.g. to find what lies behind
        an object.

    Returns
    -------
    RayHits
    """
    o, d = _rays(origins, directions)
    n = len(o)
    best_t = np.full(n, np.inf)
    best_i = np.full(n, -1, dtype=np.int64)
    best_normal = np.zeros((n, 3))
    skip = None if exclude is None else np.broadcast_to(np.asarray(exclude, dtype=np.int64), (n,))
    for index, shape in enumerate(shapes):
        active = np.ones(n, bool) if skip is None else skip != index
        if not np.any(active):
            continue
        t, normal = shape.intersect(o[active], d[active])
        rows = np.flatnonzero(active)
        closer = t < best_t[rows]
        rows = rows[closer]
        best_t[rows] = t[closer]
        best_i[rows] = index
        best_normal[rows] = normal[closer]
    cos = np.abs(np.einsum("ij,ij->i", best_normal, d))
    return RayHits(range=best_t, object_index=best_i, cos_incidence=cos, normal=best_normal)
