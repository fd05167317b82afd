"""Everything a report shows, gathered once as plain data (numpy only).

:func:`report_data` reads a :class:`~asbuilt.model.Model` and returns a frozen
:class:`ReportData`: the header (scan name and date, catalog, units, counts, the compliance
summary), the quantity take-off (:mod:`asbuilt.report.takeoff`), the fit quality of every fitted
object and the findings. The HTML, CSV and JSON writers only format it. SI units throughout
(metres, m2, m3, kg); residuals in metres.
"""

from __future__ import annotations

import datetime as _dt
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from asbuilt.findings import SEVERITIES, Finding
from asbuilt.model import Model

from .takeoff import TakeOff, model_catalog, severity_rank, take_off

__all__ = ["FitQuality", "ReportData", "report_data", "fit_quality"]


@dataclass(frozen=True, eq=False)
class FitQuality:
    """How sure the model is of one fitted component.

    Attributes
    ----------
    id, type, kind : str
        Component id and type; the fitted primitive's kind.
    method : str
        The fit's algorithm.
    points, inliers : int
    rms, max_residual, sigma : float, metres
        Inlier RMS and largest absolute inlier residual; the noise level the standard errors
        were scaled by.
    stderr : Mapping[str, float or tuple]
        The fit's standard errors (keys ending ``_deg`` in degrees, the rest metres).
    residuals : ndarray, shape (n,), metres
        Signed orthogonal residuals of every point (for the histogram).
    inlier_mask : ndarray, shape (n,), bool
    size : str or None
        Snapped size label (``"NPS 4"``) when the size was snapped.
    snap_status : str or None
        The merger's ``snap["status"]`` (``"snapped"``, ``"no-size"``, ``"ambiguous"``...).
    od_fit, od_stderr, od_catalog : float or None, metres
        Fitted outside diameter, its standard error, the catalog OD snapped to.
    snap_offset : float or None, metres
        ``od_fit - od_catalog``: how far the fit was from the snapped size.
    snap_sigmas : float or None
        ``|snap_offset| / od_stderr``.
    snap_reason : str or None
    findings : tuple of str
        Codes of the findings naming it.
    severity : str or None
        The worst of them.
    """

    id: str
    type: str
    kind: str
    method: str
    points: int
    inliers: int
    rms: float
    max_residual: float
    sigma: float
    stderr: Mapping
    residuals: np.ndarray
    inlier_mask: np.ndarray
    size: str | None = None
    snap_status: str | None = None
    od_fit: float | None = None
    od_stderr: float | None = None
    od_catalog: float | None = None
    snap_offset: float | None = None
    snap_sigmas: float | None = None
    snap_reason: str | None = None
    findings: tuple[str, ...] = ()
    severity: str | None = None


@dataclass(frozen=True, eq=False)
class ReportData:
    """The content of a report.

    Attributes
    ----------
    model : Model
    title : str
        The scan's name (or the source file's, or ``"as-built model"``).
    source : str or None
        The scan file.
    scan_date : str or None
        The date the scan file records (a top-level ``date``, ``created``, ``scanned`` or
        ``time`` key, or ``acquisition.started``), if any.
    scan_file_modified : str or None
        When the scan file was last modified (ISO 8601 UTC), if it can be read.
    generated : str
        When the report was made, ISO 8601 UTC.
    catalog, catalog_title, units : str or None
    catalog_file : str or None
        The user's catalog file the model was built with (None: a shipped catalog).
    catalog_problem : str or None
        Why the model's catalog could not be read, if it could not (sizes are then shown
        without catalog labels, walls or weights).
    counts : Mapping[str, int]
        Components by type, plus ``"components"``, ``"spools"``, ``"objects"``, ``"points"``.
    severities : Mapping[str, int]
        Findings by severity (every severity present, zeros included) and ``"unverifiable"``.
    takeoff : TakeOff
    quality : tuple of FitQuality
        Fitted components, in the model's order.
    findings : tuple of Finding
        Worst first, then by code and first object.
    """

    model: Model
    title: str
    source: str | None
    scan_date: str | None
    generated: str
    catalog: str | None
    catalog_title: str | None
    units: str
    counts: Mapping[str, int]
    severities: Mapping[str, int]
    takeoff: TakeOff
    quality: tuple[FitQuality, ...]
    findings: tuple[Finding, ...] = field(default_factory=tuple)
    scan_file_modified: str | None = None
    catalog_file: str | None = None
    catalog_problem: str | None = None


def _float(value) -> float | None:
    if value is None:
        return None
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if np.isfinite(number) else None


def fit_quality(model: Model, takeoff: TakeOff | None = None) -> tuple[FitQuality, ...]:
    """Fit quality of every component that comes from a fit (in the model's order).

    Parameters
    ----------
    model : Model
    takeoff : TakeOff, optional
        Its take-off (for size labels and finding codes); computed when not given.
    """
    takeoff = takeoff if takeoff is not None else take_off(model)
    rows = {row.id: row for row in takeoff.rows}
    quality = []
    for comp in model.components:
        fit = comp.fit
        if fit is None:
            continue
        snap = comp.snap if isinstance(comp.snap, Mapping) else {}
        od_fit = _float(snap.get("od_fit"))
        od_catalog = _float(snap.get("od_catalog"))
        od_stderr = _float(snap.get("od_stderr"))
        offset = od_fit - od_catalog if od_fit is not None and od_catalog is not None else None
        sigmas = abs(offset) / od_stderr if offset is not None and od_stderr else None
        row = rows.get(comp.id)
        quality.append(
            FitQuality(
                id=comp.id,
                type=comp.type,
                kind=fit.kind,
                method=fit.method,
                points=fit.n_points,
                inliers=fit.n_inliers,
                rms=fit.rms,
                max_residual=fit.max_residual,
                sigma=float(fit.sigma),
                stderr=dict(fit.stderr),
                residuals=np.asarray(fit.residuals, dtype=np.float64),
                inlier_mask=np.asarray(fit.inliers, dtype=bool),
                size=row.size if row is not None and comp.nominal else None,
                snap_status=snap.get("status"),
                od_fit=od_fit,
                od_stderr=od_stderr,
                od_catalog=od_catalog,
                snap_offset=offset,
                snap_sigmas=sigmas,
                snap_reason=snap.get("reason"),
                findings=row.findings if row is not None else (),
                severity=row.severity if row is not None else None,
            )
        )
    return tuple(quality)


def _scan_date(model: Model) -> str | None:
    if model.scan is None or not isinstance(model.scan.extra, Mapping):
        return None
    extra = model.scan.extra
    for key in ("date", "created", "scanned", "time"):
        if extra.get(key):
            return str(extra[key])
    acquisition = extra.get("acquisition")
    if isinstance(acquisition, Mapping) and acquisition.get("started"):
        return str(acquisition["started"])
    return None


def _iso(stamp: _dt.datetime) -> str:
    utc = stamp.astimezone(_dt.timezone.utc).replace(microsecond=0)
    return utc.isoformat().replace("+00:00", "Z")


def _file_modified(source) -> str | None:
    if not source:
        return None
    try:
        seconds = Path(source).stat().st_mtime
    except OSError:
        return None
    return _iso(_dt.datetime.fromtimestamp(seconds, _dt.timezone.utc))


def _catalog_title(catalog) -> str | None:
    if catalog is None:
        return None
    return f"{catalog.standard} ({catalog.title})" if catalog.standard else catalog.title


def report_data(
    model: Model,
    *,
    density: float | None = None,
    generated: _dt.datetime | None = None,
    catalog=None,
) -> ReportData:
    """Gather what a report shows.

    Parameters
    ----------
    model : Model
        Lengths metres; ``model.findings`` as the rules left them.
    density : float, kg/m3, optional
        Pipe material density (default from the catalog's material, see
        :data:`asbuilt.report.takeoff.DENSITIES`).
    generated : datetime, optional
        The report's time stamp (default now, UTC).
    catalog : Catalog, str or Path, optional
        The catalog the model was built with (default: the model's ``catalog_file``, else the
        shipped catalog its ``catalog`` names; see :func:`~asbuilt.report.takeoff.model_catalog`).
    """
    catalog, catalog_problem = model_catalog(model, catalog)
    takeoff = take_off(model, density=density, catalog=catalog)
    quality = fit_quality(model, takeoff)
    findings = tuple(
        sorted(
            model.findings,
            key=lambda f: (severity_rank(f.severity), f.code, f.objects[:1]),
        )
    )
    severities = {severity: 0 for severity in SEVERITIES}
    for finding in findings:
        severities[finding.severity] += 1
    severities["unverifiable"] = sum(1 for f in findings if f.unverifiable)
    counts = dict(sorted(takeoff.counts.items()))
    counts["components"] = len(model.components)
    counts["spools"] = len(model.spools)
    if model.scan is not None:
        counts["objects"] = len(model.scan.objects)
        counts["points"] = int(sum(len(obj.points) for obj in model.scan.objects))
    source = model.scan.source if model.scan is not None else model.source
    title = model.name or (str(source) if source else "as-built model")
    stamp = generated or _dt.datetime.now(_dt.timezone.utc)
    return ReportData(
        model=model,
        title=title,
        source=None if source is None else str(source),
        scan_date=_scan_date(model),
        generated=_iso(stamp),
        catalog=model.catalog or (catalog.name if catalog is not None else None),
        catalog_title=_catalog_title(catalog),
        catalog_file=model.catalog_file,
        catalog_problem=catalog_problem,
        units=model.units,
        counts=counts,
        severities=severities,
        takeoff=takeoff,
        quality=quality,
        findings=findings,
        scan_file_modified=_file_modified(source),
    )
