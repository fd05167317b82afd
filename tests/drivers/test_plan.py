"""Plan files, targets and windows."""

from __future__ import annotations

import json
import math

import pytest
from asbuilt.drivers.plan import (
    Plan,
    Target,
    Window,
    load_plan,
    plan_digest,
    plan_record,
    plan_to_dict,
    required_points,
    resume_plan_mismatch,
)

from asbuilt.errors import ScanError
from asbuilt.tolerances import MIN_POINTS


def test_window_from_corners_in_any_order():
    w = Window.from_degrees([10, 5, -10, -5])
    assert w.degrees() == pytest.approx([-10, -5, 10, 5])
    assert w.width == pytest.approx(math.radians(20))
    assert w.height == pytest.approx(math.radians(10))


@pytest.mark.parametrize("corners", [[0, 0, 0, 5], [0, 0, 5, 0], [0, 0, float("nan"), 1]])
def test_degenerate_windows(corners):
    with pytest.raises(ValueError):
        Window.from_degrees(corners)


@pytest.mark.parametrize(
    "kind, paper",
    [("cylinder", 20), ("cuboid", 30), ("sphere", 20), ("plane", 12), ("hull", 30), ("auto", 30)],
)
def test_required_points_meet_the_papers_minimums(kind, paper):
    assert required_points(kind) == paper
    assert required_points(kind) >= MIN_POINTS[kind]


def test_target_wants_at_least_the_minimum():
    w = Window.from_degrees([0, 0, 1, 1])
    assert Target("a", "cylinder", w, points=5).wanted() == 20
    assert Target("a", "cylinder", w, points=35).wanted() == 35


def test_plan_round_trip(tmp_path):
    plan = Plan(
        (
            Target(
                "P1",
                "cylinder",
                Window.from_degrees([-10, -3, 12, 4]),
                points=24,
                group="line-1",
                nominal='4"',
                insulation=0.05,
            ),
            Target("C1", "cuboid", Window.from_degrees([20, -10, 30, 10])),
        ),
        {"retries": 1},
    )
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(plan_to_dict(plan)))
    back = load_plan(path)
    assert back.settings == {"retries": 1}
    assert [t.id for t in back.targets] == ["P1", "C1"]
    assert back.targets[0].points == 24 and back.targets[0].nominal == '4"'
    assert back.targets[0].insulation == 0.05 and back.targets[1].insulation is None
    assert back.targets[0].window.degrees() == pytest.approx([-10, -3, 12, 4])


GOOD = {"id": "P1", "kind": "cylinder", "window_deg": [0, 0, 10, 5]}


@pytest.mark.parametrize(
    "doc, where",
    [
        ({"format": "x"}, "not a plan file"),
        ({"format": "asbuilt-scan-plan", "version": 2, "targets": [GOOD]}, "version"),
        ({"format": "asbuilt-scan-plan", "version": 1, "targets": []}, "targets"),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [{**GOOD, "kind": "cone"}]},
            "targets[0] (P1).kind",
        ),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [{**GOOD, "window_deg": [1]}]},
            "targets[0] (P1).window_deg",
        ),
        (
            {
                "format": "asbuilt-scan-plan",
                "version": 1,
                "targets": [{**GOOD, "window_deg": [1, 1, 1, 2]}],
            },
            "targets[0] (P1).window_deg",
        ),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [{**GOOD, "points": 0}]},
            "targets[0] (P1).points",
        ),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [{**GOOD, "id": ""}]},
            "targets[0].id",
        ),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [{**GOOD, "nominl": "12"}]},
            "targets[0] (P1).nominl: unknown key; use id, kind, window_deg",
        ),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [GOOD], "setings": {}},
            "setings: unknown key; use format, version, comment, settings, targets",
        ),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [GOOD], "comment": 3},
            "comment: must be a string",
        ),
        (
            {"format": "asbuilt-scan-plan", "version": 1, "targets": [GOOD, GOOD]},
            "targets[1] (P1): duplicate id",
        ),
        (
            {
                "format": "asbuilt-scan-plan",
                "version": 1,
                "targets": [GOOD],
                "settings": {"retry": 1},
            },
            "settings.retry",
        ),
        (
            {
                "format": "asbuilt-scan-plan",
                "version": 1,
                "targets": [GOOD],
                "settings": {"retries": -1},
            },
            "settings.retries",
        ),
        (
            {
                "format": "asbuilt-scan-plan",
                "version": 1,
                "targets": [GOOD],
                "settings": {"edge_tolerance": 0},
            },
            "settings.edge_tolerance",
        ),
        (
            {
                "format": "asbuilt-scan-plan",
                "version": 1,
                "targets": [GOOD],
                "settings": {"edge_tolerance": "2mm"},
            },
            "settings.edge_tolerance",
        ),
        (
            {
                "format": "asbuilt-scan-plan",
                "version": 1,
                "targets": [GOOD],
                "settings": {"edge_tolerance": True},
            },
            "settings.edge_tolerance",
        ),
        (
            {
                "format": "asbuilt-scan-plan",
                "version": 1,
                "targets": [GOOD],
                "settings": {"edge_shots": 2.5},
            },
            "settings.edge_shots",
        ),
    ],
)
def test_bad_plans_name_the_place(tmp_path, doc, where):
    path = tmp_path / "plan.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ScanError) as info:
        load_plan(path)
    assert where in str(info.value)
    assert str(info.value).startswith(str(path))


def test_unreadable_plan(tmp_path):
    with pytest.raises(ScanError, match="cannot read the plan"):
        load_plan(tmp_path / "missing.json")
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(ScanError, match="not valid JSON"):
        load_plan(tmp_path / "bad.json")


@pytest.mark.parametrize(
    "settings",
    [{"edge_tolerance": 0.003}, {"edge_tolerance": 1}, {"edge_shots": 12, "edge_depth": 5}],
)
def test_edge_settings_in_a_plan_make_session_settings(tmp_path, settings):
    from asbuilt.drivers.plan import SessionSettings

    path = tmp_path / "plan.json"
    doc = {"format": "asbuilt-scan-plan", "version": 1, "targets": [GOOD], "settings": settings}
    path.write_text(json.dumps(doc))
    made = SessionSettings(**load_plan(path).settings)
    for key, value in settings.items():
        assert getattr(made, key) == value


# Found by mutation fuzzing (asbuilt scan --plan over the simulators, 400 mutated plans): each
# was a traceback (or the planner allocating gigabytes until the process was killed) and is
# now one located line.
_TARGET = '{"id": "A", "kind": "plane", "window_deg": %s%s}'


def _plan_text(target=None, settings="{}"):
    target = target or _TARGET % ("[0, 0, 10, 10]", "")
    head = '"format": "asbuilt-scan-plan", "version": 1'
    return f'{{{head}, "targets": [{target}], "settings": {settings}}}'


@pytest.mark.parametrize(
    "content, message",
    [
        (
            _plan_text().encode() + b"\xff",
            "is not UTF-8 text (byte 0xff at offset 134); save the plan as UTF-8 JSON",
        ),
        (
            _plan_text(_TARGET % ("[0, 0, 10, 10]", ', "points": 1000000000')).encode(),
            "targets[0] (A).points: must be at most 1,000,000 (the most a scan holds)",
        ),
        (
            _plan_text(_TARGET % ("[-1e308, 0, 1e308, 10]", "")).encode(),
            "targets[0] (A).window_deg: angles must be finite and within +-360 degrees (a turn)",
        ),
        (
            _plan_text(_TARGET % ("[1" + "0" * 400 + ", 0, 10, 10]", "")).encode(),
            "targets[0] (A).window_deg: angles must be finite and within +-360 degrees (a turn)",
        ),
        (
            _plan_text(settings='{"lost_after": 0}').encode(),
            "settings.lost_after: must be an integer >= 1",
        ),
        (
            _plan_text(settings='{"retries": 1' + "0" * 5000 + "}").encode(),
            "settings.retries: must be an integer >= 0",
        ),
        (("[" * 100_000).encode(), "not valid JSON (nested too deeply)"),
    ],
    ids=[
        "not-utf8",
        "points-beyond-a-scan",
        "window-beyond-a-turn",
        "window-integer-400-digits",
        "lost-after-zero",
        "integer-5000-digits",
        "nested-too-deeply",
    ],
)
def test_fuzzed_plans_are_one_located_line(tmp_path, content, message):
    path = tmp_path / "plan.json"
    path.write_bytes(content)
    with pytest.raises(ScanError) as info:
        load_plan(path)
    assert str(info.value) == f"{path}: {message}"


def _insulated(tmp_path, **target):
    path = tmp_path / "plan.json"
    doc = {"format": "asbuilt-scan-plan", "version": 1, "targets": [{**GOOD, **target}]}
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize("thickness", [0, 0.05, 0.5, None])
def test_a_cylinders_insulation_is_metres_like_every_plan_length(tmp_path, thickness):
    target = load_plan(_insulated(tmp_path, insulation=thickness)).targets[0]
    assert target.insulation == thickness
    assert ("insulation" in target.to_dict()) is (thickness is not None)


@pytest.mark.parametrize(
    "target, message",
    [
        (
            {"insulation": -0.01},
            "must be a number >= 0 (the insulation's thickness in metres), not -0.01",
        ),
        (
            {"insulation": "50 mm"},
            'must be a number >= 0 (the insulation\'s thickness in metres), not a string ("50 mm")',
        ),
        ({"insulation": True}, "not true"),
        ({"insulation": [0.05]}, "not an array"),
        (
            {"insulation": 50},
            "50 m is thicker than any pipe insulation (at most 0.5 m); a plan's lengths are in "
            "metres (50 mm is 0.05): check the value",
        ),
        (
            {"insulation": 10**400},
            "must be a number >= 0 (the insulation's thickness in metres), not infinite",
        ),
        (
            {"kind": "cuboid", "insulation": 0.05},
            'insulation is a radial thickness on a cylinder, not on kind "cuboid"; give the '
            'target "kind": "cylinder" or remove its insulation',
        ),
        ({"kind": "sphere", "insulation": 0.05}, 'not on kind "sphere"'),
    ],
    ids=["negative", "text", "boolean", "array", "millimetres", "huge-integer", "cuboid", "sphere"],
)
def test_a_bad_insulation_is_one_located_line(tmp_path, target, message):
    """The scan loader's rules (a number >= 0, at most MAX_INSULATION, cylinders only), refused
    when the plan is read: the session would otherwise write a scan no command reads."""
    path = _insulated(tmp_path, **target)
    with pytest.raises(ScanError) as info:
        load_plan(path)
    text = str(info.value)
    assert text.startswith(f"{path}: targets[0] (P1).insulation: ") and message in text, text
    assert "\n" not in text


def test_a_non_finite_insulation_is_refused(tmp_path):
    path = tmp_path / "plan.json"
    path.write_text(
        '{"format": "asbuilt-scan-plan", "version": 1, "targets": [{"id": "P1", "kind": '
        '"cylinder", "window_deg": [0, 0, 10, 5], "insulation": NaN}]}'
    )
    with pytest.raises(ScanError, match=r"targets\[0\] \(P1\)\.insulation: must be a number"):
        load_plan(path)


def test_a_bare_cuboid_may_say_zero_as_a_scan_object_may():
    w = Window.from_degrees([0, 0, 1, 1])
    assert Target("C1", "cuboid", w, insulation=0).insulation == 0
    with pytest.raises(ScanError, match="C1.insulation: insulation is a radial thickness"):
        Target("C1", "cuboid", w, insulation=0.05)


def test_a_plan_may_carry_a_comment(tmp_path):
    doc = {"format": "asbuilt-scan-plan", "version": 1, "comment": "site A", "targets": [GOOD]}
    (tmp_path / "p.json").write_text(json.dumps(doc))
    assert [t.id for t in load_plan(tmp_path / "p.json").targets] == ["P1"]


def _session(plan, name="site.plan.json", **more):
    return [{"type": "session", "version": 1, "plan": plan_record(plan, name), **more}]


def test_a_resume_must_give_the_sessions_own_plan():
    site = Plan((Target.from_dict(GOOD),))
    other = Plan((Target.from_dict({**GOOD, "id": "W1", "kind": "plane"}),))
    assert resume_plan_mismatch(_session(site), site, "copy.json") is None  # same targets
    assert "ran another plan, site.plan.json (1 target), not room.plan.json (1 target)" in (
        resume_plan_mismatch(_session(site), other, "room.plan.json")
    )
    assert "ran the plan site.plan.json (1 target); resume with that --plan" in (
        resume_plan_mismatch(_session(site), None)
    )
    assert resume_plan_mismatch(_session(None), None) is None
    assert "from the prompts; resume without --plan" in resume_plan_mismatch(_session(None), site)
    assert plan_digest(site) != plan_digest(other) and len(plan_digest(site)) == 64


def test_an_older_journal_is_checked_by_the_targets_it_began():
    """Journals written before sessions recorded their plan: each begun target must be the
    plan's, as it was journaled."""
    site = Plan((Target.from_dict(GOOD),))
    old = [
        {"type": "session", "version": 1},
        {"type": "object", "target": site.targets[0].to_dict()},
    ]
    assert resume_plan_mismatch(old, site) is None
    assert resume_plan_mismatch(old, None) is None  # the prompts go on, as before
    moved = Plan((Target.from_dict({**GOOD, "window_deg": [0, 0, 11, 5]}),))
    assert "target 'P1', which room.plan.json gives otherwise" in (
        resume_plan_mismatch(old, moved, "room.plan.json")
    )
    other = Plan((Target.from_dict({**GOOD, "id": "W1"}),))
    assert "target 'P1', which this plan does not have" in resume_plan_mismatch(old, other)
