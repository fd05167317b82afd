"""The meaningful range of every numeric value of the rules file, checked when it is loaded.

A value outside its range is a :class:`~asbuilt.errors.RulesConfigError` naming the file, the
table and key, the value and the range, instead of a ``ZeroDivisionError`` deep in a rule (a
``pipe_ratio = 0``) or a silently meaningless check (``steel_ratio = 0.002`` meant as 1/500,
which would allow a lean of 500 times the height). ``nan`` and ``inf``, which TOML allows, are
never accepted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Range", "RANGES", "describe", "check_range", "check_rows"]


@dataclass(frozen=True)
class Range:
    """An interval of accepted values; ``None`` bounds are unbounded (finite values only).

    Attributes
    ----------
    low, high : float or None
        The bounds, in the option's unit.
    low_open, high_open : bool
        Whether the bound itself is excluded.
    meaning : str
        What the value is, for the error message (e.g. ``"1 in N of the height, e.g. 500"``).
    """

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    meaning: str = ""

    def contains(self, value: float) -> bool:
        """Whether ``value`` (finite) lies in the range."""
        if not math.isfinite(value):
            return False
        if self.low is not None and (value <= self.low if self.low_open else value < self.low):
            return False
        if self.high is not None and (value >= self.high if self.high_open else value > self.high):
            return False
        return True

    def text(self) -> str:
        """The range in words (``"greater than 0"``, ``"from 0 to 1"``...)."""
        low = None if self.low is None else f"{self.low:g}"
        high = None if self.high is None else f"{self.high:g}"
        if low is not None and high is not None:
            if not self.low_open and not self.high_open:
                return f"from {low} to {high}"
            left = "greater than" if self.low_open else "at least"
            right = "less than" if self.high_open else "at most"
            return f"{left} {low} and {right} {high}"
        if low is not None:
            return f"greater than {low}" if self.low_open else f"at least {low}"
        if high is not None:
            return f"less than {high}" if self.high_open else f"at most {high}"
        return "finite"


def _positive(meaning: str) -> Range:
    return Range(0.0, low_open=True, meaning=meaning)


def _non_negative(meaning: str) -> Range:
    return Range(0.0, meaning=meaning)


def _count(meaning: str, low: int = 1, high: int | None = None) -> Range:
    return Range(low, high, meaning=meaning)


# A "1 in N" ratio below 1 allows a lean longer than the member, so it is a mistake (most likely
# the fraction 1/N written instead of N): ratios start at 1.
_RATIO = Range(1.0, meaning="1 in N of the height, e.g. 500")
# Misalignment angles: an axis is judged against vertical *or* horizontal; beyond 45 degrees it
# would be near both, so the regular-direction bands must stay below 45.
_AXIS_BAND = Range(
    0.0, 45.0, low_open=True, high_open=True, meaning="degrees off vertical or horizontal"
)

#: (table, key) -> accepted range; table "general" for ``[general]`` (Tolerances fields included)
#: and the rule slug otherwise. Every int or float value of the shipped schema has an entry
#: (tested), so a new option cannot be added without saying what values make sense.
RANGES: dict[tuple[str, str], Range] = {
    # [general]: 0 means "any excess over the limit is an error", which is meaningful.
    ("general", "k_sigma"): _non_negative("standard errors a violation must exceed its limit by"),
    # Tolerances fields (asbuilt.tolerances explains each default).
    ("general", "outlier_cutoff_sigma"): _positive(
        "robust sigmas beyond which a shot is an outlier"
    ),
    # The robust estimators break down at 50% contamination (Tolerances.max_outlier_fraction).
    ("general", "max_outlier_fraction"): Range(
        0.0, 0.5, high_open=True, meaning="share of a fit's points that may be rejected"
    ),
    # A zero floor lets a noise-free fit divide by a zero scale.
    ("general", "sigma_floor"): _positive("smallest noise level, metres"),
    # A noise level needs at least one residual degree of freedom to be estimated at all.
    ("general", "min_noise_dof"): _count("residual degrees of freedom for a noise estimate"),
    ("general", "prior_range_sigma"): _positive("assumed range noise, metres"),
    # A local plane needs the point and two neighbours (the paper's three-point sets).
    ("general", "normal_neighbours"): _count("neighbours per local normal", low=2),
    # Adjacent cuboid faces are 90 degrees apart: a threshold of 90 or more merges them.
    ("general", "face_angle_deg"): Range(
        0.0, 90.0, low_open=True, high_open=True, meaning="degrees between normals of one face"
    ),
    ("general", "recommended_points_cylinder"): _count("points wanted on a cylinder"),
    ("general", "recommended_points_cuboid"): _count("points wanted on a cuboid"),
    ("general", "angle_snap_deg"): Range(0.0, 45.0, high_open=True, meaning="degrees regularised"),
    ("general", "angle_snap_max_deg"): Range(
        0.0, 45.0, high_open=True, meaning="degrees regularised on a poorly measured axis"
    ),
    ("general", "intended_angle_deg"): _AXIS_BAND,
    ("general", "diameter_tolerance"): _non_negative("metres"),
    ("general", "joint_distance"): _non_negative("metres"),
    # A plate of no thickness is no closed solid.
    ("general", "plate_thickness"): _positive("metres"),
    # Rule options.
    ("nonstandard-diameter", "suggest"): _count("catalog sizes suggested"),
    ("out-of-plumb", "steel_ratio"): _RATIO,
    ("out-of-plumb", "pipe_ratio"): _RATIO,
    ("out-of-plumb", "tank_ratio"): _RATIO,
    # A fraction of the height: 0 would allow no lean at all, above 1 more than the height.
    ("out-of-plumb", "concrete_fraction"): Range(
        0.0, 1.0, low_open=True, meaning="fraction of the height, e.g. 0.003"
    ),
    ("out-of-plumb", "concrete_max"): _positive("metres, e.g. 0.025"),
    # A slope is a fraction (0.01 = 1%); 1 (45 degrees) or more is a percentage written by mistake.
    ("slope", "required"): Range(
        0.0, 1.0, high_open=True, meaning="fraction, 0.01 = 1%; 0 = none set"
    ),
    ("joint-gap", "tolerance"): _non_negative("metres"),
    ("too-few-points", "sphere"): _count("points wanted on a sphere"),
    ("too-few-points", "plane"): _count("points wanted on a plane"),
    ("too-few-points", "hull"): _count("points wanted on a hull"),
    ("weak-geometry", "min_arc_deg"): Range(0.0, 360.0, meaning="degrees of visible arc"),
    ("weak-geometry", "min_length_over_diameter"): _non_negative("length over diameter"),
    # A cuboid has six faces; 1 is always met (the rule is then silent about faces).
    ("weak-geometry", "min_faces"): _count("seen faces of a cuboid", high=6),
    # 0 would call every fit weak.
    ("weak-geometry", "max_relative_stderr"): _positive("standard error over the value, 0.05 = 5%"),
    ("poor-fit", "max_rms_ratio"): _positive("residual RMS in sensor sigmas"),
    ("outliers", "max_share"): Range(0.0, 1.0, meaning="share of the points, 0.2 = 20%"),
    ("clash", "min_volume"): _non_negative("cubic metres"),
    ("clash", "samples"): _count("quasi-random samples per pair"),
    ("clash", "touch_distance"): _non_negative("metres"),
    ("design-deviation", "length_tolerance_above"): _non_negative("metres"),
    ("design-deviation", "position_tolerance"): _non_negative("metres"),
    # The angle between two axes (either way along them) is at most 90 degrees.
    ("design-deviation", "direction_tolerance_deg"): Range(0.0, 90.0, meaning="degrees"),
    ("design-deviation", "section_plus"): _non_negative("metres"),
    ("design-deviation", "section_minus"): _non_negative("metres"),
    # 0 would match nothing: every designed component would be missing.
    ("missing-component", "match_radius"): _positive("metres"),
}

#: List-valued options checked row by row: (table, key) -> (row meaning, ranges of a row's values).
ROWS: dict[tuple[str, str], tuple[str, tuple[Range, ...]]] = {
    ("design-deviation", "length_tolerance"): (
        "[largest NPS, tolerance in metres] with the NPS increasing",
        (_positive("NPS"), _non_negative("tolerance")),
    ),
}


def describe(kind: str, table: str, key: str) -> str:
    """``kind`` ("a number", "an integer") with the range of ``table.key`` when it has one."""
    found = RANGES.get((table, key))
    if found is None:
        return kind
    meaning = f" ({found.meaning})" if found.meaning else ""
    return f"{kind} {found.text()}{meaning}"


def check_range(value, kind: str, table: str, key: str) -> str | None:
    """None when ``value`` (already of the right type) is in range, else what it must be."""
    found = RANGES.get((table, key))
    if found is None:
        if isinstance(value, float) and not math.isfinite(value):
            return f"{kind} (finite)"
        return None
    return None if found.contains(float(value)) else describe(kind, table, key)


#: List options whose items are words of a label (letters, digits and inner dashes), and those
#: whose items are equipment tag letters; checked by :class:`asbuilt.merge.LabelWords`.
WORD_LISTS = {
    ("general", "pipe_keywords"): "pipe",
    ("general", "vessel_keywords"): "vessel",
    ("general", "equipment_tags"): "tags",
}


def check_rows(value: list, table: str, key: str) -> str | None:
    """None when the rows of a list-valued option are well formed, else what they must be."""
    if (table, key) in WORD_LISTS:
        from asbuilt.labels import LabelWords  # the merge's own check, one source

        try:
            LabelWords(**{WORD_LISTS[table, key]: tuple(value)})
        except ValueError as err:
            return "a list of " + str(err).rsplit(" is not a ", 1)[1].removeprefix("word of ")
        return None
    found = ROWS.get((table, key))
    if found is None:
        return None
    meaning, ranges = found
    wanted = f"a non-empty list of rows {meaning}"
    if not value:
        return wanted
    previous = -math.inf
    for row in value:
        if len(row) != len(ranges):
            return wanted
        if not all(r.contains(float(v)) for r, v in zip(ranges, row, strict=True)):
            bounds = ", ".join(f"{r.meaning} {r.text()}" for r in ranges)
            return f"{wanted} ({bounds})"
        if float(row[0]) <= previous:
            return wanted
        previous = float(row[0])
    return None
