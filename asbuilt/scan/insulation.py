"""The rules an ``insulation`` thickness obeys, wherever one is given (a scan object, an
acquisition plan's target, a scene): shared so that every reader refuses the same values."""

from __future__ import annotations

import math
from collections.abc import Callable

from asbuilt.units import UNITS

__all__ = ["MAX_INSULATION", "INSULATED_KINDS", "insulation_in_metres"]

#: Thickest insulation an object may carry, metres: pipe lagging tables stop near 150-200 mm
#: and cryogenic or cold-box systems reach about 300 mm, so half a metre of it in a file is a
#: unit slip (50 written with "units": "m" meaning millimetres).
MAX_INSULATION = 0.5

#: The kinds an insulation thickness applies to: its surface is a cylinder's, the thickness is
#: radial.
INSULATED_KINDS = ("cylinder",)


def insulation_in_metres(
    value, kind: str, factor: float, describe: Callable[[object], str] = repr
) -> tuple[float, str | None]:
    """``(thickness in metres, None)`` for a valid thickness ``value`` given in a unit of
    ``factor`` metres (0 when None), else ``(0, the problem in words)``: not a number >= 0,
    thicker than :data:`MAX_INSULATION` (a unit slip), or on a kind not in
    :data:`INSULATED_KINDS`. ``describe`` words a bad value as its reader does."""
    if value is None:
        return 0.0, None
    number = isinstance(value, (int, float)) and not isinstance(value, bool)
    if not number or not math.isfinite(float(value)) or value < 0:
        return 0.0, (
            "must be a number >= 0 (the insulation's thickness in the file's units), "
            f"not {describe(value)}"
        )
    thickness = float(value) * factor
    if thickness > MAX_INSULATION:
        units = next((name for name, f in UNITS.items() if f == factor), "m")
        return 0.0, (
            f"{float(value):g} {units} is thicker than any pipe insulation (at most "
            f"{MAX_INSULATION / factor:g} {units}); it is in the file's units ({units}): "
            "check the value and the units"
        )
    if thickness > 0 and kind not in INSULATED_KINDS:
        return 0.0, (
            f'insulation is a radial thickness on a cylinder, not on kind "{kind}"; give the '
            'object "kind": "cylinder" or remove its insulation'
        )
    return thickness, None
