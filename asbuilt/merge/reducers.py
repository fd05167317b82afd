"""Which reducers a fittings catalog makes: the small ends for each large end.

ASME B16.9 makes a concentric (or eccentric) reducer only for listed pairs of sizes: from NPS 12
down to 10, 8, 6 or 5, not to 4 (that takes two reducers in series). The pairs ship beside the
fittings table as ``catalogs/<fittings name>-reducers.toml`` (``[small_ends]``: large end ->
list of small ends, the catalog's nominal names). A fittings table without such a file, or a
pipe without a catalog size, gives no verdict (None): merging builds the reducer as before.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

try:  # Python 3.11+
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib

__all__ = ["nps_order", "reducer_made", "small_ends"]


@cache
def small_ends(fittings: str | None) -> dict[str, frozenset[str]] | None:
    """The ``{large end: small ends}`` of the shipped fittings table ``fittings`` (its name),
    or None when no reducer list ships with it."""
    if not fittings:
        return None
    resource = resources.files("asbuilt.catalogs") / f"{fittings}-reducers.toml"
    if not resource.is_file():
        return None
    table = tomllib.loads(resource.read_text(encoding="utf-8"))
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
