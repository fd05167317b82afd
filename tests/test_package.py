"""Packaging: a wheel built from the repository works on its own, data files included."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# Folders whose non-Python files the code loads at run time, and where the wheel puts them.
DATA_FOLDERS = {"catalogs": "asbuilt/catalogs", "asbuilt": "asbuilt", "drivers": "asbuilt/drivers"}
DATA_SUFFIXES = {".csv", ".json", ".toml"}


def _data_files_in_repo() -> set[str]:
    expected = set()
    for folder, installed in DATA_FOLDERS.items():
        for path in (ROOT / folder).rglob("*"):
            if path.suffix in DATA_SUFFIXES and "__pycache__" not in path.parts:
                rel = path.relative_to(ROOT / folder).as_posix()
                expected.add(f"{installed}/{rel}")
    return expected


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """Build a wheel from a copy of the repository's own files (no network, no build isolation)."""
    src = tmp_path_factory.mktemp("src")
    for name in ("asbuilt", "drivers", "catalogs"):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    out = tmp_path_factory.mktemp("dist")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(out),
            str(src),
        ],
        check=True,
    )
    (found,) = out.glob("asbuilt-*.whl")
    return found


def test_wheel_contains_every_data_file(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    missing = sorted(_data_files_in_repo() - names)
    assert not missing, f"data files missing from the wheel: {missing}"
    assert "asbuilt/drivers/__init__.py" in names
    assert "asbuilt/catalogs/__init__.py" in names


def test_wheel_contains_every_driver_module(wheel):
    """Every module of drivers/ (the device drivers and simulators: pelco, lw20, sim_pelco...)
    is installed as asbuilt.drivers.<name>."""
    names = set(zipfile.ZipFile(wheel).namelist())
    modules = {
        f"asbuilt/drivers/{p.relative_to(ROOT / 'drivers').as_posix()}"
        for p in (ROOT / "drivers").rglob("*.py")
        if "__pycache__" not in p.parts
    }
    assert {"asbuilt/drivers/pelco.py", "asbuilt/drivers/lw20.py"} <= modules
    missing = sorted(modules - names)
    assert not missing, f"driver modules missing from the wheel: {missing}"


def test_installed_wheel_works_on_its_own(wheel, tmp_path):
    target = tmp_path / "site"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--no-deps",
            "-q",
            "--target",
            str(target),
            str(wheel),
        ],
        check=True,
    )
    probe = (
        "import asbuilt, asbuilt.drivers, asbuilt.catalogs, importlib.resources as r\n"
        f"assert asbuilt.__file__.startswith({str(target)!r}), asbuilt.__file__\n"
        "from asbuilt.cli import build_parser\n"
        "from asbuilt.drivers.pelco import PelcoD\n"
        "from asbuilt.drivers.lw20 import LW20\n"
        "from asbuilt.drivers import sim_pelco, sim_lw20\n"
        "build_parser()\n"
        "names = [p.name for p in r.files('asbuilt.catalogs').iterdir()]\n"
        "assert any(n.endswith('.csv') for n in names), names\n"
        "print('ok')\n"
    )
    env = dict(os.environ, PYTHONPATH=str(target))
    result = subprocess.run(
        [sys.executable, "-c", probe], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"


def test_readme_test_command_is_what_ci_runs():
    readme = (ROOT / "README.md").read_text()
    ci = (ROOT / ".ci" / "run").read_text()
    command = next(
        line.strip() for line in readme.splitlines() if line.strip().endswith(".venv/bin/pytest")
    )
    assert command in ci
    # ``set -e`` ignores a failure before ``&&``: the bare line let a failed install pass CI.
    (line,) = [line.strip() for line in ci.splitlines() if command in line]
    assert line.startswith("if ! {") and line.endswith("; }; then"), line


SUBMODULE_PROBE = r"""
import json, sys
import asbuilt
schema = asbuilt.scan.scan_schema()  # no 'import asbuilt.scan' first
reached = {
    "schema_title": schema.get("title"),
    "check_model": asbuilt.rules.check_model.__name__,
    "export_model": asbuilt.export.export_model.__name__,
    "in_dir": sorted({"scan", "rules", "export", "report"} & set(dir(asbuilt))),
}
try:
    asbuilt.no_such_module
except AttributeError as exc:
    reached["missing"] = str(exc)
reached["heavy"] = sorted(m for m in sys.modules if m.split(".")[0] in ("cadquery", "OCP"))
print(json.dumps(reached))
"""


def test_documented_submodules_are_reachable_after_import_asbuilt(tmp_path):
    done = subprocess.run(
        [sys.executable, "-c", SUBMODULE_PROBE],
        cwd=tmp_path,
        env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    reached = __import__("json").loads(done.stdout.strip().splitlines()[-1])
    from asbuilt.scan import scan_schema

    assert reached["schema_title"] == scan_schema()["title"]
    assert (reached["check_model"], reached["export_model"]) == ("check_model", "export_model")
    assert reached["in_dir"] == ["export", "report", "rules", "scan"]
    assert reached["missing"] == "module 'asbuilt' has no attribute 'no_such_module'"
    assert reached["heavy"] == []  # reaching export/report does not load the CAD kernel
