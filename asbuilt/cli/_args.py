"""Argument types shared by the subcommands (argparse turns their errors into usage errors)."""

from __future__ import annotations

import argparse

__all__ = ["positive_number", "refuse_standard_output", "refuse_other_format"]


def positive_number(what: str, upper: float = 1e5):
    """An argparse ``type`` accepting a number in (0, ``upper``); ``what`` names it in errors,
    e.g. ``"thickness in mm"``."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
        if not 0 < value < upper:
            raise argparse.ArgumentTypeError(
                f"must be a positive {what} below {upper:g}, not {text}"
            )
        return value

    return parse


def refuse_standard_output(path, option: str, what: str, example: str) -> None:
    """Refuse ``-`` as the output ``path`` of a command that cannot write to standard output.

    ``-`` means standard output where a command can write there (``fit --output``, ``simulate
    --out``); elsewhere it made a file named ``-`` (``scan``, ``calibrate``) or was called a file
    without a suffix. ``what`` is what the command writes, ``example`` a file name to suggest.

    Raises
    ------
    ExportError
        ``path`` is ``-`` (one line naming ``option``).
    """
    from asbuilt.errors import ExportError

    if str(path) == "-":
        raise ExportError(
            f"standard output cannot take {what}; give a file name such as {example}",
            where=f"{option} -",
        )


#: Suffixes of the files other commands write (models, reports): a scan or calibration, which is
#: JSON, named so would be taken for one. The export and report registries' suffixes, JSON aside,
#: written out so that simulate and scan need not import them (a test keeps them equal).
OTHER_FORMATS = (
    ".step", ".stp", ".glb", ".gltf", ".dxf", ".stl", ".obj", ".pcf", ".ifc", ".html", ".htm",
    ".csv",
)  # fmt: skip


def refuse_other_format(path, option: str, what: str, example: str) -> None:
    """Refuse an output ``path`` whose suffix names a model or report format when the command
    writes ``what`` as JSON (``simulate --out site.step`` wrote a JSON scan named .step).

    Raises
    ------
    ExportError
        One line naming the file and ``option``, suggesting ``example``.
    """
    from pathlib import PurePath

    from asbuilt.errors import ExportError

    suffix = PurePath(str(path)).suffix.lower()
    if suffix in OTHER_FORMATS:
        raise ExportError(
            f"{option} writes {what} as JSON, not {suffix}; name it like {example} (the model "
            "and report formats are written by asbuilt model and asbuilt report)",
            source=str(path),
        )
