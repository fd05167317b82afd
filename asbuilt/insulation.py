"""The insulation around a component, as geometry: its jacket (the lagging itself, a hollow
shape) and its envelope (the space the insulated component takes up).

A scan object's ``insulation`` (the thickness of lagging and cladding the points were measured
on) comes to its components as :attr:`asbuilt.model.Component.insulation`; their ``geometry``
is the pipe inside. The jacket is the same kind of geometry with every outer radius grown by the
thickness and a wall of the thickness: its bore is the component's outside, so the existing
solid and mesh builders make it, and the jacket and the pipe fill the envelope without
overlapping. Plain numpy: CAD, the compliance rules (clearances are to the cladding) and the
take-off share it.

Lagging cannot be thicker than the room a fitting leaves: an elbow's inside radius, a tee's
outlet beyond the run. There the jacket is drawn thinner (:func:`jacket_thickness`), as
insulators mitre and trim it on a tight bend.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.model import Bend, Component, Cross, Reducer, Straight, Tee
from asbuilt.primitives import Cylinder

__all__ = ["jacket", "envelope", "jacket_thickness", "JACKET_ROOM"]

#: Share of a fitting's room the jacket may fill: of the bend radius for an elbow's outer
#: radius, of an outlet's length beyond the run for a tee's. Below 1 so the jacket's surfaces
#: stay apart from the bend axis and the run's jacket, which the kernel needs for a valid solid.
JACKET_ROOM = 0.95


def jacket_thickness(component: Component) -> float:
    """The thickness (metres) the component's jacket is drawn with: its ``insulation``, less
    where a fitting leaves no room for it (:data:`JACKET_ROOM`); 0 when it has none."""
    thickness = float(component.insulation)
    geometry = component.geometry
    if thickness <= 0:
        return 0.0
    if isinstance(geometry, Bend):
        room = JACKET_ROOM * geometry.bend_radius - max(geometry.radii)
        thickness = min(thickness, room)
    elif isinstance(geometry, (Tee, Cross)):
        outlet = min(float(np.linalg.norm(end - geometry.center)) for end in geometry.outlets)
        half_run = 0.5 * float(np.linalg.norm(geometry.run_end - geometry.run_start))
        thickness = min(
            thickness,
            JACKET_ROOM * outlet - geometry.outer_radius,
            JACKET_ROOM * half_run - geometry.branch_outer_radius,
        )
    return max(thickness, 0.0)


def _grown(geometry, thickness: float, wall: float):
    """``geometry`` with its outer radii grown by ``thickness`` and walls set to ``wall``
    (metres); a fitted cylinder becomes a straight."""
    t = thickness
    if isinstance(geometry, Cylinder):
        start, end = geometry.ends
        return Straight(start=start, end=end, outer_radius=geometry.radius + t, wall=wall)
    if isinstance(geometry, Straight):
        return dataclasses.replace(geometry, outer_radius=geometry.outer_radius + t, wall=wall)
    if isinstance(geometry, Bend):
        r_start, r_end = geometry.radii
        return dataclasses.replace(
            geometry, outer_radius=r_start + t, outer_radius_end=r_end + t, wall=wall, wall_end=wall
        )
    if isinstance(geometry, Reducer):
        return dataclasses.replace(
            geometry,
            outer_radius_start=geometry.outer_radius_start + t,
            outer_radius_end=geometry.outer_radius_end + t,
            wall_start=wall,
            wall_end=wall,
        )
    if isinstance(geometry, (Tee, Cross)):
        return dataclasses.replace(
            geometry,
            outer_radius=geometry.outer_radius + t,
            branch_outer_radius=geometry.branch_outer_radius + t,
            wall=wall,
            branch_wall=wall,
        )
    return None


def jacket(component: Component):
    """The insulation around ``component`` as a hollow geometry, or None when it has none.

    Returns
    -------
    Straight, Bend, Reducer, Tee, Cross or None
        Metres: the component's geometry (a fitted cylinder as a straight) with every outer
        radius grown by :func:`jacket_thickness` and that thickness as its wall, so its bore is
        the component's outside. None for a bare component, a shape insulation does not wrap
        (boxes, spheres, planes, hulls), or a fitting with no room for it.
    """
    thickness = jacket_thickness(component)
    if thickness <= 0:
        return None
    return _grown(component.geometry, thickness, thickness)


def envelope(component: Component):
    """The space the insulated component takes up: its geometry grown by its full insulation,
    solid (wall 0); the geometry itself when bare or not wrappable. Metres."""
    if component.insulation <= 0:
        return component.geometry
    grown = _grown(component.geometry, float(component.insulation), 0.0)
    return component.geometry if grown is None else grown
