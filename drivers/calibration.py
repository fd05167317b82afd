"""Calibration files and least-squares estimation of the kinematic chain from known targets.

File format (``asbuilt-calibration`` JSON, documented in docs/calibration.md): lengths in metres,
angles in degrees; every section and key is optional (defaults: an ideal unit)::

    {"format": "asbuilt-calibration", "version": 1,
     "pan":  {"sign": 1, "scale": 1.0, "zero_deg": 0.0},
     "tilt": {"sign": 1, "scale": 1.0, "zero_deg": 0.0},
     "tilt_axis": {"offset_m": [0, 0, 0.047], "skew_deg": 0.0},
     "laser": {"offset_m": [0, 0, 0], "beam_horizontal_deg": 0.0, "beam_vertical_deg": 0.0},
     "range": {"offset_m": 0.0, "scale": 1.0},
     "base": {"position_m": [0, 0, 0], "rotation_deg": [0, 0, 0]},
     "estimate": {...}}          # written by asbuilt calibrate: residual, free/fixed, stderr

Estimation (:func:`estimate_calibration`): nonlinear least squares (Levenberg-Marquardt /
trust-region reflective, :func:`scipy.optimize.least_squares`) of the point-to-target residuals
of shots at known targets: planes (signed distance), spheres (distance to the surface) and
surveyed points (3 coordinates). Targets of unknown pose (a flat wall, a ball of known radius
at an unknown place) add nuisance parameters. Which calibration parameters are observable from
the shots is decided before fitting (:func:`observable_parameters`): a greedy Gram-Schmidt pass
over the columns of the Jacobian at the starting point, in a physical priority order, keeps a
parameter only if its column has a component of at least ``min_independence`` (relative)
outside the span of the nuisance columns and the parameters already kept; the others stay
fixed at their starting values and are reported as fixed. Standard errors come from
``s^2 (J^T J)^-1`` at the solution, with ``s^2`` the residual variance.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from asbuilt.atomic import atomic_write
from asbuilt.errors import CalibrationError
from asbuilt.scan.load import MAX_COORDINATE_M

from .calibration_checks import check_reach, correlated_pairs, single_target_parameters
from .kinematics import PARAMETERS, Calibration, forward

__all__ = [
    "load_calibration",
    "loads_calibration",
    "save_calibration",
    "calibration_to_dict",
    "calibration_from_dict",
    "PlaneTarget",
    "SphereTarget",
    "PointTarget",
    "TargetShots",
    "CalibrationResult",
    "PRIORITY",
    "observable_parameters",
    "estimate_calibration",
    "load_targets",
    "file_key",
    "file_value",
]

_SECTIONS = {
    "pan": {"sign", "scale", "zero_deg"},
    "tilt": {"sign", "scale", "zero_deg"},
    "tilt_axis": {"offset_m", "skew_deg"},
    "laser": {"offset_m", "beam_horizontal_deg", "beam_vertical_deg"},
    "range": {"offset_m", "scale"},
    "base": {"position_m", "rotation_deg"},
}
_TOP = {"format", "version", "estimate", "comment", *_SECTIONS}

#: Largest angle a calibration or target field may hold, degrees: a turn either way.
_MAX_DEGREES = 360.0


def _read_json(path: Path, what: str):
    """The JSON document in ``path``; CalibrationError (one line) when it cannot be read."""
    from asbuilt._text import read_text

    source = str(path)
    text = read_text(
        path,
        CalibrationError,
        what=what,
        missing=f"cannot read the {what} (No such file or directory); check the path",
    )
    return _loads(text, source)


def _loads(text: str, source: str | None):
    from asbuilt._text import loads_json

    try:
        return loads_json(text, CalibrationError, source=source)
    except json.JSONDecodeError as exc:
        raise CalibrationError(
            f"not valid JSON (line {exc.lineno}, column {exc.colno}: {exc.msg})", source=source
        ) from None
    except RecursionError:
        raise CalibrationError("not valid JSON (nested too deeply)", source=source) from None


def _in_range(value: float, name: str, source, where: str) -> None:
    """Refuse a finite length beyond any site or an angle beyond a turn, by name."""
    if name.endswith("_deg") and abs(value) > _MAX_DEGREES:
        raise CalibrationError(
            f"{value:g} degrees is more than a turn; use an angle within +-{_MAX_DEGREES:g}",
            source=source,
            where=where,
        )
    if name.endswith("_m") and abs(value) > MAX_COORDINATE_M:
        raise CalibrationError(
            f"{value:.3g} m is beyond any site (at most {MAX_COORDINATE_M:g} m); check the number",
            source=source,
            where=where,
        )


# -- file I/O -----------------------------------------------------------------------------------
def calibration_to_dict(calibration: Calibration, estimate: dict | None = None) -> dict:
    """The JSON document for ``calibration`` (degrees and metres), with an optional estimate."""
    c = calibration
    doc = {
        "format": "asbuilt-calibration",
        "version": 1,
        "pan": {"sign": c.pan_sign, "scale": c.pan_scale, "zero_deg": math.degrees(c.pan_zero)},
        "tilt": {
            "sign": c.tilt_sign,
            "scale": c.tilt_scale,
            "zero_deg": math.degrees(c.tilt_zero),
        },
        "tilt_axis": {
            "offset_m": list(c.tilt_axis_offset),
            "skew_deg": math.degrees(c.tilt_axis_skew),
        },
        "laser": {
            "offset_m": list(c.laser_offset),
            "beam_horizontal_deg": math.degrees(c.beam_horizontal),
            "beam_vertical_deg": math.degrees(c.beam_vertical),
        },
        "range": {"offset_m": c.range_offset, "scale": c.range_scale},
        "base": {
            "position_m": list(c.base_position),
            "rotation_deg": [math.degrees(a) for a in c.base_rotation],
        },
    }
    if estimate:
        doc["estimate"] = estimate
    return doc


def calibration_from_dict(doc, source: str | None = None) -> Calibration:
    """Parse an ``asbuilt-calibration`` document; CalibrationError naming the bad field."""
    if not isinstance(doc, dict):
        raise CalibrationError("the calibration must be a JSON object", source=source)
    if doc.get("format", "asbuilt-calibration") != "asbuilt-calibration":
        raise CalibrationError(
            f"format is {doc.get('format')!r}; expected 'asbuilt-calibration'", source=source
        )
    if doc.get("version", 1) != 1:
        raise CalibrationError(
            f"version {doc.get('version')!r} is not supported; use 1", source=source
        )
    for key in doc:
        if key not in _TOP:
            raise CalibrationError(
                f"unknown key; use one of {', '.join(sorted(_TOP))}", source=source, where=key
            )
    for section, keys in _SECTIONS.items():
        value = doc.get(section, {})
        if not isinstance(value, dict):
            raise CalibrationError("must be an object", source=source, where=section)
        for key in value:
            if key not in keys:
                raise CalibrationError(
                    f"unknown key; use one of {', '.join(sorted(keys))}",
                    source=source,
                    where=f"{section}.{key}",
                )

    def get(section: str, key: str, default):
        value = doc.get(section, {}).get(key, default)
        where = f"{section}.{key}"
        if isinstance(default, list):
            if (
                not isinstance(value, list)
                or len(value) != 3
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
            ):
                raise CalibrationError("must be a list of 3 numbers", source=source, where=where)
            if not all(math.isfinite(v) for v in value):
                raise CalibrationError("must be 3 finite numbers", source=source, where=where)
            for v in value:
                _in_range(float(v), key, source, where)
            return [float(v) for v in value]
        if (
            not isinstance(value, (int, float))
            or isinstance(value, bool)
            or not math.isfinite(value)
        ):
            raise CalibrationError("must be a finite number", source=source, where=where)
        _in_range(float(value), key, source, where)
        return float(value)

    signs = {}
    for axis in ("pan", "tilt"):
        sign = get(axis, "sign", 1)
        if sign not in (1.0, -1.0):
            raise CalibrationError("must be 1 or -1", source=source, where=f"{axis}.sign")
        signs[axis] = int(sign)
    try:
        return Calibration(
            pan_sign=signs["pan"],
            pan_scale=get("pan", "scale", 1.0),
            pan_zero=math.radians(get("pan", "zero_deg", 0.0)),
            tilt_sign=signs["tilt"],
            tilt_scale=get("tilt", "scale", 1.0),
            tilt_zero=math.radians(get("tilt", "zero_deg", 0.0)),
            tilt_axis_offset=tuple(get("tilt_axis", "offset_m", [0.0, 0.0, 0.0])),
            tilt_axis_skew=math.radians(get("tilt_axis", "skew_deg", 0.0)),
            laser_offset=tuple(get("laser", "offset_m", [0.0, 0.0, 0.0])),
            beam_horizontal=math.radians(get("laser", "beam_horizontal_deg", 0.0)),
            beam_vertical=math.radians(get("laser", "beam_vertical_deg", 0.0)),
            range_offset=get("range", "offset_m", 0.0),
            range_scale=get("range", "scale", 1.0),
            base_position=tuple(get("base", "position_m", [0.0, 0.0, 0.0])),
            base_rotation=tuple(math.radians(a) for a in get("base", "rotation_deg", [0.0] * 3)),
        )
    except CalibrationError:
        raise  # a field's own located error (raised by get() inside the call)
    except ValueError as exc:
        raise CalibrationError(str(exc), source=source) from None


def loads_calibration(text: str, source: str | None = None) -> Calibration:
    """Parse calibration JSON text."""
    return calibration_from_dict(_loads(text, source), source)


def load_calibration(path) -> Calibration:
    """Read a calibration file; CalibrationError (one line, names the file) on any problem."""
    path = Path(path)
    return calibration_from_dict(_read_json(path, "calibration file"), str(path))


def save_calibration(calibration: Calibration, path, estimate: dict | None = None) -> None:
    """Write ``calibration`` (and an optional estimate summary) atomically as JSON."""
    with atomic_write(path, "w") as f:
        json.dump(calibration_to_dict(calibration, estimate), f, indent=2)
        f.write("\n")


# -- targets ------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PlaneTarget:
    """A plane ``normal . x = offset`` in the scan frame; ``normal=None`` means pose unknown."""

    normal: tuple[float, float, float] | None = None
    offset: float = 0.0


@dataclass(frozen=True)
class SphereTarget:
    """A sphere of known ``radius`` (m); ``center`` (3,) m in the scan frame or None (unknown)."""

    radius: float
    center: tuple[float, float, float] | None = None


@dataclass(frozen=True)
class PointTarget:
    """A surveyed point (3,) m in the scan frame (e.g. a total-station prism centre)."""

    point: tuple[float, float, float]


@dataclass(frozen=True, eq=False)
class TargetShots:
    """Shots at one target.

    Attributes
    ----------
    name : str
        Target name (the scan object's id).
    target : PlaneTarget, SphereTarget or PointTarget
    pan, tilt : ndarray, shape (n,), radians
        Unit angles of each shot.
    rng : ndarray, shape (n,), metres
        Raw ranges.
    """

    name: str
    target: object
    pan: np.ndarray
    tilt: np.ndarray
    rng: np.ndarray


def _unit_suffix(name: str) -> str:
    """``"_deg"`` for an angle parameter, ``"_m"`` for a length, ``""`` for a scale (ratio)."""
    field_name = name.partition(".")[0]
    if field_name.endswith("scale"):
        return ""
    return "_m" if field_name.endswith(("offset", "position")) else "_deg"


def file_key(name: str) -> str:
    """A parameter's key in a calibration file's ``estimate``, with the file's unit suffix.

    ``pan_zero`` -> ``pan_zero_deg``, ``tilt_axis_offset.z`` -> ``tilt_axis_offset_m.z``,
    ``base_rotation.yaw`` -> ``base_rotation_deg.yaw``, ``range_scale`` -> ``range_scale``
    (version 1 files written before the suffixes held bare names in radians and metres).
    """
    field_name, dot, comp = name.partition(".")
    return f"{field_name}{_unit_suffix(name)}{dot}{comp}"


def file_value(name: str, value: float) -> float:
    """``value`` of parameter ``name`` (radians, metres or ratio) in the file's units."""
    return math.degrees(float(value)) if _unit_suffix(name) == "_deg" else float(value)


@dataclass(frozen=True)
class CalibrationResult:
    """What :func:`estimate_calibration` found.

    Attributes
    ----------
    calibration : Calibration
        The estimate (fixed parameters keep their starting values).
    free, fixed : tuple of str
        Parameter names estimated / held fixed (see :data:`asbuilt.drivers.kinematics.PARAMETERS`).
    stderr : dict of str to float
        Standard error of each free parameter (radians, metres or ratio; :meth:`summary`
        writes them in the file's degrees and metres, under :func:`file_key` names).
    residual_rms, initial_rms : float
        Metres, RMS of the residuals after and before.
    per_target_rms : dict of str to float
        Metres, RMS residual per target.
    n_shots : int
    correlated : tuple of (str, str, float)
        Pairs of free parameters with |correlation| >= 0.95: the targets determine mainly their
        combination (:func:`~asbuilt.drivers.calibration_checks.correlated_pairs`).
    one_target : dict of str to str
        Free parameter -> the target whose known pose alone determines it: an error in that
        pose moves the parameter undetected
        (:func:`~asbuilt.drivers.calibration_checks.single_target_parameters`).
    """

    calibration: Calibration
    free: tuple[str, ...]
    fixed: tuple[str, ...]
    stderr: dict = field(default_factory=dict)
    residual_rms: float = 0.0
    initial_rms: float = 0.0
    per_target_rms: dict = field(default_factory=dict)
    n_shots: int = 0
    correlated: tuple = ()
    one_target: dict = field(default_factory=dict)

    def summary(self) -> dict:
        """JSON-ready summary for the calibration file's ``estimate`` section."""
        return {
            "residual_rms_m": self.residual_rms,
            "initial_rms_m": self.initial_rms,
            "n_shots": self.n_shots,
            "free": list(self.free),
            "fixed": list(self.fixed),
            "stderr": {file_key(k): file_value(k, v) for k, v in self.stderr.items()},
            "per_target_rms_m": {k: float(v) for k, v in self.per_target_rms.items()},
            "correlated": [[a, b, round(rho, 3)] for a, b, rho in self.correlated],
            "one_target": dict(self.one_target),
        }


#: Order in which observable parameters are chosen when several explain the same effect
#: (e.g. the pan zero before the base yaw, the range offset before the lever arm along x).
PRIORITY = (
    "pan_zero",
    "tilt_zero",
    "range_offset",
    "range_scale",
    "tilt_axis_offset.z",
    "laser_offset.z",
    "laser_offset.y",
    "beam_vertical",
    "beam_horizontal",
    "tilt_axis_offset.y",
    "tilt_axis_offset.x",
    "pan_scale",
    "tilt_scale",
    "tilt_axis_skew",
    "laser_offset.x",
    "base_position.x",
    "base_position.y",
    "base_position.z",
    "base_rotation.roll",
    "base_rotation.pitch",
    "base_rotation.yaw",
)


def _unit(v) -> np.ndarray:
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


class _Problem:
    """Residual function over (free calibration parameters, nuisance parameters)."""

    def __init__(self, shots: Sequence[TargetShots], initial: Calibration, free: Sequence[str]):
        self.shots = list(shots)
        self.initial = initial
        self.free = tuple(free)
        self.pan = np.concatenate([np.asarray(s.pan, float) for s in self.shots])
        self.tilt = np.concatenate([np.asarray(s.tilt, float) for s in self.shots])
        self.rng = np.concatenate([np.asarray(s.rng, float) for s in self.shots])
        bounds = np.cumsum([0] + [len(s.pan) for s in self.shots])
        self.slices = [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:])]
        pts0 = forward(initial, self.pan, self.tilt, self.rng)
        self.nuisance0: list[np.ndarray] = []
        self.bases: list = []
        for s, sl in zip(self.shots, self.slices):
            p = pts0[sl]
            t = s.target
            if isinstance(t, PlaneTarget) and t.normal is None:
                centroid = p.mean(axis=0)
                n0 = np.linalg.svd(p - centroid)[2][-1]
                helper = np.eye(3)[np.argmin(np.abs(n0))]
                u = _unit(np.cross(n0, helper))
                self.bases.append((n0, u, np.cross(n0, u)))
                self.nuisance0.append(np.array([0.0, 0.0, float(n0 @ centroid)]))
            elif isinstance(t, SphereTarget) and t.center is None:
                a = np.c_[2 * p, np.ones(len(p))]
                sol = np.linalg.lstsq(a, (p**2).sum(axis=1), rcond=None)[0]
                self.bases.append(None)
                self.nuisance0.append(sol[:3])
            else:
                self.bases.append(None)
                self.nuisance0.append(np.zeros(0))
        self.n_nuisance = sum(len(v) for v in self.nuisance0)

    def x0(self) -> np.ndarray:
        return np.concatenate([self.initial.to_vector(self.free), *self.nuisance0])

    def calibration(self, x: np.ndarray) -> Calibration:
        return self.initial.with_vector(self.free, x[: len(self.free)])

    def residuals(self, x: np.ndarray) -> np.ndarray:
        cal = self.initial.with_vector(self.free, x[: len(self.free)])
        pts = forward(cal, self.pan, self.tilt, self.rng)
        out = []
        k = len(self.free)
        for s, sl, basis, nu0 in zip(self.shots, self.slices, self.bases, self.nuisance0):
            p = pts[sl]
            nu = x[k : k + len(nu0)]
            k += len(nu0)
            t = s.target
            if isinstance(t, PlaneTarget):
                if t.normal is None:
                    n0, u, v = basis
                    n = _unit(n0 + nu[0] * u + nu[1] * v)
                    out.append(p @ n - nu[2])
                else:
                    out.append(p @ _unit(t.normal) - t.offset)
            elif isinstance(t, SphereTarget):
                c = nu if t.center is None else np.asarray(t.center, float)
                out.append(np.linalg.norm(p - c, axis=1) - t.radius)
            elif isinstance(t, PointTarget):
                out.append((p - np.asarray(t.point, float)).ravel())
            else:
                raise CalibrationError(f"target {s.name!r}: unknown target type {type(t).__name__}")
        return np.concatenate(out)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """Central differences; steps 1e-6 (radians, metres, ratios alike)."""
        h = 1e-6
        cols = []
        for i in range(len(x)):
            xp, xm = x.copy(), x.copy()
            xp[i] += h
            xm[i] -= h
            cols.append((self.residuals(xp) - self.residuals(xm)) / (2 * h))
        return np.stack(cols, axis=1)


def observable_parameters(
    shots: Sequence[TargetShots],
    initial: Calibration,
    candidates: Sequence[str] = PRIORITY,
    min_independence: float = 1e-3,
) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Split ``candidates`` into parameters the shots determine and ones to hold fixed.

    Greedy Gram-Schmidt on the Jacobian columns at ``initial`` (nuisance columns first, then
    candidates in the given priority order): a parameter is kept when the norm of its column
    after projecting out everything kept so far is at least ``min_independence`` times the
    column's own norm.

    Returns
    -------
    free, fixed : tuple of str
    """
    candidates = tuple(candidates)
    problem = _Problem(shots, initial, candidates)
    jac = problem.jacobian(problem.x0())
    basis: list[np.ndarray] = []

    def residual_part(col: np.ndarray) -> np.ndarray:
        for q in basis:
            col = col - (q @ col) * q
        for q in basis:  # second pass for numerical orthogonality
            col = col - (q @ col) * q
        return col

    for j in range(len(candidates), jac.shape[1]):  # nuisance columns are always free
        col = residual_part(jac[:, j])
        if np.linalg.norm(col) > 1e-12:
            basis.append(col / np.linalg.norm(col))
    free, fixed = [], []
    for j, name in enumerate(candidates):
        col = jac[:, j]
        norm = np.linalg.norm(col)
        rest = residual_part(col)
        if norm > 0 and np.linalg.norm(rest) >= min_independence * norm:
            basis.append(rest / np.linalg.norm(rest))
            free.append(name)
        else:
            fixed.append(name)
    return tuple(free), tuple(fixed)


def estimate_calibration(
    shots: Sequence[TargetShots],
    initial: Calibration | None = None,
    *,
    free: Sequence[str] | None = None,
    fixed: Sequence[str] = (),
    min_independence: float = 1e-3,
    loss: str = "linear",
) -> CalibrationResult:
    """Estimate the calibration from shots at known targets (nonlinear least squares).

    Parameters
    ----------
    shots : sequence of TargetShots
        Unit angles (rad) and raw ranges (m) per target.
    initial : Calibration, optional
        Starting point; its signs are kept (they are discrete: set them in the file).
    free : sequence of str, optional
        Parameters to estimate (default: those :func:`observable_parameters` finds).
    fixed : sequence of str
        Parameters never estimated (e.g. a surveyed base pose).
    min_independence : float
        Observability threshold for the automatic choice.
    loss : str
        :func:`scipy.optimize.least_squares` loss (``"soft_l1"`` resists stray shots).

    Returns
    -------
    CalibrationResult

    Raises
    ------
    CalibrationError
        Too few shots, unknown parameter names, no parameter observable, or targets the shots
        cannot fit (the estimate fails, or moves the instrument beyond the shots' reach:
        :func:`~asbuilt.drivers.calibration_checks.check_reach`).
    """
    from scipy.optimize import least_squares

    initial = initial or Calibration()
    shots = [s for s in shots if len(s.pan)]
    n_shots = sum(len(s.pan) for s in shots)
    if n_shots < 6:
        raise CalibrationError(f"only {n_shots} shots at targets; take at least a few dozen")
    unknown = [n for n in [*(free or ()), *fixed] if n not in PARAMETERS]
    if unknown:
        raise CalibrationError(
            f"unknown parameter {unknown[0]!r}; use names from: {', '.join(PARAMETERS)}"
        )
    candidates = [n for n in (free or PRIORITY) if n not in set(fixed)]
    try:
        if free is None:
            chosen, _ = observable_parameters(shots, initial, candidates, min_independence)
        else:
            chosen = tuple(candidates)
        if not chosen:
            raise CalibrationError("no calibration parameter is observable from these targets")
        problem = _Problem(shots, initial, chosen)
        x0 = problem.x0()
        r0 = problem.residuals(x0)
        sol = least_squares(problem.residuals, x0, method="trf", loss=loss, x_scale="jac")
        res = problem.residuals(sol.x)
        problem.calibration(sol.x)
        jac = problem.jacobian(sol.x)
    except CalibrationError:
        raise
    except ValueError as exc:
        # A parameter left its valid range (a scale through zero, a non-finite offset) or the
        # residuals are not finite: the targets and the shots cannot be reconciled.
        raise CalibrationError(
            f"the estimate failed ({exc}); the targets do not fit these shots: check each "
            "target's numbers, that the scan's objects are the targets named, and the initial "
            "calibration"
        ) from None
    calibration = problem.calibration(sol.x)
    check_reach(shots, initial, calibration, _per_target(shots, r0))
    dof = max(len(res) - len(sol.x), 1)
    s2 = float(res @ res) / dof
    try:
        cov = np.linalg.pinv(jac.T @ jac) * s2
        err = np.sqrt(np.clip(np.diag(cov), 0, None))
    except np.linalg.LinAlgError:
        cov, err = None, np.full(len(sol.x), np.nan)
    return CalibrationResult(
        calibration=calibration,
        free=chosen,
        fixed=tuple(n for n in PRIORITY if n not in chosen),
        stderr={name: float(e) for name, e in zip(chosen, err)},
        residual_rms=float(np.sqrt(np.mean(res**2))),
        initial_rms=float(np.sqrt(np.mean(r0**2))),
        per_target_rms=_per_target(shots, res),
        n_shots=n_shots,
        correlated=tuple(correlated_pairs(chosen, cov)) if cov is not None else (),
        one_target=single_target_parameters(shots, calibration, chosen, min_independence),
    )


def _per_target(shots: Sequence[TargetShots], res: np.ndarray) -> dict[str, float]:
    """RMS of ``res`` (m) over each target's shots, by target name."""
    out = {}
    k = 0
    for s in shots:
        m = len(s.pan) * (3 if isinstance(s.target, PointTarget) else 1)
        out[s.name] = float(np.sqrt(np.mean(res[k : k + m] ** 2)))
        k += m
    return out


def _vec(value, source, where) -> tuple[float, float, float]:
    if (
        not isinstance(value, list)
        or len(value) != 3
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ):
        raise CalibrationError("must be a list of 3 numbers (metres)", source=source, where=where)
    if not all(math.isfinite(v) for v in value):
        raise CalibrationError("must be 3 finite numbers (metres)", source=source, where=where)
    for v in value:
        _in_range(float(v), "_m", source, where)
    return tuple(float(v) for v in value)


def load_targets(path) -> dict[str, object]:
    """Read a targets file: object id -> PlaneTarget / SphereTarget / PointTarget.

    Format (metres, scan frame)::

        {"format": "asbuilt-targets", "version": 1, "targets": {
           "floor": {"type": "plane", "normal": [0, 0, 1], "offset": 0.0},
           "wall":  {"type": "plane"},                       # flat, pose unknown
           "ball":  {"type": "sphere", "radius": 0.1, "center": [3, 0, 1]},
           "prism": {"type": "point", "point": [4, 1, 0.5]}}}
    """
    path = Path(path)
    source = str(path)
    doc = _read_json(path, "targets file")
    targets = doc.get("targets") if isinstance(doc, dict) else None
    if not isinstance(targets, dict) or not targets:
        kind = doc.get("format") if isinstance(doc, dict) else None
        what = (
            f"is an {kind} file, not targets; "
            if isinstance(kind, str) and kind != "asbuilt-targets"
            else ""
        )
        raise CalibrationError(
            f"{what}needs a non-empty 'targets' object naming the known targets (an "
            "asbuilt-targets file, see docs/calibration.md)",
            source=source,
        )
    out: dict[str, object] = {}
    for name, spec in targets.items():
        where = f"targets.{name}"
        if not isinstance(spec, dict):
            raise CalibrationError("must be an object", source=source, where=where)
        kind = spec.get("type")
        if kind == "plane":
            if "normal" in spec:
                normal = _vec(spec["normal"], source, f"{where}.normal")
                if np.linalg.norm(normal) == 0:
                    raise CalibrationError(
                        "must not be zero", source=source, where=f"{where}.normal"
                    )
                offset = spec.get("offset", 0.0)
                if (
                    not isinstance(offset, (int, float))
                    or isinstance(offset, bool)
                    or not math.isfinite(offset)
                ):
                    raise CalibrationError(
                        "must be a finite number (metres)", source=source, where=f"{where}.offset"
                    )
                _in_range(float(offset), "_m", source, f"{where}.offset")
                scale = float(np.linalg.norm(normal))
                out[name] = PlaneTarget(tuple(np.asarray(normal) / scale), float(offset) / scale)
            else:
                out[name] = PlaneTarget()
        elif kind == "sphere":
            radius = spec.get("radius")
            if (
                not isinstance(radius, (int, float))
                or isinstance(radius, bool)
                or not math.isfinite(radius)
                or radius <= 0
            ):
                raise CalibrationError(
                    "must be a positive number (metres)", source=source, where=f"{where}.radius"
                )
            _in_range(float(radius), "_m", source, f"{where}.radius")
            center = _vec(spec["center"], source, f"{where}.center") if "center" in spec else None
            out[name] = SphereTarget(float(radius), center)
        elif kind == "point":
            out[name] = PointTarget(_vec(spec.get("point"), source, f"{where}.point"))
        else:
            raise CalibrationError(
                f"type is {kind!r}; use plane, sphere or point",
                source=source,
                where=f"{where}.type",
            )
    return out
