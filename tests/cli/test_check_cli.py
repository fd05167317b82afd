"""``asbuilt check``: linter output, JSON, exit codes, --rules/--select/--ignore, --design, --fix.

Scans are simulated (asbuilt.sim) from small scenes with the paper's point counts and 2 mm noise.
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from asbuilt.cli import main
from asbuilt.sim.scene import scene_from_dict
from asbuilt.sim.simulate import simulate_scan

STATION = {"id": "S1", "position": [0, 0, 1.5], "range_sigma": 0.002}
PIPE = {
    "id": "P1",
    "kind": "cylinder",
    "points": 30,
    "nominal": '4"',
    "geometry": {"type": "cylinder", "start": [-1.5, 4, 1.0], "end": [1.5, 4, 1.0], "od": 0.1143},
}
CROSSING = {
    "id": "P2",
    "kind": "cylinder",
    "points": 30,
    "geometry": {
        "type": "cylinder",
        "start": [0.0, 2.5, 1.02],
        "end": [0.0, 5.5, 1.02],
        "od": 0.1143,
    },
}
t = np.radians(5.0)
TILTED = {
    "id": "P9",
    "kind": "cylinder",
    "points": 30,
    "geometry": {
        "type": "cylinder",
        "start": [-1.5, 6, 1.0],
        "end": [-1.5 + 3 * np.cos(t), 6, 1.0 + 3 * np.sin(t)],
        "od": 0.1143,
    },
}


def scan_file(tmp_path, *objects, name="scan.json", seed=3):
    scene = {
        "format": "asbuilt-scene",
        "version": 1,
        "units": "m",
        "seed": seed,
        "stations": [STATION],
        "objects": list(objects),
    }
    path = tmp_path / name
    path.write_text(json.dumps(simulate_scan(scene_from_dict(scene), seed=seed)), encoding="utf-8")
    return path


def run(argv, capsys):
    code = main(["check", *map(str, argv)])
    out, err = capsys.readouterr()
    return code, out, err


def test_clean_scan_exits_0_with_a_summary(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE)
    code, out, _ = run([path], capsys)
    assert code == 0
    assert out.splitlines()[-1].startswith("0 errors, ")
    assert "in 1 component" in out


def test_clash_exits_1_and_reads_like_a_linter(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE, CROSSING)
    code, out, _ = run([path, "--format", "concise"], capsys)
    assert code == 1
    lines = out.splitlines()
    assert any(
        line.startswith(f"{path}: P1,P2: error clash: P1 and P2 intersect: ") for line in lines
    )
    # one finding per line, errors first, then the summary
    severities = [line.split(": ")[2].split()[0] for line in lines[:-1]]
    assert severities == sorted(severities, key=["error", "warning", "info"].index)
    assert lines[-1].split(", ")[0].endswith(("error", "errors"))


def _scanned_alone(*objects, seed=1):
    """A scan of each object simulated on its own (no shot hits the others), as one file: two
    pipes passing through each other would otherwise hide each other's shots."""
    scans = [
        simulate_scan(
            scene_from_dict(
                {
                    "format": "asbuilt-scene",
                    "version": 1,
                    "units": "m",
                    "seed": seed + k,
                    "stations": [STATION],
                    "objects": [obj],
                }
            ),
            seed=seed + k,
        )
        for k, obj in enumerate(objects)
    ]
    doc = scans[0]
    doc["objects"] = [o for scan in scans for o in scan["objects"]]
    return doc


@pytest.mark.parametrize("offset", [[0.15, 0.0], [0.0, 0.15]], ids=["side-by-side", "stacked"])
def test_parallel_pipes_passing_through_each_other_are_a_clash(tmp_path, capsys, offset):
    """Independent review 59, defect 2: an NPS 8 and an NPS 6 5 m from the station, parallel,
    axes 150 mm apart (radii sum 193.7 mm), gave exit 0 and an AB304 weldolet suggestion."""
    dx, dz = offset

    def pipe(pid, x, z, od):
        geometry = {"type": "cylinder", "start": [x, -1.5, z], "end": [x, 1.5, z], "od": od}
        return {"id": pid, "kind": "cylinder", "points": 35, "geometry": geometry}

    doc = _scanned_alone(pipe("P1", 5.0, 1.5, 0.2191), pipe("P2", 5.0 + dx, 1.5 + dz, 0.1683))
    path = tmp_path / "scan.json"
    path.write_text(json.dumps(doc), encoding="utf-8")
    code, out, _ = run([path, "--format", "concise"], capsys)
    lines = out.splitlines()
    assert code == 1, out
    assert lines[0].startswith(f"{path}: P1,P2: error clash: P1 and P2 intersect: "), out
    assert "unjoined-end" not in out and "weldolet" not in out
    assert lines[-1].startswith("1 error, 0 warnings")


def test_json_is_the_model_document_shape(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE, CROSSING)
    code, out, _ = run([path, "--format", "json"], capsys)
    assert code == 1
    findings = json.loads(out)
    assert isinstance(findings, list) and findings
    clash = next(f for f in findings if f["slug"] == "clash")
    assert set(clash) == {
        "code",
        "slug",
        "severity",
        "objects",
        "location",
        "message",
        "measured",
        "allowed",
        "stderr",
        "unit",
        "suggestions",
        "unverifiable",
        "waived",
    }
    assert clash["code"] == "AB501" and clash["unit"] == "m3" and len(clash["location"]) == 3
    assert all(set(f) == set(clash) for f in findings)


def test_json_keys_equal_the_model_documents():
    from asbuilt.export.model_json import finding_to_dict, model_document
    from asbuilt.findings import Finding, Suggestion
    from asbuilt.model import Component, Model, Straight

    finding = Finding(
        "AB501",
        "clash",
        "error",
        ("A", "B"),
        "m",
        location=[1.0, 2.0, 3.0],
        measured=1.0,
        allowed=0.5,
        stderr=0.1,
        unit="m3",
        suggestions=(Suggestion("x", {"object": "A"}, True),),
    )
    comp = Component(id="A", type="pipe", geometry=Straight([0, 0, 0], [1, 0, 0], 0.05))
    document = model_document(Model(components=(comp,), findings=(finding,)))
    assert finding_to_dict(finding) == document["findings"][0]


@pytest.mark.parametrize(
    "option", [["--ignore", "clash"], ["--select", "AB4,AB2"], ["--ignore", "AB5"]]
)
def test_select_and_ignore(tmp_path, capsys, option):
    path = scan_file(tmp_path, PIPE, CROSSING)
    code, out, _ = run([path, *option], capsys)
    assert " clash:" not in out
    # the size rules (AB1) judge the occluded crossing pipe's fit, not what is tested here
    code, out, _ = run([path, *option, "--ignore", "AB1"], capsys)
    assert code == 0 and " clash:" not in out


def test_clash_alone_selected(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE, CROSSING)
    code, out, _ = run([path, "--select", "clash"], capsys)
    findings = [line for line in out.splitlines()[:-1] if not line.startswith("    ")]
    assert code == 1 and findings and all(" clash: " in line for line in findings)


def test_rules_file_changes_severity(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE, CROSSING)
    rules = tmp_path / "rules.toml"
    rules.write_text('[clash]\nseverity = "warning"\n', encoding="utf-8")
    code, out, _ = run([path, "--rules", rules, "--ignore", "AB1"], capsys)
    assert code == 0 and "warning clash:" in out


@pytest.mark.parametrize(
    "argv_tail, message",
    [
        (["--rules", "{tmp}/missing.toml"], "no such file"),
        (["--rules", "{tmp}/bad.toml"], "[no-such-rule]: unknown rule"),
        (["--design", "{tmp}/bad.json"], "invalid JSON"),
        (["--select", "AB999"], "unknown rule 'AB999'"),
        (["--fix", "{tmp}/out.xyz"], "unknown output format"),
    ],
)
def test_bad_input_exits_2_with_one_line(tmp_path, capsys, argv_tail, message):
    path = scan_file(tmp_path, PIPE)
    (tmp_path / "bad.toml").write_text("[no-such-rule]\nx = 1\n", encoding="utf-8")
    (tmp_path / "bad.json").write_text("{", encoding="utf-8")
    argv = [path, *(a.format(tmp=tmp_path) for a in argv_tail)]
    code, out, err = run(argv, capsys)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in err
    assert not (tmp_path / "out.xyz").exists()


def test_missing_scan_exits_2(tmp_path, capsys):
    code, _, err = run([tmp_path / "nope.json"], capsys)
    assert code == 2 and "nope.json" in err


def test_design_missing_and_extra(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE)
    design = tmp_path / "design.json"
    design.write_text(
        json.dumps(
            {
                "format": "asbuilt-design",
                "version": 1,
                "units": "mm",
                "pipes": [
                    {
                        "id": "D1",
                        "nominal": "4",
                        "start": [-1500, 4000, 1000],
                        "end": [1500, 4000, 1000],
                    },
                    {
                        "id": "D2",
                        "nominal": "4",
                        "start": [-1500, 9000, 1000],
                        "end": [1500, 9000, 1000],
                    },
                ],
            }
        ),
        encoding="utf-8",
    )
    code, out, _ = run([path, "--design", design], capsys)
    assert code == 1
    assert "D2: error missing-component: designed pipe D2" in out
    assert "P1: error" not in out  # the built pipe matches D1


def test_fix_writes_model_and_recheck_is_clean(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE, TILTED)
    code, out, _ = run([path, "--select", "misaligned-axis"], capsys)
    assert "P9: warning misaligned-axis: axis is" in out
    fixed = tmp_path / "fixed.json"
    # a tilt measured this well was built so: --fix alone leaves it as measured
    code, out, _ = run([path, "--select", "misaligned-axis", "--fix", fixed], capsys)
    assert code == 0 and "fixed:" not in out and "0 fixes written" in out
    args = [path, "--select", "misaligned-axis", "--accept", "AB201@P9", "--fix", fixed]
    code, out, _ = run(args, capsys)
    assert code == 0
    assert "fixed: P9: make P9's axis horizontal" in out
    assert "misaligned-axis:" not in out.replace("fixed:", "")
    assert fixed.exists()
    # the written model document, checked again, has nothing left to fix
    code, out, _ = run([fixed, "--select", "misaligned-axis"], capsys)
    assert code == 0 and out.splitlines()[-1].startswith("0 errors, 0 warnings")


def test_fix_keeps_the_hint_of_an_insulated_pipe(tmp_path, capsys):
    """A 4" pipe under 50 mm of lagging (OD 214.3 mm) snaps NPS 8; its hint is right, so --fix
    must not re-size it: the warning stays, naming lagging as a possible cause."""
    lagged = {**PIPE, "geometry": {**PIPE["geometry"], "od": 0.1143 + 2 * 0.050}}
    path = scan_file(tmp_path, lagged)
    fixed = tmp_path / "fixed.json"
    code, out, _ = run([path, "--select", "hint-mismatch", "--fix", fixed], capsys)
    assert code == 0
    assert 'P1: warning hint-mismatch: the hint 4" (114.3 mm) disagrees' in out
    assert "catalog sizes above the hint: lagging or insulation about" in out
    assert "fixed:" not in out and "0 fixes written" in out
    document = json.loads(fixed.read_text(encoding="utf-8"))
    (p1,) = [c for c in document["components"] if c["id"] == "P1"]
    assert not p1["snap"].get("hint_rejected")  # the hint still stands, and is reported again


def test_subprocess_exit_code(tmp_path):
    path = scan_file(tmp_path, PIPE, CROSSING)
    proc = subprocess.run(
        [sys.executable, "-m", "asbuilt", "check", str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 1 and "error clash" in proc.stdout


def test_list_rules_shows_the_rules_files_view(tmp_path, capsys):
    rules = tmp_path / "rules.toml"
    rules.write_text('ignore = ["slope"]\n[clash]\nseverity = "warning"\n', encoding="utf-8")
    code, out, _ = run(["--list-rules", "--rules", rules], capsys)
    assert code == 0
    clash = next(line for line in out.splitlines() if "AB501" in line)
    slope = next(line for line in out.splitlines() if "AB203" in line)
    assert "warning" in clash and " yes " in clash
    assert " no " in slope
    from asbuilt.rules import RULES

    assert all(r.code in out for r in RULES)
    # the pipeline's own finding for a refused fit is listed too, always on, not configurable
    refused = next(line for line in out.splitlines() if "AB001" in line)
    assert "fit-refused" in refused and "error" in refused and "always" in refused


def _runs(out, code):
    """The runs column of a rule's row in --list-rules' table."""
    row = next(line for line in out.splitlines() if f" {code} " in line)
    return [cell.strip() for cell in row.split("\u2502")][4]


@pytest.mark.parametrize(
    "options, runs",
    [
        (["--ignore", "slope"], {"AB203": "no", "AB202": "yes", "AB501": "yes"}),
        (["--select", "AB2"], {"AB203": "yes", "AB202": "yes", "AB501": "no"}),
        (["--select", "AB2", "--ignore", "AB203"], {"AB203": "no", "AB202": "yes", "AB501": "no"}),
    ],
)
def test_list_rules_honours_select_and_ignore(tmp_path, capsys, options, runs):
    code, out, _ = run(["--list-rules", *options], capsys)
    assert code == 0
    assert {c: _runs(out, c) for c in runs} == runs
    assert _runs(out, "AB001") == "always"  # no selection drops a refused fit


def test_list_rules_refuses_an_unknown_selector(capsys):
    code, _, err = run(["--list-rules", "--ignore", "no-such-rule"], capsys)
    assert code == 2 and "no-such-rule" in err


def test_no_scan_is_bad_input(capsys):
    code, out, err = run([], capsys)
    assert code == 2 and out == "" and "SCAN" in err


def test_a_scan_that_calls_itself_a_model_is_not_checked_as_an_empty_one(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE)
    document = json.loads(path.read_text())
    document["format"] = "asbuilt-model"
    path.write_text(json.dumps(document))
    code, out, err = run([path], capsys)
    assert code == 2 and out == ""
    assert err == (
        f'asbuilt: error: {path}: components: missing; it has "objects", so it looks like a '
        'scan: a scan\'s format is "asbuilt-scan"\n'
    )


def _site_catalog(path):
    """A user's pipe catalog (a renamed copy of the shipped ASME B36.10M table)."""
    from importlib import resources

    shipped = (resources.files("asbuilt.catalogs") / "asme-b36.10m.csv").read_text("utf-8")
    path.write_text(shipped.replace("# name: asme-b36.10m", "# name: site-pipe"), "utf-8")
    return path


def test_a_model_built_with_a_user_catalog_is_checked_with_it(tmp_path, capsys):
    """Re-checking a model document built with a user's catalog looked the catalog up by name
    among the shipped ones and exited 2 ("unknown catalog"), although the document records its
    file; a document that does not record it says which option gives it."""
    from pathlib import Path

    catalog = _site_catalog(tmp_path / "site.csv")
    spool = Path(__file__).resolve().parents[2] / "samples" / "spool.json"
    document = tmp_path / "model.json"
    assert main(["model", str(spool), "--catalog", str(catalog), "--out", str(document)]) == 0
    capsys.readouterr()
    code, out, err = run([document], capsys)
    assert code == 0, err
    assert "0 errors" in out
    old = json.loads(document.read_text(encoding="utf-8"))
    assert old.pop("catalog_file") == str(catalog.resolve())
    (tmp_path / "old.json").write_text(json.dumps(old), encoding="utf-8")
    code, out, err = run([tmp_path / "old.json"], capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and "old.json" in err and "'site-pipe'" in err
    assert "--catalog FILE" in err
    code, out, err = run([tmp_path / "old.json", "--catalog", catalog], capsys)
    assert code == 0, err


def test_the_same_user_catalog_by_a_relative_path_is_its_own(tmp_path, capsys, monkeypatch):
    # The document stores the catalog's absolute path; '--catalog site.csv' from its directory
    # named the same file and was refused as another catalog.
    from pathlib import Path

    _site_catalog(tmp_path / "site.csv")
    spool = Path(__file__).resolve().parents[2] / "samples" / "spool.json"
    monkeypatch.chdir(tmp_path)
    assert main(["model", str(spool), "--catalog", "site.csv", "--out", "model.json"]) == 0
    capsys.readouterr()
    code, out, err = run(["model.json", "--catalog", "site.csv"], capsys)
    assert code == 0, err
    code, out, err = run(["model.json", "--catalog", "./site.csv"], capsys)
    assert code == 0, err


def test_plural_of_fix_and_the_others():
    from asbuilt.cli._text import plural as _plural

    assert [_plural(n, "fix") for n in (0, 1, 2)] == ["0 fixes", "1 fix", "2 fixes"]
    assert [_plural(n, "error") for n in (0, 1, 2)] == ["0 errors", "1 error", "2 errors"]
    assert _plural(3, "component") == "3 components"


@pytest.fixture(scope="module")
def refused(tmp_path_factory):
    """The spool sample with the ray caster's refused NPS 1 scan X1, and its model documents
    (merged, and unmerged as built with --no-merge)."""
    from refused_scans import spool_with_refused, write

    folder = tmp_path_factory.mktemp("refused")
    scan = write(folder / "scan.json", spool_with_refused())
    assert main(["model", str(scan), "--out", str(folder / "model.json"), "-q"]) == 1
    assert main(["model", str(scan), "--no-merge", "--out", str(folder / "plain.json"), "-q"]) == 1
    return scan, folder / "model.json", folder / "plain.json"


def test_a_refused_object_is_an_error_finding_that_no_selection_drops(refused, capsys):
    scan, model, _ = refused
    capsys.readouterr()
    for source, extra in ((scan, []), (scan, ["--select", "clash"]), (model, [])):
        code, out, _ = run([source, *extra, "--format", "concise"], capsys)
        lines = out.splitlines()
        assert code == 1 and len(lines) == 2
        assert lines[0].startswith(
            f"{source}: X1: error fit-refused: not fitted as a cylinder, so it is not in the "
            "model: The shots this cylinder fits were nearly all seen edge-on"
        )
        assert lines[1] == "1 error, 0 warnings (0 unverifiable), 0 info in 10 components"


def test_fix_keeps_the_refused_object_and_says_0_fixes(refused, tmp_path, capsys):
    scan, _, _ = refused
    fixed = tmp_path / "fixed.json"
    code, out, _ = run([scan, "--fix", fixed], capsys)
    assert code == 1 and out.splitlines()[-1].endswith(f"; 0 fixes written to {fixed}")
    document = json.loads(fixed.read_text())
    (finding,) = document["findings"]
    assert finding["code"] == "AB001" and finding["objects"] == ["X1"]
    assert len(finding["suggestions"][0]["change"]["points"]) == 30  # the measured points


def test_model_document_refuses_no_merge_with_one_line(refused, capsys):
    _, model, _ = refused
    code, out, err = run([model, "--no-merge"], capsys)
    assert (code, out) == (2, "")
    assert err == (
        f"asbuilt: error: {model}: --no-merge applies only when building from a scan; this is "
        "an asbuilt-model document, already built: give the scan instead, or leave it out\n"
    )


def test_model_document_catalog_is_used_or_refused(refused, capsys):
    _, model, plain = refused
    # Merged: the pipes' sizes were chosen when it was built; another catalog changes nothing.
    code, out, err = run([model, "--catalog", "astm-b88"], capsys)
    assert (code, out) == (2, "") and len(err.splitlines()) == 1
    assert err.startswith(f"asbuilt: error: {model}: --catalog astm-b88 cannot re-size")
    code, out, _ = run([model, "--catalog", "asme-b36.10m"], capsys)  # its own: fine
    assert code == 1 and out.splitlines()[-1].startswith("1 error, 0 warnings")
    # Unmerged: the size rules snap against it (steel pipe ODs are no copper tube sizes).
    code, out, _ = run([plain], capsys)
    assert "nonstandard-diameter" not in out
    code, out, _ = run([plain, "--catalog", "astm-b88"], capsys)
    assert code == 1 and out.count("error nonstandard-diameter: ") == 4
    assert "is no ASTM B88 size" in out


@pytest.fixture(scope="module")
def model_document(tmp_path_factory):
    """The bytes of an asbuilt-model document of one fitted pipe (``check --fix``)."""
    tmp = tmp_path_factory.mktemp("model")
    scan = scan_file(tmp, PIPE)
    assert main(["check", str(scan), "--fix", str(tmp / "model.json")]) == 0
    return (tmp / "model.json").read_bytes()


def _deeply_nested_model(document: bytes) -> bytes:
    return document.replace(
        b'"components"', b'"deep": ' + b"[" * 100_000 + b"]" * 100_000 + b', "components"', 1
    )


# Before: a model document with a byte order mark was taken for a scan ("is "asbuilt-model",
# not "asbuilt-scan" ... report on it with 'asbuilt check'"), one nested too deeply was a
# RecursionError traceback (exit 1), from a file and from standard input alike, and a key given
# twice was read as its last value (a scan or design refuses it).
@pytest.mark.parametrize("command", ["check", "report"])
@pytest.mark.parametrize("stdin", [False, True], ids=["file", "stdin"])
@pytest.mark.parametrize(
    "mistake, expected",
    [
        ("bom", None),
        ("deep", "invalid JSON (nested too deeply)"),
    ],
)
def test_model_documents_with_a_bom_nested_too_deeply_or_a_repeated_key(
    model_document, command, stdin, mistake, expected, tmp_path
):
    data = {
        "bom": lambda: b"\xef\xbb\xbf" + model_document,
        "deep": lambda: _deeply_nested_model(model_document),
        "repeated": lambda: model_document.replace(
            b'"version": 1', b'"version": 1, "version": 1', 1
        ),
    }[mistake]()
    given = tmp_path / "given.json"
    given.write_bytes(data)
    out = tmp_path / ("out.json" if command == "check" else "out.csv")
    option = "--fix" if command == "check" else "--out"
    argv = [
        sys.executable,
        "-m",
        "asbuilt",
        command,
        "-" if stdin else str(given),
        option,
        str(out),
    ]
    result = subprocess.run(argv, input=data, capture_output=True, timeout=300)
    err = result.stderr.decode()
    assert "Traceback" not in err
    if expected is None:
        assert result.returncode == 0, err
        assert out.exists()
    else:
        assert result.returncode == 2
        name = "<stdin>" if stdin else str(given)
        assert err == f"asbuilt: error: {name}: {expected}\n"
        assert not out.exists()
    assert given.read_bytes() == data


def test_findings_on_ids_the_output_encoding_lacks_do_not_stop_check(tmp_path):
    """`check` printing a finding on a Chinese id to a Latin-1 standard output stopped with a
    UnicodeEncodeError traceback and exit code 1 (read as "error findings"); now the id is
    written as a backslash escape and the exit code is the findings'."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    doc = json.loads((root / "samples" / "spool.json").read_text(encoding="utf-8"))
    doc["objects"] = [o for o in doc["objects"] if o["id"] == "P5"]
    doc["objects"][0]["id"] = "管 5"
    doc["objects"][0]["points"] = doc["objects"][0]["points"][:12]  # too few: a warning
    doc["objects"][0].pop("measurements", None)
    doc["links"] = None
    (tmp_path / "scan.json").write_text(json.dumps(doc, ensure_ascii=False), encoding="utf-8")
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "check", "scan.json"],
        cwd=tmp_path,
        capture_output=True,
        timeout=300,
        env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin", "PYTHONIOENCODING": "latin-1"},
    )
    assert b"Traceback" not in done.stderr, done.stderr.decode("latin-1")
    assert done.returncode == 0
    assert "scan.json: \\u7ba1 5: warning too-few-points" in done.stdout.decode("latin-1")


ODD = {
    "id": "P5",
    "kind": "cylinder",
    "points": 30,
    "geometry": {"type": "cylinder", "start": [-1.5, 8, 2.0], "end": [1.5, 8, 2.0], "od": 0.125},
}


@pytest.fixture(scope="module")
def odd_scan(tmp_path_factory):
    """A pipe fitted between NPS 4 and NPS 5 (no hint) beside a pipe 5 degrees off level."""
    return scan_file(tmp_path_factory.mktemp("odd"), ODD, TILTED)


def test_text_numbers_each_findings_suggestions_with_the_choice_that_accepts_it(odd_scan, capsys):
    code, out, _ = run([odd_scan], capsys)
    assert code == 1
    lines = out.splitlines()
    at = next(i for i, line in enumerate(lines) if "P5: error nonstandard-diameter:" in line)
    assert lines[at + 1].startswith("    1. use NPS 4 (114.3 mm")
    assert lines[at + 1].endswith("[--accept AB101@P5:1]")
    assert lines[at + 2].startswith("    2. use NPS 5 (141.3 mm")
    assert lines[at + 2].endswith("[--accept AB101@P5:2]")
    assert lines[at + 3].startswith("    3. check the material") and "[" not in lines[at + 3]
    # an unambiguous change: --fix alone accepts it, and one change needs no number
    # measured 5 degrees off: accepted only by choice, not by --fix alone
    assert out.count("  [--accept AB201@P9]") == 1 and "[--fix, or" not in out
    # concise: the finding lines and the summary only
    _, concise, _ = run([odd_scan, "--format", "concise"], capsys)
    assert concise.splitlines() == [line for line in lines if not line.startswith("    ")]


def test_accept_applies_the_chosen_size_only(odd_scan, tmp_path, capsys):
    fixed = tmp_path / "fixed.json"
    code, out, _ = run([odd_scan, "--accept", "AB101@P5:2", "--fix", fixed], capsys)
    assert code == 0
    assert "fixed: P5: use NPS 5 (141.3 mm" in out
    assert "P5: error nonstandard-diameter" not in out  # the re-check after the fix
    assert "P9: warning misaligned-axis" in out  # not chosen, so not fixed
    document = json.loads(fixed.read_text(encoding="utf-8"))
    (p5,) = [c for c in document["components"] if c["id"] == "P5"]
    assert p5["nominal"] == "5"
    # --fix alone accepts nothing here: the size and the levelling of a tilt measured to a
    # fraction of a degree are for a person to choose
    code, out, _ = run([odd_scan, "--fix", tmp_path / "all.json"], capsys)
    assert "fixed:" not in out and "0 fixes written" in out


@pytest.mark.parametrize(
    "accept, message",
    [
        ("AB101@P5", "AB101@P5 has 2 suggestions to choose from: add :1 (use NPS 4"),
        ("AB101@P5:3", "suggestion 3 of AB101@P5 is advice, not a change to accept"),
        ("AB101@P7", "no AB101 finding on P7 in this check; findings with a change to accept: "),
        ("P5", "give a finding as RULE@OBJECTS[:N]"),
    ],
)
def test_a_bad_choice_is_one_line_and_writes_nothing(odd_scan, tmp_path, capsys, accept, message):
    fixed = tmp_path / "fixed.step"
    code, out, err = run([odd_scan, "--accept", accept, "--fix", fixed], capsys)
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and message in err
    assert list(tmp_path.iterdir()) == []


def test_accept_needs_fix(odd_scan, capsys):
    code, out, err = run([odd_scan, "--accept", "AB101@P5:2"], capsys)
    assert code == 2 and out == ""
    assert "--accept needs --fix OUT" in err and err.count("\n") == 1


def test_a_waiver_in_the_rules_file_turns_an_error_into_info_and_exit_0(tmp_path, capsys):
    path = scan_file(tmp_path, PIPE, CROSSING)
    code, out, _ = run([path, "--select", "clash"], capsys)
    assert code == 1 and "P1,P2: error clash:" in out
    waivers = tmp_path / "project.toml"
    waivers.write_text(
        '[[waive]]\nfinding = "clash@P1,P2"\nreason = "P2 passes through a sleeve in P1, M-201"\n',
        encoding="utf-8",
    )
    code, out, _ = run([path, "--select", "clash", "--rules", waivers], capsys)
    assert code == 0
    assert (
        "P1,P2: info clash: waived (P2 passes through a sleeve in P1, M-201); as an error: " in out
    )
    code, out, _ = run(["--list-rules"], capsys)
    assert "AB002" in out and "unused-waiver" in out


FACING = [
    {
        "id": "F1",
        "kind": "cylinder",
        "points": 30,
        "geometry": {"type": "cylinder", "start": [-1, 4, 1], "end": [1.4, 4, 1], "od": 0.1143},
    },
    {
        "id": "F2",
        "kind": "cylinder",
        "points": 30,
        "geometry": {"type": "cylinder", "start": [2, 4.6, 1], "end": [2, 7, 1], "od": 0.1143},
    },
]


def test_accepting_a_scan_link_merges_again_and_joins_the_pipes(tmp_path, capsys):
    """AB304 on two pipes facing each other beyond merging's reach offers the scan link that
    would join them; accepted, the model is merged again with it (an elbow), and the written
    document's scan keeps the link."""
    path = scan_file(tmp_path, *FACING)
    code, out, _ = run([path, "--select", "unjoined-end"], capsys)
    assert "warning unjoined-end: F1 ends" in out
    assert "1. link F1 and F2 in the scan and merge again" in out
    assert "[--accept AB304@F1,F2]" in out and "[--fix, or" not in out
    fixed = tmp_path / "fixed.json"
    # never by --fix alone
    run([path, "--fix", fixed], capsys)
    document = json.loads(fixed.read_text(encoding="utf-8"))
    assert [c["type"] for c in document["components"]] == ["pipe", "pipe"]
    code, out, _ = run([path, "--accept", "AB304@F1,F2", "--fix", fixed], capsys)
    assert code == 0
    assert "fixed: F1, F2: link F1 and F2 in the scan and merge again" in out
    assert "unjoined-end" not in out.replace("(unjoined-end)", "")
    document = json.loads(fixed.read_text(encoding="utf-8"))
    assert [c["type"] for c in document["components"]] == ["pipe", "elbow", "pipe"]
    assert len({c["spool"] for c in document["components"]}) == 1
    assert document["scan"]["links"] == [["F1", "F2"]]
    # the same from the model document of the unlinked scan
    model = tmp_path / "model.json"
    assert main(["model", str(path), "--out", str(model)]) == 0
    capsys.readouterr()
    code, out, _ = run([model, "--accept", "AB304@F1,F2", "--fix", tmp_path / "f2.json"], capsys)
    assert code == 0 and "fixed: F1, F2: link F1 and F2" in out
