"""The pan-tilt range finder as the operator uses it: a raster of shots over one object.

The ideal kinematic chain: the beam starts at the station position and points along
``(cos tilt cos pan, cos tilt sin pan, sin tilt)`` (:func:`~asbuilt.sim.raycast.direction_from_angles`).
The calibrated chain with lever arms and axis offsets belongs to ``asbuilt.drivers.kinematics``.

Shot model (one shot, nominal angles ``pan, tilt`` as the device reports them):

1. the beam actually leaves along ``pan + e_p, tilt + e_t`` with ``e ~ N(0, angular_sigma)``;
2. it is ray-cast against the whole scene; the nearest surface is what it measures, and a shot
   whose nearest surface is not the aimed-at object is not recorded ("no target" for that
   object, as a real operator discards shots that fell off it);
3. the beam footprint (radius ``spot/2 + divergence * range / 2``) is probed by four rays at the
   footprint's edge; when any of them meets another surface or nothing, the shot straddles a
   silhouette edge and, with probability ``mixed_return``, returns the background range (the next
   surface behind, found by casting past the object; nothing behind means no return) or, with
   equal chance, a range uniformly in between (a mixed pixel);
4. with probability ``dropout`` it returns nothing at all;
5. otherwise the range is the true range plus ``N(0, range_sigma)``.

The recorded point is ``station + range * direction(pan, tilt)`` with the *nominal* angles, so
pointing noise displaces points across the beam by about ``range * e``.

The raster is cell-centred over a window: by default the object's exact angular silhouette
window (the outer shots half a raster step inside it), or, with ``operator_window=True`` in
:func:`scan_object`, the window an operator marks by eye - the silhouette window enlarged on
each side by an independent random margin uniform between 0 and one raster step - so the
object's edge falls anywhere between the last hit and the first miss.

:func:`fire` is the same shot model for beams aimed one at a time by an acquisition algorithm
(``asbuilt.drivers.session.scan_target``): it returns whatever each beam meets, the aimed-at
object or the background behind it, as the range finder would.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from asbuilt.sim.raycast import angles_from_direction, direction_from_angles

__all__ = [
    "Returns",
    "fire",
    "Shots",
    "angular_window",
    "raster_angles",
    "operator_margins",
    "operator_window",
    "plan_raster",
    "shoot",
    "scan_object",
]

#: Largest angular window (radians, either direction) a raster may cover.
MAX_WINDOW = np.radians(170.0)


@dataclass(frozen=True, eq=False)
class Shots:
    """The shots of one raster that returned a range on the aimed-at object.

    Attributes
    ----------
    station : ndarray, shape (3,), metres
    pan, tilt : ndarray, shape (n,), radians
        Nominal angles as the device reports them.
    range : ndarray, shape (n,), metres
        Measured range (noise and mixed returns included).
    true_range : ndarray, shape (n,), metres
        Noise-free range to the object along the actual beam.
    surface_points : ndarray, shape (n, 3), metres
        Where the actual beam met the object (exactly on its surface).
    normals : ndarray, shape (n, 3)
        Outward unit surface normals there.
    edge : ndarray, shape (n,), bool
        The footprint straddled a silhouette edge.
    mixed : ndarray, shape (n,), bool
        The range is a mixed return (background or in between): an outlier.
    background_range : ndarray, shape (n,), metres
        Range to the next surface behind the object along the actual beam (``inf``: none).
    planned : int
        Shots in the raster (hits, misses and dropouts).
    index : ndarray, shape (n,), int
        Each shot's position in the raster it came from.
    """

    station: np.ndarray
    pan: np.ndarray
    tilt: np.ndarray
    range: np.ndarray
    true_range: np.ndarray
    surface_points: np.ndarray
    normals: np.ndarray
    edge: np.ndarray
    mixed: np.ndarray
    background_range: np.ndarray
    planned: int
    index: np.ndarray

    def __len__(self) -> int:
        return int(self.range.shape[0])

    @property
    def directions(self) -> np.ndarray:
        """Nominal beam directions, shape (n, 3)."""
        return direction_from_angles(self.pan, self.tilt)

    @property
    def points(self) -> np.ndarray:
        """Measured points ``station + range * direction(pan, tilt)``, shape (n, 3) metres."""
        return self.station + self.range[:, None] * self.directions

    def subset(self, keep) -> Shots:
        """These shots restricted to ``keep`` (boolean mask or indices)."""
        fields = (
            "pan",
            "tilt",
            "range",
            "true_range",
            "surface_points",
            "normals",
            "edge",
            "mixed",
            "background_range",
            "index",
        )
        values = {name: getattr(self, name)[keep] for name in fields}
        return Shots(station=self.station, planned=self.planned, **values)


@dataclass(frozen=True, eq=False)
class Returns:
    """What each beam of :func:`fire` measured, whatever it met.

    Attributes
    ----------
    object_index : ndarray, shape (m,), int
        The object the actual beam met first (``-1``: nothing within the station's range).
    range : ndarray, shape (m,), metres
        Measured range (noise and mixed returns included); NaN when there is no return.
    true_range : ndarray, shape (m,), metres
        Noise-free range along the actual beam (``inf`` when it met nothing).
    surface_points : ndarray, shape (m, 3), metres
        Where the actual beam met the scene (NaN when it met nothing).
    normals : ndarray, shape (m, 3)
        Outward unit surface normals there (NaN when it met nothing).
    mixed : ndarray, shape (m,), bool
        The range is a mixed return (the footprint straddled a silhouette edge).
    edge : ndarray, shape (m,), bool
        The footprint straddled a silhouette edge of what the beam met.
    background_range : ndarray, shape (m,), metres
        Range to the next surface behind what the beam met (``inf``: none, or nothing met).
    """

    object_index: np.ndarray
    range: np.ndarray
    true_range: np.ndarray
    surface_points: np.ndarray
    normals: np.ndarray
    mixed: np.ndarray
    edge: np.ndarray
    background_range: np.ndarray


def fire(scene, station, pan, tilt, rng) -> Returns:
    """Fire beams one aims at a time: each measures whatever it meets first (the shot model).

    The module's shot model (pointing noise, footprint probes, mixed returns, dropout, range
    noise) applied to every beam whatever it meets: the object aimed at, the wall behind it or
    nothing. A footprint that straddles a silhouette edge returns, with probability
    ``mixed_return``, the range of the next surface behind (or nothing) or a range in between.

    Parameters
    ----------
    scene : Scene
    station : Station
    pan, tilt : array_like, shape (m,), radians
        Nominal angles (the recorded point is ``station + range * direction(pan, tilt)``).
    rng : numpy.random.Generator
        Draws 7 numbers per beam up front (as :func:`shoot`), whatever the beams meet.

    Returns
    -------
    Returns
    """
    pan = np.atleast_1d(np.asarray(pan, dtype=np.float64))
    tilt = np.atleast_1d(np.asarray(tilt, dtype=np.float64))
    m = len(pan)
    # Draw every random number up front so the stream never depends on the geometry.
    e_pan, e_tilt = rng.normal(0.0, station.angular_sigma, size=(2, m))
    noise = rng.normal(0.0, station.range_sigma, size=m)
    u_drop, u_mixed, u_kind, u_frac = rng.random(size=(4, m))

    actual_pan, actual_tilt = pan + e_pan, tilt + e_tilt
    beam = direction_from_angles(actual_pan, actual_tilt)
    origin = np.asarray(station.position, dtype=np.float64)
    hits = scene.raycast(origin, beam)
    met = (hits.object_index >= 0) & (hits.range <= station.max_range)
    index = np.where(met, hits.object_index, -1)
    true_range = np.where(met, hits.range, np.inf)
    surface = np.full((m, 3), np.nan)
    normals = np.full((m, 3), np.nan)
    surface[met] = origin + true_range[met, None] * beam[met]
    normals[met] = hits.normal[met]

    measured = np.full(m, np.nan)
    mixed = np.zeros(m, dtype=bool)
    edges = np.zeros(m, dtype=bool)
    behind_range = np.full(m, np.inf)
    idx = np.flatnonzero(met)
    if idx.size:
        r = true_range[idx]
        delta = station.footprint_radius(r) / r
        cos_t = np.maximum(np.cos(actual_tilt[idx]), 1e-6)
        edge = np.zeros(idx.size, dtype=bool)
        for dp, dt in ((1, 0), (-1, 0), (0, 1), (0, -1)):
            probe = direction_from_angles(
                actual_pan[idx] + dp * delta / cos_t, actual_tilt[idx] + dt * delta
            )
            edge |= scene.raycast(origin, probe).object_index != index[idx]
        behind = scene.raycast(origin, beam[idx], exclude=index[idx])
        background = np.where(behind.range <= station.max_range, behind.range, np.inf)
        value = r.copy()
        mix = edge & (u_mixed[idx] < station.mixed_return)
        lost = mix & ~np.isfinite(background)
        full = mix & np.isfinite(background) & (u_kind[idx] < 0.5)
        between = mix & np.isfinite(background) & ~full
        value[full] = background[full]
        value[between] = r[between] + u_frac[idx][between] * (background[between] - r[between])
        value = value + noise[idx]
        ok = ~lost & (u_drop[idx] >= station.dropout) & (value > 0)
        measured[idx[ok]] = value[ok]
        mixed[idx] = mix
        edges[idx] = edge
        behind_range[idx] = background
    return Returns(index, measured, true_range, surface, normals, mixed, edges, behind_range)


def angular_window(shape, station) -> tuple[float, float, float, float]:
    """The pan-tilt window that covers a shape as seen from the station.

    Parameters
    ----------
    shape : Shape
        Anything with ``sample_surface() -> (k, 3)`` metres.
    station : array_like, shape (3,), metres

    Returns
    -------
    pan0, tilt0 : float, radians
        Centre direction of the window.
    pan_extent, tilt_extent : float, radians
        Full widths: the window is ``pan0 +- pan_extent / 2`` and ``tilt0 +- tilt_extent / 2``.

    Raises
    ------
    ValueError
        The shape surrounds the station or spans more than 170 degrees.
    """
    station = np.asarray(station, dtype=np.float64)
    rel = shape.sample_surface() - station
    dist = np.linalg.norm(rel, axis=1)
    if np.any(dist <= 1e-9):
        raise ValueError("the station is on the object's surface")
    unit = rel / dist[:, None]
    mean = unit.mean(axis=0)
    if np.linalg.norm(mean) < 0.2:
        raise ValueError("the object surrounds the station")
    pan0, _ = angles_from_direction(mean)
    pan, tilt = angles_from_direction(unit)
    dpan = np.angle(np.exp(1j * (pan - pan0)))
    lo, hi = float(dpan.min()), float(dpan.max())
    t_lo, t_hi = float(tilt.min()), float(tilt.max())
    if hi - lo > MAX_WINDOW or t_hi - t_lo > MAX_WINDOW:
        raise ValueError(
            "the object spans more than 170 degrees seen from the station; move the station "
            "away from it or split it into smaller objects"
        )
    return (float(pan0) + 0.5 * (lo + hi), 0.5 * (t_lo + t_hi), hi - lo, t_hi - t_lo)


def raster_angles(window, n_pan: int, n_tilt: int) -> tuple[np.ndarray, np.ndarray]:
    """A cell-centred pan-tilt raster over ``window``, row by row, serpentine like a PTU.

    The operator marks the object's extreme directions; the unit splits that window into equal
    cells and shoots at each cell's centre (:data:`EDGE_INSET`), so the outer shots fall half a
    raster step inside the silhouette's bounding window.

    Parameters
    ----------
    window : tuple of float
        ``(pan0, tilt0, pan_extent, tilt_extent)`` radians (see :func:`angular_window`).
    n_pan, n_tilt : int
        Columns and rows.

    Returns
    -------
    pan, tilt : ndarray, shape (n_pan * n_tilt,), radians
    """
    pan0, tilt0, pan_ext, tilt_ext = window
    cols = pan0 + pan_ext * (_steps(n_pan) - 0.5)
    rows = tilt0 + tilt_ext * (0.5 - _steps(n_tilt))
    pan = np.empty((n_tilt, n_pan))
    pan[:] = cols
    pan[1::2] = cols[::-1]
    tilt = np.repeat(rows, n_pan).reshape(n_tilt, n_pan)
    return pan.ravel(), tilt.ravel()


#: The outermost shots sit this fraction of a raster step inside the marked window: 0.5 is a
#: cell-centred raster (the window split into equal cells, one shot at each cell's centre), so
#: points stop short of a silhouette edge by half a raster spacing, which is what
#: ``asbuilt.fit.cuboid`` adds back to extent-bounded sizes.
EDGE_INSET = 0.5


def _steps(n: int) -> np.ndarray:
    """``n`` evenly spaced fractions of [0, 1], the outer ones ``EDGE_INSET`` steps inside."""
    return (np.arange(n) + EDGE_INSET) / (n - 1 + 2 * EDGE_INSET)


#: Fewest raster lines in either direction: an operator covers an object's width with at least
#: five lines of shots however thin it looks, so every face or arc gets more than one line.
MIN_LINES = 5


def _grid_shape(window, shots: float) -> tuple[int, int]:
    _, tilt0, pan_ext, tilt_ext = window
    width = max(pan_ext * np.cos(tilt0), 1e-6)
    height = max(tilt_ext, 1e-6)
    aspect = width / height
    n_tilt = max(MIN_LINES, int(round(np.sqrt(shots / aspect))))
    n_pan = max(MIN_LINES, int(round(shots / n_tilt)))
    return n_pan, n_tilt


def operator_margins(rng) -> np.ndarray:
    """Random margins by which an operator's marked window overshoots the object's silhouette.

    A real operator marks the window by eye (or by aiming at the object's extreme directions),
    never exactly on its silhouette: each of the four sides lands an independent distance
    beyond the silhouette's bounding window, uniform between 0 and one raster step.

    Parameters
    ----------
    rng : numpy.random.Generator
        Draws exactly four uniforms, so a stream stays reproducible.

    Returns
    -------
    ndarray, shape (4,)
        Margins in raster steps, each in [0, 1): ``[pan_low, pan_high, tilt_low, tilt_high]``.
    """
    return rng.uniform(0.0, 1.0, size=4)


def operator_window(window, n_pan: int, n_tilt: int, margins) -> tuple[float, float, float, float]:
    """The silhouette window enlarged on each side by a margin in steps of the final raster.

    The raster step depends on the enlarged window it is cut from: with ``c = n - 1 +
    2 EDGE_INSET`` cells the step is ``extent' / c`` and ``extent' = extent + (m_lo + m_hi)
    step``, so ``extent' = extent / (1 - (m_lo + m_hi) / c)`` makes every margin exactly
    ``m`` steps of the raster :func:`raster_angles` then shoots over the enlarged window. With
    cell-centred shots the object's edge then falls anywhere from 0 to 1 step beyond the last
    line of hits (uniformly, for margins uniform over one step), as on a real device.

    Parameters
    ----------
    window : tuple of float
        ``(pan0, tilt0, pan_extent, tilt_extent)`` radians: the silhouette window
        (:func:`angular_window`).
    n_pan, n_tilt : int
        Columns and rows of the raster that will be shot over the enlarged window (>= 2).
    margins : array_like, shape (4,)
        ``[pan_low, pan_high, tilt_low, tilt_high]`` in raster steps, each in [0, 1]
        (:func:`operator_margins`).

    Returns
    -------
    tuple of float
        The enlarged ``(pan0, tilt0, pan_extent, tilt_extent)``, radians.
    """
    pan0, tilt0, pan_ext, tilt_ext = window
    m = np.asarray(margins, dtype=np.float64)
    if m.shape != (4,) or np.any(m < 0.0) or np.any(m > 1.0):
        raise ValueError("operator margins must be four values in [0, 1] raster steps")
    out = []
    for centre, extent, n, lo, hi in (
        (pan0, pan_ext, n_pan, m[0], m[1]),
        (tilt0, tilt_ext, n_tilt, m[2], m[3]),
    ):
        cells = n - 1 + 2 * EDGE_INSET
        enlarged = extent / (1.0 - (lo + hi) / cells)
        step = enlarged / cells
        out.append((centre + 0.5 * (hi - lo) * step, enlarged))
    return (float(out[0][0]), float(out[1][0]), float(out[0][1]), float(out[1][1]))


def plan_raster(scene, target: int, station, n_points: int, *, max_rounds: int = 16, margins=None):
    """Choose a raster over the object's window with at least ``n_points`` noise-free hits.

    The grid's aspect follows the window's; its size is rescaled by the observed hit fraction
    until the first raster with ``n_points`` to ``1.15 n_points + 1`` hits on the object is found (or
    the smallest one with enough hits after ``max_rounds``).

    Parameters
    ----------
    scene : Scene
    target : int
        Object index.
    station : Station
    n_points : int
    margins : array_like, shape (4,), optional
        The operator's window: the silhouette window enlarged by these margins, in raster steps
        (:func:`operator_margins`, :func:`operator_window`); each candidate grid is cut from the
        window enlarged for its own step, and the shots off the object are simply not counted.
        Default: the exact silhouette window.

    Returns
    -------
    pan, tilt : ndarray, shape (m,), radians
        The raster.
    hits : int
        Noise-free hits on the object.

    Raises
    ------
    ValueError
        The object cannot be seen from the station (occluded or out of range).
    """
    window = angular_window(scene.objects[target].shape, station.position)
    shots = n_points / 0.6
    best = None
    tried = set()
    for _ in range(max_rounds):
        dims = _grid_shape(window, shots)
        if dims in tried:
            dims = (dims[0] + 1, dims[1] + (dims[1] >= dims[0]))
        tried.add(dims)
        marked = window if margins is None else operator_window(window, *dims, margins)
        pan, tilt = raster_angles(marked, *dims)
        hits = scene.raycast(station.position, direction_from_angles(pan, tilt))
        n_hit = int(
            np.count_nonzero((hits.object_index == target) & (hits.range <= station.max_range))
        )
        if n_hit >= n_points and (best is None or n_hit < best[2]):
            best = (pan, tilt, n_hit)
        if n_points <= n_hit <= 1.15 * n_points + 1:
            break
        if n_hit == 0:
            shots *= 2
            if shots > 200 * n_points:
                break
            continue
        shots = shots * float(np.clip(1.08 * n_points / n_hit, 0.5, 2.0))
    if best is None:
        raise ValueError(
            "too few shots land on it from this station (occluded, too small "
            "or out of range); move the station"
        )
    return best


def shoot(scene, target: int, station, pan, tilt, rng) -> Shots:
    """Fire a raster at one object with the station's noise model (see the module notes).

    Parameters
    ----------
    scene : Scene
    target : int
        Object index the operator aims at.
    station : Station
    pan, tilt : array_like, shape (m,), radians
        Nominal raster angles.
    rng : numpy.random.Generator

    Returns
    -------
    Shots
        Only the shots that returned a range on the object.
    """
    pan = np.atleast_1d(np.asarray(pan, dtype=np.float64))
    tilt = np.atleast_1d(np.asarray(tilt, dtype=np.float64))
    # The same beams as :func:`fire` (same random numbers); the operator keeps the returns
    # whose beam met the aimed-at object.
    got = fire(scene, station, pan, tilt, rng)
    idx = np.flatnonzero(got.object_index == target)
    shots = Shots(
        station=np.asarray(station.position, dtype=np.float64).copy(),
        pan=pan[idx],
        tilt=tilt[idx],
        range=got.range[idx],
        true_range=got.true_range[idx],
        surface_points=got.surface_points[idx],
        normals=got.normals[idx],
        edge=got.edge[idx],
        mixed=got.mixed[idx],
        background_range=got.background_range[idx],
        planned=len(pan),
        index=idx,
    )
    return shots.subset(np.isfinite(got.range[idx]))


def scan_object(
    scene,
    target: int,
    *,
    n_points: int | None = None,
    station=None,
    rng=None,
    exact: bool = False,
    operator_window: bool = False,
) -> Shots:
    """Aim at one object and shoot a raster of about ``n_points`` shots landing on it.

    Parameters
    ----------
    scene : Scene
    target : int
        Object index.
    n_points : int, optional
        Shots wanted on the object (default: the object's ``points``).
    station : Station, optional
        Default: the object's station.
    rng : numpy.random.Generator, optional
        Default: ``numpy.random.default_rng(0)``.
    exact : bool
        Return exactly ``n_points`` shots (evenly thinned from a raster with at least that
        many returns), as the accuracy benchmark needs; otherwise return what the raster gave.
    operator_window : bool
        Shoot over an operator's window instead of the exact silhouette window: the window
        enlarged on each side by an independent margin uniform between 0 and one raster step
        (:func:`operator_margins`, four uniforms drawn from ``rng`` before any shot), so the
        object's edges fall anywhere between the last hit and the first miss. Shots off the
        object are dropped; the raster is sized so about ``n_points`` still land on it. Default
        False: the exact window (the committed samples and ``asbuilt simulate``).

    Returns
    -------
    Shots

    Raises
    ------
    ValueError
        The object cannot be seen well enough from the station.
    """
    obj = scene.objects[target]
    station = scene.station(obj.station) if station is None else station
    n_points = obj.points if n_points is None else int(n_points)
    rng = np.random.default_rng(0) if rng is None else rng
    margins = operator_margins(rng) if operator_window else None
    wanted = n_points
    for _ in range(6):
        pan, tilt, _hits = plan_raster(scene, target, station, wanted, margins=margins)
        shots = shoot(scene, target, station, pan, tilt, rng)
        if not exact:
            return shots
        if len(shots) >= n_points:
            keep = np.unique(np.round(np.linspace(0, len(shots) - 1, n_points)).astype(int))
            return shots.subset(keep)
        wanted = int(np.ceil(wanted * 1.2 * n_points / max(len(shots), 1)))
    raise ValueError(
        f"only {len(shots)} of {n_points} shots returned; reduce dropout or move the station"
    )
