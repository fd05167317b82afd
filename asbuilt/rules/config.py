"""The rules file: TOML, shipped defaults in ``asbuilt/data/rules.toml``, user files override per key.

The shipped file is the schema: a user file may set only the keys it has (with the same type),
plus ``severity`` per rule and any :class:`~asbuilt.tolerances.Tolerances` field in
``[general]``. Tolerances are one source of truth: a field the rules file does not set keeps
its :data:`~asbuilt.tolerances.DEFAULT_TOLERANCES` value, and :attr:`RulesConfig.tolerances`
gives the object merging should use.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from functools import lru_cache
from importlib import resources
from types import MappingProxyType

from asbuilt.errors import RulesConfigError
from asbuilt.findings import SEVERITIES
from asbuilt.tolerances import DEFAULT_TOLERANCES, Tolerances

from ._ranges import check_range, check_rows, describe
from .registry import RULES, Rule, match_rules
from .waivers import Waiver, parse_waivers

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["RulesConfig", "load_rules", "loads_rules", "DEFAULT_RULES_PATH"]

#: Where the shipped defaults live (package data).
DEFAULT_RULES_PATH = "asbuilt/data/rules.toml"

_TOLERANCE_FIELDS = {f.name: f for f in fields(Tolerances)}


def _frozen_map(mapping: Mapping) -> Mapping:
    return MappingProxyType(dict(mapping))


@dataclass(frozen=True)
class RulesConfig:
    """The resolved rules: every rule's options (severity included), the general options,
    the selection, and the file they came from.

    Attributes
    ----------
    options : Mapping[str, Mapping[str, object]]
        Rule slug to its options (``severity`` and the rule's tolerances, SI units).
    general : Mapping[str, object]
        ``[general]`` options, including every Tolerances field (defaults filled in).
    select, ignore : tuple of str
        Selectors (code, code prefix, slug or ``"ALL"``); ignore wins.
    source : str or None
        The user rules file, None for the shipped defaults.
    waivers : tuple of Waiver
        The findings the file's ``[[waive]]`` tables accept (:mod:`asbuilt.rules.waivers`).
    """

    options: Mapping[str, Mapping[str, object]]
    general: Mapping[str, object]
    select: tuple[str, ...] = ("ALL",)
    ignore: tuple[str, ...] = ()
    source: str | None = None
    waivers: tuple[Waiver, ...] = ()
    _active: frozenset = field(default=frozenset(), repr=False, compare=False)

    def __post_init__(self):
        chosen = {r.slug for sel in self.select for r in match_rules(sel)}
        dropped = {r.slug for sel in self.ignore for r in match_rules(sel)}
        object.__setattr__(self, "_active", frozenset(chosen - dropped))

    def is_active(self, key: str) -> bool:
        """Whether the rule with this slug (or code) runs."""
        return _rule(key).slug in self._active

    def active_rules(self) -> tuple[Rule, ...]:
        """The rules that run, in registry order."""
        return tuple(r for r in RULES if r.slug in self._active)

    def severity(self, key: str) -> str:
        """The configured severity of the rule with this slug (or code)."""
        return str(self.options[_rule(key).slug]["severity"])

    def option(self, key: str, name: str):
        """One option of a rule (``option("out-of-plumb", "steel_ratio")``)."""
        return self.options[_rule(key).slug][name]

    @property
    def k_sigma(self) -> float:
        """Standard errors by which a violation must exceed its limit to be an error."""
        return float(self.general["k_sigma"])

    @property
    def tolerances(self) -> Tolerances:
        """:class:`Tolerances` with the ``[general]`` overrides applied."""
        changes = {k: self.general[k] for k in _TOLERANCE_FIELDS if k in self.general}
        return dataclasses.replace(DEFAULT_TOLERANCES, **changes)

    @property
    def label_words(self):
        """:class:`asbuilt.merge.LabelWords` from ``[general]`` ``pipe_keywords``,
        ``vessel_keywords`` and ``equipment_tags``: the words merging tells a pipe from a
        vessel by."""
        from asbuilt.labels import LabelWords

        return LabelWords(
            pipe=tuple(self.general["pipe_keywords"]),
            vessel=tuple(self.general["vessel_keywords"]),
            tags=tuple(self.general["equipment_tags"]),
        )

    def with_selection(self, select=None, ignore=()) -> RulesConfig:
        """A copy whose ``select`` is replaced (when given) and ``ignore`` extended.

        Raises RulesConfigError when a selector names no rule.
        """
        new_select = tuple(_selectors(select, "--select", None)) if select else self.select
        new_ignore = self.ignore + tuple(_selectors(ignore or (), "--ignore", None))
        return dataclasses.replace(self, select=new_select, ignore=new_ignore)


def _rule(key: str) -> Rule:
    found = match_rules(key)
    if len(found) != 1:
        raise KeyError(key)
    return found[0]


def _selectors(values, where: str, source: str | None) -> list[str]:
    if isinstance(values, str) or not isinstance(values, (list, tuple)):
        raise RulesConfigError(
            'must be a list of rule codes or slugs, e.g. ["AB202", "too-few-points"]',
            source=source,
            where=where,
        )
    out = []
    for value in values:
        if not isinstance(value, str) or not match_rules(value):
            known = ", ".join(r.slug for r in RULES)
            raise RulesConfigError(
                f"unknown rule {value!r}; use a code like AB202, a prefix like AB2, ALL, or one of: "
                f"{known}",
                source=source,
                where=where,
            )
        out.append(value)
    return out


def _type_name(value) -> str:
    return {
        bool: "true or false",
        int: "an integer",
        float: "a number",
        str: "a string",
        list: "a list",
    }.get(type(value), type(value).__name__)


def _check_value(value, default, where: str, source: str | None, option=None):
    """``value`` coerced to the type of ``default`` (int accepted for float); else an error.

    ``option`` is ``(table, key)`` when the value has a range to name in the error.
    """
    wanted = _type_name(default) if option is None else describe(_type_name(default), *option)
    if isinstance(value, int) and not isinstance(value, bool) and not _fits_float(value):
        # TOML integers are unbounded: one past any float would overflow the range check
        raise RulesConfigError(
            f"must be {wanted}, not an integer of {len(str(abs(value))):,} digits",
            source=source,
            where=where,
        )
    if isinstance(default, bool):
        if isinstance(value, bool):
            return value
    elif isinstance(default, float):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
    elif isinstance(default, int):
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif isinstance(default, str):
        if isinstance(value, str):
            return value
    elif isinstance(default, list):
        if isinstance(value, list):
            if default:
                return [
                    _check_value(v, default[0], f"{where}[{i}]", source)
                    for i, v in enumerate(value)
                ]
            if all(isinstance(v, str) for v in value):
                return list(value)
    raise RulesConfigError(f"must be {wanted}, not {value!r}", source=source, where=where)


def _fits_float(value: int) -> bool:
    try:
        float(value)
    except OverflowError:
        return False
    return True


def _parse(text: str, source: str | None) -> dict:
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RulesConfigError(f"not valid TOML ({exc}); fix the syntax", source=source) from None
    except RecursionError:
        raise RulesConfigError(
            "not valid TOML (nested too deeply); a rules file nests lists two levels at most",
            source=source,
        ) from None
    except ValueError:  # tomllib's int() of a literal past Python's 4,300-digit limit
        found = re.search(rf"\d{{{_LONGEST_INTEGER_LITERAL},}}", text)
        where = f"line {text.count(chr(10), 0, found.start()) + 1}" if found else None
        raise RulesConfigError(
            f"a number of over {_LONGEST_INTEGER_LITERAL - 1:,} digits; fix the number there",
            source=source,
            where=where,
        ) from None


#: Digits of the shortest integer literal tomllib cannot convert (Python's default
#: ``sys.int_info.default_max_str_digits`` is 4,300).
_LONGEST_INTEGER_LITERAL = 4301


@lru_cache(maxsize=1)
def _shipped() -> dict:
    text = resources.files("asbuilt").joinpath("data/rules.toml").read_text(encoding="utf-8")
    return _parse(text, DEFAULT_RULES_PATH)


def _tolerance_default(name: str):
    return getattr(DEFAULT_TOLERANCES, name)


def _resolve(user: Mapping, source: str | None) -> RulesConfig:
    shipped = _shipped()
    general = dict(shipped["general"])
    for name in _TOLERANCE_FIELDS:
        general.setdefault(name, _tolerance_default(name))
    options = {r.slug: dict(shipped[r.slug]) for r in RULES}
    select = list(shipped["select"])
    ignore = list(shipped["ignore"])
    waivers: tuple[Waiver, ...] = ()
    for key, value in user.items():
        if key == "waive":
            waivers = parse_waivers(value, source)
            continue
        if key in ("select", "ignore"):
            chosen = _selectors(value, key, source)
            if key == "select":
                select = chosen
            else:
                ignore = chosen
            continue
        if key == "general":
            table, target = value, general
        else:
            found = match_rules(key)
            if len(found) != 1 or key.lower() == "all":
                raise RulesConfigError(
                    "unknown rule or table; use [general] or a rule slug such as "
                    "[out-of-plumb] (docs/rules.md lists them)",
                    source=source,
                    where=f"[{key}]",
                )
            table, target = value, options[found[0].slug]
            key = found[0].slug
        if not isinstance(table, dict):
            raise RulesConfigError(
                f"must be a table ([{key}]), not {value!r}", source=source, where=key
            )
        for name, item in table.items():
            where = f"[{key}].{name}"
            if name not in target:
                allowed = ", ".join(sorted(target))
                raise RulesConfigError(
                    f"unknown option; [{key}] accepts: {allowed}", source=source, where=where
                )
            checked = _check_value(item, target[name], where, source, (key, name))
            if name == "severity" and checked not in SEVERITIES:
                raise RulesConfigError(
                    f"must be one of {', '.join(SEVERITIES)}, not {item!r}",
                    source=source,
                    where=where,
                )
            if isinstance(checked, (int, float)) and not isinstance(checked, bool):
                wanted = check_range(checked, _type_name(target[name]), key, name)
            elif isinstance(checked, list):
                wanted = check_rows(checked, key, name)
            else:
                wanted = None
            if wanted is not None:
                raise RulesConfigError(
                    f"must be {wanted}, not {item!r}", source=source, where=where
                )
            target[name] = checked
    if general["angle_snap_deg"] > general["intended_angle_deg"]:
        raise RulesConfigError(
            f"angle_snap_deg {general['angle_snap_deg']:g} must be at most intended_angle_deg "
            f"{general['intended_angle_deg']:g} (axes are regularised below the first and "
            "deliberately skewed above the second); lower it or raise intended_angle_deg",
            source=source,
            where="[general].angle_snap_deg",
        )
    if general["default_material"] not in ("steel", "concrete"):
        raise RulesConfigError(
            f'must be "steel" or "concrete", not {general["default_material"]!r}',
            source=source,
            where="[general].default_material",
        )
    return RulesConfig(
        options=_frozen_map({slug: _frozen_map(opts) for slug, opts in options.items()}),
        general=_frozen_map(general),
        select=tuple(select),
        ignore=tuple(ignore),
        source=source,
        waivers=waivers,
    )


def loads_rules(text: str, *, source: str | None = None) -> RulesConfig:
    """Rules from TOML text (the shipped defaults overridden by it); ``source`` names it in errors."""
    return _resolve(_parse(text, source), source)


def load_rules(path=None) -> RulesConfig:
    """The rules: the shipped defaults, overridden per key by the TOML file at ``path`` if given.

    Raises
    ------
    RulesConfigError
        The file cannot be read, is not TOML, names an unknown rule or option, or gives a value of
        the wrong type (one line naming the file, the key and what to write instead).
    """
    if path is None:
        return _resolve({}, None)
    from .._text import read_text

    source = str(path)
    text = read_text(
        path,
        RulesConfigError,
        what="rules file",
        missing="no such file; check the --rules path",
        kind="TOML",
    )
    return loads_rules(text, source=source)
