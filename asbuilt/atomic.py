"""Atomic output: write to a temporary file beside the target, then rename over it.

A failure never leaves a truncated file, and an existing file is replaced only by a complete
one. :class:`AtomicBatch` extends that to several outputs: every target is checked and every
file written first, then all are renamed, so a run that fails on its third output leaves none
of the new files.

A target that is a symbolic link is written through: the file it points to is replaced and the
link kept. A target that exists but is not a regular file (a named pipe, ``/dev/stdout``, a
terminal) cannot be renamed over; it gets the complete content, written into it once every
output is ready. A target that is a directory is an :class:`~asbuilt.errors.ExportError`.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import stat
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

from .errors import ExportError

__all__ = ["atomic_write", "AtomicBatch", "check_target", "default_file_mode", "TERMINATING"]

#: Set by the command line's SIGTERM handler until the command returns: a batch committed while
#: it is set publishes nothing. The handler's exception can be swallowed on the way up (by
#: ifcopenshell's bare ``except``), and the run would otherwise go on to publish its outputs.
TERMINATING = threading.Event()


def default_file_mode() -> int:
    """The mode a plain ``open(path, "w")`` would give a new file (0o666 less the umask)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


#: The file name a directory-target message suggests adding when the caller names none: the
#: model is the output most commands write.
DEFAULT_EXAMPLE = "model.step"


def _target(path, example: str = DEFAULT_EXAMPLE) -> tuple[Path, bool]:
    """The file to publish to for an output ``path``, and whether it is a special file.

    Symbolic links are followed (the file they point to is the output). Raises ExportError for
    a directory, before anything is written; its message suggests adding ``/`` and ``example``.
    """
    given = Path(path)
    text = os.fspath(path)
    if not text:
        raise ExportError("the output file name is empty; give a file name", source="''")
    try:
        info = os.stat(given)  # through any links
    except OSError:
        info = None  # a new file (or one the rename will report on)
    if info is not None and stat.S_ISDIR(info.st_mode):
        raise ExportError(
            f"is a directory; give a file name to write (e.g. add /{example})", source=text
        )
    if text.endswith(("/", os.sep)):
        raise ExportError(
            "ends with a slash, so it names a directory; give a file name", source=text
        )
    if info is not None and not stat.S_ISREG(info.st_mode):
        # A pipe or device, possibly behind links (/dev/stdout -> /proc/self/fd/1 -> pipe:[..],
        # which has no path of its own): opened as given.
        return given, True
    if info is not None and not os.access(given, os.W_OK):
        # A rename would replace it all the same (the directory's permission decides): a file
        # made read-only to keep it is kept, as a plain open() would.
        raise ExportError(
            "is read-only; make it writable (chmod u+w) or choose another output", source=text
        )
    # A link to a file (or a dangling one) is written through: its target is replaced.
    return (Path(os.path.realpath(given)) if given.is_symlink() else given), False


def check_target(path, option: str = "--out", inputs=(), example: str = DEFAULT_EXAMPLE) -> Path:
    """Check, before any work, that an output can be written to ``path``; return the file it
    will be published to (symbolic links followed).

    Parameters
    ----------
    path : str or Path
    option : str
        The command-line option that named the output, for the message.
    inputs : iterable of str or Path
        The command's input files: an output that is one of them would replace it (a scan's
        measured points lost under the model written from them).
    example : str
        A file name of the kind the option writes (``fit.json``, ``report.html``), suggested
        when ``path`` is a directory.

    Raises
    ------
    ExportError
        An empty name, a directory, a directory that does not exist, or one of ``inputs``.
    """
    final, special = _target(path, example)
    directory = final.parent if str(final.parent) else Path(".")
    if not special and not directory.is_dir():
        raise ExportError(
            f"directory does not exist; create it or choose another {option}", source=str(path)
        )
    for source in inputs:
        if _same_file(final, Path(source)):
            raise ExportError(
                f"is the input file itself, which the output would replace; choose another "
                f"{option}",
                source=str(path),
            )
    return final


def _same_file(a: Path, b: Path) -> bool:
    """Whether two paths name one existing file (hard and symbolic links included)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _temp_beside(path: Path) -> tuple[int, str]:
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise ExportError(
            "directory does not exist; create it or choose another --out", source=str(path)
        )
    try:
        fd, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=directory)
    except OSError as exc:
        raise ExportError(
            f"cannot write here ({exc.strerror}); choose a writable directory", source=str(path)
        ) from None
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
    path, special = _target(path)
    text_encoding = (encoding or "utf-8") if "b" not in mode else None
    if special:
        # A pipe or device: nothing to rename over, and nothing half-written left on disk.
        try:
            handle = open(path, mode, encoding=text_encoding)  # noqa: SIM115 - closed below
        except OSError as exc:
            raise ExportError(f"cannot write here ({exc.strerror})", source=str(path)) from None
        with handle as f:
            yield f
        return
    fd, temp = _temp_beside(path)
    try:
        with os.fdopen(fd, mode, encoding=text_encoding) as f:
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
        self._staged: list[tuple[Path, Path, bool]] = []

    def stage(self, path) -> Path:
        """A temporary path to write ``path``'s content to: beside it, renamed to it on commit
        (for a pipe or device, in the temporary directory, copied into it on commit).

        Raises
        ------
        ExportError
            ``path`` is a directory, or its directory is missing or not writable.
        """
        final, special = _target(path)
        if special:
            fd, temp = tempfile.mkstemp(prefix="asbuilt-", suffix=f"-{final.name}.part")
        else:
            fd, temp = _temp_beside(final)
        os.close(fd)
        self._staged.append((Path(temp), final, special))
        return Path(temp)

    def staged_for(self, path) -> Path | None:
        """The temporary file staged for the output ``path`` (links followed), or None."""
        final, _ = _target(path)
        for temp, target, _ in self._staged:
            if target == final:
                return temp
        return None

    def commit(self) -> list[Path]:
        """Publish every staged file to its target; return the targets.

        Pipes and devices get their content first, then the files are renamed into place, so
        a pipe or device that fails (``/dev/full``) leaves every file unpublished.

        Raises
        ------
        ExportError
            A rename or copy failed (the files not yet published are discarded).
        """
        done = []
        # Pipes and devices first: writing into one can fail (a full device, a closed pipe)
        # and cannot be taken back, while the renames that follow hardly fail; so a failure
        # leaves no regular file published. (Stable sort: each kind keeps its order.)
        self._staged.sort(key=lambda staged: not staged[2])
        try:
            if TERMINATING.is_set():
                raise ExportError("the run is being terminated; no output was written")
            while self._staged:
                temp, final, special = self._staged[0]
                try:
                    if special:
                        with open(temp, "rb") as source, open(final, "wb") as sink:
                            shutil.copyfileobj(source, sink)
                        temp.unlink()
                    else:
                        os.replace(temp, final)
                except OSError as exc:
                    raise ExportError(
                        f"cannot write the file ({exc.strerror or exc})", source=str(final)
                    ) from None
                self._staged.pop(0)
                done.append(final)
        finally:
            self.discard()
        return done

    def discard(self) -> None:
        """Delete every staged temporary file."""
        for temp, _, _ in self._staged:
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
