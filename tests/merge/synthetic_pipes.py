"""Synthetic fits for merge tests: FitResult objects built directly (no fitter needed)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asbuilt.fit.result import FitReport, FitResult, ObjectFit
from asbuilt.primitives import Cuboid, Cylinder
from asbuilt.scan.model import Scan, ScanObject


@dataclass
class Pipe:
    """A pipe as a test describes it: a segment (metres) and a fitted OD with its error."""

    id: str
    start: tuple
    end: tuple
    od: float
    se_radius: float = 0.0005
    nominal: str | None = None
    group: str | None = None
    label: str | None = None
    se_axis_deg: float = 0.2
    insulation: float = 0.0  # metres; ``od`` is then the fitted (cladding) OD


def cylinder_fit(start, end, od, se_radius=0.0005, se_axis_deg=0.2) -> FitResult:
    start, end = np.asarray(start, float), np.asarray(end, float)
    axis = (end - start) / np.linalg.norm(end - start)
    cyl = Cylinder(
        center=(start + end) / 2,
        axis=axis,
        radius=od / 2,
        length=float(np.linalg.norm(end - start)),
    )
    n = 20
    return FitResult(
        primitive=cyl,
        residuals=np.zeros(n),
        inliers=np.ones(n, bool),
        stderr={"radius": se_radius, "axis_deg": se_axis_deg, "center": 0.001, "length": 0.01},
        sigma=0.002,
        sigma_source="sensor",
        method="synthetic",
    )


def report_of(pipes, links=(), extra=()) -> FitReport:
    """A FitReport of the given Pipe descriptions (plus extra (ScanObject, FitResult) pairs)."""
    objects, fits = [], []
    for k, p in enumerate(pipes):
        obj = ScanObject(
            id=p.id,
            kind="cylinder",
            points=np.zeros((6, 3)),
            index=k,
            group=p.group,
            label=p.label,
            nominal=p.nominal,
            insulation=p.insulation,
        )
        objects.append(obj)
        fit = cylinder_fit(p.start, p.end, p.od, p.se_radius, p.se_axis_deg)
        fits.append(ObjectFit(obj, fit, "cylinder"))
    for obj, result in extra:
        objects.append(obj)
        fits.append(ObjectFit(obj, result, obj.kind))
    scan = Scan(units="m", objects=tuple(objects), links=tuple(links), name="test")
    return FitReport(scan=scan, fits=tuple(fits))


def box_fit() -> tuple[ScanObject, FitResult]:
    box = Cuboid(center=[5, 5, 1], axes=np.eye(3), size=[0.4, 0.4, 2.0])
    obj = ScanObject(id="C1", kind="cuboid", points=np.zeros((8, 3)), index=99)
    res = FitResult(
        primitive=box,
        residuals=np.zeros(8),
        inliers=np.ones(8, bool),
        stderr={},
        sigma=0.002,
        sigma_source="sensor",
        method="synthetic",
    )
    return obj, res


def raster_points(start, end, od, n, station, rng, sigma=0.002, margin=0.03):
    """n noisy shots (n, 3) m on the side of a pipe facing ``station`` (4 columns, n/4 rows
    along the pipe), each moved along its ray by Gaussian range noise ``sigma`` metres."""
    start, end, station = (np.asarray(v, float) for v in (start, end, station))
    axis = (end - start) / np.linalg.norm(end - start)
    length = float(np.linalg.norm(end - start))
    rows = int(np.ceil(n / 4))
    t = np.repeat(np.linspace(margin, length - margin, rows), 4)[:n]
    centres = start + t[:, None] * axis
    facing = station - centres
    facing -= (facing @ axis)[:, None] * axis
    facing /= np.linalg.norm(facing, axis=1)[:, None]
    side = np.cross(axis, facing)
    phi = np.tile(np.radians([-52.5, -17.5, 17.5, 52.5]), rows)[:n]
    surface = centres + 0.5 * od * (np.cos(phi)[:, None] * facing + np.sin(phi)[:, None] * side)
    rays = surface - station
    rays /= np.linalg.norm(rays, axis=1)[:, None]
    return surface + rng.normal(0, sigma, n)[:, None] * rays
