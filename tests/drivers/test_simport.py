"""The sim-ptu:// and sim-lrf:// pyserial URL handlers: parsing, shared rigs, bad URLs."""

from __future__ import annotations

import json
import re

import pytest
import serial
from asbuilt.drivers.simport import parse_sim_url
from asbuilt.drivers.simrig import register_rig
from driver_helpers import SCENE, wall_rig


@pytest.mark.parametrize(
    "url, scheme, name, options",
    [
        ("sim-ptu://lab?scene=a.json&seed=3", "sim-ptu", "lab", {"scene": "a.json", "seed": "3"}),
        ("SIM-LRF://lab?protocol=ldm", "sim-lrf", "lab", {"protocol": "ldm"}),
        ("sim-lrf://", "sim-lrf", "default", {}),
    ],
)
def test_parse_sim_url(url, scheme, name, options):
    assert parse_sim_url(url) == (scheme, name, options)


def test_ptu_and_lrf_urls_share_one_rig(scene_file):
    ptu = serial.serial_for_url(f"sim-ptu://shared?scene={scene_file}", timeout=0.5)
    lrf = serial.serial_for_url("sim-lrf://shared", timeout=0.5)
    ptu.write(b"ED PP1500 A ")
    lrf.write(b"s0g\r\n")
    assert lrf.read_until(b"g0g").endswith(b"g0g")  # power-up g0? first, then the distance
    ptu.close()
    lrf.close()


@pytest.mark.parametrize(
    "url, message",
    [
        ("sim-lrf://nowhere", "does not exist; give ?scene=PATH"),
        ("sim-lrf://wall?protocol=pelco", "unknown simulated range finder protocol"),
        ("sim-lrf://wall?scene=other.json", "already exists with scene=None"),
        ("sim-ptu://x?scene=/no/such/scene.json", "scene file not found"),
    ],
)
def test_bad_sim_urls_fail_to_open(wall, url, message):
    with pytest.raises(serial.SerialException, match=re.escape(message)):
        serial.serial_for_url(url)


def test_registered_rig_is_reused():
    rig = register_rig("mine", wall_rig())
    port = serial.serial_for_url("sim-ptu://mine", timeout=0.2)
    port.write(b"ED PP300 ")
    port.read(100)
    assert rig.counts()[0] == 300
    port.close()


def test_station_option_places_the_rig(tmp_path):
    scene = dict(SCENE)
    scene["stations"] = [*SCENE["stations"], {"id": "S2", "position": [0.0, 1.0, 1.5]}]
    path = tmp_path / "two.json"
    path.write_text(json.dumps(scene))
    serial.serial_for_url(f"sim-ptu://two?scene={path}&station=S2").close()
    from asbuilt.drivers.simrig import get_rig

    assert get_rig("two", {}).calibration.base_position == (0.0, 1.0, 1.5)
    with pytest.raises(serial.SerialException, match="no station 'S9'; use one of S1, S2"):
        serial.serial_for_url(f"sim-ptu://three?scene={path}&station=S9")


@pytest.mark.parametrize(
    "url, key",
    [
        ("sim-ptu://t?scene=a.json&calibraton=true.cal.json", "calibraton"),
        ("sim-ptu://x?scene=a.json&bogus=1", "bogus"),
        ("sim-ptu://x?prefix=ld:", "prefix"),  # a sim-lrf option
        ("sim-lrf://x?trickle=0.1", "trickle"),  # a Pelco-D sim-ptu option
    ],
)
def test_unknown_url_options_are_refused_by_name(url, key):
    # A misspelt calibration= used to be dropped, giving an ideal rig without a word.
    with pytest.raises(serial.SerialException, match=rf"unknown URL option '{key}'; use .*seed"):
        parse_sim_url(url)


def test_every_documented_url_option_is_accepted():
    ptu = "sim-ptu://r?scene=a&calibration=c&range_sigma=0&angle_sigma=0&dropout=0&divergence=0"
    ptu += "&min_cos=0&max_range=9&seed=1&speed=0&station=s&protocol=flir&address=1&trickle=0"
    assert len(parse_sim_url(ptu + "&silent=0&unplug_after=3")[2]) == 16
    assert parse_sim_url("sim-lrf://r?protocol=lw20&device_id=0&prefix=ld:")[2]["prefix"] == "ld:"
