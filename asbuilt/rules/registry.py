"""The rule registry: every compliance rule's stable code, slug, severity, message and source.

A rule is data (:class:`Rule`); the functions that check it live in one module per family
(:mod:`.sizes`, :mod:`.alignment`, :mod:`.joints`, :mod:`.quality`, :mod:`.clash`,
:mod:`.design`) and are looked up by slug in :data:`CHECKS` there. Codes never change meaning:
``AB1xx`` sizes, ``AB2xx`` alignment, ``AB3xx`` joints, ``AB4xx`` scan quality, ``AB5xx`` clashes,
``AB6xx`` design comparison.
"""

from __future__ import annotations

from dataclasses import dataclass

from asbuilt.findings import SEVERITIES

__all__ = ["Rule", "RULES", "rule", "match_rules"]


@dataclass(frozen=True)
class Rule:
    """One compliance rule.

    Attributes
    ----------
    code, slug : str
        Stable identifiers (``"AB202"``, ``"out-of-plumb"``); either selects or ignores it.
    severity : str
        Default severity (one of :data:`asbuilt.findings.SEVERITIES`); the rules file may change it.
    message : str
        One-line template of the finding's message (``str.format`` fields named per rule).
    source : str
        The standard or reason the rule and its default tolerance come from.
    family : str
        The module checking it (``"sizes"``, ``"alignment"``, ...).
    """

    code: str
    slug: str
    severity: str
    message: str
    source: str
    family: str

    def __post_init__(self):
        if self.severity not in SEVERITIES:
            raise ValueError(f"rule {self.code}: severity must be one of {SEVERITIES}")


RULES: tuple[Rule, ...] = (
    Rule(
        "AB101",
        "nonstandard-diameter",
        "error",
        "OD {od} +- {s} is no {catalog} size (nearest {nearest} = {nearest_od}, {off} off; a size is "
        "taken within {window})",
        "The catalog's standard (e.g. ASME B36.10M): a pipe is made in catalog sizes only; the "
        "tolerance is Tolerances.diameter_tolerance (2 mm, under half the 5.4 mm smallest gap from NPS 1/2 up).",
        "sizes",
    ),
    Rule(
        "AB102",
        "ambiguous-size",
        "warning",
        "OD {od} +- {stderr} fits {count} sizes ({sizes}); the size cannot be decided",
        "Two catalog ODs both within the fit's uncertainty: choosing one would be a guess.",
        "sizes",
    ),
    Rule(
        "AB103",
        "hint-mismatch",
        "warning",
        "the hint {hint} ({hint_od}) disagrees with the fitted OD {od} by {off}",
        "The operator's size hint and the measurement must agree within the fit's uncertainty.",
        "sizes",
    ),
    Rule(
        "AB104",
        "contiguous-diameter-mismatch",
        "error",
        "{first} is {first_size} but the contiguous {second} is {second_size} with no reducer",
        "Contiguous pipes of one spool share a size unless a reducer joins them (ASME B16.9).",
        "sizes",
    ),
    Rule(
        "AB105",
        "nonstandard-tee",
        "warning",
        "the tee {tee} joins an {run} run to an {outlet} outlet, a reducing tee {fittings} does "
        "not make ({run} reduces on the outlet to {outlets} only)",
        "ASME B16.9 Table 8 makes reducing-outlet tees for listed run x outlet pairs only (NPS 6 "
        "reduces to 5 down to 2 1/2); a larger reduction is a branch outlet fitting (MSS SP-97) "
        "or a tee with a reducer on its outlet. A reducing cross is made of the same pairs.",
        "sizes",
    ),
    Rule(
        "AB201",
        "misaligned-axis",
        "warning",
        "axis is {angle} off {direction} (regularised within {snap}, intended beyond {intended})",
        "Orientation regularisation (GlobFit, Li et al. 2011): Tolerances.angle_snap_deg and "
        "Tolerances.intended_angle_deg bound an axis that is almost, but not quite, regular.",
        "alignment",
    ),
    Rule(
        "AB202",
        "out-of-plumb",
        "error",
        "leans {lean} over {height} (1:{ratio}), allowed {allowed} (1:{allowed_ratio}, {standard})",
        "AISC 303-16 7.13.1.1 (steel columns: 1/500 of the height); ACI 117-10 (concrete: 0.3% "
        "of the height, at most 25 mm); API 650 7.5.2 (storage tanks: the top of the shell "
        "within 1/200 of the height of its bottom).",
        "alignment",
    ),
    Rule(
        "AB203",
        "slope",
        "error",
        "slope {slope} is below the required drainage slope {required} ({source})",
        "IPC 2021 table 704.1 (drainage: 2% up to 2 1/2 in, 1% for 3-6 in, 0.5% from 8 in) or the "
        "project's piping spec, when the rules file sets one.",
        "alignment",
    ),
    Rule(
        "AB301",
        "joint-gap",
        "warning",
        "{kind} of {size} between the ends of {first} and {second}, which no catalog fitting explains",
        "Merged spools meet end to end or through an ASME B16.9 fitting; anything else is a "
        "missing part (valve, flange) or a scan that stopped short.",
        "joints",
    ),
    Rule(
        "AB302",
        "merge-note",
        "warning",
        "{note}",
        "Merging's own account of what it could not do as the scan asked or had to invent: a "
        "link no fitting can make, a bend no B16.9 elbow turns, a pipe extended beyond its last "
        "shot or cut back over measured pipe to fit a fitting.",
        "joints",
    ),
    Rule(
        "AB303",
        "fit-up",
        "warning",
        "the axes of {first} and {second} miss each other by {miss} (+- {stderr}) at their "
        "joint; merging shifted them to meet",
        "Joined pipes' axes meet at their fitting (ASME B16.9 fittings are symmetric about "
        "their axes); a miss beyond 3 standard errors of the fits (and 6 mm) is a real offset "
        "at the joint (fit-up) or a wrong joint, not noise for merging to absorb.",
        "joints",
    ),
    Rule(
        "AB304",
        "unjoined-end",
        "warning",
        "{pipe} ends {gap} from {target} but is not joined to it: {why}",
        "Merging joins each pipe end to one other, at most three pipes at a tee and four at a "
        "cross (two outlets of one size on one line); a pipe end that runs into a fitting or another pipe within "
        "joint_distance (plus its shot spacing) and is joined to nothing is a fitting the "
        "model lacks, a part the scan missed, or a pipe that stops short.",
        "joints",
    ),
    Rule(
        "AB401",
        "too-few-points",
        "warning",
        "{count} points for a {kind}; the paper's accuracy needs at least {needed}",
        "Kwon et al. (experimental results): 20-40 points for cylinders (1-5% error), at least 30 "
        "for the location, orientation and size of cuboids (1-2% error).",
        "quality",
    ),
    Rule(
        "AB402",
        "weak-geometry",
        "warning",
        "the fit is too weak to trust: {reasons}",
        "Kwon et al.: a cylinder's accuracy falls with its length/diameter ratio; a circle from "
        "an arc under 90 degrees and a box from one face are poorly determined.",
        "quality",
    ),
    Rule(
        "AB403",
        "poor-fit",
        "warning",
        "residual RMS {rms} is {ratio} times the sensor sigma {sigma}",
        "The residuals of a good fit match the range finder's noise; far larger ones mean the "
        "wrong kind or a bent or damaged object.",
        "quality",
    ),
    Rule(
        "AB404",
        "outliers",
        "warning",
        "{rejected} of {count} points ({share}) were rejected as outliers",
        "A robust fit that rejects a large share of points may have fitted the background.",
        "quality",
    ),
    Rule(
        "AB405",
        "ambiguous-kind",
        "warning",
        "auto chose {kind}, but {rivals} explains the shots as well; they cannot tell them apart",
        "Bayesian information criterion (Schwarz 1978) within 6 of the chosen kind with as many "
        "fitted parameters: not strong evidence (Kass & Raftery 1995).",
        "quality",
    ),
    Rule(
        "AB406",
        "another-object",
        "warning",
        "{shots} of {count} points, left out of the fit, fit another cylinder",
        "A raster window takes in what lies around the object: a tee's header, a rack "
        "neighbour. The fit keeps the cylinder with the most shots, which need not be the one "
        "aimed at.",
        "quality",
    ),
    Rule(
        "AB407",
        "viewpoint-ignored",
        "warning",
        "no cylinder that honours the station fits the shots; the one kept is in doubt",
        "A beam stops at the first surface it meets: a pipe that more than a third of the shots "
        "were measured through, seen from the station, was not where those shots were taken.",
        "quality",
    ),
    Rule(
        "AB501",
        "clash",
        "error",
        "{first} and {second} intersect: {volume} of overlap",
        "Solids may not occupy the same space except where they touch at a fitting.",
        "clash",
    ),
    Rule(
        "AB601",
        "design-deviation",
        "error",
        "{aspect} deviates from design {design}: {measured}, allowed {allowed}",
        "PFI ES-3 (spool length: +-3 mm up to NPS 10, +-5 mm NPS 12-24, +-6 mm NPS 26-36) and the "
        "rules file's position, direction and section tolerances.",
        "design",
    ),
    Rule(
        "AB602",
        "missing-component",
        "error",
        "designed {kind} {design} has no as-built counterpart within {radius}",
        "Every designed component should be built (or its scan is missing).",
        "design",
    ),
    Rule(
        "AB603",
        "extra-component",
        "warning",
        "as-built {kind} matches no designed component within {radius}",
        "A built component that is not in the design is a change to record.",
        "design",
    ),
)

_BY_KEY = {**{r.code.lower(): r for r in RULES}, **{r.slug: r for r in RULES}}


def rule(key: str) -> Rule:
    """The rule with this code or slug (case-insensitive); KeyError when there is none."""
    return _BY_KEY[str(key).strip().lower()]


def match_rules(selector: str) -> tuple[Rule, ...]:
    """Rules a selector names: ``"ALL"``, a code (``"AB202"``), a code prefix (``"AB2"``) or a slug.

    Returns an empty tuple when the selector names nothing.
    """
    key = str(selector).strip().lower()
    if key == "all":
        return RULES
    if key in _BY_KEY:
        return (_BY_KEY[key],)
    if key.startswith("ab") and key[2:].isdigit():
        return tuple(r for r in RULES if r.code.lower().startswith(key))
    return ()
