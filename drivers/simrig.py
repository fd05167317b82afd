"""The simulated rig behind the device simulators: a pan-tilt head, a range finder and a world.

One :class:`SimulatedRig` holds the true head position (counts) and the scene; the simulated
pan-tilt unit moves it and the simulated range finder measures along the beam the *same*
kinematic chain (:mod:`asbuilt.drivers.kinematics`) gives for the rig's own "true" calibration,
so a driver-side calibration can be checked against the injected one.

The world is anything with ``raycast(origins (n,3), directions (n,3))`` returning an object with
``range`` (n,) metres (``inf`` = miss) and ``cos_incidence`` (n,): a scene from :mod:`asbuilt.sim`,
or :class:`ShapesWorld` over shapes / a triangle mesh loaded with trimesh from an exported model.

Sensor effects (:class:`SimNoise`): Gaussian range noise, Gaussian pointing noise, random
dropouts and a range limit (both answered as "signal too weak"), grazing incidence below a
cosine threshold ("signal too weak"), and mixed returns at edges: the beam is a cone of
``divergence`` half-angle sampled by a centre ray and a ring of six; when part of the footprint
hits the object and part the background, the device reports the return-power-weighted mean
range (weights ``cos_incidence / range**2``), a phantom point between the two surfaces, and
answers "signal too weak" when less than half of the footprint returns anything.

Rigs are shared by name (:func:`get_rig`) so that ``sim-ptu://lab`` and ``sim-lrf://lab`` opened
separately drive the same head.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from asbuilt.errors import AsbuiltError, DeviceError, SceneError

from .kinematics import Calibration, beam

__all__ = [
    "SimNoise",
    "SimulatedRig",
    "ShapesWorld",
    "load_world",
    "get_rig",
    "register_rig",
    "forget_rigs",
    "station_defaults",
    "D46_RESOLUTION",
    "D46_LIMITS",
]

#: PTU-D46 example resolution, seconds of arc per position (manual; other models differ).
D46_RESOLUTION = 185.1428
#: PTU-D46 example limits: pan min, pan max, tilt min, tilt max (positions).
D46_LIMITS = (-3090, 3090, -907, 604)


#: Radians: the largest beam half-angle a simulated range finder takes. Laser range finders'
#: beams spread by 0.1-3 mrad; at 0.1 rad (5.7 degrees) the four edge rays would probe a footprint
#: metres wide at 10 m, no longer a laser's mixed edge return.
MAX_DIVERGENCE = 0.1


@dataclass(frozen=True)
class SimNoise:
    """Sensor effects of the simulated range finder.

    Attributes
    ----------
    range_sigma : float
        Metres, standard deviation of Gaussian range noise.
    angle_sigma : float
        Radians, standard deviation of Gaussian pointing noise per axis.
    dropout : float
        Probability (0-1) that a shot returns "signal too weak" regardless of the target.
    divergence : float
        Radians, beam half-angle for mixed edge returns (0: a single ray, no mixing).
    min_cos : float
        Returns at incidence cosines below this are too weak (grazing).
    max_range : float
        Metres; beyond it the signal is too weak.
    seed : int or None
        Random seed (None: fresh entropy).
    """

    range_sigma: float = 0.0
    angle_sigma: float = 0.0
    dropout: float = 0.0
    divergence: float = 0.0
    min_cos: float = 0.02
    max_range: float = 200.0
    seed: int | None = 0

    def __post_init__(self) -> None:
        for name in ("range_sigma", "angle_sigma", "divergence", "min_cos", "max_range"):
            if not np.isfinite(getattr(self, name)) or getattr(self, name) < 0:
                raise ValueError(f"{name} must be a finite number >= 0")
        if not 0.0 <= self.dropout <= 1.0:
            raise ValueError("dropout must be between 0 and 1")
        if self.min_cos > 1.0:
            raise ValueError(f"min_cos is a cosine, at most 1, not {self.min_cos:g}")
        if self.divergence > MAX_DIVERGENCE:
            raise ValueError(
                f"divergence {self.divergence * 1e3:g} mrad is not a laser beam's: a range "
                f"finder's beam spreads by a few milliradians (at most {MAX_DIVERGENCE * 1e3:g})"
            )
        seed = self.seed
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
            raise ValueError(f"seed must be a non-negative integer, not {seed!r}")


class ShapesWorld:
    """A world of :mod:`asbuilt.sim.raycast` shapes (analytic solids or triangle meshes).

    Parameters
    ----------
    shapes : sequence of asbuilt.sim.raycast.Shape
    """

    def __init__(self, shapes):
        self.shapes = tuple(shapes)

    def raycast(self, origins, directions):
        """Nearest hits; see :func:`asbuilt.sim.raycast.raycast`."""
        from asbuilt.sim.raycast import raycast

        return raycast(self.shapes, origins, directions)


def load_world(path):
    """Load a world to cast rays into from a scene description or an exported model.

    Parameters
    ----------
    path : str or Path
        ``.json``: an asbuilt scene (loaded by :mod:`asbuilt.sim`); any mesh format trimesh
        reads (``.stl``, ``.glb``, ``.gltf``, ``.obj``, ``.ply``): the model's triangles, in
        metres as stored.

    Raises
    ------
    SceneError
        The file cannot be read or holds no geometry.
    """
    path = Path(path)
    if path.is_dir():
        raise SceneError("is a directory; give the scene or model file itself", source=str(path))
    if not path.is_file():
        raise SceneError(
            "scene file not found; give an existing scene or model file", source=str(path)
        )
    if path.suffix.lower() == ".json":
        from asbuilt import sim

        loader = getattr(sim, "load_scene", None)
        if loader is None:
            raise SceneError(
                "this build has no scene loader (asbuilt.sim.load_scene); "
                "give an exported mesh (.stl, .glb) instead",
                source=str(path),
            )
        return loader(path)
    from asbuilt.sim.meshfile import read_mesh_file
    from asbuilt.sim.raycast import MeshShape

    try:
        vertices, faces = read_mesh_file(path)
    except ValueError as exc:
        raise SceneError(str(exc), source=str(path)) from None
    shape = MeshShape(vertices=vertices, faces=faces)
    return ShapesWorld([shape])


@dataclass
class _Axis:
    """One axis' motion: position interpolates from ``start`` to ``target`` over the move."""

    start: float = 0.0
    target: float = 0.0
    t0: float = 0.0
    t1: float = 0.0

    def at(self, now: float) -> float:
        if now >= self.t1 or self.t1 <= self.t0:
            return self.target
        return self.start + (self.target - self.start) * (now - self.t0) / (self.t1 - self.t0)


@dataclass
class SimulatedRig:
    """The shared state of a simulated pan-tilt unit and range finder.

    Parameters
    ----------
    world : object with ``raycast``
        What the beam hits.
    calibration : Calibration
        The rig's true kinematic chain (unit angles and raw range -> scan frame).
    noise : SimNoise
        Sensor effects.
    resolution : (float, float)
        Pan and tilt seconds of arc per position.
    limits : (int, int, int, int)
        Pan min, pan max, tilt min, tilt max in positions.
    speed : float
        Positions per second of each axis; 0 moves instantly (tests).
    """

    world: object
    calibration: Calibration = field(default_factory=Calibration)
    noise: SimNoise = field(default_factory=SimNoise)
    resolution: tuple[float, float] = (D46_RESOLUTION, D46_RESOLUTION)
    limits: tuple[int, int, int, int] = D46_LIMITS
    speed: float = 0.0
    shots: int = 0
    options: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.speed) and self.speed >= 0):
            raise ValueError(
                f"speed must be a finite number >= 0 (positions per second; 0 moves instantly), "
                f"not {self.speed!r}"
            )
        self.pan = _Axis()
        self.tilt = _Axis()
        self.lock = threading.RLock()
        self.rng = np.random.default_rng(self.noise.seed)

    # -- head ------------------------------------------------------------------------------
    def move(self, pan_counts: int | None = None, tilt_counts: int | None = None) -> float:
        """Start a move to absolute counts; returns the time (monotonic) it will end."""
        with self.lock:
            now = time.monotonic()
            end = now
            for axis, target in ((self.pan, pan_counts), (self.tilt, tilt_counts)):
                if target is None:
                    continue
                start = axis.at(now)
                duration = abs(target - start) / self.speed if self.speed > 0 else 0.0
                axis.start, axis.target, axis.t0, axis.t1 = (
                    start,
                    float(target),
                    now,
                    now + duration,
                )
                end = max(end, axis.t1)
            return max(end, self.pan.t1, self.tilt.t1)

    def counts(self, now: float | None = None) -> tuple[float, float]:
        """Current pan and tilt position, counts (fractional while moving)."""
        now = time.monotonic() if now is None else now
        return self.pan.at(now), self.tilt.at(now)

    def move_end(self) -> float:
        """Monotonic time at which the current move ends."""
        return max(self.pan.t1, self.tilt.t1)

    def unit_angles(self) -> tuple[float, float]:
        """Current unit angles, radians."""
        pc, tc = self.counts()
        k = np.pi / (180 * 3600)
        return pc * self.resolution[0] * k, tc * self.resolution[1] * k

    # -- range finder ----------------------------------------------------------------------
    def measure(self) -> float | None:
        """One raw range along the current beam, metres; None when the signal is too weak.

        The returned value is what the device would print: ``(D - r0) / s`` plus noise, where
        ``D`` is the geometric distance along the true beam and ``r0``, ``s`` the true
        range offset and scale.
        """
        with self.lock:
            self.shots += 1
            noise = self.noise
            pan, tilt = self.unit_angles()
            if noise.angle_sigma > 0:
                pan += self.rng.normal(0.0, noise.angle_sigma)
                tilt += self.rng.normal(0.0, noise.angle_sigma)
            if noise.dropout > 0 and self.rng.random() < noise.dropout:
                return None
            origins, directions = beam(self.calibration, pan, tilt)
            rays = self._footprint(directions[0])
            hits = self.world.raycast(np.repeat(origins, len(rays), axis=0), rays)
            rng = np.asarray(hits.range, float)
            cos = np.asarray(hits.cos_incidence, float)
            ok = np.isfinite(rng) & (rng <= noise.max_range) & (cos >= noise.min_cos)
            if ok.sum() * 2 < len(rays):
                return None
            weights = cos[ok] / np.maximum(rng[ok], 0.05) ** 2
            distance = float(np.sum(weights * rng[ok]) / np.sum(weights))
            if noise.range_sigma > 0:
                distance += self.rng.normal(0.0, noise.range_sigma)
            cal = self.calibration
            return (distance - cal.range_offset) / cal.range_scale

    def _footprint(self, direction: np.ndarray) -> np.ndarray:
        if self.noise.divergence <= 0:
            return direction[None, :]
        helper = np.array([0.0, 0.0, 1.0]) if abs(direction[2]) < 0.9 else np.array([1.0, 0, 0])
        u = np.cross(direction, helper)
        u /= np.linalg.norm(u)
        v = np.cross(direction, u)
        a = np.linspace(0, 2 * np.pi, 6, endpoint=False)
        ring = np.cos(self.noise.divergence) * direction + np.sin(self.noise.divergence) * (
            np.cos(a)[:, None] * u + np.sin(a)[:, None] * v
        )
        return np.vstack([direction, ring])


_RIGS: dict[str, SimulatedRig] = {}
_RIGS_LOCK = threading.Lock()


def register_rig(name: str, rig: SimulatedRig) -> SimulatedRig:
    """Make ``rig`` the one ``sim-ptu://<name>`` and ``sim-lrf://<name>`` open."""
    with _RIGS_LOCK:
        _RIGS[name] = rig
    return rig


def forget_rigs() -> None:
    """Drop every registered rig (tests)."""
    with _RIGS_LOCK:
        _RIGS.clear()


#: URL options that configure the rig (as opposed to one port).
RIG_OPTIONS = (
    "scene",
    "calibration",
    "range_sigma",
    "angle_sigma",
    "dropout",
    "divergence",
    "min_cos",
    "max_range",
    "seed",
    "speed",
    "station",
)


def get_rig(name: str, options: dict[str, str]) -> SimulatedRig:
    """The rig called ``name``, created from URL ``options`` on first use.

    Parameters
    ----------
    name : str
        Rig name (the URL's host part).
    options : dict of str
        Rig options from the URL query (see :data:`RIG_OPTIONS`); ``scene`` is required to
        create a rig. A later URL may repeat the same options or leave them out.

    Raises
    ------
    DeviceError
        No such rig and no scene to create it, bad option values, or options that contradict
        the existing rig.
    """
    rig_opts = {k: v for k, v in options.items() if k in RIG_OPTIONS}
    with _RIGS_LOCK:
        rig = _RIGS.get(name)
        if rig is not None:
            for key, value in rig_opts.items():
                if rig.options.get(key) != value:
                    raise DeviceError(
                        f"simulated rig {name!r} already exists with {key}="
                        f"{rig.options.get(key)!r}, not {value!r}; use the same options or "
                        "another rig name"
                    )
            return rig
        if "scene" not in rig_opts:
            raise DeviceError(
                f"simulated rig {name!r} does not exist; give ?scene=PATH in the first URL "
                "opened for it"
            )
        rig = _rig_from_options(rig_opts)
        _RIGS[name] = rig
        return rig


def station_defaults(world, station: str | None = None) -> tuple[Calibration, dict]:
    """Base position and noise defaults from a scene's station (empty for other worlds).

    Parameters
    ----------
    world : object
        A scene (with ``stations``) or any other world.
    station : str, optional
        Station id (default: the scene's first station).

    Returns
    -------
    (Calibration, dict)
        An ideal chain standing at the station, and ``SimNoise`` keyword defaults
        (``range_sigma``, ``angle_sigma``, ``dropout``, ``max_range``, ``divergence`` as the
        half-angle of the station's full beam divergence).
    """
    stations = getattr(world, "stations", None)
    if not stations:
        if station is not None:
            raise DeviceError(f"station {station!r}: this world has no stations (not a scene)")
        return Calibration(), {}
    st = stations[0]
    if station is not None:
        matches = [s for s in stations if s.id == station]
        if not matches:
            known = ", ".join(s.id for s in stations)
            raise DeviceError(f"the scene has no station {station!r}; use one of {known}")
        st = matches[0]
    noise = {
        "range_sigma": float(st.range_sigma),
        "angle_sigma": float(st.angular_sigma),
        "dropout": float(st.dropout),
        "max_range": float(st.max_range),
        "divergence": 0.5 * float(st.beam_divergence),
    }
    return Calibration(base_position=tuple(float(v) for v in st.position)), noise


def _rig_from_options(opts: dict[str, str]) -> SimulatedRig:
    from .calibration import load_calibration

    world = load_world(opts["scene"])
    calibration, noise_kwargs = station_defaults(world, opts.get("station"))
    try:
        for key in ("range_sigma", "angle_sigma", "dropout", "divergence", "min_cos", "max_range"):
            if key in opts:
                noise_kwargs[key] = float(opts[key])
        if "seed" in opts:
            noise_kwargs["seed"] = int(opts["seed"])
        noise = SimNoise(**noise_kwargs)
        speed = float(opts.get("speed", 0.0))
        if "calibration" in opts:
            calibration = load_calibration(opts["calibration"])
        return SimulatedRig(world, calibration, noise, speed=speed, options=dict(opts))
    except ValueError as exc:
        if isinstance(exc, AsbuiltError):  # a bad calibration file says so itself
            raise
        raise DeviceError(f"simulated rig: bad option value ({exc})") from None
