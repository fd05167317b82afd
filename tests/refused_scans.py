"""Scans holding objects the fit refuses beside good ones, for the tests of the scan-level fit,
the pipeline and the commands (``fit``, ``model``, ``check``, ``report``).

The refused objects are the independent ray caster's NPS 1 pipe scans of
``tests/fit/thin_pipe_mixed_pixels.json`` (mixed returns strung along their beams; the cylinder
fit refuses them as seen edge-on, ``tests/fit/test_cylinder.py``), each with its own station; the
good objects are the six pipes of ``samples/spool.json`` with its links.
"""

from __future__ import annotations

import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPOOL = ROOT / "samples" / "spool.json"
_THIN = json.loads((ROOT / "tests" / "fit" / "thin_pipe_mixed_pixels.json").read_text())["scans"]


def refused_object(index: int, object_id: str) -> dict:
    """Scan ``index`` of the thin-pipe fixture as a scan object (metres) with its station."""
    scan = _THIN[index]
    return {
        "id": object_id,
        "kind": "cylinder",
        "points": [[c / 1000.0 for c in p] for p in scan["points_mm"]],
        "station": [c / 1000.0 for c in scan["station_mm"]],
    }


def spool_with_refused(count: int = 1, *, good: bool = True, link: bool = False) -> dict:
    """``samples/spool.json`` (or, without ``good``, its header only) with ``count`` refused
    objects X1, X2, ... appended; ``link`` also links P5 to X1."""
    document = json.loads(SPOOL.read_text())
    refused = [refused_object(k, f"X{k + 1}") for k in range(count)]
    if good:
        document["objects"] += refused
        if link:
            document["links"] = [*document.get("links", []), ["P5", "X1"]]
    else:
        document["objects"] = refused
        document.pop("links", None)
    return document


def write(path: Path, document: dict) -> Path:
    """Write ``document`` as JSON to ``path``; return ``path``."""
    path.write_text(json.dumps(document), encoding="utf-8")
    return path
