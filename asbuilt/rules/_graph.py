"""Which components are joined: touching ends, scan links, and ends near enough to be inferred.

Used by the size, joint and clash rules. End points come from :func:`._context.ends_of`; a
cKDTree finds close ends in O(n log n).
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np
from scipy.spatial import cKDTree

from asbuilt.merge.contiguity import elbow_bend_limit, line_closest_points
from asbuilt.model import Component, Model
from asbuilt.tolerances import DEFAULT_TOLERANCES

from ._context import ends_of

__all__ = [
    "end_pairs",
    "linked_pairs",
    "adjacency",
    "inferred_pairs",
    "contiguous_pipes",
    "could_join",
    "fittings_between",
    "FITTING_PASS",
]

#: Fittings a size passes through unchanged (a reducer or a tee branch may change it).
FITTING_PASS = ("elbow", "coupling")


def _ends(components):
    points, owners = [], []
    for comp in components:
        for end in ends_of(comp.geometry):
            points.append(end)
            owners.append(comp.id)
    return np.asarray(points, dtype=np.float64).reshape(-1, 3), owners


def end_pairs(
    components, distance: float, free_only_touch: float | None = None
) -> dict[frozenset, float]:
    """Pairs of components with ends within ``distance`` metres: ``{frozenset(ids): gap m}``.

    With ``free_only_touch``, ends already within that distance of another component's end
    (joined) are left out.
    """
    points, owners = _ends(components)
    found: dict[frozenset, float] = {}
    if len(points) < 2:
        return found
    tree = cKDTree(points)
    free = np.ones(len(points), bool)
    if free_only_touch is not None:
        for i, j in tree.query_pairs(free_only_touch):
            if owners[i] != owners[j]:
                free[i] = free[j] = False
    for i, j in tree.query_pairs(distance):
        if owners[i] == owners[j] or not (free[i] and free[j]):
            continue
        key = frozenset((owners[i], owners[j]))
        gap = float(np.linalg.norm(points[i] - points[j]))
        found[key] = min(gap, found.get(key, np.inf))
    return found


def linked_pairs(model: Model) -> set[frozenset]:
    """Pairs of component ids joined by the scan's ``links`` (through their source objects)."""
    if model.scan is None or not model.scan.links:
        return set()
    by_source = defaultdict(list)
    for comp in model.components:
        for source in comp.sources:
            by_source[source].append(comp.id)
    pairs = set()
    for a, b in model.scan.links:
        for ca in by_source.get(a, ()):
            for cb in by_source.get(b, ()):
                if ca != cb:
                    pairs.add(frozenset((ca, cb)))
    return pairs


def adjacency(
    model: Model, touch: float, infer: float | None = None, *, links: bool = True
) -> dict[str, set[str]]:
    """Component id to the ids it is joined to.

    Joined: ends within ``touch`` metres, linked in the scan (unless ``links`` is False: what
    is physically joined, not what the scan says should be), or (pipes only, when ``infer`` is
    given) ends within ``infer`` metres of each other.
    """
    graph: dict[str, set[str]] = defaultdict(set)
    pairs = set(end_pairs(model.components, touch))
    if links:
        pairs |= linked_pairs(model)
    if infer:
        pairs |= inferred_pairs(model, touch, infer)
    for pair in pairs:
        a, b = tuple(pair)
        graph[a].add(b)
        graph[b].add(a)
    return graph


#: Largest bend (degrees) between two pipe ends that an elbow can join: merging's limit (ASME
#: B16.9 elbows turn 45 or 90 degrees, plus ``intended_angle_deg``).
ELBOW_BEND_MAX_DEG = elbow_bend_limit(DEFAULT_TOLERANCES)


def inferred_pairs(model: Model, touch: float, infer: float) -> set[frozenset]:
    """Pipes whose *free* ends (joined to nothing within ``touch``) lie within ``infer`` metres
    and could be joined there (:func:`could_join`): pipes side by side in a rack, whose ends are
    close but run the same way, are not contiguous."""
    points, owners = _ends(model.components)
    if len(points) < 2:
        return set()
    tree = cKDTree(points)
    free = np.ones(len(points), bool)
    for i, j in tree.query_pairs(touch):
        if owners[i] != owners[j]:
            free[i] = free[j] = False
    comps = {c.id: c for c in model.components}
    pairs = set()
    for i, j in tree.query_pairs(infer):
        a, b = comps[owners[i]], comps[owners[j]]
        if (
            a.id != b.id
            and free[i]
            and free[j]
            and a.type in ("pipe", "cylinder")
            and b.type in ("pipe", "cylinder")
            and could_join(a.geometry, points[i], b.geometry, points[j], infer)
        ):
            pairs.add(frozenset((a.id, b.id)))
    return pairs


def _outward(geometry, end: np.ndarray) -> np.ndarray | None:
    """Unit direction out of a straight pipe at its end ``end`` (3,) m (None if not two-ended)."""
    ends = ends_of(geometry)
    if len(ends) != 2:
        return None
    other = ends[1] if np.linalg.norm(ends[0] - end) <= np.linalg.norm(ends[1] - end) else ends[0]
    direction = end - other
    norm = float(np.linalg.norm(direction))
    return None if norm == 0 else direction / norm


def _outer_radius(geometry) -> float:
    return float(getattr(geometry, "outer_radius", getattr(geometry, "radius", 0.0)))


def could_join(ga, ea: np.ndarray, gb, eb: np.ndarray, reach: float) -> bool:
    """Whether straight pipes ``ga`` and ``gb`` could be joined at their ends ``ea``, ``eb``
    ((3,) m): in line (ends facing each other, axes within the larger outer radius of one line),
    or by an elbow of at most ``ELBOW_BEND_MAX_DEG`` (axis lines meeting within that radius, the
    corner ahead of both ends, less than ``reach`` metres behind either)."""
    oa, ob = _outward(ga, ea), _outward(gb, eb)
    if oa is None or ob is None:
        return False
    radius = max(_outer_radius(ga), _outer_radius(gb))
    bend = float(np.degrees(np.arccos(np.clip(-(oa @ ob), -1.0, 1.0))))  # 0: facing, in line
    rel = eb - ea
    if bend <= 5.0:
        lateral = rel - (rel @ oa) * oa
        return float(np.linalg.norm(lateral)) <= radius
    if bend > ELBOW_BEND_MAX_DEG:
        return False
    s, t, qa, qb = line_closest_points(ea, oa, eb, ob)
    return float(np.linalg.norm(qa - qb)) <= radius and s >= -reach and t >= -reach


def contiguous_pipes(
    model: Model, graph: dict[str, set[str]], pipe_ids, through=FITTING_PASS
) -> list[tuple]:
    """Pairs of pipes joined directly or through fittings of the types ``through`` only
    (elbows and couplings by default).

    Returns ``(first id, second id, intermediate fitting ids)`` once per pair.
    """
    types = {c.id: c.type for c in model.components}
    pipe_ids = set(pipe_ids)
    result = {}
    for start in sorted(pipe_ids):
        stack = [(start, ())]
        seen = {start}
        while stack:
            node, path = stack.pop()
            for nxt in sorted(graph.get(node, ())):
                if nxt in seen:
                    continue
                seen.add(nxt)
                if nxt in pipe_ids:
                    key = tuple(sorted((start, nxt)))
                    result.setdefault(key, path)
                elif types.get(nxt) in through:
                    stack.append((nxt, (*path, nxt)))
    return [(a, b, path) for (a, b), path in sorted(result.items())]


def component_map(model: Model) -> dict[str, Component]:
    return {c.id: c for c in model.components}


def fittings_between(model: Model, graph: dict[str, set[str]], a: str, b: str) -> list[str] | None:
    """The fittings (ids, in order) on a shortest path from component ``a`` to ``b`` through
    fittings only (no other pipe) in ``graph``; ``[]`` when they touch, None when no such
    path exists."""
    kinds = {c.id: c.type for c in model.components}
    previous: dict[str, str | None] = {a: None}
    queue = [a]
    while queue:
        node = queue.pop(0)
        for nxt in sorted(graph.get(node, ())):
            if nxt in previous:
                continue
            previous[nxt] = node
            if nxt == b:
                path = []
                step = previous[b]
                while step is not None and step != a:
                    path.append(step)
                    step = previous[step]
                return path[::-1]
            if kinds.get(nxt) in ("elbow", "tee", "cross", "reducer", "coupling"):
                queue.append(nxt)
    return None
