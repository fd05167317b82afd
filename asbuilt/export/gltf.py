"""glTF 2.0 export: ``.glb`` (binary) or ``.gltf`` (JSON with the buffer embedded as a data URI).

Written directly from the shared meshes (:meth:`asbuilt.cad.CadModel.mesh`) with numpy: one
node per object named by its id under one node per group under the root, one mesh per object
(positions, unit normals, triangle indices), one material per kind or status colour. glTF
lengths are metres and +Y is up (glTF 2.0 specification, section 3.4), so the scan frame's
(x, y, z) with z up becomes (x, z, -y). Each node's translation is its part's bounding-box
centre, so the float32 vertex data stay precise far from the origin.
"""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path

import numpy as np

from asbuilt import __version__

__all__ = ["write_gltf", "gltf_document", "z_up_to_y_up", "read_glb", "gltf_problem"]

_ARRAY_BUFFER = 34962
_ELEMENT_ARRAY_BUFFER = 34963
_FLOAT = 5126
_UNSIGNED_SHORT = 5123
_UNSIGNED_INT = 5125
_TRIANGLES = 4
#: A binary glTF file's first four bytes, "glTF", as a little-endian uint32.
_GLB_MAGIC = 0x46546C67


def z_up_to_y_up(points: np.ndarray) -> np.ndarray:
    """Scan frame (z up) to glTF frame (y up): (x, y, z) -> (x, z, -y); shape (n, 3) kept."""
    points = np.asarray(points, dtype=np.float64)
    return np.stack([points[..., 0], points[..., 2], -points[..., 1]], axis=-1)


def _srgb_to_linear(channel: float) -> float:
    """glTF's baseColorFactor is linear; the colour table is sRGB (IEC 61966-2-1)."""
    if channel <= 0.04045:
        return channel / 12.92
    return ((channel + 0.055) / 1.055) ** 2.4


class _Buffer:
    def __init__(self) -> None:
        self.chunks: list[bytes] = []
        self.length = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def add(
        self, array: np.ndarray, target: int, component: int, kind: str, bounds: bool = False
    ) -> int:
        data = array.tobytes()
        self.views.append(
            {"buffer": 0, "byteOffset": self.length, "byteLength": len(data), "target": target}
        )
        self.chunks.append(data)
        self.length += len(data)
        pad = (-self.length) % 4
        if pad:
            self.chunks.append(b"\x00" * pad)
            self.length += pad
        accessor = {
            "bufferView": len(self.views) - 1,
            "componentType": component,
            "count": int(array.shape[0]) if kind != "SCALAR" else int(array.size),
            "type": kind,
        }
        if bounds:
            accessor["min"] = [float(v) for v in array.min(axis=0)]
            accessor["max"] = [float(v) for v in array.max(axis=0)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def data(self) -> bytes:
        return b"".join(self.chunks)


def gltf_document(cad) -> tuple[dict, bytes]:
    """The glTF JSON document and its binary buffer for a CAD model.

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
        Meshes in metres, z up.

    Returns
    -------
    (dict, bytes)
        The document (the buffer's ``uri`` not yet set) and the buffer bytes.
    """
    buffer = _Buffer()
    nodes: list[dict] = [{"name": cad.name, "children": []}]
    meshes: list[dict] = []
    materials: list[dict] = []
    material_index: dict[str, int] = {}
    group_names = cad.group_node_names()

    def material_for(part) -> int:
        key = part.status if part.status in ("error", "warning") else part.kind
        if key not in material_index:
            r, g, b, a = part.colour
            material = {
                "name": key,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [
                        _srgb_to_linear(r),
                        _srgb_to_linear(g),
                        _srgb_to_linear(b),
                        float(a),
                    ],
                    "metallicFactor": 0.0,
                    "roughnessFactor": 0.8,
                },
            }
            if a < 1.0:
                material["alphaMode"] = "BLEND"
                material["doubleSided"] = True
            material_index[key] = len(materials)
            materials.append(material)
        return material_index[key]

    def leaf(part) -> int:
        mesh = cad.mesh(part)
        vertices = z_up_to_y_up(mesh.vertices)
        centre = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        positions = (vertices - centre).astype(np.float32)
        normals = z_up_to_y_up(mesh.normals)
        normals = (normals / np.linalg.norm(normals, axis=1)[:, None]).astype(np.float32)
        wide = len(positions) > 65535
        indices = mesh.faces.astype(np.uint32 if wide else np.uint16).reshape(-1)
        attributes = {
            "POSITION": buffer.add(positions, _ARRAY_BUFFER, _FLOAT, "VEC3", bounds=True),
            "NORMAL": buffer.add(normals, _ARRAY_BUFFER, _FLOAT, "VEC3"),
        }
        index_accessor = buffer.add(
            indices, _ELEMENT_ARRAY_BUFFER, _UNSIGNED_INT if wide else _UNSIGNED_SHORT, "SCALAR"
        )
        meshes.append(
            {
                "name": part.id,
                "primitives": [
                    {
                        "attributes": attributes,
                        "indices": index_accessor,
                        "material": material_for(part),
                        "mode": _TRIANGLES,
                    }
                ],
            }
        )
        extras = {"type": part.kind}
        if part.insulation:
            extras["insulates"] = part.component.id
        if part.group is not None:
            extras["group"] = part.group
        if part.status is not None:
            extras["status"] = part.status
        nodes.append(
            {
                "name": part.id,
                "mesh": len(meshes) - 1,
                "translation": [float(c) for c in centre],
                "extras": extras,
            }
        )
        return len(nodes) - 1

    for group, parts in cad.groups().items():
        if group is None:
            nodes[0]["children"].extend(leaf(part) for part in parts)
            continue
        group_node = {"name": group_names[group], "children": [], "extras": {"group": group}}
        nodes.append(group_node)
        nodes[0]["children"].append(len(nodes) - 1)
        group_node["children"].extend(leaf(part) for part in parts)
    if not nodes[0]["children"]:
        del nodes[0]["children"]

    data = buffer.data()
    document = {
        "asset": {"version": "2.0", "generator": f"asbuilt {__version__}"},
        "scene": 0,
        "scenes": [{"name": cad.name, "nodes": [0]}],
        "nodes": nodes,
        "extras": {"units": "m", "up": "+Y", "source_frame": "scan frame, z up"},
    }
    if meshes:
        document.update(
            {
                "meshes": meshes,
                "materials": materials,
                "accessors": buffer.accessors,
                "bufferViews": buffer.views,
                "buffers": [{"byteLength": len(data)}],
            }
        )
    return document, data


def _glb(document: dict, data: bytes) -> bytes:
    text = json.dumps(document, separators=(",", ":")).encode("utf-8")
    text += b" " * ((-len(text)) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
    if data:
        data += b"\x00" * ((-len(data)) % 4)
        chunks += struct.pack("<II", len(data), 0x004E4942) + data
    return struct.pack("<III", _GLB_MAGIC, 2, 12 + len(chunks)) + chunks


def write_gltf(cad, path, *, binary: bool | None = None) -> None:
    """Write the CAD model as glTF 2.0 to ``path``.

    Parameters
    ----------
    cad : asbuilt.cad.CadModel
    path : str or Path
        Written directly; callers stage it for atomicity (:mod:`asbuilt.export`).
    binary : bool, optional
        GLB (True) or JSON with an embedded base64 buffer (False); default from the suffix of
        ``path`` (``.glb`` binary).
    """
    path = Path(path)
    if binary is None:
        binary = path.suffix.lower() == ".glb"
    document, data = gltf_document(cad)
    if binary:
        path.write_bytes(_glb(document, data))
        return
    if data:
        document["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(
            data
        ).decode("ascii")
    path.write_text(json.dumps(document, indent=1), encoding="utf-8")


def read_glb(path) -> tuple[dict, bytes]:
    """The JSON document and binary chunk of a ``.glb`` file (for checks and tests)."""
    raw = Path(path).read_bytes()
    magic, version, length = struct.unpack_from("<III", raw, 0)
    if magic != _GLB_MAGIC or version != 2 or length != len(raw):
        raise ValueError(f"{path}: not a glTF 2.0 binary file")
    json_length, _ = struct.unpack_from("<II", raw, 12)
    document = json.loads(raw[20 : 20 + json_length])
    offset = 20 + json_length
    data = b""
    if offset < len(raw):
        bin_length, _ = struct.unpack_from("<II", raw, offset)
        data = raw[offset + 8 : offset + 8 + bin_length]
    return document, data


def gltf_problem(path: Path) -> str | None:
    """What is wrong with a glTF file a report is to embed (``report --gltf``), or None: a
    ``.glb`` must start with the glTF 2.0 binary header and be as long as it says (an empty,
    truncated or foreign file would be embedded and only fail in the reader's browser); a
    ``.gltf`` must be a JSON object with an ``asset``. The message starts with "file", for
    the caller to name the option before it."""
    try:
        with open(path, "rb") as handle:
            if path.suffix.lower() == ".glb":
                header = handle.read(12)
                size = path.stat().st_size
            else:
                document = json.loads(handle.read().decode("utf-8-sig"))
    except OSError as exc:
        return f"file cannot be read ({exc.strerror})"
    except (ValueError, RecursionError):
        return "file is not glTF JSON (not UTF-8 JSON)"
    if path.suffix.lower() != ".glb":
        if not isinstance(document, dict) or not isinstance(document.get("asset"), dict):
            return 'file is not glTF JSON (no "asset" object)'
        return None
    if len(header) < 12 or int.from_bytes(header[:4], "little") != _GLB_MAGIC:
        return "file is not a glTF binary (it does not start with 'glTF')"
    version = int.from_bytes(header[4:8], "little")
    length = int.from_bytes(header[8:12], "little")
    if version != 2:
        return f"file is glTF version {version}; the viewer reads version 2"
    if length != size:
        return f"file is truncated or padded ({size:,} bytes, its header says {length:,})"
    return None
