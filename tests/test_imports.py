"""Import hygiene: scan loading, fitting and ``asbuilt fit`` never load the CAD kernel.

Each check runs in a fresh interpreter so that other tests' imports cannot hide a leak.
"""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ENV = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}

SCRIPT = r"""
import importlib.util, io, json, sys
from contextlib import redirect_stdout

import asbuilt
from asbuilt.cli import main
from asbuilt.fit import FITTERS

assert "asbuilt.fit.cylinder" not in sys.modules, "the fits are imported only when used"
kinds = [k for k in ("cylinder", "cuboid", "sphere", "plane", "hull")
         if importlib.util.find_spec(FITTERS[k][0]) is not None]
path = sys.argv[1]
with open(path) as handle:
    doc = json.load(handle)
doc["objects"] = [o for o in doc["objects"] if o["kind"] in kinds]
with open(path, "w") as handle:
    json.dump(doc, handle)

scan = asbuilt.load_scan(path)
report = asbuilt.fit(scan)
buffer = io.StringIO()
with redirect_stdout(buffer):
    code = main(["fit", path, "--json"])
assert code == 0
assert len(json.loads(buffer.getvalue())["objects"]) == len(report) == len(kinds)
heavy = sorted(m for m in sys.modules if m.split(".")[0] in ("cadquery", "OCP"))
print(json.dumps({"kinds": kinds, "heavy": heavy}))
"""


def _scan_file(tmp_path: Path) -> Path:
    sys.path.insert(0, str(ROOT / "tests" / "scan"))
    try:
        from scan_cases import make_doc
    finally:
        sys.path.remove(str(ROOT / "tests" / "scan"))
    path = tmp_path / "scan.json"
    path.write_text(json.dumps(make_doc("mm")), encoding="utf-8")
    return path


def test_load_fit_and_cli_do_not_import_cadquery(tmp_path):
    path = _scan_file(tmp_path)
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT, str(path)],
        capture_output=True,
        text=True,
        timeout=120,
        env=ENV,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["heavy"] == [], f"CAD kernel modules imported: {result['heavy']}"


def test_python_m_asbuilt_help(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "asbuilt", "--help"],
        capture_output=True,
        text=True,
        timeout=120,
        env=ENV,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage: asbuilt")
    assert "fit" in done.stdout


def test_console_script_version(tmp_path):
    script = Path(sys.executable).parent / "asbuilt"
    if not script.exists():
        found = shutil.which("asbuilt")
        if found is None:
            pytest.skip("the asbuilt console script is not installed (pip install -e .)")
        script = Path(found)
    done = subprocess.run(
        [str(script), "--version"], capture_output=True, text=True, timeout=120, cwd=tmp_path
    )
    import asbuilt

    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"asbuilt {asbuilt.__version__}"
