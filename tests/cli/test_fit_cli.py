"""``asbuilt fit``: table, ``--json``, ``--units``, ``--output``; every bad input is one line, exit 2.

In-process through :func:`asbuilt.cli.main` (with capsys) and as a subprocess
(``python -m asbuilt fit ...``). The table of bad documents is shared with tests/scan.
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from asbuilt.cli import main
from asbuilt.errors import FitError
from asbuilt.fit import FITTERS
from asbuilt.fit.result import FitResult
from asbuilt.primitives import Sphere
from asbuilt.scan import MAX_FILE_BYTES

ROOT = Path(__file__).resolve().parents[2]


def _load_cases():
    spec = importlib.util.spec_from_file_location(
        "scan_cases_for_cli", ROOT / "tests" / "scan" / "scan_cases.py"
    )
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


cases = _load_cases()
BAD = cases.BAD
make_doc = cases.make_doc


def _stand_in(points, *, sigma=None, tolerances=None) -> FitResult:
    """A deterministic stand-in fit: sphere at the centroid (the CLI is under test, not the fit)."""
    center = points.mean(axis=0)
    sphere = Sphere(center, np.linalg.norm(points - center, axis=1).mean())
    return FitResult(
        primitive=sphere,
        residuals=sphere.distance(points),
        inliers=np.ones(len(points), bool),
        stderr={"radius": 1e-4},
        sigma=sigma or 1e-3,
        sigma_source="sensor" if sigma else "residuals",
        method="centroid (test stand-in)",
    )


def _refuse(points, *, sigma=None, tolerances=None) -> FitResult:
    raise FitError("the points are coplanar; a sphere needs points off one plane")


@pytest.fixture
def stand_ins(monkeypatch):
    module = types.ModuleType("cli_stand_in_fits")
    module.fit = _stand_in
    module.refuse = _refuse
    monkeypatch.setitem(sys.modules, module.__name__, module)
    for kind in FITTERS:
        monkeypatch.setitem(FITTERS, kind, (module.__name__, "fit"))
    return module


@pytest.fixture
def scan_file(tmp_path, monkeypatch):
    """Write a document as tmp_path/scan.json and chdir there; return the file name."""
    monkeypatch.chdir(tmp_path)

    def write(document, name="scan.json"):
        text = document if isinstance(document, str) else json.dumps(document)
        (tmp_path / name).write_text(text, encoding="utf-8")
        return name

    return write


def run_cli(capsys, *argv):
    code = main(["fit", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_table_by_default(stand_ins, scan_file, capsys):
    code, out, err = run_cli(capsys, scan_file(make_doc("mm")))
    assert code == 0 and err == ""
    for object_id in ("K1", "K2", "K3", "K4", "K5", "K6"):
        assert object_id in out
    assert "auto→sphere" in out and "6 objects" in out
    assert "rms" in out and "inliers" in out


def test_json_in_the_scan_units(stand_ins, scan_file, capsys):
    code, out, err = run_cli(capsys, scan_file(make_doc("mm")), "--json")
    assert code == 0 and err == ""
    data = json.loads(out)
    assert data["units"] == "mm"
    assert [o["id"] for o in data["objects"]] == ["K1", "K2", "K3", "K4", "K5", "K6"]
    sphere = data["objects"][2]
    points = cases.surface_points("sphere") * 1000.0  # what the stand-in does, in mm
    centre = points.mean(axis=0)
    assert sphere["kind"] == "sphere" and sphere["center"] == pytest.approx(centre.tolist())
    assert sphere["radius"] == pytest.approx(np.linalg.norm(points - centre, axis=1).mean())
    auto = data["objects"][5]
    assert auto["kind"] == "auto" and auto["chosen"] == "sphere"


def test_units_option(stand_ins, scan_file, capsys):
    name = scan_file(make_doc("mm"))
    _, out_mm, _ = run_cli(capsys, name, "--json")
    code, out_in, _ = run_cli(capsys, name, "--json", "--units", "in")
    assert code == 0
    mm, inch = json.loads(out_mm), json.loads(out_in)
    assert inch["units"] == "in"
    for a, b in zip(mm["objects"], inch["objects"]):
        assert b["center"] == pytest.approx([c / 25.4 for c in a["center"]])
        assert b["stderr"]["radius"] == pytest.approx(a["stderr"]["radius"] / 25.4)


def test_output_file_is_written_instead_of_stdout(stand_ins, scan_file, capsys, tmp_path):
    name = scan_file(make_doc())
    _, expected, _ = run_cli(capsys, name, "--json")
    code, out, err = run_cli(capsys, name, "--json", "--output", "fits.json")
    assert code == 0 and out == ""
    assert err.strip() == "wrote fits.json"
    assert (tmp_path / "fits.json").read_text(encoding="utf-8") == expected
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".part")] == []
    code, out, _ = run_cli(capsys, name, "-o", "again.json")
    assert code == 0 and "K1" in out  # without --json the table still goes to stdout
    assert json.loads((tmp_path / "again.json").read_text(encoding="utf-8")) == json.loads(expected)


def test_output_into_a_missing_directory(stand_ins, scan_file, capsys):
    code, out, err = run_cli(capsys, scan_file(make_doc()), "--json", "-o", "no/such/dir.json")
    assert code == 2 and out == ""
    assert err == (
        "asbuilt: error: no/such/dir.json: directory does not exist; create it or choose "
        "another --output\n"
    )


@pytest.mark.parametrize("case", BAD, ids=[case.name for case in BAD])
def test_bad_scan_is_one_line_exit_2_and_no_output(case, scan_file, capsys, tmp_path):
    name = scan_file(case.build(make_doc()))
    code, out, err = run_cli(capsys, name, "--json", "--output", "out.json")
    assert code == 2
    assert out == ""
    assert err == f"asbuilt: error: scan.json: {case.message}\n"
    assert "Traceback" not in err
    assert not (tmp_path / "out.json").exists()


def test_missing_file(scan_file, capsys, tmp_path):
    code, out, err = run_cli(capsys, "absent.json")
    assert (code, out) == (2, "")
    assert err == (
        "asbuilt: error: absent.json: file does not exist; check the path and the current "
        "directory\n"
    )


def test_too_large_file(scan_file, capsys, tmp_path):
    with open(tmp_path / "big.json", "wb") as handle:
        handle.truncate(MAX_FILE_BYTES + 1)
    code, out, err = run_cli(capsys, "big.json", "-o", "out.json")
    assert (code, out) == (2, "")
    assert err == (
        "asbuilt: error: big.json: is 67,108,865 bytes, too large to be a sparse scan (the limit is "
        "64 MiB and 1,000,000 points); split it into several scans\n"
    )
    assert not (tmp_path / "out.json").exists()


def test_a_scan_no_object_of_which_fits_is_bad_input(stand_ins, scan_file, capsys, tmp_path):
    for kind in FITTERS:
        FITTERS[kind] = (stand_ins.__name__, "refuse")  # restored by the fixture's monkeypatch
    code, out, err = run_cli(capsys, scan_file(make_doc()), "--json", "-o", "out.json")
    assert (code, out) == (2, "")
    lines = err.splitlines()
    reason = "the points are coplanar; a sphere needs points off one plane"
    assert lines[0] == (
        f"asbuilt: error: scan.json: objects[0] (K1): {reason} No object of the scan could be "
        "fitted: the 5 other objects (K2, K3, K4, K5, K6) were refused too."
    )
    assert lines[1:] == [
        f"asbuilt: error: scan.json: objects[{k}] (K{k + 1}): {reason}" for k in range(1, 6)
    ]
    assert not (tmp_path / "out.json").exists()


def test_a_refused_object_is_listed_and_the_others_fitted(tmp_path, capsys, monkeypatch):
    """Real fits: the spool sample's six pipes and the ray caster's refused NPS 1 scan X1."""
    from refused_scans import spool_with_refused, write

    from asbuilt.fit import fit_points
    from asbuilt.scan import load_scan

    monkeypatch.chdir(tmp_path)
    write(tmp_path / "scan.json", spool_with_refused())
    x1 = load_scan("scan.json").objects[-1]
    with pytest.raises(FitError) as direct:
        fit_points("cylinder", x1.points, sigma=0.002, viewpoint=x1.station)
    reason = direct.value.message
    code, out, err = run_cli(capsys, "scan.json", "--json", "-o", "fits.json")
    assert code == 1 and out == "" and err.strip().endswith("wrote fits.json")
    data = json.loads((tmp_path / "fits.json").read_text())
    assert [o["id"] for o in data["objects"]] == ["P1", "P2", "P3", "P4", "P5", "P6", "X1"]
    assert data["objects"][-1] == {"id": "X1", "kind": "cylinder", "error": reason}
    assert all("error" not in o and o["radius"] > 0.05 for o in data["objects"][:6])
    code, out, _ = run_cli(capsys, "scan.json")
    assert code == 1 and "6 fitted, 1 refused" in out
    refused = out[out.index("refused (not fitted") :]
    assert "X1 (cylinder)" in refused and " ".join(refused.split()).endswith(
        " ".join(reason.split())
    )


def test_unknown_units_option(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["fit", "scan.json", "--units", "yd"])
    assert exit_.value.code == 2
    assert "invalid choice: 'yd'" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv, prog",
    [
        (["fit", "scan.json", "--units", "yd"], "asbuilt fit"),
        (["model", "scan.json"], "asbuilt model"),  # --out missing
        (["check", "scan.json", "--frobnicate"], "asbuilt"),  # unknown options: the top parser
        (["frobnicate"], "asbuilt"),
    ],
)
def test_usage_errors_are_one_line(capsys, argv, prog):
    # Bad input gets one line and exit code 2; argparse printed its usage over several lines.
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"{prog}: error: "), err
    assert err.endswith(f" (see {prog} --help)\n")


def test_help_lists_the_options(capsys):
    with pytest.raises(SystemExit):
        main(["fit", "--help"])
    out = capsys.readouterr().out
    for option in ("--json", "--units", "--output"):
        assert option in out


# --------------------------------------------------------------------------------------------
# As a subprocess, with the real fits


def _run(*argv, cwd):
    return subprocess.run(
        [sys.executable, "-m", "asbuilt", "fit", *argv],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )


def test_subprocess_bad_input(tmp_path):
    doc = make_doc()
    doc["objects"][3]["points"][17 % 16][0] = float("nan")
    (tmp_path / "scan.json").write_text(json.dumps(doc), encoding="utf-8")
    done = _run("scan.json", "--json", cwd=tmp_path)
    assert done.returncode == 2 and done.stdout == ""
    assert (
        done.stderr == "asbuilt: error: scan.json: objects[3] (K4).points[1]: coordinate is NaN\n"
    )


def test_subprocess_real_fits(tmp_path):
    kinds = [k for k in ("cylinder", "cuboid", "sphere", "plane", "hull", "auto") if _exists(k)]
    if not kinds:
        pytest.skip("no real fit module is written yet")
    doc = make_doc("mm", kinds=kinds)
    doc["sensor"] = {"range_sigma": 0.5}
    (tmp_path / "scan.json").write_text(json.dumps(doc), encoding="utf-8")
    done = _run("scan.json", "--json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert data["units"] == "mm" and [o["kind"] for o in data["objects"]] == kinds
    by_kind = {o["kind"]: o for o in data["objects"]}
    if "cylinder" in by_kind:
        assert by_kind["cylinder"]["radius"] == pytest.approx(57.15, abs=0.1)
        assert by_kind["cylinder"]["sigma"] == pytest.approx(0.5)
    if "sphere" in by_kind:
        assert by_kind["sphere"]["radius"] == pytest.approx(300.0, abs=0.1)
    if "plane" in by_kind:
        assert [abs(c) for c in by_kind["plane"]["normal"]] == pytest.approx([0, 0, 1], abs=1e-9)
        assert by_kind["plane"]["point"][2] == pytest.approx(2500.0)
    if "hull" in by_kind:
        assert len(by_kind["hull"]["vertices"]) >= 4 and len(by_kind["hull"]["faces"]) >= 4
    if "auto" in by_kind:  # the auto object's points are the same pipe's
        assert by_kind["auto"]["chosen"] == "cylinder"
        assert by_kind["auto"]["radius"] == pytest.approx(57.15, abs=0.1)
    table = _run("scan.json", cwd=tmp_path)
    assert table.returncode == 0 and "K1" in table.stdout and table.stderr == ""


def _exists(kind: str) -> bool:
    return importlib.util.find_spec(FITTERS[kind][0]) is not None


SAMPLES = sorted((ROOT / "samples").glob("*.json"))


@pytest.mark.parametrize("sample", SAMPLES, ids=[p.name for p in SAMPLES])
def test_samples_fit_in_process(sample, capsys):
    """Every shipped sample fits with the real fits; the JSON names every object once."""
    if not all(_exists(kind) for kind in FITTERS):
        pytest.skip("not every fit module is written yet")
    document = json.loads(sample.read_text(encoding="utf-8"))
    code, out, err = run_cli(capsys, str(sample), "--json", "--units", "mm")
    assert code == 0, err
    data = json.loads(out)
    assert data["units"] == "mm"
    assert [o["id"] for o in data["objects"]] == [o["id"] for o in document["objects"]]
    for obj, raw in zip(data["objects"], document["objects"]):
        assert obj["kind"] == raw["kind"] and obj["n_points"] == len(raw["points"])
        assert obj["rms"] is not None and obj["rms"] < 10.0  # mm: range noise is 2 mm


def test_names_and_ids_are_shown_as_written_not_as_rich_markup(tmp_path, capsys):
    """A scan name with "[/]" crashed the table (rich markup), and "S[red]2" lost its brackets
    (audit)."""
    angles = np.radians(np.linspace(-60, 60, 6))
    ring = [[0.0, 5.0 - 0.5 * np.cos(a), 1.0 + 0.5 * np.sin(a)] for a in angles]
    points = [[x + dx, y, z] for dx in (0.0, 0.2, 0.4, 0.6, 0.8) for x, y, z in ring]
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "name": "Tank farm [/] east",
        "objects": [{"id": "S[red]2", "kind": "cylinder", "points": points}],
    }
    path = tmp_path / "markup.json"
    path.write_text(json.dumps(doc))
    assert main(["fit", str(path)]) == 0
    out = capsys.readouterr().out
    assert "Tank farm [/] east" in out
    assert "S[red]2" in out


def test_a_wall_fitted_as_a_pipe_is_refused_not_reported_kilometres_wide(tmp_path, capsys):
    """A flat wall's shots fitted as a cylinder gave "r 179.604 m" in the table, exit 0 (audit);
    its radius is not known to within its size, so the fit is refused with one located line."""
    rng = np.random.default_rng(4)
    wall = np.column_stack([rng.uniform(0, 1.4, 25), np.full(25, 4.0), rng.uniform(0, 1.4, 25)])
    wall[:, 1] += rng.normal(0, 0.002, 25)
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"position": [0.7, 0.0, 0.7], "range_sigma": 0.002},
        "objects": [{"id": "NotAPipe", "kind": "cylinder", "points": wall.tolist()}],
    }
    path = tmp_path / "wall_as_pipe.json"
    path.write_text(json.dumps(doc))
    assert main(["fit", str(path)]) == 2
    err = capsys.readouterr().err
    assert "objects[0] (NotAPipe).points: These points do not determine the cylinder's" in err
    assert len(err.strip().splitlines()) == 1


def test_the_table_shows_each_fits_notes(tmp_path, capsys):
    """A loosely determined fit's warning was shown only with --json (audit)."""
    # Eight shots along a 1 m helix over 120 degrees of a 0.1 m pipe: radius +-65%.
    angles = np.radians(np.linspace(-60, 60, 8))
    helix = np.column_stack(
        [np.linspace(0, 1, 8), 3.0 - 0.1 * np.cos(angles), 1.0 + 0.1 * np.sin(angles)]
    )
    doc = {
        "format": "asbuilt-scan",
        "version": 1,
        "units": "m",
        "sensor": {"range_sigma": 0.001},
        "objects": [{"id": "Loose", "kind": "cylinder", "points": helix.tolist()}],
    }
    path = tmp_path / "loose.json"
    path.write_text(json.dumps(doc))
    assert main(["fit", str(path), "--json"]) == 0
    notes = json.loads(capsys.readouterr().out)["objects"][0]["notes"]
    assert any(note.startswith("These points do not determine the cylinder") for note in notes)
    assert main(["fit", str(path)]) == 0
    out = capsys.readouterr().out
    table, _, below = out.partition("notes:")
    assert below, out
    assert "Loose" in below and "These points do not determine the cylinder" in below


def test_an_output_directory_is_refused_with_a_json_file_name_to_add(tmp_path, capsys):
    """``fit --output`` writes JSON: the hint names a JSON file, not a model (audit 25)."""
    scan = ROOT / "samples" / "spool.json"
    assert main(["fit", str(scan), "--output", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err == (
        f"asbuilt: error: {tmp_path}: is a directory; give a file name to write "
        "(e.g. add /fit.json)\n"
    )
    assert list(tmp_path.iterdir()) == []


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("json_out", [True, False])
def test_a_full_disk_under_stdout_is_one_line_exit_2(tmp_path, json_out):
    doc = make_doc("mm", kinds=("plane",))
    (tmp_path / "scan.json").write_text(json.dumps(doc), encoding="utf-8")
    with open("/dev/full", "w") as full:
        done = subprocess.run(
            [sys.executable, "-m", "asbuilt", "fit", "scan.json", *(["--json"] * json_out)],
            cwd=tmp_path,
            stdout=full,
            stderr=subprocess.PIPE,
            text=True,
            timeout=120,
            env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
        )
    assert done.returncode == 2
    assert done.stderr == "asbuilt: error: cannot write the output (No space left on device)\n"


def test_the_scan_may_come_on_standard_input_and_the_json_go_to_standard_output(tmp_path):
    doc = make_doc("mm", kinds=("plane",))
    text = json.dumps(doc)
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "fit", "-", "--output", "-"],
        input=text,
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["objects"][0]["id"] == "K1"
    assert list(tmp_path.iterdir()) == []  # no file named '-'
    bad = subprocess.run(
        [sys.executable, "-m", "asbuilt", "fit", "-"],
        input='{"format": 1',
        capture_output=True,
        text=True,
        timeout=120,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
    )
    assert bad.returncode == 2
    assert bad.stderr == (
        "asbuilt: error: <stdin>: line 1 column 13: invalid JSON (Expecting ',' delimiter); fix the "
        "syntax there\n"
    )


def test_subprocess_ids_the_output_encoding_lacks(tmp_path):
    """A Chinese id (and an astral one) to a Latin-1 standard output (a legacy terminal, a
    cp1252 redirect on Windows) stopped `fit` with a UnicodeEncodeError traceback, exit code 1.
    The table writes it as a backslash escape; --json as JSON's own escapes, so it reads back."""
    doc = make_doc("mm", kinds=["sphere", "sphere"])
    doc["objects"][0]["id"] = "管 2"
    doc["objects"][1]["id"] = "𝔸 Ø"
    (tmp_path / "scan.json").write_text(json.dumps(doc, ensure_ascii=False), encoding="utf-8")
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "PYTHONIOENCODING": "latin-1"}
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "fit", "scan.json", "--json"],
        cwd=tmp_path,
        capture_output=True,
        timeout=120,
        env=env,
    )
    assert done.returncode == 0, done.stderr.decode("latin-1")
    ids = [o["id"] for o in json.loads(done.stdout.decode("latin-1"))["objects"]]
    assert ids[:2] == ["管 2", "𝔸 Ø"]
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "fit", "scan.json"],
        cwd=tmp_path,
        capture_output=True,
        timeout=120,
        env=env,
    )
    assert done.returncode == 0, done.stderr.decode("latin-1")
    assert b"Traceback" not in done.stderr
    assert "\\u7ba1 2" in done.stdout.decode("latin-1")


@pytest.mark.parametrize("options, shown", [([], False), (["-W", "default"], True)])
def test_library_warnings_stay_off_stderr_unless_asked_for(tmp_path, options, shown):
    """A library's warning (matplotlib's "constrained_layout not applied" for a report figure
    with a 255-character id) printed two lines of source location around a clean result;
    -W (or PYTHONWARNINGS) shows them again for a developer."""
    code = (
        "import warnings, asbuilt.cli.fit as fit\n"
        "fit.run = lambda args: warnings.warn('constrained_layout not applied', UserWarning)\n"
        "from asbuilt.cli import main\n"
        "raise SystemExit(main(['fit', 'scan.json']))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "PYTHONWARNINGS"}
    done = subprocess.run(
        [sys.executable, *options, "-c", code], capture_output=True, text=True, env=env
    )
    assert done.returncode == 0, done.stderr
    assert ("constrained_layout not applied" in done.stderr) is shown, done.stderr
