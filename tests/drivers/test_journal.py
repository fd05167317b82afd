"""The session journal: durable appends, torn and corrupt lines, its place beside the scan."""

from __future__ import annotations

import json
import os

import pytest
from asbuilt.drivers.journal import Journal, journal_path_for, read_journal, torn_path_for

from asbuilt.errors import ScanError


def test_journal_sits_beside_the_scan(tmp_path):
    assert journal_path_for(tmp_path / "site.json") == tmp_path / "site.json.journal"


def test_records_are_on_disk_as_soon_as_appended(tmp_path):
    path = tmp_path / "s.json.journal"
    journal = Journal(path)
    journal.append({"type": "session", "version": 1})
    journal.append({"type": "shot", "range": 1.25, "error": None})
    # read through another file object while the journal is still open: nothing is buffered
    lines = path.read_text().splitlines()
    assert [json.loads(line) for line in lines] == [
        {"type": "session", "version": 1},
        {"type": "shot", "range": 1.25, "error": None},
    ]
    journal.close()
    assert read_journal(path)[1]["range"] == 1.25


def test_appending_continues_an_existing_journal(tmp_path):
    path = tmp_path / "j"
    for n in range(3):
        journal = Journal(path)
        journal.append({"n": n})
        journal.close()
    assert [r["n"] for r in read_journal(path)] == [0, 1, 2]


def test_torn_last_line_is_dropped(tmp_path):
    path = tmp_path / "j"
    path.write_text('{"type":"session"}\n\n{"type":"shot","ra')
    assert read_journal(path) == [{"type": "session"}]


def test_corrupt_line_before_the_end_is_refused(tmp_path):
    path = tmp_path / "x.json.journal"
    path.write_text('{"type":"session"}\nnot json\n{"type":"resume"}\n')
    with pytest.raises(ScanError, match="line 2: corrupt line"):
        read_journal(path)


def test_missing_journal(tmp_path):
    with pytest.raises(ScanError, match="cannot read the journal"):
        read_journal(tmp_path / "none")


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_unwritable_directory(tmp_path):
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        with pytest.raises(ScanError, match="cannot write the journal"):
            Journal(locked / "s.json.journal")
    finally:
        locked.chmod(0o700)


def test_missing_directory(tmp_path):
    with pytest.raises(ScanError, match="cannot write the journal"):
        Journal(tmp_path / "nowhere" / "s.json.journal")


def test_a_resumed_journal_is_not_glued_onto_a_torn_last_line(tmp_path):
    # crash mid-write: the torn record is ignored, and the next record starts its own line
    path = tmp_path / "s.json.journal"
    path.write_text('{"type":"session"}\n{"type":"shot","seq":1}\n{"type":"shot","se')
    journal = Journal(path)
    journal.append({"type": "resume"})
    journal.close()
    assert read_journal(path) == [
        {"type": "session"},
        {"type": "shot", "seq": 1},
        {"type": "resume"},
    ]
    journal = Journal(path)  # and the next resume reads it again
    journal.append({"type": "resume"})
    journal.close()
    assert len(read_journal(path)) == 4


def test_a_complete_last_record_without_its_newline_is_kept(tmp_path):
    path = tmp_path / "s.json.journal"
    path.write_text('{"type":"session"}\n{"type":"shot","seq":1}')  # crash before the newline
    journal = Journal(path)
    journal.append({"type": "resume"})
    journal.close()
    assert [r["type"] for r in read_journal(path)] == ["session", "shot", "resume"]


# Found by mutation fuzzing (asbuilt scan --resume over the simulators, 400 journals cut short
# and mutated): each was a traceback and is now one located line.
@pytest.mark.parametrize(
    "content, message",
    [
        (
            b'{"type": "session"}\n{"type": "shot", "x": "\xff"}\n',
            "not UTF-8 text (byte 43); the journal was edited or corrupted and cannot be resumed",
        ),
        (
            b'{"type": "session"}\ntrue\n{"type": "done"}\n',
            "line 2: corrupt line (not a JSON object); the journal cannot be resumed",
        ),
    ],
    ids=["not-utf8", "record-not-an-object"],
)
def test_fuzzed_journals_are_one_located_line(tmp_path, content, message):
    path = tmp_path / "scan.json.journal"
    path.write_bytes(content)
    with pytest.raises(ScanError) as info:
        read_journal(path)
    assert str(info.value) == f"{path}: {message}"


def test_long_integers_in_a_journal_read_as_infinite(tmp_path):
    # a 5,000-digit range escaped Python's integer-string limit as a ValueError
    path = tmp_path / "scan.json.journal"
    path.write_text('{"type": "shot", "range": 1' + "0" * 5000 + "}\n", encoding="utf-8")
    assert read_journal(path) == [{"type": "shot", "range": float("inf")}]


TORN = b'{"type":"session"}\n{"type":"shot","seq":1}\n{"type":"shot","seq":2,"range":4.12'


def test_opening_a_journal_modifies_nothing(tmp_path):
    # a session opens the journal before it may still refuse (the scan file cannot be written):
    # until the first append the bytes, torn last line included, are untouched
    path = tmp_path / "s.json.journal"
    path.write_bytes(TORN)
    Journal(path).close()
    assert path.read_bytes() == TORN
    assert not torn_path_for(path).exists()


def test_the_torn_last_line_is_kept_beside_the_journal_before_it_is_cut(tmp_path):
    # the torn bytes may be the only trace of a shot's range: copied to <journal>.torn first
    path = tmp_path / "s.json.journal"
    path.write_bytes(TORN)
    journal = Journal(path)
    journal.append({"type": "resume"})
    journal.close()
    assert torn_path_for(path) == tmp_path / "s.json.journal.torn"
    assert torn_path_for(path).read_bytes() == b'{"type":"shot","seq":2,"range":4.12\n'
    assert path.read_bytes() == TORN.rsplit(b"\n", 1)[0] + b'\n{"type":"resume"}\n'
    with open(path, "ab") as f:  # a second crash, a second torn line: kept after the first
        f.write(b'{"type":"sh')
    journal = Journal(path)
    journal.append({"type": "resume"})
    journal.close()
    assert torn_path_for(path).read_bytes().splitlines() == [
        b'{"type":"shot","seq":2,"range":4.12',
        b'{"type":"sh',
    ]
    assert [r["type"] for r in read_journal(path)] == ["session", "shot", "resume", "resume"]


def test_a_torn_line_that_cannot_be_kept_is_not_cut(tmp_path):
    path = tmp_path / "s.json.journal"
    path.write_bytes(TORN)
    torn_path_for(path).mkdir()  # the copy cannot be written
    journal = Journal(path)
    with pytest.raises(ScanError, match="cannot write the journal .*nothing was appended"):
        journal.append({"type": "resume"})
    journal.close()
    assert path.read_bytes() == TORN


def test_a_complete_last_record_with_a_long_integer_is_not_torn(tmp_path):
    # read_journal reads it (as infinite), so mending must not cut it as torn
    path = tmp_path / "s.json.journal"
    path.write_text('{"type":"session"}\n{"type":"shot","range":1' + "0" * 5000 + "}")
    journal = Journal(path)
    journal.append({"type": "resume"})
    journal.close()
    assert [r["type"] for r in read_journal(path)] == ["session", "shot", "resume"]
    assert not torn_path_for(path).exists()
