"""The progress display shared by the subcommands (rich, on stderr, only on a terminal)."""

from __future__ import annotations

__all__ = ["stage_progress"]


def stage_progress(console, *, quiet: bool = False):
    """A transient rich progress bar: stage name, bar, done/total and the current object.

    Tasks take a ``stage`` field (e.g. ``bar.add_task("", total=n, stage="fitting")``). The
    bar is disabled when ``quiet`` or when ``console`` is not a terminal, so pipes and CI logs
    stay clean.
    """
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn

    return Progress(
        TextColumn("{task.fields[stage]:<8}", markup=False),
        BarColumn(),
        MofNCompleteColumn(),
        # The description is an object id: shown as written ("P[1]" is not rich markup).
        TextColumn("{task.description}", markup=False),
        console=console,
        transient=True,
        disable=quiet or not console.is_terminal,
    )
