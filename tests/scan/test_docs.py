"""docs/scan-format.md stays true: its example messages are the loader's, its limits the code's."""

from __future__ import annotations

import re
from pathlib import Path

from scan_cases import BAD

from asbuilt.scan import KINDS, MAX_FILE_BYTES, MAX_POINTS
from asbuilt.tolerances import MIN_POINTS
from asbuilt.units import UNITS

DOC = (Path(__file__).resolve().parents[2] / "docs" / "scan-format.md").read_text(encoding="utf-8")

# Messages about the file as a whole, checked word for word in test_load.py.
FILE_LEVEL = (
    "file does not exist;",
    "cannot be read (",
    "is not UTF-8 text",
    "is UTF-16 text, not UTF-8;",
    "objects[12] (P13): the scan holds more than",
)


def test_every_example_message_is_one_the_loader_gives():
    examples = re.findall(r"`scan\.json: ([^`]+)`", DOC)
    assert len(examples) >= 15
    known = {case.message for case in BAD}
    for example in examples:
        if example.startswith(FILE_LEVEL) or example == "objects[2] (P3): <why>":
            continue
        assert example in known, example


def test_limits_kinds_and_units_are_documented():
    assert f"**{MAX_FILE_BYTES // (1024 * 1024)} MiB**" in DOC
    assert f"**{MAX_POINTS:,} points**" in DOC
    for kind in KINDS:
        assert re.search(rf"\| `{kind}` \| [^|]+ \| {MIN_POINTS[kind]} \|", DOC), kind
    for unit in UNITS:
        assert f'`"{unit}"`' in DOC
    assert "asbuilt/schemas/scan.schema.json" in DOC
