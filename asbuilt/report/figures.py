"""Pictures for the report: plan (XY) and elevation (XZ) views, and residual histograms.

The views are drawn with matplotlib (imported inside the functions; a bare ``Figure`` rendered
by the Agg/SVG canvases, never pyplot, so no GUI backend and no global state): every
component is the 2-D convex hull of its projected pieces (a cylinder's two end circles, a
bend's short arc segments, a tee's run and branch, a box's corners...), which is the exact
silhouette of each convex piece under orthographic projection. The scanned points are overlaid
(inliers as dots, points the fit rejected as crosses) and components with findings are filled in
their worst severity's colour. Every layer is one matplotlib collection (never one call per
object), so a 1,000-object view takes about 2 s, mostly the silhouettes and labels (see
``benchmarks/RESULTS.md``); the point layers are rasterised inside the SVG to keep the file
small. Labels link to the object's row in the report (``#obj-<id>``).

The residual histograms are tiny hand-written SVGs (no matplotlib: one per object).
"""

from __future__ import annotations

import base64
import contextlib
import dataclasses
import functools
import html
import io
import re
import warnings

import numpy as np

from asbuilt.insulation import envelope
from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee
from asbuilt.primitives import Cuboid, Cylinder, Hull, Plane, Sphere

from .takeoff import severity_rank

__all__ = [
    "VIEWS",
    "SEVERITY_COLOURS",
    "component_pieces",
    "projected_outlines",
    "hull_2d",
    "render_view",
    "histogram_svg",
    "anchor",
    "label_fonts",
    "drawable_label",
]

#: View name -> (title, the two scan axes it shows, their labels).
VIEWS = {
    "plan": ("Plan (XY, looking down)", (0, 1), ("x (m)", "y (m)")),
    "elevation": ("Elevation (XZ, looking along +y)", (0, 2), ("x (m)", "z (m)")),
}

#: Fill colours by worst finding severity (``None``: no finding).
SEVERITY_COLOURS = {"error": "#d62728", "warning": "#ff7f0e", "info": "#1f77b4", None: "#9e9e9e"}

_RING = 16
_ARC_STEPS = 8


#: Characters an anchor keeps as they are (safe in an HTML id, a URL fragment and SVG).
_ANCHOR_SAFE = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_.:-")


def anchor(component_id: str) -> str:
    """The HTML id of a component's row: ``obj-`` and the id, every character other than ASCII
    letters, digits and ``_ . : -`` written as ``~`` + its code point in hex + ``~``
    (``"P 1"`` -> ``obj-P~20~1``, ``"Rohr-Ä1"`` -> ``obj-Rohr-~c4~1``).

    Injective: kept characters are never ``~`` and every escape is delimited, so the id can be
    read back from its anchor and two ids never share one (``"P 1"``, ``"P/1"`` and ``"P_1"``
    get three anchors).
    """
    return "obj-" + "".join(c if c in _ANCHOR_SAFE else f"~{ord(c):x}~" for c in component_id)


def _ring(center: np.ndarray, axis: np.ndarray, radius: float, n: int = _RING) -> np.ndarray:
    """Points (n, 3) metres on the circle of ``radius`` about ``center`` normal to ``axis``."""
    axis = axis / np.linalg.norm(axis)
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    u = np.cross(axis, helper)
    u /= np.linalg.norm(u)
    v = np.cross(axis, u)
    angles = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return center + radius * (np.cos(angles)[:, None] * u + np.sin(angles)[:, None] * v)


def _bend_pieces(g: Bend) -> list[np.ndarray]:
    a = g.start - g.center
    b = g.end - g.center
    radius = np.linalg.norm(a)
    u = a / radius
    w = b - np.dot(b, u) * u
    norm = np.linalg.norm(w)
    if norm < 1e-12:  # a 180 degree bend: any perpendicular in the plane is ambiguous
        w = np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))])
        norm = np.linalg.norm(w)
    w /= norm
    theta = np.radians(g.angle_deg)
    t = np.linspace(0.0, theta, _ARC_STEPS + 1)
    centres = g.center + radius * (np.cos(t)[:, None] * u + np.sin(t)[:, None] * w)
    tangents = -np.sin(t)[:, None] * u + np.cos(t)[:, None] * w
    rings = [_ring(c, d, g.outer_radius) for c, d in zip(centres, tangents)]
    return [np.vstack([rings[i], rings[i + 1]]) for i in range(_ARC_STEPS)]


def _sphere_points(center: np.ndarray, radius: float) -> np.ndarray:
    return np.vstack([_ring(center, axis, radius, 32) for axis in np.eye(3)])


def component_pieces(component: Component) -> list[np.ndarray]:
    """Convex pieces of a component as 3-D point sets, each shape (k, 3) metres.

    The union of the pieces' convex hulls is the component's solid (exactly for straights,
    cylinders, reducers, boxes, spheres and hulls; a bend is approximated by 8 straight
    segments).
    """
    g = component.geometry
    if isinstance(g, Straight):
        d = g.end - g.start
        return [np.vstack([_ring(g.start, d, g.outer_radius), _ring(g.end, d, g.outer_radius)])]
    if isinstance(g, Cylinder):
        start, end = g.ends
        return [np.vstack([_ring(start, g.axis, g.radius), _ring(end, g.axis, g.radius)])]
    if isinstance(g, Reducer):
        d = g.direction  # the end circles lie across the run (offset when eccentric)
        return [
            np.vstack(
                [_ring(g.start, d, g.outer_radius_start), _ring(g.end, d, g.outer_radius_end)]
            )
        ]
    if isinstance(g, Bend):
        return _bend_pieces(g)
    if isinstance(g, (Tee, Cross)):
        run, outlet = g.run_end - g.run_start, g.branch_end - g.outlet_start
        return [
            np.vstack(
                [_ring(g.run_start, run, g.outer_radius), _ring(g.run_end, run, g.outer_radius)]
            ),
            np.vstack(
                [
                    _ring(g.outlet_start, outlet, g.branch_outer_radius),
                    _ring(g.branch_end, outlet, g.branch_outer_radius),
                ]
            ),
        ]
    if isinstance(g, Cuboid):
        return [np.asarray(g.corners)]
    if isinstance(g, Sphere):
        return [_sphere_points(g.center, g.radius)]
    if isinstance(g, Plane):
        return [np.asarray(g.outline)] if len(g.outline) else [np.asarray(g.point)[None, :]]
    if isinstance(g, Hull):
        return [np.asarray(g.vertices)]
    raise TypeError(f"no picture for geometry {type(g).__name__}")


def hull_2d(points: np.ndarray) -> np.ndarray:
    """Convex hull of 2-D points, counter-clockwise (Qhull, with Andrew's monotone chain for
    degenerate input).

    Parameters
    ----------
    points : ndarray, shape (n, 2)

    Returns
    -------
    ndarray, shape (h, 2)
        The hull's vertices; fewer than 3 rows when the points are collinear (a segment) or
        all equal (one point).
    """
    from scipy.spatial import ConvexHull, QhullError

    pts = np.asarray(points, dtype=np.float64)
    if len(pts) >= 3:
        try:
            hull = ConvexHull(pts)
        except (QhullError, ValueError):
            pass
        else:
            if hull.volume > 1e-12 * max(1.0, float(np.ptp(pts)) ** 2):
                return pts[hull.vertices]  # Qhull lists 2-D hull vertices counter-clockwise
    return _monotone_chain(pts)


def _monotone_chain(points: np.ndarray) -> np.ndarray:
    """Andrew's monotone chain: the hull of (n, 2) points, collinear points dropped.

    The vertices are input points as given (exact duplicates merged): rounding them would
    change a thin hull's area by far more than its own rounding error.
    """
    pts = np.unique(np.asarray(points, dtype=np.float64), axis=0)
    if len(pts) < 3:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list = []
    for p in pts[::-1]:
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def projected_outlines(component: Component, axes: tuple[int, int]) -> list[np.ndarray]:
    """The component's silhouette in a view: one 2-D convex polygon (h, 2) metres per piece.

    ``axes`` are the two scan axes the view shows, e.g. ``(0, 1)`` for the plan.
    """
    return [hull_2d(piece[:, list(axes)]) for piece in component_pieces(component)]


def _worst(model: Model) -> dict[str, str]:
    worst: dict[str, str] = {}
    for finding in model.findings:
        for oid in finding.objects:
            if oid not in worst or severity_rank(finding.severity) < severity_rank(worst[oid]):
                worst[oid] = finding.severity
    return worst


def _points(model: Model, axes) -> tuple[np.ndarray, np.ndarray]:
    """Inlier and rejected points of every scanned object, each (n, 2) metres."""
    keep, drop = [], []
    if model.scan is None:
        return np.zeros((0, 2)), np.zeros((0, 2))
    masks = {}
    for comp in model.components:
        if comp.fit is not None and len(comp.sources) == 1:
            masks[comp.sources[0]] = np.asarray(comp.fit.inliers, dtype=bool)
    for obj in model.scan.objects:
        pts = obj.points[:, list(axes)]
        mask = masks.get(obj.id)
        if mask is None or mask.shape[0] != len(pts):
            keep.append(pts)
        else:
            keep.append(pts[mask])
            drop.append(pts[~mask])
    stack = lambda parts: np.vstack(parts) if parts else np.zeros((0, 2))  # noqa: E731
    return stack(keep), stack(drop)


#: Installed font families never used for labels: the placeholder font (a box for every
#: character, not the character) and matplotlib's TeX and STIX math fonts, whose character maps
#: give ordinary code points to math symbols.
_NOT_LABEL_FONTS = re.compile(r"Last Resort|cm[a-z]+10$|STIXSize|STIXNonUnicode")

#: matplotlib's warning for a character no font of a text has (the label box is measured with
#: a placeholder; an SVG viewer still draws the character with its own fonts).
_MISSING_GLYPH = r"Glyph \d+ .* missing from font"


@functools.cache
def _charmap(path) -> frozenset[int]:
    """The code points a font file (a path, or matplotlib's path and face index) maps to glyphs
    (empty when it cannot be read)."""
    from matplotlib.ft2font import FT2Font

    try:
        return frozenset(FT2Font(path).get_charmap())
    except (OSError, RuntimeError, ValueError):
        return frozenset()


@functools.cache
def _regular_faces() -> tuple[tuple[str, str], ...]:
    """(family, file matplotlib draws it from) of every installed family with an upright
    regular face a label may fall back to, sans serif families first, then by name."""
    from matplotlib import font_manager

    names = {
        entry.name
        for entry in font_manager.fontManager.ttflist
        if (entry.style, entry.variant, entry.weight, entry.stretch)
        == ("normal", "normal", 400, "normal")
        and not _NOT_LABEL_FONTS.search(entry.name)
    }
    faces = []
    for name in sorted(names, key=lambda name: ("Sans" not in name, name)):
        # The file a family name resolves to (two installed copies of one family may differ).
        properties = font_manager.FontProperties(family=[name])
        with contextlib.suppress(ValueError):
            faces.append((name, font_manager.findfont(properties, fallback_to_default=False)))
    return tuple(faces)


#: Offsets (in label heights) tried, in order, for a label that would cover one already placed:
#: a vertical pipe and its elbow share a plan position, and their ids printed over each other
#: ("P2" on "P2-P3" read "P2-P32").
LABEL_NUDGES = (0.0, 1.0, -1.0, 2.0, -2.0)


def _separate_labels(fig, texts) -> None:
    """Move each label, in order, up or down by whole label heights (:data:`LABEL_NUDGES`) off
    the labels placed before it; one that fits nowhere stays on its component. The layout is
    made first (without rendering), so the boxes are measured at the picture's final scale."""
    if len(texts) < 2:
        return
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    # The boxes are measured on an Agg canvas (the PNG's; an SVG's text is drawn with the same
    # font metrics); savefig picks its own canvas by format afterwards.
    canvas = fig.canvas if hasattr(fig.canvas, "get_renderer") else FigureCanvasAgg(fig)
    fig.draw_without_rendering()
    renderer = canvas.get_renderer()
    placed = []
    for text in texts:
        box = text.get_window_extent(renderer)
        if any(box.overlaps(other) for other in placed):
            step = box.height * 72.0 / fig.dpi + 1.0  # points: the label's height and a gap
            for nudge in LABEL_NUDGES[1:]:
                text.xyann = (0.0, nudge * step)
                moved = text.get_window_extent(renderer)
                if not any(moved.overlaps(other) for other in placed):
                    box = moved
                    break
            else:
                text.xyann = (0.0, 0.0)
        placed.append(box)


def label_fonts(labels) -> tuple[list[str], frozenset[int]]:
    """The font families to draw ``labels`` with, and the code points they can draw.

    The current default sans-serif font comes first; installed fonts (e.g. Noto Sans CJK) are
    added, in a fixed order, while some label character is still missing, each only when it
    has a character the families before it lack.

    Parameters
    ----------
    labels : iterable of str

    Returns
    -------
    families : list of str
        Empty when the default font draws every character (the labels keep the default).
    drawable : frozenset of int
        Code points some family in the list (or the default font) maps to a glyph.
    """
    from matplotlib import font_manager

    default = font_manager.findfont(font_manager.FontProperties(family=["sans-serif"]))
    drawable = set(_charmap(default))
    missing = {ord(c) for label in labels for c in label} - drawable
    families: list[str] = []
    if missing:
        families.append(font_manager.FontProperties(fname=default).get_name())
        for family, path in _regular_faces():
            gained = missing & _charmap(path)
            if gained and family not in families:
                families.append(family)
                drawable |= gained
                missing -= gained
            if not missing:
                break
        if len(families) == 1:
            families = []  # no installed font helps: the default alone, as for plain ids
    return families, frozenset(drawable)


#: Longest label drawn in a picture, in characters: a longer id (the scan format allows 255) is
#: cut to this many with "..." at the end, since a label wider than the plot squeezed the axes
#: to nothing; the label still links to the component's row, which has the whole id.
LABEL_MAX_CHARS = 32


def drawable_label(component_id: str, drawable=None) -> str:
    """A component id as a picture can draw it: each character that is not printable, or (when
    ``drawable`` is given) that no label font has, written as a Python escape (``\\u7ba1``,
    ``\\U0001f600``, ``\\x07``); ``"管道2"`` with no CJK font installed -> ``"\\u7ba1\\u90532"``.
    Ids longer than :data:`LABEL_MAX_CHARS` are cut to that length, ending in ``...``.
    """

    def shown(c: str) -> str:
        if c.isprintable() and (drawable is None or ord(c) in drawable):
            return c
        return ascii(c)[1:-1]

    if len(component_id) > LABEL_MAX_CHARS:
        return "".join(shown(c) for c in component_id[: LABEL_MAX_CHARS - 3]) + "..."
    return "".join(shown(c) for c in component_id)


_ID_REF = re.compile(r'(id="|href="#|url\(#)([^"\)]+)')


def _prefix_ids(svg: str, prefix: str) -> str:
    """Prefix every id the SVG defines (and the references to them) with ``prefix-``, so
    that several inline SVGs in one page never share an id; links to ids the SVG does not
    define (the labels' ``#obj-...``) are left alone."""
    defined = set(re.findall(r'id="([^"]+)"', svg))

    def rename(match: re.Match) -> str:
        head, name = match.group(1), match.group(2)
        return f"{head}{prefix}-{name}" if name in defined else match.group(0)

    return _ID_REF.sub(rename, svg)


def render_view(
    model: Model,
    view: str,
    *,
    fmt: str = "svg",
    label_limit: int = 200,
    size: tuple[float, float] = (9.0, 6.0),
    dpi: int = 110,
) -> str:
    """Draw one view of the model with the scanned points.

    Parameters
    ----------
    model : Model
        Metres, scan frame (z up).
    view : {"plan", "elevation"}
    fmt : {"svg", "png"}
        ``"svg"``: the ``<svg>`` element as text (no XML prolog, for inline HTML);
        ``"png"``: a ``data:image/png;base64,...`` URI.
    label_limit : int
        Label every component when there are at most this many; otherwise label only those
        with findings (worst first), at most this many.
    size : (float, float), inches
    dpi : int
        PNG resolution (and the rasterised point layers inside an SVG).

    Returns
    -------
    str
    """
    import matplotlib
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure

    if view not in VIEWS:
        raise ValueError(f"unknown view {view!r}; use one of {', '.join(VIEWS)}")
    if fmt not in ("svg", "png"):
        raise ValueError(f"unknown figure format {fmt!r}; use svg or png")
    title, axes, labels = VIEWS[view]
    worst = _worst(model)
    polygons: dict[str | None, list] = {key: [] for key in SEVERITY_COLOURS}
    segments: list = []
    centres: list[tuple[str, np.ndarray, str | None]] = []
    lagging: list = []  # insulated components' cladding, where their points lie
    for comp in model.components:
        outlines = projected_outlines(comp, axes)
        if comp.insulation:
            clad = dataclasses.replace(comp, geometry=envelope(comp))
            lagging.extend(o for o in projected_outlines(clad, axes) if len(o) >= 3)
        severity = worst.get(comp.id)
        for outline in outlines:
            (polygons[severity] if len(outline) >= 3 else segments).append(outline)
        allpts = np.vstack(outlines)
        centres.append((comp.id, allpts.mean(axis=0), severity))

    with matplotlib.rc_context(
        {"svg.fonttype": "none", "svg.hashsalt": f"asbuilt-{view}", "font.size": 8}
    ):
        fig = Figure(figsize=size, dpi=dpi, layout="constrained")
        ax = fig.add_subplot()
        for severity in (None, "info", "warning", "error"):
            polys = polygons[severity]
            if not polys:
                continue
            colour = SEVERITY_COLOURS[severity]
            ax.add_collection(
                PolyCollection(
                    polys,
                    facecolors=colour,
                    edgecolors=colour,
                    alpha=0.45 if severity is None else 0.6,
                    linewidths=0.6,
                    label="no finding" if severity is None else severity,
                    zorder=2 if severity is None else 3,
                )
            )
        if lagging:
            ax.add_collection(
                PolyCollection(
                    lagging,
                    facecolors="none",
                    edgecolors="#8c8677",
                    linestyles="--",
                    linewidths=0.6,
                    label="insulation",
                    zorder=1,
                )
            )
        if segments:
            from matplotlib.collections import LineCollection

            ax.add_collection(LineCollection(segments, colors="#555555", linewidths=1.2, zorder=2))
        keep, drop = _points(model, axes)
        if len(keep):
            ax.scatter(
                keep[:, 0],
                keep[:, 1],
                s=2,
                c="#111111",
                linewidths=0,
                label="scanned points",
                zorder=4,
                rasterized=True,
            )
        if len(drop):
            ax.scatter(
                drop[:, 0],
                drop[:, 1],
                s=10 if len(model.components) <= 100 else 3,  # crowded views: small crosses
                c="#d62728",
                marker="x",
                linewidths=0.7,
                label="rejected by the fit",
                zorder=5,
                rasterized=True,
            )
        if len(centres) <= label_limit:
            labelled = centres
        else:
            flagged = [c for c in centres if c[2] is not None]
            flagged.sort(key=lambda c: severity_rank(c[2]))
            labelled = flagged[:label_limit]
        families, drawable = label_fonts(oid for oid, _, _ in labelled)
        font = {"fontfamily": families} if families else {}
        texts = []
        for oid, centre, _severity in labelled:
            text = ax.annotate(
                # An SVG keeps the characters for the viewer's fonts to draw; a PNG is drawn
                # here, where a character no installed font has would be an empty box.
                drawable_label(oid, None if fmt == "svg" else drawable),
                centre,
                xytext=(0.0, 0.0),
                textcoords="offset points",
                fontsize=7,
                **font,
                ha="center",
                va="center",
                zorder=6,
                parse_math=False,  # ids are drawn literally: "$" starts no mathtext
                bbox={"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none", "alpha": 0.7},
            )
            text.set_url(f"#{anchor(oid)}")
            texts.append(text)
        ax.autoscale_view()
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel(labels[0])
        ax.set_ylabel(labels[1])
        shown = "" if len(labelled) == len(centres) else f" (labels: {len(labelled)} flagged)"
        ax.set_title(title + shown)
        ax.grid(True, linewidth=0.3, alpha=0.5)
        if any(polygons.values()) or len(keep):
            # a fixed place outside the axes: "best" costs seconds on large models
            fig.legend(
                loc="outside lower center", ncols=6, fontsize=7, markerscale=2, frameon=False
            )
        with warnings.catch_warnings():
            # measured on Agg: an SVG label's character no font has (see below) is no concern
            warnings.filterwarnings("ignore", _MISSING_GLYPH, UserWarning)
            _separate_labels(fig, texts)
        buffer = io.BytesIO()
        with warnings.catch_warnings():
            # Only an SVG label can still miss a glyph here (see above): not the user's concern.
            warnings.filterwarnings("ignore", _MISSING_GLYPH, UserWarning)
            if fmt == "svg":
                fig.savefig(buffer, format="svg", metadata={"Date": None})
            else:
                fig.savefig(buffer, format="png", metadata={"Software": None})
        if fmt == "svg":
            text = buffer.getvalue().decode("utf-8")
            return _prefix_ids(text[text.index("<svg") :], view)
        return "data:image/png;base64," + base64.b64encode(buffer.getvalue()).decode("ascii")


def histogram_svg(
    residuals: np.ndarray,
    inliers: np.ndarray | None = None,
    *,
    bins: int = 12,
    width: int = 132,
    height: int = 34,
    title: str | None = None,
) -> str:
    """A small inline SVG histogram of signed residuals (inliers grey, rejected points red).

    Parameters
    ----------
    residuals : ndarray, shape (n,), metres
    inliers : ndarray, shape (n,), bool, optional
        Default: all points are inliers.
    bins : int
        Number of bars over ``[-a, a]`` where ``a`` is the largest absolute residual.
    width, height : int, pixels
    title : str, optional
        Tooltip text (default: the range in mm).

    Returns
    -------
    str
        An ``<svg>`` element; the x axis is centred on zero residual (a tick marks it).
    """
    r = np.asarray(residuals, dtype=np.float64)
    mask = np.ones(r.shape, dtype=bool) if inliers is None else np.asarray(inliers, dtype=bool)
    finite = np.isfinite(r)
    r, mask = r[finite], mask[finite]
    limit = float(np.max(np.abs(r))) if r.size else 0.0
    limit = limit if limit > 0 else 1e-3
    edges = np.linspace(-limit, limit, bins + 1)
    kept, _ = np.histogram(r[mask], bins=edges)
    rejected, _ = np.histogram(r[~mask], bins=edges)
    top = max(int((kept + rejected).max()) if r.size else 0, 1)
    bar = width / bins
    tip = title or f"residuals -{limit * 1000:.1f} .. +{limit * 1000:.1f} mm, {r.size} points"
    parts = [
        f'<svg class="hist" xmlns="http://www.w3.org/2000/svg" width="{width}" '
        f'height="{height}" viewBox="0 0 {width} {height}" role="img">',
        f"<title>{html.escape(tip)}</title>",
    ]
    for i in range(bins):
        x = i * bar
        h_keep = (height - 2) * kept[i] / top
        h_drop = (height - 2) * rejected[i] / top
        if kept[i]:
            parts.append(
                f'<rect x="{x + 0.5:.1f}" y="{height - h_keep:.1f}" width="{bar - 1:.1f}" '
                f'height="{h_keep:.1f}" fill="#777"/>'
            )
        if rejected[i]:
            parts.append(
                f'<rect x="{x + 0.5:.1f}" y="{height - h_keep - h_drop:.1f}" '
                f'width="{bar - 1:.1f}" height="{h_drop:.1f}" fill="#d62728"/>'
            )
    parts.append(
        f'<line x1="{width / 2:.1f}" y1="0" x2="{width / 2:.1f}" y2="{height}" '
        'stroke="#1f77b4" stroke-width="1"/>'
    )
    parts.append("</svg>")
    return "".join(parts)
