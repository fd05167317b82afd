"""Shared fixtures: the zoo model (tests/cad/cad_zoo.py), its solids, and the glTF validator."""

from __future__ import annotations

import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
VALIDATOR_SCRIPT = Path(__file__).with_name("validate_gltf.mjs")


def _load_zoo():
    name = "cad_zoo"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, ROOT / "tests" / "cad" / "cad_zoo.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


zoo_module = _load_zoo()


def _load_synthetic_pipes():
    name = "synthetic_pipes"
    if name not in sys.modules:
        path = ROOT / "tests" / "merge" / "synthetic_pipes.py"
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


@pytest.fixture(scope="session")
def synthetic_pipes():
    """tests/merge/synthetic_pipes.py: pipes and fit reports made by hand."""
    return _load_synthetic_pipes()


@pytest.fixture(scope="session")
def zoo():
    return zoo_module.zoo_model()


@pytest.fixture(scope="session")
def zoo_cad(zoo):
    from asbuilt.cad import prepare

    return prepare(zoo)


@pytest.fixture(scope="session")
def spool_6x4x2():
    """A merged NPS 6 SCH 40 run with an NPS 2 outlet tee and a 6 x 4 reducer on an NPS 4
    pipe (synthetic fits, tests/merge/synthetic_pipes.py): fittings between pipes of two
    walls."""
    from asbuilt.merge import merge_model

    pipes = _load_synthetic_pipes()
    Pipe = pipes.Pipe
    fits = [
        Pipe("P1", (0, 0, 1), (1.8, 0, 1), 0.1683),
        Pipe("P2", (2.2, 0, 1), (3.4, 0, 1), 0.1683),
        Pipe("P3", (2, 0.2, 1), (2, 2, 1), 0.0603),
        Pipe("P4", (3.6, 0, 1), (5, 0, 1), 0.1143),
    ]
    return merge_model(pipes.report_of(fits), schedule="40")


@pytest.fixture(scope="session")
def elbow_6x4():
    """A merged L of NPS 6 and NPS 4 SCH 40 pipes (synthetic fits): an elbow between pipes of
    two sizes and walls."""
    from asbuilt.merge import merge_model

    pipes = _load_synthetic_pipes()
    Pipe = pipes.Pipe
    fits = [Pipe("P1", (0, 0, 1), (1.8, 0, 1), 0.1683), Pipe("P2", (2, 0.2, 1), (2, 2, 1), 0.1143)]
    return merge_model(pipes.report_of(fits), schedule="40")


def _node_modules() -> Path | None:
    candidates = [
        os.environ.get("ASBUILT_NODE_MODULES"),
        ROOT / "node_modules",
        ROOT / ".ci" / "node_modules",
        ROOT / ".ci" / "node" / "node_modules",
    ]
    for candidate in candidates:
        if candidate and (Path(candidate) / "gltf-validator" / "package.json").is_file():
            return Path(candidate)
    return None


@pytest.fixture(scope="session")
def gltf_validator():
    """A function validating glTF files with the Khronos validator; returns its reports.

    Skips (with the reason) only on a developer machine without node or the npm package; under
    CI (``CI=true``) a missing validator fails the test.
    """
    node = shutil.which("node")
    modules = _node_modules()
    if node is None or modules is None:
        missing = "node" if node is None else "the npm package gltf-validator"
        message = (
            f"{missing} not found: run `npm install --prefix .ci/node gltf-validator` "
            "or set ASBUILT_NODE_MODULES to a node_modules folder that has it"
        )
        if os.environ.get("CI", "").lower() in ("true", "1", "yes"):
            pytest.fail(message)
        pytest.skip(message)

    def validate(*paths) -> list[dict]:
        result = subprocess.run(
            [node, str(VALIDATOR_SCRIPT), str(modules), *map(str, paths)],
            capture_output=True,
            text=True,
            timeout=120,
        )
        if result.returncode == 2:
            pytest.fail(f"the glTF validator could not run: {result.stderr.strip()}")
        return [json.loads(line) for line in result.stdout.splitlines() if line.strip()]

    return validate
