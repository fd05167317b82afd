"""One pipe (or box) seen from two stations: two linked objects fitted as one.

A pan-tilt station sees at most the half of a pipe that faces it; to see more, the operator
moves the tripod and scans the pipe again, as a second object with its own ``station``, and
links the two. Fitted apart, each half is a weak fit of its own (15 shots over less than half
the circle), and merging then finds two pipes in one place (a duplicate scan, AB501). Fitted
together, the two arcs pin the circle down: :func:`fuse_station_views` replaces such a pair by
one fit of all their shots.

A linked pair is one pipe when, fitted apart, the two are cylinders seen from different
stations, their axes agree (within ``SAME_AXIS_DEG`` or three combined standard errors), each
one's axis runs within ``SAME_LINE_RADII`` of the radius of the other's (two distinct pipes'
axes are at least the sum of their radii apart), their radii agree within three combined
standard errors (or the diameter tolerance) and they overlap along the axis by more than
``MIN_OVERLAP`` of the shorter one (contiguous pipes meet end to end, and stay apart). The joint
fit runs without a viewpoint (each shot was seen from its own station, which one fit cannot
take) and is kept when it explains both objects' shots.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._cuboid_stations import fuse_box_views
from asbuilt.fit.result import FitReport, ObjectFit
from asbuilt.primitives import Cylinder
from asbuilt.scan.model import ScanObject
from asbuilt.tolerances import Tolerances

__all__ = [
    "MIN_OVERLAP",
    "SAME_AXIS_DEG",
    "SAME_LINE_RADII",
    "SAME_STATION",
    "fuse_station_views",
    "same_pipe",
]

#: Axes closer than this (degrees), or than three combined standard errors, are one direction.
SAME_AXIS_DEG = 3.0
#: Each axis must pass within this fraction of the radius of the other's: distinct pipes, which
#: cannot share space, have axes at least the sum of their radii apart.
SAME_LINE_RADII = 0.5
#: Stations closer than this (metres) are one set-up.
SAME_STATION = 1e-3
#: Shortest overlap along the axis, as a fraction of the shorter object, for one pipe: two
#: contiguous pipes meet end to end (a coupling between), overlapping only by their ends' noise.
MIN_OVERLAP = 0.25


def same_pipe(first, second, tolerances: Tolerances) -> bool:
    """Whether two cylinder fits (:class:`~asbuilt.fit.result.FitResult`) are one pipe, by the
    tests of the module docstring."""
    one, two = first.primitive, second.primitive
    if not (isinstance(one, Cylinder) and isinstance(two, Cylinder)):
        return False
    se_one, se_two = first.stderr or {}, second.stderr or {}
    angle = np.degrees(np.arccos(min(abs(float(one.axis @ two.axis)), 1.0)))
    axis_se = np.hypot(se_one.get("axis_deg", 0.0), se_two.get("axis_deg", 0.0))
    if not angle <= max(SAME_AXIS_DEG, 3.0 * axis_se):
        return False
    for here, there in ((one, two), (two, one)):
        offset = there.center - here.center
        across = offset - (offset @ here.axis) * here.axis
        if np.linalg.norm(across) > SAME_LINE_RADII * there.radius:
            return False
    radius_se = np.hypot(se_one.get("radius", 0.0), se_two.get("radius", 0.0))
    if abs(one.radius - two.radius) > max(3.0 * radius_se, tolerances.diameter_tolerance / 2):
        return False
    middle = float((two.center - one.center) @ one.axis)
    overlap = min(one.length / 2, middle + two.length / 2) - max(
        -one.length / 2, middle - two.length / 2
    )
    return overlap > MIN_OVERLAP * min(one.length, two.length)


def fuse_station_views(report: FitReport, tolerances: Tolerances) -> FitReport:
    """``report`` with every linked pair of objects that is one pipe seen from two stations
    (:func:`same_pipe`, each object's viewpoint different) fitted as one object; likewise a
    linked pair of cuboids that is one box
    (:func:`asbuilt.fit._cuboid_stations.fuse_box_views`).

    The fused object keeps the first object's id, place, group, label and size hint (the
    second's where the first has none), holds both objects' points (first's, then second's),
    has no station and records the second's id in ``extra["fused_with"]``; its fit's notes say
    so. The second object leaves ``report.fits``, and the scan's links to it (in the report's
    copy of the scan; ``scan.objects`` keeps every measured point) go to the first.
    """

    scan = report.scan
    by_id = {item.object.id: item for item in report.fits}
    fused: dict[str, ObjectFit] = {}
    gone: dict[str, str] = {}
    for first_id, second_id in scan.links:
        first, second = by_id.get(first_id), by_id.get(second_id)
        if first is None or second is None or {first_id, second_id} & (set(fused) | set(gone)):
            continue
        kind = first.requested
        if kind not in ("cylinder", "cuboid") or second.requested != kind:
            continue  # a kind the operator left to auto stays as auto chose it
        views = (first.object.viewpoint(scan.sensor), second.object.viewpoint(scan.sensor))
        # One station: contiguous objects, not two views of one. (An absolute test: a relative
        # one, as np.allclose's, took stations 6 m apart at survey coordinates for one.)
        if any(view is None for view in views) or (
            float(np.linalg.norm(np.subtract(views[0], views[1]))) <= SAME_STATION
        ):
            continue
        fuse = fuse_box_views if kind == "cuboid" else _fuse_pipe_views
        joint = fuse(
            first.result,
            second.result,
            np.asarray(first.object.points, dtype=np.float64),
            np.asarray(second.object.points, dtype=np.float64),
            scan.sensor.range_sigma,
            tolerances,
        )
        if joint is None:
            continue
        fused[first_id] = _fused(first, second, joint)
        gone[second_id] = first_id
    if not fused:
        return report
    fits = tuple(
        fused.get(item.object.id, item) for item in report.fits if item.object.id not in gone
    )
    links = []
    for link in scan.links:
        pair = tuple(gone.get(obj_id, obj_id) for obj_id in link)
        if pair[0] != pair[1] and pair not in links and pair[::-1] not in links:
            links.append(pair)
    return dataclasses.replace(
        report, fits=fits, scan=dataclasses.replace(scan, links=tuple(links))
    )


def _fuse_pipe_views(one, two, points_one, points_two, sigma, tolerances: Tolerances):
    """One cylinder fit of two views' shots (``points_one`` then ``points_two``, metres, as
    fitted apart to ``one`` and ``two``), or None when they are not one pipe
    (:func:`same_pipe`), the joint fit is refused, or it fits something else."""
    from asbuilt.fit import fit_points  # the package imports this module

    if not same_pipe(one, two, tolerances):
        return None
    points = np.vstack([points_one, points_two])
    try:
        joint = fit_points("cylinder", points, sigma=sigma, tolerances=tolerances)
    except FitError:
        return None
    if not same_pipe(joint, one, tolerances) or not same_pipe(joint, two, tolerances):
        return None  # the shots together fit something else: leave them apart
    return joint


def _fused(first: ObjectFit, second: ObjectFit, joint) -> ObjectFit:
    """The ObjectFit of two views fitted together (``joint``, a cylinder FitResult of the
    first's points then the second's)."""
    one, two = first.object, second.object
    n = len(one.points) + len(two.points)
    what = (
        "one box seen from two stations (linked, square to each other and overlapping)"
        if first.requested == "cuboid"
        else "one pipe seen from two stations (linked, coaxial and overlapping)"
    )
    note = (
        f"{one.id} and {two.id} are {what}: fitted together from their {n} shots, without "
        f"the viewpoints; {two.id} is part of this object."
    )
    points = np.vstack([one.points, two.points])
    points.setflags(write=False)
    obj = ScanObject(
        id=one.id,
        kind=one.kind,
        points=points,
        index=one.index,
        group=one.group or two.group,
        label=one.label or two.label,
        nominal=one.nominal or two.nominal,
        station=None,
        extra={**one.extra, "fused_with": two.id},
    )
    result = dataclasses.replace(joint, notes=(*joint.notes, note))
    return ObjectFit(object=obj, result=result, requested=first.requested)
