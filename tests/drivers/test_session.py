"""Scan sessions: rasters, foreground, edge bisection, retries, journal, crash and resume."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from asbuilt.drivers.kinematics import Calibration
from asbuilt.drivers.plan import SessionSettings, Target, Window
from asbuilt.drivers.ptu import PanTiltUnit, PTUCommandError, PTULimitError
from asbuilt.drivers.rangefinder import SignalTooWeak, open_range_finder
from asbuilt.drivers.session import (
    DeviceShooter,
    ScanSession,
    Shot,
    foreground_threshold,
    grid,
    journal_path_for,
    min_lines,
    read_journal,
    scan_target,
)
from hypothesis import given, settings
from hypothesis import strategies as st

from asbuilt.errors import AsbuiltError, DeviceError, DeviceTimeout, ScanError
from asbuilt.tolerances import DEFAULT_TOLERANCES


@settings(max_examples=50, deadline=None)
@given(
    p0=st.floats(-1, 1),
    t0=st.floats(-0.5, 0.5),
    w=st.floats(0.01, 1.0),
    h=st.floats(0.01, 1.0),
    n=st.integers(1, 60),
)
def test_grid_covers_the_window_with_enough_shots(p0, t0, w, h, n):
    window = Window(p0, p0 + w, t0, t0 + h)
    pan, tilt, (rows, cols) = grid(window, n)
    assert len(pan) == rows * cols >= n
    assert rows >= 3 and cols >= 3
    assert np.all((pan > window.pan_min) & (pan < window.pan_max))
    assert np.all((tilt > window.tilt_min) & (tilt < window.tilt_max))
    assert len(set(zip(pan.round(12), tilt.round(12)))) == len(pan)
    # serpentine: consecutive shots in a row are one cell apart
    assert np.abs(np.diff(pan[:cols])).max() == pytest.approx(w / cols)


@pytest.mark.parametrize(
    "ranges, threshold",
    [
        ([3.0, 3.01, 3.02, 6.0, 6.1], 4.51),
        ([3.0, 3.01, None, 3.02], math.inf),
        ([], math.inf),
        ([5.0, 5.2], math.inf),  # 0.2 m at 5 m is under 5 %: one surface
        ([1.0, 1.05, 1.3], 1.175),  # 0.25 m gap above 0.1 m
    ],
)
def test_foreground_threshold(ranges, threshold):
    assert foreground_threshold(ranges) == pytest.approx(threshold)


def disc_world(radius=0.05, near=3.0, far=6.0):
    """A fake shooter: a disc of angular radius ``radius`` at ``near`` metres, a wall behind."""
    log = []

    def shoot(pan, tilt, phase):
        inside = math.hypot(pan, tilt) < radius
        shot = Shot(pan, tilt, pan, tilt, near if inside else far, None, 1, phase)
        log.append(shot)
        return shot

    return shoot, log


def test_scan_target_puts_enough_points_on_the_object_and_pins_its_edges():
    shoot, log = disc_world()
    target = Target("D", "cylinder", Window(-0.08, 0.08, -0.08, 0.08))
    result = scan_target(target, shoot, SessionSettings(edge_pairs=4, curved_depth=3))
    assert len(result.shots) == len(log)
    on = result.on_object
    assert on.sum() >= 20
    assert all(s.range == 3.0 for s, k in zip(result.shots, on) if k)
    edge = [s for s in result.shots if s.phase == "edge"]
    # three steps for each of the 4 pairs, plus one shot at the cell beyond the (fill) raster's
    # border for each pair that starts there
    assert 12 <= len(edge) <= 16
    # each bisection hit is the midpoint of a hit/miss pair that straddles the silhouette, so
    # it lies within half a raster cell (0.04 x 0.032 rad here) inside the disc's edge
    _, _, (rows, cols) = grid(target.window, 20)
    half_cell = 0.5 * max(0.16 / cols, 0.16 / rows)
    inside = [0.05 - math.hypot(s.pan, s.tilt) for s in edge if s.range == 3.0]
    assert inside and 0.0 < min(inside) and max(inside) <= half_cell + 1e-12


def test_fill_adds_points_when_the_object_is_small_in_the_window():
    shoot, _ = disc_world(radius=0.07)
    target = Target("D", "cuboid", Window(-0.2, 0.2, -0.2, 0.2))
    result = scan_target(target, shoot, SessionSettings(edge_pairs=0))
    phases = [s.phase for s in result.shots]
    first = sum(1 for s, k in zip(result.shots, result.on_object) if k and s.phase == "raster")
    assert first < 30  # the raster alone falls short ...
    assert "fill" in phases
    assert result.on_object.sum() >= 30  # ... the fill raster over the object makes it up


def test_keep_background_keeps_every_return():
    shoot, _ = disc_world()
    target = Target("D", "plane", Window(-0.08, 0.08, -0.08, 0.08))
    result = scan_target(target, shoot, SessionSettings(keep_background=True, edge_pairs=0))
    assert result.on_object.all()


class FakePTU:
    def __init__(self, limit=10.0, refuse_beyond=None):
        self.limit = limit
        self.refuse_beyond = refuse_beyond
        self.moves = []

    def move_to(self, pan, tilt):
        if abs(pan) > self.limit:
            raise PTULimitError("outside")
        if self.refuse_beyond is not None and abs(pan) >= self.refuse_beyond:
            raise PTUCommandError(f"'PP{pan}' refused: position out of range")
        self.moves.append((pan, tilt))
        return round(pan, 3), round(tilt, 3)


class FakeLRF:
    def __init__(self, outcomes):
        self.outcomes = list(outcomes)

    def measure(self):
        outcome = self.outcomes.pop(0)
        if isinstance(outcome, Exception):
            raise outcome
        return outcome


def test_device_shooter_retries_then_measures():
    lrf = FakeLRF([SignalTooWeak("weak", code="E255"), DeviceTimeout("silent"), 4.2])
    shot = DeviceShooter(FakePTU(), lrf, SessionSettings(retries=2))(0.1234, 0.0, "raster")
    assert shot.range == 4.2 and shot.attempts == 3 and shot.error is None
    assert (shot.pan, shot.pan_req) == (0.123, 0.1234)


def test_device_shooter_skips_after_the_retries():
    lrf = FakeLRF([SignalTooWeak("weak", code="E255")] * 3)
    shot = DeviceShooter(FakePTU(), lrf, SessionSettings(retries=2))(0.0, 0.0, "raster")
    assert shot.range is None and shot.error == "E255" and shot.attempts == 3


def test_device_shooter_skips_targets_beyond_the_limits():
    shot = DeviceShooter(FakePTU(limit=1.0), FakeLRF([]))(2.0, 0.0, "edge")
    assert shot.range is None and shot.error == "limit"


def test_a_refused_move_skips_its_shot_and_the_session_goes_on():
    # The manual allows '! <message>' for any command: a unit holding its limits exclusive
    # refuses a move to the limit itself.
    shooter = DeviceShooter(FakePTU(refuse_beyond=1.0), FakeLRF([4.2]))
    shot = shooter(1.0, 0.0, "edge")
    assert shot.range is None and shot.error == "refused" and shot.attempts == 0
    assert shooter(0.5, 0.0, "raster").range == 4.2


def test_a_unit_refusing_every_move_is_declared_lost():
    shooter = DeviceShooter(FakePTU(refuse_beyond=0.0), FakeLRF([]), SessionSettings(lost_after=3))
    assert shooter(0.1, 0, "raster").error == "refused"
    assert shooter(0.2, 0, "raster").error == "refused"
    with pytest.raises(PTUCommandError, match="refused.*3 shots in a row.*--resume"):
        shooter(0.3, 0, "raster")


def test_a_silent_range_finder_is_declared_lost():
    lrf = FakeLRF([DeviceTimeout("silent")] * 10)
    shooter = DeviceShooter(FakePTU(), lrf, SessionSettings(retries=0, lost_after=3))
    assert shooter(0, 0, "raster").error == "timeout"
    assert shooter(0, 0, "raster").error == "timeout"
    with pytest.raises(DeviceTimeout, match="3 shots in a row.*--resume"):
        shooter(0, 0, "raster")


# -- sessions over the simulated devices -------------------------------------------------------
STATION = Calibration(base_position=(0.0, 0.0, 1.5))
PIPE = Target("P1", "cylinder", Window.from_degrees([72, -6.5, 108, -1.5]))
COLUMN = Target("C1", "cuboid", Window.from_degrees([63.5, -8, 73, 10]))


def _devices(scene_file, rig, lrf_options=""):
    ptu = PanTiltUnit.open(f"sim-ptu://{rig}?scene={scene_file}&range_sigma=0", timeout=1.0)
    lrf = open_range_finder(f"sim-lrf://{rig}{lrf_options}", timeout=0.5)
    return ptu, lrf


def _run(scene_file, out, rig, targets, lrf_options="", resume=False):
    ptu, lrf = _devices(scene_file, rig, lrf_options)
    try:
        with ScanSession(DeviceShooter(ptu, lrf), STATION, out, resume=resume) as session:
            for target in targets:
                if not session.is_done(target.id):
                    session.scan(target)
            return session
    finally:
        ptu.close()
        lrf.close()


def test_session_writes_scan_and_journal(scene_file, tmp_path):
    out = tmp_path / "scan.json"
    session = _run(scene_file, out, "s1", [PIPE, COLUMN])
    doc = json.loads(out.read_text())
    assert doc["format"] == "asbuilt-scan" and doc["units"] == "m"
    assert [o["id"] for o in doc["objects"]] == ["P1", "C1"]
    for obj in doc["objects"]:
        assert len(obj["points"]) == len(obj["measurements"]) >= 20
    records = read_journal(journal_path_for(out))
    shots = [r for r in records if r["type"] == "shot"]
    assert len(shots) == sum(len(r.shots) for r in session.objects.values())
    assert [r["type"] for r in records if r["type"] != "shot"] == [
        "session",
        "object",
        "done",
        "object",
        "done",
    ]
    # the raw measurements recompute the points through the chain
    from asbuilt.drivers.kinematics import forward

    m = np.array(doc["objects"][0]["measurements"])
    pts = forward(STATION, np.radians(m[:, 0]), np.radians(m[:, 1]), m[:, 2])
    assert pts == pytest.approx(np.array(doc["objects"][0]["points"]), abs=1e-8)


@pytest.mark.parametrize("laser", [(0.0, 0.0, 0.0), (0.0, 0.03, 0.01)])
def test_the_sensor_position_is_where_the_beams_start(scene_file, tmp_path, laser):
    # A PTU-D46's tilt axis is 47 mm above its base. Seen from the base, a raster row's shots
    # have tilts that change with their range (a parallax of 0.01 degree at 5 m for 3 cm of
    # range), and the fits could not tell the row's shots, nor its bisection shots, apart.
    from asbuilt.drivers.kinematics import beam

    station = Calibration(
        base_position=(0.0, 0.0, 1.5), tilt_axis_offset=(0.0, 0.0, 0.047), laser_offset=laser
    )
    ptu, lrf = _devices(scene_file, f"origin{laser[1]}")
    out = tmp_path / "scan.json"
    try:
        with ScanSession(DeviceShooter(ptu, lrf), station, out) as session:
            session.scan(COLUMN)
    finally:
        ptu.close()
        lrf.close()
    doc = json.loads(out.read_text())
    position = np.array(doc["sensor"]["position"])
    m = np.radians(np.array(doc["objects"][0]["measurements"])[:, :2])
    origins, directions = beam(station, m[:, 0], m[:, 1])
    assert position == pytest.approx(origins.mean(axis=0), abs=1e-9)
    # every point on its beam as seen from there: exactly with the laser on the tilt axis,
    # to within the laser's offset (a few centimetres at metres) otherwise
    rays = np.array(doc["objects"][0]["points"]) - position
    rays /= np.linalg.norm(rays, axis=1, keepdims=True)
    off = np.degrees(np.arccos(np.clip(np.sum(rays * directions, axis=1), -1.0, 1.0)))
    if laser == (0.0, 0.0, 0.0):
        assert position == pytest.approx([0.0, 0.0, 1.547], abs=1e-12)
        assert off.max() < 1e-6
    else:
        assert off.max() < 0.5


def test_crash_mid_object_then_resume_gives_the_uninterrupted_scan(scene_file, tmp_path):
    whole = tmp_path / "whole.json"
    _run(scene_file, whole, "w", [PIPE, COLUMN])

    out = tmp_path / "crash.json"
    with pytest.raises(DeviceError, match="unplugged"):
        _run(scene_file, out, "c1", [PIPE, COLUMN], lrf_options="?unplug_after=70")
    # the scan holds what was finished, the journal every shot up to the crash
    partial = json.loads(out.read_text())
    assert [o["id"] for o in partial["objects"]] == ["P1"]
    taken = [r for r in read_journal(journal_path_for(out)) if r["type"] == "shot"]
    assert len(taken) == 70
    with pytest.raises(ScanError, match="--resume"):
        _run(scene_file, out, "c2", [PIPE, COLUMN])
    _run(scene_file, out, "c3", [PIPE, COLUMN], resume=True)
    assert json.loads(out.read_text())["objects"] == json.loads(whole.read_text())["objects"]
    shots = [r for r in read_journal(journal_path_for(out)) if r["type"] == "shot"]
    whole_shots = [r for r in read_journal(journal_path_for(whole)) if r["type"] == "shot"]
    assert len(shots) == len(whole_shots)  # no shot was taken twice


def test_torn_last_journal_line_is_ignored(scene_file, tmp_path):
    out = tmp_path / "torn.json"
    with pytest.raises(DeviceError):
        _run(scene_file, out, "t1", [PIPE], lrf_options="?unplug_after=10")
    journal = journal_path_for(out)
    with open(journal, "a") as f:
        f.write('{"type":"shot","obj')  # the crash hit mid-write
    assert len([r for r in read_journal(journal) if r["type"] == "shot"]) == 10
    session = _run(scene_file, out, "t2", [PIPE], resume=True)
    assert "P1" in session.objects


def _crashed_in_c1(scene_file, tmp_path, rig):
    """A journal with P1 finished and C1 interrupted (the range finder unplugged), ending in a
    torn line (the crash hit mid-write); its path."""
    out = tmp_path / "crashed.json"
    with pytest.raises(DeviceError):
        _run(scene_file, out, rig, [PIPE, COLUMN], lrf_options="?unplug_after=70")
    journal = journal_path_for(out)
    with open(journal, "a") as f:
        f.write('{"type":"shot","object":"C1","seq":9,"req":[1.2')  # torn: the only trace
    return journal


def _resume_pending(scene_file, out, rig):
    """What ``asbuilt scan --resume`` does first: open the session, finish the pending object."""
    ptu, lrf = _devices(scene_file, rig)
    try:
        with ScanSession(DeviceShooter(ptu, lrf), STATION, out, resume=True) as session:
            if session.pending is not None:
                session.scan(session.pending)
    finally:
        ptu.close()
        lrf.close()


def _pending_object_finished_earlier(journal, out):
    # an edited journal begins P1 again after its 'done': the pending object is in the scan
    with open(journal, "r+b") as f:
        data = f.read()
        torn = data.rindex(b"\n") + 1
        f.seek(torn)
        f.write(b'{"type":"object","target":' + json.dumps(PIPE.to_dict()).encode() + b"}\n")
        f.write(data[torn:])
        f.truncate()
    return out


def _out_is_a_directory(journal, out):
    # the scan file's name is now a directory: the finished P1 cannot be written back
    out.unlink()
    out.mkdir()
    return out


@pytest.mark.parametrize(
    "edit, message",
    [
        (_pending_object_finished_earlier, "P1"),
        (_out_is_a_directory, "is a directory"),
    ],
    ids=["pending-object-finished-earlier", "out-is-a-directory"],
)
def test_a_refused_resume_leaves_the_journal_byte_for_byte(scene_file, tmp_path, edit, message):
    """Refusing a journal must not cut its torn last line, append a resume record or write a
    sidecar: the bytes before and after are the same (both paths modified it before)."""
    journal = _crashed_in_c1(scene_file, tmp_path, "rj1")
    out = edit(journal, tmp_path / "crashed.json")
    before = journal.read_bytes()
    listing = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(AsbuiltError, match=message):
        _resume_pending(scene_file, out, "rj2")
    assert journal.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == listing


def test_a_resume_refused_for_its_units_leaves_the_journal_byte_for_byte(scene_file, tmp_path):
    journal = _crashed_in_c1(scene_file, tmp_path, "ru1")
    before = journal.read_bytes()
    with pytest.raises(ScanError, match="resume with --units m"):
        ScanSession(lambda *a: None, STATION, tmp_path / "crashed.json", units="mm", resume=True)
    assert journal.read_bytes() == before


def test_an_accepted_resume_keeps_the_torn_last_line_beside_the_journal(scene_file, tmp_path):
    journal = _crashed_in_c1(scene_file, tmp_path, "rk1")
    torn = journal.read_bytes().rsplit(b"\n", 1)[1]
    _resume_pending(scene_file, tmp_path / "crashed.json", "rk2")
    assert (tmp_path / "crashed.json.journal.torn").read_bytes() == torn + b"\n"
    assert torn not in journal.read_bytes()
    assert read_journal(journal)[-1]["type"] == "done"


def test_resume_without_journal(tmp_path):
    with pytest.raises(ScanError, match="no journal to resume"):
        ScanSession(lambda *a: None, STATION, tmp_path / "s.json", resume=True)


def test_object_that_misses_everything_is_reported_not_added(scene_file, tmp_path):
    nothing = Target("X", "cylinder", Window.from_degrees([-100, 10, -90, 20]))  # the open sky
    out = tmp_path / "sky.json"
    session = _run(scene_file, out, "sky", [nothing, PIPE])
    assert "X" in session.failed and "re-aim" in session.failed["X"]
    assert list(session.objects) == ["P1"]
    assert json.loads(out.read_text())["acquisition"]["failed"] == {"X": session.failed["X"]}


def test_a_window_beyond_the_units_reach_is_reported_as_such_not_as_aim(scene_file, tmp_path):
    """Tilt 35-45 deg is above the simulated unit's +31.063 deg: every shot is refused before the
    head moves, and the reason names the tilt range (read from the unit), not the aim."""
    high = Target("H", "plane", Window.from_degrees([80, 35, 100, 45]))
    session = _run(scene_file, tmp_path / "high.json", "high", [high])
    reason = session.failed["H"]
    assert "re-aim" not in reason and "pan range" not in reason
    assert "shots were beyond the pan-tilt unit's tilt range [-46.646, 31.063] deg" in reason
    assert reason.endswith("put the window within reach or move the station")
    journal = [
        json.loads(line) for line in (tmp_path / "high.json.journal").read_text().splitlines()
    ]
    shots = [r for r in journal if r["type"] == "shot"]
    assert shots and all(r["error"] == "limit" for r in shots)
    assert reason.startswith(f"{len(shots)} of {len(shots)} shots")


def test_duplicate_object_ids_are_refused(scene_file, tmp_path):
    ptu, lrf = _devices(scene_file, "dup")
    with ScanSession(DeviceShooter(ptu, lrf), STATION, tmp_path / "d.json") as session:
        session.scan(PIPE)
        with pytest.raises(ScanError, match="already in the scan"):
            session.scan(PIPE)


# -- edge seeking ---------------------------------------------------------------------------------
def box_world(half_pan=0.05, half_tilt=0.12, near=4.0, far=7.0):
    """A fake shooter: an angular rectangle (a column seen side-on) at ``near``, a wall behind."""
    log = []

    def shoot(pan, tilt, phase):
        inside = abs(pan - 0.01) < half_pan and abs(tilt + 0.02) < half_tilt
        shot = Shot(pan, tilt, pan, tilt, near if inside else far, None, 1, phase)
        log.append(shot)
        return shot

    return shoot, log


@pytest.mark.parametrize("tolerance", [0.002, 0.005, 0.02])
def test_every_side_is_bisected_down_to_the_tolerance(tolerance):
    shoot, _ = box_world()
    # an operator's window: wider than the object by uneven margins
    target = Target("C", "cuboid", Window(-0.07, 0.09, -0.17, 0.13))
    settings = SessionSettings(edge_pairs=4, edge_tolerance=tolerance, edge_depth=20)
    result = scan_target(target, shoot, settings)
    edges = [(s, k) for s, k in zip(result.shots, result.on_object) if s.phase == "edge"]
    hits = [s for s, k in zip(result.shots, result.on_object) if k]
    # the outermost hit towards each side's edge: within the tolerance (across the beam at 4 m)
    gaps = {
        "left": min(s.pan - (0.01 - 0.05) for s in hits),
        "right": min((0.01 + 0.05) - s.pan for s in hits),
        "bottom": min(s.tilt - (-0.02 - 0.12) for s in hits),
        "top": min((-0.02 + 0.12) - s.tilt for s in hits),
    }
    for side, gap in gaps.items():
        assert 0.0 <= gap * 4.0 <= tolerance, side
    # and no more shots than halving the first bracket (one raster cell) down to the tolerance,
    # plus one per side for the cell beyond the raster's border when the pair starts there and
    # one per side a bracket back inside when the last hit is on a line of other hits
    _, _, (rows, cols) = grid(target.window, 30)
    cells = (target.window.width / cols, target.window.height / rows)
    most = sum(2 * math.ceil(math.log2(c * 4.0 / tolerance)) for c in cells) + 8
    assert len(edges) <= most


def test_a_bisection_stops_at_the_heads_resolution():
    # A PTU-D46 aims in whole positions of 0.0514 degree: once a bracket is one position across,
    # a midpoint reaches one of its ends again. The bisection stops there instead of shooting
    # the same position again until its depth runs out (each repeat a point counted twice).
    step = math.radians(0.0514)
    shoot_exactly, _ = box_world()

    def shoot(pan, tilt, phase):
        at = shoot_exactly(round(pan / step) * step, round(tilt / step) * step, phase)
        return dataclasses.replace(at, pan_req=pan, tilt_req=tilt)

    target = Target("C", "cuboid", Window(-0.07, 0.09, -0.17, 0.13))
    settings = SessionSettings(edge_pairs=4, edge_tolerance=1e-6, edge_depth=30, edge_shots=200)
    result = scan_target(target, shoot, settings)
    edges = [s for s in result.shots if s.phase == "edge"]
    positions = [(s.pan, s.tilt) for s in result.shots]
    repeats = len(positions) - len(set(positions))
    # One repeat at most per bisected pair (the shot that finds the bracket closed), where an
    # unbounded bisection would spend its depth: 30 shots a pair.
    assert repeats <= 4
    assert len(edges) <= 4 * 12
    # and each side's edge is still pinned to within one position of the truth
    hits = [s for s, k in zip(result.shots, result.on_object) if k]
    assert min(s.pan for s in hits) - (0.01 - 0.05) < step
    assert (0.01 + 0.05) - max(s.pan for s in hits) < step


def test_edge_shots_are_capped_per_object():
    shoot, _ = box_world()
    target = Target("C", "cuboid", Window(-0.07, 0.09, -0.17, 0.13))
    settings = SessionSettings(edge_pairs=8, edge_tolerance=1e-6, edge_depth=30, edge_shots=11)
    result = scan_target(target, shoot, settings)
    assert sum(s.phase == "edge" for s in result.shots) == 11


@pytest.mark.parametrize(
    "counts, want, expected",
    [
        (
            {"left": 5, "right": 5, "bottom": 3, "top": 3},
            4,
            {"left": [2], "right": [2], "bottom": [1], "top": [1]},
        ),
        (
            {"left": 4, "right": 4, "bottom": 0, "top": 2},
            4,
            {"left": [1, 3], "right": [2], "top": [1]},
        ),
        ({"left": 1, "right": 6, "bottom": 0, "top": 0}, 4, {"left": [0], "right": [1, 3, 5]}),
        ({"left": 3, "right": 3, "bottom": 3, "top": 3}, 0, {}),
        (
            {"left": 1, "right": 1, "bottom": 1, "top": 1},
            9,
            {s: [0] for s in ("left", "right", "bottom", "top")},
        ),
    ],
)
def test_pairs_are_dealt_to_every_side(counts, want, expected):
    from asbuilt.drivers.edges import deal_pairs

    sides = {side: [(side, i) for i in range(k)] for side, k in counts.items()}
    dealt = deal_pairs(sides, want)
    got: dict = {}
    for side, i in dealt:
        got.setdefault(side, []).append(i)
    assert got == expected


@pytest.mark.parametrize(
    "field, value",
    [
        ("edge_tolerance", 0.0),
        ("edge_tolerance", -0.001),
        ("edge_tolerance", math.nan),
        ("edge_shots", -1),
        ("edge_depth", -1),
    ],
)
def test_bad_edge_settings_are_refused(field, value):
    with pytest.raises(ValueError, match=field):
        SessionSettings(**{field: value})


def test_resume_replays_tolerance_driven_bisection():
    shoot, log = box_world()
    target = Target("C", "cuboid", Window(-0.07, 0.09, -0.17, 0.13))
    whole = scan_target(target, shoot)
    from asbuilt.drivers.session import _Replay

    # half the shots from the journal, the rest live: the same shots in the same order
    replay = _Replay(list(whole.shots[: len(whole.shots) // 2]), box_world()[0])
    again = scan_target(target, replay)
    assert [(s.pan_req, s.tilt_req, s.range) for s in again.shots] == [
        (s.pan_req, s.tilt_req, s.range) for s in whole.shots
    ]
    assert replay.i == len(whole.shots) // 2 and not replay.diverged


#: The paper's minimum point counts only (not its recommended 30 per cuboid): a small budget.
FEW_POINTS = dataclasses.replace(DEFAULT_TOLERANCES, recommended_points_cuboid=7)


@pytest.mark.parametrize(
    "kind, window, expected",
    [
        ("cuboid", Window(-0.03, 0.03, -0.3, 0.3), (3, 5)),  # a column: five columns of shots
        ("cuboid", Window(-0.3, 0.3, -0.03, 0.03), (5, 3)),  # a beam: five rows
        ("cuboid", Window(-0.1, 0.1, -0.1, 0.1), (5, 5)),  # a box: either split
        ("cuboid", Window(-0.1, 0.1, -0.06, 0.06), (5, 5)),  # under twice as wide as tall
        ("cuboid", Window(-0.2, 0.2, 1.0, 1.4), (3, 5)),  # pan extent shrinks by cos(tilt)
        ("cylinder", Window(-0.03, 0.03, -0.3, 0.3), (3, 3)),
    ],
)
def test_min_lines_across_and_along_an_elongated_window(kind, window, expected):
    assert min_lines(kind, window) == expected


def test_a_column_window_spends_no_extra_rows_along_the_column():
    shoot, _ = box_world(half_pan=0.02, half_tilt=0.25)
    target = Target("C", "cuboid", Window(-0.015, 0.035, -0.3, 0.26), points=12)
    result = scan_target(target, shoot, SessionSettings(edge_pairs=0), FEW_POINTS)
    raster = [s for s in result.shots if s.phase == "raster"]
    assert len(raster) == 15  # five columns across, three rows along: not 5 x 5
    assert len({round(s.pan, 12) for s in raster}) == 5


def notched_world(near=4.0, far=7.0):
    """A column whose upper left corner is cut off (as a column's top, seen from below, cuts
    the row through it short of the vertical edge): pan -0.04..0.06 for tilt -0.14..0.06, only
    -0.01..0.06 above that up to 0.10."""

    def shoot(pan, tilt, phase):
        body = -0.04 < pan < 0.06 and -0.14 < tilt < 0.06
        head = -0.01 < pan < 0.06 and 0.06 <= tilt < 0.10
        return Shot(pan, tilt, pan, tilt, near if body or head else far, None, 1, phase)

    return shoot


def test_side_pairs_bracket_the_outermost_line_of_object_cells():
    # five raster rows: four on the body (tilt -0.124 to 0.032), one on the cut-off head (0.084)
    target = Target("C", "cuboid", Window(-0.05, 0.07, -0.15, 0.11), points=23)
    result = scan_target(target, notched_world(), SessionSettings(edge_pairs=4), FEW_POINTS)
    assert not any(s.phase == "fill" for s in result.shots)
    hits = [s for s, k in zip(result.shots, result.on_object) if k]
    # the left edge is pinned where it is the object's extreme, not at the cut-off head
    assert min(s.pan for s in hits) == pytest.approx(-0.04, abs=0.002 / 4.0)
    left = [s for s in result.shots if s.phase == "edge" and s.pan < -0.0141]
    assert left and all(s.tilt == pytest.approx(-0.072) for s in left)  # a body row


def test_a_bracket_that_never_hit_again_adds_a_hit_off_the_raster_lines():
    window = Window(-0.05, 0.07, -0.3, 0.26)
    target = Target("C", "cuboid", window, points=12)
    pans, _, _ = grid(window, 12, min_lines("cuboid", window))
    columns = np.unique(pans)
    # the right edge a hair (0.04 mm at 4 m) beyond a raster column: every bisection step misses
    right = columns[3] + 1e-5
    shoot, _ = box_world(half_pan=(right - columns[1] + 0.002) / 2, half_tilt=0.25)
    shift = 0.5 * (right + columns[1] - 0.002) - 0.01  # box_world is centred on pan 0.01

    def shifted(pan, tilt, phase):
        shot = shoot(pan - shift, tilt, phase)
        return Shot(pan, tilt, pan, tilt, shot.range, None, 1, phase)

    result = scan_target(target, shifted, SessionSettings(edge_pairs=4), FEW_POINTS)
    hits = [s for s, k in zip(result.shots, result.on_object) if k]
    off_lines = [s for s in hits if s.phase == "edge" and np.abs(columns - s.pan).min() > 1e-9]
    # a hit a bracket (at most the 2 mm tolerance at 4 m) inside the column, off every column
    back = [s for s in off_lines if columns[3] - 0.002 / 4.0 <= s.pan < columns[3]]
    assert back


def test_a_back_shot_that_misses_steps_further_inside():
    # The raster column's shot on the pair's row hit although the edge there lies a tolerance
    # (2 mm at 4 m) inside the column (a pointing error): the first shot a bracket back
    # inside misses too, the next, two brackets inside, lands on the object.
    window = Window(-0.05, 0.07, -0.3, 0.26)
    target = Target("C", "cuboid", window, points=12)
    pans, _, _ = grid(window, 12, min_lines("cuboid", window))
    columns = np.unique(pans)
    edge = columns[3] - 0.002 / 4.0

    def shoot(pan, tilt, phase):
        on = (columns[1] - 0.002 < pan < edge or abs(pan - columns[3]) < 1e-12) and abs(
            tilt + 0.02
        ) < 0.25
        return Shot(pan, tilt, pan, tilt, 4.0 if on else 7.0, None, 1, phase)

    result = scan_target(target, shoot, SessionSettings(edge_pairs=4), FEW_POINTS)
    right = [
        (s, k)
        for s, k in zip(result.shots, result.on_object)
        if s.phase == "edge" and columns[3] - 0.01 / 4.0 < s.pan < columns[3]
    ]
    assert len(right) >= 2 and not right[0][1]  # the first one back missed ...
    assert right[-1][1] and right[-1][0].pan < edge  # ... a later one hit, inside the edge


def test_an_insulated_target_is_written_in_the_file_units_and_survives_a_resume(
    scene_file, tmp_path
):
    """The thickness (metres in the target) is written in the scan's units, the journal keeps it
    in the plan's metres, and a resumed object is written with it; the scan loader reads it back
    in metres."""
    from asbuilt.scan import load_scan

    lagged = dataclasses.replace(PIPE, insulation=0.05)

    def run(rig, lrf_options="", resume=False):
        ptu, lrf = _devices(scene_file, rig, lrf_options)
        try:
            shooter = DeviceShooter(ptu, lrf)
            with ScanSession(shooter, STATION, out, units="mm", resume=resume) as session:
                if session.pending is not None:
                    session.scan(session.pending)
                for target in (lagged, COLUMN):
                    if not session.is_done(target.id):
                        session.scan(target)
        finally:
            ptu.close()
            lrf.close()

    out = tmp_path / "lagged.json"
    with pytest.raises(DeviceError, match="unplugged"):
        run("lag1", lrf_options="?unplug_after=10")  # in the middle of P1
    objects = [r for r in read_journal(journal_path_for(out)) if r["type"] == "object"]
    assert objects[0]["target"]["insulation"] == 0.05
    run("lag2", resume=True)
    doc = json.loads(out.read_text())
    assert doc["units"] == "mm"
    assert doc["objects"][0]["insulation"] == 50  # not 50.00000000000001
    assert "insulation" not in doc["objects"][1]
    scan = load_scan(out)
    assert scan.object("P1").insulation == pytest.approx(0.05)
    assert scan.object("C1").insulation == 0


@pytest.mark.parametrize("units", ["m", "mm", "cm", "in", "ft"])
def test_the_thickest_insulation_a_target_takes_is_one_the_scan_loader_reads(units):
    from asbuilt.drivers.session import _file_thickness

    from asbuilt.scan.insulation import MAX_INSULATION
    from asbuilt.units import unit_factor

    k = unit_factor(units)
    for metres in (MAX_INSULATION, math.nextafter(MAX_INSULATION, 0), 0.0381, 0.0):
        assert _file_thickness(metres, k) * k <= MAX_INSULATION
        assert _file_thickness(metres, k) * k == pytest.approx(metres, abs=1e-9)
