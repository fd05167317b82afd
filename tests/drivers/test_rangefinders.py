"""Dimetix DLS and Jenoptik LDM drivers: scripted replies, error codes, simulators over URLs."""

from __future__ import annotations

import math

import pytest
from asbuilt.drivers.dimetix import DimetixDLS
from asbuilt.drivers.ldm import LDM4x
from asbuilt.drivers.ptu import PanTiltUnit
from asbuilt.drivers.rangefinder import (
    RangeFinderCommandError,
    RangeFinderError,
    SignalTooStrong,
    SignalTooWeak,
    TemperatureError,
    TooMuchBackgroundLight,
    open_range_finder,
)

from asbuilt.errors import DeviceError, DeviceProtocolError, DeviceTimeout

LINE = b"\r\n"


def _dimetix(scripted, script, device_id=0, timeout=0.3, **kwargs):
    channel, port = scripted(script, timeout=timeout, delimiters=LINE, **kwargs)
    return DimetixDLS(channel, device_id), port


@pytest.mark.parametrize(
    "reply, metres",
    [
        (b"g0g+00012345\r\n", 1.2345),
        (b"g0g+00000001\r\n", 0.0001),
        (b"g0g+99999999\r\n", 9999.9999),
        (b"g0g-00000150\r\n", -0.015),
    ],
)
def test_dimetix_distance_in_tenths_of_millimetres(scripted, reply, metres):
    lrf, port = _dimetix(scripted, [("s0g", reply)])
    assert lrf.measure() == pytest.approx(metres, abs=1e-12)
    assert port.written == ["s0g"]


@pytest.mark.parametrize(
    "code, cls, words",
    [
        (255, SignalTooWeak, "signal too weak"),
        (256, SignalTooStrong, "too strong"),
        (257, TooMuchBackgroundLight, "background light"),
        (252, TemperatureError, "too high"),
        (254, TemperatureError, "too low"),
        (203, RangeFinderCommandError, "wrong command"),
        (223, RangeFinderCommandError, "framing"),
        (999, RangeFinderError, "unknown error"),
    ],
)
def test_dimetix_error_codes_map_to_exceptions(scripted, code, cls, words):
    lrf, _ = _dimetix(scripted, [("s0g", f"g0@E{code:03d}\r\n".encode())])
    with pytest.raises(cls, match=words) as info:
        lrf.measure()
    assert info.value.code == f"E{code:03d}"
    assert isinstance(info.value, DeviceError)


def test_dimetix_skips_power_up_message_and_other_devices(scripted):
    lrf, _ = _dimetix(
        scripted,
        [("s3g", b"g3?\r\ng1g+00000007\r\ng1@E255\r\ng3g+00020000\r\n")],
        device_id=3,
    )
    assert lrf.measure() == pytest.approx(2.0)


@pytest.mark.parametrize("reply", [b"g0g+12x\r\n", b"OK\r\n", b"g0g12345\r\n"])
def test_dimetix_garbage_is_a_protocol_error(scripted, reply):
    lrf, _ = _dimetix(scripted, [("s0g", reply)])
    with pytest.raises(DeviceProtocolError, match="expected gNg"):
        lrf.measure()


def test_dimetix_silence_times_out(scripted):
    lrf, _ = _dimetix(scripted, [], timeout=0.2)
    with pytest.raises(DeviceTimeout, match="no distance reply within 0.2 s"):
        lrf.measure()


def test_dimetix_rejects_bad_device_id(scripted):
    channel, _ = scripted([])
    with pytest.raises(ValueError):
        DimetixDLS(channel, 12)


def _ldm(scripted, script, timeout=0.3):
    channel, port = scripted(script, timeout=timeout, delimiters=LINE)
    return LDM4x(channel), port


@pytest.mark.parametrize(
    "reply, metres, quality",
    [
        (b"004.996\r\n", 4.996, None),
        (b"123.456\r\n", 123.456, None),
        (b"004.996 000985\r\n", 4.996, 985),
    ],
)
def test_ldm_decimal_formats(scripted, reply, metres, quality):
    lrf, port = _ldm(scripted, [("DM", reply)])
    assert lrf.measure() == pytest.approx(metres)
    assert lrf.last_quality == quality
    assert port.written == ["DM"]


@pytest.mark.parametrize(
    "reply, cls",
    [
        (b"E15\r\n", SignalTooWeak),
        (b"E16\r\n", SignalTooWeak),
        (b"E17\r\n", RangeFinderCommandError),
        (b"E99\r\n", RangeFinderError),
    ],
)
def test_ldm_error_codes(scripted, reply, cls):
    lrf, _ = _ldm(scripted, [("DM", reply)])
    with pytest.raises(cls) as info:
        lrf.measure()
    assert info.value.code == reply.strip().decode()


@pytest.mark.parametrize("reply", [b"1388\r\n", b"??\r\n"])
def test_ldm_other_formats_are_protocol_errors(scripted, reply):
    lrf, _ = _ldm(scripted, [("DM", reply)])
    with pytest.raises(DeviceProtocolError, match="format d or s"):
        lrf.measure()


def test_unknown_protocol_name():
    with pytest.raises(DeviceError, match="unknown range finder protocol 'pelco'"):
        open_range_finder("loop://", "pelco")


# -- over the simulator URLs: the range finder measures where the head points --------------------
@pytest.mark.parametrize("protocol, tol", [("dimetix", 1e-4), ("ldm", 1e-3)])
def test_range_finders_measure_the_wall_along_the_current_beam(wall, protocol, tol):
    with (
        PanTiltUnit.open("sim-ptu://wall") as ptu,
        open_range_finder(f"sim-lrf://wall?protocol={protocol}", protocol) as lrf,
    ):
        for pan_deg, tilt_deg in [(0, 0), (20, 5), (-30, -10)]:
            pan, tilt = ptu.move_to(math.radians(pan_deg), math.radians(tilt_deg))
            expected = 5.0 / (math.cos(pan) * math.cos(tilt))
            assert lrf.measure() == pytest.approx(expected, abs=tol)


def test_looking_away_from_the_wall_is_a_weak_signal(wall):
    with PanTiltUnit.open("sim-ptu://wall") as ptu, open_range_finder("sim-lrf://wall") as lrf:
        ptu.move_to(math.radians(150), 0.0)
        with pytest.raises(SignalTooWeak):
            lrf.measure()


def test_silent_simulated_device_times_out(wall):
    lrf = open_range_finder("sim-lrf://wall?silent=1", timeout=0.2)
    with pytest.raises(DeviceTimeout):
        lrf.measure()
    lrf.close()


def test_unplugged_simulated_device_fails_clearly(wall):
    lrf = open_range_finder("sim-lrf://wall?unplug_after=2", timeout=0.5)
    lrf.measure()
    lrf.measure()
    with pytest.raises(DeviceError, match="cable may be unplugged"):
        lrf.measure()
    lrf.close()
