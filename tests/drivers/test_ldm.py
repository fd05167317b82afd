"""Jenoptik LDM41/42 driver against scripted replies: formats, error codes, garbage."""

from __future__ import annotations

import pytest
from asbuilt.drivers.ldm import LDM4x
from asbuilt.drivers.rangefinder import RangeFinderError, SignalTooWeak

from asbuilt.errors import DeviceProtocolError

LINE = b"\r\n"


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
        (b"E16\r\n", RangeFinderError),
        (b"E17\r\n", RangeFinderError),
        (b"E19\r\n", RangeFinderError),
        (b"E99\r\n", RangeFinderError),
    ],
)
def test_ldm_error_codes(scripted, reply, cls):
    lrf, _ = _ldm(scripted, [("DM", reply)])
    with pytest.raises(cls) as info:
        lrf.measure()
    assert type(info.value) is cls
    assert info.value.code == reply.strip().decode()


@pytest.mark.parametrize("code", ["E16", "E17", "E18", "E19"])
def test_ldm_codes_without_a_documented_meaning_get_no_invented_one(scripted, code):
    # the reference (protocols.md) gives only E15's meaning
    lrf, _ = _ldm(scripted, [("DM", f"{code}\r\n".encode())])
    with pytest.raises(RangeFinderError) as info:
        lrf.measure()
    assert f"{code} device error; see the LDM manual" in str(info.value)


@pytest.mark.parametrize(
    "reply, metres", [(b"001388\r\n", 5.0), (b"1388\r\n", 5.0), (b"000c8a\r\n", 3.21)]
)
def test_ldm_hexadecimal_millimetres(scripted, reply, metres):
    # format h: hexadecimal millimetres (protocols.md)
    lrf, _ = _ldm(scripted, [("DM", reply)])
    assert lrf.measure() == pytest.approx(metres)
    assert lrf.last_quality is None


@pytest.mark.parametrize("reply", [b"??\r\n", b"4.99.6\r\n", b"12G4\r\n"])
def test_ldm_other_replies_are_protocol_errors(scripted, reply):
    lrf, _ = _ldm(scripted, [("DM", reply)])
    with pytest.raises(DeviceProtocolError, match="check the baud rate"):
        lrf.measure()
