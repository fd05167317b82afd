"""The HTML QA report: one self-contained file (styles and pictures inline, no network needed).

Sections: a header (scan, dates, catalog, units, counts and the compliance summary), the plan and
elevation pictures (inline SVG from :mod:`asbuilt.report.figures`), the quantity take-off (pipe
by size and schedule in metres and feet with weights, fittings by size and angle, volumes and
areas of members, tanks and other solids), one row per component (the CSV's content), the fit
quality of every fitted object with a residual histogram, and the findings with their
suggestions. Ids link both ways: a label in a picture or a finding's object jumps to the
component's row; a row's finding codes jump to the finding.

An optional interactive 3-D view (``gltf=`` a glTF/GLB file of the same model: embedded in the
page as a ``data:`` URI up to :data:`GLTF_EMBED_LIMIT` bytes, so that it works from disk, else
linked by a relative path, which needs the page served over HTTP) is loaded only when the reader
presses its button, from the model-viewer web component on a CDN; nothing else on the page uses
the network.
"""

from __future__ import annotations

import numpy as np

from asbuilt.atomic import atomic_write

from ._html_cells import _e, _link, _mm, _num, _table, _td
from ._html_gltf import GLTF_EMBED_LIMIT, StagedGltf, gltf_source
from ._html_takeoff import _takeoff
from .data import ReportData
from .figures import VIEWS, anchor, histogram_svg, render_view

__all__ = [
    "html_text",
    "write_html",
    "gltf_source",
    "StagedGltf",
    "MODEL_VIEWER_URL",
    "GLTF_EMBED_LIMIT",
]

#: Where the optional 3-D viewer's script comes from (only fetched on the reader's request).
MODEL_VIEWER_URL = "https://ajax.googleapis.com/ajax/libs/model-viewer/3.5.0/model-viewer.min.js"


_CSS = """
:root { --err:#d62728; --warn:#ff7f0e; --info:#1f77b4; --ok:#2ca02c; --line:#ddd; }
* { box-sizing: border-box; }
body { font: 14px/1.4 system-ui, -apple-system, "Segoe UI", Roboto, sans-serif; margin: 0;
       color: #222; background: #fafafa; }
header { background: #263238; color: #fff; padding: 16px 24px; }
header h1 { margin: 0 0 6px; font-size: 22px; }
header dl { display: grid; grid-template-columns: max-content 1fr; gap: 2px 12px; margin: 8px 0 0; }
header dt { color: #b0bec5; } header dd { margin: 0; }
main { padding: 8px 24px 32px; max-width: 1400px; }
section { margin-top: 24px; }
h2 { font-size: 18px; border-bottom: 2px solid #263238; padding-bottom: 4px; }
h3 { font-size: 15px; margin: 16px 0 6px; }
nav a { color: #cfd8dc; margin-right: 14px; }
table { border-collapse: collapse; background: #fff; margin: 4px 0 8px; }
th, td { border: 1px solid var(--line); padding: 3px 7px; text-align: left; vertical-align: top; }
th { background: #eceff1; position: sticky; top: 0; }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums; }
tr.total td { font-weight: 600; background: #f5f5f5; }
tr:target { outline: 2px solid var(--info); }
li:target { outline: 2px solid var(--info); }
.summary { display: flex; gap: 12px; flex-wrap: wrap; margin-top: 12px; }
.badge { border-radius: 6px; padding: 6px 12px; font-weight: 600; color: #fff; }
.badge.error { background: var(--err); } .badge.warning { background: var(--warn); }
.badge.info { background: var(--info); } .badge.ok { background: var(--ok); }
.badge.zero { background: #546e7a; }
.sev { font-weight: 600; } .sev.error { color: var(--err); } .sev.warning { color: var(--warn); }
.sev.info { color: var(--info); }
.pictures { display: grid; grid-template-columns: repeat(auto-fit, minmax(680px, 1fr)); gap: 12px; }
figure { margin: 0; background: #fff; border: 1px solid var(--line); padding: 6px; }
figure svg, figure img { width: 100%; height: auto; display: block; }
figcaption { font-size: 12px; color: #555; }
svg.hist { display: block; background: #f7f7f7; }
ol.findings > li { margin-bottom: 10px; background: #fff; border: 1px solid var(--line);
                   padding: 6px 10px; list-style-position: inside; }
.muted { color: #777; font-size: 12px; }
.viewer { background: #fff; border: 1px solid var(--line); padding: 8px; }
.viewer model-viewer { width: 100%; height: 480px; }
"""

_SCRIPT = """
document.addEventListener("DOMContentLoaded", function () {
  var button = document.getElementById("load-3d");
  if (!button) { return; }
  button.addEventListener("click", function () {
    var status = document.getElementById("viewer-status");
    var script = document.createElement("script");
    script.type = "module";
    script.src = button.getAttribute("data-src");
    script.onerror = function () {
      status.textContent = "The 3-D viewer could not be loaded (no network?). " +
        "The rest of this report does not need it.";
    };
    script.onload = function () {
      var viewer = document.createElement("model-viewer");
      viewer.setAttribute("src", button.getAttribute("data-model"));
      viewer.setAttribute("camera-controls", "");
      viewer.setAttribute("alt", "as-built model");
      document.getElementById("viewer-slot").appendChild(viewer);
      status.textContent = "";
    };
    status.textContent = "Loading the viewer...";
    document.head.appendChild(script);
    button.disabled = true;
  });
});
"""


def _scan_date(data: ReportData) -> str:
    if data.scan_date:
        return _e(data.scan_date)
    text = "not recorded in the scan file"
    if data.scan_file_modified:
        text += f" (file modified {_e(data.scan_file_modified)})"
    return text


def _header(data: ReportData) -> str:
    s = data.severities
    badges = []
    for severity, name in (("error", "errors"), ("warning", "warnings"), ("info", "info")):
        count = s.get(severity, 0)
        cls = severity if count else "zero"
        badges.append(f'<span class="badge {cls}" id="count-{severity}">{count} {name}</span>')
    verdict = (
        '<span class="badge ok">no errors</span>'
        if not s.get("error")
        else '<span class="badge error">has errors</span>'
    )
    unverifiable = s.get("unverifiable", 0)
    counts = data.counts
    order = ("components", "spools", "objects", "points")
    parts = [f"{counts[k]} {k}" for k in order if k in counts]
    by_type = ", ".join(
        f"{v} {k}" for k, v in counts.items() if k not in order and not k.startswith("_")
    )
    catalog = _e(data.catalog) if data.catalog else "none"
    if data.catalog_title:
        catalog += f" &mdash; {_e(data.catalog_title)}"
    if data.catalog_file:
        catalog += f" (file {_e(data.catalog_file)})"
    if data.catalog_problem:
        problem = _e(data.catalog_problem)
        catalog += f'<br><span class="sev warning" id="catalog-problem">{problem}</span>'
    nav = "".join(
        f'<a href="#{target}">{label}</a>'
        for target, label in (
            ("pictures", "Pictures"),
            ("takeoff", "Take-off"),
            ("components", "Components"),
            ("quality", "Fit quality"),
            ("findings", "Findings"),
        )
    )
    return f"""<header>
<h1>{_e(data.title)}</h1>
<nav>{nav}</nav>
<dl>
<dt>Scan</dt><dd>{_e(data.source) or "not recorded"}</dd>
<dt>Scan date</dt><dd>{_scan_date(data)}</dd>
<dt>Report made</dt><dd>{_e(data.generated)}</dd>
<dt>Catalog</dt><dd>{catalog}</dd>
<dt>Units</dt><dd>scan in {_e(data.units)}; this report in metres (pipe lengths also in feet),
 diameters and residuals in millimetres</dd>
<dt>Counts</dt><dd>{_e(", ".join(parts))}{(" (" + _e(by_type) + ")") if by_type else ""}</dd>
</dl>
<div class="summary" id="compliance">{verdict}{"".join(badges)}
<span class="badge zero">{unverifiable} unverifiable</span></div>
</header>"""


def _pictures(data: ReportData, figure_format: str, label_limit: int) -> str:
    figures = []
    for view in VIEWS:
        picture = render_view(data.model, view, fmt=figure_format, label_limit=label_limit)
        if figure_format == "png":
            picture = f'<img src="{picture}" alt="{_e(VIEWS[view][0])}">'
        figures.append(
            f'<figure id="view-{view}">{picture}<figcaption>{_e(VIEWS[view][0])}: components '
            "filled by their worst finding (grey: none, blue: info, orange: warning, red: "
            "error); black dots: scanned points; red crosses: points the fit rejected. "
            "Click a label to jump to its row.</figcaption></figure>"
        )
    return (
        '<section id="pictures"><h2>Pictures</h2><div class="pictures">'
        + "".join(figures)
        + "</div></section>"
    )


def _finding_links(data: ReportData) -> dict[str, list[tuple[int, str, str]]]:
    links: dict[str, list[tuple[int, str, str]]] = {}
    for index, finding in enumerate(data.findings, 1):
        for oid in finding.objects:
            links.setdefault(oid, []).append((index, finding.code, finding.severity))
    return links


def _codes(links: list[tuple[int, str, str]]) -> str:
    return " ".join(
        f'<a class="sev {sev}" href="#finding-{i}">{_e(code)}</a>' for i, code, sev in links
    )


def _components(data: ReportData, links) -> str:
    fitted = {q.id for q in data.quality}
    # The insulation column only when something is lagged, as the take-off's insulation table:
    # most plants are bare, and a column of zeros would crowd the table.
    lagged = any(r.insulation for r in data.takeoff.rows)
    rows = []
    for r in data.takeoff.rows:
        oid = _e(r.id)
        if r.id in fitted:
            oid = f'{oid} <a class="muted" href="#fit-{anchor(r.id)[4:]}">fit</a>'
        rows.append(
            f'<tr id="{anchor(r.id)}">'
            + _td(oid)
            + _td(_e(r.type))
            + _td(_e(r.spool or ""))
            + _td(_e(r.label or ""))
            + _td(_e(r.size or ""))
            + _td(_e(r.schedule or ""))
            + _td(_num(r.length), True)
            + _td(_e(r.quantity_unit))
            + _td(_num(r.quantity, 0 if r.quantity_unit == "ea" else 3), True)
            + _td(_num(r.weight, 1), True)
            + (_td(_mm(r.insulation) if r.insulation else "", True) if lagged else "")
            + _td(_codes(links.get(r.id, [])))
            + "</tr>"
        )
    table = _table(
        [
            ("Id", False),
            ("Type", False),
            ("Spool", False),
            ("Label", False),
            ("Size", False),
            ("Schedule", False),
            ("Length (m)", True),
            ("Unit", False),
            ("Quantity", True),
            ("Weight (kg)", True),
            *([("Insulation (mm)", True)] if lagged else []),
            ("Findings", False),
        ],
        rows,
        "components",
    )
    return (
        '<section id="components"><h2>Components</h2>'
        '<p class="muted">One row per component, as in the CSV report.</p>'
        f"{table}</section>"
    )


def _stderr_text(stderr) -> str:
    parts = []
    for key, value in stderr.items():
        if value is None:
            continue
        values = value if isinstance(value, (tuple, list)) else (value,)
        try:
            numbers = [float(v) for v in values]
        except (TypeError, ValueError):
            continue
        if not all(np.isfinite(numbers)):
            continue
        if key.endswith("_deg"):
            text = "/".join(f"{v:.2f}" for v in numbers) + "°"
            key = key[: -len("_deg")]
        else:
            text = "/".join(f"{v * 1000:.1f}" for v in numbers) + " mm"
        parts.append(f"{key} {text}")
    return ", ".join(parts)


def _residual_cell(q) -> str:
    """The residual histogram, or a note for fits read from a model document written before
    documents stored the per-point residuals (the fit's summary only)."""
    if q.residuals.size == 0 and q.points > 0:
        return '<span class="muted">not stored in the model file</span>'
    return histogram_svg(q.residuals, q.inlier_mask)


def _quality(data: ReportData, links) -> str:
    if not data.quality:
        return (
            '<section id="quality"><h2>Fit quality</h2>'
            '<p class="muted">No fitted objects.</p></section>'
        )
    rows = []
    for q in data.quality:
        offset = ""
        if q.snap_offset is not None:
            offset = f"{q.snap_offset * 1000:+.1f}"
            if q.snap_sigmas is not None:
                offset += f" ({q.snap_sigmas:.1f}&sigma;)"
        size = _e(q.size or "")
        if q.snap_status and q.snap_status not in ("snapped", "fitting"):
            size += f' <span class="muted">{_e(q.snap_status)}</span>'
        rows.append(
            f'<tr id="fit-{anchor(q.id)[4:]}">'
            + _td(_link(q.id))
            + _td(_e(q.kind))
            + _td(str(q.points), True)
            + _td(str(q.inliers), True)
            + _td(_mm(q.rms, 2), True)
            + _td(_mm(q.max_residual, 2), True)
            + _td(_e(_stderr_text(q.stderr)))
            + _td(size)
            + _td(_mm(q.od_fit), True)
            + _td(_mm(q.od_catalog), True)
            + _td(offset, True)
            + _td(_residual_cell(q))
            + _td(_codes(links.get(q.id, [])))
            + "</tr>"
        )
    table = _table(
        [
            ("Id", False),
            ("Fitted as", False),
            ("Points", True),
            ("Inliers", True),
            ("RMS (mm)", True),
            ("Max (mm)", True),
            ("Standard errors", False),
            ("Snapped size", False),
            ("Fitted OD (mm)", True),
            ("Catalog OD (mm)", True),
            ("Fit - catalog (mm)", True),
            ("Residuals", False),
            ("Findings", False),
        ],
        rows,
        "quality",
    )
    return (
        '<section id="quality"><h2>Fit quality</h2>'
        '<p class="muted">RMS and max over the inliers; standard errors from the fit\'s '
        "covariance; the histogram spans &plusmn; the largest residual (grey: inliers, red: "
        "rejected points, blue line: zero).</p>"
        f"{table}</section>"
    )


def _accept_note(finding, number: int, suggestion) -> str:
    """How ``asbuilt check`` accepts suggestion ``number`` of ``finding`` (HTML), or ``""``."""
    from asbuilt.rules.accept import accept_choice

    if (choice := accept_choice(finding, number)) is None:
        return ""
    alone = "--fix applies it, or " if suggestion.unambiguous else "accept with "
    return f' <span class="muted">({alone}<code>--accept {_e(choice)}</code>)</span>'


def _findings(data: ReportData) -> str:
    if not data.findings:
        return (
            '<section id="findings"><h2>Findings</h2>'
            '<p id="no-findings">No findings: every rule passed.</p></section>'
        )
    rows = {comp.id for comp in data.model.components}  # the ids that have a row to link to

    def named(oid: str) -> str:  # a design's missing object has no row: plain text
        return _link(oid) if oid in rows else f'<span class="missing">{_e(oid)}</span>'

    items = []
    for index, f in enumerate(data.findings, 1):
        values = []
        for name, value in (
            ("measured", f.measured),
            ("allowed", f.allowed),
            ("&plusmn;", f.stderr),
        ):
            if value is not None and np.isfinite(value):
                values.append(f"{name} {value:.4g} {_e(f.unit)}")
        suggestions = "".join(
            f"<li>{_e(s.description)}{_accept_note(f, number, s)}</li>"
            for number, s in enumerate(f.suggestions, 1)
        )
        items.append(
            f'<li id="finding-{index}"><span class="sev {f.severity}">{_e(f.severity)}</span> '
            f"<code>{_e(f.code)}</code> {_e(f.slug)}"
            f"{' (unverifiable)' if f.unverifiable else ''} &mdash; "
            f"{', '.join(named(o) for o in f.objects)}<br>{_e(f.message)}"
            + (f'<br><span class="muted">{"; ".join(values)}</span>' if values else "")
            + (f"<ol>{suggestions}</ol>" if suggestions else "")
            + "</li>"
        )
    return (
        '<section id="findings"><h2>Findings</h2><ol class="findings">'
        + "\n".join(items)
        + "</ol></section>"
    )


def _viewer(gltf: str | None) -> str:
    if not gltf:
        return ""
    if gltf.startswith("data:"):
        where = (
            "The model is embedded in this page, so the view works from a file on disk or an "
            "e-mail attachment too"
        )
    else:
        where = (
            f'The model is linked: <a href="{_e(gltf)}">{_e(gltf)}</a>. A page opened from '
            "disk (file://) may not read another file, so the view needs the page and the model "
            "served over HTTP (for example <code>python -m http.server</code> in their folder)"
        )
    return (
        '<section id="viewer3d"><h2>Interactive 3-D view</h2><div class="viewer">'
        f"<p>{where}. The viewer itself is loaded from the web when the button is pressed "
        "(network access needed); the view is optional and the rest of this report does not "
        "need it.</p>"
        f'<button id="load-3d" type="button" data-src="{_e(MODEL_VIEWER_URL)}" '
        f'data-model="{_e(gltf)}">Load the 3-D viewer</button> '
        '<span id="viewer-status" class="muted"></span><div id="viewer-slot"></div>'
        "</div></section>"
    )


def html_text(
    data: ReportData,
    *,
    figure_format: str = "svg",
    label_limit: int = 200,
    gltf: str | None = None,
) -> str:
    """The HTML report as text.

    Parameters
    ----------
    data : ReportData
    figure_format : {"svg", "png"}
        Inline SVG (vector outlines and text, rasterised points) or embedded PNG.
    label_limit : int
        See :func:`asbuilt.report.figures.render_view`.
    gltf : str, optional
        URL (usually a path relative to the report) of a glTF/GLB file of the same model for
        the optional 3-D view.
    """
    links = _finding_links(data)
    body = "\n".join(
        [
            _header(data),
            "<main>",
            _pictures(data, figure_format, label_limit),
            _takeoff(data),
            _components(data, links),
            _quality(data, links),
            _findings(data),
            _viewer(gltf),
            '<p class="muted">Made by asbuilt. Lengths in metres unless marked; '
            "1 ft = 0.3048 m.</p>",
            "</main>",
        ]
    )
    script = f"<script>{_SCRIPT}</script>" if gltf else ""
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        '<meta name="viewport" content="width=device-width, initial-scale=1">\n'
        f"<title>{_e(data.title)} &mdash; as-built QA report</title>\n"
        f"<style>{_CSS}</style>\n{script}</head>\n<body>\n{body}\n</body>\n</html>\n"
    )


def write_html(
    data: ReportData,
    path,
    *,
    figure_format: str = "svg",
    label_limit: int = 200,
    gltf=None,
) -> None:
    """Write the HTML report to ``path`` atomically; see :func:`html_text` for the options.

    ``gltf`` may be a path: the file is embedded in the page up to :data:`GLTF_EMBED_LIMIT`
    bytes, else linked relative to the report's directory (see :func:`gltf_source`).
    """
    if gltf is not None:
        gltf = gltf_source(gltf, path)
    text = html_text(data, figure_format=figure_format, label_limit=label_limit, gltf=gltf)
    with atomic_write(path, "w", encoding="utf-8") as handle:
        handle.write(text)
