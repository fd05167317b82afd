"""Scene description files for the simulator: load, validate, and expand into ray-castable shapes.

A scene (JSON, documented in ``docs/scene-format.md``) has units, one or more stations (the
pan-tilt range finder's position and noise) and objects, each with the kind the operator would
say and an exact geometry. Loading converts every length to metres once; the result is a frozen
:class:`Scene` whose :meth:`Scene.raycast` casts rays against every object (occlusion included).
Every mistake in the file raises :class:`~asbuilt.errors.SceneError` naming the file, the
object and the field.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from asbuilt.errors import SceneError
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Primitive, Sphere
from asbuilt.scan.insulation import INSULATED_KINDS, MAX_INSULATION
from asbuilt.scan.load import MAX_POINTS
from asbuilt.scan.model import KINDS
from asbuilt.tolerances import MIN_POINTS
from asbuilt.units import UNITS

from .geometry import frustum_mesh, member_axes, plate_axes, rotation_zyx, torus_segment_mesh
from .meshfile import mesh_problem, read_mesh_file
from .raycast import (
    BoxShape,
    CylinderShape,
    MeshShape,
    PlaneShape,
    RayHits,
    Shape,
    SphereShape,
    raycast,
)
from .scene_fields import FieldReader as _Reader

__all__ = [
    "Station",
    "SceneObject",
    "Scene",
    "load_scene",
    "loads_scene",
    "scene_from_dict",
    "GEOMETRY_TYPES",
    "INSULATED_GEOMETRY",
    "DEFAULT_POINTS",
]

#: Geometry types a scene object may use.
GEOMETRY_TYPES = (
    "cylinder",
    "tank",
    "pipe_run",
    "box",
    "member",
    "plate",
    "sphere",
    "frustum",
    "elbow",
    "mesh",
    "ground",
)

#: Geometry types an object's ``insulation`` may wrap: its surface is a pipe's (a pipe run's
#: elbows are wrapped with its straights).
INSULATED_GEOMETRY = ("cylinder", "pipe_run", "elbow")

#: Share of an elbow's bend radius its cladding may reach: lagging is mitred thinner on a tight
#: bend. The same share as :data:`asbuilt.insulation.JACKET_ROOM` (not imported: it would load
#: the model package into every simulation).
ELBOW_CLADDING_ROOM = 0.95

#: Points per object when neither the object nor the scene says.
DEFAULT_POINTS = 30

_MAX_FILE_BYTES = 20_000_000


@dataclass(frozen=True, eq=False)
class Station:
    """Where the pan-tilt range finder stands and how it errs.

    Attributes
    ----------
    id : str
    position : ndarray, shape (3,), metres
        The beam origin (ideal chain: pan and tilt axes meet here).
    range_sigma : float, metres
        Standard deviation of the range noise (default 2 mm).
    angular_sigma : float, radians
        Standard deviation of the pan and tilt pointing noise (default 0.01 degree).
    dropout : float
        Probability that any shot returns nothing.
    mixed_return : float
        Probability that a shot whose footprint straddles a silhouette edge returns the
        background range or a range in between.
    beam_divergence : float, radians
        Full divergence of the laser beam (footprint grows with range).
    spot_diameter : float, metres
        Beam diameter at the exit.
    max_range : float, metres
        Farther surfaces return nothing.
    """

    id: str
    position: np.ndarray
    range_sigma: float = 0.002
    angular_sigma: float = math.radians(0.01)
    dropout: float = 0.0
    mixed_return: float = 0.3
    beam_divergence: float = 0.0005
    spot_diameter: float = 0.003
    max_range: float = 100.0

    def footprint_radius(self, rng) -> np.ndarray:
        """Beam footprint radius, metres, at range ``rng`` (array, metres)."""
        return 0.5 * self.spot_diameter + 0.5 * self.beam_divergence * np.asarray(rng, float)


@dataclass(frozen=True, eq=False)
class SceneObject:
    """One object of the scene.

    Attributes
    ----------
    id : str
    kind : str or None
        The kind the operator says when scanning it (one of the scan kinds); None for
        background-only geometry.
    shape : Shape
        Exact geometry in metres: what the beams hit, the cladding of an insulated pipe.
    truth : Primitive
        The true primitive (what a perfect fit would return), metres; of an insulated pipe,
        the bare pipe inside its insulation.
    points : int
        Shots wanted on it.
    scan : bool
        Whether the operator scans it (False: it only occludes and catches stray beams).
    station : str
        The station that scans it.
    index : int
        Position in :attr:`Scene.objects` (the ``object_index`` of ray hits).
    group, label, nominal : str or None
        Copied to the scan.
    insulation : float, metres
        Thickness of the lagging and cladding around the pipe (0: bare); ``shape`` is the
        cladding, ``truth`` the pipe, and the scan object carries the thickness.
    """

    id: str
    kind: str | None
    shape: Shape
    truth: Primitive
    points: int
    scan: bool
    station: str
    index: int
    group: str | None = None
    label: str | None = None
    nominal: str | None = None
    insulation: float = 0.0


@dataclass(frozen=True, eq=False)
class Scene:
    """A loaded scene, all lengths in metres.

    ``units`` is the unit the file was written in (simulated scans are written in it).
    """

    units: str
    stations: tuple[Station, ...]
    objects: tuple[SceneObject, ...]
    links: tuple[tuple[str, str], ...] = ()
    name: str | None = None
    seed: int | None = None
    source: str | None = None
    extra: Mapping = field(default_factory=dict)

    @property
    def shapes(self) -> tuple[Shape, ...]:
        """Every object's shape, in object order."""
        return tuple(obj.shape for obj in self.objects)

    def raycast(self, origins, directions, *, exclude=None) -> RayHits:
        """Nearest hit of each ray over every object of the scene.

        Parameters
        ----------
        origins : array_like, shape (n, 3) or (3,), metres
        directions : array_like, shape (n, 3)
            Normalised here.
        exclude : int or array_like of int, shape (n,), optional
            An object index each ray ignores (``-1`` for none).

        Returns
        -------
        RayHits
            ``range`` (n,) metres (``inf`` for a miss), ``object_index`` (n,) into
            :attr:`objects` (``-1`` for a miss), ``cos_incidence`` (n,), ``normal`` (n, 3).
        """
        return raycast(self.shapes, origins, directions, exclude=exclude)

    def station(self, station_id: str | None = None) -> Station:
        """The station with this id (the first one when None); KeyError when unknown."""
        if station_id is None:
            return self.stations[0]
        for station in self.stations:
            if station.id == station_id:
                return station
        raise KeyError(station_id)

    def object(self, object_id: str) -> SceneObject:
        """The object with this id; KeyError when unknown."""
        for obj in self.objects:
            if obj.id == object_id:
                return obj
        raise KeyError(object_id)


def load_scene(path) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path : str or Path
        A JSON scene file; mesh files it names are resolved relative to it.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        The file is missing, unreadable, not JSON, or any field is wrong (one line naming the
        file, the object and the field).
    """
    from .._text import read_text

    path = Path(path)
    try:
        too_large = path.is_file() and path.stat().st_size > _MAX_FILE_BYTES
    except OSError:
        too_large = False  # read_text says why it cannot be read
    if too_large:
        raise SceneError("file is larger than 20 MB; is this a scene file?", source=str(path))
    text = read_text(path, SceneError, what="scene", missing="file not found; check the path")
    return loads_scene(text, source=str(path), base_dir=path.parent)


def loads_scene(text: str, *, source: str | None = None, base_dir=None) -> Scene:
    """Parse and validate a scene from JSON text (see :func:`load_scene`)."""
    from .._text import loads_json

    try:
        doc = loads_json(text, SceneError, source=source)
    except json.JSONDecodeError as exc:
        raise SceneError(
            f"line {exc.lineno} column {exc.colno}: invalid JSON ({exc.msg}); fix the syntax there",
            source=source,
        ) from None
    except RecursionError:
        raise SceneError(
            "invalid JSON (nested too deeply); a scene nests lists three levels at most",
            source=source,
        ) from None
    return scene_from_dict(doc, source=source, base_dir=base_dir)


def _load_mesh(reader: _Reader, geo, where) -> tuple[np.ndarray, np.ndarray]:
    if "file" in geo:
        name = reader.text(geo, "file", where, required=True)
        path = Path(name)
        if not path.is_absolute():
            path = reader.base_dir / path
        try:
            vertices, faces = read_mesh_file(path, on_site=False)  # scaled, then checked
        except ValueError as exc:
            reader.fail(f"{where}.file", f"mesh {str(path)!r}: {exc}")
    else:
        vertices = geo.get("vertices")
        faces = geo.get("faces")
        if vertices is None or faces is None:
            reader.fail(where, "a mesh needs 'file' or both 'vertices' and 'faces'")
        try:
            vertices = np.array(vertices, dtype=np.float64)
            faces = np.array(faces, dtype=np.int64)
        except (TypeError, ValueError, OverflowError):
            reader.fail(where, "'vertices' must be [[x, y, z], ...] and 'faces' [[i, j, k], ...]")
    if vertices.ndim != 2 or vertices.shape[1] != 3 or len(vertices) < 4:
        reader.fail(f"{where}.vertices", "needs at least 4 vertices of 3 coordinates")
    if not np.all(np.isfinite(vertices)):
        reader.fail(f"{where}.vertices", "must be finite")
    if faces.ndim != 2 or faces.shape[1] != 3 or len(faces) < 4:
        reader.fail(f"{where}.faces", "needs at least 4 triangles of 3 vertex indices")
    if faces.min() < 0 or faces.max() >= len(vertices):
        reader.fail(f"{where}.faces", "must index the vertices (0-based)")
    scale = reader.number(geo, "scale", where, default=1.0, positive=True)
    vertices = vertices * scale * reader.scale
    translate = reader.vector(geo, "translate", where, required=False, default=np.zeros(3))
    reader._on_site(vertices + translate, f"{where}.vertices")
    problem = mesh_problem(vertices + translate, faces)
    if problem:
        reader.fail(where, problem)
    return vertices + translate, faces


def _rows(value) -> np.ndarray | None:
    """``value`` as an array of numbers, None when it is not a list of lists of numbers."""
    if not isinstance(value, list) or not all(
        isinstance(row, list)
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)
        for row in value
    ):
        return None
    try:
        return np.array(value, dtype=np.float64)
    except ValueError:  # rows of different lengths
        return None


def _cylinder_object(
    start, end, radius, capped: bool = True, insulation: float = 0.0
) -> tuple[Shape, Primitive]:
    """The shape the beams hit (the cladding, ``radius + insulation``) and the true pipe."""
    axis = end - start
    length = float(np.linalg.norm(axis))
    shape = CylinderShape(start=start, end=end, radius=radius + insulation, capped=capped)
    truth = Cylinder(center=0.5 * (start + end), axis=axis / length, radius=radius, length=length)
    return shape, truth


def _box_object(center, axes, size) -> tuple[Shape, Primitive]:
    truth = Cuboid(center=center, axes=axes, size=size)
    return BoxShape(center=truth.center, axes=truth.axes, size=truth.size), truth


def _elbow_object(corner, before, after, bend, radius, insulation: float = 0.0) -> dict:
    """An elbow's shape (its cladding, mitred to :data:`ELBOW_CLADDING_ROOM` of the bend
    radius) and its truth (the bare torus segment), as a piece; ValueError when no turn."""
    vertices, faces = torus_segment_mesh(corner, before, after, bend, radius)
    piece = {"truth": Hull(vertices=vertices, faces=faces)}
    clad = max(radius, min(radius + insulation, ELBOW_CLADDING_ROOM * bend))
    if clad > radius:
        vertices, faces = torus_segment_mesh(corner, before, after, bend, clad)
    piece["shape"] = MeshShape(vertices=vertices, faces=faces)
    return piece


def _geometry(reader: _Reader, geo, where, obj_id: str, insulation: float = 0.0) -> list[dict]:
    """Expand one geometry into one or more pieces ``{id, shape, truth, scan?}``; an insulated
    pipe's shape is its cladding, ``insulation`` (metres) outside its truth."""
    kind = geo.get("type")
    if kind not in GEOMETRY_TYPES:
        reader.fail(
            f"{where}.type",
            f"unknown geometry type {kind!r}; use one of " + ", ".join(GEOMETRY_TYPES),
        )
    if kind == "cylinder":
        start = reader.vector(geo, "start", where)
        end = reader.vector(geo, "end", where)
        if np.linalg.norm(end - start) <= 0:
            reader.fail(where, "'start' and 'end' must differ")
        capped = geo.get("capped", True)
        if not isinstance(capped, bool):
            reader.fail(f"{where}.capped", f"must be true or false, not {capped!r}")
        radius = reader.radius(geo, where)
        shape, truth = _cylinder_object(start, end, radius, capped, insulation)
        return [{"shape": shape, "truth": truth}]
    if kind == "tank":
        base = reader.vector(geo, "base", where)
        height = reader.length(geo, "height", where, positive=True, required=True)
        top = base + np.array([0.0, 0.0, height])
        return [
            dict(zip(("shape", "truth"), _cylinder_object(base, top, reader.radius(geo, where))))
        ]
    if kind == "pipe_run":
        return _pipe_run(reader, geo, where, obj_id, insulation)
    if kind == "sphere":
        center = reader.vector(geo, "center", where)
        radius = reader.radius(geo, where)
        return [
            {
                "shape": SphereShape(center=center, radius=radius),
                "truth": Sphere(center=center, radius=radius),
            }
        ]
    if kind == "box":
        center = reader.vector(geo, "center", where)
        size = reader.vector(geo, "size", where)
        if np.any(size <= 0):
            reader.fail(f"{where}.size", "every size must be positive")
        if "axes" in geo:
            axes = _rows(geo["axes"])
            if axes is None or axes.shape != (3, 3) or not np.all(np.isfinite(axes)):
                reader.fail(f"{where}.axes", "must be three [x, y, z] rows")
            norms = np.linalg.norm(axes, axis=1, keepdims=True)
            if not np.all((norms > 0) & np.isfinite(norms)):
                reader.fail(f"{where}.axes", "rows must be non-zero finite vectors")
            axes = axes / norms
            if np.abs(axes @ axes.T - np.eye(3)).max() > 1e-6:
                reader.fail(f"{where}.axes", "rows must be mutually perpendicular")
        else:
            angles = [
                reader.number(geo, k, where, default=0.0)
                for k in ("yaw_deg", "pitch_deg", "roll_deg")
            ]
            axes = rotation_zyx(*angles)
        shape, truth = _box_object(center, axes, size)
        return [{"shape": shape, "truth": truth}]
    if kind == "member":
        start = reader.vector(geo, "start", where)
        end = reader.vector(geo, "end", where)
        length = float(np.linalg.norm(end - start))
        if length <= 0:
            reader.fail(where, "'start' and 'end' must differ")
        section = reader.vector(geo, "section", where, size=2)
        if np.any(section <= 0):
            reader.fail(f"{where}.section", "width and depth must be positive")
        axes = member_axes(start, end, reader.number(geo, "roll_deg", where, default=0.0))
        size = np.array([length, section[0], section[1]])
        shape, truth = _box_object(0.5 * (start + end), axes, size)
        return [{"shape": shape, "truth": truth}]
    if kind == "plate":
        center = reader.vector(geo, "center", where)
        normal = reader.direction(geo, "normal", where)
        up = reader.direction(geo, "up", where, required=False)
        size = reader.vector(geo, "size", where, size=2)
        if np.any(size <= 0):
            reader.fail(f"{where}.size", "width and height must be positive")
        thickness = reader.length(
            geo, "thickness", where, positive=True, default=0.01 / reader.scale
        )
        try:
            axes = plate_axes(normal, up)
        except ValueError as exc:
            reader.fail(f"{where}.up", str(exc))
        box = BoxShape(center=center, axes=axes, size=np.array([size[0], size[1], thickness]))
        face = center + 0.5 * thickness * axes[2]
        half = 0.5 * size
        outline = np.array(
            [
                face + sx * half[0] * axes[0] + sy * half[1] * axes[1]
                for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))
            ]
        )
        return [{"shape": box, "truth": Plane(point=face, normal=axes[2], outline=outline)}]
    if kind == "frustum":
        start = reader.vector(geo, "start", where)
        end = reader.vector(geo, "end", where)
        if np.linalg.norm(end - start) <= 0:
            reader.fail(where, "'start' and 'end' must differ")
        r0 = 0.5 * reader.length(geo, "start_diameter", where, positive=True, required=True)
        r1 = 0.5 * reader.length(geo, "end_diameter", where, positive=True, required=True)
        vertices, faces = frustum_mesh(start, end, r0, r1)
        return [
            {
                "shape": MeshShape(vertices=vertices, faces=faces),
                "truth": Hull(vertices=vertices, faces=faces),
            }
        ]
    if kind == "elbow":
        corner = reader.vector(geo, "corner", where)
        before = reader.vector(geo, "from", where)
        after = reader.vector(geo, "to", where)
        bend = reader.length(geo, "bend_radius", where, positive=True, required=True)
        radius = reader.radius(geo, where)
        try:
            return [_elbow_object(corner, before, after, bend, radius, insulation)]
        except ValueError as exc:
            reader.fail(where, f"{exc}; 'from', 'corner' and 'to' must make a turn")
    if kind == "mesh":
        vertices, faces = _load_mesh(reader, geo, where)
        return [
            {
                "shape": MeshShape(vertices=vertices, faces=faces),
                "truth": Hull(vertices=vertices, faces=faces),
            }
        ]
    # ground: an unbounded plane (floor or far wall) that only catches beams
    point = reader.vector(geo, "point", where, required=False, default=np.zeros(3))
    normal = reader.direction(
        geo, "normal", where, required=False, default=np.array([0.0, 0.0, 1.0])
    )
    return [
        {
            "shape": PlaneShape(point=point, normal=normal),
            "truth": Plane(point=point, normal=normal),
            "scan": False,
            "ground": True,
        }
    ]


def _pipe_run(reader: _Reader, geo, where, obj_id: str, insulation: float = 0.0) -> list[dict]:
    """A polyline pipe: straight cylinders stopping short of each corner by the elbow's
    centre-to-end, plus (unscanned) elbow meshes at the corners; all clad in ``insulation``
    (metres) when given, the truths bare."""
    raw = geo.get("path")
    if not isinstance(raw, list) or len(raw) < 2:
        reader.fail(f"{where}.path", "must be a list of at least 2 points")
    path = np.array([reader.vector({"p": p}, "p", f"{where}.path[{i}]") for i, p in enumerate(raw)])
    radius = reader.radius(geo, where)
    bend = reader.length(
        geo, "bend_radius", where, positive=True, default=3.0 * radius / reader.scale
    )
    ids = geo.get("ids")
    count = len(path) - 1
    if ids is None:
        ids = [f"{obj_id}-{i + 1}" for i in range(count)]
    elif not (
        isinstance(ids, list) and len(ids) == count and all(isinstance(i, str) and i for i in ids)
    ):
        reader.fail(f"{where}.ids", f"must be a list of {count} names, one per straight")
    elbows = geo.get("elbows", True)
    cut = np.zeros((count, 2))
    for k in range(1, count):
        d_in = path[k] - path[k - 1]
        d_out = path[k + 1] - path[k]
        if np.linalg.norm(d_in) == 0 or np.linalg.norm(d_out) == 0:
            reader.fail(f"{where}.path[{k}]", "repeats the previous point")
        c = d_in @ d_out / (np.linalg.norm(d_in) * np.linalg.norm(d_out))
        angle = float(np.arccos(np.clip(c, -1.0, 1.0)))
        if angle > np.radians(179.0):
            reader.fail(f"{where}.path[{k}]", "the run turns back on itself")
        setback = bend * np.tan(angle / 2)
        cut[k - 1, 1] = setback
        cut[k, 0] = setback
    pieces = []
    for k in range(count):
        d = path[k + 1] - path[k]
        length = float(np.linalg.norm(d))
        if length <= 0:
            reader.fail(f"{where}.path[{k + 1}]", "repeats the previous point")
        u = d / length
        if cut[k].sum() >= length - 1e-6:
            reader.fail(
                f"{where}.path[{k + 1}]",
                "straight is shorter than its elbows' centre-to-end; lengthen it or "
                "reduce bend_radius",
            )
        start = path[k] + cut[k, 0] * u
        end = path[k + 1] - cut[k, 1] * u
        shape, truth = _cylinder_object(start, end, radius, insulation=insulation)
        pieces.append({"id": ids[k], "shape": shape, "truth": truth})
    if elbows:
        for k in range(1, count):
            if cut[k, 0] <= 1e-9:
                continue
            elbow = _elbow_object(path[k], path[k - 1], path[k + 1], bend, radius, insulation)
            pieces.append({"id": f"{obj_id}-E{k}", **elbow, "scan": False, "kind": None})
    return pieces


def _insulation(reader: _Reader, data, geo, kind: str | None, where: str) -> float:
    """The object's insulation thickness in metres (0 when absent or null), or a located error:
    a number >= 0, at most the scan format's :data:`~asbuilt.scan.insulation.MAX_INSULATION`, on a
    pipe geometry (:data:`INSULATED_GEOMETRY`) that is scanned, if at all, as a cylinder."""
    thickness = reader.length(data, "insulation", where, minimum=0.0, default=0.0)
    if thickness <= 0:
        return 0.0
    at = f"{where}.insulation"
    if thickness > MAX_INSULATION:
        units = next((k for k, v in UNITS.items() if v == reader.scale), "m")
        reader.fail(
            at,
            f"{thickness / reader.scale:g} {units} is thicker than any pipe insulation (at most "
            f"{MAX_INSULATION / reader.scale:g} {units}); it is in the scene's units ({units}): "
            "check the value and the units",
        )
    kind_of_geometry = geo.get("type")
    if kind_of_geometry in GEOMETRY_TYPES and kind_of_geometry not in INSULATED_GEOMETRY:
        reader.fail(
            at,
            f"insulation wraps a pipe, not geometry type {kind_of_geometry!r}; use it on "
            + ", ".join(INSULATED_GEOMETRY)
            + " or remove it",
        )
    if kind is not None and kind not in INSULATED_KINDS:
        reader.fail(
            at,
            f'the scan carries insulation on a cylinder only, not on kind "{kind}"; give the '
            'object "kind": "cylinder" or remove its insulation',
        )
    return thickness


def _station(reader: _Reader, data, where) -> Station:
    if not isinstance(data, dict):
        reader.fail(where, "must be an object with at least 'position'")
    return Station(
        id=reader.text(data, "id", where, default=None) or where,
        position=reader.vector(data, "position", where),
        range_sigma=reader.length(
            data, "range_sigma", where, minimum=0.0, default=0.002 / reader.scale
        ),
        angular_sigma=math.radians(
            reader.number(data, "angular_sigma_deg", where, minimum=0.0, default=0.01)
        ),
        dropout=reader.number(data, "dropout", where, minimum=0.0, maximum=0.9, default=0.0),
        mixed_return=reader.number(
            data, "mixed_return", where, minimum=0.0, maximum=1.0, default=0.3
        ),
        # a laser beam spreads by 0.2-3 mrad; 200 (11 degrees) is no laser's (the simulated
        # device's half-angle limit, drivers.simrig.MAX_DIVERGENCE, doubled)
        beam_divergence=1e-3
        * reader.number(
            data, "beam_divergence_mrad", where, minimum=0.0, maximum=200.0, default=0.5
        ),
        spot_diameter=reader.length(
            data, "spot_diameter", where, minimum=0.0, default=0.003 / reader.scale
        ),
        max_range=reader.length(
            data, "max_range", where, positive=True, default=100.0 / reader.scale
        ),
    )


def scene_from_dict(doc, *, source: str | None = None, base_dir=None) -> Scene:
    """Validate a parsed scene document and build the :class:`Scene` (metres inside).

    Parameters
    ----------
    doc : dict
        The parsed JSON (see ``docs/scene-format.md``).
    source : str, optional
        File name for messages.
    base_dir : str or Path, optional
        Directory that relative mesh file names are resolved against.
    """
    if not isinstance(doc, dict):
        raise SceneError("the top level must be a JSON object", source=source)
    if doc.get("format", "asbuilt-scene") != "asbuilt-scene":
        raise SceneError(
            f"format is {doc.get('format')!r}, expected 'asbuilt-scene'",
            source=source,
            where="format",
        )
    if doc.get("version", 1) != 1:
        raise SceneError(
            f"version {doc.get('version')!r} is not supported; use 1",
            source=source,
            where="version",
        )
    units = doc.get("units", "m")
    if not isinstance(units, str) or units not in UNITS:
        raise SceneError(
            f"unknown unit {units!r}; use one of " + ", ".join(UNITS), source=source, where="units"
        )
    reader = _Reader(source, UNITS[units], base_dir)

    stations_doc = doc.get("stations")
    if not isinstance(stations_doc, list) or not stations_doc:
        reader.fail("stations", "give a list with at least one station (its 'position')")
    stations = tuple(_station(reader, s, f"stations[{i}]") for i, s in enumerate(stations_doc))
    station_ids = [s.id for s in stations]
    if len(set(station_ids)) != len(station_ids):
        reader.fail("stations", "station ids must be unique")

    default_points = doc.get("points", DEFAULT_POINTS)
    if (
        isinstance(default_points, bool)
        or not isinstance(default_points, int)
        or default_points < 1
    ):
        reader.fail("points", f"must be a positive integer, not {default_points!r}")
    if default_points > MAX_POINTS:
        reader.fail("points", f"must be at most {MAX_POINTS:,} (the most a scan holds)")
    seed = doc.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or seed < 0):
        reader.fail("seed", f"must be a non-negative integer, not {seed!r}")

    objects_doc = doc.get("objects")
    if not isinstance(objects_doc, list) or not objects_doc:
        reader.fail("objects", "give a list with at least one object")
    objects: list[SceneObject] = []
    links: list[tuple[str, str]] = []
    for i, data in enumerate(objects_doc):
        where = f"objects[{i}]"
        if not isinstance(data, dict):
            reader.fail(where, "must be a JSON object")
        obj_id = reader.text(data, "id", where, required=True)
        where = f"objects[{i}] ({obj_id})"
        scan = data.get("scan", True)
        if not isinstance(scan, bool):
            reader.fail(f"{where}.scan", f"must be true or false, not {scan!r}")
        kind = data.get("kind")
        if kind is not None and kind not in KINDS:
            reader.fail(f"{where}.kind", f"unknown kind {kind!r}; use one of " + ", ".join(KINDS))
        if scan and kind is None:
            reader.fail(
                where,
                "missing field 'kind' (the kind the operator says); or set "
                '"scan": false for background geometry',
            )
        geo = data.get("geometry")
        if not isinstance(geo, dict):
            reader.fail(where, "missing field 'geometry' (an object with a 'type')")
        insulation = _insulation(reader, data, geo, kind if scan else None, where)
        pieces = _geometry(reader, geo, f"{where}.geometry", obj_id, insulation)
        if scan and any(p.get("ground") for p in pieces):
            reader.fail(
                f"{where}.scan",
                "an unbounded ground plane cannot be scanned; use a "
                "'plate' geometry or set \"scan\": false",
            )
        points = data.get("points", default_points)
        if isinstance(points, bool) or not isinstance(points, int) or points < 1:
            reader.fail(f"{where}.points", f"must be a positive integer, not {points!r}")
        if points > MAX_POINTS:
            reader.fail(
                f"{where}.points", f"must be at most {MAX_POINTS:,} (the most a scan holds)"
            )
        if scan and points < MIN_POINTS[kind]:
            reader.fail(f"{where}.points", f"a {kind} needs at least {MIN_POINTS[kind]} points")
        station = data.get("station", stations[0].id)
        if station not in station_ids:
            reader.fail(
                f"{where}.station",
                f"unknown station {station!r}; stations are " + ", ".join(station_ids),
            )
        strings = {k: reader.text(data, k, where) for k in ("group", "label", "nominal")}
        scanned_ids = []
        for piece in pieces:
            piece_scan = scan and piece.get("scan", True)
            piece_id = piece.get("id", obj_id)
            objects.append(
                SceneObject(
                    id=piece_id,
                    kind=piece.get("kind", kind),
                    shape=piece["shape"],
                    truth=piece["truth"],
                    points=points,
                    scan=piece_scan,
                    station=station,
                    index=len(objects),
                    insulation=insulation,
                    **strings,
                )
            )
            if piece_scan:
                scanned_ids.append(piece_id)
        links.extend(zip(scanned_ids[:-1], scanned_ids[1:]))
    ids = [o.id for o in objects]
    seen = set()
    for obj in objects:
        if obj.id in seen:
            reader.fail(
                f"objects ({obj.id})",
                "object ids must be unique (pipe runs add '-1', '-2', ... to their id); "
                "rename one of them",
            )
        seen.add(obj.id)
    links_doc = doc.get("links", [])
    if not isinstance(links_doc, list):
        reader.fail("links", "must be a list of [id, id] pairs")
    for k, pair in enumerate(links_doc):
        if not (isinstance(pair, list) and len(pair) == 2):
            reader.fail(f"links[{k}]", f"must be a pair of object ids, not {pair!r}")
        for p in pair:
            if p not in ids:
                reader.fail(f"links[{k}]", f"{p!r} is not the id of an object in the scene")
        links.append((pair[0], pair[1]))
    known = {"format", "version", "units", "name", "seed", "points", "stations", "objects", "links"}
    return Scene(
        units=units,
        stations=stations,
        objects=tuple(objects),
        links=tuple(links),
        name=doc.get("name") if isinstance(doc.get("name"), str) else None,
        seed=seed,
        source=source,
        extra={k: v for k, v in doc.items() if k not in known},
    )
