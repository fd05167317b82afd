"""One box seen from two stations: linked cuboid views fitted as one
(asbuilt.fit._cuboid_stations, through asbuilt.fit.fit)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from asbuilt.fit import fit, fit_points
from asbuilt.fit._cuboid_stations import fuse_box_views, same_box
from asbuilt.scan import loads_scan
from asbuilt.tolerances import DEFAULT_TOLERANCES

SIGMA = 0.002
# a 0.4 x 0.6 x 2.0 m column standing on the floor at the origin
LOW, HIGH = np.array([-0.2, -0.3, 0.0]), np.array([0.2, 0.3, 2.0])


def raster(station, columns, rows, half_pan, seed, low=LOW, high=HIGH, half_tilt=0.25):
    """A pan-tilt raster (``columns`` x ``rows`` beams, pan +-``half_pan`` about the box's
    centre, tilt +-``half_tilt`` radians) from ``station`` (3,) metres: the first hit on the
    box of each beam, 2 mm range noise along it; beams that miss give no shot."""
    rng = np.random.default_rng(seed)
    station = np.asarray(station, dtype=np.float64)
    centre = 0.5 * (low + high) - station
    facing = np.arctan2(centre[1], centre[0])
    shots = []
    for pan in np.linspace(facing - half_pan, facing + half_pan, columns):
        for tilt in np.linspace(-half_tilt, half_tilt, rows):
            beam = np.array([np.cos(tilt) * np.cos(pan), np.cos(tilt) * np.sin(pan), np.sin(tilt)])
            with np.errstate(divide="ignore"):
                a, b = (low - station) / beam, (high - station) / beam
            near, far = np.max(np.minimum(a, b)), np.min(np.maximum(a, b))
            if 0.0 < near <= far:
                shots.append(station + (near + rng.normal(0.0, SIGMA)) * beam)
    return np.array(shots)


def _scan_doc(first, second, stations, linked=True, kinds=("cuboid", "cuboid")):
    return {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"range_sigma": SIGMA},
        "objects": [
            {"id": "C1", "kind": kinds[0], "station": list(stations[0]), "points": first.tolist()},
            {
                "id": "C1b",
                "kind": kinds[1],
                "station": list(stations[1]),
                "points": second.tolist(),
            },
        ],
        "links": [["C1", "C1b"]] if linked else [],
    }


def _fit(doc):
    return fit(loads_scan(json.dumps(doc), source="column.json"))


# (first station, second station, first raster, second raster): corner views of opposite
# corners (all four sides seen), front and back square-on with rasters of different density
# (the independent review's case: "77 of 154 points are outliers").
CASES = [
    ((-4.0, -3.0, 1.0), (4.0, 3.0, 1.0), (9, 11, 0.1), (13, 11, 0.12)),
    ((-4.0, -1.0, 1.0), (4.0, 2.0, 1.0), (9, 11, 0.1), (9, 11, 0.1)),
    ((-5.0, -2.0, 1.5), (3.0, 4.0, 0.5), (9, 11, 0.1), (13, 11, 0.12)),
    ((-4.0, 0.0, 1.0), (4.0, 0.0, 1.0), (9, 11, 0.1), (13, 11, 0.12)),
]


@pytest.mark.parametrize("first_station, second_station, first_raster, second_raster", CASES)
@pytest.mark.parametrize("seed", [0, 1])
def test_two_linked_views_of_one_column_are_fitted_as_one(
    first_station, second_station, first_raster, second_raster, seed
):
    first = raster(first_station, *first_raster, seed=seed)
    second = raster(second_station, *second_raster, seed=seed + 10)
    report = _fit(_scan_doc(first, second, (first_station, second_station)))
    assert [item.object.id for item in report.fits] == ["C1"]
    item = report.get("C1")
    result = item.result
    assert item.object.extra["fused_with"] == "C1b"
    assert len(item.object.points) == len(first) + len(second)
    assert "C1 and C1b are one box seen from two stations" in result.notes[-1]
    assert report.scan.links == ()
    # the front (x) and back faces were seen from the two stations: the depth is measured
    box = result.primitive
    x_row = int(np.abs(box.axes[:, 0]).argmax())
    assert result.observed[x_row]
    assert box.size[x_row] == pytest.approx(0.4, abs=max(0.002, 3 * result.stderr["size"][x_row]))
    # every size is the truth within three standard errors (or 2 mm): measured between
    # opposite faces, or bounded by the shots' extent with the raster gap as its error
    truth = HIGH - LOW
    for row in range(3):
        along = truth[int(np.abs(box.axes[row]).argmax())]
        tolerance = max(0.002, 3 * result.stderr["size"][row])
        assert box.size[row] == pytest.approx(along, abs=tolerance)
    # both sides were seen when each station saw two: the width is measured too
    if first_station[1] != 0.0:
        assert all(
            result.observed[row]
            for row in range(3)
            if row != int(np.argmax(np.abs(box.axes[:, 2])))
        )


def test_each_view_alone_measures_less_than_the_two_together():
    stations = ((-4.0, -3.0, 1.0), (4.0, 3.0, 1.0))
    first, second = raster(stations[0], 9, 11, 0.1, 0), raster(stations[1], 13, 11, 0.12, 1)
    apart = _fit(_scan_doc(first, second, stations, linked=False))
    assert [item.object.id for item in apart.fits] == ["C1", "C1b"]
    for item in apart.fits:
        assert not any(item.result.observed)  # one station sees no opposite pair
    fused = _fit(_scan_doc(first, second, stations)).get("C1").result
    assert sum(fused.observed) == 2


@pytest.mark.parametrize("seed", [0, 1])
def test_a_side_seen_only_on_its_edge_measures_nothing(seed):
    # 6 x 6 rasters: each station's one column on its side face lies on the far edge, where
    # the other station's front meets it; the fused width would rest on no shot of its own
    # (0.593 m for 0.6 +- 0.001 before this check), so the views stay apart
    stations = ((-4.0, -3.0, 1.0), (4.0, 3.0, 1.0))
    first = raster(stations[0], 6, 6, 0.1, seed)
    second = raster(stations[1], 6, 6, 0.12, seed + 10)
    report = _fit(_scan_doc(first, second, stations))
    assert [item.object.id for item in report.fits] == ["C1", "C1b"]


def test_two_columns_side_by_side_are_not_one_box():
    # linked, parallel and square, but 1.5 m apart: no overlap, so two objects stay
    shift = np.array([1.5, 0.0, 0.0])
    stations = ((-4.0, -3.0, 1.0), (5.5, 3.0, 1.0))
    first = raster(stations[0], 9, 11, 0.1, 0)
    second = raster(stations[1], 9, 11, 0.1, 1, low=LOW + shift, high=HIGH + shift)
    report = _fit(_scan_doc(first, second, stations))
    assert [item.object.id for item in report.fits] == ["C1", "C1b"]
    assert report.scan.links == (("C1", "C1b"),)


def test_one_station_or_another_kind_is_left_apart():
    station = (-4.0, -3.0, 1.0)
    first, second = raster(station, 9, 11, 0.1, 0), raster(station, 9, 11, 0.1, 1)
    report = _fit(_scan_doc(first, second, (station, station)))
    assert [item.object.id for item in report.fits] == ["C1", "C1b"]  # one viewpoint
    stations = ((-4.0, -3.0, 1.0), (4.0, 3.0, 1.0))
    first, second = raster(stations[0], 9, 11, 0.1, 0), raster(stations[1], 9, 11, 0.1, 1)
    report = _fit(_scan_doc(first, second, stations, kinds=("cuboid", "auto")))
    assert [item.object.id for item in report.fits] == ["C1", "C1b"]  # auto stays as chosen


def test_boxes_turned_against_each_other_are_not_one_box():
    stations = ((-4.0, -3.0, 1.0), (4.0, 3.0, 1.0))
    first = raster(stations[0], 9, 11, 0.1, 0)
    second = raster(stations[1], 9, 11, 0.1, 1)
    one = fit_points("cuboid", first, sigma=SIGMA, viewpoint=stations[0])
    turn = np.radians(20.0)
    rotation = np.array(
        [[np.cos(turn), -np.sin(turn), 0.0], [np.sin(turn), np.cos(turn), 0.0], [0.0, 0.0, 1.0]]
    )
    turned = second @ rotation.T
    two = fit_points("cuboid", turned, sigma=SIGMA, viewpoint=rotation @ stations[1])
    assert same_box(one, two) is None
    assert fuse_box_views(one, two, first, turned, SIGMA, DEFAULT_TOLERANCES) is None


def test_the_fused_column_is_one_component():
    from asbuilt.pipeline import build_model

    stations = ((-4.0, -3.0, 1.0), (4.0, 3.0, 1.0))
    first, second = raster(stations[0], 9, 11, 0.1, 0), raster(stations[1], 13, 11, 0.12, 1)
    model = build_model(loads_scan(json.dumps(_scan_doc(first, second, stations)), source="c.json"))
    cuboids = [c for c in model.components if c.type == "cuboid"]
    assert [c.id for c in cuboids] == ["C1"]
    assert not [f for f in model.findings if f.code in ("AB501",)]  # no duplicate scan


def test_the_views_are_fused_at_survey_coordinates():
    shift = np.array([500000.0, 4500000.0, 120.0])
    stations = ((-4.0, -3.0, 1.0), (4.0, 3.0, 1.0))
    first, second = raster(stations[0], 9, 11, 0.1, 0), raster(stations[1], 13, 11, 0.12, 1)
    near = _fit(_scan_doc(first, second, stations)).get("C1").result
    far_stations = tuple(tuple(np.add(s, shift)) for s in stations)
    report = _fit(_scan_doc(first + shift, second + shift, far_stations))
    assert [item.object.id for item in report.fits] == ["C1"]
    far = report.get("C1").result
    assert far.primitive.size == pytest.approx(near.primitive.size, abs=1e-6)
    assert far.primitive.center - shift == pytest.approx(near.primitive.center, abs=1e-6)
