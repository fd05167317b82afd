"""Open ends of piping components and the check that neighbours share them exactly.

:func:`ports` gives each pipe's, coupling's, reducer's, elbow's and tee's open ends with their
outward directions; :func:`connection_mismatches` pairs the ports of one spool and reports
those whose points or directions differ (merging makes them equal to rounding). Used by
merging's tests, the CAD layer and the rules.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from asbuilt.model import Bend, Component, Cross, Reducer, Straight, Tee

__all__ = ["connection_mismatches", "ports"]


def _unit(v):
    return v / np.linalg.norm(v)


def ports(component: Component) -> list[tuple[np.ndarray, np.ndarray]]:
    """The connection ports of a piping component.

    Returns
    -------
    list of (point, direction)
        Each ``point`` (3,) metres is an open end; ``direction`` (3,) the unit vector pointing
        out of the component there. Pipes and couplings (``Straight``), reducers: start and end;
        elbows (``Bend``): the two ends with their tangents; tees: run start, run end and branch
        end (crosses: both outlet ends). Other components have no ports (empty list).
    """
    g = component.geometry
    if isinstance(g, Reducer):
        return [(g.start, -g.direction), (g.end, g.direction)]
    if isinstance(g, Straight):
        d = _unit(g.end - g.start)
        return [(g.start, -d), (g.end, d)]
    if isinstance(g, Bend):
        s = g.start - g.center
        e = g.end - g.center
        us, ue = _unit(s), _unit(e)
        travel_start = _unit(e - (e @ us) * us)
        travel_end = _unit(-(s - (s @ ue) * ue))
        return [(g.start, -travel_start), (g.end, travel_end)]
    if isinstance(g, Tee | Cross):
        return [
            (g.run_start, _unit(g.run_start - g.center)),
            (g.run_end, _unit(g.run_end - g.center)),
            *((end, _unit(end - g.center)) for end in g.outlets),
        ]
    return []


def connection_mismatches(components: Sequence[Component], tolerance: float = 1e-4):
    """Check that neighbouring components share end points and directions.

    Every port of every piping component is paired with the nearest port of another component
    of the same spool; a pair closer than 10 x ``tolerance`` is a connection. A connection is a
    mismatch when the points differ by more than ``tolerance`` (metres) or the directions are not
    opposite within ``tolerance`` (radians, as the length of their sum).

    Returns
    -------
    connections : int
        Number of port pairs found.
    mismatches : list of (str, str, float, float)
        Component ids, point gap (metres) and direction error, for each bad pair.
    """
    entries = []
    for comp in components:
        for point, direction in ports(comp):
            entries.append((comp.id, comp.spool, np.asarray(point), np.asarray(direction)))
    if not entries:
        return 0, []
    tree = cKDTree(np.array([e[2] for e in entries]))
    connections = 0
    bad = []
    for id_a, spool_a, pa, da in entries:
        best = None
        for b in tree.query_ball_point(pa, 10 * tolerance):
            id_b, spool_b, pb, db = entries[b]
            if id_b == id_a or spool_b != spool_a:
                continue
            gap = float(np.linalg.norm(pa - pb))
            if best is None or gap < best[0]:
                best = (gap, id_b, db)
        if best is None:
            continue
        connections += 1
        gap, id_b, db = best
        turn = float(np.linalg.norm(da + db))
        if gap > tolerance or turn > tolerance:
            bad.append((id_a, id_b, gap, turn))
    return connections // 2, bad
