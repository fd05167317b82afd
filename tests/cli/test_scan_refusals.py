"""``asbuilt scan`` refuses, before the devices open, what would end the session in a scan file
that no command reads (a plan's or the operator's id, ``--name``) or in a file named ``-``."""

from __future__ import annotations

import io
import json
import sys

import pytest
from asbuilt.drivers.simrig import _RIGS

from asbuilt.cli import main
from asbuilt.scan import load_scan


def _args(site, *more, out="scan.json"):
    return [
        "scan",
        "--ptu",
        f"sim-ptu://wall?scene={site / 'scene.json'}",
        "--lrf",
        "sim-lrf://wall",
        "--out",
        str(site / out) if out != "-" else out,
        *more,
    ]


def _plan(site, **target) -> str:
    plan = json.loads((site / "plan.json").read_text())
    plan["targets"][0].update(target)
    (site / "bad-plan.json").write_text(json.dumps(plan))
    return str(site / "bad-plan.json")


@pytest.mark.parametrize(
    "target, message",
    [
        ({"id": "W\u001b[A1"}, "bad-plan.json: targets[0].id: holds a control character (\\u001b)"),
        ({"id": " W1"}, 'bad-plan.json: targets[0].id: " W1" starts or ends with white space'),
        (
            {"id": "W" * 300},
            "bad-plan.json: targets[0].id: is 300 characters long; use at most 255",
        ),
        ({"nominal": '4"\n'}, "bad-plan.json: targets[0] (W1).nominal: holds a control character"),
        ({"label": "a\u0007b"}, "bad-plan.json: targets[0] (W1).label: holds a control character"),
        (
            {"kind": "cuboid", "insulation": 0.05},
            "bad-plan.json: targets[0] (W1).insulation: insulation is a radial thickness on a "
            'cylinder, not on kind "cuboid"; give the target "kind": "cylinder" or remove its '
            "insulation\n",
        ),
        (
            {"insulation": 0.05},
            "bad-plan.json: targets[0] (W1).insulation: insulation is a radial thickness on a "
            'cylinder, not on kind "plane"',
        ),
        (
            {"kind": "cylinder", "insulation": -0.05},
            "bad-plan.json: targets[0] (W1).insulation: must be a number >= 0 (the insulation's "
            "thickness in metres), not -0.05\n",
        ),
        (  # a typo used to drop the insulation silently: the pipe came out 50 mm too big
            {"kind": "cylinder", "insualtion": 0.05},
            "bad-plan.json: targets[0] (W1).insualtion: unknown key; use id, kind, window_deg, "
            "points, group, label, nominal, insulation\n",
        ),
        ({"foo": 1}, "bad-plan.json: targets[0] (W1).foo: unknown key; use id, kind"),
        (
            {"kind": "cylinder", "insulation": 50},
            "bad-plan.json: targets[0] (W1).insulation: 50 m is thicker than any pipe insulation "
            "(at most 0.5 m); a plan's lengths are in metres (50 mm is 0.05): check the value\n",
        ),
    ],
)
def test_a_plan_the_scan_file_could_not_carry_is_refused_before_the_session(
    site, capsys, target, message
):
    """The session ran and wrote a scan that every command refused (its own loader's rules)."""
    plan = _plan(site, **target)
    assert main(_args(site, "--plan", plan)) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"asbuilt: error: {site / message}") and err.count("\n") == 1, err
    assert sorted(p.name for p in site.iterdir()) == ["bad-plan.json", "plan.json", "scene.json"]
    assert not _RIGS  # no simulated device was opened


def test_a_name_the_scan_file_could_not_carry_is_refused_before_the_session(site, capsys):
    assert main(_args(site, "--plan", str(site / "plan.json"), "--name", "a\u001bb")) == 2
    err = capsys.readouterr().err
    assert err == (
        "asbuilt: error: --name: holds a control character (\\u001b) at character 2; "
        "use printable text\n"
    )
    assert not (site / "scan.json").exists() and not (site / "scan.json.journal").exists()


def test_an_operators_id_the_scan_file_could_not_carry_is_asked_again(site, monkeypatch, capsys):
    """An arrow key typed into the id (its escape sequence) made a scan no command read."""
    answers = ["W\u001b[A1", "W1", "plane", "80 -5 100 5", "", ""]
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n".join(answers) + "\n"))
    assert main(_args(site, "--edge-pairs", "0")) == 0
    err = capsys.readouterr().err
    assert "holds a control character (\\u001b) at character 2; use printable text; choose" in err
    assert "no --calibration: using an ideal chain at the origin" in err
    scan = load_scan(site / "scan.json")  # readable
    assert [obj.id for obj in scan.objects] == ["W1"]


def test_a_port_that_does_not_open_is_the_only_line(site, capsys):
    """The notice that no --calibration was given came first: two lines for one error."""
    argv = ["scan", "--ptu", str(site / "no-such-port"), "--lrf", str(site / "no-such-port")]
    assert main([*argv, "--out", str(site / "scan.json"), "--plan", str(site / "plan.json")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"asbuilt: error: {site / 'no-such-port'}: cannot open the port")
    assert err.count("\n") == 1, err
