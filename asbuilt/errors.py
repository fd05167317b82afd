"""The exceptions a user can hit, one root and one subclass per kind of failure.

Each class is also a built-in exception (``ValueError``, ``OSError``...) so callers that do not
know asbuilt can still catch it sensibly. The CLI maps every :class:`AsbuiltError` to one line on
stderr and its ``exit_code``; anything else is a bug and keeps its traceback.

Compliance findings are *not* exceptions: they are data (:mod:`asbuilt.findings`).
"""

from __future__ import annotations

__all__ = [
    "AsbuiltError",
    "ScanError",
    "ScanReadError",
    "FitError",
    "CatalogError",
    "RulesConfigError",
    "DesignError",
    "ExportError",
    "UnknownFormatError",
    "SolidBuildError",
    "DeviceError",
    "DeviceTimeout",
    "DeviceProtocolError",
    "CalibrationError",
    "SceneError",
    "SuggestionError",
]


class AsbuiltError(Exception):
    """Root of every error asbuilt raises on purpose. ``str(err)`` is one line for the user."""

    exit_code = 2


def located(source: str | None, where: str | None, message: str) -> str:
    """Format ``source: where: message`` leaving out the parts that are unknown.

    >>> located("scan.json", "objects[3] (P4).points[17]", "coordinate is NaN")
    'scan.json: objects[3] (P4).points[17]: coordinate is NaN'
    """
    return ": ".join(part for part in (source, where, message) if part)


#: The most characters of a user's value an error message quotes (:func:`quoted`).
QUOTE_LIMIT = 40


def quoted(value, limit: int = QUOTE_LIMIT) -> str:
    """``repr(value)`` for a message, its first ``limit`` characters and length when longer.

    A message quotes the offending cell or name so the user can find it; a 5,000-digit cell
    must not make a 5,000-character line.

    >>> quoted("4x")
    "'4x'"
    >>> quoted("9" * 5000, limit=8)
    "'99999999...' (5,000 characters)"
    """
    text = str(value)
    if len(text) <= limit:
        return repr(text)
    head = repr(text[:limit])
    return f"{head[:-1]}...{head[-1]} ({len(text):,} characters)"


class _LocatedError(AsbuiltError):
    """An error that knows the file (``source``) and the place in it (``where``)."""

    def __init__(self, message: str, *, source: str | None = None, where: str | None = None):
        self.message = message
        self.source = source
        self.where = where
        super().__init__(located(source, where, message))


class ScanError(_LocatedError, ValueError):
    """The scan file is not a valid ``asbuilt-scan`` document (bad JSON, field, point...)."""


class ScanReadError(AsbuiltError, OSError):
    """The scan file cannot be read at all (missing, unreadable, too large)."""


class FitError(_LocatedError, ValueError):
    """The points cannot define the requested primitive (too few, collinear, coplanar...)."""


class CatalogError(_LocatedError, ValueError):
    """A catalog file is malformed or a catalog name is unknown."""


class RulesConfigError(_LocatedError, ValueError):
    """The compliance rules file is malformed (unknown rule, wrong type...)."""


class DesignError(_LocatedError, ValueError):
    """The design file given for comparison is malformed."""


class SceneError(_LocatedError, ValueError):
    """A scene description (for the simulator) is malformed."""


class SuggestionError(AsbuiltError, ValueError):
    """A suggestion chosen to accept (``check --accept``) is not in the check's findings, is
    advice rather than a change, or is not told apart from the others offered."""


class ExportError(_LocatedError, ValueError):
    """An output cannot be written (unwritable directory, failed writer...)."""


class UnknownFormatError(ExportError):
    """No exporter is registered for the output's suffix."""


class SolidBuildError(ExportError):
    """The CAD kernel could not build a valid solid for an object."""


class DeviceError(AsbuiltError, OSError):
    """A serial device failed, replied with an error or could not be opened."""


class DeviceTimeout(DeviceError, TimeoutError):
    """A device stayed silent past its timeout (lost cable, wrong port, powered off)."""


class DeviceProtocolError(DeviceError):
    """A device replied with something its protocol does not allow (garbage, wrong echo)."""


class CalibrationError(_LocatedError, ValueError):
    """A calibration file is malformed or a calibration could not be estimated."""
