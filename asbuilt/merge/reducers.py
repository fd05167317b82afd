"""Which reducers a fittings catalog makes (the small ends for each large end), and the
dimensions of its reducing tees and reducing elbows by pair of sizes.

ASME B16.9 makes a concentric (or eccentric) reducer only for listed pairs of sizes: from NPS 12
down to 10, 8, 6 or 5, not to 4 (that takes two reducers in series). The pairs ship beside the
fittings table as ``catalogs/<fittings name>-reducers.toml`` (``[small_ends]``: large end ->
list of small ends, the catalog's nominal names). A fittings table without such a file, or a
pipe without a catalog size, gives no verdict (None): merging builds the reducer as before.

Reducing-outlet tees (ASME B16.9 Table 8) have their own centre-to-end C (run) and M (outlet)
for each run x outlet pair, shipped as ``[dimensions]`` of ``catalogs/<fittings>-tees.toml``
(:func:`reducing_tee_dims`); the 90 degree long-radius reducing elbows' pairs and centre-to-end
A ship as ``catalogs/<fittings>-elbows.toml`` (:func:`reducing_elbow_end`).
"""

from __future__ import annotations

from functools import cache
from importlib import resources

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = [
    "nps_order",
    "reducer_made",
    "small_ends",
    "reducing_tee_dims",
    "reducing_elbow_ends",
    "reducing_elbow_end",
]


def _shipped(fittings: str | None, suffix: str) -> dict | None:
    """The TOML ``catalogs/<fittings>-<suffix>.toml`` shipped beside a fittings table, or None."""
    if not fittings:
        return None
    resource = resources.files("asbuilt.catalogs") / f"{fittings}-{suffix}.toml"
    if not resource.is_file():
        return None
    return tomllib.loads(resource.read_text(encoding="utf-8"))


@cache
def small_ends(fittings: str | None) -> dict[str, frozenset[str]] | None:
    """The ``{large end: small ends}`` of the shipped fittings table ``fittings`` (its name),
    or None when no reducer list ships with it."""
    table = _shipped(fittings, "reducers")
    if table is None:
        return None
    return {large: frozenset(small) for large, small in table.get("small_ends", {}).items()}


def reducer_made(fittings: str | None, large: str | None, small: str | None) -> bool | None:
    """Whether the fittings table ``fittings`` makes a ``large`` x ``small`` reducer (nominal
    names of its pipe catalog); None when it cannot be told (no list, a size unknown)."""
    table = small_ends(fittings)
    if table is None or large is None or small is None:
        return None
    return small in table.get(large, frozenset())


def nps_order(nominal: str) -> float:
    """NPS ``"1 1/2"`` as 1.5, for ordering nominal names."""
    total = 0.0
    for part in nominal.split():
        top, _, bottom = part.partition("/")
        total += float(top) / float(bottom or 1)
    return total


@cache
def _tee_dims(fittings: str | None) -> dict[tuple[str, str], tuple[float, float]] | None:
    table = _shipped(fittings, "tees")
    if table is None or "dimensions" not in table:
        return None
    return {
        (run, outlet): (float(c) / 1000.0, float(m) / 1000.0)
        for run, outlets in table["dimensions"].items()
        for outlet, (c, m) in outlets.items()
    }


def reducing_tee_dims(
    fittings: str | None, run: str | None, outlet: str | None
) -> tuple[float, float] | None:
    """``(C, M)`` in metres of the fittings table's reducing-outlet tee of run ``run`` and
    outlet ``outlet`` (nominal names), or None when the table lists no such pair (not made, or
    not in the shipped data; then the equal tee's dimensions of the run stand in)."""
    table = _tee_dims(fittings)
    if table is None or run is None or outlet is None:
        return None
    return table.get((run, outlet))


@cache
def reducing_elbow_ends(fittings: str | None) -> dict[str, dict[str, float]] | None:
    """``{large end: {small end: A in metres}}`` of the 90 degree long-radius reducing elbows
    the fittings table ``fittings`` makes, or None when no list ships with it."""
    table = _shipped(fittings, "elbows")
    if table is None:
        return None
    return {
        large: {small: float(a) / 1000.0 for small, a in smalls.items()}
        for large, smalls in table.get("center_to_end", {}).items()
    }


def reducing_elbow_end(fittings: str | None, large: str | None, small: str | None):
    """The centre-to-end A (metres) of a listed 90 degree long-radius ``large`` x ``small``
    reducing elbow; False when the list covers the large end but not this small end (not
    made); None when it cannot be told (no list, a size unknown, a large end not listed)."""
    table = reducing_elbow_ends(fittings)
    if table is None or large is None or small is None or large not in table:
        return None
    return table[large].get(small, False)
