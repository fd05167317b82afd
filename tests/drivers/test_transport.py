"""Line reading with deadlines, port opening and URL handler registration."""

from __future__ import annotations

import os
import sys
import time
import tty

import pytest
import serial
from asbuilt.drivers.transport import SIM_SCHEMES, LineChannel, open_port, register_url_handlers

from asbuilt.errors import DeviceError, DeviceProtocolError, DeviceTimeout


class Feed:
    """A port that hands out pre-loaded bytes, then stays silent."""

    def __init__(self, data: bytes):
        self.data = bytearray(data)

    @property
    def in_waiting(self):
        return len(self.data)

    def read(self, size=1):
        if not self.data:
            time.sleep(0.01)
            return b""
        out = bytes(self.data[:size])
        del self.data[:size]
        return out

    def reset_input_buffer(self):
        self.data.clear()

    def close(self):
        pass


@pytest.mark.parametrize(
    "data, lines",
    [
        (b"* 12\r\n", ["* 12"]),
        (b"* 1\r* 2\n* 3\r\n", ["* 1", "* 2", "* 3"]),
        (b"\r\n\r\n  \r\n* x\r\n", ["* x"]),
        (b"g0g+00012345\r\ng0?\r\n", ["g0g+00012345", "g0?"]),
    ],
)
def test_read_line_splits_on_any_line_end_and_skips_blank_lines(data, lines):
    channel = LineChannel(Feed(data), "dev", timeout=0.2)
    assert [channel.read_line() for _ in lines] == lines


def test_silence_times_out_with_a_clear_message_within_the_deadline():
    channel = LineChannel(Feed(b""), "pan-tilt unit on /dev/ttyUSB9", timeout=0.3)
    start = time.monotonic()
    with pytest.raises(DeviceTimeout, match="pan-tilt unit on /dev/ttyUSB9: no reply within 0.3 s"):
        channel.read_line()
    assert time.monotonic() - start < 3.0  # generous bound: it must not hang


def test_a_partial_line_is_reported_in_the_timeout():
    channel = LineChannel(Feed(b"* 12"), "dev", timeout=0.1)
    with pytest.raises(DeviceTimeout, match=r"partial b'\* 12'"):
        channel.read_line()


def test_non_ascii_bytes_are_a_protocol_error():
    channel = LineChannel(Feed(b"\xff\xfe*\r\n"), "dev", timeout=0.2)
    with pytest.raises(DeviceProtocolError, match="baud rate"):
        channel.read_line()


def test_endless_garbage_without_line_end_is_a_protocol_error():
    channel = LineChannel(Feed(b"x" * 5000), "dev", timeout=2.0)
    with pytest.raises(DeviceProtocolError, match="without a line end"):
        channel.read_line()


def test_discard_input_forgets_stale_bytes():
    channel = LineChannel(Feed(b"stale\r\n"), "dev", timeout=0.1)
    channel.discard_input()
    with pytest.raises(DeviceTimeout):
        channel.read_line()


@pytest.mark.parametrize("url", ["/dev/does-not-exist-asbuilt", "nosuchscheme://x"])
def test_open_port_failure_is_a_device_error(url):
    with pytest.raises(DeviceError, match="cannot open the port"):
        open_port(url)


def test_url_handlers_registered_once():
    register_url_handlers()
    register_url_handlers()
    assert serial.protocol_handler_packages.count("asbuilt.drivers") == 1
    assert SIM_SCHEMES == ("sim-ptu", "sim-lrf")


def test_loop_url_round_trip():
    port = open_port("loop://", timeout=0.05)
    channel = LineChannel(port, "loop", timeout=0.5)
    channel.write("hello\r\n")
    assert channel.read_line() == "hello"
    channel.close()
    channel.close()  # idempotent


@pytest.mark.parametrize("timeout", [float("nan"), float("inf"), -1.0])
def test_a_deadline_that_could_never_expire_is_refused(timeout):
    # NaN compares false with everything: read_line would wait forever
    with pytest.raises(ValueError, match="finite number of seconds"):
        LineChannel(Feed(b""), "dev", timeout=timeout)
    channel = LineChannel(Feed(b""), "dev", timeout=0.1)
    with pytest.raises(ValueError, match="finite number of seconds"):
        channel.read_line(timeout)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="Linux pseudo-terminals")
def test_a_7e1_driver_reopens_a_plain_pty_also_through_the_spy_wrapper(tmp_path):
    # A pty that no server re-marks between opens (socat's, an independent simulator's): Linux
    # refuses a 7E1 tcsetattr that can change nothing, so the second 7E1 open failed (EINVAL).
    from asbuilt.drivers.dimetix import DimetixDLS
    from asbuilt.drivers.transport import is_pseudo_terminal

    master, slave = os.openpty()
    try:
        tty.setraw(slave)
        path = os.ttyname(slave)
        spied = f"spy://{path}?file={tmp_path / 'traffic.txt'}"
        assert is_pseudo_terminal(path) and not is_pseudo_terminal(spied)
        for url in (spied, spied, path, path, spied):
            DimetixDLS.open(url, timeout=0.5).close()  # 7E1 by default
    finally:
        os.close(master)
        os.close(slave)


def test_open_port_names_an_unknown_simulator_option():
    url = "sim-ptu://typo?scene=a.json&calibraton=true.cal.json"
    with pytest.raises(DeviceError, match=r"^sim-ptu://typo\?.*: unknown URL option 'calibraton'"):
        open_port(url)
