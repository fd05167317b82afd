"""A hand-built model with every geometry (shared by tests/cad and tests/export).

Expected volumes come from closed-form formulas (and scipy's Qhull for the hull, numerical
quadrature for the tee's overlap), independent of the CAD kernel.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad
from scipy.spatial import ConvexHull

from asbuilt.findings import Finding
from asbuilt.model import Bend, Component, Model, Reducer, Spool, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

R4 = 0.1143 / 2  # NPS 4 outer radius, metres
W4 = 0.00602  # NPS 4 STD wall
R3 = 0.0889 / 2
W3 = 0.00549


def rotation_z(deg: float) -> np.ndarray:
    a = math.radians(deg)
    return np.array(
        [[math.cos(a), math.sin(a), 0.0], [-math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]]
    )


def hull_points() -> np.ndarray:
    rng = np.random.default_rng(7)
    return rng.normal(size=(30, 3)) * [0.4, 0.3, 0.5] + [9.0, 1.0, 1.0]


def hull_geometry() -> Hull:
    points = hull_points()
    hull = ConvexHull(points)
    faces = hull.simplices.copy()
    # Wind every triangle outwards (Qhull's simplices are not oriented).
    centre = points[hull.vertices].mean(axis=0)
    for i, tri in enumerate(faces):
        a, b, c = points[tri]
        if np.dot(np.cross(b - a, c - a), a - centre) < 0:
            faces[i] = tri[[0, 2, 1]]
    return Hull(points, faces)


def annulus(r: float, wall: float) -> float:
    return math.pi * (r**2 - (r - wall) ** 2)


def frustum(r1: float, r2: float, h: float) -> float:
    return math.pi * h * (r1 * r1 + r1 * r2 + r2 * r2) / 3


def tee_overlap(run_r: float, branch_r: float) -> float:
    """Volume of the branch cylinder inside the run cylinder (axes perpendicular, meeting)."""
    value, _ = quad(
        lambda y: 2 * math.sqrt(branch_r**2 - y**2) * math.sqrt(run_r**2 - y**2),
        -branch_r,
        branch_r,
    )
    return value


def zoo_components() -> list[Component]:
    spool = "S1"
    return [
        Component(
            "P1",
            "pipe",
            Straight([0, 0, 0], [1, 0, 0], R4, W4),
            sources=("P1",),
            spool=spool,
            nominal="4",
            schedule="STD",
        ),
        Component(
            "E1",
            "elbow",
            Bend([1, 0, 0], [1.2, 0.2, 0], [1, 0.2, 0], R4, W4),
            spool=spool,
            nominal="4",
            schedule="STD",
        ),
        Component(
            "P2",
            "pipe",
            Straight([1.2, 0.2, 0], [1.2, 1.2, 0], R4, W4),
            sources=("P2",),
            spool=spool,
            nominal="4",
            schedule="STD",
        ),
        # a reducing tee and a reducer with each end's STD wall (NPS 4 run, NPS 3 outlet / end)
        Component(
            "T1",
            "tee",
            Tee([3, 0, 0], [2.8, 0, 0], [3.2, 0, 0], [3, 0, 0.25], R4, R3, W4, W3),
            group="S2",
        ),
        Component(
            "R1",
            "reducer",
            Reducer([3.2, 0, 0], [3.35, 0, 0], R4, R3, wall_start=W4, wall_end=W3),
            group="S2",
        ),
        Component(
            "CY",
            "cylinder",
            Cylinder([5, 0, 1.5], [0, 0, 1], 0.15, 3.0),
            group="frame",
            sources=("CY",),
        ),
        Component(
            "C1",
            "cuboid",
            Cuboid([6, 2, 1], rotation_z(30), [0.4, 0.5, 2.0]),
            group="frame",
            sources=("C1",),
        ),
        Component("SP", "sphere", Sphere([7, 0, 1], 0.5), sources=("SP",)),
        Component(
            "PL",
            "plane",
            Plane([8, 0, 0], [0, 0, 1], [[7, -1, 0], [9, -1, 0], [9, 1, 0], [7, 1, 0]]),
            sources=("PL",),
        ),
        Component("H", "hull", hull_geometry(), sources=("H",)),
    ]


def expected_volumes(plate_thickness: float = 0.010) -> dict[str, float]:
    """Each zoo component's volume, cubic metres, from formulas."""
    bend_arc = 0.2 * math.pi / 2

    def tee(run_r: float, branch_r: float) -> float:
        return math.pi * (run_r**2 * 0.4 + branch_r**2 * 0.25) - tee_overlap(run_r, branch_r)

    return {
        "P1": annulus(R4, W4) * 1.0,
        "E1": annulus(R4, W4) * bend_arc,  # Pappus: area times the centroid's path
        "P2": annulus(R4, W4) * 1.0,
        # the bores lie inside the outsides: the outside's volume less the bores'
        "T1": tee(R4, R3) - tee(R4 - W4, R3 - W3),
        "R1": frustum(R4, R3, 0.15) - frustum(R4 - W4, R3 - W3, 0.15),
        "CY": math.pi * 0.15**2 * 3.0,
        "C1": 0.4 * 0.5 * 2.0,
        "SP": 4 / 3 * math.pi * 0.5**3,
        "PL": 4.0 * plate_thickness,
        "H": ConvexHull(hull_points()).volume,
    }


FINDINGS = (
    Finding("AB101", "nonstandard-diameter", "error", ("C1",), "C1 is off", location=[6, 2, 1]),
    Finding(
        "AB201",
        "misalignment",
        "warning",
        ("SP",),
        "SP is tilted",
        measured=1.5,
        allowed=1.0,
        stderr=0.2,
        unit="deg",
    ),
    Finding("AB301", "few-points", "info", ("H",), "H has few points"),
)


def zoo_model(findings: bool = True, name: str = "zoo") -> Model:
    return Model(
        components=tuple(zoo_components()),
        units="mm",
        name=name,
        catalog="asme-b36.10m",
        spools=(Spool("S1", ("P1", "E1", "P2"), pipe_length=2.0),),
        findings=FINDINGS if findings else (),
    )
