"""Design comparison rules: design-deviation, missing-component, extra-component.

Matching is :func:`asbuilt.design.match_design`. Each designed pipe's ``nominal`` (``"6"``,
``6"``, ``NPS 6``, ``DN150``...) is first read as a size of the model's catalog
(:meth:`SizeTable.find`; the default catalog when the model names none): one that names no size
of it is a :class:`~asbuilt.errors.DesignError` naming the file and the entry. For each matched
pair: pipes are checked for size (the as-built catalog size against the designed one), length
(PFI ES-3 spool length tolerance by NPS, a DN size mapped to NPS through the catalog's ``nps``
column; a pipe with a free end, where the scan stopped short, only for being too long), position (largest distance of the as-built ends from the designed axis line) and direction;
columns for position (the axis's plan offset at the designed base height) and section (ACI 117,
+10 / -6 mm); boxes for centre position and edge sizes. Standard errors come from the fit.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from asbuilt.catalog import DEFAULT_CATALOG, parse_nominal
from asbuilt.design import built_axis, match_design
from asbuilt.errors import DesignError
from asbuilt.findings import Suggestion
from asbuilt.model import Straight
from asbuilt.primitives import Cuboid, Cylinder

from ._catalog import SizeTable, size_table
from ._context import Context, centre_of, deg, ends_of, mm, stderr_value, verdict
from .alignment import axis_stderr_deg

__all__ = ["CHECKS"]


def _table(ctx: Context) -> SizeTable:
    """The model's catalog sizes; the default catalog's when the model names none."""
    return ctx.catalog if ctx.catalog is not None else size_table(DEFAULT_CATALOG)


def _designed_sizes(ctx: Context, table: SizeTable) -> dict[str, str]:
    """Designed pipe id to the catalog nominal its ``nominal`` names (pipes with one).

    Raises
    ------
    DesignError
        A designed size names no size of the catalog (file, entry, and what to write instead).
    """
    sizes = {}
    for designed in ctx.design.components:
        if designed.kind != "pipe" or not designed.nominal:
            continue
        found = table.find(designed.nominal)
        if found is None:
            first, last = table.sizes[0][0], table.sizes[-1][0]
            raise DesignError(
                f"{designed.nominal!r} is no size of the catalog ({table.standard}, "
                f"{table.label(first)} to {table.label(last)}); write one of its sizes, or "
                "give the catalog the pipes come from with --catalog",
                source=getattr(ctx.design, "source", None),
                where=f"{designed.where or designed.id}.nominal",
            )
        sizes[designed.id] = found
    return sizes


def _size_text(table: SizeTable, nominal: str, written: str | None = None) -> str:
    """``DN 150`` for a catalog nominal, plus the designed text when written in the other
    system (``DN 150 (6")``), so the reader sees both."""
    label = table.label(nominal)
    hint = parse_nominal(written) if written else None
    dn_table = table.designation.upper() == "DN"
    if hint is not None and (hint.system == "dn") != dn_table and hint.system != "number":
        return f"{label} ({written})"
    return label


def _length_tolerance(ctx: Context, table: SizeTable, nominal: str | None) -> tuple[float, str]:
    """PFI ES-3 spool length tolerance (metres) of catalog size ``nominal``, and its wording."""
    rows = ctx.opt("design-deviation", "length_tolerance")
    nps = table.nps_of(nominal) if nominal else None
    if nps is None:
        return float(rows[0][1]), "PFI ES-3, size unknown"
    label = table.label(nominal)
    if table.designation.upper() != "NPS":
        label += f" = NPS {_inches(nps)}"
    for limit, tol in rows:
        if nps <= limit:
            return float(tol), f"PFI ES-3, {label}"
    return float(ctx.opt("design-deviation", "length_tolerance_above")), f"PFI ES-3, {label}"


def _inches(nps: float) -> str:
    """An NPS value written as a mixed fraction (``1 1/2``, ``6``)."""
    whole, frac = divmod(Fraction(nps).limit_denominator(16), 1)
    if not frac:
        return str(whole)
    return f"{whole} {frac}" if whole else str(frac)


def _ends(geometry):
    if isinstance(geometry, Straight):
        return np.array(geometry.start), np.array(geometry.end)
    if isinstance(geometry, Cylinder):
        return tuple(np.array(e) for e in geometry.ends)
    if isinstance(geometry, Cuboid):
        i = int(np.argmax(geometry.size))
        half = 0.5 * geometry.size[i] * geometry.axes[i]
        return geometry.center - half, geometry.center + half
    return None


def _both_ends_joined(ctx: Context, comp) -> bool:
    """Whether both ends of a pipe meet another component (a fitting or a joint).

    A free end is where the scan stopped, short of the real end (shots near an edge miss or
    are rejected), so a pipe with a free end can only be checked for being too long.
    """
    touch = float(ctx.opt("clash", "touch_distance"))
    others = [e for c in ctx.model.components if c.id != comp.id for e in ends_of(c.geometry)]
    if not others:
        return False
    others = np.asarray(others)
    return all(
        np.min(np.linalg.norm(others - end, axis=1)) <= touch for end in ends_of(comp.geometry)
    )


def _length_stderr(ctx: Context, comp) -> float | None:
    """Standard error of a pipe's length, metres.

    A merged pipe (in a spool) ends where its fittings are, placed by the neighbouring axes: each
    end is known to about the fit's centre standard error, so the length to ``sqrt(2)`` times it.
    An end at a reducer is not placed by any axis: merging centres the reducer on the gap between
    the two pipes' last shots, extending each pipe by ``e`` (its ``extended at`` correction), so
    the end lies anywhere within +-``e`` of where it is drawn; that adds ``e / sqrt(3)`` (the
    standard deviation of a uniform spread over ``2 e``) to the end's error.
    A free pipe's length is its scanned extent: the fit's ``stderr["length"]``.
    """
    fit = comp.fit
    if fit is None:
        return None
    centre = stderr_value(fit.stderr, "center")
    if comp.spool is not None and centre is not None:
        variance = 2.0 * centre**2
        for slack in _reducer_end_slack(ctx, comp):
            variance += slack**2 / 3.0
        return float(np.sqrt(variance))
    return stderr_value(fit.stderr, "length")


def _reducer_end_slack(ctx: Context, comp) -> list[float]:
    """For each end of ``comp`` at a reducer, how far merging extended it there (metres)."""
    touch = float(ctx.opt("clash", "touch_distance"))
    reducer_ends = [
        end
        for other in ctx.model.components
        if other.type == "reducer" and other.id != comp.id
        for end in ends_of(other.geometry)
    ]
    if not reducer_ends:
        return []
    reducer_ends = np.asarray(reducer_ends)
    slack = []
    for correction in comp.corrections:
        if not correction.what.startswith("extended at") or correction.after is None:
            continue
        end = np.asarray(correction.after, dtype=float)
        if end.shape == (3,) and np.min(np.linalg.norm(reducer_ends - end, axis=1)) <= touch:
            slack.append(float(np.linalg.norm(end - np.asarray(correction.before, dtype=float))))
    return slack


def _line_distance(points, start, axis) -> float:
    rel = np.asarray(points) - start
    return float(np.max(np.linalg.norm(rel - np.outer(rel @ axis, axis), axis=1)))


def _emit(
    ctx,
    comp,
    designed,
    aspect,
    measured_text,
    measured,
    allowed,
    se,
    unit,
    standard,
    outcome,
    suggestion=None,
):
    # An unverifiable one may be within the tolerance: it is not known to deviate.
    verb = "cannot be told from" if outcome == "unverifiable" else "deviates from"
    known = f" (known to +- {se * 1000:.1f} mm)" if outcome == "unverifiable" and se else ""
    if unit != "m":
        known = ""
    elif known and not np.isfinite(se):
        known = " (a bound only: the shots do not reach across it)"
    ctx.emit(
        "design-deviation",
        [comp.id],
        f"{aspect} {verb} design {designed.id}: {measured_text}{known}, allowed {standard}",
        location=centre_of(comp.geometry),
        measured=measured,
        allowed=allowed,
        stderr=se,
        unit=unit,
        outcome=outcome,
        rescan=f"scan {comp.id} with more points to measure its {aspect} better",
        suggestions=(suggestion,) if suggestion else (),
    )


def _check_pipe(ctx, designed, comp, table: SizeTable, wanted: str | None):
    fit = comp.fit
    ends = _ends(comp.geometry)
    if ends is None:
        return
    built = (table.find(comp.nominal) or comp.nominal) if comp.nominal else None
    if wanted and built and built != wanted:
        ctx.emit(
            "design-deviation",
            [comp.id],
            f"size deviates from design {designed.id}: {table.label(built)} built, "
            f"{_size_text(table, wanted, designed.nominal)} designed",
            location=centre_of(comp.geometry),
            unit="",
            suggestions=(Suggestion(f"check which size {comp.id} really is (rescan with a hint)"),),
        )
    length = float(np.linalg.norm(ends[1] - ends[0]))
    tol, standard = _length_tolerance(ctx, table, wanted or built)
    off = length - designed.length
    se = _length_stderr(ctx, comp)
    if off >= 0 or _both_ends_joined(ctx, comp):
        _emit(
            ctx,
            comp,
            designed,
            "length",
            f"{length * 1000:.1f} mm built, {designed.length * 1000:.1f} mm designed "
            f"({mm(abs(off))} {'long' if off >= 0 else 'short'})",
            abs(off),
            tol,
            se,
            "m",
            f"+-{mm(tol)} ({standard})",
            verdict(abs(off), tol, se, ctx.k),
        )
    pos_tol = float(ctx.opt("design-deviation", "position_tolerance"))
    offset = _line_distance(ends, designed.start, designed.axis)
    se_pos = stderr_value(fit.stderr, "center") if fit is not None else None
    _emit(
        ctx,
        comp,
        designed,
        "position",
        f"axis {mm(offset)} off the designed axis",
        offset,
        pos_tol,
        se_pos,
        "m",
        mm(pos_tol),
        verdict(offset, pos_tol, se_pos, ctx.k),
    )
    _check_direction(ctx, designed, comp)


def _check_direction(ctx, designed, comp):
    _, axis = built_axis(comp)
    if axis is None:
        return
    angle = float(np.degrees(np.arccos(min(abs(float(np.dot(axis, designed.axis))), 1.0))))
    tol = float(ctx.opt("design-deviation", "direction_tolerance_deg"))
    se = axis_stderr_deg(comp)
    _emit(
        ctx,
        comp,
        designed,
        "direction",
        f"axis {deg(angle)} off the designed one",
        angle,
        tol,
        se,
        "deg",
        deg(tol),
        verdict(angle, tol, se, ctx.k),
    )


def _size_stderrs(comp) -> np.ndarray:
    """Each of a cuboid's sizes' own standard errors (metres, in ``geometry.size``'s order):
    infinite where the fit has none (a size the shots only bound, written null in a model
    document), and for every size when the component has no fit (nothing says how well it is
    known: exact, as the rules take a missing standard error, is 0)."""
    size = np.asarray(comp.geometry.size, dtype=np.float64)
    fit = comp.fit
    if fit is None or not fit.stderr or fit.stderr.get("size") is None:
        return np.zeros(len(size))
    values = np.asarray(
        [np.nan if v is None else v for v in np.ravel(fit.stderr["size"])], dtype=np.float64
    )
    if values.shape != size.shape:
        return np.full(len(size), np.inf)
    return np.where(np.isfinite(values), values, np.inf)


def _section(comp):
    """The built section's sizes (metres, ascending) and each one's standard error: a cuboid's
    two sizes across its longest, a cylinder's diameter; None for other shapes."""
    geometry = comp.geometry
    if isinstance(geometry, Cuboid):
        keep = np.delete(np.arange(3), int(np.argmax(geometry.size)))
        order = keep[np.argsort(np.asarray(geometry.size)[keep])]
        return np.asarray(geometry.size)[order], _size_stderrs(comp)[order]
    if isinstance(geometry, Cylinder):
        se = stderr_value(comp.fit.stderr, "radius") if comp.fit is not None else None
        return np.array([2 * geometry.radius]), np.array([np.nan if se is None else 2 * se])
    return None


def _plan_stderr(comp) -> float | None:
    """The standard error (metres) of a column's axis position in plan: the fit's centre error
    is over all three box axes, and along a column its height (bounded by the shots' extent)
    dominates it (a 5 m column: 131 mm where its section is known to 34); across the axis it
    is at least half the section sizes' errors (the centre lies midway between faces), and the
    centre's variance less the length's share, when that is more."""
    fit = comp.fit
    if fit is None:
        return None
    g = comp.geometry
    if not isinstance(g, Cuboid):
        return stderr_value(fit.stderr, "center")
    se = _size_stderrs(comp)
    longest = int(np.argmax(g.size))
    across = np.delete(se, longest)
    floor = 0.25 * float(np.sum(across**2))
    centre = stderr_value(fit.stderr, "center")
    if centre is None or not np.isfinite(centre) or not np.isfinite(se[longest]):
        return float(np.sqrt(floor))
    return float(np.sqrt(max(centre**2 - 0.25 * se[longest] ** 2, floor)))


def _check_section(ctx, designed, comp, built, wanted, se_values):
    plus = float(ctx.opt("design-deviation", "section_plus"))
    minus = float(ctx.opt("design-deviation", "section_minus"))
    for b, w, se_value in zip(built, wanted, se_values):
        se_value = None if np.isnan(se_value) else float(se_value)
        diff = float(b - w)
        allowed = plus if diff >= 0 else minus
        _emit(
            ctx,
            comp,
            designed,
            "section",
            f"{b * 1000:.1f} mm built, {w * 1000:.1f} mm designed ({diff * 1000:+.1f} mm)",
            abs(diff),
            allowed,
            se_value,
            "m",
            f"+{mm(plus)} / -{mm(minus)} ("
            + (
                "ACI 117"  # concrete members' cross-section tolerance
                if getattr(designed, "material", None) != "steel"
                else "the rules file's section tolerance; ACI 117 is for concrete"
            )
            + ")",
            verdict(abs(diff), allowed, se_value, ctx.k),
        )


def _check_column(ctx, designed, comp):
    centre, axis = built_axis(comp)
    if centre is None:
        return
    # plan offset of the as-built axis where it crosses the designed base's height
    t = (designed.start[2] - centre[2]) / axis[2] if abs(axis[2]) > 1e-9 else 0.0
    at_base = centre + t * axis
    offset = float(np.hypot(*(at_base - designed.start)[:2]))
    tol = float(ctx.opt("design-deviation", "position_tolerance"))
    se = _plan_stderr(comp)
    _emit(
        ctx,
        comp,
        designed,
        "position",
        f"axis {mm(offset)} off the designed one in plan",
        offset,
        tol,
        se,
        "m",
        mm(tol),
        verdict(offset, tol, se, ctx.k),
    )
    section = _section(comp)
    if section is not None and designed.size is not None and len(section[0]) == len(designed.size):
        _check_section(ctx, designed, comp, *section[:1], np.sort(designed.size), section[1])


def _check_box(ctx, designed, comp):
    g = comp.geometry
    if not isinstance(g, Cuboid):
        return
    fit = comp.fit
    offset = float(np.linalg.norm(g.center - designed.center))
    tol = float(ctx.opt("design-deviation", "position_tolerance"))
    se = stderr_value(fit.stderr, "center") if fit is not None else None
    _emit(
        ctx,
        comp,
        designed,
        "position",
        f"centre {mm(offset)} off the designed one",
        offset,
        tol,
        se,
        "m",
        mm(tol),
        verdict(offset, tol, se, ctx.k),
    )
    order = np.argsort(g.size)
    sizes, stderrs = np.asarray(g.size)[order], _size_stderrs(comp)[order]
    _check_section(ctx, designed, comp, sizes, np.sort(designed.size), stderrs)


def check_design(ctx: Context) -> None:
    """All three design rules in one pass (one matching).

    Raises
    ------
    DesignError
        A designed pipe's ``nominal`` names no size of the model's catalog.
    """
    design = ctx.design
    if design is None:
        return
    table = _table(ctx)
    sizes = _designed_sizes(ctx, table)
    radius = float(ctx.opt("missing-component", "match_radius"))
    match = match_design(ctx.model, design, radius)
    if ctx.config.is_active("design-deviation"):
        for designed, comp in match.pairs:
            if designed.kind == "pipe":
                _check_pipe(ctx, designed, comp, table, sizes.get(designed.id))
            else:
                {"column": _check_column, "box": _check_box}[designed.kind](ctx, designed, comp)
    if ctx.config.is_active("missing-component"):
        for designed in match.missing:
            ctx.emit(
                "missing-component",
                [designed.id],
                f"designed {designed.kind} {designed.id} has no as-built counterpart within "
                f"{radius:.2f} m",
                location=designed.center,
                unit="",
                suggestions=(Suggestion(f"check whether {designed.id} was built; if so, scan it"),),
            )
    if ctx.config.is_active("extra-component"):
        for comp in match.extra:
            ctx.emit(
                "extra-component",
                [comp.id],
                f"as-built {comp.type} matches no designed component within {radius:.2f} m",
                location=centre_of(comp.geometry),
                unit="",
                suggestions=(Suggestion(f"add {comp.id} to the design or record it as a change"),),
            )


CHECKS = {"design-deviation": check_design}
