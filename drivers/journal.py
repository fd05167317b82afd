"""The session journal: one JSON line per record, flushed and fsynced before the next shot.

``scan.json`` gets ``scan.json.journal`` beside it. Records (see docs/acquisition.md):
``session`` (settings, calibration), ``object`` (the target), ``shot`` (requested and reached
angles, raw range or error), ``done`` / ``failed`` and ``resume``. A torn last line (a crash in
the middle of a write) is ignored when reading and cut off before the next record is appended
(a complete last record that only lacks its newline gets one); a bad line elsewhere is an error.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from asbuilt._json_numbers import parse_int as _parse_int
from asbuilt.errors import ScanError

__all__ = ["Journal", "read_journal", "journal_path_for"]

_TAIL_BLOCK = 65536  # bytes read at a time when looking for the journal's last line break


def journal_path_for(out) -> Path:
    """The journal beside an output scan: ``scan.json`` -> ``scan.json.journal``."""
    out = Path(out)
    return out.with_name(out.name + ".journal")


class Journal:
    """Append-only JSON-lines file; every record is flushed and fsynced before returning."""

    def __init__(self, path):
        self.path = Path(path)
        try:
            _mend_tail(self.path)
            self._f = open(self.path, "a", encoding="utf-8")  # kept open for the session
        except OSError as exc:
            raise ScanError(
                f"cannot write the journal ({exc.strerror}); choose a writable --out directory",
                source=str(self.path),
            ) from None

    def append(self, record: dict) -> None:
        """Write one record durably."""
        self._f.write(json.dumps(record, separators=(",", ":")) + "\n")
        self._f.flush()
        os.fsync(self._f.fileno())

    def close(self) -> None:
        """Close the file."""
        self._f.close()


def _mend_tail(path: Path) -> None:
    """End an existing journal at a line break before appending to it.

    A crash mid-write leaves a last line without its newline. If that line is a complete record
    (the crash came just before the newline), the newline is added; otherwise the torn bytes,
    which :func:`read_journal` ignores, are cut off. Either way the next record starts a line
    of its own instead of being glued onto the torn one.
    """
    try:
        f = open(path, "r+b")
    except FileNotFoundError:
        return
    with f:
        size = f.seek(0, os.SEEK_END)
        if size == 0:
            return
        f.seek(size - 1)
        if f.read(1) == b"\n":
            return
        start = size
        while start > 0:  # find the last line break, reading backwards in blocks
            block = min(start, _TAIL_BLOCK)
            f.seek(start - block)
            data = f.read(block)
            newline = data.rfind(b"\n")
            if newline >= 0:
                start = start - block + newline + 1
                break
            start -= block
        f.seek(start)
        tail = f.read()
        try:
            json.loads(tail)
        except (ValueError, RecursionError):  # torn: not a record (bad JSON or UTF-8, too deep)
            f.truncate(start)
        else:
            f.write(b"\n")
        f.flush()
        os.fsync(f.fileno())


def read_journal(path) -> list[dict]:
    """Every complete record of a journal; a torn last line (crash mid-write) is ignored.

    Raises
    ------
    ScanError
        A line other than the last is not JSON (the journal was edited or corrupted).
    """
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise ScanError(f"cannot read the journal ({exc.strerror})", source=str(path)) from None
    except UnicodeDecodeError as exc:
        raise ScanError(
            f"not UTF-8 text (byte {exc.start}); the journal was edited or corrupted and cannot "
            "be resumed",
            source=str(path),
        ) from None
    records = []
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            record = json.loads(line, parse_int=_parse_int)
        except (json.JSONDecodeError, RecursionError):
            if i == len(lines) - 1:
                break  # torn write at the crash
            record = None
        if not isinstance(record, dict):
            raise ScanError(
                "corrupt line (not a JSON object); the journal cannot be resumed",
                source=str(path),
                where=f"line {i + 1}",
            )
        records.append(record)
    return records
