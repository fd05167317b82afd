"""Waivers: findings a person has reviewed and accepted as built, with the reason.

A spell checker's "ignore": a project's rules file lists the findings it accepts, each by the
key ``asbuilt check`` prints (rule code or slug, ``@``, the finding's objects) and a reason::

    [[waive]]
    finding = "AB202@C4"
    reason = "lean accepted by the structural engineer, RFI-0123"

A waived finding stays in the output as ``info``, its message starting ``waived (REASON):``,
and without suggestions (``--fix`` changes nothing it waives): the record shows what was
accepted and why, and the exit code no longer fails on it. A waiver that matches no finding of
a rule that ran, on objects of which at least one is in the model, is itself an info finding,
``AB002 unused-waiver``, so a list of waivers does not outlive the faults it excused (a rescan
that fixed the column, a pipe renamed); one naming no object of the model belongs to another
scan of the project and is passed over.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from dataclasses import dataclass

from asbuilt.errors import RulesConfigError, quoted
from asbuilt.findings import FIT_REFUSED_CODE, Finding, Waived

from .registry import match_rules

__all__ = ["Waiver", "UNUSED_WAIVER_CODE", "UNUSED_WAIVER_SLUG", "parse_waivers", "apply_waivers"]

#: The pipeline's own code for a waiver that matches no finding (AB0xx: not a registry rule).
UNUSED_WAIVER_CODE = "AB002"
UNUSED_WAIVER_SLUG = "unused-waiver"

_WAS = {"error": "an error", "warning": "a warning", "info": "info"}

#: Longest reason kept: a waiver's reason is a reference, not a report.
REASON_LIMIT = 500


@dataclass(frozen=True)
class Waiver:
    """One accepted finding: the rule's ``code`` and ``slug``, its ``objects`` and the reason."""

    code: str
    slug: str
    objects: tuple[str, ...]
    reason: str

    @property
    def key(self) -> str:
        """``CODE@OBJECTS`` as ``asbuilt check`` prints a finding."""
        return f"{self.code}@{','.join(self.objects)}"

    def matches(self, finding: Finding) -> bool:
        return finding.code == self.code and tuple(finding.objects) == self.objects


def _entry(item, index: int, source: str | None) -> Waiver:
    where = f"[[waive]] {index}"
    if not isinstance(item, dict):
        raise RulesConfigError(
            'must be a table with finding = "CODE@OBJECTS" and reason = "..."',
            source=source,
            where=where,
        )
    unknown = sorted(set(item) - {"finding", "reason"})
    if unknown:
        raise RulesConfigError(
            f"unknown option {unknown[0]!r}; [[waive]] takes finding and reason",
            source=source,
            where=f"{where}.{unknown[0]}",
        )
    for name in ("finding", "reason"):
        value = item.get(name)
        if not isinstance(value, str) or not value.strip():
            problem = "missing" if value is None else f"must be text, not {quoted(value)}"
            hint = (
                'give the finding as check prints it, e.g. "AB202@C4"'
                if name == "finding"
                else "say why the finding is accepted (who, which document)"
            )
            raise RulesConfigError(
                f"{problem}; {hint}",
                source=source,
                where=f"{where}.{name}",
            )
    reason = " ".join(item["reason"].split())
    if len(reason) > REASON_LIMIT:
        raise RulesConfigError(
            f"{len(reason):,} characters; keep a reason to {REASON_LIMIT} (a reference such as "
            "an RFI number, not the report)",
            source=source,
            where=f"{where}.reason",
        )
    rule, sep, objects = item["finding"].strip().partition("@")
    found = match_rules(rule.strip()) if sep and rule.strip() and objects else ()
    if rule.strip().upper() == FIT_REFUSED_CODE or rule.strip().lower() == "fit-refused":
        raise RulesConfigError(
            "a refused fit cannot be waived: the object is not in the model; rescan it",
            source=source,
            where=f"{where}.finding",
        )
    exact = [r for r in found if rule.strip().upper() == r.code or rule.strip().lower() == r.slug]
    if len(exact) != 1:
        raise RulesConfigError(
            f"{quoted(item['finding'])} is no finding key; give it as check prints it, "
            'RULE@OBJECTS with a rule code or slug, e.g. "AB202@C4" or "clash@P1,P2"',
            source=source,
            where=f"{where}.finding",
        )
    return Waiver(exact[0].code, exact[0].slug, tuple(objects.split(",")), reason)


def parse_waivers(value, source: str | None) -> tuple[Waiver, ...]:
    """The ``[[waive]]`` entries of a rules file (``value``: its list of tables).

    Raises
    ------
    RulesConfigError
        Not a list of tables, an unknown key, an empty or missing finding or reason, a key that
        names no rule, a refused fit (AB001), or one finding waived twice.
    """
    if not isinstance(value, list):
        raise RulesConfigError(
            'write each waiver as a [[waive]] table with finding = "CODE@OBJECTS" and '
            'reason = "..."',
            source=source,
            where="waive",
        )
    waivers: list[Waiver] = []
    for index, item in enumerate(value, 1):
        waiver = _entry(item, index, source)
        if any(w.code == waiver.code and w.objects == waiver.objects for w in waivers):
            raise RulesConfigError(
                f"{waiver.key} is waived twice; keep one entry with its reason",
                source=source,
                where=f"[[waive]] {index}.finding",
            )
        waivers.append(waiver)
    return tuple(waivers)


def apply_waivers(
    findings: Iterable[Finding],
    waivers: Iterable[Waiver],
    ran: Iterable[str],
    ids: Iterable[str],
) -> list[Finding]:
    """``findings`` with the waived ones turned into info, plus one AB002 per unused waiver.

    Parameters
    ----------
    findings : iterable of Finding
    waivers : iterable of Waiver
    ran : iterable of str
        Slugs of the rules that ran: a waiver of a rule that did not run is not unused.
    ids : iterable of str
        The checked model's component ids: a waiver naming none of them is another scan's (one
        project rules file serves every scan of a site), not unused.

    Returns
    -------
    list of Finding
        Unsorted.
    """
    waivers = tuple(waivers)
    used: set[Waiver] = set()
    out: list[Finding] = []
    for finding in findings:
        waiver = next((w for w in waivers if w.matches(finding)), None)
        if waiver is None:
            out.append(finding)
            continue
        used.add(waiver)
        out.append(
            dataclasses.replace(
                finding,
                severity="info",
                message=f"waived ({waiver.reason}); as {_WAS[finding.severity]}: {finding.message}",
                suggestions=(),
                unverifiable=False,
                waived=Waived(waiver.reason, finding.severity),
            )
        )
    ran, ids = set(ran), set(ids)
    for waiver in waivers:
        if waiver in used or waiver.slug not in ran or ids.isdisjoint(waiver.objects):
            continue
        out.append(
            Finding(
                code=UNUSED_WAIVER_CODE,
                slug=UNUSED_WAIVER_SLUG,
                severity="info",
                objects=waiver.objects,
                message=f"the waiver of {waiver.key} ({waiver.reason}) matches no finding of this "
                "check: the fault it accepted is gone or its ids changed; remove it from the "
                "rules file",
            )
        )
    return out
