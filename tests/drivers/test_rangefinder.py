"""Range finders by protocol name, over the simulator URLs: measuring where the head points."""

from __future__ import annotations

import math

import pytest
from asbuilt.drivers.ptu import PanTiltUnit
from asbuilt.drivers.rangefinder import (
    SignalTooWeak,
    open_range_finder,
)

from asbuilt.errors import DeviceError, DeviceTimeout


def test_unknown_protocol_name():
    with pytest.raises(DeviceError, match="unknown range finder protocol 'pelco'"):
        open_range_finder("loop://", "pelco")


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
