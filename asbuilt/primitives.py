"""Geometric primitives: small frozen value objects holding float64 arrays in metres.

Each primitive validates itself on creation (finite values, unit axes, positive sizes) with an
exact message, stores read-only arrays, and can measure the signed orthogonal distance of points
to its surface (positive outside). Nothing here fits or draws: see :mod:`asbuilt.fit` and
:mod:`asbuilt.cad`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

__all__ = ["Cylinder", "Cuboid", "Sphere", "Plane", "Hull", "Primitive", "as_vector", "as_points"]


def _frozen(array: np.ndarray) -> np.ndarray:
    array = np.array(array, dtype=np.float64, copy=True)
    array.setflags(write=False)
    return array


def as_vector(value, name: str, size: int = 3) -> np.ndarray:
    """Return ``value`` as a read-only float64 array of shape ``(size,)``; raise ValueError."""
    array = np.asarray(value, dtype=np.float64)
    if array.shape != (size,):
        raise ValueError(f"The {name} must have shape ({size},), not {array.shape}.")
    # Python's isfinite on the few values: a numpy call costs more than the test.
    if not all(map(math.isfinite, array.tolist())):
        raise ValueError(f"The {name} must be finite.")
    return _frozen(array)


def as_points(value, name: str = "points") -> np.ndarray:
    """Return ``value`` as a read-only float64 array of shape ``(n, 3)``; raise ValueError."""
    array = np.asarray(value, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3:
        raise ValueError(f"The {name} must have shape (n, 3), not {array.shape}.")
    if not np.isfinite(array).all():
        raise ValueError(f"The {name} must be finite.")
    return _frozen(array)


def _unit(value, name: str) -> np.ndarray:
    vector = as_vector(value, name)
    # np.linalg.norm's arithmetic (both roots correctly rounded), without its overhead.
    norm = math.sqrt(float(vector.dot(vector)))
    if abs(norm - 1.0) > 1e-6:
        raise ValueError(f"The {name} must be a unit vector (its norm is {norm:.6g}).")
    return _frozen(vector / norm)


def _positive(value, name: str) -> float:
    number = float(value)
    if not math.isfinite(number) or number <= 0.0:
        raise ValueError(f"The {name} must be a positive finite number, not {value!r}.")
    return number


@dataclass(frozen=True, eq=False)
class Cylinder:
    """A bounded right circular cylinder.

    Attributes
    ----------
    center : ndarray, shape (3,), metres
        Mid-point of the axis segment.
    axis : ndarray, shape (3,)
        Unit axis direction (the sign is arbitrary).
    radius : float, metres
    length : float, metres
        Length of the axis segment.
    """

    kind: ClassVar[str] = "cylinder"
    center: np.ndarray
    axis: np.ndarray
    radius: float
    length: float

    def __post_init__(self):
        object.__setattr__(self, "center", as_vector(self.center, "center"))
        object.__setattr__(self, "axis", _unit(self.axis, "axis"))
        object.__setattr__(self, "radius", _positive(self.radius, "radius"))
        object.__setattr__(self, "length", _positive(self.length, "length"))

    @property
    def ends(self) -> tuple[np.ndarray, np.ndarray]:
        """The two end points of the axis segment, each shape (3,), metres."""
        half = 0.5 * self.length * self.axis
        return self.center - half, self.center + half

    def distance(self, points) -> np.ndarray:
        """Signed distance, shape (n,) metres, of points (n, 3) to the infinite lateral surface."""
        rel = np.asarray(points, dtype=np.float64) - self.center
        radial = rel - (rel @ self.axis)[:, None] * self.axis  # np.outer's products
        # np.linalg.norm(radial, axis=1)'s arithmetic, without its overhead.
        return np.sqrt(np.add.reduce(radial * radial, axis=1)) - self.radius


@dataclass(frozen=True, eq=False)
class Sphere:
    """A sphere: ``center`` shape (3,) metres, ``radius`` metres."""

    kind: ClassVar[str] = "sphere"
    center: np.ndarray
    radius: float

    def __post_init__(self):
        object.__setattr__(self, "center", as_vector(self.center, "center"))
        object.__setattr__(self, "radius", _positive(self.radius, "radius"))

    def distance(self, points) -> np.ndarray:
        """Signed distance, shape (n,) metres, of points (n, 3) to the sphere."""
        rel = np.asarray(points, dtype=np.float64) - self.center
        return np.linalg.norm(rel, axis=1) - self.radius


@dataclass(frozen=True, eq=False)
class Plane:
    """A bounded plane.

    Attributes
    ----------
    point : ndarray, shape (3,), metres
        A point on the plane (the centroid of the fitted points).
    normal : ndarray, shape (3,)
        Unit normal.
    outline : ndarray, shape (k, 3), metres
        Convex outline polygon of the points projected on the plane, counter-clockwise about
        ``normal``; may be empty (shape (0, 3)) for an unbounded plane.
    """

    kind: ClassVar[str] = "plane"
    point: np.ndarray
    normal: np.ndarray
    outline: np.ndarray = None  # type: ignore[assignment]

    def __post_init__(self):
        object.__setattr__(self, "point", as_vector(self.point, "point"))
        object.__setattr__(self, "normal", _unit(self.normal, "normal"))
        outline = np.zeros((0, 3)) if self.outline is None else self.outline
        object.__setattr__(self, "outline", as_points(outline, "outline"))

    def distance(self, points) -> np.ndarray:
        """Signed distance, shape (n,) metres, of points (n, 3) along the normal."""
        return (np.asarray(points, dtype=np.float64) - self.point) @ self.normal

    @property
    def area(self) -> float:
        """Area, m², of the outline (0 for fewer than 3 corners; vector shoelace formula).

        The corners are taken about their mean first: in site coordinates (1e6-1e7 m) the
        products of absolute coordinates would cancel to centimetres squared.
        """
        if len(self.outline) < 3:
            return 0.0
        corners = self.outline - self.outline.mean(axis=0)
        cross = np.cross(corners, np.roll(corners, -1, axis=0)).sum(axis=0)
        return abs(float(cross @ self.normal)) / 2.0


@dataclass(frozen=True, eq=False)
class Cuboid:
    """A box.

    Attributes
    ----------
    center : ndarray, shape (3,), metres
    axes : ndarray, shape (3, 3)
        Rows are the box's orthonormal, right-handed edge directions.
    size : ndarray, shape (3,), metres
        Full edge lengths along each row of ``axes``.
    """

    kind: ClassVar[str] = "cuboid"
    center: np.ndarray
    axes: np.ndarray
    size: np.ndarray

    def __post_init__(self):
        object.__setattr__(self, "center", as_vector(self.center, "center"))
        axes = np.asarray(self.axes, dtype=np.float64)
        if axes.shape != (3, 3) or not np.isfinite(axes).all():
            raise ValueError("The axes must be a finite (3, 3) array.")
        if np.abs(axes @ axes.T - np.eye(3)).max() > 1e-6:
            raise ValueError("The axes must be orthonormal.")
        if np.linalg.det(axes) < 0:
            axes = axes.copy()
            axes[2] = -axes[2]
        object.__setattr__(self, "axes", _frozen(axes))
        size = as_vector(self.size, "size")
        if (size <= 0).any():
            raise ValueError("The size must be positive along every axis.")
        object.__setattr__(self, "size", size)

    @property
    def corners(self) -> np.ndarray:
        """The eight corners, shape (8, 3) metres."""
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
        return self.center + (signs * (0.5 * self.size)) @ self.axes

    def distance(self, points) -> np.ndarray:
        """Signed distance, shape (n,) metres, of points (n, 3) to the box surface."""
        local = (np.asarray(points, dtype=np.float64) - self.center) @ self.axes.T
        q = np.abs(local) - 0.5 * self.size
        outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
        inside = np.minimum(q.max(axis=1), 0.0)
        return outside + inside


@dataclass(frozen=True, eq=False)
class Hull:
    """A closed convex polyhedron (a bounding model for obstacles and peripheral objects).

    Attributes
    ----------
    vertices : ndarray, shape (n, 3), metres
    faces : ndarray, shape (m, 3), int
        Triangles indexing ``vertices``, wound counter-clockwise seen from outside.
    """

    kind: ClassVar[str] = "hull"
    vertices: np.ndarray
    faces: np.ndarray

    def __post_init__(self):
        vertices = as_points(self.vertices, "vertices")
        if len(vertices) < 4:
            raise ValueError("A hull needs at least 4 vertices.")
        object.__setattr__(self, "vertices", vertices)
        faces = np.array(self.faces, dtype=np.int64, copy=True)
        if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) < 4:
            raise ValueError("The faces must have shape (m, 3) with m >= 4.")
        if faces.min() < 0 or faces.max() >= len(vertices):
            raise ValueError("The faces must index the vertices.")
        faces.setflags(write=False)
        object.__setattr__(self, "faces", faces)

    @property
    def volume(self) -> float:
        """Enclosed volume, m³ (divergence theorem over the triangles, about the vertices'
        mean: in site coordinates absolute products would cancel)."""
        tri = self.vertices[self.faces] - self.vertices.mean(axis=0)
        triple = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2]))
        return abs(float(triple.sum())) / 6.0

    @property
    def area(self) -> float:
        """Surface area, m²."""
        tri = self.vertices[self.faces]
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        return float(np.linalg.norm(cross, axis=1).sum()) / 2.0

    def distance(self, points) -> np.ndarray:
        """Signed distance bound, shape (n,) metres: the largest face-plane distance.

        Exact inside and near faces; outside near edges and corners it is a lower bound.
        """
        tri = self.vertices[self.faces]
        normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        norms = np.linalg.norm(normals, axis=1)
        keep = norms > 1e-15
        normals = normals[keep] / norms[keep, None]
        offsets = np.einsum("ij,ij->i", normals, tri[keep, 0])
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        # In blocks of rows: a dense cloud against a many-faced hull would be a huge matrix.
        rows = max(1, 4_000_000 // max(len(normals), 1))
        out = np.empty(len(pts))
        for start in range(0, len(pts), rows):
            block = pts[start : start + rows]
            out[start : start + rows] = (block @ normals.T - offsets).max(axis=1)
        return out


Primitive = Cylinder | Cuboid | Sphere | Plane | Hull
