"""The kinematic chain: hand-computed points, inverse aiming, parameter vectors."""

from __future__ import annotations

import math

import numpy as np
import pytest
from asbuilt.drivers.kinematics import PARAMETERS, Calibration, aim, beam, forward, rotation_base
from hypothesis import given, settings
from hypothesis import strategies as st


@pytest.mark.parametrize(
    "cal, pan_deg, tilt_deg, rng, expected",
    [
        # ideal chain: spherical coordinates, x forward, z up, positive tilt looks up
        (Calibration(), 0, 0, 2.0, (2.0, 0, 0)),
        (Calibration(), 90, 0, 2.0, (0, 2.0, 0)),
        (Calibration(), 0, 90, 2.0, (0, 0, 2.0)),
        (Calibration(), 180, 45, math.sqrt(2), (-1.0, 0, 1.0)),
        # the D46's 4.7 cm tilt axis height and a 2 cm lever arm along the beam, by hand:
        # Rz(90) [ (0, 0, 0.047) + (0.02 + 2, 0, 0) ] = (0, 2.02, 0.047)
        (
            Calibration(tilt_axis_offset=(0, 0, 0.047), laser_offset=(0.02, 0, 0)),
            90,
            0,
            2.0,
            (0, 2.02, 0.047),
        ),
        # tilted up 90 deg: the lever arm z (0.05) points back along -x
        (Calibration(laser_offset=(0, 0, 0.05)), 0, 90, 1.0, (-0.05, 0, 1.0)),
        # range offset and scale: distance = 1.01 * 3 + 0.02
        (Calibration(range_offset=0.02, range_scale=1.01), 0, 0, 3.0, (3.05, 0, 0)),
        # sign, scale and zero of the axes: pan = -1 * 2 * 10 + 30 = 10 deg
        (
            Calibration(pan_sign=-1, pan_scale=2.0, pan_zero=math.radians(30)),
            10,
            0,
            1.0,
            (math.cos(math.radians(10)), math.sin(math.radians(10)), 0),
        ),
        # beam misalignment dv = 90 deg points the beam straight up
        (Calibration(beam_vertical=math.radians(90)), 0, 0, 1.0, (0, 0, 1.0)),
        # base pose: yaw 90 deg and a translation
        (
            Calibration(base_position=(1, 2, 3), base_rotation=(0, 0, math.radians(90))),
            0,
            0,
            1.0,
            (1, 3, 3),
        ),
    ],
)
def test_forward_matches_hand_computed_points(cal, pan_deg, tilt_deg, rng, expected):
    point = forward(cal, [math.radians(pan_deg)], [math.radians(tilt_deg)], [rng])
    assert point.shape == (1, 3)
    assert point[0] == pytest.approx(expected, abs=1e-12)


def test_ignoring_the_offsets_costs_centimetres():
    """protocols.md: a 4.7 cm tilt axis height and a few cm of lever arm matter at 2 m."""
    real = Calibration(tilt_axis_offset=(0, 0, 0.047), laser_offset=(0.0, 0.03, 0.04))
    pan, tilt = np.radians([10, -20, 35]), np.radians([5, -10, 20])
    err = np.linalg.norm(
        forward(real, pan, tilt, [2, 2, 2]) - forward(Calibration(), pan, tilt, [2, 2, 2]), axis=1
    )
    assert np.all(err > 0.04)


def test_beam_directions_are_unit_and_forward_lies_on_the_beam():
    cal = Calibration(
        tilt_axis_offset=(0.01, 0, 0.047),
        laser_offset=(0.02, 0.03, 0.04),
        beam_horizontal=0.01,
        beam_vertical=-0.02,
        tilt_axis_skew=0.003,
        base_rotation=(0.01, 0.02, 0.3),
    )
    pan, tilt = np.radians([0, 45, -60]), np.radians([0, 10, -30])
    origins, directions = beam(cal, pan, tilt)
    assert np.linalg.norm(directions, axis=1) == pytest.approx(np.ones(3))
    pts = forward(cal, pan, tilt, [1.0, 2.0, 3.0])
    assert np.linalg.norm(pts - origins, axis=1) == pytest.approx([1.0, 2.0, 3.0])


def test_base_rotation_is_a_rotation():
    r = rotation_base(Calibration(base_rotation=(0.3, -0.2, 1.1)))
    assert r @ r.T == pytest.approx(np.eye(3), abs=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)


calibrations = st.builds(
    Calibration,
    pan_sign=st.sampled_from([1, -1]),
    tilt_sign=st.sampled_from([1, -1]),
    pan_zero=st.floats(-0.2, 0.2),
    tilt_zero=st.floats(-0.2, 0.2),
    tilt_axis_offset=st.tuples(*[st.floats(-0.05, 0.05)] * 3),
    laser_offset=st.tuples(*[st.floats(-0.05, 0.05)] * 3),
    beam_horizontal=st.floats(-0.02, 0.02),
    beam_vertical=st.floats(-0.02, 0.02),
    range_offset=st.floats(-0.05, 0.05),
    range_scale=st.floats(0.98, 1.02),
    base_position=st.tuples(*[st.floats(-1, 1)] * 3),
    base_rotation=st.tuples(*[st.floats(-0.3, 0.3)] * 3),
)


@settings(max_examples=60, deadline=None)
@given(
    cal=calibrations,
    pan=st.floats(-2.5, 2.5),
    tilt=st.floats(-0.9, 0.9),
    dist=st.floats(1.0, 30.0),
)
def test_aim_inverts_forward(cal, pan, tilt, dist):
    target = forward(cal, [pan], [tilt], [dist])
    p, t = aim(cal, target)
    origins, directions = beam(cal, p, t)
    v = target - origins
    miss = np.linalg.norm(np.cross(v, directions), axis=1)
    assert miss[0] < 1e-9
    assert float(np.sum(v * directions)) > 0  # the target is ahead, not behind


@pytest.mark.parametrize("name", PARAMETERS)
def test_parameter_vector_round_trip(name):
    cal = Calibration().with_vector([name], [0.5 if "scale" not in name else 1.5])
    assert cal.get(name) == pytest.approx(0.5 if "scale" not in name else 1.5)
    assert cal.to_vector([name])[0] == cal.get(name)


@pytest.mark.parametrize(
    "kwargs",
    [{"pan_sign": 0}, {"range_scale": 0.0}, {"laser_offset": (1, 2)}, {"pan_zero": float("nan")}],
)
def test_invalid_calibration_values(kwargs):
    with pytest.raises(ValueError):
        Calibration(**kwargs)
