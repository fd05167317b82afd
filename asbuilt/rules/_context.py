"""What every rule needs: the model, the config, the verdict arithmetic and shared geometry.

The verdict follows the shared-risk scheme of ISO 14253-1 with a resolution floor: a measured
value ``m`` with standard error ``s`` against an allowed maximum ``a`` is a *violation* when
``m - k*s > a``; it is *unverifiable* when ``m > a`` but within ``k*s`` of it, or when ``k*s > a``
(the measurement cannot resolve the tolerance at all); otherwise it *passes*.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from asbuilt.findings import Finding, Suggestion
from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere
from asbuilt.units import note_in_units

from .config import RulesConfig
from .registry import rule

__all__ = [
    "Context",
    "verdict",
    "verdict_min",
    "mm",
    "deg",
    "axis_of",
    "ends_of",
    "centre_of",
    "PIPE_TYPES",
]

#: Component types that are straight pipe runs for the size, slope and joint rules.
PIPE_TYPES = ("pipe", "cylinder", "coupling")


def _spread(stderr: float | None) -> float:
    """A standard error for the verdicts: None or NaN as 0 (exact), +inf kept (unbounded)."""
    if stderr is None or np.isnan(stderr):
        return 0.0
    return float(stderr)


def verdict(measured: float, allowed: float, stderr: float | None, k: float) -> str:
    """``"pass"``, ``"violation"`` or ``"unverifiable"`` for ``measured <= allowed``.

    Parameters
    ----------
    measured, allowed : float
        In one unit; ``allowed`` is the largest compliant value.
    stderr : float or None
        Standard error of ``measured`` (None or NaN is taken as 0: an exact measurement; an
        infinite one, a quantity the scan only bounds, can never be verified).
    k : float
        Coverage factor (2: "exceeds by more than twice its standard error").
    """
    s = _spread(stderr)
    if measured - k * s > allowed:
        return "violation"
    if measured > allowed or k * s > allowed:
        return "unverifiable"
    return "pass"


def verdict_min(measured: float, required: float, stderr: float | None, k: float) -> str:
    """Like :func:`verdict` for a value that must be *at least* ``required`` (e.g. a slope).

    Violation when ``measured + k*s < required``; unverifiable when ``measured < required`` within
    ``k*s``, or when ``k*s > required`` (the measurement cannot tell the required value from 0).
    """
    s = _spread(stderr)
    if measured + k * s < required:
        return "violation"
    if measured < required or k * s > required:
        return "unverifiable"
    return "pass"


def mm(value: float) -> str:
    """A length in metres written in millimetres for messages (``"3.9 mm"``); :meth:`Context.emit`
    tells it in inches or feet when the model's display units are imperial."""
    return f"{value * 1000:.1f} mm"


def deg(value: float) -> str:
    """An angle in degrees for messages."""
    return f"{value:.2f} deg" if value < 1 else f"{value:.1f} deg"


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def axis_of(geometry) -> tuple[np.ndarray, float, np.ndarray] | None:
    """The main axis of a straight geometry: (unit axis (3,), length m, centre (3,) m), or None.

    Straight: start to end; reducer: its run direction and length, centred between its end
    centres (an eccentric reducer's axis steps sideways); cylinder: its axis; cuboid: its longest
    edge direction.
    """
    if isinstance(geometry, Reducer):
        return geometry.direction, geometry.length, 0.5 * (geometry.start + geometry.end)
    if isinstance(geometry, Straight):
        d = geometry.end - geometry.start
        length = float(np.linalg.norm(d))
        return d / length, length, 0.5 * (geometry.start + geometry.end)
    if isinstance(geometry, Cylinder):
        return np.array(geometry.axis), float(geometry.length), np.array(geometry.center)
    if isinstance(geometry, Cuboid):
        i = int(np.argmax(geometry.size))
        return np.array(geometry.axes[i]), float(geometry.size[i]), np.array(geometry.center)
    return None


def ends_of(geometry) -> list[np.ndarray]:
    """Connection points of a piping geometry, each (3,) metres (empty for other kinds)."""
    if isinstance(geometry, (Straight, Reducer, Bend)):
        return [np.array(geometry.start), np.array(geometry.end)]
    if isinstance(geometry, Tee | Cross):
        return [
            np.array(geometry.run_start),
            np.array(geometry.run_end),
            *(np.array(end) for end in geometry.outlets),
        ]
    if isinstance(geometry, Cylinder):
        return [np.array(e) for e in geometry.ends]
    return []


def centre_of(geometry) -> np.ndarray:
    """A representative point of any geometry, shape (3,) metres (for locations and sorting)."""
    if isinstance(geometry, (Straight, Reducer)):
        return 0.5 * (geometry.start + geometry.end)
    if isinstance(geometry, Bend):
        mid = 0.5 * (geometry.start + geometry.end) - geometry.center
        norm = np.linalg.norm(mid)
        if norm == 0:
            return np.array(geometry.center)
        return geometry.center + mid / norm * geometry.bend_radius
    if isinstance(geometry, Tee | Cross):
        return np.array(geometry.center)
    if isinstance(geometry, (Cylinder, Cuboid, Sphere)):
        return np.array(geometry.center)
    if isinstance(geometry, Plane):
        return geometry.outline.mean(axis=0) if len(geometry.outline) else np.array(geometry.point)
    if isinstance(geometry, Hull):
        return geometry.vertices.mean(axis=0)
    raise TypeError(f"unknown geometry {type(geometry).__name__}")


def stderr_value(stderr: Mapping, key: str, index: int | None = None) -> float | None:
    """One standard error from a fit's ``stderr`` mapping (an element of a tuple when indexed)."""
    value = stderr.get(key) if stderr else None
    if value is None:
        return None
    if isinstance(value, (tuple, list, np.ndarray)):
        values = np.asarray(value, dtype=np.float64).ravel()
        if values.size == 0:
            return None
        return float(values[index] if index is not None and index < values.size else values.max())
    return float(value)


@dataclass
class Context:
    """One check run: the model, the config, the design and the catalog (if any)."""

    model: Model
    config: RulesConfig
    design: object = None
    catalog: object = None
    findings: list[Finding] = field(default_factory=list)

    @property
    def k(self) -> float:
        return self.config.k_sigma

    def opt(self, slug: str, name: str):
        return self.config.option(slug, name)

    def general(self, name: str):
        return self.config.general[name]

    @property
    def pipes(self) -> list[Component]:
        return [
            c
            for c in self.model.components
            if c.type in PIPE_TYPES and isinstance(c.geometry, (Straight, Cylinder))
        ]

    def hint(self, component: Component) -> str | None:
        """The operator's size hint of the scan object a component comes from, if any."""
        scan = self.model.scan
        if scan is None:
            return None
        for source in component.sources or (component.id,):
            try:
                nominal = scan.object(source).nominal
            except KeyError:
                continue
            if nominal:
                return nominal
        return None

    def text(self, message: str) -> str:
        """``message`` (lengths written in mm and m) as people read it: its lengths in inches
        and feet when the model's display units are imperial, as the fits' notes
        (:func:`asbuilt.units.note_in_units`); unchanged for metric units."""
        return note_in_units(message, self.model.units)

    def emit(
        self,
        slug: str,
        objects,
        message: str,
        *,
        location=None,
        measured=None,
        allowed=None,
        stderr=None,
        unit: str = "",
        suggestions=(),
        outcome: str = "violation",
        rescan: str = "",
    ) -> None:
        """Record a finding of rule ``slug``; ``outcome`` "violation" or "unverifiable".

        An unverifiable finding is a warning whose message starts ``cannot verify <slug>:`` and
        carries the ``rescan`` advice as a suggestion. The message and the suggestions' texts
        are written with lengths in mm and m; they are told in the model's units (:meth:`text`),
        while ``measured``, ``allowed``, ``stderr`` and the suggestions' changes stay SI.
        """
        if outcome == "pass":
            return
        unverifiable = outcome == "unverifiable"
        if unverifiable and not self.general("report_unverifiable"):
            return
        severity = self.config.severity(slug)
        if unverifiable:
            severity = "warning" if severity == "error" else severity
            message = f"cannot verify {slug}: {message}"
            if rescan:
                suggestions = (Suggestion(rescan), *suggestions)
        r = rule(slug)
        message = self.text(message)
        suggestions = tuple(replace(s, description=self.text(s.description)) for s in suggestions)
        self.findings.append(
            Finding(
                code=r.code,
                slug=r.slug,
                severity=severity,
                objects=tuple(objects),
                message=message,
                location=None if location is None else np.asarray(location, dtype=np.float64),
                measured=None if measured is None else float(measured),
                allowed=None if allowed is None else float(allowed),
                stderr=None if stderr is None or not np.isfinite(stderr) else float(stderr),
                unit=unit,
                suggestions=tuple(suggestions),
                unverifiable=unverifiable,
            )
        )
