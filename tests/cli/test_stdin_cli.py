"""``SCAN`` may be ``-`` (standard input) for every command that reads a scan: ``fit``,
``model``, ``check``, ``report`` and ``calibrate``.

The truth is the same command on the same bytes as a file: the same output, and for a bad
scan the same one-line error with ``<stdin>`` in place of the path, exit code 2, no traceback,
nothing written. In-process through :func:`asbuilt.cli.main` (standard input replaced) and as a
subprocess with a sample piped in.
"""

from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from asbuilt.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[2]
SPOOL = ROOT / "samples" / "spool.json"
#: The subprocesses run this tree's asbuilt, whatever is installed.
ENV = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}

#: Every command that reads a scan, and the arguments that make it write OUT.
COMMANDS = {
    "fit": ["--output", "{out}.json"],
    "model": ["--out", "{out}.json"],
    "check": ["--fix", "{out}.json"],
    "report": ["--out", "{out}.csv"],
    "calibrate": ["--targets", "{targets}", "--out", "{out}.json"],
}


def _argv(command, scan, tmp_path):
    out = tmp_path / "out"
    targets = tmp_path / "targets.json"
    tail = [a.format(out=out, targets=targets) for a in COMMANDS[command]]
    return [command, str(scan), *tail]


def _feed(monkeypatch, data: bytes):
    """Replace standard input with a pipe-like stream holding ``data``."""
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(data)))


def _bad_scan() -> bytes:
    """The spool sample with its first object's points replaced by a string."""
    doc = json.loads(SPOOL.read_text(encoding="utf-8"))
    doc["objects"][0]["points"] = "x"
    return json.dumps(doc).encode()


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_a_bad_scan_on_stdin_is_the_files_error_naming_stdin(
    command, tmp_path, monkeypatch, capsys
):
    bad = tmp_path / "bad.json"
    bad.write_bytes(_bad_scan())
    assert main(_argv(command, bad, tmp_path)) == 2
    _, from_file = capsys.readouterr()

    _feed(monkeypatch, _bad_scan())
    assert main(_argv(command, "-", tmp_path)) == 2
    out, err = capsys.readouterr()
    assert err == from_file.replace(str(bad), "<stdin>")
    lines = err.splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert lines[0].startswith("asbuilt: error: <stdin>: objects[0] (")
    assert ").points: must be an array of points" in lines[0]
    assert out == ""
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.json"]  # nothing written


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_not_json_on_stdin_is_one_line(command, tmp_path, monkeypatch, capsys):
    _feed(monkeypatch, b"{not json")
    assert main(_argv(command, "-", tmp_path)) == 2
    out, err = capsys.readouterr()
    assert err.startswith("asbuilt: error: <stdin>: ") and err.count("\n") == 1
    assert "JSON" in err and out == "" and not list(tmp_path.iterdir())


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_stdin_past_the_size_limit_is_refused(command, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr("asbuilt.scan.load.MAX_FILE_BYTES", 1024 * 1024)
    _feed(monkeypatch, b" " * (1024 * 1024 + 10))
    assert main(_argv(command, "-", tmp_path)) == 2
    _, err = capsys.readouterr()
    assert err == (
        "asbuilt: error: <stdin>: holds more than 1 MiB, too large for a sparse scan; split it "
        "into several scans\n"
    )


def test_a_terminal_on_stdin_is_refused_not_waited_on(tmp_path, monkeypatch, capsys):
    class Terminal(io.TextIOWrapper):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stdin", Terminal(io.BytesIO(SPOOL.read_bytes())))
    assert main(["model", "-", "--out", str(tmp_path / "m.json")]) == 2
    _, err = capsys.readouterr()
    assert err.startswith("asbuilt: error: <stdin>: standard input is a terminal")
    assert not list(tmp_path.iterdir())


def test_a_closed_stdin_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(sys, "stdin", None)  # started with 0<&-
    assert main(["check", "-"]) == 2
    _, err = capsys.readouterr()
    assert err.startswith("asbuilt: error: <stdin>: standard input is closed")


@pytest.mark.parametrize(
    "argv",
    [["check"], ["check", "--format", "json"], ["fit", "--json"]],
    ids=["check", "check-json", "fit-json"],
)
def test_stdin_gives_what_the_file_gives(argv, monkeypatch, capsys):
    from_file = main([argv[0], str(SPOOL), *argv[1:]])
    file_out, _ = capsys.readouterr()
    _feed(monkeypatch, SPOOL.read_bytes())
    assert main([argv[0], "-", *argv[1:]]) == from_file
    out, _ = capsys.readouterr()
    assert out == file_out.replace(str(SPOOL), "<stdin>")
    assert out


def test_model_and_report_from_stdin_write_what_the_file_writes(tmp_path, monkeypatch, capsys):
    assert main(["model", str(SPOOL), "--out", str(tmp_path / "file.json")]) == 0
    _feed(monkeypatch, SPOOL.read_bytes())
    assert main(["model", "-", "--out", str(tmp_path / "stdin.json")]) == 0
    from_file = json.loads((tmp_path / "file.json").read_text())
    from_stdin = json.loads((tmp_path / "stdin.json").read_text())
    assert from_stdin["source"] == "<stdin>"
    from_stdin["source"] = from_file["source"]
    assert from_stdin == from_file

    assert main(["report", str(SPOOL), "--out", str(tmp_path / "file.csv")]) == 0
    _feed(monkeypatch, SPOOL.read_bytes())
    assert main(["report", "-", "--out", str(tmp_path / "stdin.csv")]) == 0
    assert (tmp_path / "stdin.csv").read_text() == (tmp_path / "file.csv").read_text()
    capsys.readouterr()


def test_a_model_document_on_stdin_is_checked_and_reported_as_a_file_is(
    tmp_path, monkeypatch, capsys
):
    document = tmp_path / "model.json"
    assert main(["model", str(SPOOL), "--out", str(document)]) == 0
    capsys.readouterr()
    for argv in (["check"], ["report", "--out", str(tmp_path / "r.json")]):
        assert main([argv[0], str(document), *argv[1:]]) == 0
        file_out, _ = capsys.readouterr()
        _feed(monkeypatch, document.read_bytes())
        assert main([argv[0], "-", *argv[1:]]) == 0
        out, _ = capsys.readouterr()
        assert out == file_out.replace(str(document), "<stdin>")
    # build options are refused for a piped model document as for a file
    _feed(monkeypatch, document.read_bytes())
    assert main(["check", "-", "--no-merge"]) == 2
    _, err = capsys.readouterr()
    assert err.startswith("asbuilt: error: <stdin>: --no-merge applies only when building")


def test_a_bad_model_document_on_stdin_names_stdin_and_the_field(tmp_path, monkeypatch, capsys):
    document = tmp_path / "model.json"
    assert main(["model", str(SPOOL), "--out", str(document)]) == 0
    capsys.readouterr()
    doc = json.loads(document.read_text())
    doc["version"] = 7
    _feed(monkeypatch, json.dumps(doc).encode())
    assert main(["report", "-", "--out", str(tmp_path / "r.csv")]) == 2
    _, err = capsys.readouterr()
    assert err.startswith("asbuilt: error: <stdin>: version: version 7 is not supported")
    assert not (tmp_path / "r.csv").exists()


def test_a_400_digit_integer_in_a_model_document_on_stdin_is_named(tmp_path, monkeypatch, capsys):
    """Standard input's document is read with the file reader's integer hook: the integer
    overflowed float() in a field check (a traceback) where the file gave a located line."""
    document = tmp_path / "model.json"
    assert main(["model", str(SPOOL), "--out", str(document)]) == 0
    capsys.readouterr()
    doc = json.loads(document.read_text())
    doc["components"][0]["od"] = 12345
    text = json.dumps(doc).replace('"od": 12345', '"od": ' + "9" * 400, 1)
    _feed(monkeypatch, text.encode())
    assert main(["check", "-"]) == 2
    _, err = capsys.readouterr()
    component = doc["components"][0]["id"]
    assert err == (
        f"asbuilt: error: <stdin>: components[0] ({component}).od: must be a finite number, "
        "not Infinity\n"
    )


def test_a_file_named_dash_is_not_the_input_an_output_would_replace(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "-").write_text("not the input")
    _feed(monkeypatch, SPOOL.read_bytes())
    assert main(["fit", "-", "--output", "-"]) == 0  # '-' output is standard output
    capsys.readouterr()
    _feed(monkeypatch, SPOOL.read_bytes())
    assert main(["model", "-", "--out", str(tmp_path / "m.json")]) == 0
    capsys.readouterr()


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_help_says_scan_may_be_stdin(command, capsys):
    parser = build_parser()
    with pytest.raises(SystemExit):
        parser.parse_args([command, "--help"])
    out, _ = capsys.readouterr()
    assert "'-': read it from standard input" in " ".join(out.split())


@pytest.mark.parametrize(
    "argv, code, expect",
    [
        (["check", "-"], 0, "<stdin>"),  # a summary line only: the sample is clean
        (["fit", "-", "--json"], 0, '"objects"'),
        (["report", "-", "--out", "{tmp}/qa.csv"], 0, "wrote"),
    ],
    ids=["check", "fit", "report"],
)
def test_a_sample_piped_to_a_subprocess(argv, code, expect, tmp_path):
    argv = [a.format(tmp=tmp_path) for a in argv]
    proc = subprocess.run(
        [sys.executable, "-m", "asbuilt", *argv],
        input=SPOOL.read_bytes(),
        capture_output=True,
        timeout=120,
        cwd=tmp_path,
        env=ENV,
    )
    assert proc.returncode == code, proc.stderr
    assert b"Traceback" not in proc.stderr
    if argv[0] != "check":
        assert expect.encode() in proc.stdout


def test_a_bad_scan_piped_to_a_subprocess_is_one_line_and_writes_nothing(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "asbuilt", "model", "-", "--out", str(tmp_path / "m.step")],
        input=_bad_scan(),
        capture_output=True,
        timeout=120,
        env=ENV,
    )
    assert proc.returncode == 2
    lines = proc.stderr.decode().splitlines()
    assert len(lines) == 1 and lines[0].startswith("asbuilt: error: <stdin>: objects[0] (")
    assert proc.stdout == b"" and not list(tmp_path.iterdir())
