"""Read a triangle mesh file (STL, glTF/GLB, OBJ, PLY...) for the simulator, and check meshes.

trimesh reads the bytes; this module turns whatever a damaged or wrong file makes trimesh do
(many kinds of exception, non-finite vertices it would silently drop, triangles without area)
into one :class:`ValueError` line saying what is wrong and what to do. The callers add the
place: the scene loader names the scene file, object and field, ``simulate-device`` the model.
"""

from __future__ import annotations

import contextlib
import logging
import re
from pathlib import Path

import numpy as np

from asbuilt.scan.load import MAX_COORDINATE_M

__all__ = ["read_mesh_file", "mesh_problem", "MESH_SUFFIXES", "MAX_MESH_BYTES"]

#: Mesh formats the documentation promises (trimesh may read a few more).
MESH_SUFFIXES = (".stl", ".glb", ".gltf", ".obj", ".ply")

#: Bytes: the largest mesh file read. A binary STL of 512 MiB holds about 10 million triangles,
#: which trimesh reads into some 2 GB; a plant model beyond that is better decimated or cut to
#: the objects scanned than loaded for minutes and cast into slowly.
MAX_MESH_BYTES = 512 * 1024 * 1024


def _reason(exc: BaseException) -> str:
    """trimesh's complaint as a short single line."""
    if isinstance(exc, ImportError):
        # trimesh falls back to guessing a text encoding (an optional package) for bytes that
        # are neither the binary format nor UTF-8 text: the file is damaged or not this format
        return "neither a valid binary file nor UTF-8 text"
    text = " ".join(str(exc).split())
    if (
        isinstance(exc, IndexError)
        or "could not be broadcast" in text
        or "setting an array element with a sequence" in text
    ):
        # a reader indexing or stacking records that end early: numpy's words say nothing to
        # the user about the file
        return "damaged or truncated: a record ends early"
    if isinstance(exc, FileNotFoundError):  # a glTF's buffer or an OBJ's material file
        missing = Path(exc.filename).name if exc.filename else text
        return f"a file it refers to is missing: {missing}"
    if isinstance(exc, AssertionError) and not text:  # a reader's own consistency check
        return "damaged or truncated: its parts disagree in length"
    if isinstance(exc, (KeyError, OSError)) or not text:
        text = f"{type(exc).__name__} {text}".strip()
    return text if len(text) <= 160 else text[:157] + "..."


# Files cut short (a copy or download that stopped) that trimesh reads without a word, losing
# triangles: an OBJ face needs 3 corners and a vertex 3 coordinates (a shorter record is dropped),
# and a text PLY stops at the cut whatever count its header declares.
_SHORT_OBJ_RECORD = re.compile(rb"^(f|v)(?:[ \t]+[^ \t\r\n]+){0,2}[ \t]*\r?$", re.MULTILINE)
_PLY_FACE_COUNT = re.compile(rb"^element[ \t]+face[ \t]+(\d+)[ \t]*\r?$", re.MULTILINE)


def _ply_faces_declared(path: Path) -> int | None:
    """The face count a PLY header declares (None without one): a text PLY cut short reads
    fewer faces without a word from trimesh."""
    with path.open("rb") as f:
        head = f.read(65536)
    end = head.find(b"end_header")
    found = _PLY_FACE_COUNT.search(head, 0, end if end >= 0 else len(head))
    return int(found.group(1)) if found else None


def _text_stl_cut(path: Path) -> bool:
    """A text STL (``solid`` first) whose end lacks ``endsolid``: trimesh reads none of it."""
    with path.open("rb") as f:
        head = f.read(5)
        f.seek(max(path.stat().st_size - 4096, 0))
        tail = f.read()
    return head.lower() == b"solid" and b"endsolid" not in tail.lower()


def _obj_problem(data: bytes) -> str | None:
    """A face with fewer than 3 corners or a vertex with fewer than 3 coordinates, or None."""
    short = _SHORT_OBJ_RECORD.search(data)
    if short is None:
        return None
    line = data.count(b"\n", 0, short.start()) + 1
    what = "face" if short.group(1) == b"f" else "vertex"
    needs = "3 corners" if what == "face" else "3 coordinates"
    return (
        f"damaged or truncated: the {what} on line {line} has fewer than {needs}; check the "
        "file or export it again"
    )


@contextlib.contextmanager
def _quiet_trimesh():
    """Keep trimesh's log (warnings with tracebacks on stderr) out of the one-line promise."""
    logger = logging.getLogger("trimesh")
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        logger.setLevel(level)


def read_mesh_file(path, on_site: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The vertices (n, 3) and triangles (m, 3) of a mesh file, as stored (no unit change).

    ``on_site``: the stored numbers are metres, checked against the site limit here; a caller
    that scales them (a scene in mm) passes False and checks the scaled metres itself.

    Raises
    ------
    ValueError
        One line: the file is missing, not a regular file, larger than
        :data:`MAX_MESH_BYTES`, of an unknown format, unreadable,
        or holds no usable triangles (see :func:`mesh_problem`).
    """
    path = Path(path)
    if not path.exists():
        raise ValueError("file not found; check the path")
    if not path.is_file():  # a directory, or a pipe that would block the reader forever
        raise ValueError("not a regular file; give a mesh file (" + ", ".join(MESH_SUFFIXES) + ")")
    size = path.stat().st_size
    if size > MAX_MESH_BYTES:
        raise ValueError(
            f"the file is {size:,} bytes, larger than the {MAX_MESH_BYTES // 2**20} MiB a mesh "
            "may be; decimate the model or export only the objects to scan"
        )
    import trimesh

    suffix = path.suffix.lower()
    if suffix.lstrip(".") not in trimesh.available_formats():
        found = f"'{path.suffix}'" if path.suffix else "no suffix"
        raise ValueError(
            f"unknown mesh format ({found}); give a mesh file (" + ", ".join(MESH_SUFFIXES) + ")"
        )
    if suffix == ".obj":
        problem = _obj_problem(path.read_bytes())
        if problem:
            raise ValueError(problem)
    try:
        # process=False: trimesh's processing drops non-finite vertices silently; check first
        with _quiet_trimesh():
            mesh = trimesh.load(str(path), force="mesh", process=False)
        vertices = np.asarray(getattr(mesh, "vertices", ()), dtype=np.float64)
        faces = np.asarray(getattr(mesh, "faces", ()))
    except Exception as exc:  # trimesh raises many kinds for damaged files
        raise ValueError(
            f"cannot read the file as {suffix[1:].upper()} ({_reason(exc)}); check the file or "
            "export it again"
        ) from None
    if faces.size == 0:
        if suffix == ".stl" and _text_stl_cut(path):
            raise ValueError(
                "damaged or truncated: a text STL without its closing 'endsolid' line; check "
                "the file or export it again"
            )
        raise ValueError("the model holds no triangles; check the file or export it again")
    declared = _ply_faces_declared(path) if suffix == ".ply" else None
    if declared is not None and len(faces) < declared:  # a polygon gives 1+ triangles
        raise ValueError(
            f"damaged or truncated: the header declares {declared} faces, the file holds "
            f"{len(faces)}; check the file or export it again"
        )
    problem = mesh_problem(vertices, faces, on_site)
    if problem:
        raise ValueError(problem)
    with _quiet_trimesh():
        mesh.process()  # merge duplicate vertices, as trimesh does by default
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    problem = mesh_problem(vertices, faces, on_site)  # merging may collapse tiny triangles
    if problem:
        raise ValueError(problem)
    return vertices, faces


def mesh_problem(vertices: np.ndarray, faces: np.ndarray, on_site: bool = True) -> str | None:
    """What makes a mesh unusable for ray casting, or None when it is fine.

    Checks the shapes, that every vertex is finite and (``on_site``: the vertices are metres)
    on a site (at most :data:`~asbuilt.scan.load.MAX_COORDINATE_M` from the origin, or ray
    casting overflows), that the triangles index the vertices and that they enclose some area.
    """
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        return "vertices must be [x, y, z] points; check the file or export it again"
    if faces.ndim != 2 or faces.shape[1] != 3 or not np.issubdtype(faces.dtype, np.integer):
        return "faces must be triangles [i, j, k]; triangulate the model and export it again"
    bad = np.flatnonzero(~np.all(np.isfinite(vertices), axis=1))
    if bad.size:
        return (
            f"vertex {bad[0]} is not finite (NaN or infinity; {bad.size} in all); "
            "fix or export the model again"
        )
    largest = float(np.abs(vertices).max()) if vertices.size else 0.0
    if on_site and largest > MAX_COORDINATE_M:
        return (
            f"a vertex lies {largest:.3g} m from the origin, beyond any site (at most "
            f"{MAX_COORDINATE_M:g} m); check the model's units"
        )
    if faces.min() < 0 or faces.max() >= len(vertices):
        return "faces must index the vertices (0-based); check the file or export it again"
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    if not np.any(np.linalg.norm(np.cross(b - a, c - a), axis=1) > 0):
        return (
            "every triangle has zero area (its corners coincide or lie on a line), so nothing "
            "can be hit; check the file or export it again"
        )
    return None
