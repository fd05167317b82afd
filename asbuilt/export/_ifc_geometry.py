"""Dimensions and directions the IFC writer reads off a component's geometry.

Private helper of :mod:`asbuilt.export.ifc`: a unit vector across an axis
(:func:`_perpendicular`), the outer radius and wall a piping geometry reports
(:func:`_outer_radius`, :func:`_wall`), its centreline length (:func:`_centreline_length`) and
its open ends with their outward directions (:func:`_piping_ends`, where the ports go). Metres,
scan frame.
"""

from __future__ import annotations

import numpy as np

from asbuilt.model import Bend, Cross, Reducer, Straight, Tee
from asbuilt.primitives import Cylinder


def _perpendicular(axis: np.ndarray) -> np.ndarray:
    """A unit vector (3,) perpendicular to the unit ``axis`` (3,)."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(axis, helper)
    return u / np.linalg.norm(u)


def _outer_radius(g) -> float | None:
    if isinstance(g, Straight | Bend | Tee | Cross):
        return g.outer_radius
    if isinstance(g, Reducer):
        return g.outer_radius_start
    if isinstance(g, Cylinder):
        return g.radius
    return None


def _wall(g) -> float:
    """The wall (m) that goes with :func:`_outer_radius`: a reducer's or elbow's at its start
    end, a tee's run's; 0 when unknown or not piping."""
    if isinstance(g, Reducer):
        return g.wall_start
    return getattr(g, "wall", 0.0)


def _centreline_length(g) -> float | None:
    """Centreline length, metres: straight and reducer end to end, bend arc, tee run."""
    if isinstance(g, Straight | Reducer):
        return g.length
    if isinstance(g, Bend):
        return g.bend_radius * float(np.radians(g.angle_deg))
    if isinstance(g, Tee | Cross):
        return float(np.linalg.norm(g.run_end - g.run_start))
    if isinstance(g, Cylinder):
        return g.length
    return None


def _piping_ends(g) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(point (3,) m, outward unit direction (3,))`` of each open end of a piping geometry."""
    if isinstance(g, Straight):
        return [(g.start, -g.direction), (g.end, g.direction)]
    if isinstance(g, Reducer):
        return [(g.start, -g.direction), (g.end, g.direction)]
    if isinstance(g, Bend):
        normal = np.cross(g.start - g.center, g.end - g.center)
        normal /= np.linalg.norm(normal)
        out_start = -np.cross(normal, g.start - g.center)
        out_end = np.cross(normal, g.end - g.center)
        return [
            (g.start, out_start / np.linalg.norm(out_start)),
            (g.end, out_end / np.linalg.norm(out_end)),
        ]
    if isinstance(g, Tee | Cross):
        run = (g.run_end - g.run_start) / np.linalg.norm(g.run_end - g.run_start)
        outlets = [(end, (end - g.center) / np.linalg.norm(end - g.center)) for end in g.outlets]
        return [(g.run_start, -run), (g.run_end, run), *outlets]
    if isinstance(g, Cylinder):
        start, end = g.ends
        axis = (end - start) / np.linalg.norm(end - start)
        return [(start, -axis), (end, axis)]
    return []
