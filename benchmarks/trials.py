"""The simulated scans of the fitting benchmark (``benchmarks/fit_accuracy.py``).

The sensor, the cells' sizes and each kind's trial: an object placed 3 to 10 m from a pan-tilt
range finder (:mod:`asbuilt.sim`: range noise sigma 2 mm, pointing noise 0.01 degree), a raster
over its exact silhouette window or an operator's window, or the acquisition session's raster,
fill and edge-bisection shots, thinned to n points, and the same shots with 20% edge outliers
(mixed returns by the sensor model's rule). Each :class:`Trial` carries its truth and its
Cramer-Rao bounds (``benchmarks/crb.py``). ``cylinder_speed.py``, ``cuboid_speed.py`` and
``auto_choice.py`` draw the same trials (same seeds, :func:`hash_key`).
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import crb  # noqa: E402

from asbuilt.sim.raycast import (  # noqa: E402
    BoxShape,
    CylinderShape,
    PlaneShape,
    SphereShape,
    direction_from_angles,
)
from asbuilt.sim.scene import Scene, SceneObject, Station  # noqa: E402
from asbuilt.sim.sensor import (  # noqa: E402
    angular_window,
    fire,
    operator_margins,
    operator_window,
    plan_raster,
    shoot,
)

SIGMA_R = 0.002
SIGMA_A = math.radians(0.01)
ODS_MM = (60.3, 114.3, 219.1, 323.8, 609.6)
LDS = (1, 3, 10)
NS = (20, 30, 40)
SPHERE_D = (0.2, 0.5, 1.0, 3.0)
PLANE_W = (0.5, 3.0)
SECTIONS = (0.2, 0.4, 0.6)
OUTLIER_FRACTION = 0.2
#: Suffix of the data versions shot over an operator's window (``"clean" + OPERATOR``).
OPERATOR = "@operator"
#: Suffix of the cuboid data versions acquired by the scan session's algorithm (raster, fill and
#: edge bisection: ``asbuilt.drivers.session.scan_target``) over an operator's window.
SESSION = "@session"
#: Edge-bisection hits a session trial keeps within its n points (about two a side: each
#: bisection's last hits; the intermediate ones are dropped first).
SESSION_EDGE_HITS = 8
STATION = Station(
    id="S",
    position=np.zeros(3),
    range_sigma=SIGMA_R,
    angular_sigma=SIGMA_A,
    dropout=0.0,
    mixed_return=0.0,
)


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


# --------------------------------------------------------------------------- trials


def _scene(target_shape, target_truth, kind, background_point, background_normal) -> Scene:
    objects = (
        SceneObject(
            id="T",
            kind=kind,
            shape=target_shape,
            truth=target_truth,
            points=30,
            scan=True,
            station="S",
            index=0,
        ),
        SceneObject(
            id="bg",
            kind=None,
            shape=PlaneShape(point=background_point, normal=background_normal),
            truth=None,
            points=30,
            scan=False,
            station="S",
            index=1,
        ),
    )
    return Scene(units="m", stations=(STATION,), objects=objects)


def _line_of_sight(rng, distance):
    pan = rng.uniform(-math.pi, math.pi)
    tilt = rng.uniform(-0.3, 0.4)
    los = direction_from_angles(pan, tilt)
    return los, distance * los


def _random_axis(rng, los, min_angle_deg=45.0):
    while True:
        a = unit(rng.normal(size=3))
        if abs(a @ los) <= math.cos(math.radians(min_angle_deg)):
            return a


@dataclass
class Trial:
    """One simulated measurement: clean points, outlier points, truth and bound."""

    clean: np.ndarray
    dirty: np.ndarray
    truth: dict
    bound: dict
    #: The bound from the shots the outlier version keeps (its edge shots replaced): what an
    #: estimator that rejected every outlier and refitted the rest could reach at best.
    retained_bound: dict | None = None


def _take(scene, n, rng, keep=None, operator=False):
    """Exactly n clean returns on object 0, the outlier version, the shots' effective noise
    sigmas and a mask of the shots the outlier version keeps.

    ``keep(shots) -> bool mask`` drops returns the operator would not take (pipe end caps).
    ``operator``: shoot over an operator's window (the silhouette window enlarged by random
    margins of 0-1 raster step per side) instead of the exact silhouette window.
    """
    margins = operator_margins(rng) if operator else None
    wanted = n
    for _ in range(8):
        pan, tilt, _ = plan_raster(scene, 0, STATION, wanted, margins=margins)
        shots = shoot(scene, 0, STATION, pan, tilt, rng)
        if keep is not None:
            shots = shots.subset(keep(shots))
        if len(shots) >= n:
            break
        wanted = int(math.ceil(wanted * 1.2 * n / max(len(shots), 1)))
    else:
        raise RuntimeError("could not land enough shots")
    keep = np.unique(np.round(np.linspace(0, len(shots) - 1, n)).astype(int))
    shots = shots.subset(keep)
    # Edge proximity: angular distance to the nearest raster shot that missed the object.
    nominal = scene.raycast(STATION.position, direction_from_angles(pan, tilt))
    missed = nominal.object_index != 0
    xy = np.column_stack([pan * np.cos(tilt), tilt])
    if missed.any():
        diff = xy[shots.index][:, None, :] - xy[missed][None, :, :]
        proximity = np.sqrt((diff**2).sum(axis=2)).min(axis=1)
    else:
        proximity = np.zeros(len(shots))
    return _with_edge_outliers(shots, shots.range, proximity, n, rng)


def _with_edge_outliers(shots, ranges, proximity, n, rng):
    """The outlier version of n shots: the fifth nearest a miss become mixed returns.

    ``shots`` has ``true_range``, ``background_range``, ``directions``, ``surface_points`` and
    ``normals`` (n rows); ``ranges`` (n,) metres are the measured ones; ``proximity`` (n,) the
    angular distance of each shot to the nearest one that missed (ties broken at random). Half
    of the chosen shots land on the background surface, half uniformly between object and
    background, plus range noise. Returns the shots, the outlier points (n, 3), the shots'
    effective noise sigmas and the mask of shots kept as they were.
    """
    k = int(round(OUTLIER_FRACTION * n))
    chosen = np.lexsort((rng.random(n), proximity))[:k]
    measured = np.asarray(ranges, dtype=np.float64).copy()
    r_true = shots.true_range[chosen]
    bg = shots.background_range[chosen]
    bg = np.where(np.isfinite(bg), bg, r_true + 2.0)
    full = rng.random(k) < 0.5
    frac = rng.random(k)
    mixed = np.where(full, bg, r_true + frac * (bg - r_true))
    measured[chosen] = mixed + rng.normal(0.0, SIGMA_R, size=k)
    dirty = STATION.position + measured[:, None] * shots.directions
    sig = crb.sigma_eff(shots.surface_points, shots.normals, STATION.position, SIGMA_R, SIGMA_A)
    retained = np.ones(n, dtype=bool)
    retained[chosen] = False
    return shots, dirty, sig, retained


def cylinder_trial(rng, od_mm, ld, n, operator=False) -> Trial:
    radius = od_mm / 2000.0
    length = ld * 2 * radius
    los, centre = _line_of_sight(rng, rng.uniform(3.0, 10.0))
    axis = _random_axis(rng, los)
    # Closed ends keep the beam out of the bore; returns on the end caps are dropped (a pipe
    # runs on into its fittings, so the operator's shots all land on its body).
    shape = CylinderShape(
        start=centre - 0.5 * length * axis,
        end=centre + 0.5 * length * axis,
        radius=radius,
        capped=True,
    )
    behind = centre + (radius + rng.uniform(1.5, 3.0)) * los
    scene = _scene(shape, None, "cylinder", behind, -los)
    shots, dirty, sig, kept = _take(
        scene, n, rng, keep=lambda s: np.abs(s.normals @ axis) < 0.5, operator=operator
    )
    bound = crb.cylinder_bounds(shots.surface_points, centre, axis, radius, sig)
    retained = crb.cylinder_bounds(shots.surface_points[kept], centre, axis, radius, sig[kept])
    truth = {"radius": radius, "axis": axis, "center": centre}
    return Trial(shots.points, dirty, truth, bound, retained)


def sphere_trial(rng, diameter, n, operator=False) -> Trial:
    radius = diameter / 2
    los, centre = _line_of_sight(rng, rng.uniform(3.0, 10.0))
    shape = SphereShape(center=centre, radius=radius)
    behind = centre + (radius + rng.uniform(1.5, 3.0)) * los
    scene = _scene(shape, None, "sphere", behind, -los)
    shots, dirty, sig, kept = _take(scene, n, rng, operator=operator)
    bound = crb.sphere_bounds(shots.surface_points, centre, sig)
    retained = crb.sphere_bounds(shots.surface_points[kept], centre, sig[kept])
    return Trial(shots.points, dirty, {"radius": radius, "center": centre}, bound, retained)


def plane_trial(rng, width, n, operator=False) -> Trial:
    los, centre = _line_of_sight(rng, rng.uniform(3.0, 10.0))
    incidence = math.radians(rng.uniform(0.0, 60.0))
    u, v = crb.perpendicular_basis(los)
    turn = unit(
        math.cos(rng.uniform(0, 2 * math.pi)) * u + math.sin(rng.uniform(0, 2 * math.pi)) * v
    )
    normal = unit(-math.cos(incidence) * los + math.sin(incidence) * turn)
    height_dir = unit(np.cross(normal, u if abs(normal @ u) < 0.9 else v))
    width_dir = np.cross(height_dir, normal)
    axes = np.array([width_dir, height_dir, normal])
    thickness = 0.02
    shape = BoxShape(
        center=centre - 0.5 * thickness * normal,
        axes=axes,
        size=np.array([width, width * rng.uniform(0.5, 1.0), thickness]),
    )
    behind = centre + rng.uniform(1.5, 3.0) * los
    scene = _scene(shape, None, "plane", behind, -los)
    shots, dirty, sig, _ = _take(scene, n, rng, operator=operator)
    front = shots.normals @ normal > 0.999
    bound = crb.plane_bounds(shots.surface_points[front], normal, sig[front])
    return Trial(shots.points, dirty, {"normal": normal, "point": centre}, bound)


def cuboid_trial(rng, section, faces, n, operator=False, session=False) -> Trial:
    size_a, size_b = section * rng.uniform(0.8, 1.2, size=2)
    distance = rng.uniform(3.0, 10.0)
    pan = rng.uniform(-math.pi, math.pi)
    los_h = np.array([math.cos(pan), math.sin(pan), 0.0])
    if faces == 2:
        height = 3.0
        base_z = -1.5 + rng.uniform(-0.3, 0.3)
    else:
        height = 1.2
        top_z = -distance * math.tan(math.radians(rng.uniform(20.0, 35.0)))
        base_z = top_z - height
    centre = distance * los_h + np.array([0.0, 0.0, base_z + 0.5 * height])
    yaw = pan + math.radians(rng.uniform(25.0, 65.0)) * rng.choice([-1.0, 1.0])
    x = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    y = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
    axes = np.array([x, y, [0.0, 0.0, 1.0]])
    size = np.array([size_a, size_b, height])
    shape = BoxShape(center=centre, axes=axes, size=size)
    los = unit(centre)
    behind = centre + rng.uniform(1.5, 3.0) * los_h + 0.5 * max(size_a, size_b) * los_h
    scene = _scene(shape, None, "cuboid", behind, -los_h)
    if session:
        shots, dirty, sig, _ = _take_session(scene, n, rng)
    else:
        shots, dirty, sig, _ = _take(scene, n, rng, operator=operator)
    bound = crb.cuboid_bounds(shots.surface_points, shots.normals, centre, sig)
    truth = {"axes": axes, "size": size, "los": los, "center": centre}
    return Trial(shots.points, dirty, truth, bound)


@dataclass
class SessionShots:
    """The object's points from a simulated session and the truth behind each (n rows)."""

    points: np.ndarray  # (n, 3) metres, measured
    directions: np.ndarray  # (n, 3) nominal unit directions
    true_range: np.ndarray  # (n,) metres
    background_range: np.ndarray  # (n,) metres, next surface behind (inf: none)
    surface_points: np.ndarray  # (n, 3) metres
    normals: np.ndarray  # (n, 3)
    edge: np.ndarray  # (n,) bool: an edge-bisection shot


def session_window(scene, wanted, margins):
    """The operator's window for a session: the silhouette window enlarged by ``margins``.

    ``margins`` are in steps of the session's raster (``drivers.session.grid``: ``wanted`` shots,
    cell-centred, columns and rows in proportion to the window), found by cutting the raster
    from the enlarged window twice (the raster's shape follows the window's aspect).
    """
    from asbuilt.drivers.plan import Window
    from asbuilt.drivers.session import grid

    silhouette = angular_window(scene.objects[0].shape, STATION.position)
    marked = silhouette
    for _ in range(2):
        pan0, tilt0, width, height = marked
        box = Window(pan0 - width / 2, pan0 + width / 2, tilt0 - height / 2, tilt0 + height / 2)
        rows, cols = grid(box, wanted)[2]
        marked = operator_window(silhouette, cols, rows, margins)
    pan0, tilt0, width, height = marked
    return Window(pan0 - width / 2, pan0 + width / 2, tilt0 - height / 2, tilt0 + height / 2)


def _take_session(scene, n, rng):
    """Exactly n points on object 0 acquired by the scan session's algorithm, outlier version.

    The session (``asbuilt.drivers.session.scan_target``, default settings: 4 edge pairs, one per
    silhouette side, bisected to 2 mm) shoots over an operator's window (:func:`session_window`,
    margins from :func:`~asbuilt.sim.sensor.operator_margins`), each shot by the station's model
    (:func:`asbuilt.sim.sensor.fire`: the beam measures whatever it meets, the wall behind when
    it misses). ``n`` counts every point kept on the object: raster, fill and edge-bisection
    hits. The session takes about 15 edge hits with the default 2 mm tolerance, most of them
    intermediate steps; within ``n`` it is asked for ``n - SESSION_EDGE_HITS`` raster points
    (again, adjusted, when its raster and fill land more or fewer) and the coarsest edge hits
    (farthest from a miss: a bisection's first steps) are dropped to make ``n``, which keeps
    the last two or so of each side's bisection. The raster is never thinned: its shots stay
    on their lattice, as on the device. Outliers as in :func:`_take`: the fifth of the
    points nearest a shot that missed become mixed returns (edge shots first: they graze the
    silhouette). Returns like :func:`_take`.
    """
    import dataclasses

    from asbuilt.drivers.plan import Target
    from asbuilt.drivers.session import Shot, scan_target

    from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS

    margins = operator_margins(rng)
    window = session_window(scene, n, margins)
    tolerances = dataclasses.replace(
        DEFAULT_TOLERANCES, recommended_points_cuboid=MIN_POINTS["cuboid"]
    )
    log = []

    def device(pan, tilt, phase):
        got = fire(scene, STATION, [pan], [tilt], rng)
        log.append(got)
        value = float(got.range[0])
        if not math.isfinite(value):
            return Shot(pan, tilt, pan, tilt, None, "E255", 1, phase)
        return Shot(pan, tilt, pan, tilt, value, None, 1, phase)

    # Ask for the raster points the kept edge hits leave room for: the session's raster and
    # fill keep at least what they are asked for, so a few rounds settle (the round nearest
    # the aim is kept).
    wanted = max(MIN_POINTS["cuboid"], n - SESSION_EDGE_HITS)
    best, fallback, tried = None, None, set()
    for _ in range(8):
        if wanted in tried:
            break
        tried.add(wanted)
        log.clear()
        target = Target("T", "cuboid", window, points=wanted)
        scan = scan_target(target, device, tolerances=tolerances)
        on = scan.on_object & np.array([r.object_index[0] == 0 for r in log])
        edge = np.array([s.phase == "edge" for s in scan.shots])
        body = int(np.count_nonzero(on & ~edge))
        hits = int(np.count_nonzero(on & edge))
        aim = n - min(SESSION_EDGE_HITS, hits)
        if body <= n <= body + hits and (best is None or abs(body - aim) < best[0]):
            best = (abs(body - aim), scan, on, edge, list(log))
        if best is not None and best[0] <= 1:
            break
        wanted = max(MIN_POINTS["cuboid"], wanted + aim - body)
        if best is None and body + hits >= n:
            fallback = (scan, on, edge, list(log))
    if best is None:
        if fallback is None:
            raise RuntimeError("the session could not put n points on the object")
        # Last resort: the raster and fill hits thinned evenly to leave room for the edge hits.
        scan, on, edge, log = fallback
        body = np.flatnonzero(on & ~edge)
        room = max(n - int(np.count_nonzero(on & edge)), MIN_POINTS["cuboid"])
        thinned = np.unique(np.round(np.linspace(0, len(body) - 1, room)).astype(int))
        on = on.copy()
        on[np.setdiff1d(body, body[thinned])] = False
    else:
        _, scan, on, edge, log = best
    angles = np.array([[s.pan, s.tilt] for s in scan.shots])
    # Edge proximity: angular distance to the nearest shot of the session that missed.
    missed = np.array([r.object_index[0] != 0 or not np.isfinite(r.range[0]) for r in log])
    xy = np.column_stack([angles[:, 0] * np.cos(angles[:, 1]), angles[:, 1]])
    near = np.zeros(len(log))
    if missed.any():
        diff = xy[:, None, :] - xy[missed][None, :, :]
        near = np.sqrt((diff**2).sum(axis=2)).min(axis=1)
    body = np.flatnonzero(on & ~edge)
    edges = np.flatnonzero(on & edge)
    extra = len(body) + len(edges) - n
    if extra > len(edges):
        raise RuntimeError("the session put more raster points on the object than n")
    if extra > 0:
        coarse = edges[np.argsort(-near[edges], kind="stable")[:extra]]
        edges = np.setdiff1d(edges, coarse)
    keep = np.sort(np.concatenate([body, edges]))
    proximity = near[keep]
    directions = direction_from_angles(angles[:, 0], angles[:, 1])
    ranges = np.array([np.nan if s.range is None else s.range for s in scan.shots])
    surface = np.array([log[i].surface_points[0] for i in keep])
    behind = scene.raycast(STATION.position, surface - STATION.position, exclude=0)
    shots = SessionShots(
        points=STATION.position + ranges[keep, None] * directions[keep],
        directions=directions[keep],
        true_range=np.array([log[i].true_range[0] for i in keep]),
        background_range=np.where(np.isfinite(behind.range), behind.range, np.inf),
        surface_points=surface,
        normals=np.array([log[i].normals[0] for i in keep]),
        edge=edge[keep],
    )
    return _with_edge_outliers(shots, ranges[keep], proximity, n, rng)


def hash_key(kind, key) -> int:
    text = f"{kind}:{key}"
    return sum((i + 1) * ord(c) for i, c in enumerate(text)) % (2**31)
