"""Pictures: silhouettes against closed forms, the convex hull against Qhull, the SVG/PNG output
and the residual histograms."""

import base64
import dataclasses
import math
import re

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from report_helpers import known_model
from scipy.spatial import ConvexHull

from asbuilt.model import Bend, Component, Model, Straight
from asbuilt.primitives import Cuboid, Sphere
from asbuilt.report.figures import (
    _RING,
    _monotone_chain,
    anchor,
    drawable_label,
    histogram_svg,
    hull_2d,
    label_fonts,
    projected_outlines,
    render_view,
)

PLAN, ELEVATION = (0, 1), (0, 2)


def area(polygon: np.ndarray) -> float:
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def polygon_of_circle(r: float, n: int = _RING) -> float:
    return 0.5 * n * r * r * math.sin(2 * math.pi / n)


@settings(max_examples=60, deadline=None)
@given(
    arrays(
        np.float64,
        st.tuples(st.integers(3, 40), st.just(2)),
        elements=st.floats(-100, 100, allow_nan=False),
    )
)
# A thin triangle that rounding the chain's input to 1e-9 once skewed by 2.6e-6 of its area.
@example(np.array([[13.0, 2.0**-14], [2.0**-14, 0.0], [2.0**-14, 2.0**-14]]))
def test_hull_2d_matches_qhull(points):
    for ours in (hull_2d(points), _monotone_chain(points)):
        check_hull(ours, points)


def check_hull(ours, points):
    try:
        reference = ConvexHull(points)
    except Exception:  # degenerate (collinear) input: ours is a segment or a point
        assert len(ours) <= 2 or area(ours) < 1e-6 * max(1.0, np.ptp(points) ** 2)
        return
    if reference.volume < 1e-9 * max(1.0, np.ptp(points) ** 2):
        return  # nearly collinear: areas at rounding level, where hull codes legitimately differ
    assert area(ours) == pytest.approx(reference.volume, rel=1e-7, abs=1e-9)
    # counter-clockwise
    x, y = ours[:, 0], ours[:, 1]
    assert np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)) > 0


def test_horizontal_pipe_is_a_rectangle_in_plan_and_elevation():
    comp = Component("P1", "pipe", Straight([0, 0, 1], [2, 0, 1], 0.05))
    (plan,) = projected_outlines(comp, PLAN)
    assert area(plan) == pytest.approx(2 * 0.1, rel=1e-9)
    assert plan[:, 0].min() == pytest.approx(0) and plan[:, 0].max() == pytest.approx(2)
    (elev,) = projected_outlines(comp, ELEVATION)
    assert area(elev) == pytest.approx(2 * 0.1, rel=1e-9)


def test_vertical_pipe_is_a_circle_in_plan():
    comp = Component("P1", "pipe", Straight([1, 1, 0], [1, 1, 3], 0.1))
    (plan,) = projected_outlines(comp, PLAN)
    assert area(plan) == pytest.approx(polygon_of_circle(0.1), rel=1e-7)  # hull rounds to 1 nm


def test_column_and_sphere_silhouettes():
    axes = np.array(
        [[math.cos(0.3), math.sin(0.3), 0], [-math.sin(0.3), math.cos(0.3), 0], [0, 0, 1]]
    )
    column = Component("C1", "cuboid", Cuboid([0, 0, 1.5], axes, [0.4, 0.3, 3.0]))
    assert area(projected_outlines(column, PLAN)[0]) == pytest.approx(0.12)
    ball = Component("S1", "sphere", Sphere([0, 0, 0], 0.5))
    assert area(projected_outlines(ball, ELEVATION)[0]) == pytest.approx(
        polygon_of_circle(0.5, 32), rel=1e-9
    )


def test_bend_pieces_follow_the_arc():
    r, lr = 0.05, 0.3
    bend = Component("E1", "elbow", Bend([0, 0, 0], [lr, lr, 0], [0, lr, 0], r))
    pieces = projected_outlines(bend, PLAN)
    assert len(pieces) == 8
    total = sum(area(p) for p in pieces)
    # the quarter annulus between lr - r and lr + r, within the polygonal approximation
    assert total == pytest.approx(math.pi / 4 * ((lr + r) ** 2 - (lr - r) ** 2), rel=0.03)
    corner = np.array([0.0, lr])  # the centre of curvature is outside every piece
    for piece in pieces:
        assert np.min(np.linalg.norm(piece - corner, axis=1)) >= lr - r - 1e-9


def test_svg_views_are_inline_and_ids_do_not_collide():
    model = known_model()
    plan = render_view(model, "plan")
    elevation = render_view(model, "elevation")
    for svg, prefix in ((plan, "plan-"), (elevation, "elevation-")):
        assert svg.startswith("<svg") and svg.rstrip().endswith("</svg>")
        ids = re.findall(r'id="([^"]+)"', svg)
        assert ids and all(i.startswith(prefix) for i in ids)
        for ref in re.findall(r'href="#([^"]+)"', svg):
            assert ref in ids or ref.startswith("obj-")
        for comp in model.components:
            assert f'href="#{anchor(comp.id)}"' in svg
            assert f">{comp.id}<" in svg  # labels are text, not glyph paths
    assert not set(re.findall(r'id="([^"]+)"', plan)) & set(re.findall(r'id="([^"]+)"', elevation))


@settings(max_examples=300, deadline=None)
@given(st.text(max_size=12), st.text(max_size=12))
@example("P 1", "P/1")
@example("Rohr-Ä1", "Rohr-Ö1")
@example("P_1", "P 1")
def test_anchor_is_injective_and_safe(a, b):
    """Two ids never share an anchor, and an anchor uses only URL- and id-safe characters."""
    assert re.fullmatch(r"obj-[A-Za-z0-9_.:~-]*", anchor(a))
    assert (anchor(a) == anchor(b)) == (a == b)


def test_mathtext_ids_are_drawn_literally():
    """'$' in an id starts no mathtext (it crashed the report, audit D2)."""
    model = known_model()
    comps = model.components[:3] + tuple(
        dataclasses.replace(c, id=new)
        for c, new in zip(model.components[3:], ("C$^$1", "$\\frac{1}{2}$"))
    )
    svg = render_view(model.replace(components=comps), "plan")
    assert ">C$^$1</text>" in svg and ">$\\frac{1}{2}$</text>" in svg


def _with_ids(*ids: str) -> Model:
    model = known_model()
    renamed = tuple(dataclasses.replace(c, id=new) for c, new in zip(model.components, ids))
    return model.replace(components=renamed + model.components[len(ids) :])


@pytest.mark.parametrize("fmt", ["svg", "png"])
def test_ids_in_other_scripts_draw_without_warnings(fmt, recwarn):
    """A CJK id printed 'Glyph ... missing from font(s) DejaVu Sans' four times (audit 25)."""
    picture = render_view(_with_ids("管道2", "Rohr-Ä1"), "plan", fmt=fmt)
    assert not recwarn.list, [str(w.message) for w in recwarn.list]
    if fmt == "svg":  # the characters are kept: the viewer's fonts draw them
        assert ">管道2</text>" in picture and ">Rohr-Ä1</text>" in picture


def test_a_label_the_default_font_lacks_is_drawn_with_an_installed_font():
    """U+2312 (arc) is in DejaVu Sans Mono, which matplotlib ships, and not in DejaVu Sans."""
    families, drawable = label_fonts(["P\u23121", "P2"])
    assert families[0] == "DejaVu Sans" and len(families) == 2
    assert 0x2312 in drawable
    svg = render_view(_with_ids("P\u23121"), "plan")
    label = re.search(r'<text style="([^"]*)"[^>]*>P\u23121</text>', svg)
    assert label and f"font-family: 'DejaVu Sans', '{families[1]}'" in label.group(1)
    assert label_fonts(["P1", "Rohr-Ä1"])[0] == []  # the default font draws these


def test_a_label_no_installed_font_draws_is_escaped():
    families, drawable = label_fonts(["管道2"])
    assert (0x7BA1 in drawable) == bool(families)  # a CJK font is used when installed
    assert drawable_label("管道2", frozenset(map(ord, "2"))) == "\\u7ba1\\u90532"
    assert drawable_label("管道2", frozenset(map(ord, "管道2"))) == "管道2"
    assert drawable_label("P\x07\U0001f600") == "P\\x07\U0001f600"  # unprintable only


def test_png_view_is_a_png():
    uri = render_view(known_model(), "plan", fmt="png")
    assert uri.startswith("data:image/png;base64,")
    assert base64.b64decode(uri.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"


def test_label_limit_keeps_flagged_objects():
    from report_helpers import many_findings

    model = known_model()
    flagged = many_findings(model)[:1]  # an error on P1 only
    svg = render_view(model.replace(findings=flagged), "plan", label_limit=2)
    assert 'href="#obj-P1"' in svg and 'href="#obj-C1"' not in svg


def test_unknown_view_or_format():
    with pytest.raises(ValueError, match="unknown view"):
        render_view(known_model(), "side")
    with pytest.raises(ValueError, match="unknown figure format"):
        render_view(known_model(), "plan", fmt="gif")


def test_empty_model_draws():
    assert render_view(Model(components=()), "plan").startswith("<svg")


def bars(svg: str, colour: str) -> list[float]:
    return [float(h) for h in re.findall(rf'height="([\d.]+)" fill="{colour}"', svg)]


def test_histogram_counts_and_colours():
    residuals = np.array([-0.002, -0.001, 0.0, 0.0005, 0.001, 0.0015, 0.02])
    inliers = np.array([True] * 6 + [False])
    svg = histogram_svg(residuals, inliers, bins=4, height=42)
    grey, red = bars(svg, "#777"), bars(svg, "#d62728")
    # bins of width 10 mm over [-20, 20] mm: the 6 inliers share bin 2 ([-10, 0) holds 2,
    # [0, 10) holds 4); the outlier is alone in the last bin
    assert grey == pytest.approx([40 * 2 / 4, 40.0])
    assert red == pytest.approx([40 * 1 / 4])
    assert "<title>residuals -20.0 .. +20.0 mm, 7 points</title>" in svg


def test_histogram_of_nothing_or_zeros():
    assert "0 points" in histogram_svg(np.array([]))
    svg = histogram_svg(np.zeros(5))
    assert len(bars(svg, "#777")) == 1 and not bars(svg, "#d62728")


def test_eccentric_reducer_elevation_is_a_trapezoid_flat_on_top():
    """NPS 6 x 4 eccentric (radii 84.15 / 57.15 mm, H 140 mm), small end raised 27 mm: in
    elevation the end circles are vertical segments, the outline a trapezoid of area
    H (R6 + R4) with a level top at 1 + R6."""
    from asbuilt.model import Reducer

    r6, r4, h = 0.08415, 0.05715, 0.14
    g = Reducer([0, 0, 1], [h, 0, 1 + r6 - r4], r6, r4, offset=[0, 0, r6 - r4])
    (elev,) = projected_outlines(Component("R1", "reducer", g), ELEVATION)
    assert elev[:, 0].min() == pytest.approx(0, abs=1e-12)
    assert elev[:, 0].max() == pytest.approx(h, abs=1e-12)
    assert area(elev) == pytest.approx(h * (r6 + r4), rel=1e-9)
    top = elev[np.isclose(elev[:, 1], 1 + r6)]
    assert sorted(top[:, 0]) == pytest.approx([0, h])


def test_a_long_id_is_cut_in_the_picture_and_links_to_its_row(recwarn):
    """A 255-character id made matplotlib warn "constrained_layout not applied" and squeezed
    the axes to nothing (CLI review)."""
    long_id = "P" * 250 + "-end"
    assert drawable_label(long_id) == "P" * 29 + "..."
    assert drawable_label("P" * 32) == "P" * 32  # at the limit: whole
    svg = render_view(_with_ids(long_id), "plan")
    assert ">" + "P" * 29 + "...</text>" in svg and long_id not in svg.replace(anchor(long_id), "")
    assert not recwarn.list, [str(w.message) for w in recwarn.list]


def test_insulated_components_show_their_cladding_outline():
    # the points of an insulated pipe lie on its cladding: the views draw it, dashed, unfilled
    model = known_model()
    bare = render_view(model, "plan")
    assert ">insulation<" not in bare
    pipe = next(c for c in model.components if c.type == "pipe")
    lagged = model.replace(
        components=tuple(
            dataclasses.replace(c, insulation=0.05) if c is pipe else c for c in model.components
        )
    )
    svg = render_view(lagged, "plan")
    assert ">insulation<" in svg  # its legend entry
    assert "stroke-dasharray" in svg and svg.count("<path") > bare.count("<path")


def test_labels_at_one_plan_position_are_moved_apart():
    """A vertical pipe and its elbow share a plan position: their ids were printed over each
    other ("P2" on "P2-P3" read "P2-P32", seen in review). Each label after the first is moved
    by whole label heights off those placed before it."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from asbuilt.report.figures import _separate_labels

    fig = Figure(figsize=(4, 3), dpi=100, layout="constrained")
    ax = fig.add_subplot()
    ax.set_xlim(0, 10)
    ax.set_ylim(0, 10)
    texts = [
        ax.annotate(label, (5.0, 5.0), xytext=(0.0, 0.0), textcoords="offset points", fontsize=7)
        for label in ("P2", "P2-P3", "P1-P2", "TK1")
    ]
    lone = ax.annotate("C1", (1.0, 1.0), xytext=(0.0, 0.0), textcoords="offset points")
    _separate_labels(fig, [*texts, lone])
    renderer = FigureCanvasAgg(fig).get_renderer()
    boxes = [t.get_window_extent(renderer) for t in texts]
    for i, box in enumerate(boxes):
        for other in boxes[:i]:
            assert not box.overlaps(other)
    assert texts[0].xyann == (0.0, 0.0) and lone.xyann == (0.0, 0.0)  # only movers move
