"""The session journal: one JSON line per record, flushed and fsynced before the next shot.

``scan.json`` gets ``scan.json.journal`` beside it. Records (see docs/acquisition.md):
``session`` (settings, calibration), ``object`` (the target), ``shot`` (requested and reached
angles, raw range or error), ``done`` / ``failed`` and ``resume``. A torn last line (a crash in
the middle of a write) is ignored when reading; a bad line elsewhere is an error.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from asbuilt.errors import ScanError

__all__ = ["Journal", "read_journal", "journal_path_for"]


def journal_path_for(out) -> Path:
    """The journal beside an output scan: ``scan.json`` -> ``scan.json.journal``."""
    out = Path(out)
    return out.with_name(out.name + ".journal")


class Journal:
    """Append-only JSON-lines file; every record is flushed and fsynced before returning."""

    def __init__(self, path):
        self.path = Path(path)
        try:
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
    records = []
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            if i == len(lines) - 1:
                break  # torn write at the crash
            raise ScanError(
                "corrupt line; the journal cannot be resumed",
                source=str(path),
                where=f"line {i + 1}",
            ) from None
    return records
