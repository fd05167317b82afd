"""Field access for scene documents: one located :class:`~asbuilt.errors.SceneError` per mistake.

:class:`FieldReader` reads numbers, lengths, vectors, directions and strings out of the parsed
JSON of a scene (``docs/scene-format.md``), converting lengths to metres by the scene's unit
factor and refusing anything off a site, so that :mod:`asbuilt.sim.scene` only says which fields
a geometry has.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from asbuilt.errors import SceneError
from asbuilt.scan.load import MAX_COORDINATE_M

__all__ = ["FieldReader"]


class FieldReader:
    """Field access with located errors, converting lengths by the scene's unit factor."""

    def __init__(self, source: str | None, scale: float, base_dir):
        self.source = source
        self.scale = scale
        self.base_dir = Path(base_dir) if base_dir is not None else Path(".")

    def fail(self, where: str, message: str):
        raise SceneError(message, source=self.source, where=where)

    def number(
        self,
        data,
        key,
        where,
        *,
        default=None,
        minimum=None,
        maximum=None,
        positive=False,
        required=False,
    ) -> float:
        if key not in data or data[key] is None:
            if required:
                self.fail(where, f"missing field {key!r}")
            return default
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(f"{where}.{key}", f"must be a number, not {value!r}")
        value = float(value)
        if not math.isfinite(value):
            self.fail(f"{where}.{key}", "must be finite")
        if positive and value <= 0:
            self.fail(f"{where}.{key}", f"must be positive, not {value:g}")
        if minimum is not None and value < minimum:
            self.fail(f"{where}.{key}", f"must be at least {minimum:g}, not {value:g}")
        if maximum is not None and value > maximum:
            self.fail(f"{where}.{key}", f"must be at most {maximum:g}, not {value:g}")
        return value

    def length(self, data, key, where, **kwargs) -> float:
        value = self.number(data, key, where, **kwargs)
        if value is None:
            return None
        self._on_site(np.array([value * self.scale]), f"{where}.{key}")
        return value * self.scale

    def _on_site(self, metres: np.ndarray, where: str) -> None:
        """Refuse lengths beyond any site: their squares would overflow the ray casting."""
        largest = float(np.abs(metres).max()) if metres.size else 0.0
        if largest > MAX_COORDINATE_M:
            self.fail(
                where,
                f"{largest:.3g} m is beyond any site (at most {MAX_COORDINATE_M:g} m); check the "
                'number and the scene\'s "units"',
            )

    def vector(
        self, data, key, where, *, required=True, default=None, length=True, size=3
    ) -> np.ndarray:
        if key not in data or data[key] is None:
            if required:
                self.fail(where, f"missing field {key!r}")
            return default
        value = data[key]
        ok = (
            isinstance(value, list)
            and len(value) == size
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        )
        if not ok:
            self.fail(f"{where}.{key}", f"must be a list of {size} numbers, not {value!r}")
        array = np.array(value, dtype=np.float64)
        if not np.all(np.isfinite(array)):
            self.fail(f"{where}.{key}", "must be finite")
        if not length:
            return array
        self._on_site(array * self.scale, f"{where}.{key}")
        return array * self.scale

    def direction(self, data, key, where, *, required=True, default=None) -> np.ndarray:
        vector = self.vector(data, key, where, required=required, default=None, length=False)
        if vector is None:
            return default
        norm = float(np.linalg.norm(vector))
        if norm == 0.0:
            self.fail(f"{where}.{key}", "must not be the zero vector")
        return vector / norm

    def text(self, data, key, where, *, required=False, default=None) -> str | None:
        if key not in data or data[key] is None:
            if required:
                self.fail(where, f"missing field {key!r}")
            return default
        value = data[key]
        if not isinstance(value, str) or not value.strip():
            self.fail(f"{where}.{key}", f"must be a non-empty string, not {value!r}")
        return value

    def radius(self, data, where) -> float:
        keys = [k for k in ("radius", "diameter", "od") if k in data]
        if len(keys) != 1:
            self.fail(where, "give exactly one of 'radius', 'diameter' or 'od'")
        value = self.length(data, keys[0], where, positive=True, required=True)
        return value if keys[0] == "radius" else 0.5 * value
