"""A vessel's fit notes and refusals name it by its label's noun, not "pipe".

The cylinder fit's notes and refusals speak of a pipe ("3 shot(s) on the far side of the pipe",
"they are not one pipe"), the usual object; the fit itself never sees the label. A tank, drum or
round column labelled so (:meth:`asbuilt.labels.LabelWords.vessel_noun`, the reading the merge
uses to keep it out of spools) reads "the far side of the tank" instead. Only the object's own
cylinder and ``auto`` fits are renamed; a pipe's, or an unlabelled object's, keep "pipe".
"""

from __future__ import annotations

import dataclasses
import re

from asbuilt.errors import FitError
from asbuilt.fit.result import FitFailure, FitReport, ObjectFit
from asbuilt.labels import LabelWords
from asbuilt.scan.model import ScanObject

__all__ = ["named_failure", "named_report", "renamed"]

#: "pipe", "pipes", "pipe's", "Pipe", with the article before it (which a noun starting with a
#: vowel turns to "an").
_PIPE = re.compile(r"\b(?:(a|A) )?(p|P)ipe(s|'s)?\b")
_NAMED = ("cylinder", "auto")


def renamed(text: str, noun: str) -> str:
    """``text`` with every word "pipe" (its plural and possessive too) replaced by ``noun``."""

    def swap(match: re.Match) -> str:
        article, initial, tail = match.groups()
        word = (noun[0].upper() + noun[1:] if initial == "P" else noun) + (tail or "")
        if article is None:
            return word
        vowel = noun[0].lower() in "aeiou"
        return f"{article}{'n' if vowel else ''} {word}"

    return _PIPE.sub(swap, text)


def _noun(obj: ScanObject, words: LabelWords) -> str | None:
    return words.vessel_noun(obj.label, obj.group) if obj.kind in _NAMED else None


def _fit(item: ObjectFit, words: LabelWords) -> ObjectFit:
    noun = _noun(item.object, words)
    if noun is None or not item.result.notes:
        return item
    notes = tuple(renamed(note, noun) for note in item.result.notes)
    return dataclasses.replace(item, result=dataclasses.replace(item.result, notes=notes))


def named_failure(item: FitFailure, words: LabelWords) -> FitFailure:
    """``item`` with a vessel's refusal in its label's noun (itself for any other object)."""
    noun = _noun(item.object, words)
    if noun is None:
        return item
    error = item.error
    named = FitError(renamed(error.message, noun), source=error.source, where=error.where)
    return dataclasses.replace(item, error=named)


def named_report(report: FitReport, words: LabelWords) -> FitReport:
    """The report with each vessel's notes and refusal in its label's noun."""
    fits = tuple(_fit(item, words) for item in report.fits)
    failures = tuple(named_failure(item, words) for item in report.failures)
    return dataclasses.replace(report, fits=fits, failures=failures)
