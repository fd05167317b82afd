"""What the HTML report's 3-D view loads: a glTF/GLB embedded as a ``data:`` URI, or a link.

Private helper of :mod:`asbuilt.report.html` (which re-exports :func:`gltf_source`,
:class:`StagedGltf` and :data:`GLTF_EMBED_LIMIT`).
"""

from __future__ import annotations

import base64
import json
import os
from dataclasses import dataclass
from pathlib import Path

from asbuilt.errors import ExportError

__all__ = ["GLTF_EMBED_LIMIT", "StagedGltf", "gltf_source"]

#: Largest glTF/GLB file (bytes) embedded in the page for the 3-D view. Base64 makes it a third
#: larger (10 MB -> 13.3 MB of page), still under the 20-25 MB attachment limit of common mail
#: services; the 60-component plant sample's GLB is about 100 kB. Larger files are linked.
GLTF_EMBED_LIMIT = 10_000_000


def _self_contained_gltf(content: bytes) -> bool:
    """True when a ``.gltf`` (JSON) file refers to no other file (buffers and images are data
    URIs), so that it can be embedded on its own."""
    try:
        document = json.loads(content.decode("utf-8"))
    except (UnicodeDecodeError, ValueError):
        return False
    if not isinstance(document, dict):
        return False
    for key in ("buffers", "images"):
        for entry in document.get(key) or ():
            uri = entry.get("uri") if isinstance(entry, dict) else None
            if uri is not None and not str(uri).startswith("data:"):
                return False
    return True


@dataclass(frozen=True)
class StagedGltf:
    """A glTF/GLB written in the same run as the report but not published yet: its content is
    read from ``content`` (the staged temporary file) and a link points at ``published``."""

    content: Path
    published: Path


def gltf_source(gltf, report_path) -> str:
    """What the HTML's 3-D view loads: the glTF file embedded as a ``data:`` URI when it is at
    most :data:`GLTF_EMBED_LIMIT` bytes (a ``.glb``, or a ``.gltf`` that refers to no other
    file), else its path relative to the report. ``http(s):`` and ``data:`` URLs are kept.

    Raises
    ------
    ExportError
        The file does not exist or cannot be read.
    """
    published = None
    if isinstance(gltf, StagedGltf):
        gltf, published = gltf.content, gltf.published
    text = str(gltf)
    if text.startswith(("http://", "https://", "data:")):
        return text
    target = Path(gltf)
    try:
        size = target.stat().st_size
        if not target.is_file():
            raise FileNotFoundError
    except OSError:
        raise ExportError(
            "glTF file for the 3-D view not found; give a .glb or .gltf file that exists "
            "(e.g. written by 'asbuilt model --out model.glb')",
            source=text,
        ) from None
    if size <= GLTF_EMBED_LIMIT:
        try:
            content = target.read_bytes()
        except OSError as exc:
            raise ExportError(f"cannot read the glTF file ({exc.strerror})", source=text) from None
        suffix = Path(published or target).suffix.lower()
        if suffix == ".glb":
            return "data:model/gltf-binary;base64," + base64.b64encode(content).decode("ascii")
        if suffix == ".gltf" and _self_contained_gltf(content):
            return "data:model/gltf+json;base64," + base64.b64encode(content).decode("ascii")
    base = Path(report_path).resolve().parent
    return Path(os.path.relpath(Path(published or target).resolve(), base)).as_posix()
