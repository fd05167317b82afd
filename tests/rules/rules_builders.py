"""Hand-built models for the rule tests: components with exact geometry and chosen uncertainties.

Each fit carries the standard errors a test needs, so a test sets the measurement and its
uncertainty directly and checks the rule's decision against hand-computed limits.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit.result import FitResult
from asbuilt.model import Component, Model, Spool, Straight
from asbuilt.primitives import Cuboid, Cylinder
from asbuilt.rules import SizeTable

#: ASME B36.10M outside diameters (metres) typed from the standards reference table, with DN
#: and the B16.9 long-radius 90 degree elbow centre-to-end (metres).
B36 = SizeTable(
    "ASME B36.10M",
    "NPS",
    (
        ("1/2", 15, 0.0213),
        ("3/4", 20, 0.0267),
        ("1", 25, 0.0334),
        ("1 1/2", 40, 0.0483),
        ("2", 50, 0.0603),
        ("3", 80, 0.0889),
        ("4", 100, 0.1143),
        ("6", 150, 0.1683),
        ("8", 200, 0.2191),
        ("10", 250, 0.2730),
        ("12", 300, 0.3238),
    ),
    {"2": 0.076, "3": 0.114, "4": 0.152, "6": 0.229},
)


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def tilted(angle_deg: float, azimuth_deg: float = 0.0) -> np.ndarray:
    """A unit vector ``angle_deg`` off vertical, leaning towards ``azimuth_deg`` in plan."""
    t, a = np.radians(angle_deg), np.radians(azimuth_deg)
    return np.array([np.sin(t) * np.cos(a), np.sin(t) * np.sin(a), np.cos(t)])


def cylinder_fit(
    center,
    axis,
    radius,
    length,
    *,
    n=24,
    sigma=0.002,
    radius_se=0.0005,
    axis_deg=0.2,
    length_se=0.003,
    center_se=0.001,
    arc_deg=180.0,
    rms=None,
    rejected=0,
    sigma_source="sensor",
) -> FitResult:
    prim = Cylinder(center=center, axis=unit(axis), radius=radius, length=length)
    rng = np.random.default_rng(n)
    residuals = rng.normal(0.0, 1.0, n)
    residuals *= (rms if rms is not None else sigma) / np.sqrt(np.mean(residuals**2))
    inliers = np.ones(n, bool)
    inliers[:rejected] = False
    return FitResult(
        primitive=prim,
        residuals=residuals,
        inliers=inliers,
        stderr={
            "radius": radius_se,
            "axis_deg": axis_deg,
            "center": center_se,
            "length": length_se,
        },
        sigma=sigma,
        sigma_source=sigma_source,
        method="test",
        diagnostics={"arc_deg": arc_deg, "length_over_diameter": length / (2 * radius)},
    )


def cuboid_fit(
    center,
    long_axis,
    size,
    *,
    n=36,
    sigma=0.002,
    axes_deg=0.05,
    size_se=0.001,
    center_se=0.001,
    faces=3,
) -> FitResult:
    a = unit(long_axis)
    b = unit(np.cross(a, [1.0, 0, 0] if abs(a[0]) < 0.9 else [0, 1.0, 0]))
    c = np.cross(a, b)
    prim = Cuboid(center=center, axes=np.array([b, c, a]), size=size)
    rng = np.random.default_rng(n)
    return FitResult(
        primitive=prim,
        residuals=rng.normal(0.0, sigma, n),
        inliers=np.ones(n, bool),
        stderr={"size": (size_se,) * 3, "axes_deg": axes_deg, "center": center_se},
        sigma=sigma,
        sigma_source="sensor",
        method="test",
        diagnostics={"faces": faces},
    )


def pipe(
    cid,
    start,
    end,
    od,
    *,
    nominal=None,
    status=None,
    od_fit=None,
    od_stderr=0.0005,
    fit=True,
    candidates=(),
    group=None,
    label=None,
    **fit_options,
) -> Component:
    """A straight pipe component; ``fit`` True builds a cylinder fit along it."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    result = None
    if fit:
        result = cylinder_fit(
            0.5 * (start + end),
            end - start,
            od / 2,
            float(np.linalg.norm(end - start)),
            **fit_options,
        )
    snap = {}
    if status:
        snap = {
            "status": status,
            "od_fit": od if od_fit is None else od_fit,
            "od_stderr": od_stderr,
            "candidates": list(candidates),
        }
    return Component(
        id=cid,
        type="pipe",
        geometry=Straight(start, end, od / 2),
        sources=(cid,),
        nominal=nominal,
        fit=result,
        snap=snap,
        group=group,
        label=label,
    )


def column(
    cid,
    base,
    lean_deg=0.0,
    height=3.0,
    section=(0.3, 0.3),
    *,
    azimuth=0.0,
    label=None,
    **fit_options,
) -> Component:
    axis = tilted(lean_deg, azimuth)
    centre = np.asarray(base, float) + 0.5 * height * axis
    result = cuboid_fit(centre, axis, (section[0], section[1], height), **fit_options)
    return Component(
        id=cid, type="cuboid", geometry=result.primitive, sources=(cid,), fit=result, label=label
    )


def model(*components, scan=None, catalog=None, merged=True) -> Model:
    """A model of these components; ``merged`` puts the pipes in one spool, as merging would."""
    pipes = tuple(c.id for c in components if c.type == "pipe")
    spools = (Spool("S1", pipes),) if merged and pipes else ()
    return Model(components=tuple(components), scan=scan, catalog=catalog, spools=spools)
