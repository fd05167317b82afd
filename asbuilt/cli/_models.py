"""Helpers the commands that build or read a model share (``model``, ``check``, ``report``).

Objects whose fit was refused: said on standard error, one located line each, and exit code 1
(the outputs are written but lack them). Options that only shape how a scan is built: refused
with one line when the input is an ``asbuilt-model`` document, which is already built.
"""

from __future__ import annotations

__all__ = ["refuse_build_options", "say_refused"]


def refuse_build_options(source: str, given: list[str]) -> None:
    """Raise a ModelDocumentError (exit 2) naming the build options ``given`` (flags such as
    ``"--no-merge"``) that a model document ``source`` cannot take; nothing when none is."""
    from asbuilt.export.model_json import ModelDocumentError

    if not given:
        return
    several = len(given) > 1
    raise ModelDocumentError(
        f"{', '.join(given)} {'apply' if several else 'applies'} only when building from a "
        "scan; this is an asbuilt-model document, already built: give the scan instead, or "
        f"leave {'them' if several else 'it'} out",
        source=source,
    )


def say_refused(console, model, source: str) -> int:
    """Print one line per object of ``model`` whose fit was refused (its ``fit-refused``
    findings) on ``console`` (standard error); return how many there were.

    Each line is ``asbuilt: SOURCE: ID: not fitted as ...: <the fit's reason>``.
    """
    from asbuilt.pipeline import refused_findings

    refused = refused_findings(model)
    for finding in refused:
        line = f"asbuilt: {source}: {','.join(finding.objects)}: {finding.message}"
        console.print(line, soft_wrap=True, highlight=False, markup=False)
    return len(refused)
