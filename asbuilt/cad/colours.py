"""One colour table for every output: by component type, overridden by compliance status.

Plain data (no CAD kernel here) so the exporters and reports can share it. Colours are linear
RGBA tuples of floats in 0..1; :func:`hex_colour` and :func:`rgb255` convert for the formats
that want 8-bit values (DXF true colour, HTML).
"""

from __future__ import annotations

from collections.abc import Iterable

__all__ = [
    "KIND_COLOURS",
    "STATUS_COLOURS",
    "STATUS_ORDER",
    "colour_for",
    "component_status",
    "rgb255",
    "hex_colour",
]

RGBA = tuple[float, float, float, float]

#: Colour of each component type (RGBA, 0..1): pipes blue, fittings dark blue, cuboids concrete
#: grey, spheres teal, planes light grey, hulls translucent orange (bounding models, not parts),
#: insulation translucent cladding white (the pipe stays visible inside).
KIND_COLOURS: dict[str, RGBA] = {
    "pipe": (0.16, 0.42, 0.80, 1.0),
    "coupling": (0.16, 0.42, 0.80, 1.0),
    "elbow": (0.07, 0.18, 0.48, 1.0),
    "tee": (0.07, 0.18, 0.48, 1.0),
    "cross": (0.07, 0.18, 0.48, 1.0),
    "reducer": (0.07, 0.18, 0.48, 1.0),
    "cylinder": (0.30, 0.55, 0.85, 1.0),
    "cuboid": (0.60, 0.60, 0.57, 1.0),
    "sphere": (0.18, 0.60, 0.55, 1.0),
    "plane": (0.84, 0.84, 0.82, 1.0),
    "hull": (0.95, 0.55, 0.15, 0.5),
    # not a component type: the insulation parts around insulated components (asbuilt.cad)
    "insulation": (0.85, 0.83, 0.74, 0.35),
}

#: Colour of a component with findings, by its worst severity (info does not recolour).
STATUS_COLOURS: dict[str, RGBA] = {
    "error": (0.86, 0.10, 0.10, 1.0),
    "warning": (1.00, 0.70, 0.00, 1.0),
}

#: Severities from the most to the least serious (same order as ``asbuilt.findings.SEVERITIES``).
STATUS_ORDER = ("error", "warning", "info")

_FALLBACK: RGBA = (0.5, 0.5, 0.5, 1.0)


def colour_for(component_type: str, status: str | None = None) -> RGBA:
    """The RGBA colour (0..1) of a component of ``component_type`` with worst finding ``status``.

    Parameters
    ----------
    component_type : str
        One of ``asbuilt.model.COMPONENT_TYPES``.
    status : {"error", "warning", "info", None}
        The worst severity among the component's findings; errors and warnings recolour it.
    """
    if status in STATUS_COLOURS:
        return STATUS_COLOURS[status]
    return KIND_COLOURS.get(component_type, _FALLBACK)


def component_status(findings: Iterable) -> dict[str, str]:
    """Each object id mentioned by ``findings`` mapped to its worst severity.

    Parameters
    ----------
    findings : iterable of asbuilt.findings.Finding
    """
    rank = {severity: i for i, severity in enumerate(STATUS_ORDER)}
    worst: dict[str, str] = {}
    for finding in findings:
        for object_id in finding.objects:
            current = worst.get(object_id)
            if current is None or rank[finding.severity] < rank[current]:
                worst[object_id] = finding.severity
    return worst


def rgb255(colour: RGBA) -> tuple[int, int, int]:
    """The 8-bit RGB triple of an RGBA colour (alpha dropped)."""
    return tuple(int(round(max(0.0, min(1.0, c)) * 255)) for c in colour[:3])  # type: ignore[return-value]


def hex_colour(colour: RGBA) -> str:
    """``#rrggbb`` for an RGBA colour (alpha dropped)."""
    return "#{:02x}{:02x}{:02x}".format(*rgb255(colour))
