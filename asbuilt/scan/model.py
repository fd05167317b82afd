"""The in-memory scan: plain frozen data in metres (loading and validation live in ``load``)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["KINDS", "ScanObject", "Sensor", "Scan", "kind_phrase"]

#: Object kinds a scan may ask for; "auto" lets the software choose among the fitted kinds.
KINDS = ("cylinder", "cuboid", "sphere", "plane", "hull", "auto")


def kind_phrase(kind: str) -> str:
    """``"a cylinder"``, or ``'an object of kind "auto"'``: a kind in a sentence."""
    return 'an object of kind "auto"' if kind == "auto" else f"a {kind}"


@dataclass(frozen=True, eq=False)
class ScanObject:
    """One object the operator pointed at.

    Attributes
    ----------
    id : str
        Unique within the scan.
    kind : str
        One of :data:`KINDS`.
    points : ndarray, shape (n, 3), metres
        Measured points in the scan frame (z up), read-only.
    index : int
        Position in the file's ``objects`` array (for messages: ``objects[3] (P4)``).
    group, label, nominal : str or None
        Spool/assembly name, free text, operator's size hint (e.g. ``4"`` or ``DN100``).
    measurements : ndarray, shape (n, 3), or None
        Raw pan (rad), tilt (rad) and range (m) of each point when the scan came from a device,
        so points can be recomputed after a new calibration.
    station : ndarray, shape (3,), metres, or None
        Where this object was scanned from, when not from the scan's ``sensor.position``.
    insulation : float, metres
        Thickness of the insulation (lagging and its cladding) on a cylinder, 0 for a bare
        one: the points lie on the cladding, the pipe inside is ``2 * insulation`` narrower.
    extra : Mapping
        Unknown keys of the object, kept as they were.
    """

    id: str
    kind: str
    points: np.ndarray
    index: int = 0
    group: str | None = None
    label: str | None = None
    nominal: str | None = None
    measurements: np.ndarray | None = None
    station: np.ndarray | None = None
    insulation: float = 0.0
    extra: Mapping = field(default_factory=dict)

    def viewpoint(self, sensor: Sensor) -> np.ndarray | None:
        """Where the object was seen from, shape (3,) metres: its own station, else the sensor's."""
        return self.station if self.station is not None else sensor.position

    @property
    def where(self) -> str:
        """The object's place in the file for messages, e.g. ``objects[3] (P4)``."""
        return f"objects[{self.index}] ({self.id})"


@dataclass(frozen=True, eq=False)
class Sensor:
    """What the scan says of its sensor: ``position`` shape (3,) metres or None, ``range_sigma`` metres or None."""

    position: np.ndarray | None = None
    range_sigma: float | None = None


@dataclass(frozen=True, eq=False)
class Scan:
    """A loaded ``asbuilt-scan`` document, all lengths converted to metres.

    ``units`` is the unit the file was written in (outputs default to it); ``source`` the file's
    path as given (for messages); ``extra`` the unknown top-level keys, kept and ignored.
    """

    units: str
    objects: tuple[ScanObject, ...]
    links: tuple[tuple[str, str], ...] = ()
    name: str | None = None
    sensor: Sensor = field(default_factory=Sensor)
    source: str | None = None
    extra: Mapping = field(default_factory=dict)

    def object(self, object_id: str) -> ScanObject:
        """The object with this id; KeyError when there is none."""
        for obj in self.objects:
            if obj.id == object_id:
                return obj
        raise KeyError(object_id)
