"""Uncertainty-aware snapping of a fitted outside diameter to a catalog size.

The rule (the users' contract): a size is accepted when the fitted OD is within
``max(3 standard errors, diameter tolerance)`` of the catalog OD and closer to it than to its
neighbours. When no catalog OD lies in that window the pipe keeps its fitted diameter
(``no-size``); when two or more do, the choice is left open (``ambiguous``) with the candidates
listed: a wrong size is worse than an open question. An operator's hint (the scan's
``nominal``) decides between candidates that are all in the window and is flagged when the
window does not contain it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from asbuilt.catalog import Catalog, PipeSize, parse_nominal
from asbuilt.model import Model
from asbuilt.units import IMPERIAL, note_in_units

__all__ = ["SnapResult", "snap_diameter", "STATUSES", "TEXT_FIELDS", "texts_in_units"]

#: Snap statuses: a size chosen from the fit, none in range, two in range, chosen by the hint.
STATUSES = ("snapped", "no-size", "ambiguous", "hint")

#: The ``snap`` fields that are sentences for people (a text or a list of texts); the others
#: are data, in metres.
TEXT_FIELDS = ("reason", "notes", "merge_notes")


@dataclass(frozen=True)
class SnapResult:
    """The outcome of snapping one diameter estimate.

    Attributes
    ----------
    status : str
        One of :data:`STATUSES`.
    od_fit, od_stderr : float
        The estimate and its standard error, metres.
    window : float
        Half-width of the acceptance window, metres: ``max(3 * od_stderr, tolerance)``.
    size : PipeSize or None
        The chosen size (status ``snapped`` or ``hint``).
    candidates : tuple of PipeSize
        Sizes inside the window, nearest first (two or more when ambiguous), or the nearest
        size when none is inside.
    reason : str
        One sentence saying why, for people.
    hint : dict
        Empty without a hint; else ``nominal`` (as given), ``agrees`` (True, False, or None when
        the hint names no size of the catalog), ``od`` (metres, when it names a size).
    """

    status: str
    od_fit: float
    od_stderr: float
    window: float
    size: PipeSize | None = None
    candidates: tuple[PipeSize, ...] = ()
    reason: str = ""
    hint: dict = field(default_factory=dict)

    @property
    def od(self) -> float:
        """The diameter to build with, metres: the catalog OD when a size was chosen."""
        return self.size.od if self.size is not None else self.od_fit

    def as_mapping(self, catalog: Catalog) -> dict:
        """The ``Component.snap`` mapping: status, od_fit, od_stderr, od_catalog, candidates,
        reason, window (metres), and hint when there was one."""
        out = {
            "status": self.status,
            "od_fit": self.od_fit,
            "od_stderr": self.od_stderr if np.isfinite(self.od_stderr) else None,
            "od_catalog": self.size.od if self.size is not None else None,
            "nominal": self.size.nominal if self.size is not None else None,
            "candidates": [{"nominal": c.nominal, "od": c.od} for c in self.candidates],
            "reason": self.reason,
            "window": self.window,
            "catalog": catalog.name,
        }
        if self.hint:
            out["hint"] = dict(self.hint)
        return out


def _mm(value: float) -> str:
    return f"{value * 1000:.1f} mm"


def snap_diameter(
    od_fit: float,
    od_stderr: float,
    catalog: Catalog,
    *,
    tolerance: float,
    hint: str | None = None,
) -> SnapResult:
    """Snap a fitted outside diameter to the catalog, or say why not.

    Parameters
    ----------
    od_fit : float
        Fitted outside diameter, metres (twice the fitted radius, or a joint estimate).
    od_stderr : float
        Its standard error, metres (twice the radius' standard error); NaN or infinite means
        unknown, and then only ``tolerance`` sets the window.
    catalog : Catalog
        A pipe catalog.
    tolerance : float
        The smallest window half-width, metres (``Tolerances.diameter_tolerance``).
    hint : str, optional
        The operator's nominal size (``4"``, ``DN100``...; see
        :func:`asbuilt.catalog.parse_nominal`).

    Returns
    -------
    SnapResult
    """
    se = float(od_stderr) if np.isfinite(od_stderr) else 0.0
    window = max(3.0 * se, float(tolerance))
    distance = {id(s): abs(s.od - od_fit) for s in catalog.sizes}
    ordered = sorted(catalog.sizes, key=lambda s: distance[id(s)])
    inside = tuple(s for s in ordered if distance[id(s)] <= window)
    label = catalog.label

    hint_info: dict = {}
    hinted: PipeSize | None = None
    if hint:
        parsed = parse_nominal(hint)
        hinted = catalog.match_hint(parsed)
        if hinted is None:
            hint_info = {
                "nominal": hint,
                "agrees": None,
                "reason": (
                    f"{hint!r} cannot be read as a nominal size"
                    if parsed is None
                    else f"{hint!r} names no size of catalog {catalog.name}"
                ),
            }
        else:
            agrees = hinted in inside
            hint_info = {"nominal": hint, "agrees": agrees, "od": hinted.od, "size": hinted.nominal}
            if not agrees:
                hint_info["reason"] = (
                    f"hint {label(hinted.nominal)} (OD {_mm(hinted.od)}) is "
                    f"{_mm(abs(hinted.od - od_fit))} from the fitted OD {_mm(od_fit)}, outside "
                    f"the +-{_mm(window)} window"
                )

    if not inside:
        nearest = ordered[:1]
        reason = (
            f"no size of {catalog.name} within +-{_mm(window)} of the fitted OD {_mm(od_fit)}"
            + (
                f" (nearest {label(nearest[0].nominal)}, OD {_mm(nearest[0].od)})"
                if nearest
                else ""
            )
        )
        return SnapResult("no-size", od_fit, se, window, None, tuple(nearest), reason, hint_info)
    if len(inside) == 1:
        size = inside[0]
        reason = (
            f"fitted OD {_mm(od_fit)} +- {_mm(se)} is {_mm(distance[id(size)])} from "
            f"{label(size.nominal)} (OD {_mm(size.od)}), the only size within +-{_mm(window)}"
        )
        return SnapResult("snapped", od_fit, se, window, size, inside, reason, hint_info)
    if hinted is not None and hinted in inside:
        reason = (
            f"{len(inside)} sizes within +-{_mm(window)} of the fitted OD {_mm(od_fit)}; "
            f"the operator's hint chose {label(hinted.nominal)}"
        )
        return SnapResult("hint", od_fit, se, window, hinted, inside, reason, hint_info)
    names = " and ".join(f"{label(s.nominal)} (OD {_mm(s.od)})" for s in inside[:2])
    reason = (
        f"ambiguous: fitted OD {_mm(od_fit)} +- {_mm(se)} is within +-{_mm(window)} of both "
        f"{names}; scan more points or give a nominal hint"
    )
    return SnapResult("ambiguous", od_fit, se, window, None, inside, reason, hint_info)


def texts_in_units(model: Model) -> Model:
    """``model`` with its components' snap sentences (:data:`TEXT_FIELDS`: snap reasons, fitting
    and merge notes, written in mm and m) telling lengths in inches and feet when its display
    units are imperial, as the fits' notes do (:func:`asbuilt.units.note_in_units`); the very
    same model for metric units."""
    if model.units not in IMPERIAL:
        return model

    def told(value):
        if isinstance(value, str):
            return note_in_units(value, model.units)
        return [note_in_units(v, model.units) if isinstance(v, str) else v for v in value]

    components = tuple(
        dataclasses.replace(
            comp,
            snap={
                key: told(value) if key in TEXT_FIELDS and value else value
                for key, value in comp.snap.items()
            },
        )
        if comp.snap
        else comp
        for comp in model.components
    )
    return model.replace(components=components)
