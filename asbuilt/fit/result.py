"""What every fit returns: a frozen result object (primitive, residuals, inliers, standard errors)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import FitError
from ..primitives import Primitive
from ..scan.model import Scan, ScanObject

__all__ = [
    "FitResult",
    "ObjectFit",
    "FitFailure",
    "FitReport",
    "BACKGROUND_PLANE_SHOTS",
    "BACKGROUND_SHOTS",
    "BACKGROUND_KEYS",
    "NEIGHBOUR_SHOTS",
    "ROTATION_SE_KEYS",
    "ROTATION_CORR_KEYS",
    "rotation_diagnostics",
    "rotation_covariance",
]

#: ``FitResult.diagnostics`` key: the count of shots a fit left out on background planes (a
#: wall, floor or ceiling around the object: :mod:`asbuilt.fit._cylinder_planes`,
#: :mod:`asbuilt.fit._cuboid_planes`).
BACKGROUND_PLANE_SHOTS = "background_plane_shots"

#: ``FitResult.diagnostics`` key: the count of shots a nearest-surface rescue left out as lying
#: behind the object along their beams (:mod:`asbuilt.fit._cylinder_background`,
#: :mod:`asbuilt.fit._sphere_background`, :mod:`asbuilt.fit._cuboid_foreground`) or on one
#: plane behind a pipe seen without a station. Read by the rules only (the ``outliers`` rule
#: does not count these shots): no fit depends on it.
BACKGROUND_SHOTS = "background_shots"

#: Every diagnostics key counting shots told apart as background (disjoint: one rescue each).
BACKGROUND_KEYS = (BACKGROUND_PLANE_SHOTS, BACKGROUND_SHOTS)

#: ``FitResult.diagnostics`` key: the count of a cylinder's shots left out as lying on another
#: object's surface, which that object's own shots fit (:mod:`asbuilt.fit._neighbour_shots`).
#: Read by the rules only (the ``outliers`` rule does not count these shots).
NEIGHBOUR_SHOTS = "neighbour_shots"

#: ``FitResult.diagnostics`` keys of a cuboid: the standard error (degrees) of its rotation
#: about each of its output axes (``Cuboid.axes`` rows 0, 1, 2) ...
ROTATION_SE_KEYS = ("rotation_deg_0", "rotation_deg_1", "rotation_deg_2")
#: ... and the correlations of the rotations about axes 0 and 1, 0 and 2, 1 and 2. With them
#: the rotation's covariance in the axes' frame is known: an axis's direction error (``stderr
#: ["axes_deg"]``) is the rotation about the other two, and its two components (a column's tilt
#: toward each of its other axes) may be known very differently (one seen face measures the tilt
#: across it to a tenth of a degree and the turn in its plane to degrees).
ROTATION_CORR_KEYS = ("rotation_corr_01", "rotation_corr_02", "rotation_corr_12")
_PAIRS = ((0, 1), (0, 2), (1, 2))


def rotation_diagnostics(covariance) -> dict[str, float]:
    """The diagnostics (:data:`ROTATION_SE_KEYS`, :data:`ROTATION_CORR_KEYS`) of a rotation
    covariance (3, 3) in radians^2, expressed in a cuboid's output axes' frame; NaN where it
    is not finite."""
    cov = np.asarray(covariance, dtype=np.float64)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    out = {key: float(np.degrees(v)) for key, v in zip(ROTATION_SE_KEYS, se)}
    for key, (i, j) in zip(ROTATION_CORR_KEYS, _PAIRS):
        scale = se[i] * se[j]
        out[key] = float(np.clip(cov[i, j] / scale, -1.0, 1.0)) if scale > 0 else 0.0
    if not np.isfinite(cov).all():
        out = dict.fromkeys(out, float("nan"))
    return out


def rotation_covariance(diagnostics: Mapping[str, float]) -> np.ndarray | None:
    """The rotation covariance (3, 3), radians^2, in a cuboid's axes' frame, read back from its
    diagnostics (:func:`rotation_diagnostics`); None when they are missing or not finite (a fit
    of another kind, or a model document written before they were stored)."""
    try:
        se = np.radians([float(diagnostics[key]) for key in ROTATION_SE_KEYS])
        corr = [float(diagnostics[key]) for key in ROTATION_CORR_KEYS]
    except (KeyError, TypeError, ValueError):
        return None
    if not (np.isfinite(se).all() and np.isfinite(corr).all()):
        return None
    cov = np.diag(se**2)
    for c, (i, j) in zip(corr, _PAIRS):
        cov[i, j] = cov[j, i] = c * se[i] * se[j]
    return cov


@dataclass(frozen=True, eq=False)
class FitResult:
    """The outcome of fitting one primitive to points.

    Attributes
    ----------
    primitive : Primitive
        The fitted primitive, metres.
    residuals : ndarray, shape (n,), metres
        Signed orthogonal (geometric) distance of *every* input point to the fitted surface.
    inliers : ndarray, shape (n,), bool
        Points kept by the robust estimator; the final estimate uses only these.
    stderr : Mapping[str, float or tuple of float]
        Standard errors of the main parameters from the fit's covariance. Keys ending in ``_deg``
        are angles in degrees; every other key is a length in metres. Cylinder: ``radius``,
        ``axis_deg``, ``center`` (across the axis), ``length``; sphere: ``radius``, ``center``;
        plane: ``normal_deg``, ``offset``; cuboid: ``size`` (3 values), ``axes_deg``, ``center``.
    sigma : float, metres
        Noise level the standard errors were scaled by.
    sigma_source : str
        ``"sensor"`` (the scan's range sigma) or ``"residuals"`` (estimated from the fit).
    method : str
        The algorithm, e.g. ``"normals + geometric Gauss-Newton (Lukacs et al. 1998)"``.
    covariance : ndarray or None
        Covariance of the fit's internal parameters (documented per fit), metres/radians.
    observed : tuple of bool or None
        Cuboids only: whether each size was measured between two seen faces (True) or only
        bounded by the extent of the points (False).
    diagnostics : Mapping[str, float]
        Geometry quality numbers, e.g. ``arc_deg`` (visible arc of a cylinder), ``faces`` (seen
        faces of a cuboid), ``length_over_diameter``.
    notes : tuple of str
        Human-readable remarks (e.g. why ``auto`` chose this kind).
    """

    primitive: Primitive
    residuals: np.ndarray
    inliers: np.ndarray
    stderr: Mapping[str, float | tuple[float, ...]]
    sigma: float
    sigma_source: str
    method: str
    covariance: np.ndarray | None = None
    observed: tuple[bool, bool, bool] | None = None
    diagnostics: Mapping[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    @property
    def kind(self) -> str:
        """The fitted primitive's kind."""
        return self.primitive.kind

    @property
    def n_points(self) -> int:
        return int(self.residuals.shape[0])

    @property
    def n_inliers(self) -> int:
        return int(np.count_nonzero(self.inliers))

    @property
    def rms(self) -> float:
        """Root mean square of the inliers' residuals, metres."""
        kept = self.residuals[self.inliers]
        return float(np.sqrt(np.mean(kept**2))) if kept.size else float("nan")

    @property
    def max_residual(self) -> float:
        """Largest absolute inlier residual, metres."""
        kept = self.residuals[self.inliers]
        return float(np.max(np.abs(kept))) if kept.size else float("nan")


@dataclass(frozen=True, eq=False)
class ObjectFit:
    """A scan object with its fit; ``requested`` is the kind the scan asked for (may be ``auto``)."""

    object: ScanObject
    result: FitResult
    requested: str


@dataclass(frozen=True, eq=False)
class FitFailure:
    """A scan object whose fit was refused: its points define no primitive of its kind.

    ``error`` is the located :class:`~asbuilt.errors.FitError` (``scan.json: objects[2] (P3):
    ...``), whose message says why and what to do (e.g. rescan); the object keeps its
    measured points (``object.points``, shape (n, 3) metres).
    """

    object: ScanObject
    error: FitError

    @property
    def message(self) -> str:
        """The one-line reason, without the file and object it is located at."""
        return self.error.message


@dataclass(frozen=True, eq=False)
class FitReport:
    """Every object's fit, in the scan's order; ``failures`` are the objects whose fit was
    refused (in the scan's order; empty unless :func:`asbuilt.fit.fit` ran with
    ``strict=False``, its default)."""

    scan: Scan
    fits: tuple[ObjectFit, ...]
    failures: tuple[FitFailure, ...] = ()

    def __iter__(self):
        return iter(self.fits)

    def __len__(self) -> int:
        return len(self.fits)

    def get(self, object_id: str, *default):
        """The fit of the object ``object_id``: its own, or the one it was fused into (a second
        station's view of a pipe, ``extra["fused_with"]``). Without one, ``default`` when
        given (as :meth:`dict.get`), else KeyError, saying whether the object's fit was
        refused (see :attr:`failures`) or there is no such object."""
        for item in self.fits:
            if item.object.id == object_id or item.object.extra.get("fused_with") == object_id:
                return item
        if default:
            return default[0]
        for failure in self.failures:
            if failure.object.id == object_id:
                raise KeyError(f"{object_id}: its fit was refused: {failure.message}")
        raise KeyError(f"{object_id}: no object of the scan has this id")
