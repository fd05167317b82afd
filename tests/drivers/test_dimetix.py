"""Dimetix DLS driver against scripted replies: formats, error codes, garbage, silence."""

from __future__ import annotations

import pytest
from asbuilt.drivers.dimetix import DimetixDLS
from asbuilt.drivers.rangefinder import (
    RangeFinderCommandError,
    RangeFinderError,
    SignalTooStrong,
    SignalTooWeak,
    TemperatureError,
    TooMuchBackgroundLight,
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
    with pytest.raises(DeviceTimeout, match="no distance reply from device id 0 within 0.2 s"):
        lrf.measure()


def test_dimetix_rejects_bad_device_id(scripted):
    channel, _ = scripted([])
    with pytest.raises(ValueError):
        DimetixDLS(channel, 12)


@pytest.mark.parametrize("on, command", [(True, "s0o"), (False, "s0p")])
@pytest.mark.parametrize("reply", [b"g0?\r\n", None])
def test_laser_on_and_off_take_an_acknowledgement_or_silence(scripted, on, command, reply):
    # The reference gives no reply for sNo / sNp: a silent sensor is not an error.
    script = [(command, reply)] if reply is not None else []
    lrf, port = _dimetix(scripted, script, timeout=3.0)
    lrf.laser(on)
    assert port.written == [command]


def test_laser_error_reply_raises(scripted):
    lrf, _ = _dimetix(scripted, [("s0o", b"g0@E203\r\n")])
    with pytest.raises(RangeFinderCommandError):
        lrf.laser(True)
