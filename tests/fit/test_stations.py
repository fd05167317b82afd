"""One pipe seen from two stations: linked views fitted as one (asbuilt.fit._stations)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from asbuilt.fit import fit
from asbuilt.scan import loads_scan

RADIUS = 0.0603 / 2  # NPS 2
FRONT, BACK = np.array([0.0, 0.0, 1.5]), np.array([0.0, 10.0, 1.5])


def _view(station, x_range, n_along=5, seed=0):
    """15 shots of a pipe along x at (y 5, z 1.5) from ``station``: three beams across the
    half facing it at each of ``n_along`` places, 2 mm range noise along the beams."""
    rng = np.random.default_rng(seed)
    facing = np.arctan2(station[2] - 1.5, station[1] - 5.0)
    points = []
    for x in np.linspace(*x_range, n_along):
        for turn in np.radians([-50.0, 0.0, 50.0]):
            angle = facing + turn
            surface = np.array([x, 5.0 + RADIUS * np.cos(angle), 1.5 + RADIUS * np.sin(angle)])
            beam = surface - station
            beam /= np.linalg.norm(beam)
            points.append(surface + rng.normal(0.0, 0.002) * beam)
    return np.array(points)


def _scan(second_x=(-0.6, 0.6), linked=True, second_station=BACK):
    objects = [
        {"id": "P1", "kind": "cylinder", "points": _view(FRONT, (-0.6, 0.6)).tolist()},
        {"id": "P1b", "kind": "cylinder", "points": _view(BACK, second_x, seed=1).tolist()},
        {"id": "P9", "kind": "sphere", "points": (FRONT + [0, 3, 0] + 0.3 * _unit_cap()).tolist()},
    ]
    if second_station is not None:
        objects[1]["station"] = second_station.tolist()
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"position": FRONT.tolist(), "range_sigma": 0.002},
        "objects": objects,
        "links": [["P1", "P1b"], ["P1b", "P9"]] if linked else [],
    }
    return loads_scan(json.dumps(doc), source="two.json")


def _unit_cap():
    rng = np.random.default_rng(3)
    d = rng.normal(size=(30, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    d[:, 1] = -np.abs(d[:, 1])  # the side facing the front station
    return d


def test_two_linked_views_of_one_pipe_are_fitted_as_one():
    scan = _scan()
    apart = {item.object.id: item.result for item in fit(_scan(linked=False))}
    report = fit(scan)
    assert [item.object.id for item in report.fits] == ["P1", "P9"]
    item = report.get("P1")
    result = item.result
    assert len(item.object.points) == 30 and item.object.extra["fused_with"] == "P1b"
    assert result.primitive.radius == pytest.approx(RADIUS, abs=3 * result.stderr["radius"])
    # two opposite arcs pin the circle down far better than either half
    assert result.stderr["radius"] < 0.5 * min(
        apart["P1"].stderr["radius"], apart["P1b"].stderr["radius"]
    )
    assert "P1 and P1b are one pipe seen from two stations" in result.notes[-1]
    # the link from the second view now starts at the fused object; the scan keeps its points
    assert report.scan.links == (("P1", "P9"),)
    assert [obj.id for obj in report.scan.objects] == ["P1", "P1b", "P9"]


def test_the_fused_pipe_is_one_component_with_both_sources_and_no_clash():
    from asbuilt.pipeline import build_model

    model = build_model(_scan())
    pipes = [c for c in model.components if c.sources[:1] == ("P1",)]
    assert len(pipes) == 1 and pipes[0].sources == ("P1", "P1b")
    assert not [f for f in model.findings if f.slug == "clash"]


@pytest.mark.parametrize(
    "case",
    [
        "not linked",  # the operator did not say they are one: two objects (and AB501)
        "end to end",  # contiguous pipes on one line, each seen from its station
    ],
)
def test_views_that_are_not_one_pipe_stay_apart(case):
    scan = _scan(linked=False) if case == "not linked" else _scan(second_x=(0.65, 1.85))
    report = fit(scan)
    assert [item.object.id for item in report.fits] == ["P1", "P1b", "P9"]
    assert len(report.get("P1").object.points) == 15


def test_a_second_view_without_its_station_is_not_fused():
    # Given the front station, the back view's shots lie behind its own pipe: refused, and
    # nothing is fused with it (one viewpoint cannot have seen both halves).
    report = fit(_scan(second_station=None))
    assert [item.object.id for item in report.fits] == ["P1", "P9"]
    assert [failure.object.id for failure in report.failures] == ["P1b"]
    assert len(report.get("P1").object.points) == 15


def test_the_report_finds_a_fused_view_by_its_own_id_and_says_why_another_is_missing():
    report = fit(_scan(second_station=None))  # P1b refused (behind its own pipe from FRONT)
    assert report.get("P9").object.id == "P9"
    assert report.get("P1b", None) is None and report.get("nope", "x") == "x"
    with pytest.raises(KeyError, match="P1b: its fit was refused: "):
        report.get("P1b")
    with pytest.raises(KeyError, match="nope: no object of the scan has this id"):
        report.get("nope")
    fused = fit(_scan())
    assert fused.get("P1b") is fused.get("P1")


def test_asbuilt_fit_json_lists_the_fused_view_in_its_place(tmp_path, capsys):
    from asbuilt.cli import main

    scan = _scan()
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"position": FRONT.tolist(), "range_sigma": 0.002},
        "objects": [
            {"id": o.id, "kind": o.kind, "points": o.points.tolist()}
            | ({"station": o.station.tolist()} if o.station is not None else {})
            for o in scan.objects
        ],
        "links": [list(link) for link in scan.links],
    }
    path = tmp_path / "two.json"
    path.write_text(json.dumps(doc))
    assert main(["fit", str(path), "--json"]) == 0
    objects = json.loads(capsys.readouterr().out)["objects"]
    assert [o["id"] for o in objects] == ["P1", "P1b", "P9"]
    assert objects[1] == {"id": "P1b", "kind": "cylinder", "fused_into": "P1"}
    assert objects[0]["n_points"] == 30


def test_two_views_are_fused_at_survey_coordinates():
    # A relative test of "one station" (np.allclose) took stations 10 m apart at northing
    # 4,500,000 m for one set-up, so the views stayed two objects (and a duplicate-scan clash).
    shift = np.array([500000.0, 4500000.0, 120.0])
    scan = _scan()
    objects = [
        {
            "id": obj.id,
            "kind": obj.kind,
            "points": (np.asarray(obj.points) + shift).tolist(),
            **(
                {"station": (np.asarray(obj.station) + shift).tolist()}
                if obj.station is not None
                else {}
            ),
        }
        for obj in scan.objects
    ]
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"position": (FRONT + shift).tolist(), "range_sigma": 0.002},
        "objects": objects,
        "links": [list(link) for link in scan.links],
    }
    report = fit(loads_scan(json.dumps(doc), source="far.json"))
    assert [item.object.id for item in report.fits] == ["P1", "P9"]
    assert report.get("P1").object.extra["fused_with"] == "P1b"
