"""Calibration files and least-squares recovery of injected calibration errors."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from asbuilt.drivers.calibration import (
    PRIORITY,
    PlaneTarget,
    PointTarget,
    SphereTarget,
    TargetShots,
    calibration_from_dict,
    calibration_to_dict,
    estimate_calibration,
    file_key,
    load_calibration,
    load_targets,
    observable_parameters,
    save_calibration,
)
from asbuilt.drivers.calibration_checks import correlated_pairs
from asbuilt.drivers.kinematics import PARAMETERS, Calibration, aim, beam, forward

from asbuilt.errors import CalibrationError
from asbuilt.sim.raycast import PlaneShape, SphereShape, raycast

NOMINAL = Calibration(base_position=(0.0, 0.0, 1.2))
TRUE = Calibration(
    pan_zero=math.radians(1.2),
    tilt_zero=math.radians(-0.6),
    tilt_axis_offset=(0.0, 0.0, 0.047),
    laser_offset=(0.0, 0.03, 0.04),
    range_offset=0.012,
    range_scale=1.002,
    base_position=(0.0, 0.0, 1.2),
)
PLANES = {
    "floor": ((0, 0, 1), 0.0, (2.5, 0, 0)),
    "front": ((1, 0, 0), 4.0, (0, 0, 1.2)),
    "left": ((0, 1, 0), 3.0, (0, 0, 1.2)),
    "right": ((0, -1, 0), 2.5, (0, 0, 1.2)),
    "ceiling": ((0, 0, 1), 3.0, (2.5, 0, 0)),
}


def _shots(true: Calibration, rng, sigma=0.0005, n=30):
    """Shots at the room's planes and a ball, aimed with the nominal chain, measured with the
    true one (what a real rig with unknown errors does)."""
    out = []
    for name, (normal, offset, shift) in PLANES.items():
        normal = np.array(normal, float)
        helper = np.eye(3)[np.argmin(np.abs(normal))]
        u = np.cross(normal, helper)
        v = np.cross(normal, u)
        pts = normal * offset + np.array(shift) * (1 - np.abs(normal))
        pts = pts + rng.uniform(-1.4, 1.4, (n, 1)) * u + rng.uniform(-1.4, 1.4, (n, 1)) * v
        pan, tilt = aim(NOMINAL, pts)
        origins, directions = beam(true, pan, tilt)
        hit = raycast([PlaneShape(point=normal * offset, normal=normal)], origins, directions)
        raw = (hit.range - true.range_offset) / true.range_scale + rng.normal(0, sigma, n)
        out.append(TargetShots(name, PlaneTarget(tuple(normal), offset), pan, tilt, raw))
    centre, radius = np.array([3.0, 0.6, 1.0]), 0.15
    pts = centre + radius * np.c_[-np.ones(n), rng.uniform(-0.6, 0.6, n), rng.uniform(-0.6, 0.6, n)]
    pan, tilt = aim(NOMINAL, pts)
    origins, directions = beam(true, pan, tilt)
    hit = raycast([SphereShape(center=centre, radius=radius)], origins, directions)
    ok = np.isfinite(hit.range)
    raw = (hit.range[ok] - true.range_offset) / true.range_scale + rng.normal(0, sigma, ok.sum())
    out.append(TargetShots("ball", SphereTarget(radius, tuple(centre)), pan[ok], tilt[ok], raw))
    return out


def test_priority_lists_every_parameter_once():
    assert sorted(PRIORITY) == sorted(PARAMETERS)


def test_file_round_trip(tmp_path):
    cal = Calibration(
        pan_sign=-1,
        pan_zero=0.01,
        tilt_axis_offset=(0.001, 0.002, 0.047),
        laser_offset=(0.01, 0.02, 0.03),
        beam_vertical=-0.001,
        range_offset=0.004,
        range_scale=1.001,
        base_position=(1, 2, 3),
        base_rotation=(0.1, 0.2, 0.3),
    )
    path = tmp_path / "rig.cal.json"
    save_calibration(cal, path, estimate={"residual_rms_m": 0.001})
    back = load_calibration(path)
    for name in PARAMETERS:
        assert back.get(name) == pytest.approx(cal.get(name), abs=1e-15)
    assert back.pan_sign == -1
    doc = json.loads(path.read_text())
    assert doc["format"] == "asbuilt-calibration"
    assert doc["tilt_axis"]["offset_m"] == [0.001, 0.002, 0.047]
    assert doc["estimate"]["residual_rms_m"] == 0.001


def test_missing_sections_default_to_an_ideal_unit():
    assert calibration_from_dict({"format": "asbuilt-calibration"}) == Calibration()


@pytest.mark.parametrize(
    "doc, where",
    [
        ({"pan": {"sign": 2}}, "pan.sign"),
        ({"pan": {"zero": 1}}, "pan.zero"),
        ({"laser": {"offset_m": [1, 2]}}, "laser.offset_m"),
        ({"range": {"scale": "big"}}, "range.scale"),
        ({"range": {"scale": -1}}, "scale must be positive"),
        ({"tilt": 5}, "tilt"),
        ({"bogus": 1}, "bogus"),
        ({"format": "something"}, "expected 'asbuilt-calibration'"),
        ({"version": 2}, "version 2"),
    ],
)
def test_bad_calibration_documents_name_the_field(doc, where):
    with pytest.raises(CalibrationError, match=where.replace(".", r"\.")) as info:
        calibration_from_dict(doc, source="rig.json")
    assert str(info.value).startswith("rig.json")


def test_unreadable_files(tmp_path):
    with pytest.raises(CalibrationError, match="cannot read"):
        load_calibration(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{nope")
    with pytest.raises(CalibrationError, match="not valid JSON"):
        load_calibration(bad)


def test_estimation_recovers_injected_errors():
    shots = _shots(TRUE, np.random.default_rng(1))
    result = estimate_calibration(shots, NOMINAL)
    assert result.initial_rms > 0.01  # the injected errors cost centimetres
    assert result.residual_rms < 0.0007  # down to the 0.5 mm range noise
    est = result.calibration
    for name, tol in [
        ("tilt_axis_offset.z", 0.003),
        ("laser_offset.y", 0.005),
        ("laser_offset.z", 0.005),
        ("range_scale", 0.0006),
        ("tilt_zero", math.radians(0.05)),
    ]:
        assert name in result.free
        assert est.get(name) == pytest.approx(TRUE.get(name), abs=tol), name
        assert result.stderr[name] < tol
    # whatever is not separately observable, the chain as a whole is right: fresh shots agree
    check = _shots(TRUE, np.random.default_rng(7), sigma=0.0)
    for s in check:
        truth = forward(TRUE, s.pan, s.tilt, s.rng)
        assert np.abs(forward(est, s.pan, s.tilt, s.rng) - truth).max() < 0.003


def test_a_single_plane_leaves_unobservable_parameters_fixed():
    shots = [s for s in _shots(TRUE, np.random.default_rng(2)) if s.name == "front"]
    free, fixed = observable_parameters(shots, NOMINAL)
    # sliding the unit within the plane x = 4 changes no distance to it, and a base yaw is the
    # same as a pan zero: those cannot be estimated from this target
    assert {"base_position.y", "base_position.z", "base_rotation.yaw"} <= set(fixed)
    assert set(free) | set(fixed) == set(PRIORITY)
    room_free, _ = observable_parameters(_shots(TRUE, np.random.default_rng(2)), NOMINAL)
    assert len(free) < len(room_free)


def test_unknown_pose_targets_absorb_the_base_pose():
    shots = [
        TargetShots(
            s.name,
            PlaneTarget() if isinstance(s.target, PlaneTarget) else s.target,
            s.pan,
            s.tilt,
            s.rng,
        )
        for s in _shots(TRUE, np.random.default_rng(3))
        if s.name != "ball"
    ]
    result = estimate_calibration(shots, NOMINAL)
    assert not any(name.startswith("base_") for name in result.free)
    assert result.residual_rms < 0.001


def test_point_targets_and_sphere_with_unknown_centre():
    rng = np.random.default_rng(4)
    pts = rng.uniform([2, -2, 0.5], [5, 2, 2.5], (12, 3))
    pan, tilt = aim(TRUE, pts)
    origins, directions = beam(TRUE, pan, tilt)
    raw = (np.linalg.norm(pts - origins, axis=1) - TRUE.range_offset) / TRUE.range_scale
    shots = [
        TargetShots(f"p{i}", PointTarget(tuple(p)), pan[i : i + 1], tilt[i : i + 1], raw[i : i + 1])
        for i, p in enumerate(pts)
    ]
    ball = next(s for s in _shots(TRUE, rng) if s.name == "ball")
    shots.append(TargetShots("ball", SphereTarget(0.15), ball.pan, ball.tilt, ball.rng))
    result = estimate_calibration(shots, NOMINAL)
    assert result.residual_rms < 0.001
    assert set(result.per_target_rms) == {s.name for s in shots}


@pytest.mark.parametrize(
    "kwargs, message",
    [({"free": ["nope"]}, "unknown parameter 'nope'"), ({"fixed": ["bad.x"]}, "unknown parameter")],
)
def test_bad_parameter_names(kwargs, message):
    with pytest.raises(CalibrationError, match=message):
        estimate_calibration(_shots(TRUE, np.random.default_rng(5)), NOMINAL, **kwargs)


def test_too_few_shots():
    s = _shots(TRUE, np.random.default_rng(5))[0]
    few = TargetShots("x", s.target, s.pan[:3], s.tilt[:3], s.rng[:3])
    with pytest.raises(CalibrationError, match="only 3 shots"):
        estimate_calibration([few])


def test_targets_file(tmp_path):
    path = tmp_path / "t.json"
    path.write_text(
        json.dumps(
            {
                "format": "asbuilt-targets",
                "version": 1,
                "targets": {
                    "floor": {"type": "plane", "normal": [0, 0, 2], "offset": 1.0},
                    "wall": {"type": "plane"},
                    "ball": {"type": "sphere", "radius": 0.1, "center": [1, 2, 3]},
                    "prism": {"type": "point", "point": [4, 5, 6]},
                },
            }
        )
    )
    t = load_targets(path)
    assert t["floor"] == PlaneTarget((0.0, 0.0, 1.0), 0.5)
    assert t["wall"] == PlaneTarget()
    assert t["ball"] == SphereTarget(0.1, (1.0, 2.0, 3.0))
    assert t["prism"] == PointTarget((4.0, 5.0, 6.0))


@pytest.mark.parametrize(
    "targets, where",
    [
        ({}, "non-empty 'targets'"),
        ({"a": {"type": "cone"}}, "targets.a.type"),
        ({"a": {"type": "sphere", "radius": -1}}, "targets.a.radius"),
        ({"a": {"type": "plane", "normal": [0, 0]}}, "targets.a.normal"),
        ({"a": {"type": "point"}}, "targets.a.point"),
    ],
)
def test_bad_targets_files(tmp_path, targets, where):
    path = tmp_path / "t.json"
    path.write_text(json.dumps({"targets": targets}))
    with pytest.raises(CalibrationError, match=where.replace(".", r"\.")):
        load_targets(path)


def test_a_scan_given_as_targets_is_named_as_a_scan(tmp_path):
    path = tmp_path / "scan.json"
    path.write_text(json.dumps({"format": "asbuilt-scan", "version": 1, "objects": []}))
    with pytest.raises(CalibrationError) as info:
        load_targets(path)
    assert str(info.value) == (
        f"{path}: is an asbuilt-scan file, not targets; needs a non-empty 'targets' object "
        "naming the known targets (an asbuilt-targets file, see docs/calibration.md)"
    )


# Found by mutation fuzzing (asbuilt calibrate with 1,000 mutated targets and initial
# calibrations, asbuilt scan with 300 mutated --calibration files): each was a traceback (or a
# message naming the file twice) and is now one located line.
@pytest.mark.parametrize(
    "text, message",
    [
        (
            b'{"pan": {"zero_deg": "\xff"}}',
            "is not UTF-8 text (byte 0xff at offset 22); save the calibration file as UTF-8 JSON",
        ),
        ('{"tilt": {"sign": 1' + "0" * 400 + "}}", "tilt.sign: must be a finite number"),
        (
            '{"base": {"rotation_deg": [1' + "0" * 400 + ", 0, 0]}}",
            "base.rotation_deg: must be 3 finite numbers",
        ),
        (
            '{"laser": {"offset_m": [1e308, 0, 0]}}',
            "laser.offset_m: 1e+308 m is beyond any site (at most 1e+08 m); check the number",
        ),
        (
            '{"base": {"rotation_deg": [0, 1e308, 0]}}',
            "base.rotation_deg: 1e+308 degrees is more than a turn; use an angle within +-360",
        ),
        ('{"pan": {"scale": "x"}}', "pan.scale: must be a finite number"),
        ("[" * 100_000, "not valid JSON (nested too deeply)"),
    ],
    ids=[
        "not-utf8",
        "integer-400-digits",
        "vector-integer-400-digits",
        "offset-beyond-any-site",
        "angle-beyond-a-turn",
        "file-named-once",
        "nested-too-deeply",
    ],
)
def test_fuzzed_calibration_files_are_one_located_line(tmp_path, text, message):
    path = tmp_path / "c.json"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(CalibrationError) as info:
        load_calibration(path)
    assert str(info.value) == f"{path}: {message}"


@pytest.mark.parametrize(
    "text, message",
    [
        (
            b'{"targets": {"a\xff": {"type": "plane"}}}',
            "is not UTF-8 text (byte 0xff at offset 15); save the targets file as UTF-8 JSON",
        ),
        (
            '{"targets": {"a": {"type": "plane", "normal": [1' + "0" * 400 + ", 0, 0]}}}",
            "targets.a.normal: must be 3 finite numbers (metres)",
        ),
        (
            '{"targets": {"a": {"type": "plane", "normal": [0, 0, 1], "offset": NaN}}}',
            "targets.a.offset: must be a finite number (metres)",
        ),
        (
            '{"targets": {"a": {"type": "sphere", "radius": NaN}}}',
            "targets.a.radius: must be a positive number (metres)",
        ),
        (
            '{"targets": {"a": {"type": "point", "point": [0, 0, 1e300]}}}',
            "targets.a.point: 1e+300 m is beyond any site (at most 1e+08 m); check the number",
        ),
    ],
    ids=["not-utf8", "integer-400-digits", "offset-nan", "radius-nan", "point-beyond-any-site"],
)
def test_fuzzed_targets_files_are_one_located_line(tmp_path, text, message):
    path = tmp_path / "t.json"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(CalibrationError) as info:
        load_targets(path)
    assert str(info.value) == f"{path}: {message}"


def test_targets_that_do_not_fit_the_shots_fail_the_estimate_in_one_line():
    # fuzzing: a plane target's offset off by metres drove the range scale through zero and
    # the Calibration's own ValueError escaped as a traceback
    shots = _shots(TRUE, np.random.default_rng(5))
    front = shots[1]
    shots[1] = TargetShots(
        front.name, PlaneTarget(front.target.normal, 0.0), front.pan, front.tilt, front.rng
    )
    with pytest.raises(CalibrationError) as info:
        estimate_calibration(shots, NOMINAL)
    assert str(info.value) == (
        "the estimate failed (pan_scale, tilt_scale and range_scale must be positive); the "
        "targets do not fit these shots: check each target's numbers, that the scan's objects "
        "are the targets named, and the initial calibration"
    )


def test_an_initial_scale_near_zero_fails_the_estimate_in_one_line():
    # fuzzing: an initial range scale of 1e-9 let the observability check's finite-difference
    # step take the scale below zero (the Calibration's ValueError escaped as a traceback)
    initial = dataclasses.replace(NOMINAL, range_scale=1e-9)
    with pytest.raises(CalibrationError, match=r"^the estimate failed \(pan_scale, tilt_scale"):
        estimate_calibration(_shots(TRUE, np.random.default_rng(5)), initial)


def test_file_keys_carry_the_files_units():
    keys = {name: file_key(name) for name in PARAMETERS}
    assert keys["pan_zero"] == "pan_zero_deg" and keys["beam_horizontal"] == "beam_horizontal_deg"
    assert keys["tilt_axis_offset.z"] == "tilt_axis_offset_m.z"
    assert keys["base_rotation.yaw"] == "base_rotation_deg.yaw"
    assert keys["range_offset"] == "range_offset_m" and keys["range_scale"] == "range_scale"
    assert len(set(keys.values())) == len(PARAMETERS)


def test_the_estimate_summary_gives_standard_errors_in_degrees_and_metres():
    """The file's angles are degrees: its stderr said 0.003 for a pan zero known to 0.18 deg."""
    result = estimate_calibration(_shots(TRUE, np.random.default_rng(1)), NOMINAL)
    stderr = result.summary()["stderr"]
    assert "pan_zero" not in stderr  # the bare name meant radians (older files)
    assert stderr["pan_zero_deg"] == pytest.approx(math.degrees(result.stderr["pan_zero"]))
    assert stderr["tilt_zero_deg"] == pytest.approx(math.degrees(result.stderr["tilt_zero"]))
    assert stderr["laser_offset_m.z"] == pytest.approx(result.stderr["laser_offset.z"])
    assert stderr["range_scale"] == pytest.approx(result.stderr["range_scale"])
    doc = calibration_to_dict(result.calibration, result.summary())
    back = calibration_from_dict(json.loads(json.dumps(doc)))  # the estimate is no field
    assert np.allclose(back.to_vector(), result.calibration.to_vector(), rtol=0, atol=1e-12)


def _with(shots, name, target):
    return [
        TargetShots(s.name, target, s.pan, s.tilt, s.rng) if s.name == name else s for s in shots
    ]


def test_a_target_off_by_metres_is_refused_by_the_shots_reach():
    """A wall's offset typed 40 for 4 (ball centre unknown): the base went 36 m without a word."""
    shots = _with(_shots(TRUE, np.random.default_rng(3)), "ball", SphereTarget(0.15))
    bad = _with(shots, "front", PlaneTarget((1.0, 0.0, 0.0), 40.0))
    with pytest.raises(CalibrationError, match=r"moves base_position 36 m .* shots at 'front'"):
        estimate_calibration(bad, NOMINAL)


def test_what_one_targets_pose_alone_sets_is_reported_and_a_second_target_checks_it():
    rng = np.random.default_rng(4)
    shots = _with(_shots(TRUE, rng), "front", PlaneTarget((1.0, 0.0, 0.0), 4.3))  # 0.3 m off
    lone = estimate_calibration(_with(shots, "ball", SphereTarget(0.15)), NOMINAL)
    # Only the front wall fixes x: its error moves the base and leaves no residual.
    assert lone.one_target == {"base_position.x": "front"}
    assert lone.calibration.base_position[0] == pytest.approx(0.3, abs=0.01)
    assert lone.residual_rms < 0.001
    assert lone.summary()["one_target"] == {"base_position.x": "front"}
    # The ball's surveyed centre fixes x too: the same error now shows in the residuals.
    both = estimate_calibration(shots, NOMINAL)
    assert "base_position.x" not in both.one_target
    assert max(both.per_target_rms.values()) > 0.01


def test_correlated_pairs_from_a_covariance():
    cov = np.array(
        [[1.0, -0.98, 0.1, 5.0], [-0.98, 1.0, 0.0, 0.0], [0.1, 0.0, 4.0, 0.0]] + [[0] * 4]
    )
    cov[3, 3] = 1.0
    assert correlated_pairs(["a", "b", "c"], cov) == [("a", "b", pytest.approx(-0.98))]
    assert correlated_pairs(["a", "b", "c"], cov, limit=0.05) == [
        ("a", "b", pytest.approx(-0.98)),
        ("a", "c", pytest.approx(0.05)),
    ]


def test_the_summary_lists_correlated_pairs():
    result = estimate_calibration(_shots(TRUE, np.random.default_rng(1)), NOMINAL)
    pairs = result.summary()["correlated"]
    assert all(abs(rho) >= 0.95 and a in result.free and b in result.free for a, b, rho in pairs)
