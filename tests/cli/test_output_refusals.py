"""Outputs a command cannot write are refused before any work, in one line that says so: ``-``
where standard output cannot take the result (it made a file named ``-``, or was called a file
without a suffix), and a directory named as ``check --fix`` (called a file without a suffix)."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from asbuilt.cli import main

ROOT = Path(__file__).resolve().parents[2]
SPOOL = str(ROOT / "samples" / "spool.json")
PORTS = ["--ptu", "/dev/asbuilt-no-such-port", "--lrf", "/dev/asbuilt-no-such-port"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (
            ["model", SPOOL, "--out", "-"],
            "--out -: standard output cannot take a CAD model; give a file name such as model.step",
        ),
        (
            ["model", SPOOL, "--out", "m.step", "--report", "-"],
            "--report -: standard output "
            "cannot take a report; give a file name such as report.html",
        ),
        (["report", SPOOL, "--out", "-"], "--out -: standard output cannot take a report"),
        (["check", SPOOL, "--fix", "-"], "--fix -: standard output cannot take a CAD model"),
        (
            ["calibrate", "room.json", "--targets", "t.json", "--out", "-"],
            "--out -: standard "
            "output cannot take the calibration (its table is printed there); give a file name "
            "such as rig.cal.json",
        ),
        (
            ["scan", *PORTS, "--out", "-"],
            "--out -: standard output cannot take the scan and its "
            "journal; give a file name such as site.json",
        ),
        (
            ["check", SPOOL, "--fix", "folder"],
            "folder: is a directory; give a file name to write (e.g. add /fixed.step)",
        ),
        (
            ["scan", *PORTS, "--out", "folder"],
            "folder: is a directory; give a file name to write (e.g. add /site.json)",
        ),
        (
            ["simulate", "scene.json", "--out", "site.step"],
            "site.step: --out writes an "
            "asbuilt-scan file as JSON, not .step; name it like scan.json",
        ),
        (
            ["scan", *PORTS, "--out", "site.glb"],
            "site.glb: --out writes an asbuilt-scan file as JSON, not .glb; name it like site.json",
        ),
        (
            ["simulate", "-", "--out", "scan.json"],
            "SCENE -: simulate reads its scene from a file, "
            "not standard input; give the scene's file",
        ),
    ],
)
def test_an_output_the_command_cannot_write_is_one_line_and_nothing_written(
    tmp_path, monkeypatch, capsys, argv, message
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "folder").mkdir()
    shutil.copy(ROOT / "samples" / "spool.json", tmp_path / "room.json")
    shutil.copy(ROOT / "samples" / "scenes" / "spool.scene.json", tmp_path / "scene.json")
    (tmp_path / "t.json").write_text("{}")
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"asbuilt: error: {message}") and err.count("\n") == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "folder",
        "room.json",
        "scene.json",
        "t.json",
    ]
    assert list((tmp_path / "folder").iterdir()) == []


def test_the_other_formats_are_exactly_what_model_and_report_write():
    """The list the JSON-writing commands refuse (kept literal: importing the report package
    would cost simulate and scan 0.4 s of start-up) is the export and report registries'
    suffixes, JSON aside."""
    from asbuilt import export, report
    from asbuilt.cli._args import OTHER_FORMATS

    assert set(OTHER_FORMATS) == (set(export.SUFFIXES) | set(report.SUFFIXES)) - {".json"}
