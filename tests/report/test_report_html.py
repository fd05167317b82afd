"""The HTML report: valid structure, every section, links that resolve, escaping."""

import dataclasses
import datetime as dt
import re

import pytest
from report_helpers import ROOT, check_html, known_model, many_findings, tiny_glb

from asbuilt.report import report_data
from asbuilt.report.html import MODEL_VIEWER_URL, gltf_source, html_text, write_html

STAMP = dt.datetime(2026, 11, 21, 7, 0, tzinfo=dt.timezone.utc)


@pytest.fixture(scope="module")
def plant_html(plant_model):
    return html_text(report_data(plant_model, generated=STAMP))


def test_plant_report_is_well_formed_and_links_resolve(plant_html):
    checker = check_html(plant_html)
    assert checker.tags["svg"] >= 2 + 10  # two views and one histogram per fitted object
    for section in ("pictures", "takeoff", "components", "quality", "findings"):
        assert f'id="{section}"' in plant_html


def test_header_names_scan_catalog_units_counts_and_summary(plant_model, plant_html):
    assert "plant corner: structure, pipe spool" in plant_html
    assert "samples/plant.json" in plant_html
    assert "2026-11-21T07:00:00Z" in plant_html
    assert "asme-b36.10m" in plant_html and "ASME B36.10M-2004" in plant_html
    assert f"{len(plant_model.components)} components" in plant_html
    warnings = sum(f.severity == "warning" for f in plant_model.findings)
    assert f'id="count-warning">{warnings} warning' in plant_html


def test_self_contained_no_external_resources(plant_html):
    # nothing is fetched: no src/href to another document, no external CSS or scripts
    assert not re.search(r'(src|href)="(https?:)?//', plant_html)
    assert "<link" not in plant_html
    assert "<script" not in plant_html  # the script only comes with the optional 3-D view


def test_pictures_are_inline_svg_with_points_and_labels(plant_model, plant_html):
    for view in ("plan", "elevation"):
        block = plant_html.split(f'id="view-{view}"', 1)[1].split("</figure>", 1)[0]
        assert block.lstrip(">").startswith("<svg")
        assert "<image" in block  # the rasterised scanned points
        for comp in plant_model.components:
            assert f'href="#obj-{comp.id}"' in block  # every label links to its row


def test_takeoff_tables(plant_html):
    assert '<table class="pipes">' in plant_html
    assert "NPS 8" in plant_html and "ASME B36.10M" in plant_html
    fittings = plant_html.split('<table class="fittings">', 1)[1].split("</table>", 1)[0]
    assert "elbow" in fittings and "90°" in fittings
    solids = plant_html.split('<table class="solids">', 1)[1].split("</table>", 1)[0]
    for oid in ("C1", "TK1", "CH1", "W1", "H1"):
        assert f'href="#obj-{oid}"' in solids
    assert "Total tank/vessel" in solids


def test_quality_rows_have_histograms_and_snap_offsets(plant_model, plant_html):
    quality = plant_html.split('<table class="quality">', 1)[1].split("</table>", 1)[0]
    fitted = [c for c in plant_model.components if c.fit is not None]
    assert quality.count('<svg class="hist"') == len(fitted)
    for comp in fitted:
        assert f'id="fit-{comp.id}"' in quality
    p1 = quality.split('id="fit-P1"', 1)[1].split("</tr>", 1)[0]
    snap = plant_model.component("P1").snap
    assert f"{(snap['od_fit'] - snap['od_catalog']) * 1000:+.1f}" in p1
    assert "σ" in p1 or "&sigma;" in p1


def test_known_model_numbers_in_the_page():
    text = html_text(report_data(known_model(), generated=STAMP))
    check_html(text)
    pipes = text.split('<table class="pipes">', 1)[1].split("</table>", 1)[0]
    for value in ("114.3", "6.02", "2.000", "6.56", "16.08", "32.2"):
        assert f">{value}</td>" in pipes, value
    solids = text.split('<table class="solids">', 1)[1].split("</table>", 1)[0]
    assert ">0.480</td>" in solids and ">5.12</td>" in solids
    assert "No fitted objects." in text


def test_no_findings():
    text = html_text(report_data(known_model(), generated=STAMP))
    assert 'id="no-findings"' in text
    assert 'id="count-error">0 errors' in text
    assert "no errors" in text


def test_many_findings_are_listed_linked_and_escaped():
    model = known_model()
    model = model.replace(findings=many_findings(model, per_object=3))
    text = html_text(report_data(model, generated=STAMP))
    checker = check_html(text)  # every finding link and object link resolves
    items = re.findall(r'<li id="finding-(\d+)">', text)
    assert len(items) == 3 * len(model.components)
    assert "&lt;breaks&gt; rule 0 &amp; needs a look" in text and "<breaks>" not in text
    first = text.split('<li id="finding-1">', 1)[1]
    assert first.startswith('<span class="sev error">')  # worst first
    assert 'id="count-error">5 errors' in text
    assert "(unverifiable)" in text
    # each component row links to its findings
    row = text.split('<tr id="obj-P1">', 1)[1].split("</tr>", 1)[0]
    assert row.count('href="#finding-') == 3
    assert "finding-15" in checker.ids


def test_png_figures(plant_model):
    text = html_text(report_data(plant_model, generated=STAMP), figure_format="png")
    check_html(text)
    assert text.count('<img src="data:image/png;base64,') == 2


def test_optional_3d_view_embeds_the_model_and_loads_only_on_request(tmp_path):
    """The GLB is in the page (a file:// page may not fetch another file, audit D5)."""
    import base64

    glb = tiny_glb(tmp_path / "plant.glb")
    target = tmp_path / "qa.html"
    write_html(report_data(known_model(), generated=STAMP), target, gltf=glb)
    text = target.read_text(encoding="utf-8")
    check_html(text)
    (uri,) = re.findall(r'data-model="data:model/gltf-binary;base64,([^"]+)"', text)
    assert base64.b64decode(uri) == glb.read_bytes()
    assert "embedded in this page" in text
    assert f'data-src="{MODEL_VIEWER_URL}"' in text
    assert "<script src=" not in text  # nothing loads until the button is pressed


def test_a_self_contained_gltf_is_embedded_and_one_with_files_is_linked(tmp_path):
    import json

    alone = tmp_path / "alone.gltf"
    alone.write_text(json.dumps({"asset": {"version": "2.0"}, "buffers": []}), encoding="utf-8")
    linked = tmp_path / "linked.gltf"
    linked.write_text(json.dumps({"asset": {"version": "2.0"}, "buffers": [{"uri": "b.bin"}]}))
    assert gltf_source(alone, tmp_path / "qa.html").startswith("data:model/gltf+json;base64,")
    assert gltf_source(linked, tmp_path / "qa.html") == "linked.gltf"


def test_a_large_model_is_linked_and_the_page_says_it_needs_http(tmp_path, monkeypatch):
    import asbuilt.report._html_gltf as html_module

    (tmp_path / "models").mkdir()
    glb = tiny_glb(tmp_path / "models" / "plant.glb")
    monkeypatch.setattr(html_module, "GLTF_EMBED_LIMIT", glb.stat().st_size - 1)
    target = tmp_path / "qa.html"
    write_html(report_data(known_model(), generated=STAMP), target, gltf=glb)
    text = target.read_text(encoding="utf-8")
    check_html(text)
    assert 'data-model="models/plant.glb"' in text  # relative to the report
    assert "served over HTTP" in text


def test_a_missing_gltf_is_an_error_and_nothing_is_written(tmp_path):
    from asbuilt.errors import ExportError
    from asbuilt.report import write_reports

    with pytest.raises(ExportError, match="glTF file for the 3-D view not found"):
        write_reports(known_model(), [tmp_path / "qa.html"], gltf=tmp_path / "none.glb")
    assert list(tmp_path.iterdir()) == []


def test_ids_with_unusual_characters_are_safe():
    model = known_model()
    comps = list(model.components)
    from asbuilt.model import Component

    odd = comps[3]
    comps[3] = Component('C "1"/<a>', odd.type, odd.geometry, label="odd <id>")
    text = html_text(report_data(model.replace(components=tuple(comps)), generated=STAMP))
    check_html(text)
    assert 'id="obj-C~20~~22~1~22~~2f~~3c~a~3e~"' in text


# Ids that the old anchor (unsafe characters as "_") sent to one anchor, and ids that matplotlib
# read as mathtext (audit D2, D4): all drawn literally, each with its own row and anchor.
ODD_IDS = ("Rohr-Ä1", "Rohr-Ö1", "Rohr-_1", "P 1", "P/1", "P_1", "C$^$1", "$x$", r"\alpha{")


def _odd_model():
    import numpy as np

    from asbuilt.model import Component
    from asbuilt.primitives import Cuboid

    model = known_model()
    extra = tuple(
        Component(oid, "cuboid", Cuboid([3.0 * k, 6.0, 1.5], np.eye(3), [0.4, 0.4, 3.0]))
        for k, oid in enumerate(ODD_IDS)
    )
    return model.replace(components=model.components + extra)


@pytest.mark.parametrize("figure_format", ["svg", "png"])
def test_colliding_and_mathtext_ids_get_rows_anchors_and_literal_labels(figure_format):
    from asbuilt.report.figures import anchor

    model = _odd_model()
    model = model.replace(findings=many_findings(model, per_object=1))
    text = html_text(report_data(model, generated=STAMP), figure_format=figure_format)
    checker = check_html(text)  # unique ids, every #link resolves
    assert len({anchor(oid) for oid in ODD_IDS}) == len(ODD_IDS)
    for oid in ODD_IDS:
        assert anchor(oid) in checker.ids
    if figure_format == "svg":
        plan = text.split('id="view-plan"', 1)[1].split("</figure>", 1)[0]
        for oid in ODD_IDS:  # the label is the id itself, not mathtext glyphs
            assert f">{oid.replace('&', '&amp;')}</text>" in plan, oid


def test_a_finding_naming_no_component_is_not_linked():
    """A design's missing object has no row: its id is shown, not linked (audit D10)."""
    from asbuilt.findings import Finding

    model = known_model()
    missing = Finding(
        "DV101", "design-missing", "error", ("D-MISSING <x>", "P1"), "in the design, not built"
    )
    text = html_text(report_data(model.replace(findings=(missing,)), generated=STAMP))
    check_html(text)  # would fail: a link to #obj-D-MISSING~20~~3c~x~3e~ with no such row
    item = text.split('<li id="finding-1">', 1)[1].split("</li>", 1)[0]
    assert '<span class="missing">D-MISSING &lt;x&gt;</span>' in item
    assert '<a href="#obj-P1">P1</a>' in item


def test_spool_table(plant_model, plant_html):
    spools = plant_html.split('<table class="spools">', 1)[1].split("</table>", 1)[0]
    for spool in plant_model.spools:
        assert f'id="spool-{spool.id}"' in spools
    row = spools.split("</tr>", 2)[1]  # the first body row (after the header row)
    assert "NPS 8" in row
    assert "Laterals" not in spools  # a column only where a spool has a lateral


def test_spool_table_counts_laterals_in_their_own_column():
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    model = build_model(load_scan(ROOT / "samples" / "spool.json"))
    tees = [c for c in model.components if c.type == "tee"]
    assert tees, "the spool sample has a tee to turn into a lateral"
    lateral = {"standard": False, "angle_deg": 45.0, "status": "fitting"}
    components = tuple(
        dataclasses.replace(c, snap=lateral) if c is tees[0] else c for c in model.components
    )
    text = html_text(report_data(model.replace(components=components), generated=STAMP))
    check_html(text)
    spools = text.split('<table class="spools">', 1)[1].split("</table>", 1)[0]
    header = re.findall(r"<th[^>]*>([^<]*)</th>", spools.split("</tr>", 1)[0])
    assert header[header.index("Tees") + 1] == "Laterals"
    spool = next(s for s in model.spools if tees[0].id in s.components)
    row = next(r for r in spools.split("</tr>") if f'id="spool-{spool.id}"' in r)
    cells = re.findall(r"<td[^>]*>([^<]*)</td>", row)
    tees_in_spool = sum(1 for c in tees if c.id in spool.components)
    assert cells[header.index("Laterals")] == "1"
    assert cells[header.index("Tees")] == str(tees_in_spool - 1)


def test_html5lib_parses_without_errors(plant_model):
    """The WHATWG parsing algorithm (html5lib) reports no parse error either (where html5lib
    is installed; the tag-stack check above always runs)."""
    html5lib = pytest.importorskip(
        "html5lib", reason="html5lib not installed (pip install html5lib) for the WHATWG check"
    )
    model = plant_model.replace(findings=many_findings(plant_model, per_object=1))
    for text in (
        html_text(report_data(model, generated=STAMP)),
        html_text(report_data(known_model(), generated=STAMP), gltf="model.glb"),
    ):
        parser = html5lib.HTMLParser(strict=False, namespaceHTMLElements=False)
        parser.parse(text)
        assert parser.errors == []


def test_suggestions_are_numbered_with_the_check_choice_that_accepts_them():
    """A finding's suggestions are an ordered list (the numbers check --accept takes); a change
    names its choice, advice none."""
    from asbuilt.findings import Finding, Suggestion

    between = Finding(
        "AB101",
        "nonstandard-diameter",
        "error",
        ("P1",),
        "OD 126.0 mm is no size",
        suggestions=(
            Suggestion("use NPS 4", {"object": "P1", "field": "nominal", "value": "4"}),
            Suggestion("use NPS 5", {"object": "P1", "field": "nominal", "value": "5"}),
            Suggestion("rescan the pipe"),
        ),
    )
    model = known_model()
    text = html_text(report_data(model.replace(findings=(between,)), generated=STAMP))
    check_html(text)
    item = text.split('<li id="finding-1">', 1)[1].split("</ol>", 1)[0]
    choices = re.findall(r"<li>([^<]*)(?:<span[^>]*>\(accept with <code>--accept ([^<]*))?", item)
    assert choices == [
        ("use NPS 4 ", "AB101@P1:1"),
        ("use NPS 5 ", "AB101@P1:2"),
        ("rescan the pipe", ""),
    ]
