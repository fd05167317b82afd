"""A fit read back from a model document's ``fitted`` summary.

The ``asbuilt-model`` document stores what the compliance rules and the QA report read of a
fit: its primitive, standard errors, noise level, counts, RMS, notes, diagnostics and the
per-point signed residuals and inlier flags (``residuals``, ``inlier_mask``, one per given
point in the object's point order). :class:`StoredFit` carries exactly that, with the
attribute names of :class:`asbuilt.fit.result.FitResult`, so that ``asbuilt check`` and
``asbuilt report`` judge a model document as they judge the scan it was made from (the
report's rejected-shot crosses and residual histograms included). ``n_points``,
``n_inliers``, ``rms`` and ``max_residual`` are the stored numbers. A document written before
the per-point data was stored reads back with empty ``residuals`` and ``inliers``: the fit
does not pretend to have the points.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from asbuilt.primitives import Primitive
from asbuilt.scan.load import MAX_COORDINATE_M

__all__ = ["StoredFit", "SummaryFieldError", "stored_fit_from_summary"]

_EMPTY_RESIDUALS = np.zeros(0, dtype=np.float64)
_EMPTY_RESIDUALS.setflags(write=False)
_EMPTY_MASK = np.zeros(0, dtype=bool)
_EMPTY_MASK.setflags(write=False)


@dataclass(frozen=True, eq=False)
class StoredFit:
    """A fit's summary as stored in a model document (duck-types ``FitResult`` for readers).

    Attributes
    ----------
    primitive : Primitive
        The fitted primitive (metres), before merging snapped it.
    stderr : Mapping[str, float or tuple of float]
        Standard errors as the fit gave them (``_deg`` keys degrees, others metres); a value
        the document holds as null (not finite) reads back as ``inf`` (cannot be given).
    sigma : float, metres
        Noise level the standard errors were scaled by (NaN when the document has null).
    sigma_source : str
        ``"sensor"`` or ``"residuals"``.
    method : str
        The fit's algorithm.
    n_points, n_inliers : int
        Number of measured points and of points the robust estimator kept.
    rms, max_residual : float, metres
        RMS and largest absolute inlier residual (NaN when the document has null).
    observed : tuple of bool or None
        Cuboids: whether each size was measured between two seen faces.
    diagnostics : Mapping[str, float]
        Geometry quality numbers (``arc_deg``, ``faces``...; null reads back as NaN).
    notes : tuple of str
        The fit's remarks.
    residuals : ndarray, shape (n,) float64, metres, or shape (0,)
        Signed orthogonal residual of every given point, in the object's point order (NaN
        where the document has null); empty for a document written before they were stored.
    inliers : ndarray, shape (n,) bool, or shape (0,)
        Whether the robust estimator kept each point; empty exactly when ``residuals`` is.
    """

    primitive: Primitive
    stderr: Mapping[str, float | tuple[float, ...]]
    sigma: float
    sigma_source: str
    method: str
    n_points: int
    n_inliers: int
    rms: float
    max_residual: float
    observed: tuple[bool, bool, bool] | None = None
    diagnostics: Mapping[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    residuals: np.ndarray = field(default_factory=lambda: _EMPTY_RESIDUALS)
    inliers: np.ndarray = field(default_factory=lambda: _EMPTY_MASK)
    #: Not stored in the document.
    covariance = None

    @property
    def kind(self) -> str:
        """The fitted primitive's kind."""
        return self.primitive.kind


class SummaryFieldError(ValueError):
    """A model document field with the wrong type, here a ``fitted`` summary's (``key``: which
    one; the message says what it must be); :mod:`asbuilt.export.model_json` raises it for
    the component's other fields too."""

    def __init__(self, key: str, message: str):
        self.key = key
        super().__init__(message)


def describe_value(value) -> str:
    """A JSON value, shortened to 40 characters, for error messages."""
    text = json.dumps(value)  # NaN and Infinity as JSON readers that allow them write them
    return text if len(text) <= 40 else text[:37] + "..."


def summary_float(summary: Mapping, key: str, missing: float = math.nan) -> float:
    """A number of a fit summary; null (not finite when written) or absent reads as ``missing``."""
    value = summary.get(key)
    if value is None:
        return missing
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SummaryFieldError(key, f"must be a number or null, not {describe_value(value)}")
    if math.isfinite(value) and abs(value) > MAX_COORDINATE_M:
        # metres or counts on a site: a larger one is corrupt, and its square would overflow
        raise SummaryFieldError(key, f"must be at most {MAX_COORDINATE_M:g} in size, not {value:g}")
    return float(value)


def _count(summary: Mapping, key: str) -> int:
    value = summary[key]
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise SummaryFieldError(
            key, f"must be a whole number of points, not {describe_value(value)}"
        )
    return value


def _stderr(summary: Mapping) -> dict:
    """Standard errors; a null (a non-finite value when written) reads back as infinity, the
    fits' value for a standard error that cannot be given."""
    value = summary.get("stderr") or {}
    if not isinstance(value, dict):
        raise SummaryFieldError("stderr", f"must be an object, not {describe_value(value)}")
    stderr = {}
    for name, item in value.items():
        try:
            if isinstance(item, list):
                stderr[name] = tuple(summary_float({"v": v}, "v", math.inf) for v in item)
            else:
                stderr[name] = summary_float(value, name, math.inf)
        except SummaryFieldError:
            message = f"must be numbers or null, not {describe_value(item)}"
            raise SummaryFieldError(f"stderr.{name}", message) from None
    return stderr


def _diagnostics(summary: Mapping) -> dict:
    """Diagnostics; numbers as floats, null (not finite when written) as NaN."""
    value = summary.get("diagnostics") or {}
    if not isinstance(value, dict):
        raise SummaryFieldError("diagnostics", f"must be an object, not {describe_value(value)}")
    numeric = (int, float)
    return {
        name: math.nan
        if item is None
        else float(item)
        if isinstance(item, numeric) and not isinstance(item, bool)
        else item
        for name, item in value.items()
    }


def _text(summary: Mapping, key: str, default: str | None = None) -> str:
    value = summary[key] if default is None else summary.get(key, default)
    if not isinstance(value, str):
        raise SummaryFieldError(key, f"must be text, not {describe_value(value)}")
    return value


def _per_point(summary: Mapping, n_points: int, n_inliers: int) -> tuple[np.ndarray, np.ndarray]:
    """The summary's ``residuals`` (metres, null as NaN) and ``inlier_mask``, checked against
    its ``points`` and ``inliers`` counts; empty arrays when the document has neither (written
    before they were stored)."""
    residuals, mask = summary.get("residuals"), summary.get("inlier_mask")
    if residuals is None and mask is None:
        return _EMPTY_RESIDUALS, _EMPTY_MASK
    if residuals is None or mask is None:
        given, absent = (
            ("residuals", "inlier_mask") if mask is None else ("inlier_mask", "residuals")
        )
        raise SummaryFieldError(absent, f"missing while {given} is given; give both or neither")
    if not isinstance(residuals, list) or not all(
        item is None or (isinstance(item, (int, float)) and not isinstance(item, bool))
        for item in residuals
    ):
        message = f"must be a list of numbers or null (metres), not {describe_value(residuals)}"
        raise SummaryFieldError("residuals", message)
    if not isinstance(mask, list) or not all(isinstance(item, bool) for item in mask):
        raise SummaryFieldError(
            "inlier_mask", f"must be a list of true/false, not {describe_value(mask)}"
        )
    for key, values in (("residuals", residuals), ("inlier_mask", mask)):
        if len(values) != n_points:
            raise SummaryFieldError(
                key,
                f"has {len(values)} values but points is {n_points}; give one per measured "
                "point, in the object's point order",
            )
    kept = sum(mask)
    if kept != n_inliers:
        raise SummaryFieldError(
            "inlier_mask", f"marks {kept} points as inliers but inliers is {n_inliers}"
        )
    for index, item in enumerate(residuals):
        if item is not None and math.isfinite(item) and abs(item) > MAX_COORDINATE_M:
            raise SummaryFieldError(
                f"residuals[{index}]",
                f"must be at most {MAX_COORDINATE_M:g} in size (metres), not {item:g}",
            )
    values = np.array([math.nan if item is None else item for item in residuals], np.float64)
    flags = np.array(mask, dtype=bool)
    values.setflags(write=False)
    flags.setflags(write=False)
    return values, flags


def _fitted_sizes(summary: Mapping) -> None:
    """Check the summary's ``radius`` (a number) and ``size`` (3 numbers), metres or null: read
    by tools (the rules read ``primitive``), and numbers of at most 1e8 like the others."""
    summary_float(summary, "radius")
    size = summary.get("size")
    if size is None:
        return
    if not isinstance(size, list) or len(size) != 3:
        raise SummaryFieldError(
            "size", f"must be 3 numbers or null (metres), not {describe_value(size)}"
        )
    for index, item in enumerate(size):
        try:
            summary_float({"v": item}, "v")
        except SummaryFieldError as exc:
            raise SummaryFieldError(f"size[{index}]", str(exc)) from None


def stored_fit_from_summary(summary: Mapping, primitive: Primitive) -> StoredFit:
    """The :class:`StoredFit` of a model document's ``fitted`` summary.

    Parameters
    ----------
    summary : Mapping
        The component's ``fitted`` object as read from JSON (lengths metres, angles degrees).
    primitive : Primitive
        The fitted primitive, already rebuilt by the caller.

    Raises
    ------
    SummaryFieldError
        Naming the field with the wrong type, or ``residuals`` / ``inlier_mask`` whose length
        is not the ``points`` count (or whose flags do not count ``inliers``).
    KeyError
        When ``method``, ``points`` or ``inliers`` is missing.
    """
    observed = summary.get("observed")
    if observed is not None and (
        not isinstance(observed, list) or not all(isinstance(b, bool) for b in observed)
    ):
        message = f"must be a list of true/false, not {describe_value(observed)}"
        raise SummaryFieldError("observed", message)
    notes = summary.get("notes") or []
    if not isinstance(notes, list) or not all(isinstance(n, str) for n in notes):
        raise SummaryFieldError("notes", f"must be a list of text, not {describe_value(notes)}")
    _fitted_sizes(summary)
    n_points, n_inliers = _count(summary, "points"), _count(summary, "inliers")
    residuals, inliers = _per_point(summary, n_points, n_inliers)
    return StoredFit(
        primitive=primitive,
        stderr=_stderr(summary),
        sigma=summary_float(summary, "sigma"),
        sigma_source=_text(summary, "sigma_source", "residuals"),
        method=_text(summary, "method"),
        n_points=n_points,
        n_inliers=n_inliers,
        rms=summary_float(summary, "rms"),
        max_residual=summary_float(summary, "max_residual"),
        observed=None if observed is None else tuple(observed),
        diagnostics=_diagnostics(summary),
        notes=tuple(notes),
        residuals=residuals,
        inliers=inliers,
    )
