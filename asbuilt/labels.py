"""The words of a label that tell a pipe from a vessel or structure (:func:`asbuilt.merge.is_pipe`,
and the noun a fit's notes name a vessel by).

The defaults are this module's tuples; a rules file's ``[general]`` ``pipe_keywords``,
``vessel_keywords`` and ``equipment_tags`` replace them (:class:`LabelWords`), so that a plant's
own vocabulary ("Behaelter", "bullet") or tag letters (``T-101``) mark its vessels.
"""

from __future__ import annotations

import dataclasses
import functools
import re

__all__ = ["LabelWords", "DEFAULT_WORDS", "PIPE_WORDS", "VESSEL_WORDS", "EQUIPMENT_TAGS"]

#: Words in an object's label or group that mark a cylinder as a vessel or structure, not a pipe.
VESSEL_WORDS = (
    "tank",
    "vessel",
    "column",
    "chimney",
    "stack",
    "silo",
    "drum",
    "pile",
    "pier",
    "pillar",
    "pole",
    "post",
    "tower",
    "reactor",
    "receiver",
    "separator",
    "accumulator",
    "exchanger",
    "heater",
    "boiler",
    "hopper",
    "cistern",
)
#: Equipment tags that mark a vessel: ``TK-101``/``TK101`` (tank), ``V-101`` (vessel),
#: ``D-101`` (drum), ``R-101`` (reactor), ``E-101`` (exchanger shell), ``C-101`` (column),
#: with an optional suffix letter (``V-101A``). The usual plant equipment letters (PIP and
#: ISA-5.1 equipment lists); a field engineer labels a tank by its tag more often than by a
#: word. A tag stands alone: preceded by a size or a dash (``4"-V-1001-A1``, a vent line's
#: number) it is part of a line number, not a tag.
EQUIPMENT_TAGS = ("TK", "V", "D", "R", "E", "C")

#: Words that mark a label as naming a pipe; they win over vessel words ("line from the tank").
PIPE_WORDS = (
    "pipe",
    "piping",
    "line",
    "header",
    "riser",
    "drop",
    "run",
    "spool",
    "branch",
    "nps",
    "dn",
    "elbow",
    "tee",
    "bypass",
    "drain",
    "vent",
    "duct",
)

# A word or tag is letters, digits and inner dashes: anything else (a space, a regex sign) is a
# typing error in a rules file, caught when the rules are loaded.
_WORD = re.compile(r"[^\W_](?:[\w-]*[^\W_])?")
_TAG_LETTERS = re.compile(r"[^\W\d_]+")


@dataclasses.dataclass(frozen=True)
class LabelWords:
    """The vocabulary :func:`asbuilt.merge.is_pipe` reads labels with (whole words, any case).

    Attributes
    ----------
    pipe : tuple of str
        Words that mark a pipe (with a plural ``s`` or a number joined: "lines", "line2").
    vessel : tuple of str
        Words that mark a vessel or structure, never a pipe (with a plural ``s``).
    tags : tuple of str
        Equipment tag letters: the letters, a dash and a number (``TK-101``, ``V-101A``) mark a
        vessel; a tag of two letters or more may leave out the dash (``TK101``).

    Raises
    ------
    ValueError
        A word that is not letters, digits and inner dashes, or a tag that is not letters.
    """

    pipe: tuple[str, ...] = PIPE_WORDS
    vessel: tuple[str, ...] = VESSEL_WORDS
    tags: tuple[str, ...] = EQUIPMENT_TAGS

    def __post_init__(self) -> None:
        for name in ("pipe", "vessel", "tags"):
            raw = getattr(self, name)
            if isinstance(raw, str):  # tuple("tank") would be four one-letter words
                raise ValueError(f"{name}: give a list of words, not the string {raw!r}")
            values = tuple(raw)
            object.__setattr__(self, name, values)
            check = _TAG_LETTERS if name == "tags" else _WORD
            for value in values:
                if not isinstance(value, str) or not check.fullmatch(value):
                    what = "letters" if name == "tags" else "letters, digits and inner dashes"
                    raise ValueError(f"{name}: {value!r} is not a word of {what}")

    @functools.cached_property
    def _patterns(self) -> tuple:
        def words(values, tail):
            if not values:
                return None
            alternatives = "|".join(map(re.escape, values))
            return re.compile(rf"\b({alternatives}){tail}\b", re.IGNORECASE)

        tags = None
        if self.tags:
            # A tag stands alone: preceded by a size or a dash (4"-V-1001-A1, a vent line's
            # number) it is part of a line number, not a tag.
            tags = re.compile(
                r"(?<![\w\"'\-])("
                + "|".join(
                    f"{re.escape(t)}-?\\d+" if len(t) > 1 else f"{re.escape(t)}-\\d+"
                    for t in self.tags
                )
                + r")[A-Z]?(?![\w\-])",
                re.IGNORECASE,
            )
        return words(self.pipe, r"(s|\d+)?"), words(self.vessel, "s?"), tags

    def says(self, text: str | None) -> tuple[str | None, str | None]:
        """``("pipe" | "vessel" | None, the deciding word)`` for a label or group text."""
        if not text:
            return None, None
        pipe, vessel, tag = self._patterns
        found = pipe.search(text) if pipe else None
        if found:
            return "pipe", found.group(1).lower()
        found = vessel.search(text) if vessel else None
        if found:
            return "vessel", found.group(1).lower()
        found = tag.search(text) if tag else None
        if found:
            return "vessel", found.group(0)
        return None, None

    def vessel_noun(self, label: str | None, group: str | None = None) -> str | None:
        """The noun a vessel or structure is named by in a fit's notes (``"tank"``, ``"column"``;
        ``"vessel"`` for an equipment tag), or None when the label (else the group) does not
        mark one, the same reading as :func:`asbuilt.merge.is_pipe`."""
        says, word = self.says(label)
        if says is None:
            says, word = self.says(group)
        if says != "vessel":
            return None
        lowered = word.lower()
        return lowered if lowered in (w.lower() for w in self.vessel) else "vessel"


#: The shipped vocabulary.
DEFAULT_WORDS = LabelWords()
