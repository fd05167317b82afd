"""Every reader of a user's text file (design, model document, scene, rules, catalog, calibration,
targets, plan) treats the same mistake the same way (asbuilt/_text.py): a UTF-8 byte order mark
is accepted, and a file that is not UTF-8, a directory or missing is one line naming the file.

Before, the scan and catalog readers accepted a byte order mark and the others refused it as
"invalid JSON (Unexpected UTF-8 BOM (decode using utf-8-sig))" or "not valid TOML"; a Latin-1
file was "cannot read the ... ('utf-8' codec can't decode byte 0xe9 in position 5: invalid
continuation byte)" in four of them; a directory was "([Errno 21] Is a directory: '<path>')",
the path twice.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from asbuilt.drivers.calibration import load_calibration, load_targets
from asbuilt.drivers.plan import load_plan

from asbuilt.catalog import load_catalog
from asbuilt.design import load_design
from asbuilt.errors import AsbuiltError
from asbuilt.export.model_json import load_model_document
from asbuilt.rules.config import load_rules
from asbuilt.sim.scene import load_scene

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "drivers" / "examples"

DESIGN = {
    "format": "asbuilt-design",
    "version": 1,
    "units": "mm",
    "pipes": [{"id": "D1", "label": "caf\u00e9", "start": [0, 0, 0], "end": [1000, 0, 0]}],
}
MODEL = {
    "format": "asbuilt-model",
    "version": 1,
    "units": "m",
    "name": "caf\u00e9",
    "components": [],
    "spools": [],
    "findings": [],
}

#: reader, file name, valid UTF-8 content holding a non-ASCII character.
READERS = {
    "design": (load_design, "d.json", json.dumps(DESIGN, ensure_ascii=False)),
    "model": (load_model_document, "m.json", json.dumps(MODEL, ensure_ascii=False)),
    "scene": (
        load_scene,
        "s.json",
        (ROOT / "samples" / "scenes" / "spool.scene.json")
        .read_text(encoding="utf-8")
        .replace('"name": "', '"name": "caf\u00e9 ', 1),
    ),
    "rules": (load_rules, "r.toml", '# caf\u00e9\nignore = ["too-few-points"]\n'),
    "catalog": (
        load_catalog,
        "c.csv",
        "# caf\u00e9\n" + (ROOT / "catalogs" / "asme-b36.10m.csv").read_text(encoding="utf-8"),
    ),
    "calibration": (
        load_calibration,
        "cal.json",
        (EXAMPLES / "ptu-d46.cal.json")
        .read_text(encoding="utf-8")
        .replace('"comment": "', '"comment": "caf\u00e9 ', 1),
    ),
    "targets": (
        load_targets,
        "t.json",
        (EXAMPLES / "room.targets.json")
        .read_text(encoding="utf-8")
        .replace('"floor"', '"caf\u00e9"', 1),
    ),
    "plan": (
        load_plan,
        "p.json",
        (EXAMPLES / "room.plan.json").read_text(encoding="utf-8").replace('"floor"', '"caf\u00e9"'),
    ),
}


def _write(tmp_path, name, data: bytes) -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


@pytest.mark.parametrize("reader", sorted(READERS))
def test_a_byte_order_mark_is_accepted_by_every_reader(reader, tmp_path):
    load, name, text = READERS[reader]
    plain = load(_write(tmp_path, name, text.encode("utf-8")))
    with_bom = load(_write(tmp_path, "bom-" + name, b"\xef\xbb\xbf" + text.encode("utf-8")))
    assert type(with_bom) is type(plain)
    if isinstance(plain, dict):
        assert with_bom.keys() == plain.keys()


@pytest.mark.parametrize("reader", sorted(READERS))
def test_a_file_that_is_not_utf8_is_one_line_naming_it_and_the_byte(reader, tmp_path):
    load, name, text = READERS[reader]
    data = text.encode("latin-1")
    path = _write(tmp_path, name, data)
    with pytest.raises(AsbuiltError) as info:
        load(path)
    message = str(info.value)
    offset = data.index(b"\xe9")
    assert message.startswith(
        f"{path}: is not UTF-8 text (byte 0x{data[offset]:02x} at offset {offset}); save the "
    ), message
    assert "\n" not in message and "codec" not in message
    assert path.read_bytes() == data  # never modified


@pytest.mark.parametrize("reader", sorted(READERS))
@pytest.mark.parametrize(
    "encoding, named",
    [
        ("utf-16", "UTF-16"),  # with a byte order mark, as Windows "Unicode" saves
        ("utf-16-le", "UTF-16"),  # without one: was "invalid JSON at line 1 column 2"
        ("utf-16-be", "UTF-16"),
        ("utf-32", "UTF-32"),
    ],
)
def test_utf16_and_utf32_files_are_named_as_such(reader, encoding, named, tmp_path):
    load, name, text = READERS[reader]
    data = text.encode(encoding)
    path = _write(tmp_path, name, data)
    with pytest.raises(AsbuiltError) as info:
        load(path)
    message = str(info.value)
    assert message.startswith(f"{path}: is {named} text, not UTF-8; save the "), message
    assert "\n" not in message
    assert path.read_bytes() == data


@pytest.mark.parametrize("reader", sorted(READERS))
def test_a_directory_is_one_line_naming_it_once(reader, tmp_path):
    load, name, _ = READERS[reader]
    path = tmp_path / name
    path.mkdir()
    with pytest.raises(AsbuiltError) as info:
        load(path)
    message = str(info.value)
    assert message.startswith(f"{path}: is a directory; give the "), message
    assert message.count(str(path)) == 1 and "Errno" not in message


@pytest.mark.parametrize("reader", sorted(READERS))
def test_a_missing_file_is_one_line_naming_it_once(reader, tmp_path):
    load, name, _ = READERS[reader]
    path = tmp_path / name
    with pytest.raises(AsbuiltError) as info:
        load(path)
    message = str(info.value)
    assert message.startswith(f"{path}: "), message
    assert message.count(str(path)) == 1 and "Errno" not in message and "\n" not in message


# Before: the scan and design readers refused a key given twice; the scene, model document,
# calibration, targets and plan readers kept the last one without a word.
@pytest.mark.parametrize("reader", sorted(r for r in READERS if READERS[r][1].endswith(".json")))
def test_a_key_given_twice_is_refused_by_every_json_reader(reader, tmp_path):
    load, name, text = READERS[reader]
    assert '"version": 1' in text.replace('"version":1', '"version": 1'), reader
    twice = text.replace('"version": 1', '"version": 1, "version": 1', 1)
    path = _write(tmp_path, name, twice.encode("utf-8"))
    with pytest.raises(AsbuiltError) as info:
        load(path)
    assert str(info.value) == (
        f"{path}: version: given twice in one JSON object; keep one (JSON readers differ on "
        "which one counts)"
    )
