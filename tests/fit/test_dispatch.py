"""The fit dispatcher: kind -> fit function (lazily imported), sigma and errors located per object.

The unit tests replace the per-kind fits with small stand-ins registered in ``FITTERS`` (so the
lazy import path is exercised too); the end-to-end tests at the bottom run the real fits on
exact synthetic surfaces whenever their modules exist.
"""

from __future__ import annotations

import json
import re
import sys
import types
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from sim_tanks import end_on_drum

import asbuilt
from asbuilt.errors import FitError
from asbuilt.fit import (
    FITTERS,
    REFUSED_RELATIVE,
    FitReport,
    FitResult,
    NothingFittedError,
    ObjectFit,
    fit,
    fit_object,
    fit_points,
    fitter_for,
)
from asbuilt.primitives import Sphere
from asbuilt.scan import ScanObject, loads_scan
from asbuilt.scan.model import Scan, Sensor
from asbuilt.tolerances import DEFAULT_TOLERANCES, MIN_POINTS, Tolerances

CALLS: list[dict] = []


def centroid_sphere(points, *, sigma=None, tolerances=DEFAULT_TOLERANCES) -> FitResult:
    """A stand-in fit: sphere at the centroid with the mean distance as radius."""
    CALLS.append({"points": points, "sigma": sigma, "tolerances": tolerances})
    center = points.mean(axis=0)
    distances = np.linalg.norm(points - center, axis=1)
    sphere = Sphere(center, distances.mean())
    return FitResult(
        primitive=sphere,
        residuals=sphere.distance(points),
        inliers=np.ones(len(points), bool),
        stderr={"radius": 0.001},
        sigma=sigma or 0.001,
        sigma_source="sensor" if sigma else "residuals",
        method="centroid (test stand-in)",
    )


def refuse(points, *, sigma=None, tolerances=DEFAULT_TOLERANCES) -> FitResult:
    raise FitError("the points are coplanar; scan the far side too")


def refuse_located(points, *, sigma=None, tolerances=DEFAULT_TOLERANCES) -> FitResult:
    raise FitError("only 2 faces seen", where="faces")


def refuse_points(points, *, sigma=None, tolerances=DEFAULT_TOLERANCES) -> FitResult:
    raise FitError("these points do not determine the radius", where="points")


@pytest.fixture
def stand_ins(monkeypatch):
    """Route every kind to the stand-ins above through a fake module."""
    module = types.ModuleType("stand_in_fits")
    module.centroid_sphere = centroid_sphere
    module.refuse = refuse
    module.refuse_located = refuse_located
    module.refuse_points = refuse_points
    monkeypatch.setitem(sys.modules, "stand_in_fits", module)
    for kind in FITTERS:
        monkeypatch.setitem(FITTERS, kind, ("stand_in_fits", "centroid_sphere"))
    CALLS.clear()
    return module


def octahedron(center=(1.0, 2.0, 3.0), radius=0.5) -> np.ndarray:
    unit = np.vstack([np.eye(3), -np.eye(3)])
    return np.asarray(center) + radius * unit


def scan_of(*kinds: str, units: str = "m", sigma=None) -> Scan:
    objects = tuple(
        ScanObject(id=f"P{i + 1}", kind=kind, points=octahedron(), index=i)
        for i, kind in enumerate(kinds)
    )
    return Scan(units=units, objects=objects, sensor=Sensor(range_sigma=sigma), source="scan.json")


def test_fit_points_dispatches_by_kind(stand_ins):
    tolerances = Tolerances(outlier_cutoff_sigma=2.5)
    result = fit_points("sphere", octahedron().tolist(), sigma=0.003, tolerances=tolerances)
    assert isinstance(result, FitResult)
    assert result.primitive.radius == pytest.approx(0.5)
    (call,) = CALLS
    assert call["sigma"] == 0.003 and call["tolerances"] is tolerances
    assert call["points"].dtype == np.float64 and call["points"].shape == (6, 3)


@pytest.mark.parametrize("kind", ["cone", "", None, "Cylinder"])
def test_unknown_kind(kind):
    with pytest.raises(FitError) as err:
        fit_points(kind, octahedron())
    assert str(err.value) == (
        f"kind: unknown kind {kind!r}; use one of cylinder, cuboid, sphere, plane, hull, auto"
    )


@pytest.mark.parametrize(
    ("points", "message"),
    [
        (np.zeros((5, 2)), "points: The points must have shape (n, 3), not (5, 2)."),
        ([[0, 0, np.nan]] * 5, "points: The points must be finite."),
    ],
)
def test_bad_points(stand_ins, points, message):
    with pytest.raises(FitError) as err:
        fit_points("sphere", points)
    assert str(err.value) == message


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (
            {"sigma": 0.0},
            "sigma: 0 m is not a range finder's noise; give it in metres, 1e-05 to 0.1, or None "
            "to estimate it from the residuals",
        ),
        ({"sigma": -0.002}, "sigma: -0.002 m is not a range finder's noise"),
        ({"sigma": float("nan")}, "sigma: nan m is not a range finder's noise"),
        ({"sigma": 2.0}, "sigma: 2 m is not a range finder's noise"),  # millimetres meant
        ({"sigma": "2 mm"}, "sigma: must be a number in metres, not '2 mm'"),
        ({"viewpoint": [0.0, 0.0]}, "viewpoint: The viewpoint must have shape (3,), not (2,)."),
        ({"viewpoint": [0.0, 0.0, np.inf]}, "viewpoint: The viewpoint must be finite."),
    ],
)
@pytest.mark.parametrize("kind", ["cylinder", "auto", "cuboid"])
def test_bad_sigma_or_viewpoint_is_refused_with_its_name(kind, options, message):
    """The public API once fitted with sigma 0 (every standard error 0), said "within -6 mm"
    for a negative one and raised numpy's broadcast error for a 2-number viewpoint."""
    with pytest.raises(FitError) as err:
        fit_points(kind, octahedron(), **options)
    assert str(err.value).startswith(message)


def test_no_tolerances_means_the_defaults():
    points = octahedron()
    assert fit_points("sphere", points, tolerances=None).primitive.radius == pytest.approx(
        fit_points("sphere", points).primitive.radius
    )


def test_every_kind_has_a_fitter_named_in_the_contract():
    assert set(FITTERS) == set(asbuilt.scan.KINDS)
    for kind, (module, name) in FITTERS.items():
        assert module == f"asbuilt.fit.{kind}" and name == f"fit_{kind}"


def test_fit_object_keeps_the_object_and_requested_kind(stand_ins):
    obj = ScanObject(id="X1", kind="auto", points=octahedron(), index=4)
    item = fit_object(obj, sigma=0.002)
    assert isinstance(item, ObjectFit)
    assert item.object is obj and item.requested == "auto" and item.result.kind == "sphere"
    assert CALLS[0]["sigma"] == 0.002


@pytest.mark.parametrize(
    ("function", "message"),
    [
        ("refuse", "objects[2] (P3): the points are coplanar; scan the far side too"),
        ("refuse_located", "objects[2] (P3): faces: only 2 faces seen"),
        # the object's own field, named as the scan loader names it
        ("refuse_points", "objects[2] (P3).points: these points do not determine the radius"),
    ],
)
def test_fit_errors_are_located_at_the_object(stand_ins, monkeypatch, function, message):
    monkeypatch.setitem(FITTERS, "cuboid", ("stand_in_fits", function))
    obj = ScanObject(id="P3", kind="cuboid", points=octahedron(), index=2)
    with pytest.raises(FitError) as err:
        fit_object(obj)
    assert str(err.value) == message
    with pytest.raises(FitError) as err:
        fit(scan_of("sphere", "plane", "cuboid", "sphere"), strict=True)
    assert str(err.value) == f"scan.json: {message}"
    assert err.value.source == "scan.json"
    report = fit(scan_of("sphere", "plane", "cuboid", "sphere"))  # the others go on
    assert [item.object.id for item in report] == ["P1", "P2", "P4"]
    (failure,) = report.failures
    assert failure.object.id == "P3" and str(failure.error) == f"scan.json: {message}"
    assert failure.message == message.split(": ", 2)[-1]


def test_fit_reports_refused_objects_with_progress(stand_ins, monkeypatch):
    monkeypatch.setitem(FITTERS, "cuboid", ("stand_in_fits", "refuse"))
    seen = []
    report = fit(
        scan_of("cuboid", "sphere", "cuboid"),
        progress=lambda done, total, oid: seen.append((done, total, oid)),
    )
    assert seen == [(1, 3, "P1"), (2, 3, "P2"), (3, 3, "P3")]
    assert [f.object.id for f in report.failures] == ["P1", "P3"]
    assert [item.object.id for item in report.fits] == ["P2"] and len(report) == 1


def test_a_scan_no_object_of_which_fits_is_one_error_naming_them_all(stand_ins, monkeypatch):
    monkeypatch.setitem(FITTERS, "cuboid", ("stand_in_fits", "refuse"))
    with pytest.raises(NothingFittedError) as err:
        fit(scan_of(*["cuboid"] * 8))
    assert str(err.value) == (
        "scan.json: objects[0] (P1): the points are coplanar; scan the far side too No object "
        "of the scan could be fitted: the 7 other objects (P2, P3, P4, P5, P6, ...) were "
        "refused too."
    )
    assert [f.object.id for f in err.value.failures] == [f"P{i}" for i in range(1, 9)]
    with pytest.raises(NothingFittedError) as err:
        fit(scan_of("cuboid"))  # a single object: its own line
    assert (
        str(err.value)
        == "scan.json: objects[0] (P1): the points are coplanar; scan the far side too"
    )


def test_fit_uses_the_sensor_sigma_in_metres(stand_ins):
    text = (
        '{"format": "asbuilt-scan", "version": 1, "units": "mm", "sensor": {"range_sigma": 2},'
        ' "objects": [{"id": "S1", "kind": "sphere", "points": '
        + str((octahedron() * 1000).tolist())
        + "}]}"
    )
    report = fit(loads_scan(text))
    assert CALLS[0]["sigma"] == pytest.approx(0.002)
    # the same rows, in the fit's own order (every order of the shots gives the same fit)
    np.testing.assert_allclose(
        np.unique(CALLS[0]["points"], axis=0), np.unique(octahedron(), axis=0)
    )
    assert report.get("S1").result.sigma_source == "sensor"


def sighted_sphere(points, *, sigma=None, tolerances=DEFAULT_TOLERANCES, viewpoint=None):
    CALLS.append({"viewpoint": viewpoint})
    return centroid_sphere(points, sigma=sigma, tolerances=tolerances)


def test_fit_passes_the_sensor_position_to_fits_that_take_a_viewpoint(stand_ins, monkeypatch):
    stand_ins.sighted_sphere = sighted_sphere
    monkeypatch.setitem(FITTERS, "cuboid", ("stand_in_fits", "sighted_sphere"))
    scan = scan_of("cuboid", "sphere")
    scan = Scan(units="m", objects=scan.objects, sensor=Sensor(position=np.array([1.0, 2, 3])))
    fit(scan)
    np.testing.assert_allclose(CALLS[0]["viewpoint"], [1, 2, 3])
    assert "viewpoint" not in CALLS[2]  # the plain stand-in is called without one


def test_an_objects_own_station_is_its_viewpoint(stand_ins, monkeypatch):
    stand_ins.sighted_sphere = sighted_sphere
    monkeypatch.setitem(FITTERS, "cuboid", ("stand_in_fits", "sighted_sphere"))
    obj = ScanObject(id="C1", kind="cuboid", points=octahedron(), station=np.array([9.0, 8, 7]))
    fit(Scan(units="m", objects=(obj,), sensor=Sensor(position=np.array([1.0, 2, 3]))))
    np.testing.assert_allclose(CALLS[0]["viewpoint"], [9, 8, 7])


def test_fit_without_sensor_sigma_passes_none(stand_ins):
    fit(scan_of("sphere"))
    assert CALLS[0]["sigma"] is None


def test_fit_reports_every_object_in_order_with_progress(stand_ins):
    scan = scan_of("cylinder", "sphere", "auto", "hull")
    seen = []
    report = fit(scan, progress=lambda done, total, oid: seen.append((done, total, oid)))
    assert isinstance(report, FitReport) and len(report) == 4
    assert [item.object.id for item in report] == ["P1", "P2", "P3", "P4"]
    assert [item.requested for item in report] == ["cylinder", "sphere", "auto", "hull"]
    assert seen == [(1, 4, "P1"), (2, 4, "P2"), (3, 4, "P3"), (4, 4, "P4")]
    assert report.scan is scan


def test_fit_passes_tolerances_down(stand_ins):
    tolerances = replace(DEFAULT_TOLERANCES, sigma_floor=5e-4)
    fit(scan_of("sphere", "plane"), tolerances)
    assert all(call["tolerances"] is tolerances for call in CALLS)


def test_package_level_names(stand_ins):
    """``asbuilt.fit(scan)`` works although ``asbuilt.fit`` is also the subpackage's name."""
    assert asbuilt.fit_object is fit_object and asbuilt.fit_points is fit_points
    assert asbuilt.FitReport is FitReport and asbuilt.FitResult is FitResult
    report = asbuilt.fit(scan_of("sphere"))
    assert isinstance(report, FitReport) and report.get("P1").result.kind == "sphere"
    report = asbuilt.fit(scan_of("plane"), DEFAULT_TOLERANCES, progress=None)
    assert len(report) == 1
    from asbuilt.fit.output import fit_report_to_dict

    assert asbuilt.fit_report_to_dict is fit_report_to_dict
    assert asbuilt.fit_report_to_dict(report)["objects"][0]["kind"] == "plane"


# --------------------------------------------------------------------------------------------
# End to end with the real fits (each runs once its module exists)


def _cylinder_points(rng) -> tuple[np.ndarray, dict]:
    s, phi = np.meshgrid(np.linspace(-0.8, 0.8, 6), np.radians(np.linspace(-70, 70, 6)))
    r = 0.05715
    points = np.column_stack(
        [1.0 + s.ravel(), 2.0 - r * np.cos(phi.ravel()), 0.5 + r * np.sin(phi.ravel())]
    )
    return points + rng.normal(0, 2e-4, points.shape), {"radius": r}


def _sphere_points(rng):
    k = np.arange(30) + 0.5
    z = 1 - k / 30
    phi = np.pi * (1 + 5**0.5) * k
    rho = np.sqrt(1 - z * z)
    unit = np.column_stack([rho * np.cos(phi), rho * np.sin(phi), z])
    points = np.array([3.0, 0.0, 1.0]) + 0.3 * unit
    return points + rng.normal(0, 2e-4, points.shape), {"radius": 0.3}


def _plane_points(rng):
    x, y = np.meshgrid(np.linspace(0, 2, 5), np.linspace(0, 1.5, 5))
    points = np.column_stack([x.ravel(), y.ravel(), np.full(25, 2.5)])
    return points + rng.normal(0, 2e-4, points.shape), {"normal_z": 1.0}


def _cuboid_points(rng):
    """Three faces seen (-x, -y, +z), each sampled over 90% of its width."""
    u, v = np.meshgrid(np.linspace(-0.45, 0.45, 4), np.linspace(-0.45, 0.45, 4))
    u, v = u.ravel(), v.ravel()
    size = np.array([1.0, 0.8, 0.6])
    faces = [
        np.column_stack([np.full(16, -size[0] / 2), u * size[1], v * size[2]]),
        np.column_stack([u * size[0], np.full(16, -size[1] / 2), v * size[2]]),
        np.column_stack([u * size[0], v * size[1], np.full(16, size[2] / 2)]),
    ]
    points = np.array([5.0, 5.0, 0.3]) + np.vstack(faces)
    return points + rng.normal(0, 2e-4, points.shape), {"size": size}


def _hull_points(rng):
    return rng.uniform([-1, -1, 0], [1, 1, 2], size=(20, 3)), {}


def _real(kind: str):
    module, _ = FITTERS[kind]
    try:
        __import__(module)
    except ModuleNotFoundError as exc:
        if exc.name == module:
            pytest.skip(f"{module} is not written yet")
        raise


#: (kind, maker of exact synthetic points and their truth) for every kind with a fit.
REAL_SURFACES = [
    ("cylinder", _cylinder_points),
    ("sphere", _sphere_points),
    ("plane", _plane_points),
    ("cuboid", _cuboid_points),
    ("hull", _hull_points),
]


@pytest.mark.parametrize(("kind", "make"), REAL_SURFACES)
def test_real_fits_end_to_end(kind, make):
    _real(kind)
    rng = np.random.default_rng(11)
    points, truth = make(rng)
    objects = (ScanObject(id="A", kind=kind, points=points, index=0),)
    report = fit(Scan(units="m", objects=objects, sensor=Sensor(range_sigma=2e-4)))
    result = report.get("A").result
    assert result.kind == kind and result.n_points == len(points)
    assert result.sigma_source == "sensor" and result.sigma == pytest.approx(2e-4)
    if "radius" in truth:
        assert result.primitive.radius == pytest.approx(truth["radius"], abs=1e-3)
    if "normal_z" in truth:
        assert abs(result.primitive.normal[2]) == pytest.approx(1.0, abs=1e-3)
    if "size" in truth:
        # one face per axis: no size is measured between two faces, each is bounded below by
        # the points' extent (90% of the box) and padded by about one shot spacing at most
        assert result.observed == (False, False, False)
        fitted, true = np.sort(result.primitive.size), np.sort(truth["size"])
        assert np.all(fitted >= 0.9 * true - 5e-3) and np.all(fitted <= 1.2 * true)
    if kind == "hull":
        assert np.all(result.primitive.distance(points) <= 1e-9)


def test_real_auto_end_to_end():
    _real("auto")
    points, truth = _cylinder_points(np.random.default_rng(5))
    item = fit_object(ScanObject(id="X", kind="auto", points=points, index=0))
    assert item.requested == "auto" and item.result.kind == "cylinder"
    assert item.result.primitive.radius == pytest.approx(truth["radius"], abs=1e-3)


@pytest.mark.parametrize("kind", ["cylinder", "plane", "sphere", "cuboid", "auto"])
def test_points_within_the_noise_of_a_line_are_refused(kind):
    # 30 shots along a 1 m line, scattered across it by the 2 mm noise itself: no surface is
    # measured (about half of such scans spread a little more than one sigma).
    rng = np.random.default_rng(7)
    for _ in range(10):
        points = np.column_stack([np.linspace(0, 1, 30), 0.002 * rng.standard_normal((30, 2))])
        with pytest.raises(FitError) as info:
            fit_points(kind, points, sigma=0.002)
        assert info.value.where == "points"
        assert info.value.message.startswith(
            "The points lie within 4 mm (2 x the range noise, 2 mm) of one line (RMS "
        )
        what = 'an object of kind "auto"' if kind == "auto" else f"a {kind}"
        assert info.value.message.endswith(f"{what} needs points spread over its surface.")


def test_the_line_refusal_states_the_limit_it_applied():
    """A 60 mm pipe 10 m away shot over a 70 degree arc with 3.5 mm noise (an independent
    review's ray caster): RMS 6.96 mm across the line, refused at twice the noise. The message
    said "within the range noise (3.5 mm) of one line (RMS 6.96 mm across it)", which reads as
    a contradiction; it now names the 7 mm limit the RMS was held to."""
    rng = np.random.default_rng(3)
    across = rng.standard_normal((30, 2))
    across *= 0.0065 / np.sqrt(np.mean(np.sum(across**2, axis=1)))
    points = np.column_stack([np.linspace(0, 2, 30), across])
    with pytest.raises(FitError) as info:
        fit_points("cylinder", points, sigma=0.0035)
    limit, rms = re.search(
        r"within ([\d.]+) mm .* \(RMS ([\d.]+) mm across it\)", info.value.message
    ).groups()
    assert float(rms) <= float(limit) == pytest.approx(7.0)
    assert "(2 x the range noise, 3.5 mm)" in info.value.message


@pytest.mark.parametrize("kind", ["cylinder", "plane", "sphere", "cuboid", "auto"])
def test_a_stuck_head_without_a_sensor_sigma_is_refused(kind):
    """30 shots at one spot (a stuck pan-tilt head): they scatter along the beam by the range
    noise and across it by the pointing noise only. Without a sensor sigma this was fitted
    (a 2 mm "pipe", audit); the prior noise now refuses it."""
    rng = np.random.default_rng(11)
    beam = np.array([0.6, 0.8, 0.0])
    ranges = 5.0 + 0.002 * rng.standard_normal(30)
    across = 5.0 * np.radians(0.01) * rng.standard_normal((30, 2))
    side, up = np.array([-0.8, 0.6, 0.0]), np.array([0.0, 0.0, 1.0])
    points = ranges[:, None] * beam + across[:, :1] * side + across[:, 1:] * up
    with pytest.raises(FitError) as info:
        fit_points(kind, points)
    assert "the 2 mm noise assumed without a sensor sigma" in info.value.message
    assert info.value.message.endswith(
        "(give sensor.range_sigma if the range finder is more precise). The whole object spans"
        " 6.06 mm: a pan-tilt head stuck on one spot, or a file whose numbers are metres (or"
        ' feet) under other "units".'
    )


def test_few_points_without_a_sigma_keep_every_shot_and_say_so():
    """A sphere of 6 shots without a sensor sigma: one residual degree of freedom gave a
    0.1 mm noise level, rejected a good shot and claimed +-0.1 mm (audit); now no shot is
    rejected and the standard error leans on the 2 mm prior, with a note."""
    rng = np.random.default_rng(5)
    directions = rng.normal(size=(6, 3))
    directions[:, 1] = -np.abs(directions[:, 1])  # the side facing the station
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    points = np.array([0, 6, 1]) + 0.5 * directions
    points += 0.002 * directions * rng.standard_normal((6, 1))
    result = fit_points("sphere", points)
    assert result.n_inliers == 6
    assert result.stderr["radius"] > 0.0005
    assert any("too few to estimate the noise" in note for note in result.notes)


def test_few_points_without_a_sigma_do_not_deny_a_rejection():
    """Six wall shots and one 0.2 m off, no sigma: the fit takes the far one as background and
    says so; the few-points note said in the same breath that no point was rejected (audit)."""
    rng = np.random.default_rng(4)
    points = np.column_stack(
        [rng.uniform(0, 2, 7), 4.0 + rng.normal(0, 0.002, 7), rng.uniform(0, 2, 7)]
    )
    points[3, 1] += 0.2
    result = fit_points("plane", points)
    assert not result.inliers[3]
    few = [note for note in result.notes if "too few to estimate the noise" in note]
    assert few and "no point was rejected" not in few[0]


def test_few_points_with_a_sigma_say_nothing_of_a_missing_sigma():
    """Seven wall shots with a 2 mm sensor sigma, one of them 3 cm off: the fit rejects it and
    may refit with the residuals' wider noise, but the note asking for the scan's sigma (which
    it gives) and saying no point was rejected contradicted both (audit)."""
    rng = np.random.default_rng(3)
    points = np.column_stack(
        [rng.uniform(0, 2, 7), 4.0 + rng.normal(0, 0.004, 7), rng.uniform(0, 2, 7)]
    )
    points[3, 1] += 0.03
    result = fit_points("plane", points, sigma=0.002)
    assert not result.inliers[3]
    assert not any("too few to estimate the noise" in note for note in result.notes)


def test_a_thin_pipe_is_not_taken_for_a_line():
    # NPS 1/2 (OD 21.3 mm) seen over 150 degrees at 2 mm noise: its shots spread about 7 mm.
    rng = np.random.default_rng(3)
    angle = np.radians(rng.uniform(-75, 75, 30))
    radius = 0.01065
    points = np.column_stack(
        [rng.uniform(-1, 1, 30), 5.0 - radius * np.cos(angle), radius * np.sin(angle)]
    )
    points[:, 1] += rng.normal(0, 0.002, 30)
    assert fit_points("cylinder", points, sigma=0.002).kind == "cylinder"


def _helix(count: int, half_arc_deg: float) -> np.ndarray:
    """Noise-free shots (count, 3) metres along a 1 m helix over +-half_arc_deg of a 0.1 m
    pipe."""
    angles = np.radians(np.linspace(-half_arc_deg, half_arc_deg, count))
    return np.column_stack(
        [np.linspace(0, 1, count), 3.0 - 0.1 * np.cos(angles), 1.0 + 0.1 * np.sin(angles)]
    )


def test_a_radius_not_known_to_within_its_size_is_refused():
    # Six shots over 66 degrees: at 1 mm noise they fix neither radius nor axis; the fit came
    # out r 0.80 m +-24 m (true 0.1) and used to stand with a note.
    with pytest.raises(FitError, match="do not determine the cylinder's radius .best fit r "):
        fit_points("cylinder", _helix(6, 33), sigma=0.001)


def _flat_wall(seed: int, noise: float) -> np.ndarray:
    """30 shots (30, 3) metres on a 3 x 2 m wall 6 m away with ``noise`` metres across it."""
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(-1.5, 1.5, 30), rng.uniform(-1.0, 1.0, 30)
    return np.column_stack([u, 6.0 + rng.normal(0, noise, 30), 1.5 + v])


@pytest.mark.parametrize("seed", [2, 3])
def test_a_flat_wall_fitted_as_a_sphere_is_refused(seed):
    # The best sphere is tens of kilometres wide and its radius is not known at all. J^T J was
    # singular to rounding; its inverse or pseudo-inverse reported the radius to a fraction of
    # its size (r 155 km +-84 m for seed 3), so the refusal never fired.
    with pytest.raises(FitError, match="do not determine the sphere's radius"):
        fit_points("sphere", _flat_wall(seed, 0.0001), sigma=0.0001)


@pytest.mark.parametrize("seed", [2, 3])
def test_a_flat_wall_fitted_as_a_cylinder_no_closer_than_its_plane_is_refused(seed):
    # The search stops at r 8-12 km with a local standard error of 19-27% and a larger sum of
    # squares than the wall's plane: the radius is refused for the plane, not the error.
    with pytest.raises(
        FitError, match="do not determine the cylinder's radius .* a plane fits the points about"
    ):
        fit_points("cylinder", _flat_wall(seed, 0.00001), sigma=0.00001)


@pytest.mark.parametrize("seed", [10, 141, 201, 226, 234])
def test_an_end_on_drum_fitted_as_a_huge_cylinder_is_refused_naming_its_end(seed):
    # A horizontal drum on a floor, its axis within 30 degrees of the line of sight: mostly its
    # flat end is seen, with a rim or side shot or two among the fit's inliers. The fit came out
    # r 26-206 m +-12-26% (its curvature set by those shots, or standing out from the 2 mm
    # sigma but not from the scatter the end's shots show), as an independent review's did
    # (r 87.8 m +-11 m). Scans: sim_tanks.end_on_drum.
    points, station, _ = end_on_drum(seed)
    with pytest.raises(FitError, match="a plane fits the points about as closely") as caught:
        fit_points("cylinder", points, sigma=0.002, viewpoint=station)
    assert "end of a drum or tank seen end-on" in str(caught.value)
    assert "a drum's side from a station beside it" in str(caught.value)


@pytest.mark.parametrize("seed", [112, 116, 209])
def test_end_on_drums_seen_enough_from_the_side_are_fitted(seed):
    # Enough of the side is seen among the end's shots: the drum is fitted.
    points, station, truth = end_on_drum(seed)
    result = fit_points("cylinder", points, sigma=0.002, viewpoint=station)
    error = result.primitive.radius - truth["radius"]
    assert abs(error) <= max(3.0 * result.stderr["radius"], 0.05 * truth["radius"])


@pytest.mark.xfail(strict=True, reason="an end left out as a wall leaves a cylinder across it")
def test_an_end_on_drum_whose_end_is_taken_for_a_wall_is_not_caught():
    # The drum's end is left out as a wall behind a pipe, and a cylinder across the drum fits
    # its side's shots: r 0.43 m +-4 mm for 0.80 (docs/fitting.md, what is left).
    points, station, truth = end_on_drum(162)
    try:
        result = fit_points("cylinder", points, sigma=0.002, viewpoint=station)
    except FitError:
        return
    error = result.primitive.radius - truth["radius"]
    assert abs(error) <= max(3.0 * result.stderr["radius"], 0.05 * truth["radius"])


def test_an_undetermined_fit_says_so():
    # Eight shots over 120 degrees: the radius is known to +-65% only, which stands with a note.
    result = fit_points("cylinder", _helix(8, 60), sigma=0.001)
    assert 0.5 < result.stderr["radius"] / result.primitive.radius <= REFUSED_RELATIVE
    note = result.notes[-1]
    assert note.startswith("These points do not determine the cylinder (one standard error: ")
    assert note.endswith("); measure more of its surface, or check its kind.")
    along, phi = np.meshgrid(np.linspace(0, 1, 6), np.radians(np.linspace(-60, 60, 5)))
    well = fit_points(
        "cylinder",
        np.column_stack(
            [along.ravel(), 3.0 - 0.1 * np.cos(phi.ravel()), 1.0 + 0.1 * np.sin(phi.ravel())]
        ),
        sigma=0.001,
    )
    assert not any(n.startswith("These points do not determine") for n in well.notes)


def _rough_pipe(rng, roughness: float, count: int = 40) -> np.ndarray:
    """Shots on the near side of an NPS 4 pipe (OD 114.3 mm) 5 m away: 2 mm range noise plus a
    surface roughness (metres) along the normal."""
    angle = rng.uniform(-1.2, 1.2, count)
    radius = 0.05715 + rng.normal(0, roughness, count) + rng.normal(0, 0.002, count)
    return np.column_stack(
        [5.0 - radius * np.cos(angle), radius * np.sin(angle), rng.uniform(0, 1, count)]
    )


def _rough_wall(rng, roughness: float, count: int = 30) -> np.ndarray:
    depth = 4.0 + rng.normal(0, roughness, count) + rng.normal(0, 0.002, count)
    return np.column_stack([rng.uniform(0, 2, count), depth, rng.uniform(0, 2, count)])


@pytest.mark.parametrize("kind, make", [("cylinder", _rough_pipe), ("plane", _rough_wall)])
def test_points_scattered_wider_than_the_sensor_sigma_keep_their_shots(kind, make):
    # 5 mm roughness on 2 mm noise: the 6 mm inlier test would reject a third of the shots and
    # the standard errors would assume 2 mm. The fit takes the residuals' noise level instead.
    rng = np.random.default_rng(11)
    points = make(rng, 0.005)
    naive = fitter_for(kind)(points, sigma=0.002)
    result = fit_points(kind, points, sigma=0.002, viewpoint=np.zeros(3))
    assert naive.inliers.sum() <= len(points) - 4  # what the sensor sigma alone does
    assert result.inliers.sum() >= len(points) - 1
    assert result.sigma_source == "residuals"
    assert 0.003 < result.sigma < 0.008
    note = result.notes[-1]
    assert note.startswith(f"The points scatter by {result.sigma * 1000:.3g} mm about the {kind}")
    assert "more than the sensor's range sigma (2 mm)" in note


@pytest.mark.parametrize("kind, make", [("cylinder", _rough_pipe), ("plane", _rough_wall)])
def test_points_within_the_sensor_sigma_keep_it(kind, make):
    result = fit_points(kind, make(np.random.default_rng(12), 0.0), sigma=0.002)
    assert result.sigma_source == "sensor" and result.sigma == 0.002
    assert not any("scatter by" in note for note in result.notes)


def test_a_fit_refused_for_outliers_is_retried_with_the_residuals_noise():
    # 8 mm roughness on 2 mm noise: with the sensor sigma alone more than 45% of the shots are
    # outliers (refused); the noise level the shots support (about 8 mm) is within five sigmas.
    rng = np.random.default_rng(3)
    points = _rough_pipe(rng, 0.008)
    from asbuilt.fit.cylinder import fit_cylinder

    for _ in range(20):
        try:
            fit_cylinder(points, sigma=0.002, viewpoint=np.zeros(3))
        except FitError:
            break
        points = _rough_pipe(rng, 0.008)
    else:
        pytest.fail("no refused scan in 20 draws")
    result = fit_points("cylinder", points, sigma=0.002, viewpoint=np.zeros(3))
    assert result.sigma_source == "residuals" and result.sigma > 0.004
    assert "scatter by" in result.notes[-1]


def _two_faces_of_a_column() -> np.ndarray:
    """Two faces of a 0.4 m column 4 m away, 20 shots each with 2 mm noise (metres)."""
    rng = np.random.default_rng(7)
    across = rng.uniform(-0.2, 0.2, (20, 2))
    points = np.vstack(
        [
            np.column_stack([np.full(20, -0.2), across[:, 0], rng.uniform(0, 2, 20)]),
            np.column_stack([across[:, 1], np.full(20, -0.2), rng.uniform(0, 2, 20)]),
        ]
    ) + [4.0, 0.5, 0.0]
    return points + rng.normal(0, 0.002, points.shape)


def test_a_box_labelled_a_cylinder_is_still_refused():
    # Two faces of a 0.4 m column: no cylinder explains them within five sensor sigmas.
    points = _two_faces_of_a_column()
    with pytest.raises(FitError, match="cylinder"):
        fit_points("cylinder", points, sigma=0.002, viewpoint=np.zeros(3))


@pytest.mark.parametrize("kind, make", [("cylinder", _rough_pipe), ("plane", _rough_wall)])
def test_a_sigma_ten_times_optimistic_is_told_not_fatal(kind, make):
    """A 2 mm finder declared 0.2 mm (a survey instrument's data sheet): at 0.2 mm most shots
    are outliers and the fit is refused; without the sigma the shots scatter by 2 mm, ten
    times the sensor's, but a range finder's noise, so the sigma is what is wrong: the fit
    stands with the note (seen in review: pipes and walls refused with 'check that they are
    one cylinder'; scan-format.md promises the residuals' level)."""
    rng = np.random.default_rng(5)
    for _ in range(20):
        points = make(rng, 0.0)
        try:
            fitter_for(kind)(points, sigma=0.0002)
        except FitError:
            break
    else:
        pytest.fail("no refused scan in 20 draws")
    result = fit_points(kind, points, sigma=0.0002)
    assert result.sigma_source == "residuals" and 0.0015 < result.sigma < 0.003
    assert result.n_inliers >= len(points) - 2
    assert "more than the sensor's range sigma (0.2 mm)" in result.notes[-1]


def test_a_box_labelled_a_cylinder_under_an_optimistic_sigma_says_what_the_shots_scatter_by():
    points = _two_faces_of_a_column()
    with pytest.raises(FitError) as refused:
        fit_points("cylinder", points, sigma=0.0002, viewpoint=np.zeros(3))
    message = str(refused.value)
    assert "(Fitted at its own noise level instead of the scan's range sigma, 0.2 mm" in message
    assert "the best cylinder leaves" in message
    assert message.endswith("unless range_sigma is far too optimistic.)")


@pytest.mark.parametrize("station", [True, False])
def test_a_pipe_scanned_past_its_end_is_found_with_the_sensors_sigma(station):
    """An NPS 6 pipe scanned past its free end (15 of 36 shots on the wall behind; independent
    ray caster): with the sensor's 2 mm sigma the robust search had found no cylinder holding
    most points (refused with the station; without it, the retry without the sigma fitted a
    0.8 m cylinder through pipe and wall). The MSAC rescue's half-keep robust line now gives it
    the pipe's axis."""
    scan = json.loads((Path(__file__).parent / "pipe_past_its_end.json").read_text())
    points = np.array(scan["points"])
    viewpoint = np.array(scan["station"]) if station else None
    result = fit_points("cylinder", points, sigma=scan["range_sigma"], viewpoint=viewpoint)
    assert result.primitive.radius == pytest.approx(scan["radius"], abs=0.003)
    assert result.n_inliers >= 20
    assert result.sigma_source == "sensor"


@pytest.mark.parametrize("station", [True, False])
def test_without_a_sigma_the_wall_behind_a_pipe_is_background(station):
    """The same scan without the sensor's sigma: every threshold scaled with the residuals, and
    a 0.8 m cylinder through pipe and wall shots fitted all of them at 9 mm (audit plant: 16 of
    54 pipe fits). The fit with the assumed 2 mm noise rejects the wall shots, 1.4 m from it."""
    scan = json.loads((Path(__file__).parent / "pipe_past_its_end.json").read_text())
    points = np.array(scan["points"])
    viewpoint = np.array(scan["station"]) if station else None
    result = fit_points("cylinder", points, viewpoint=viewpoint)
    assert result.primitive.radius == pytest.approx(scan["radius"], abs=0.003)
    assert result.n_inliers >= 20
    assert result.sigma_source == "residuals" and result.sigma <= 1.5 * scan["range_sigma"]
    if not station:  # with the station the beams already reject the wall shots
        assert "taken as background" in result.notes[-1]
        assert "Give sensor.range_sigma" in result.notes[-1]


@pytest.mark.parametrize("roughness", [0.005, 0.008])
def test_without_a_sigma_a_rough_pipe_keeps_its_shots(roughness):
    """Shots scattered by a rough surface are no background: without a sigma they all stay
    inliers at the residuals' noise level (the assumed-noise fit's rejected shots lie only
    one or two of those noise levels from it)."""
    rng = np.random.default_rng(5)
    for _ in range(5):
        points = _rough_pipe(rng, roughness)
        result = fit_points("cylinder", points, viewpoint=np.zeros(3))
        # no assumed noise; the rows in the order fit_points gives the fits (by distance from
        # their centroid), so that both draw the same random samples
        centred = points - points.mean(axis=0)
        rows = points[np.argsort(np.einsum("ij,ij->i", centred, centred))]
        plain = fitter_for("cylinder")(rows, viewpoint=np.zeros(3))
        assert result.primitive.radius == plain.primitive.radius
        assert result.inliers.sum() >= len(points) - 2
        assert result.sigma > 0.004
        assert not any("background" in note for note in result.notes)


def test_a_wide_cylinder_leaving_shots_inside_it_gives_way_to_the_pipe():
    """An NPS 4 pipe scanned past its free end (9 of 36 shots on the wall, 3 mixed returns;
    independent ray caster), no station: the fit kept a 0.78 m cylinder through pipe and wall
    shots that left shots inside it, since no MSAC circle gave a consistent fit. The last
    resort, the circles across the half-keep robust line, finds the pipe."""
    scan = json.loads((Path(__file__).parent / "pipe_past_its_end_inadmissible.json").read_text())
    result = fit_points("cylinder", np.array(scan["points"]), sigma=scan["range_sigma"])
    assert abs(result.primitive.radius - scan["radius"]) < 3 * result.stderr["radius"]
    assert result.n_inliers >= 22


def refused_with_a_sigma(points, *, sigma=None, tolerances=DEFAULT_TOLERANCES) -> FitResult:
    """A stand-in fit that finds no primitive holding most points at a given sigma, and fits
    at its own noise level without one."""
    if sigma is not None:
        raise FitError("28 of 36 points are outliers to the best sphere")
    found = centroid_sphere(points)
    return replace(found, sigma=0.0025, sigma_source="residuals")


def test_a_fit_found_only_at_the_residuals_noise_is_kept_when_that_noise_is_the_sensors(
    stand_ins, monkeypatch
):
    monkeypatch.setitem(FITTERS, "sphere", (__name__, "refused_with_a_sigma"))
    result = fit_points("sphere", octahedron(), sigma=0.002)
    assert result.sigma == 0.0025 and result.sigma_source == "residuals"
    assert "found no sphere holding most points" in result.notes[-1]
    # ... and beyond WIDER_NOISE_LIMIT sensor sigmas when it is a range finder's noise (2.5 mm
    # within 1.5 x the 2 mm prior: the 0.4 mm sigma is what is wrong) ...
    wider = fit_points("sphere", octahedron(), sigma=0.0004)
    assert wider.sigma == 0.0025 and "more than the sensor's range sigma" in wider.notes[-1]
    # ... but not when it is beyond both (a finder whose noise is 1 mm: 2.5 mm is not its noise)
    finer = replace(DEFAULT_TOLERANCES, prior_range_sigma=0.001)
    with pytest.raises(FitError, match="28 of 36") as refused:
        fit_points("sphere", octahedron(), sigma=0.0004, tolerances=finer)
    assert "the best sphere leaves the shots scattered by 2.5 mm" in str(refused.value)


# --------------------------------------------------------------------------------------------
# Exactly repeated points (a scan file merged with itself, copied rows)


@pytest.mark.parametrize(("kind", "make"), REAL_SURFACES)
def test_repeated_points_count_once(kind, make):
    """Every point given twice is the same measurement: the same primitive and the same
    standard errors as the points given once (counted twice they shrank by sqrt(2)), with
    residuals and inliers still one per given point and a note saying so."""
    _real(kind)
    points, _ = make(np.random.default_rng(3))
    once = fit_points(kind, points, sigma=2e-4)
    doubled = np.vstack([points, points[::-1]])
    twice = fit_points(kind, doubled, sigma=2e-4)
    assert twice.primitive.distance(points) == pytest.approx(once.primitive.distance(points))
    for key, value in once.stderr.items():
        assert np.asarray(twice.stderr[key]) == pytest.approx(np.asarray(value)), key
    assert twice.residuals.shape == twice.inliers.shape == (len(doubled),)
    assert twice.residuals == pytest.approx(twice.primitive.distance(doubled))
    assert twice.inliers[: len(points)].tolist() == twice.inliers[len(points) :][::-1].tolist()
    assert twice.notes[-1].startswith(f"{len(points)} point(s) repeat other points exactly")
    assert not any("repeat other points" in note for note in once.notes)


def test_too_few_distinct_points_say_so():
    points, _ = _cylinder_points(np.random.default_rng(3))
    with pytest.raises(FitError) as info:
        fit_points("cylinder", np.vstack([points[[0, 7, 14, 21]]] * 3))
    assert info.value.where == "points"
    assert info.value.message == (
        "A cylinder needs at least 6 distinct points, got 4 (8 of the 12 points repeat others "
        "exactly); measure more points."
    )


@pytest.mark.parametrize("kind", ["cylinder", "sphere", "plane", "cuboid", "auto"])
def test_points_beyond_floating_point_squares_are_a_fit_error_without_warnings(kind, recwarn):
    # 1e155 m: squares overflow to infinity and LAPACK's eigensolver gives up. The library's
    # caller gets one FitError and no RuntimeWarning noise (the scan loader refuses such
    # coordinates before any fit).
    rng = np.random.default_rng(1)
    directions = rng.normal(size=(30, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    directions[:, 2] = np.abs(directions[:, 2])
    with pytest.raises(FitError, match="failed numerically.*check the points' coordinates"):
        fit_points(kind, directions * 1e155)
    assert not recwarn.list, [str(w.message) for w in recwarn.list]


@pytest.mark.parametrize("kind", ["sphere", "cylinder"])
@pytest.mark.parametrize("seed", range(10))
def test_a_wall_labelled_a_sphere_or_cylinder_is_refused_at_a_real_noise(kind, seed):
    # 2 mm noise: the curvature's extra parameters explain about one sigma^2 of it by chance,
    # which the old one-sigma^2 test let through on a third to two thirds of walls, drawn as
    # kilometre-wide solids; the chi-square test at 1e-3 refuses them.
    with pytest.raises(FitError, match=f"do not determine the {kind}'s radius"):
        fit_points(kind, _flat_wall(seed, 0.002), sigma=0.002, viewpoint=[0.0, 0.0, 1.5])


def test_a_wide_tank_seen_over_a_short_arc_stands():
    # r 5 m seen over 1.2 m (the plane-like regime: radius over three times the extent): it
    # lies 36 mm off its chord's plane, far beyond the test's chi-square threshold.
    rng = np.random.default_rng(0)
    phi, z = rng.uniform(-0.12, 0.12, 30), rng.uniform(0.0, 2.0, 30)
    r = 5.0 + rng.normal(0.0, 0.002, 30)
    points = np.column_stack([r * np.sin(phi), 10.0 - r * np.cos(phi), z])
    result = fit_points("cylinder", points, sigma=0.002, viewpoint=[0.0, 0.0, 1.0])
    assert result.primitive.radius == pytest.approx(5.0, abs=3 * result.stderr["radius"])


def test_a_pipe_in_metres_declared_in_millimetres_is_told_to_check_the_units():
    # A 114 mm pipe 5 m away whose numbers (metres) were read as millimetres: 4 mm across,
    # within the 2 mm noise of a line. The refusal says what the user most likely did.
    angles = np.linspace(-1.2, 1.2, 6)
    along = np.linspace(0.0, 2.0, 5)
    a, z = np.meshgrid(angles, along)
    metres = np.column_stack(
        [0.05715 * np.sin(a.ravel()), 5 - 0.05715 * np.cos(a.ravel()), z.ravel()]
    )
    with pytest.raises(FitError) as info:
        fit_points("cylinder", metres * 0.001, sigma=0.002)
    assert "The whole object spans 2 mm: a pan-tilt head stuck on one spot, or a file whose" in str(
        info.value
    )
    with pytest.raises(FitError) as info:  # a real needle-thin line of shots 2 m long: no hint
        fit_points(
            "cylinder",
            np.column_stack([z.ravel() * 0, 5 + 0 * z.ravel(), z.ravel()])
            + np.random.default_rng(0).normal(0, 1e-4, (30, 3)),
            sigma=0.002,
        )
    assert "spans" not in str(info.value)


def test_a_cuboid_turned_anyhow_in_its_plane_says_so():
    # Seven shots on one face of a box: its in-plane orientation is known to +-31 degrees
    # (a new user's object C5, which flipped between two fits on sub-micrometre changes).
    from asbuilt.fit import _undetermined
    from asbuilt.fit.result import FitResult
    from asbuilt.primitives import Cuboid

    box = Cuboid(center=[0.0, 0.0, 1.0], axes=np.eye(3), size=[0.36, 0.36, 4.9])
    result = FitResult(
        primitive=box,
        residuals=np.zeros(7),
        inliers=np.ones(7, bool),
        stderr={"size": [None, 0.03, 0.79], "axes_deg": [0.57, 30.96, 30.95], "center": 0.39},
        observed=(False, False, False),
        sigma=0.002,
        sigma_source="sensor",
        method="test",
    )
    assert _undetermined(result) == (
        "These points do not determine the cuboid (one standard error: orientation +-31 deg); "
        "measure more of its surface, or check its kind."
    )


# --------------------------------------------------------------------------------------------
# Whole raster rows on a wall behind a pipe (an independent review's ray caster)

_FAR_WALL = {
    scan["name"]: scan
    for scan in json.loads((Path(__file__).parent / "pipes_before_far_wall_rows.json").read_text())[
        "scans"
    ]
}


def test_an_optimistic_sigma_falls_back_to_the_fit_at_the_prior_noise():
    """An NPS 10 pipe at 8 m, 22 of 35 shots on it and two rows on the wall behind, declared
    0.5 mm (real 2 mm): the fit with the sensor's sigma is refused, and the documented retry
    without it had fitted every shot at its own scale (a 1 m cylinder at 62 mm, over five
    sensor sigmas), so the refusal stood. The retry now has the prior-noise rescue of a scan
    without a sigma, which keeps the pipe at its own 2 mm."""
    scan = _FAR_WALL["p013"]
    result = fit_points(
        "cylinder", np.array(scan["points"]), sigma=0.0005, viewpoint=scan["station"]
    )
    assert result.primitive.radius == pytest.approx(scan["radius"], abs=0.003)
    assert result.n_inliers >= scan["on_pipe"] - 1
    assert result.sigma_source == "residuals" and result.sigma < 0.0025
    assert any("scatter by" in note for note in result.notes)
    # The sensor's sigma was given: no note tells the user to give it.
    assert not any("Give sensor.range_sigma" in note for note in result.notes)


def test_without_a_sensor_block_the_wall_rows_behind_a_pipe_are_background():
    """An NPS 8 pipe at 6.9 m, 30 of 42 shots on it and two whole rows on a wall 1.7 m behind;
    no sensor block. The fit at its own scale was a 1 m cylinder through pipe and wall at
    38 mm, +-9.5 mm, every shot an inlier, and the fit at the prior noise found no cylinder
    (the wall rows are more background than the robust starts take). Without the plane of the
    wall rows the prior-noise fit finds the pipe, and the rows lie 1.7 m from it."""
    scan = _FAR_WALL["p027"]
    result = fit_points("cylinder", np.array(scan["points"]))
    assert abs(result.primitive.radius - scan["radius"]) < 3 * result.stderr["radius"]
    assert result.n_inliers >= scan["on_pipe"] - 1
    assert result.sigma < 0.003
    assert any("taken as background" in note for note in result.notes)


def test_a_fit_scattering_over_five_sensor_sigmas_is_settled_at_its_own_noise():
    """An NPS 8 pipe at 3.7 m declared 0.5 mm (real 2 mm, pointing noise on top), 24 of 36
    shots on it: fitted with its wall rows left out at the sensor's sigma, 9 good shots
    beyond 1.5 mm were rejected and the radius came out 7 mm small at +-0.5 mm. Its likeliest
    inliers scatter by 2.9 mm, over five sensor sigmas, which used to leave the fit as it was."""
    scan = _FAR_WALL["p037"]
    result = fit_points(
        "cylinder", np.array(scan["points"]), sigma=0.0005, viewpoint=scan["station"]
    )
    assert abs(result.primitive.radius - scan["radius"]) < 3 * result.stderr["radius"]
    assert result.n_inliers == scan["on_pipe"]
    assert result.sigma_source == "residuals" and result.sigma > 0.002


def test_a_fit_scattering_ten_prior_sigmas_without_a_sigma_says_so(monkeypatch):
    """Without a sensor sigma a fit whose shots scatter by over ten times the prior noise, and
    which no fit at the prior noise replaces, is not presented like any other fit."""
    monkeypatch.setitem(FITTERS, "sphere", (__name__, "wide_without_a_sigma"))
    result = fit_points("sphere", octahedron())
    assert "times the 2 mm noise of a typical range finder" in result.notes[-1]


def wide_without_a_sigma(points, *, sigma=None, tolerances=DEFAULT_TOLERANCES) -> FitResult:
    """A stand-in fit that scatters by 40 mm at its own noise and is refused at the prior."""
    if sigma is not None:
        raise FitError("28 of 36 points are outliers to the best sphere")
    return replace(centroid_sphere(points), sigma=0.04, sigma_source="residuals")


@pytest.mark.parametrize("count", [0, 1, 2])
@pytest.mark.parametrize("kind", sorted(MIN_POINTS))
def test_too_few_points_say_how_many_the_kind_needs(kind, count):
    """Before, 0 points failed "numerically (Eigenvalues did not converge)" and 1-2 points were
    said to lie on one line."""
    points = np.random.default_rng(count).normal(size=(count, 3))
    with pytest.raises(FitError, match=f"needs at least {MIN_POINTS[kind]} points, got {count};"):
        fit_points(kind, points, sigma=0.002)
