"""Atomic output: write to a temporary file beside the target, then rename over it.

A failure never leaves a truncated file, and an existing file is replaced only by a complete
one. :class:`AtomicBatch` extends that to several outputs: all are written first, then all are
renamed, so a run that fails on its third output leaves none of the new files.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from .errors import ExportError

__all__ = ["atomic_write", "AtomicBatch", "default_file_mode"]


def default_file_mode() -> int:
    """The mode a plain ``open(path, "w")`` would give a new file (0o666 less the umask)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def _temp_beside(path: Path) -> tuple[int, str]:
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise ExportError("directory does not exist; create it or choose another --out",
                          source=str(path))
    try:
        fd, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=directory)
    except OSError as exc:
        raise ExportError(f"cannot write here ({exc.strerror}); choose a writable directory",
                          source=str(path)) from None
    # mkstemp makes owner-only files; the published file should look like any other output.
    os.chmod(temp, default_file_mode())
    return fd, temp


@contextlib.contextmanager
def atomic_write(path, mode: str = "wb", encoding: str | None = None) -> Iterator:
    """Open a temporary file for writing; on success rename it to ``path``.

    Parameters
    ----------
    path : str or Path
        The final file.
    mode : {"wb", "w"}
        Binary or text.
    encoding : str, optional
        Text encoding (default UTF-8 in text mode).
    """
    path = Path(path)
    fd, temp = _temp_beside(path)
    try:
        with os.fdopen(fd, mode, encoding=(encoding or "utf-8") if "b" not in mode else None) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(temp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temp)
        raise


class AtomicBatch:
    """Stage several outputs, then publish them all at once.

    >>> with AtomicBatch() as batch:               # doctest: +SKIP
    ...     batch.stage("a.step").write_bytes(data)  # writes a temporary file
    ...     # nothing is visible until the with-block ends without an error
    """

    def __init__(self) -> None:
        self._staged: list[tuple[Path, Path]] = []

    def stage(self, path) -> Path:
        """A temporary path beside ``path`` to write to; renamed to ``path`` on commit."""
        path = Path(path)
        fd, temp = _temp_beside(path)
        os.close(fd)
        self._staged.append((Path(temp), path))
        return Path(temp)

    def commit(self) -> list[Path]:
        """Rename every staged file to its target; return the targets."""
        done = []
        for temp, final in self._staged:
            os.replace(temp, final)
            done.append(final)
        self._staged.clear()
        return done

    def discard(self) -> None:
        """Delete every staged temporary file."""
        for temp, _ in self._staged:
            with contextlib.suppress(OSError):
                temp.unlink()
        self._staged.clear()

    def __enter__(self) -> AtomicBatch:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            self.commit()
        else:
            self.discard()
