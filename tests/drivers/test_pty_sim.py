"""The real drivers over a real tty: simulators served on pseudo-terminals."""

from __future__ import annotations

import math
import os

import pytest
from asbuilt.drivers.dimetix import DimetixDLS
from asbuilt.drivers.ldm import LDM4x
from asbuilt.drivers.ptu import PanTiltUnit
from asbuilt.drivers.pty_sim import PtyServer
from driver_helpers import wall_rig

from asbuilt.errors import DeviceError

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")


@pytest.mark.parametrize("protocol", ["dimetix", "ldm"])
def test_drivers_over_pseudo_terminals(protocol):
    with PtyServer(wall_rig(4.0), protocol) as server:
        assert server.ptu_path.startswith("/dev/")
        with PanTiltUnit.open(server.ptu_path, timeout=2.0) as ptu:
            if protocol == "dimetix":
                lrf = DimetixDLS.open(server.lrf_path, bytesize=8, parity="N", timeout=2.0)
            else:
                lrf = LDM4x.open(server.lrf_path, timeout=2.0)
            with lrf:
                assert ptu.limits.pan_max == 3090
                for pan_deg in (0, 15, -25):
                    pan, tilt = ptu.move_to(math.radians(pan_deg), math.radians(3))
                    expected = 4.0 / (math.cos(pan) * math.cos(tilt))
                    assert lrf.measure() == pytest.approx(expected, abs=1e-3)
        assert server.error is None


def test_stopped_server_leaves_the_driver_with_a_clear_error():
    server = PtyServer(wall_rig()).start()
    ptu = PanTiltUnit.open(server.ptu_path, timeout=0.5)
    server.stop()
    with pytest.raises(DeviceError):
        ptu.position()
    ptu.close()
    server.stop()  # idempotent


def test_spy_url_logs_the_traffic(tmp_path):
    log = tmp_path / "traffic.txt"
    with PtyServer(wall_rig()) as server:
        with PanTiltUnit.open(f"spy://{server.ptu_path}?file={log}", timeout=2.0) as ptu:
            ptu.move_to(0.05, 0.0)
    text = log.read_text()
    assert "FT" in text and "PP" in text  # pyserial's spy handler recorded the exchange


def test_a_7e1_client_reopens_the_simulator_any_number_of_times():
    """pyserial itself, 7E1 as a factory Dimetix: open, measure, close, three times.

    Linux keeps a pty at CS8 without parity and refuses a tcsetattr that can change nothing;
    the second open asked only for CS7 + PARENB and failed with EINVAL.
    """
    import serial
    from asbuilt.drivers.transport import LineChannel

    with PtyServer(wall_rig(4.0), "dimetix") as server:
        for attempt in range(3):
            port = serial.Serial(server.lrf_path, 19200, bytesize=7, parity="E", timeout=0.05)
            with DimetixDLS(LineChannel(port, f"attempt {attempt}", 2.0)) as lrf:
                assert lrf.measure() == pytest.approx(4.0, abs=1e-3)
        assert server.error is None


def test_the_driver_reopens_a_pty_even_without_a_word_in_between():
    """The driver opens a pseudo-terminal 8N1 (what the kernel gives it anyway), so even a
    session that closes before sending anything leaves the tty re-openable with 7E1 asked."""
    from asbuilt.drivers.transport import is_pseudo_terminal

    with PtyServer(wall_rig(4.0), "dimetix") as server:
        path = server.lrf_path
        assert is_pseudo_terminal(path)
        assert not is_pseudo_terminal(f"spy://{path}")
        for _ in range(3):
            DimetixDLS.open(path, timeout=2.0).close()  # 7E1 by default
        with DimetixDLS.open(path, timeout=2.0) as lrf:
            assert lrf.measure() == pytest.approx(4.0, abs=1e-3)
    assert not is_pseudo_terminal(os.devnull)


def test_a_stopped_simulator_is_not_blamed_on_a_cable():
    server = PtyServer(wall_rig()).start()
    path = server.lrf_path
    server.stop()  # its /dev/pts/N is gone
    with pytest.raises(DeviceError, match="simulate-device") as info:
        DimetixDLS.open(path, timeout=0.5)
    assert "cable" not in str(info.value)
