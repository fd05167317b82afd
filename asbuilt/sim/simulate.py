"""Simulate an operator scanning a scene: one raster per object, written as an ``asbuilt-scan``.

Deterministic: the same scene, seed and options give the same document, byte for byte once
serialised (each object draws from its own generator seeded by ``(seed, object index)``, so
adding an object does not change the others' points).
"""

from __future__ import annotations

import json
import math
import re

import numpy as np

from asbuilt.errors import SceneError
from asbuilt.scan.model import KINDS
from asbuilt.sim.scene import Scene
from asbuilt.sim.sensor import scan_object
from asbuilt.tolerances import MIN_POINTS
from asbuilt.units import UNITS

__all__ = ["simulate_scan", "default_decimals", "dumps_scan"]


def default_decimals(units: str) -> int:
    """Decimals that round coordinates in ``units`` to 0.1 mm or finer (m: 4, mm: 1, in: 3)."""
    return max(0, math.ceil(-math.log10(1e-4 / UNITS[units]) - 1e-9))


def _round(values, decimals: int):
    return np.round(np.asarray(values, dtype=np.float64), decimals).tolist()


def simulate_scan(
    scene: Scene,
    *,
    seed: int | None = None,
    points: int | None = None,
    exact: bool = False,
    decimals: int | None = None,
) -> dict:
    """Scan every scannable object of a scene with the simulated pan-tilt range finder.

    Parameters
    ----------
    scene : Scene
        A loaded scene (metres inside).
    seed : int, optional
        Random seed; default the scene's ``seed``, else 0.
    points : int, optional
        Shots wanted per object, overriding every object's ``points``.
    exact : bool
        Thin each object's returns to exactly the wanted count.
    decimals : int, optional
        Decimals kept in the file's units; default 0.1 mm (see :func:`default_decimals`).

    Returns
    -------
    dict
        An ``asbuilt-scan`` version 1 document in the scene's units: ``sensor`` is the first
        station; each object carries ``points`` (n, 3) and ``measurements`` (n, 3) of
        ``[pan_deg, tilt_deg, range]``; an object scanned from another station also carries
        ``"station": [x, y, z]``, an insulated one its ``"insulation"`` thickness.

    Raises
    ------
    SceneError
        An object cannot be scanned from its station (occluded, out of range) or would get
        fewer points than its kind needs.
    """
    if seed is None:
        seed = scene.seed if scene.seed is not None else 0
    if points is not None and points < 1:
        raise SceneError(f"points must be positive, not {points}", source=scene.source)
    decimals = default_decimals(scene.units) if decimals is None else decimals
    scale = UNITS[scene.units]
    main = scene.stations[0]
    objects = []
    for obj in scene.objects:
        if not obj.scan:
            continue
        where = f"objects ({obj.id})"
        station = scene.station(obj.station)
        wanted = obj.points if points is None else points
        rng = np.random.default_rng([int(seed), obj.index])
        try:
            shots = scan_object(
                scene, obj.index, n_points=wanted, station=station, rng=rng, exact=exact
            )
        except ValueError as exc:
            raise SceneError(
                f"{exc} (station {station.id})", source=scene.source, where=where
            ) from None
        need = MIN_POINTS.get(obj.kind, MIN_POINTS["auto"])
        if len(shots) < need:
            raise SceneError(
                f"only {len(shots)} shots landed from station {station.id}, a {obj.kind} needs "
                f"{need}; move the station or raise 'points'",
                source=scene.source,
                where=where,
            )
        entry = {
            "id": obj.id,
            "kind": obj.kind if obj.kind in KINDS else "auto",
            "points": _round(shots.points / scale, decimals),
            "measurements": [
                [round(math.degrees(p), 6), round(math.degrees(t), 6), round(r / scale, decimals)]
                for p, t, r in zip(shots.pan.tolist(), shots.tilt.tolist(), shots.range.tolist())
            ],
        }
        for key in ("group", "label", "nominal"):
            value = getattr(obj, key)
            if value is not None:
                entry[key] = value
        if obj.insulation > 0:  # the cladding was scanned: say how thick, in the file's units
            entry["insulation"] = float(f"{obj.insulation / scale:.6g}")
        if station is not main:
            entry["station"] = _round(station.position / scale, decimals)
        objects.append(entry)
    if not objects:
        raise SceneError(
            'no object to scan (every object has "scan": false)',
            source=scene.source,
            where="objects",
        )
    present = {o["id"] for o in objects}
    links = [[a, b] for a, b in scene.links if a in present and b in present]
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": scene.units,
        "name": scene.name or "simulated scan",
        "sensor": {
            "position": _round(main.position / scale, decimals),
            "range_sigma": float(f"{main.range_sigma / scale:.6g}"),
        },
        "objects": objects,
        "links": links,
        "simulation": {"seed": int(seed), "generator": "asbuilt simulate"},
    }
    return doc


def dumps_scan(doc: dict) -> str:
    """Serialise a scan document as JSON with each point on one line (compact, diff-friendly).

    Parameters
    ----------
    doc : dict
        An ``asbuilt-scan`` document.

    Returns
    -------
    str
        JSON text ending in a newline.
    """
    text = json.dumps(doc, indent=2, ensure_ascii=False)
    text = _NUMBER_LIST.sub(
        lambda m: "[" + ", ".join(p.strip() for p in m.group(1).split(",")) + "]", text
    )
    return text + "\n"


_NUMBER_LIST = re.compile(r"\[\s*((?:-?[0-9][-0-9.eE+]*\s*,\s*)*-?[0-9][-0-9.eE+]*)\s*\]")
