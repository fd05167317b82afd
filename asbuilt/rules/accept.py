"""Accept chosen suggestions, like a spell checker's "accept this one".

``asbuilt check --fix OUT`` alone accepts every *unambiguous* suggestion. A finding with several
possible corrections (a pipe fitted at 126 mm lies between NPS 4 and NPS 5) has none that is
unambiguous: the user chooses. A choice names the finding by its key and the suggestion by its
number::

    AB101@P5:2        rule code @ the finding's objects : the suggestion's number (1 = first)
    nonstandard-diameter@P5:2    the rule's slug works too
    AB201@P9          the number may be left out when only one suggestion is a change

A finding's key is its rule code, ``@`` and its objects joined by commas, as ``asbuilt check``
prints them (``AB501@P1,P2``). Suggestions are numbered in their order (the order of the
finding's ``suggestions`` in JSON), advice included; only a change to the model's components
(a size, a rotation: :func:`asbuilt.rules.fixes.applicable`), or a scan link merging then
realises (:func:`asbuilt.rules.fixes.is_link`), can be accepted. The choices are checked against the findings before anything is applied, so a typo
never writes half of what was asked.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from asbuilt.errors import SuggestionError, quoted
from asbuilt.findings import Finding, Suggestion

from .fixes import acceptable_change, is_link

__all__ = [
    "Choice",
    "acceptable",
    "accept_choice",
    "finding_key",
    "parse_choice",
    "choose_suggestions",
]

_NUMBER = re.compile(r"^(?P<objects>.*):(?P<number>[0-9]+)$")


@dataclass(frozen=True)
class Choice:
    """One ``--accept`` choice: a rule (code or slug), the finding's objects, a number or None."""

    text: str
    rule: str
    objects: str
    number: int | None


def finding_key(finding: Finding) -> str:
    """The key a choice names ``finding`` by: ``CODE@OBJECTS`` (``AB101@P5``, ``AB501@P1,P2``)."""
    return f"{finding.code}@{','.join(finding.objects)}"


def acceptable(finding: Finding) -> list[int]:
    """Numbers (1-based) of ``finding``'s suggestions that are changes ``--fix`` can make (not
    advice, nor a change only a person can make, such as reading the scan in other units)."""
    return [i for i, s in enumerate(finding.suggestions, 1) if acceptable_change(s)]


def accept_choice(finding: Finding, number: int) -> str | None:
    """The choice that accepts suggestion ``number`` (1-based) of ``finding``, shell-quoted
    where needed (``AB101@P5:2``; ``AB201@P9`` when it is the only change), or None for advice."""
    import shlex

    changes = acceptable(finding)
    if number not in changes:
        return None
    return shlex.quote(finding_key(finding) + ("" if len(changes) == 1 else f":{number}"))


def parse_choice(text: str) -> Choice:
    """Read one choice, ``RULE@OBJECTS[:N]``; raise :class:`SuggestionError` if malformed."""
    rule, sep, rest = str(text).strip().partition("@")
    if not sep or not rule.strip() or not rest:
        raise SuggestionError(
            f"--accept {quoted(text)}: give a finding as RULE@OBJECTS[:N] as check prints it, "
            "e.g. AB101@P5:2 (rule code or slug, the finding's objects, the suggestion's number)"
        )
    match = _NUMBER.match(rest)
    if match is None:
        return Choice(str(text), rule.strip(), rest, None)
    number = int(match["number"])
    if number < 1:
        raise SuggestionError(f"--accept {quoted(text)}: suggestions are numbered from 1")
    return Choice(str(text), rule.strip(), match["objects"], number)


def _matches(choice: Choice, finding: Finding, objects: str) -> bool:
    rule = choice.rule
    named = rule.upper() == finding.code or rule.lower() == finding.slug
    return named and objects == ",".join(finding.objects)


def _find(choice: Choice, findings: Sequence[Finding]) -> tuple[Finding, int | None]:
    """The finding ``choice`` names and its number; an id that itself ends in ``:N`` is taken
    whole when a finding has it (``P:2``), else the tail is the suggestion's number."""
    whole = f"{choice.objects}:{choice.number}" if choice.number is not None else None
    for f in findings:
        if whole is not None and _matches(choice, f, whole):
            return f, None
    for f in findings:
        if _matches(choice, f, choice.objects):
            return f, choice.number
    keys = sorted({finding_key(f) for f in findings if acceptable(f)})
    listing = ", ".join(keys[:8]) + (f" and {len(keys) - 8} more" if len(keys) > 8 else "")
    raise SuggestionError(
        f"--accept {quoted(choice.text)}: no {choice.rule} finding on {choice.objects} in this "
        "check; "
        + (
            f"findings with a change to accept: {listing}"
            if keys
            else "no finding has a change to accept"
        )
    )


def _pick(choice: Choice, finding: Finding, number: int | None) -> Suggestion:
    key = finding_key(finding)
    changes = acceptable(finding)
    if number is None:
        if len(changes) == 1:
            return finding.suggestions[changes[0] - 1]
        if not changes:
            raise SuggestionError(
                f"--accept {quoted(choice.text)}: {key} suggests no change to accept, only "
                f"advice ({finding.suggestions[0].description if finding.suggestions else 'none'})"
            )
        options = " or ".join(f":{i} ({finding.suggestions[i - 1].description})" for i in changes)
        raise SuggestionError(
            f"--accept {quoted(choice.text)}: {key} has {len(changes)} suggestions to choose "
            f"from: add {options}"
        )
    if number > len(finding.suggestions):
        raise SuggestionError(
            f"--accept {quoted(choice.text)}: {key} has {len(finding.suggestions)} "
            f"suggestion{'s' if len(finding.suggestions) != 1 else ''}, not {number}"
        )
    suggestion = finding.suggestions[number - 1]
    if not acceptable_change(suggestion):
        hint = f"; accept {key}:{changes[0]}" if len(changes) == 1 else ""
        raise SuggestionError(
            f"--accept {quoted(choice.text)}: suggestion {number} of {key} is advice, not a "
            f"change to accept ({suggestion.description}){hint}"
        )
    return suggestion


def _targets(suggestion: Suggestion) -> list[str]:
    change = suggestion.change
    return [str(t) for t in (change.get("objects") or [change.get("object")]) if t is not None]


def choose_suggestions(
    findings: Iterable[Finding], choices: Iterable[str | Choice]
) -> list[tuple[Finding, Suggestion]]:
    """The suggestions ``choices`` name among ``findings``, in the order given.

    Parameters
    ----------
    findings : iterable of Finding
        The findings of one check.
    choices : iterable of str or Choice
        ``RULE@OBJECTS[:N]`` each (see the module docstring).

    Returns
    -------
    list of (Finding, Suggestion)
        For :func:`asbuilt.rules.fixes.apply_suggestions`.

    Raises
    ------
    SuggestionError
        A choice is malformed, names no finding of this check, a number it does not have or
        advice; leaves the number out where several changes are offered; or two choices change
        the same field of the same object (one would undo the other).
    """
    findings = list(findings)
    chosen: list[tuple[Finding, Suggestion]] = []
    claimed: dict[tuple[str, str], str] = {}
    for item in choices:
        choice = item if isinstance(item, Choice) else parse_choice(item)
        finding, number = _find(choice, findings)
        suggestion = _pick(choice, finding, number)
        if any(f is finding and s is suggestion for f, s in chosen):
            continue  # the same choice twice
        # a link names a pair (one pipe may be linked to two others); a change, each object
        targets = [",".join(sorted(_targets(suggestion)))] if is_link(suggestion) else None
        for target in targets or _targets(suggestion):
            slot = (target, str(suggestion.change.get("field")))
            if slot in claimed:
                raise SuggestionError(
                    f"--accept {quoted(choice.text)} and --accept {quoted(claimed[slot])} both "
                    f"change the {slot[1]} of {target}: accept one of them"
                )
            claimed[slot] = choice.text
        chosen.append((finding, suggestion))
    return chosen
