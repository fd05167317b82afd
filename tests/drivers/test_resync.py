"""Replies stay with their shots: late replies, notices on their own, echoes, half-written
commands and wrong line settings, over real pseudo-terminals with fakes written from the manuals
(tests/drivers/pty_fakes.py). Ranges encode where the head pointed (2 m + pan counts / 1000), so
a range that belongs to another aim is caught."""

from __future__ import annotations

import math
import os
import time

import pytest
from asbuilt.drivers.dimetix import DimetixDLS
from asbuilt.drivers.ldm import LDM4x
from asbuilt.drivers.plan import SessionSettings
from asbuilt.drivers.ptu import PanTiltUnit, PTULimitError
from asbuilt.drivers.session import DeviceShooter
from pty_fakes import FakeFlirPTU, PtyFake, wait_until_readable

from asbuilt.errors import DeviceProtocolError

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")

COUNT = math.radians(185.1428 / 3600)  # radians per count of the fake unit (PR)
TIMEOUT = 0.3  # s, the drivers' reply timeout here
LATE = 0.55  # s, a reply later than TIMEOUT


class AimPTU:
    """A head stub that moves at once: the range finder fakes measure where it points."""

    def __init__(self):
        self.pan = 0.0

    def move_to(self, pan, tilt):
        self.pan = pan
        return pan, tilt


def _range_at(pan_rad: float) -> float:
    return 2.0 + round(pan_rad / COUNT) / 1000


class FakeDimetix:
    """Dimetix DLS (protocols.md): ``sNg`` -> ``gNg+xxxxxxxx`` (0.1 mm) when the measurement
    ends, one measurement at a time; ``sNc`` stops it (``gN?``)."""

    def __init__(self, head, device_id=0, durations=(), **fake_options):
        self.head = head
        self.n = device_id
        self.durations = list(durations)
        self.busy_until = 0.0
        self.fake = PtyFake(self.respond, **fake_options)

    def respond(self, fake, command):
        n = self.n
        if command == f"s{n}g":
            value = round(_range_at(self.head.pan) * 1e4)  # where the beam points now
            start = max(time.monotonic(), self.busy_until)
            self.busy_until = start + (self.durations.pop(0) if self.durations else 0.01)
            fake.reply(f"g{n}g{value:+09d}\r\n".encode(), self.busy_until - time.monotonic(), "m")
        elif command == f"s{n}c":
            fake.cancel("m")
            self.busy_until = 0.0
            fake.reply(f"g{n}?\r\n".encode())


class FakeLDM:
    """LDM41/42 (protocols.md): ``DM`` -> ``004.996`` (format d) or hexadecimal millimetres
    (``hex``), one measurement at a time; no stop command. ``split_ends``: CR and LF each end a
    command, and the empty one between is answered at once with ``E61`` (the manual gives the
    replies' line ending, not the commands'); ``in_turn``: that error only once the measurement
    before it has been answered (a meter that works through its commands in turn)."""

    def __init__(self, head, durations=(), hex=False, split_ends=False, in_turn=False):
        self.head = head
        self.durations = list(durations)
        self.busy_until = 0.0
        self.hex = hex
        self.in_turn = in_turn
        self.fake = PtyFake(self.respond, empty_commands=split_ends)

    def respond(self, fake, command):
        if command.upper() == "DM":
            value = _range_at(self.head.pan)
            start = max(time.monotonic(), self.busy_until)
            self.busy_until = start + (self.durations.pop(0) if self.durations else 0.01)
            text = f"{round(value * 1000):06X}" if self.hex else f"{value:07.3f}"
            fake.reply(f"{text}\r\n".encode(), self.busy_until - time.monotonic())
        elif not command:
            wait = self.busy_until - time.monotonic() + 0.001 if self.in_turn else 0.0
            fake.reply(b"E61\r\n", max(wait, 0.0))


def _shoot(shooter, counts):
    return [shooter(c * COUNT, 0.0, "raster") for c in counts]


@pytest.mark.parametrize("retries", [0, 2])
def test_a_late_dimetix_reply_is_not_taken_for_a_later_shot(retries):
    head = AimPTU()
    dev = FakeDimetix(head, durations=[LATE])
    with dev.fake, DimetixDLS.open(dev.fake.path, timeout=TIMEOUT) as lrf:
        shots = _shoot(DeviceShooter(head, lrf, SessionSettings(retries=retries)), [100, 200, 300])
    for shot, counts in zip(shots, [100, 200, 300]):
        assert shot.range is None or shot.range == pytest.approx(2.0 + counts / 1000)
    assert [s.range for s in shots[1:]] == pytest.approx([2.2, 2.3])
    assert "s0c" in dev.fake.commands  # the measurement that timed out was stopped


@pytest.mark.parametrize("retries", [0, 2])
def test_a_late_ldm_reply_is_not_taken_for_a_later_shot(retries):
    head = AimPTU()
    dev = FakeLDM(head, durations=[LATE])
    with dev.fake, LDM4x.open(dev.fake.path, timeout=TIMEOUT) as lrf:
        shots = _shoot(DeviceShooter(head, lrf, SessionSettings(retries=retries)), [100, 200, 300])
    for shot, counts in zip(shots, [100, 200, 300]):
        assert shot.range is None or shot.range == pytest.approx(2.0 + counts / 1000)
    assert [s.range for s in shots[1:]] == pytest.approx([2.2, 2.3])


@pytest.mark.parametrize("hex_format", [False, True])
@pytest.mark.parametrize("duration, in_turn", [(0.01, False), (0.2, False), (0.2, True)])
def test_an_ldm_that_ends_commands_at_cr_and_at_lf_is_found_by_the_probe(
    hex_format, duration, in_turn
):
    # Each DM + CR LF draws two replies, the distance and the empty command's error, in either
    # order: without the probe's check a shot could take the error or the last shot's distance.
    head = AimPTU()
    dev = FakeLDM(head, [duration] * 10, hex=hex_format, split_ends=True, in_turn=in_turn)
    # A timeout well beyond the 0.2 s measurements: a loaded machine must not turn one into a
    # missed shot (0.3 s left 0.1 s to spare, and one shot in a full run timed out).
    with dev.fake, LDM4x.open(dev.fake.path, timeout=1.0) as lrf:
        lrf.probe()
        assert lrf.eol == "\r"
        shots = _shoot(DeviceShooter(head, lrf, SessionSettings(retries=0)), [100, 200, 300])
    assert [s.range for s in shots] == pytest.approx([2.1, 2.2, 2.3])
    assert [s.error for s in shots] == [None, None, None]


@pytest.mark.parametrize("hex_format", [False, True])
def test_an_ldm_that_ends_commands_at_cr_lf_keeps_cr_lf(hex_format):
    head = AimPTU()
    dev = FakeLDM(head, hex=hex_format)
    with dev.fake, LDM4x.open(dev.fake.path, timeout=TIMEOUT) as lrf:
        lrf.probe()
        assert lrf.eol == "\r\n"
        shots = _shoot(DeviceShooter(head, lrf, SessionSettings(retries=0)), [100, 200])
    assert [s.range for s in shots] == pytest.approx([2.1, 2.2])
    # the probe: two DM answered alike keep CR LF; a hex reply asks for format d (SDd), which
    # this fake ignores: its hex distances are still read
    probe = ["DM", "DM", "SDd", "DM"] if hex_format else ["DM", "DM"]
    assert dev.fake.commands == probe + ["DM"] * 2


def test_an_ldm_autostart_line_is_not_taken_for_the_first_shot():
    head = AimPTU()
    dev = FakeLDM(head)
    with dev.fake, LDM4x.open(dev.fake.path, timeout=TIMEOUT) as lrf:
        dev.fake.reply(b"009.999\r\n")  # autostart (AS): a measurement at power-up
        wait_until_readable(lrf.channel.port)
        head.pan = 400 * COUNT
        assert lrf.measure() == pytest.approx(2.4)


class _HeadRange:
    """A range finder fake measuring where the fake unit's head really points."""

    def __init__(self, ptu_dev):
        self.ptu_dev = ptu_dev
        self.calls = 0

    def measure(self):
        self.calls += 1
        return 2.0 + self.ptu_dev.head.position()[0] / 1000


def test_a_slow_move_does_not_let_later_shots_fire_mid_move():
    # the first move outlasts --move-timeout; its late '*' must not end later moves early
    ptu_dev = FakeFlirPTU(durations=[LATE], default=0.15)

    class HeadLRF:
        def measure(self):
            return 2.0 + ptu_dev.head.position()[0] / 1000  # where the head really is

    with ptu_dev.fake:
        ptu = PanTiltUnit.open(ptu_dev.fake.path, timeout=TIMEOUT, move_timeout=TIMEOUT)
        with ptu:
            shooter = DeviceShooter(ptu, HeadLRF(), SessionSettings(retries=2))
            shots = _shoot(shooter, [100, 1100, 2100, 1100, 100])
            assert ptu.position_counts() == (100, 0)
    assert [s.range for s in shots] == pytest.approx([2.1, 3.1, 4.1, 3.1, 2.1])


def test_a_head_that_settles_a_count_off_its_target_ends_the_check_after_a_late_move():
    # After a late '*' the driver checks the position; a count off is at the target.
    ptu_dev = FakeFlirPTU(durations=[LATE], default=0.0, settle=1)
    with ptu_dev.fake:
        ptu = PanTiltUnit.open(ptu_dev.fake.path, timeout=TIMEOUT, move_timeout=TIMEOUT)
        with ptu:
            lrf = _HeadRange(ptu_dev)
            shooter = DeviceShooter(ptu, lrf, SessionSettings())
            shots = _shoot(shooter, [100, 1100])
    assert [s.error for s in shots] == [None, None]
    assert [s.range for s in shots] == pytest.approx([2.101, 3.101])
    assert lrf.calls == 2


def test_a_limit_notice_after_the_moves_star_is_not_blamed_on_the_next_shot():
    ptu_dev = FakeFlirPTU(after_star={1: b"!P\r\n"})

    class HeadLRF:
        def measure(self):
            return 2.0 + ptu_dev.head.position()[0] / 1000

    with ptu_dev.fake, PanTiltUnit.open(ptu_dev.fake.path, timeout=TIMEOUT) as ptu:
        shots = _shoot(DeviceShooter(ptu, HeadLRF()), [100, 200, 300])
    # the move that drew the notice may have stopped short: its shot is not kept
    assert shots[0].range is None and shots[0].error == "limit"
    assert [s.range for s in shots[1:]] == pytest.approx([2.2, 2.3])
    assert [s.error for s in shots[1:]] == [None, None]


def test_a_limit_notice_in_place_of_the_star_ends_the_wait_as_a_limit():
    ptu_dev = FakeFlirPTU(instead_of_star={1: b"!P\r\n"})
    with ptu_dev.fake:
        ptu = PanTiltUnit.open(ptu_dev.fake.path, timeout=TIMEOUT, move_timeout=3.0)
        with ptu:
            with pytest.raises(PTULimitError, match="pan axis hit its limit during 'A'"):
                ptu.move_to(3000 * COUNT, 0.0)
            ptu.move_to(200 * COUNT, 0.0)  # the unit is still usable
            assert ptu.position_counts() == (200, 0)


def test_a_half_written_command_left_in_the_unit_does_not_fail_the_opening():
    ptu_dev = FakeFlirPTU()
    ptu_dev.fake.token.extend(b"PP12")  # what a killed program left before its delimiter
    with ptu_dev.fake, PanTiltUnit.open(ptu_dev.fake.path, timeout=TIMEOUT) as ptu:
        assert ptu.limits.pan_max == 3090 and ptu.limits.tilt_min == -907
        ptu.move_to(100 * COUNT, 0.0)
        assert ptu.position_counts() == (100, 0)


def test_dimetix_skips_bus_echoes_and_other_hosts():
    head = AimPTU()
    head.pan = 321 * COUNT
    dev = FakeDimetix(head, device_id=2, echo=True)  # a 2-wire RS-485 adapter echoes
    with dev.fake, DimetixDLS.open(dev.fake.path, device_id=2, timeout=TIMEOUT) as lrf:
        assert lrf.measure() == pytest.approx(2.321)
        dev.fake.reply(b"s1g\r\ng1g+00012345\r\ng1?\r\n")  # another host talking to sensor 1
        wait_until_readable(lrf.channel.port)
        assert lrf.measure() == pytest.approx(2.321)


def _as_7e1(data: bytes) -> bytes:
    """What an 8N1 host receives from a 7E1 device: the even parity bit as bit 7."""
    return bytes(b | (0x80 if bin(b).count("1") % 2 else 0) for b in data)


def test_wrong_line_settings_stop_the_session_with_the_drivers_message():
    head = AimPTU()
    dev = FakeDimetix(head, transform=_as_7e1)
    with dev.fake, DimetixDLS.open(dev.fake.path, bytesize=8, parity="N", timeout=TIMEOUT) as lrf:
        shooter = DeviceShooter(head, lrf, SessionSettings(retries=1, lost_after=3))
        assert _shoot(shooter, [1, 2])[1].error == "protocol"
        with pytest.raises(DeviceProtocolError, match="check the baud rate and line settings"):
            shooter(3 * COUNT, 0.0, "raster")
        with pytest.raises(DeviceProtocolError, match="line settings"):
            lrf.probe()  # the CLI's check at opening, before the head moves
