"""The HTML report as a person sees it: headless Chromium loads it with no console errors, no
network requests, and shows the pictures, the take-off table and the findings.

Skipped with a clear message where Chromium is not installed; under CI (``CI=true``) a missing
Chromium fails instead (see the ``browser`` fixture in conftest.py).
"""

import datetime as dt

import pytest
from report_helpers import ROOT, known_model, many_findings, tiny_glb

from asbuilt.report import write_report

STAMP = dt.datetime(2026, 11, 21, 7, 0, tzinfo=dt.timezone.utc)


def test_the_console_check_catches_errors(browser, tmp_path):
    # the same checks on a page known to be broken must report its problems
    page_file = tmp_path / "broken.html"
    page_file.write_text(
        '<!DOCTYPE html><html><head><title>x</title></head><body><img src="missing.png">'
        '<script>console.error("planted"); notAFunction();</script></body></html>',
        encoding="utf-8",
    )
    problems = browser.open(page_file.as_uri()).problems()
    text = "\n".join(problems)
    assert "planted" in text
    assert "notAFunction" in text
    assert "ERR_FILE_NOT_FOUND" in text


@pytest.fixture(scope="module")
def plant_page(browser, plant_model, tmp_path_factory):
    path = tmp_path_factory.mktemp("browser") / "plant.html"
    write_report(plant_model, path, generated=STAMP, gltf=tiny_glb(path.with_suffix(".glb")))
    page = browser.open(path.as_uri(), width=1280, height=2000)
    page.screenshot(path.with_suffix(".png"))  # to look at when a test fails
    return page


def test_loads_without_console_errors_or_network(plant_page):
    assert plant_page.problems() == []
    external = [u for u in plant_page.requests() if not u.startswith(("file:", "data:"))]
    assert external == []
    assert plant_page.evaluate("document.readyState") == "complete"


def test_pictures_are_rendered(plant_page):
    sizes = plant_page.evaluate(
        "Array.from(document.querySelectorAll('#pictures figure > svg'))"
        ".map(s => [s.getBoundingClientRect().width, s.getBoundingClientRect().height])"
    )
    assert len(sizes) == 2
    for width, height in sizes:
        assert width > 500 and height > 250
    # the points layer (an embedded raster image) decoded
    images = plant_page.evaluate(
        "Array.from(document.querySelectorAll('#pictures svg image')).map(i => i.getBBox().width)"
    )
    assert images and all(w > 50 for w in images)
    labels = plant_page.evaluate(
        "Array.from(document.querySelectorAll('#view-plan svg a text, #view-plan svg a')).length"
    )
    assert labels >= 15


def test_takeoff_table_is_visible(plant_page):
    cells = plant_page.evaluate(
        "Array.from(document.querySelectorAll('table.pipes tbody tr:first-child td'))"
        ".map(td => td.innerText)"
    )
    assert cells[0] == "NPS 8" and cells[1] == "STD"
    visible = plant_page.evaluate(
        "(() => { const r = document.querySelector('table.pipes').getBoundingClientRect();"
        " return r.width > 300 && r.height > 40; })()"
    )
    assert visible


def test_findings_are_shown_and_linked(browser, tmp_path):
    """The structural bay's real findings (its column C4 leans 12.8 mm over 4 m, more than
    AISC 303's 8 mm, known to +-2.9 mm: an unverifiable warning) are listed, and a finding's
    object link scrolls to that component's row. (The plant sample checks clean.)"""
    from asbuilt.pipeline import build_model
    from asbuilt.scan import load_scan

    model = build_model(load_scan(ROOT / "samples" / "structural-bay.json"))
    assert model.findings, "the structural bay sample should have a finding to show"
    path = tmp_path / "bay.html"
    write_report(model, path, generated=STAMP)
    page = browser.open(path.as_uri(), width=1280, height=2000)
    items = page.evaluate(
        "Array.from(document.querySelectorAll('ol.findings > li')).map(li => li.innerText)"
    )
    assert len(items) == len(model.findings)
    for finding in model.findings:
        assert any(finding.message in item for item in items)
    # following a finding's object link scrolls to that component's row
    target = page.evaluate(
        "(() => { const a = document.querySelector('ol.findings a[href^=\"#obj-\"]');"
        " a.click(); return location.hash; })()"
    )
    assert target.startswith("#obj-")
    assert page.evaluate(f"!!document.querySelector('{target}')")
    assert page.problems() == []


def test_many_findings_page_is_clean(browser, tmp_path):
    model = known_model()
    model = model.replace(findings=many_findings(model))
    path = tmp_path / "many.html"
    write_report(model, path, generated=STAMP)
    page = browser.open(path.as_uri())
    assert page.problems() == []
    assert page.evaluate("document.querySelectorAll('ol.findings > li').length") == 15


def test_3d_view_button_fails_gracefully_or_loads(browser, plant_model, tmp_path):
    import time

    path = tmp_path / "plant.html"
    write_report(plant_model, path, generated=STAMP, gltf=tiny_glb(tmp_path / "plant.glb"))
    plant_page = browser.open(path.as_uri())  # a page of its own: the click changes it
    assert plant_page.problems() == []
    plant_page.evaluate("document.getElementById('load-3d').click()")
    deadline = time.monotonic() + 20
    state = None
    while time.monotonic() < deadline:
        state = plant_page.evaluate(
            "[document.getElementById('viewer-status').textContent,"
            " !!document.querySelector('#viewer-slot model-viewer')]"
        )
        if state[1] or "could not be loaded" in state[0]:
            break
        time.sleep(0.2)
    status, viewer = state
    # offline the script fails and the page says so; online the viewer element appears
    assert viewer or "could not be loaded" in status, state
    assert plant_page.evaluate("document.getElementById('load-3d').disabled")
    exceptions = [p for p in plant_page.problems() if p.startswith("exception")]
    assert exceptions == []
    # the rest of the page is untouched
    assert plant_page.evaluate("document.querySelectorAll('#pictures figure > svg').length") == 2


def _fetch_model(page) -> str:
    """Fetch the 3-D view's model as the viewer would; "bytes N" or "failed ..."."""
    import time

    page.evaluate(
        "window.got = null; fetch(document.getElementById('load-3d').dataset.model)"
        ".then(r => r.arrayBuffer()).then(b => { window.got = 'bytes ' + b.byteLength; })"
        ".catch(e => { window.got = 'failed ' + e; })"
    )
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline:
        got = page.evaluate("window.got")
        if got is not None:
            return got
        time.sleep(0.1)
    return "timed out"


def test_3d_model_is_readable_from_a_page_opened_from_disk(browser, tmp_path, monkeypatch):
    """The embedded model loads in a file:// page; a linked one does not (audit D5: browsers
    refuse a file:// page's fetch of another file, so the page says it needs HTTP)."""
    import asbuilt.report._html_gltf as html_module

    glb = tiny_glb(tmp_path / "plant.glb")
    embedded = tmp_path / "embedded.html"
    write_report(known_model(), embedded, generated=STAMP, gltf=glb)
    assert _fetch_model(browser.open(embedded.as_uri())) == f"bytes {glb.stat().st_size}"
    monkeypatch.setattr(html_module, "GLTF_EMBED_LIMIT", 0)
    linked = tmp_path / "linked.html"
    write_report(known_model(), linked, generated=STAMP, gltf=glb)
    assert _fetch_model(browser.open(linked.as_uri())).startswith("failed")
