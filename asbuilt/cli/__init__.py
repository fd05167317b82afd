"""The command-line interface: thin over the library, which never prints.

Each subcommand lives in its own module here and exposes ``register(subparsers)``; the module's
heavy imports (CadQuery above all) happen inside its handler, so ``asbuilt fit`` never pays for
the CAD kernel. Every :class:`~asbuilt.errors.AsbuiltError` becomes one line on stderr and its
exit code (2 for bad input; when no object of a scan could be fitted, one such line per refused
object); anything else is a bug and keeps its traceback.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
from importlib import import_module

from .. import __version__
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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
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


def _terminate(signum, frame):
    raise Terminated()


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; return the process exit code (0 ok, 1 error findings or objects whose fit was
    refused, 2 bad input, 130 interrupted, 143 terminated by SIGTERM)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    handler = getattr(args, "handler", None)
    if handler is None:
        parser.print_help()
        return 2
    previous = None
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        return int(handler(args) or 0)
    except AsbuiltError as exc:
        print(f"asbuilt: error: {exc}", file=sys.stderr)
        from ..fit import NothingFittedError

        if isinstance(exc, NothingFittedError):
            for failure in exc.failures[1:]:  # the first one is the line above
                print(f"asbuilt: error: {failure.error}", file=sys.stderr)
        return exc.exit_code
    except Terminated:
        print("asbuilt: terminated", file=sys.stderr)
        return 143
    except KeyboardInterrupt:
        print("asbuilt: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        return 0
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)
