"""Pelco-D head driver over real pseudo-terminals: frames and checksums, bad replies (checksum,
short frame, another address, silence), resync, split replies, moves that wait by polling,
limits and the tilt convention; a scan session with the simulated head."""

from __future__ import annotations

import math
import os
import select
import threading
import time
import tty

import pytest
from asbuilt.drivers.pelco import PelcoD, checksum, frame
from asbuilt.drivers.ptu import PTULimitError, open_pan_tilt_unit
from asbuilt.drivers.pty_sim import PtyServer
from driver_helpers import wall_rig

from asbuilt.errors import DeviceError, DeviceProtocolError, DeviceTimeout

pytestmark = pytest.mark.skipif(not hasattr(os, "openpty"), reason="needs POSIX pseudo-terminals")


def _frame(addr, cmd2, value, cmd1=0):
    """A frame built by hand from the reference's description (not with the driver's helper)."""
    body = [addr, cmd1, cmd2, value >> 8, value & 0xFF]
    return bytes([0xFF, *body, sum(body) % 256])


class FrameFake:
    """A Pelco-D device on a pseudo-terminal, from protocols.md: 7-byte frames in, replies out.

    ``respond(frame) -> list of bytes chunks`` is called for every frame received (sync and
    7 bytes; the checksum is not judged here); each chunk is written separately, ``gap`` seconds
    apart (a reply split across reads).
    """

    def __init__(self, respond, gap: float = 0.0):
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        self.path = os.ttyname(self.slave)
        self.respond = respond
        self.gap = gap
        self.frames: list[bytes] = []
        self._rx = bytearray()
        self._stop = False
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self):
        while not self._stop:
            readable, _, _ = select.select([self.master], [], [], 0.05)
            if not readable:
                continue
            try:
                data = os.read(self.master, 4096)
            except OSError:
                return
            for byte in data:
                if not self._rx and byte != 0xFF:
                    continue
                self._rx.append(byte)
                if len(self._rx) == 7:
                    got = bytes(self._rx)
                    self._rx.clear()
                    self.frames.append(got)
                    for i, chunk in enumerate(self.respond(got) or []):
                        if i and self.gap:
                            time.sleep(self.gap)
                        os.write(self.master, chunk)

    def close(self):
        self._stop = True
        self._thread.join(timeout=5)
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Head:
    """A head answering position queries; the target is reached after ``polls`` pan queries."""

    def __init__(self, address=1, polls=0, pan=0, tilt=0):
        self.address = address
        self.pan, self.tilt = pan, tilt
        self.target = (pan, tilt)
        self.polls = polls
        self.left = 0

    def __call__(self, got: bytes):
        cmd2, value = got[3], (got[4] << 8) | got[5]
        if cmd2 == 0x4B:
            self.target = (value, self.target[1])
            self.left = self.polls
        elif cmd2 == 0x4D:
            self.target = (self.target[0], value)
            self.left = self.polls
        if cmd2 == 0x51:
            if self.left:
                self.left -= 1
            else:
                self.pan, self.tilt = self.target
            return [_frame(self.address, 0x59, self.pan)]
        elif cmd2 == 0x53:
            return [_frame(self.address, 0x5B, self.tilt)]
        return []


def _open(fake, **options):
    options.setdefault("timeout", 0.3)
    return PelcoD.open(fake.path, poll_interval=0, **options)


# -- frames ----------------------------------------------------------------------------------
def test_frames_and_checksums_as_the_reference_gives_them():
    # absolute pan 90.00 deg to address 1: FF 01 00 4B 23 28, checksum 01+00+4B+23+28 = 0x97
    assert frame(1, 0x00, 0x4B, 0x23, 0x28) == bytes.fromhex("FF01004B232897")
    assert checksum(1, 0x00, 0x51, 0, 0) == 0x52
    assert checksum(0xFF, 0xFF, 0xFF, 0xFF, 0xFF) == (5 * 255) % 256
    with pytest.raises(ValueError):
        frame(256, 0, 0)


def test_move_sends_absolute_frames_and_waits_by_polling_the_position():
    head = Head(polls=3)
    with FrameFake(head) as fake, _open(fake) as ptu:
        pan, tilt = ptu.move_to(math.radians(90), math.radians(-10))
        assert math.degrees(pan) == pytest.approx(90) and math.degrees(tilt) == pytest.approx(-10)
        sets = [f for f in fake.frames if f[3] in (0x4B, 0x4D)]
        # pan 9000 hundredths; tilt 10 deg *down* is +1000 raw (raw grows downwards by default)
        assert sets == [_frame(1, 0x4B, 9000), _frame(1, 0x4D, 1000)]
        pan_queries = [f for f in fake.frames if f[3] == 0x51]
        assert len(pan_queries) >= 1 + 4  # initialize, then polled until the head arrived
        assert all(f == _frame(1, 0x51, 0) for f in pan_queries)
        assert ptu.position() == pytest.approx((math.radians(90), math.radians(-10)))


@pytest.mark.parametrize(
    "pan_deg, raw, back_deg",
    [(0, 0, 0), (-25, 33500, -25), (200, 20000, -160), (-190, 17000, 170), (359.99, 35999, -0.01)],
)
def test_pan_wraps_into_0_to_35999_and_reads_back_signed(pan_deg, raw, back_deg):
    head = Head()
    with FrameFake(head) as fake, _open(fake) as ptu:
        pan, _ = ptu.move_to(math.radians(pan_deg), 0.0)
        assert math.degrees(pan) == pytest.approx(pan_deg)  # as asked, not wrapped
        assert head.target[0] == raw
        assert math.degrees(ptu.position()[0]) == pytest.approx(back_deg)


@pytest.mark.parametrize(
    "options, tilt_deg, raw",
    [
        ({}, 10, 35000),  # up: raw below 36000 (the horizon is 0, down grows)
        ({}, -30, 3000),
        ({"tilt_sign": 1}, 10, 1000),
        ({"tilt_sign": 1}, -30, 33000),
        ({"tilt_zero": 90}, 0, 9000),  # a head whose raw 90.00 deg is level
        ({"tilt_zero": 90}, 20, 7000),
    ],
)
def test_tilt_sign_and_zero_options(options, tilt_deg, raw):
    head = Head()
    with FrameFake(head) as fake, _open(fake, **options) as ptu:
        ptu.move_to(0.0, math.radians(tilt_deg))
        assert head.target[1] == raw
        assert math.degrees(ptu.position()[1]) == pytest.approx(tilt_deg)


def test_targets_outside_the_limits_are_refused_before_anything_is_sent():
    head = Head()
    with FrameFake(head) as fake, _open(fake, pan_limits=(-170, 170)) as ptu:
        sent = len(fake.frames)
        for pan, tilt in ((0, 95), (0, -91), (175, 0), (math.nan, 0), (0, math.inf)):
            with pytest.raises(PTULimitError, match="limits"):
                ptu.move_to(math.radians(pan), math.radians(tilt))
        assert len(fake.frames) == sent
        assert ptu.limits.ranges_missed([(0.0, math.radians(95))]) == (
            "tilt range [-90.000, 90.000] deg"
        )
        assert ptu.limits.ranges_missed([(math.radians(10), 0.0)]) == ""
        ptu.move_to(math.radians(-190 + 360), 0.0)  # 170 deg: inside


@pytest.mark.parametrize(
    "options",
    [{"address": 0}, {"address": 256}, {"tilt_sign": 0}, {"tilt_limits": (10, -10)}],
)
def test_bad_options_are_refused(options):
    with FrameFake(Head()) as fake, pytest.raises(ValueError):
        _open(fake, **options)


# -- bad replies -----------------------------------------------------------------------------
def test_a_bad_checksum_is_a_clear_protocol_error():
    def respond(got):
        if got[3] == 0x51:
            good = _frame(1, 0x59, 1234)
            return [good[:6] + bytes([(good[6] + 1) % 256])]
        return [_frame(1, 0x5B, 0)]

    with FrameFake(respond) as fake:
        with pytest.raises(DeviceProtocolError, match="bad checksum in the reply FF 01 00 59"):
            _open(fake)


def test_a_short_frame_is_a_clear_protocol_error():
    with FrameFake(lambda got: [_frame(1, 0x59, 0)[:4]]) as fake:
        with pytest.raises(DeviceProtocolError, match=r"short frame, 4 of 7 bytes \(FF 01 00 59\)"):
            _open(fake)


def test_replies_from_another_address_name_it():
    head = Head(address=2)
    with FrameFake(head) as fake:
        with pytest.raises(DeviceProtocolError, match="address 2, not 1.*--ptu-address"):
            _open(fake)
        with _open(fake, address=2) as ptu:  # the right address works
            ptu.move_to(math.radians(5), 0.0)
            assert all(f[1] == 2 for f in fake.frames[-4:])


def test_silence_is_a_timeout_naming_the_query():
    with FrameFake(lambda got: []) as fake:
        with pytest.raises(DeviceTimeout, match=r"pan position query \(FF 01 00 51 00 00 52\)"):
            _open(fake)


def test_garbage_and_a_false_sync_before_the_reply_are_skipped():
    # noise, then an FF that starts no valid frame, then the reply: the reader resyncs on it
    def respond(got):
        reply = _frame(1, 0x59 if got[3] == 0x51 else 0x5B, 0x01FF)  # FF inside the data too
        return [b"\x13\x37\xff\x01\x00" + reply]

    with FrameFake(respond) as fake, _open(fake) as ptu:
        assert ptu.position_raw() == (0x01FF, 0x01FF)


def test_replies_split_across_reads_byte_by_byte():
    head = Head(polls=1)

    def respond(got):
        return [bytes([b]) for chunk in head(got) for b in chunk]  # one byte per write

    with FrameFake(respond, gap=0.002) as fake, _open(fake) as ptu:
        ptu.move_to(math.radians(12.34), math.radians(5))
        assert ptu.position_raw() == (1234, 35500)


def test_the_query_after_a_bad_reply_reads_the_next_good_one():
    calls = {"n": 0}

    def respond(got):
        if got[3] == 0x51:
            calls["n"] += 1
            if calls["n"] == 2:  # the second pan query: a corrupt reply
                return [b"\xff\x01\x00\x59\x00\x05\x00"]
            return [_frame(1, 0x59, 700)]
        return [_frame(1, 0x5B, 0)]

    with FrameFake(respond) as fake, _open(fake) as ptu:
        with pytest.raises(DeviceProtocolError, match="bad checksum"):
            ptu.position_raw()
        assert ptu.position_raw() == (700, 0)


def test_noise_while_polling_a_move_is_queried_again():
    head = Head(polls=2)
    seen = {"n": 0}

    def respond(got):
        reply = head(got)
        if got[3] == 0x51:
            seen["n"] += 1
            if seen["n"] == 3:  # a reply spoilt by noise in the middle of the move
                return [reply[0][:6] + b"\x00"]
        return reply

    with FrameFake(respond) as fake, _open(fake) as ptu:
        ptu.move_to(math.radians(45), 0.0)
        assert head.pan == 4500


def test_a_head_that_never_arrives_is_a_timeout_naming_where_it_is():
    head = Head(polls=10**9)
    with FrameFake(head) as fake, _open(fake, move_timeout=0.2) as ptu:
        with pytest.raises(DeviceTimeout, match="reports pan 0 / tilt 0 .* not the target 1000"):
            ptu.move_to(math.radians(10), 0.0)


def test_a_position_outside_a_turn_is_a_protocol_error():
    with FrameFake(lambda got: [_frame(1, got[3] + 8, 40000)]) as fake:
        with pytest.raises(DeviceProtocolError, match="outside 0-35999"):
            _open(fake)


# -- over the simulator ----------------------------------------------------------------------
def test_the_driver_against_the_simulated_head_on_a_pty():
    rig = wall_rig(4.0)
    rig.speed = 5000.0  # rig counts per second: moves take a while, the driver polls
    with PtyServer(rig, "dimetix", ptu_protocol="pelco-d", ptu_address=7) as server:
        with open_pan_tilt_unit(server.ptu_path, "pelco-d", address=7, timeout=1.0) as ptu:
            from asbuilt.drivers.dimetix import DimetixDLS

            with DimetixDLS.open(server.lrf_path, timeout=1.0) as lrf:
                for pan_deg, tilt_deg in ((0, 0), (15, 3), (-25, -4), (30, 8)):
                    pan, tilt = ptu.move_to(math.radians(pan_deg), math.radians(tilt_deg))
                    expected = 4.0 / (math.cos(pan) * math.cos(tilt))
                    assert lrf.measure() == pytest.approx(expected, abs=1e-3)
                    assert ptu.position() == pytest.approx((pan, tilt), abs=1e-6)
        assert server.error is None


def test_the_simulated_head_over_a_sim_url_with_trickled_replies(wall):
    url = "sim-ptu://wall?protocol=pelco-d&trickle=0.001"
    with open_pan_tilt_unit(url, "pelco-d", timeout=1.0) as ptu:
        ptu.move_to(math.radians(-33.33), math.radians(12.5))
        assert [math.degrees(a) for a in ptu.position()] == pytest.approx([-33.33, 12.5])


def test_unknown_head_protocol_is_one_clear_error():
    with pytest.raises(DeviceError, match="use one of flir, pelco-d"):
        open_pan_tilt_unit("/dev/null", "visca")


def test_a_scan_session_with_the_simulated_pelco_head(scene_file, tmp_path):
    import json

    from asbuilt.drivers.kinematics import Calibration
    from asbuilt.drivers.plan import Target, Window
    from asbuilt.drivers.rangefinder import open_range_finder
    from asbuilt.drivers.session import DeviceShooter, ScanSession

    station = Calibration(base_position=(0.0, 0.0, 1.5))
    pipe = Target("P1", "cylinder", Window.from_degrees([72, -6.5, 108, -1.5]))
    column = Target("C1", "cuboid", Window.from_degrees([63.5, -8, 73, 10]))
    high = Target("H", "plane", Window.from_degrees([80, 91, 100, 95]))  # above the head's reach
    rig = f"pelco?scene={scene_file}&range_sigma=0&protocol=pelco-d"
    out = tmp_path / "scan.json"
    with open_pan_tilt_unit(f"sim-ptu://{rig}", "pelco-d", timeout=1.0) as ptu:
        with open_range_finder("sim-lrf://pelco", timeout=0.5) as lrf:
            with ScanSession(DeviceShooter(ptu, lrf), station, out) as session:
                for target in (pipe, column, high):
                    session.scan(target)
    doc = json.loads(out.read_text())
    assert [o["id"] for o in doc["objects"]] == ["P1", "C1"]
    for obj in doc["objects"]:
        assert len(obj["points"]) >= 20
    pipe_points = doc["objects"][0]["points"]
    # every point on the pipe (axis y = 4, z = 1.2, radius 0.162)
    for _x, y, z in pipe_points:
        assert math.hypot(y - 4.0, z - 1.2) == pytest.approx(0.162, abs=0.003)
    assert "beyond the pan-tilt unit's tilt range [-90.000, 90.000] deg" in session.failed["H"]


class SteppedHead(Head):
    """A head whose steps fall on every ``step`` hundredths: it stops at the step nearest the
    target and reports that (the reference gives no resolution for the position replies)."""

    def __init__(self, step, **kwargs):
        super().__init__(**kwargs)
        self.step = step

    def __call__(self, got: bytes):
        cmd2, value = got[3], (got[4] << 8) | got[5]
        if cmd2 in (0x4B, 0x4D):
            value = round(value / self.step) * self.step % 36000
            got = _frame(got[1], cmd2, value)
        return super().__call__(got)


def test_a_head_stopped_at_the_step_nearest_the_target_has_arrived_where_it_says():
    head = SteppedHead(step=5, polls=2)
    with FrameFake(head) as fake, _open(fake, move_timeout=3.0) as ptu:
        # 12.34 deg -> the head stops at 1235; tilt 3.33 deg up (raw 35667) at 35665
        pan, tilt = ptu.move_to(math.radians(12.34), math.radians(3.33))  # before: DeviceTimeout
        assert math.degrees(pan) == pytest.approx(12.35)
        assert math.degrees(tilt) == pytest.approx(3.35)
        assert ptu.position() == pytest.approx((pan, tilt))
        # one that stops far from the target has stopped short of it (seen moving before)
        head.step = 1000
        with pytest.raises(PTULimitError, match="short of the target 1234 / 0"):
            ptu.move_to(math.radians(12.34), 0.0)


class ClampedHead(Head):
    """A head whose tilt stops at a mechanical limit ``reach`` hundredths either side of level,
    inside the driver's default +-90 degrees (the protocol has no way to report it)."""

    def __init__(self, reach, **kwargs):
        super().__init__(**kwargs)
        self.reach = reach

    def __call__(self, got: bytes):
        cmd2, value = got[3], (got[4] << 8) | got[5]
        if cmd2 == 0x4D:
            signed = value - 36000 if value > 18000 else value
            got = _frame(got[1], cmd2, max(-self.reach, min(self.reach, signed)) % 36000)
        return super().__call__(got)


def test_a_head_stopped_at_a_mechanical_limit_is_a_limit_error_not_a_timeout():
    head = ClampedHead(reach=3000, polls=2)
    with FrameFake(head) as fake, _open(fake, move_timeout=8.0) as ptu:
        ptu.move_to(math.radians(10), math.radians(20))  # within reach: the head is seen moving
        start = time.monotonic()
        with pytest.raises(PTULimitError, match="stopped at pan 1000 / tilt 33000 .* short of"):
            ptu.move_to(math.radians(10), math.radians(45))  # before: DeviceTimeout after 8 s
        with pytest.raises(PTULimitError, match="short of the target 1000 / 31000"):
            ptu.move_to(math.radians(10), math.radians(50))  # already there: does not move
        assert time.monotonic() - start < 7.0
        # back within reach, the head arrives as usual
        pan, tilt = ptu.move_to(math.radians(5), math.radians(-10))
        assert math.degrees(tilt) == pytest.approx(-10)


# -- tilt encoding: 0-35999 or signed 16-bit ----------------------------------------------------
def _rig_tilt_deg(rig):
    return math.degrees(rig.unit_angles()[1])


@pytest.mark.parametrize("tilt_sign", [1, -1])
def test_a_head_whose_tilt_is_signed_16_bit_with_tilt_encoding_signed(tilt_sign):
    # the reference gives no encoding for tilts below zero; some heads use two's complement
    rig = wall_rig(4.0)
    options = {"tilt_encoding": "signed", "tilt_sign": tilt_sign}
    with PtyServer(rig, "dimetix", ptu_protocol="pelco-d", ptu_options=options) as server:
        with PelcoD.open(server.ptu_path, timeout=1.0, move_timeout=3.0, **options) as ptu:
            for tilt_deg in (-10.0, 15.0, -0.01, 0.0):
                pan, tilt = ptu.move_to(math.radians(5), math.radians(tilt_deg))
                assert math.degrees(tilt) == pytest.approx(tilt_deg)
                assert _rig_tilt_deg(rig) == pytest.approx(tilt_deg, abs=0.01)
                assert ptu.position() == pytest.approx((pan, tilt))
            assert ptu.notes == []
        wire = [f for f in _ptu_sim(server).frames if f[3] == 0x4D]
        # -10 deg up: raw -1000 (FC 18) for a head whose raw tilt grows upwards, +1000 (03 E8)
        assert wire[0][4:6] == (b"\xfc\x18" if tilt_sign == 1 else b"\x03\xe8")
        assert server.error is None


def _ptu_sim(server):
    return server._endpoints[0].device


def test_a_signed_tilt_reply_is_read_with_the_default_encoding_and_noted():
    # a reply above 35999 can only be signed 16-bit: read as such, not refused
    rig = wall_rig(4.0)
    rig.move(tilt_counts=rig.tilt.target - 10 * 3600 / rig.resolution[1])  # 10 deg down
    options = {"tilt_encoding": "signed", "tilt_sign": 1}
    with PtyServer(rig, "dimetix", ptu_protocol="pelco-d", ptu_options=options) as server:
        with PelcoD.open(server.ptu_path, timeout=1.0, move_timeout=1.0, tilt_sign=1) as ptu:
            assert math.degrees(ptu.position()[1]) == pytest.approx(-10)  # 64536 = -1000
            assert ptu.signed_tilt_seen
            assert len(ptu.notes) == 1 and "read as signed 16-bit -1000" in ptu.notes[0]
            # at or above level both encodings agree
            assert math.degrees(ptu.move_to(0.0, math.radians(20))[1]) == pytest.approx(20)
            # below it, "wrap" sends 35500, which such a head takes for +355 deg: the error
            # says what to set
            with pytest.raises((DeviceTimeout, PTULimitError), match="--ptu-tilt-encoding"):
                ptu.move_to(0.0, math.radians(-5))
            assert len(ptu.notes) == 1


def test_the_default_encoding_is_unchanged_and_bad_encodings_are_refused():
    head = Head()
    with FrameFake(head) as fake, _open(fake) as ptu:
        ptu.move_to(0.0, math.radians(10))
        assert head.target[1] == 35000
        assert ptu.tilt_encoding == "wrap" and ptu.notes == [] and not ptu.signed_tilt_seen
    with FrameFake(Head()) as fake, pytest.raises(ValueError, match="tilt_encoding"):
        _open(fake, tilt_encoding="two's complement")


# -- a head silent while it moves ---------------------------------------------------------------
def test_a_head_silent_to_position_queries_while_moving_is_asked_until_it_arrives():
    # the reference does not say a head answers position queries while it moves
    rig = wall_rig(4.0)
    rig.speed = 20 * 3600 / rig.resolution[0]  # 20 deg/s: 20 deg of pan take a second
    options = {"busy_silent": True}
    with PtyServer(rig, "dimetix", ptu_protocol="pelco-d", ptu_options=options) as server:
        with PelcoD.open(server.ptu_path, timeout=0.3, move_timeout=5.0) as ptu:
            start = time.monotonic()
            pan, tilt = ptu.move_to(math.radians(20), math.radians(-3))  # before: DeviceTimeout
            assert time.monotonic() - start >= 0.9
            assert [math.degrees(a) for a in (pan, tilt)] == pytest.approx([20, -3])
            assert ptu.position() == pytest.approx((pan, tilt))
        assert server.error is None


def test_a_head_that_stays_silent_after_a_move_times_out_at_the_moves_limit():
    answering = {"on": True}

    def respond(got):
        if got[3] in (0x4B, 0x4D):
            answering["on"] = False  # silent from the first move on
        return Head()(got) if answering["on"] else []

    with FrameFake(respond) as fake, _open(fake, timeout=0.2, move_timeout=1.0) as ptu:
        start = time.monotonic()
        with pytest.raises(DeviceTimeout, match="did not answer position queries up to 1 s"):
            ptu.move_to(math.radians(10), 0.0)
        assert 1.0 <= time.monotonic() - start < 2.0
