"""The HTML report's quantity take-off section: spools, pipe by size and schedule, fittings, butt
welds, insulation, and other solids (a private helper of :mod:`asbuilt.report.html`)."""

from __future__ import annotations

from ._html_cells import _e, _link, _mm, _num, _table, _td
from .data import ReportData
from .figures import anchor
from .takeoff import FOOT

__all__ = ["_takeoff"]


def _weight(total: float | None, missing: int) -> str:
    """A weight total (kg) that says how many pipes it leaves out; blank when none has one."""
    if total is None:
        return ""
    if not missing:
        return _num(total, 1)
    pipes = "pipe" if missing == 1 else "pipes"
    return f'{_num(total, 1)}<br><span class="muted">without {missing} {pipes}</span>'


def _weight_note(t) -> str:
    """Which pipes the weight leaves out for want of a wall (a sentence; "" when none)."""
    if not t.pipes_without_weight or t.density is None:
        return ""  # no density: the page already says there are no weights
    pieces = sum(p.count for p in t.pipes)
    which = (
        "No pipe has a weight"
        if t.pipe_weight is None
        else f"{t.pipes_without_weight} of {pieces} pipes have no weight and are not in the total"
    )
    return (
        f' <span id="weight-note">{which}: their wall thickness is not known (no schedule, '
        "or the catalog lists no wall for it).</span>"
    )


def _takeoff(data: ReportData) -> str:
    t = data.takeoff
    out = ['<section id="takeoff"><h2>Quantity take-off</h2>']
    if t.spools:
        out.append("<h3>Spools</h3>")
        # a lateral column only where a spool has one: most plants have none
        has_laterals = any(sp.fittings.get("lateral") for sp in t.spools)
        # a cross column only where a spool has one, as laterals
        has_crosses = any(sp.fittings.get("cross") for sp in t.spools)
        kinds = (
            ("elbow", "tee")
            + (("cross",) if has_crosses else ())
            + (("lateral",) if has_laterals else ())
            + ("reducer", "coupling")
        )
        # an insulated length column only where something is insulated
        lagged = bool(t.insulation)
        rows = [
            f'<tr id="spool-{anchor(sp.id)[4:]}">'
            + _td(_e(sp.id))
            + _td(_e(", ".join(sp.sizes)))
            + _td(str(sp.pipes), True)
            + _td(_num(sp.pipe_length), True)
            + _td(_num(sp.pipe_length / FOOT, 2), True)
            + _td(_weight(sp.pipe_weight, sp.pipes_without_weight), True)
            + "".join(_td(str(sp.fittings.get(kind, 0)), True) for kind in kinds)
            + _td(str(sp.welds), True)
            + _td(_num(sp.diameter_inches, 1), True)
            + _td(str(sp.open_ends), True)
            + (_td(_num(sp.insulated_length), True) if lagged else "")
            + _td(" ".join(_e(code) for code in sp.findings))
            + "</tr>"
            for sp in t.spools
        ]
        out.append(
            _table(
                [
                    ("Spool", False),
                    ("Sizes", False),
                    ("Pipes", True),
                    ("Pipe (m)", True),
                    ("Pipe (ft)", True),
                    ("Weight (kg)", True),
                    ("Elbows", True),
                    ("Tees", True),
                    *((("Crosses", True),) if has_crosses else ()),
                    *((("Laterals", True),) if has_laterals else ()),
                    ("Reducers", True),
                    ("Couplings", True),
                    ("Welds", True),
                    ("Dia-inch", True),
                    ("Open ends", True),
                    *((("Insulated (m)", True),) if lagged else ()),
                    ("Findings", False),
                ],
                rows,
                "spools",
            )
        )
    out.append("<h3>Pipe by nominal size and schedule</h3>")
    if t.pipes:
        rows = []
        for p in t.pipes:
            rows.append(
                "<tr>"
                + _td(_e(p.size))
                + _td(_e(p.schedule or "unknown"))
                + _td(_mm(p.od), True)
                + _td(_mm(p.wall, 2), True)
                + _td(str(p.count), True)
                + _td(_num(p.length), True)
                + _td(_num(p.length_ft, 2), True)
                + _td(_num(p.weight_per_m, 2), True)
                + _td(_num(p.weight, 1), True)
                + _td(_num(p.area, 2), True)
                + "</tr>"
            )
        rows.append(
            '<tr class="total"><td colspan="4">Total</td>'
            + _td(str(sum(p.count for p in t.pipes)), True)
            + _td(_num(t.pipe_length), True)
            + _td(_num(t.pipe_length / FOOT, 2), True)
            + "<td></td>"
            + _td(_weight(t.pipe_weight, t.pipes_without_weight), True)
            + _td(_num(sum(p.area for p in t.pipes), 2), True)
            + "</tr>"
        )
        out.append(
            _table(
                [
                    ("Size", False),
                    ("Schedule", False),
                    ("OD (mm)", True),
                    ("Wall (mm)", True),
                    ("Pieces", True),
                    ("Length (m)", True),
                    ("Length (ft)", True),
                    ("kg/m", True),
                    ("Weight (kg)", True),
                    ("Outside area (m²)", True),
                ],
                rows,
                "pipes",
            )
        )
        if t.density is not None:
            out.append(
                f'<p class="muted">Weights: plain-end pipe, density {t.density:.0f} kg/m³ '
                f"({_e(t.material or 'given')}), w = &rho; &pi; (OD &minus; t) t "
                "(ASME B36.10M). Lengths are straight pipe between fittings."
                f"{_weight_note(t)}</p>"
            )
        else:
            out.append(
                '<p class="muted">No weights: the pipe material\'s density is not known.</p>'
            )
    else:
        out.append('<p class="muted">No pipe.</p>')

    out.append("<h3>Fittings by size and angle</h3>")
    if t.fittings:
        rows = [
            "<tr>"
            + _td(_e(f.type))
            + _td(_e(f.size))
            + _td(_e(f.schedule or ""))
            + _td("" if f.angle_deg is None else f"{f.angle_deg}°", True)
            + _td(_mm(f.bend_radius, 0), True)
            + _td(str(f.count), True)
            + _td(", ".join(_link(c) for c in f.components))
            + "</tr>"
            for f in t.fittings
        ]
        out.append(
            _table(
                [
                    ("Type", False),
                    ("Size", False),
                    ("Schedule", False),
                    ("Angle", True),
                    ("Bend radius (mm)", True),
                    ("Count", True),
                    ("Components", False),
                ],
                rows,
                "fittings",
            )
        )
    else:
        out.append('<p class="muted">No fittings.</p>')
    out.append(_welds(t))
    if t.insulation:  # nothing when bare: most plants are, and the table would be empty
        out.append(_insulation(t))

    out.append("<h3>Members, tanks, vessels and other solids</h3>")
    if t.solids:
        rows = [
            "<tr>"
            + _td(_link(s.id))
            + _td(_e(s.shape))
            + _td(_e(s.category))
            + _td(_e(s.label or ""))
            + _td(_e(" x ".join(f"{d:.3f}" for d in s.dimensions)))
            + _td(_num(s.volume, 3), True)
            + _td(_num(s.area, 2), True)
            + "</tr>"
            for s in t.solids
        ]
        for category in sorted(set(t.areas) | set(t.volumes)):
            rows.append(
                f'<tr class="total"><td colspan="5">Total {_e(category)}</td>'
                + _td(_num(t.volumes.get(category), 3), True)
                + _td(_num(t.areas.get(category), 2), True)
                + "</tr>"
            )
        out.append(
            _table(
                [
                    ("Id", False),
                    ("Shape", False),
                    ("Counted as", False),
                    ("Label", False),
                    ("Dimensions (m)", False),
                    ("Volume (m³)", True),
                    ("Surface (m²)", True),
                ],
                rows,
                "solids",
            )
        )
        out.append(
            '<p class="muted">Dimensions: cuboid edges; cylinder diameter x length; sphere '
            "diameter; hull extent. Volumes: cylinders &pi; r² h; surfaces are closed (ends "
            "included); a plane's area is its outline's.</p>"
        )
    else:
        out.append('<p class="muted">No other solids.</p>')
    out.append("</section>")
    return "\n".join(out)


def _welds(t) -> str:
    """The butt welds by size, with their diameter-inches (:mod:`asbuilt.report.welds`)."""
    out = ["<h3>Butt welds by size</h3>"]
    if not t.welds:
        out.append('<p class="muted">No butt welds.</p>')
        return "\n".join(out)
    rows = [
        "<tr>"
        + _td(_e(w.size))
        + _td(_mm(w.od), True)
        + _td(str(w.count), True)
        + _td(_num(w.diameter_inches, 1), True)
        + _td(", ".join(_e(joint) for joint in w.joints))
        + "</tr>"
        for w in t.welds
    ]
    rows.append(
        '<tr class="total"><td colspan="2">Total</td>'
        + _td(str(t.weld_count), True)
        + _td(_num(t.diameter_inches, 1), True)
        + "<td></td></tr>"
    )
    out.append(
        _table(
            [
                ("Size", False),
                ("OD (mm)", True),
                ("Welds", True),
                ("Dia-inch", True),
                ("Joints", False),
            ],
            rows,
            "welds",
        )
    )
    missing = (
        f" {t.welds_without_nps} weld(s) of a size with no NPS are left out of the dia-inch."
        if t.welds_without_nps
        else ""
    )
    out.append(
        '<p class="muted">A butt weld wherever two piping components\' ends meet; each at its '
        "smaller end's size. Dia-inch: the sum of the welds' nominal pipe sizes in inches. "
        "Open ends (spools table) meet nothing: flanges, equipment, or where the scan "
        f"stopped; they are not counted as welds.{missing}</p>"
    )
    return "\n".join(out)


def _insulation(t) -> str:
    """The insulation by thickness and size (:mod:`asbuilt.report.lagging`)."""
    rows = [
        "<tr>"
        + _td(_mm(q.thickness), True)
        + _td(_e(q.size))
        + _td(_num(q.length), True)
        + _td(_num(q.area, 2), True)
        + _td(_num(q.volume, 3), True)
        + _td(str(q.fittings), True)
        + _td(", ".join(_link(c) for c in q.components))
        + "</tr>"
        for q in t.insulation
    ]
    rows.append(
        '<tr class="total"><td colspan="2">Total</td>'
        + _td(_num(t.insulated_length), True)
        + _td(_num(t.insulation_area, 2), True)
        + _td(_num(t.insulation_volume, 3), True)
        + _td(str(t.insulated_fittings), True)
        + "<td></td></tr>"
    )
    table = _table(
        [
            ("Thickness (mm)", True),
            ("Size", False),
            ("Length (m)", True),
            ("Cladding (m²)", True),
            ("Volume (m³)", True),
            ("Fittings", True),
            ("Components", False),
        ],
        rows,
        "insulation",
    )
    return (
        "<h3>Insulation by thickness and size</h3>\n"
        + table
        + '\n<p class="muted">Length along the centreline (elbows R &times; angle, tees and '
        "crosses their run plus each outlet beyond the run's cladding); cladding area "
        "2&pi;(r&nbsp;+&nbsp;t)&nbsp;L and volume &pi;((r&nbsp;+&nbsp;t)² &minus; r²)&nbsp;L "
        "(Pappus: exact for pipes and elbows, approximate at reducers, tees and crosses); the "
        "full thickness is counted, also where the drawn jacket is trimmed at a tight fitting. "
        "Tanks and vessels: their sides only (heads are not modelled).</p>"
    )
