"""The command-line interface: thin over the library, which never prints.

Each subcommand lives in its own module here and exposes ``register(subparsers)``; the module's
heavy imports (CadQuery above all) happen inside its handler, so ``asbuilt fit`` never pays for
the CAD kernel. Every :class:`~asbuilt.errors.AsbuiltError` becomes one line on stderr and its
exit code (2 for bad input; when no object of a scan could be fitted, one such line per refused
object); anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import errno
import io
import signal
import sys
import threading
import warnings
from importlib import import_module

from .. import __version__
from ..atomic import TERMINATING
from ..errors import AsbuiltError

__all__ = ["main", "build_parser"]

#: Subcommand modules in the order ``--help`` lists them.
SUBCOMMANDS = (
    "model",
    "fit",
    "check",
    "report",
    "catalog",
    "scan",
    "simulate",
    "simulate_device",
    "calibrate",
)


class _OneLineParser(argparse.ArgumentParser):
    """argparse with its usage errors on one line (bad input gets one line and exit code 2, as
    every other bad input does), pointing at ``--help`` instead of repeating the usage."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _OneLineParser(
        prog="asbuilt",
        description="Turn sparse laser range points of construction objects into as-built CAD.",
        epilog="Example: asbuilt model samples/spool.json --out spool.step",
    )
    parser.add_argument("--version", action="version", version=f"asbuilt {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMANDS:
        try:
            module = import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{name}":
                continue  # that subcommand is not part of this build
            raise
        module.register(subparsers)
    return parser


class Terminated(KeyboardInterrupt):
    """SIGTERM (``kill``, a service manager, a CI timeout): handled like Ctrl-C, so that every
    ``finally`` runs: staged outputs are removed, journals are closed, devices released."""


#: Set by the SIGTERM and SIGINT handlers (and cleared when :func:`main` returns): whatever
#: exception the run ends with after it, the command reports "terminated" (exit 143) or
#: "interrupted" (exit 130). The handler's own exception does not always arrive: a signal that
#: lands while an extension module initialises surfaces as that module's ImportError, and
#: ifcopenshell's bare ``except`` swallows it and fails later with an error of its own. Staged
#: outputs are not published while it is set (:data:`asbuilt.atomic.TERMINATING`).
_termination = TERMINATING

#: ``errno`` values of a standard output that cannot take the result: a full disk, a quota, a
#: failed device.
_OUTPUT_FULL = {errno.ENOSPC, errno.EDQUOT, errno.EIO, errno.EFBIG}


#: The signal that stopped the run (SIGINT or SIGTERM), once one has; what the command then says
#: and exits with (:func:`_stopped`).
_STOPS = {signal.SIGINT: ("interrupted", 130), signal.SIGTERM: ("terminated", 143)}
_stopped_by: list[int] = []


def _terminate(signum, frame):
    _stopped_by.append(signum)
    _termination.set()
    raise Terminated()


def _interrupt(signum, frame):
    """Ctrl-C: as Python's own handler (KeyboardInterrupt), and noted as SIGTERM is. A
    KeyboardInterrupt raised while an extension module initialises surfaces as an ImportError
    (OCP's "initialization failed", with a traceback and exit 1); noted, it is reported as the
    interruption it is, and no staged output is published after it."""
    _stopped_by.append(signum)
    _termination.set()
    raise KeyboardInterrupt()


def _stopped() -> int:
    """Say how the run was stopped (Ctrl-C unless a SIGTERM was noted); return its exit code."""
    word, code = _STOPS[_stopped_by[0] if _stopped_by else signal.SIGINT]
    print(f"asbuilt: {word}", file=sys.stderr)
    return code


def _install_stop_handlers() -> dict:
    """Install the SIGTERM and SIGINT handlers (main thread only); return the ones replaced.

    SIGINT's is replaced only when it is Python's own: a SIGINT the caller ignores (a
    background job of a script) stays ignored.
    """
    if threading.current_thread() is not threading.main_thread():
        return {}
    previous = {signal.SIGTERM: signal.signal(signal.SIGTERM, _terminate)}
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, _interrupt)
    return previous


def _drop_stdout() -> None:
    """Point stdout at /dev/null, so that the interpreter's last flush of the bytes the full
    device refused does not print its own error after ours."""
    import os

    try:
        sys.stdout = open(os.devnull, "w")  # kept open until exit
    except OSError:
        pass


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the process exit code (0 ok, 1 error findings or objects whose fit was
    refused, 2 bad input, 130 interrupted, 143 terminated by SIGTERM)."""
    _termination.clear()
    _stopped_by.clear()
    previous = _install_stop_handlers()  # first: Ctrl-C while the subcommands import too
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        handler = getattr(args, "handler", None)
        if handler is None:
            parser.print_help()
            return 2
        _tolerant_stdout()
        return _run(handler, args)
    except KeyboardInterrupt:  # before the handler ran (importing the subcommands)
        return _stopped()
    except Exception:
        if _termination.is_set():  # whatever the run failed with once it was told to stop
            return _stopped()
        raise
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        _termination.clear()
        _stopped_by.clear()


def _tolerant_stdout() -> None:
    """Let standard output take any text, as standard error does: an id the output's encoding
    cannot write (a Chinese id to a Latin-1 terminal, a cp1252 redirect on Windows) is written
    as a backslash escape instead of stopping the command with a traceback halfway through its
    output (exit code 1, which ``check`` uses for error findings)."""
    stream = sys.stdout
    if isinstance(stream, io.TextIOWrapper) and stream.errors == "strict":
        try:
            stream.reconfigure(errors="backslashreplace")
        except (AttributeError, ValueError, io.UnsupportedOperation):
            pass


def _run(handler, args) -> int:
    """Run a subcommand's handler; map its errors and interruptions to messages and codes."""
    try:
        # Numerical warnings are the library's to handle (its fits drop overflowing starts):
        # on the command line they would only print noise around one clean result or error.
        # numpy is imported here, not with the module: --help and --version do without it.
        import numpy as np

        with np.errstate(all="ignore"), warnings.catch_warnings():
            if not sys.warnoptions:
                # Nor the warnings of the libraries below (matplotlib's "constrained_layout not
                # applied" for a report's figure with a long id): two lines of source location
                # each, around a clean result. -W or PYTHONWARNINGS shows them again.
                warnings.simplefilter("ignore")
            code = int(handler(args) or 0)
        sys.stdout.flush()  # a full disk under stdout is reported here, not at exit
        return code
    except AsbuiltError as exc:
        if _termination.is_set():  # e.g. the commit refused after a swallowed SIGTERM
            raise
        print(f"asbuilt: error: {exc}", file=sys.stderr)
        from ..fit import NothingFittedError

        if isinstance(exc, NothingFittedError):
            for failure in exc.failures[1:]:  # the first one is the line above
                print(f"asbuilt: error: {failure.error}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:  # Terminated included
        return _stopped()
    except BrokenPipeError:
        return 0
    except OSError as exc:
        if exc.filename is None and exc.errno in _OUTPUT_FULL and not _termination.is_set():
            _drop_stdout()
            print(f"asbuilt: error: cannot write the output ({exc.strerror})", file=sys.stderr)
            return 2
        raise
