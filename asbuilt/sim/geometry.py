"""Geometry helpers for scenes: rotations, member frames and small generated meshes.

Pure numpy; every length is metres and every angle radians unless a name ends in ``_deg``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "rotation_zyx",
    "member_axes",
    "plate_axes",
    "torus_segment_mesh",
    "frustum_mesh",
    "unit",
]


def unit(vector) -> np.ndarray:
    """``vector`` (3,) divided by its norm; ValueError for a zero vector."""
    v = np.asarray(vector, dtype=np.float64)
    norm = float(np.linalg.norm(v))
    if not np.isfinite(norm) or norm == 0.0:
        raise ValueError("the vector must be finite and non-zero")
    return v / norm


def rotation_zyx(yaw_deg: float, pitch_deg: float, roll_deg: float) -> np.ndarray:
    """Rows of a box's local axes after yaw (about z), pitch (about y), roll (about x).

    Returns
    -------
    ndarray, shape (3, 3)
        Row ``k`` is local axis ``k`` in world coordinates (the columns of
        ``Rz(yaw) @ Ry(pitch) @ Rx(roll)``).
    """
    y, p, r = np.radians([yaw_deg, pitch_deg, roll_deg])
    rz = np.array([[np.cos(y), -np.sin(y), 0], [np.sin(y), np.cos(y), 0], [0, 0, 1]])
    ry = np.array([[np.cos(p), 0, np.sin(p)], [0, 1, 0], [-np.sin(p), 0, np.cos(p)]])
    rx = np.array([[1, 0, 0], [0, np.cos(r), -np.sin(r)], [0, np.sin(r), np.cos(r)]])
    return (rz @ ry @ rx).T


def member_axes(start, end, roll_deg: float = 0.0) -> np.ndarray:
    """Local axes (rows, shape (3, 3)) of a structural member from ``start`` to ``end``.

    Row 0 runs along the member; row 1 (the section's width direction) is horizontal for a
    non-vertical member and world -y for a vertical one; row 2 (the depth direction) completes
    a right-handed frame; ``roll_deg`` turns rows 1 and 2 about row 0.
    """
    a = unit(np.asarray(end, float) - np.asarray(start, float))
    ref = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.99 else np.array([1.0, 0.0, 0.0])
    w = unit(np.cross(ref, a))
    d = np.cross(a, w)
    c, s = np.cos(np.radians(roll_deg)), np.sin(np.radians(roll_deg))
    return np.array([a, c * w + s * d, -s * w + c * d])


def plate_axes(normal, up=None) -> np.ndarray:
    """Local axes (rows, shape (3, 3)) of a plate: width direction, height direction, normal.

    The height direction is ``up`` (default world z, or world y when the normal is vertical)
    made perpendicular to the normal.
    """
    n = unit(normal)
    if up is None:
        up = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.99 else np.array([0.0, 1.0, 0.0])
    width = np.cross(unit(up), n)
    if np.linalg.norm(width) < 1e-9:
        raise ValueError("the up direction must not be parallel to the normal")
    width = unit(width)
    height = np.cross(n, width)
    return np.array([width, height, n])


def _close_tube(rings: np.ndarray, caps: bool) -> tuple[np.ndarray, np.ndarray]:
    """Triangulate stacked rings (k, m, 3) into a tube; optionally cap both ends."""
    k, m, _ = rings.shape
    vertices = rings.reshape(-1, 3)
    faces = []
    for i in range(k - 1):
        for j in range(m):
            a = i * m + j
            b = i * m + (j + 1) % m
            c = (i + 1) * m + j
            d = (i + 1) * m + (j + 1) % m
            faces.append([a, b, d])
            faces.append([a, d, c])
    if caps:
        centres = np.array([rings[0].mean(axis=0), rings[-1].mean(axis=0)])
        first, last = len(vertices), len(vertices) + 1
        vertices = np.concatenate([vertices, centres])
        for j in range(m):
            faces.append([first, (j + 1) % m, j])
            faces.append([last, (k - 1) * m + j, (k - 1) * m + (j + 1) % m])
    return vertices, np.array(faces, dtype=np.int64)


def _ring(centre, axis, radius, m):
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = unit(np.cross(axis, helper))
    v = np.cross(axis, u)
    phi = np.linspace(0.0, 2 * np.pi, m, endpoint=False)
    return centre + radius * (np.outer(np.cos(phi), u) + np.outer(np.sin(phi), v))


def frustum_mesh(start, end, start_radius: float, end_radius: float, segments: int = 48):
    """Closed mesh of a truncated cone (a concentric reducer), metres.

    Returns
    -------
    vertices : ndarray, shape (k, 3)
    faces : ndarray, shape (m, 3), int
    """
    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = unit(end - start)
    rings = np.stack(
        [_ring(start, axis, start_radius, segments), _ring(end, axis, end_radius, segments)]
    )
    return _close_tube(rings, caps=True)


def torus_segment_mesh(
    corner,
    before,
    after,
    bend_radius: float,
    tube_radius: float,
    segments: int = 16,
    sides: int = 32,
):
    """Closed mesh of a pipe elbow turning at ``corner`` from ``before`` to ``after`` (metres).

    ``before`` and ``after`` are the neighbouring path points; the elbow's centre line is a
    circular arc of ``bend_radius`` tangent to both straight legs, so each leg ends
    ``bend_radius * tan(angle / 2)`` from the corner (the elbow's centre-to-end).

    Returns
    -------
    vertices : ndarray, shape (k, 3)
    faces : ndarray, shape (m, 3), int
    """
    corner = np.asarray(corner, float)
    d_in = unit(corner - np.asarray(before, float))
    d_out = unit(np.asarray(after, float) - corner)
    angle = float(np.arccos(np.clip(d_in @ d_out, -1.0, 1.0)))
    if angle < 1e-6:
        raise ValueError("the path does not turn at this corner")
    tangent_length = bend_radius * np.tan(angle / 2)
    p_in = corner - tangent_length * d_in
    to_centre = unit(d_out - (d_out @ d_in) * d_in)
    centre = p_in + bend_radius * to_centre
    binormal = unit(np.cross(d_in, d_out))
    phi = np.linspace(0.0, 2 * np.pi, sides, endpoint=False)
    rings = []
    for s in np.linspace(0.0, angle, segments + 1):
        radial = np.sin(s) * d_in - np.cos(s) * to_centre
        point = centre + bend_radius * radial
        rings.append(
            point + tube_radius * (np.outer(np.cos(phi), binormal) + np.outer(np.sin(phi), radial))
        )
    return _close_tube(np.stack(rings), caps=True)
