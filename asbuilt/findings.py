"""Compliance findings: data, not exceptions (in the spirit of ezdxf's audit and repo-review).

Rules (:mod:`asbuilt.rules`) return findings; the model document, the CLI, the exports and the
reports read them. Lengths are metres; ``measured``/``allowed``/``stderr`` carry their unit.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["SEVERITIES", "Suggestion", "Waived", "Finding", "FIT_REFUSED_CODE", "FIT_REFUSED_SLUG"]

#: Severities from the most to the least serious; ``unverifiable`` findings are warnings.
SEVERITIES = ("error", "warning", "info")

#: Code and slug of the error finding for a scan object whose fit was refused (it is not in the
#: model). ``AB0xx`` is the pipeline's own, outside the rule families ``AB1xx``-``AB6xx`` of
#: :mod:`asbuilt.rules.registry`: no rule checks a model for it, so ``--select``/``--ignore``
#: cannot drop it and a re-check of a model keeps it (:func:`asbuilt.pipeline.recheck`).
FIT_REFUSED_CODE = "AB001"
FIT_REFUSED_SLUG = "fit-refused"


@dataclass(frozen=True)
class Suggestion:
    """A correction the user may accept, like a spell checker's.

    ``description`` says what it would change in words; ``change`` says it as data, e.g.
    ``{"object": "P3", "field": "nominal", "value": "4"}``; ``unambiguous`` is True when
    ``asbuilt check --fix`` may apply it without asking.
    """

    description: str
    change: Mapping = field(default_factory=dict)
    unambiguous: bool = False


@dataclass(frozen=True)
class Waived:
    """Why a finding was waived: the rules file's ``reason`` and the ``severity`` the finding
    had before (``"error"``, ``"warning"`` or ``"info"``)."""

    reason: str
    severity: str

    def __post_init__(self):
        if self.severity not in SEVERITIES:
            raise ValueError(f"severity must be one of {SEVERITIES}, not {self.severity!r}")


@dataclass(frozen=True, eq=False)
class Finding:
    """One problem found in a model.

    Attributes
    ----------
    code, slug : str
        Stable rule code (e.g. ``"AB101"``) and slug (e.g. ``"nonstandard-diameter"``).
    severity : str
        One of :data:`SEVERITIES`.
    objects : tuple of str
        Component or scan object ids concerned.
    message : str
        One line for a person.
    location : ndarray, shape (3,), metres, or None
    measured, allowed, stderr : float or None
        The measured value, the allowed value and the measurement's standard error, in ``unit``.
    unit : str
        Unit of ``measured``/``allowed``/``stderr`` (``"m"``, ``"deg"``, ``"ratio"``, ``"%"``...).
    suggestions : tuple of Suggestion
    unverifiable : bool
        True when the uncertainty is too large to decide either way.
    waived : Waived or None
        Set when a rules file's ``[[waive]]`` accepted the finding: its reason and the severity
        it had (the finding itself is then ``info``, without suggestions).
    """

    code: str
    slug: str
    severity: str
    objects: tuple[str, ...]
    message: str
    location: np.ndarray | None = None
    measured: float | None = None
    allowed: float | None = None
    stderr: float | None = None
    unit: str = ""
    suggestions: tuple[Suggestion, ...] = ()
    unverifiable: bool = False
    waived: Waived | None = None

    def __post_init__(self):
        if self.severity not in SEVERITIES:
            raise ValueError(f"severity must be one of {SEVERITIES}, not {self.severity!r}")
        if self.location is not None:
            loc = np.array(self.location, dtype=np.float64)
            loc.setflags(write=False)
            object.__setattr__(self, "location", loc)
