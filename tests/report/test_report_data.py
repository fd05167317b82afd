"""report_data: header fields, counts, the severity summary and large models."""

import datetime as dt

from report_helpers import known_model, many_findings

from asbuilt.model import Component, Model
from asbuilt.report import report_data, write_reports
from asbuilt.scan.model import Scan, ScanObject

STAMP = dt.datetime(2026, 11, 21, 8, 30, tzinfo=dt.timezone(dt.timedelta(hours=1)))


def test_header_fields():
    data = report_data(known_model(), generated=STAMP)
    assert data.title == "known model"
    assert data.generated == "2026-11-21T07:30:00Z"  # converted to UTC
    assert data.catalog == "asme-b36.10m" and data.catalog_title.startswith("ASME B36.10M")
    assert data.severities == {"error": 0, "warning": 0, "info": 0, "unverifiable": 0}
    assert data.counts["components"] == 5 and data.counts["spools"] == 1
    assert data.quality == () and data.findings == ()


def test_scan_date_and_points_from_the_scan():
    import numpy as np

    obj = ScanObject("C1", "cuboid", np.zeros((3, 3)))
    scan = Scan(units="mm", objects=(obj,), source="site/scan.json", extra={"date": "2026-11-20"})
    model = known_model().replace(scan=scan, name=None)
    data = report_data(model, generated=STAMP)
    assert data.scan_date == "2026-11-20"
    assert data.title == "site/scan.json" and data.source == "site/scan.json"
    assert data.counts["objects"] == 1 and data.counts["points"] == 3
    assert data.units == "m"  # the model's output unit, not the scan's


def test_findings_sorted_worst_first_and_counted():
    model = known_model()
    model = model.replace(findings=tuple(reversed(many_findings(model))))
    data = report_data(model, generated=STAMP)
    ranks = ["error", "warning", "info"]
    order = [ranks.index(f.severity) for f in data.findings]
    assert order == sorted(order)
    assert data.severities == {"error": 5, "warning": 5, "info": 5, "unverifiable": 5}


def test_unknown_catalog_file_still_reports():
    model = known_model().replace(catalog="/nowhere/pipes.csv")
    data = report_data(model, generated=STAMP)
    assert data.catalog_title is None
    (line,) = data.takeoff.pipes
    assert line.size == "4" and line.weight is None  # no material known, no label prefix


def test_a_thousand_components(tmp_path):
    base = known_model()
    components = []
    for k in range(200):
        for comp in base.components:
            components.append(
                Component(
                    f"{comp.id}-{k}",
                    comp.type,
                    comp.geometry,
                    spool=comp.spool and f"{comp.spool}-{k}",
                    nominal=comp.nominal,
                    schedule=comp.schedule,
                )
            )
    model = Model(components=tuple(components), name="large", catalog="asme-b36.10m")
    model = model.replace(findings=many_findings(model, per_object=1)[::7])
    paths = [tmp_path / "qa.html", tmp_path / "qa.csv", tmp_path / "qa.json"]
    write_reports(model, paths, generated=STAMP)
    assert len(paths[1].read_text(encoding="utf-8").splitlines()) == 1001
    html = paths[0].read_text(encoding="utf-8")
    assert html.count('<tr id="obj-') == 1000
    assert "(labels: 143 flagged)" in html
    data = report_data(model, generated=STAMP)
    assert abs(data.takeoff.pipe_length - 400.0) < 1e-9


def test_scan_date_from_acquisition_or_file_time(tmp_path):
    import os

    import numpy as np

    source = tmp_path / "scan.json"
    source.write_text("{}", encoding="utf-8")
    os.utime(source, (1_700_000_000, 1_700_000_000))
    obj = ScanObject("C1", "cuboid", np.zeros((3, 3)))
    scan = Scan(
        units="m",
        objects=(obj,),
        source=str(source),
        extra={"acquisition": {"started": "2026-11-19T10:00:00+00:00"}},
    )
    data = report_data(known_model().replace(scan=scan), generated=STAMP)
    assert data.scan_date == "2026-11-19T10:00:00+00:00"
    assert data.scan_file_modified == "2023-11-14T22:13:20Z"
    bare = report_data(
        known_model().replace(scan=Scan(units="m", objects=(obj,), source=str(source))),
        generated=STAMP,
    )
    assert bare.scan_date is None
    from asbuilt.report.html import html_text

    assert "not recorded in the scan file (file modified 2023-11-14T22:13:20Z)" in html_text(
        bare, label_limit=0
    )
