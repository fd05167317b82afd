"""Argument types shared by the subcommands (argparse turns their errors into usage errors)."""

from __future__ import annotations

import argparse

__all__ = ["positive_number"]


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
