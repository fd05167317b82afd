"""The session journal: one JSON line per record, flushed and fsynced before the next shot.

``scan.json`` gets ``scan.json.journal`` beside it. Records (see docs/acquisition.md):
``session`` (settings, calibration), ``object`` (the target), ``shot`` (requested and reached
angles, raw range or error), ``done`` / ``failed`` and ``resume``. A torn last line (a crash in
the middle of a write) is ignored when reading; a bad line elsewhere is an error.

Opening a :class:`Journal` changes nothing: an existing journal is only touched by the first
:meth:`Journal.append`, which a session makes once it has accepted the journal (a refused
``--resume`` leaves it byte for byte). That first append ends the file at a line break: a
complete last record that only lacks its newline gets one; torn bytes are first copied, with a
newline, to ``<journal>.torn`` beside it (fsynced; they may be the only trace of a shot's
range) and then cut off, so the next record starts a line of its own.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from asbuilt._json_numbers import parse_int as _parse_int
from asbuilt.errors import ScanError

__all__ = ["Journal", "Replay", "read_journal", "journal_path_for", "torn_path_for"]

_TAIL_BLOCK = 65536  # bytes read at a time when looking for the journal's last line break


def journal_path_for(out) -> Path:
    """The journal beside an output scan: ``scan.json`` -> ``scan.json.journal``."""
    out = Path(out)
    return out.with_name(out.name + ".journal")


def torn_path_for(journal) -> Path:
    """Where the torn last lines cut off a journal are kept: ``<journal>.torn``, one a line."""
    journal = Path(journal)
    return journal.with_name(journal.name + ".torn")


class Journal:
    """Append-only JSON-lines file; every record is flushed and fsynced before returning.

    Opening it (creating an empty file if there is none) modifies nothing; the first
    :meth:`append` mends a torn last line (see the module docstring).
    """

    def __init__(self, path):
        self.path = Path(path)
        self._mended = False
        try:
            self._f = open(self.path, "a+b")  # kept open for the session; writes append
        except OSError as exc:
            raise ScanError(
                f"cannot write the journal ({exc.strerror}); choose a writable --out directory",
                source=str(self.path),
            ) from None

    def append(self, record: dict) -> None:
        """Write one record durably (the first one after ending the file at a line break)."""
        if not self._mended:
            try:
                _mend_tail(self._f, self.path)
            except OSError as exc:
                raise ScanError(
                    f"cannot write the journal ({exc.strerror}); nothing was appended",
                    source=str(self.path),
                ) from None
            self._mended = True
        line = json.dumps(record, separators=(",", ":")) + "\n"
        self._f.write(line.encode("utf-8"))
        self._f.flush()
        os.fsync(self._f.fileno())

    def close(self) -> None:
        """Close the file."""
        self._f.close()


def _mend_tail(f, path: Path) -> None:
    """End the journal open as ``f`` (``a+b``) at a line break before appending to it.

    A crash mid-write leaves a last line without its newline. If that line is a complete record
    (the crash came just before the newline), the newline is added; otherwise the torn bytes,
    which :func:`read_journal` ignores, are copied to :func:`torn_path_for` (appended, with a
    newline, and fsynced) and only then cut off. Either way the next record starts a line of
    its own instead of being glued onto the torn one. Raises OSError (nothing cut) when the
    copy cannot be written.
    """
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
        json.loads(tail, parse_int=_parse_int)  # as read_journal reads it
    except (ValueError, RecursionError):  # torn: not a record (bad JSON or UTF-8, too deep)
        with open(torn_path_for(path), "ab") as kept:
            kept.write(tail + b"\n")
            kept.flush()
            os.fsync(kept.fileno())
        f.truncate(start)
    else:
        f.write(b"\n")  # append mode: at the end
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


class Replay:
    """Serves recorded shots (:class:`asbuilt.drivers.session.Shot`) while the planner asks for
    the same directions, then goes live (``live(pan, tilt, phase)``; None: a mismatch is an
    error)."""

    def __init__(self, recorded: list, live):
        self.recorded = list(recorded)
        self.live = live
        self.i = 0
        self.diverged = False

    def __call__(self, pan: float, tilt: float, phase: str):
        if not self.diverged and self.i < len(self.recorded):
            rec = self.recorded[self.i]
            if abs(rec.pan_req - pan) < 1e-12 and abs(rec.tilt_req - tilt) < 1e-12:
                self.i += 1
                return rec
            self.diverged = True
        if self.live is None:
            raise ScanError(
                "the journal does not match the planner (edited journal or another "
                "version); rescan this object"
            )
        return self.live(pan, tilt, phase)
