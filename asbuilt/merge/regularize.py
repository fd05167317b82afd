"""Orientation regularisation and line alignment, in the spirit of GlobFit.

GlobFit (Li, Wu, Chrysathou, Sharf, Cohen-Or, Mitra, "GlobFit: consistently fitting primitives
by discovering global relations", SIGGRAPH 2011) detects near-relations between fitted
primitives (parallel, orthogonal, coaxial...) within a tolerance and refits so that they hold
exactly. Here, for pipe axes:

1. **Parallel**: axes within ``angle_snap_deg`` of each other (and pipes joined inline, which
   must share an axis) are clustered; each cluster gets one direction, the principal direction of
   its members' axes weighted by length (by inverse variance when the axes' standard errors are
   given).
2. **Vertical / horizontal**: a cluster within ``angle_snap_deg`` of the vertical becomes exactly
   vertical; one within ``angle_snap_deg`` of horizontal loses its vertical component.
3. **Perpendicular**: clusters are fixed in order of weight (the vertical first); a cluster within
   ``angle_snap_deg`` of perpendicular to fixed directions is projected onto their orthogonal
   complement (the smallest rotation making it exactly perpendicular).

Given the axes' standard errors, every relation must also be *insignificant*: the angle it
removes at most :data:`SNAP_SIGMA` combined standard errors. A well-measured 1% drain slope
(0.57 degrees, known to 0.02) is real and kept; a short, noisy axis 1 degree off level (known
to 0.5) is made level. Without standard errors the tolerance alone decides. The tolerance caps
the relations of well-measured axes; an axis known worse (a short stub, to 3 degrees) is
regularised within its :data:`SNAP_SIGMA` standard errors up to ``max_deg``
(``Tolerances.angle_snap_max_deg``), and pipes joined by an elbow within that of 45 degrees are made exactly
45 degrees apart (ASME B16.9 elbows turn 45 or 90).

Then :func:`align_lines` moves each pipe's line sideways (never rotating it again) by the
smallest weighted amount that makes joined lines meet exactly: elbows and tee branches
intersect their partner's axis, inline segments become coaxial. The constraints are linear in
the sideways offsets and the meeting parameters; they are solved together with the weighted offset penalty as one sparse,
regularised KKT system per spool (so a spool of 1,000 pipes stays fast).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .contiguity import line_closest_points

__all__ = [
    "DirectionResult",
    "FitUp",
    "align_lines",
    "fit_up",
    "perpendicular_basis",
    "regularize_directions",
]

_Z = np.array([0.0, 0.0, 1.0])

#: A relation is made exact only when the angle it removes is within this many combined
#: standard errors of the axes (as merging's diameter windows use 3 standard errors): beyond
#: that the deviation is measured, not noise (a drain's slope, a deliberately tilted line).
SNAP_SIGMA = 3.0

#: Smallest axis standard error believed (degrees): 0.2 mm over a metre, below a range
#: finder's noise; keeps noise-free synthetic fits from refusing every relation.
AXIS_SE_FLOOR_DEG = 0.01


@dataclass(frozen=True)
class DirectionResult:
    """Regularised axes and why each changed.

    Attributes
    ----------
    axes : ndarray, shape (n, 3)
        New unit axes (same sense as the inputs).
    relations : tuple of tuple of str
        Per pipe, the relations made exact (``"vertical"``, ``"horizontal"``,
        ``"parallel to P2"``, ``"perpendicular to P3"``, ``"coaxial run"``).
    angles_deg : ndarray, shape (n,)
        Angle between each old and new axis, degrees.
    cluster : ndarray, shape (n,), int
        Cluster index of each pipe (pipes in one cluster are exactly parallel).
    """

    axes: np.ndarray
    relations: tuple[tuple[str, ...], ...]
    angles_deg: np.ndarray
    cluster: np.ndarray


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    """Angle in degrees between two lines (sign-free), in [0, 90]."""
    return float(np.degrees(np.arccos(np.clip(abs(float(a @ b)), 0.0, 1.0))))


def _principal(axes: np.ndarray, weights: np.ndarray) -> np.ndarray:
    scatter = (axes * weights[:, None]).T @ axes
    values, vectors = np.linalg.eigh(scatter)
    d = vectors[:, -1]
    return d / np.linalg.norm(d)


def regularize_directions(
    axes,
    weights,
    *,
    tol_deg: float,
    parallel_groups: Sequence[Sequence[int]] = (),
    names: Sequence[str] | None = None,
    stderr_deg=None,
    k_sigma: float = SNAP_SIGMA,
    max_deg: float | None = None,
    elbow_pairs: Sequence[tuple[int, int]] = (),
) -> DirectionResult:
    """Make near-parallel, near-vertical, near-horizontal and near-perpendicular axes exact.

    Parameters
    ----------
    axes : array_like, shape (n, 3)
        Unit axes (sign arbitrary).
    weights : array_like, shape (n,)
        Weight of each axis (e.g. pipe length in metres; longer fits are steadier).
    tol_deg : float
        ``Tolerances.angle_snap_deg``.
    parallel_groups : sequence of sequence of int
        Pipes that must end up parallel whatever their angle (pipes joined inline).
    names : sequence of str, optional
        Pipe ids for the relation texts (default ``"#i"``).
    stderr_deg : array_like, shape (n,), optional
        Standard error of each axis, degrees (NaN: unknown). A relation is made exact only when
        the angle it removes is also within ``k_sigma`` combined standard errors (floored at
        :data:`AXIS_SE_FLOOR_DEG`); unknown errors leave the tolerance alone to decide.
    k_sigma : float
        See ``stderr_deg``; default :data:`SNAP_SIGMA`.
    max_deg : float, optional
        Largest angle a relation may remove between axes whose standard errors allow more than
        ``tol_deg`` (``Tolerances.angle_snap_max_deg``, at most ``intended_angle_deg``): a
        short stub's axis, known to 3 degrees, 2.2 degrees off vertical is built vertical; one
        with a well-measured axis stays within ``tol_deg`` and its standard errors. Default
        ``tol_deg`` (the tolerance caps every relation).
    elbow_pairs : sequence of (int, int)
        Pipes joined by an elbow. Besides the relations above, such a pair within the allowed
        angle of 45 degrees is made exactly 45 degrees apart (ASME B16.9 elbows turn 45 or 90
        degrees; 90 is the perpendicular relation), turning the later (lighter) cluster in the
        plane of the two axes, and keeping the perpendiculars it was given.

    Returns
    -------
    DirectionResult
    """
    axes = np.asarray(axes, float).reshape(-1, 3)
    n = len(axes)
    weights = np.maximum(np.asarray(weights, float).reshape(-1), 1e-9)
    names = list(names) if names is not None else [f"#{i}" for i in range(n)]
    if n == 0:
        return DirectionResult(np.zeros((0, 3)), (), np.zeros(0), np.zeros(0, int))
    se = np.full(n, np.inf) if stderr_deg is None else np.asarray(stderr_deg, float).reshape(-1)
    se = np.where(np.isfinite(se), np.maximum(se, AXIS_SE_FLOOR_DEG), np.inf)

    def combined(members) -> float:
        """Standard error (degrees) of a cluster's direction: inverse-variance combination."""
        values = se[list(members)]
        if not np.all(np.isfinite(values)):
            return float("inf")
        return float(1.0 / np.sqrt(np.sum(1.0 / values**2)))

    # a cluster's direction: members weighted by 1 / se^2 when every error is known (a
    # well-measured axis must not be turned by more than its own error to suit a noisy one),
    # else by the given weights
    dir_weight = 1.0 / se**2 if np.all(np.isfinite(se)) else weights

    cap_deg = tol_deg if max_deg is None else max(tol_deg, float(max_deg))

    def allowed(*errors: float) -> float:
        """The largest angle (degrees) a relation may remove between axes of these errors:
        ``k_sigma`` combined standard errors, at most ``cap_deg``; ``tol_deg`` when an error
        is unknown."""
        spread = k_sigma * float(np.hypot.reduce(errors))
        return min(spread, cap_deg) if np.isfinite(spread) else tol_deg

    elbow_partners: dict[int, set[int]] = {}
    for a, b in elbow_pairs:
        elbow_partners.setdefault(int(a), set()).add(int(b))
        elbow_partners.setdefault(int(b), set()).add(int(a))

    # clusters: forced groups first, then greedy merge of near-parallel clusters
    parent = list(range(n))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    forced = np.zeros(n, bool)
    for group in parallel_groups:
        group = list(group)
        for member in group[1:]:
            ra, rb = find(group[0]), find(member)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
        if len(group) > 1:
            forced[group] = True
    clusters: dict[int, list[int]] = {}
    for i in range(n):
        clusters.setdefault(find(i), []).append(i)
    groups = sorted(clusters.values(), key=lambda g: -weights[g].sum())
    dirs = [_principal(axes[g], dir_weight[g]) if len(g) > 1 else axes[g[0]] for g in groups]
    # leader clustering: groups (heaviest first) join the first cluster whose leading direction
    # is within the tolerance; each cluster's direction is computed once its members are known
    merged: list[list[int]] = []
    leaders = np.zeros((0, 3))
    leader_se: list[float] = []
    for group, d in zip(groups, dirs):
        group_se = combined(group)
        close = [
            k
            for k in range(len(leaders))
            if _angle(leaders[k], d) <= allowed(leader_se[k], group_se)
        ]
        if close:
            merged[close[0]].extend(group)
        else:
            merged.append(list(group))
            leaders = np.vstack([leaders, d])
            leader_se.append(group_se)
    merged_dirs = [
        _principal(axes[g], dir_weight[g])
        if len(g) > 1
        else axes[g[0]] / np.linalg.norm(axes[g[0]])
        for g in merged
    ]
    order = np.argsort([-weights[g].sum() for g in merged])
    merged = [merged[k] for k in order]
    merged_dirs = [merged_dirs[k] for k in order]

    cluster_of = np.zeros(n, int)
    relations: list[list[str]] = [[] for _ in range(n)]
    # Fixed directions as (regular direction, label, measured direction). Relations are found
    # between measured directions, so snaps cannot chain: a pipe 2.1 degrees off square to
    # another is not made square because the other was first made horizontal.
    fixed: list[tuple[np.ndarray, str, np.ndarray, float, list[int]]] = [
        (_Z, "vertical", _Z, 0.0, [])
    ]
    final_dirs = []
    for index, (group, d) in enumerate(zip(merged, merged_dirs)):
        cluster_of[group] = index
        measured = d
        d_se = combined(group)
        rel: list[str] = []
        if len(group) > 1:
            lead = names[max(group, key=lambda m: weights[m])]
            for member in group:
                if forced[member] and any(forced[o] for o in group if o != member):
                    relations[member].append("coaxial run")
                elif names[member] != lead:
                    relations[member].append(f"parallel to {lead}")
        # parallel to a fixed direction (vertical, or an earlier cluster)?
        snapped = False
        for f, label, seen, f_se, _ in fixed:
            limit = allowed(d_se, f_se)
            if _angle(measured, seen) <= limit and _angle(measured, f) <= limit:
                d = f * np.sign(float(d @ f) or 1.0)
                rel.append(label if label == "vertical" else f"parallel to {label}")
                snapped = True
                break
        if not snapped:
            near_perp = [
                (f, label, f_se)
                for f, label, seen, f_se, _ in fixed
                if abs(90.0 - _angle(measured, seen)) <= allowed(d_se, f_se)
            ]
            kept: list[str] = []
            if near_perp:
                limit = allowed(d_se, max(f_se for _, _, f_se in near_perp))
                d, kept = _make_perpendicular(d, [(f, lab) for f, lab, _ in near_perp], limit)
                for label in kept:
                    rel.append("horizontal" if label == "vertical" else f"perpendicular to {label}")
            partners = set().union(*(elbow_partners.get(m, set()) for m in group))
            for f, label, seen, f_se, f_group in fixed:
                limit = allowed(d_se, f_se)
                if not partners.intersection(f_group) or abs(45.0 - _angle(measured, seen)) > limit:
                    continue
                square_to = [g for g, lab, _ in near_perp if lab in kept]
                new = _at_45_degrees(d, f, square_to)
                if new is not None and _angle(new, measured) <= limit + 1e-9:
                    d = new
                    rel.append(f"45 degrees to {label}")
                    break
        lead_name = names[max(group, key=lambda m: weights[m])]
        fixed.append((d, lead_name, measured, d_se, list(group)))
        final_dirs.append(d)
        for member in group:
            relations[member].extend(rel)

    new_axes = np.empty_like(axes)
    angles = np.empty(n)
    for i in range(n):
        d = final_dirs[cluster_of[i]]
        d = d if float(d @ axes[i]) >= 0 else -d
        new_axes[i] = d
        angles[i] = float(np.degrees(np.arccos(np.clip(float(d @ axes[i]), -1.0, 1.0))))
    return DirectionResult(new_axes, tuple(tuple(r) for r in relations), angles, cluster_of)


def _project_out(d: np.ndarray, directions: list[np.ndarray]) -> np.ndarray | None:
    basis: list[np.ndarray] = []
    for f in directions:
        g = f - sum((f @ b) * b for b in basis)
        norm = np.linalg.norm(g)
        if norm > 1e-9:
            basis.append(g / norm)
    projected = d - sum((d @ b) * b for b in basis)
    norm = np.linalg.norm(projected)
    return projected / norm if norm > 1e-9 else None


def _at_45_degrees(d: np.ndarray, f: np.ndarray, square_to: list[np.ndarray]):
    """The direction nearest ``d`` (3,) at exactly 45 degrees to the line ``f`` (3,) and still
    perpendicular to every direction in ``square_to``: ``d`` turned in the plane of ``d`` and
    ``f`` (None when ``f`` is not itself perpendicular to ``square_to``, or ``d`` lies along
    ``f``)."""
    if any(abs(float(f @ g)) > 1e-6 for g in square_to):
        return None
    across = _project_out(d, [f, *square_to])
    if across is None:
        return None
    along = f if float(d @ f) >= 0.0 else -f
    return (along + across) / np.sqrt(2.0)


def _make_perpendicular(d, near_perp, tol_deg):
    """Project ``d`` to be exactly perpendicular to as many of the fixed directions as possible
    (all of them, else the single first one that works) without turning it by more than
    ``tol_deg``; return the new direction and the labels it was made perpendicular to."""
    options = [near_perp] + [[item] for item in near_perp]
    for option in options:
        new = _project_out(d, [f for f, _ in option])
        if new is not None and _angle(new, d) <= tol_deg + 1e-9:
            return new, [label for _, label in option]
    return d, []


def perpendicular_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (3,) perpendicular to ``axis`` and to each other."""
    x, y, z = (float(c) for c in axis)
    if abs(x) < 0.9:  # cross with (1, 0, 0)
        u = np.array([0.0, z, -y])
    else:  # cross with (0, 1, 0)
        u = np.array([-z, 0.0, x])
    u /= np.sqrt(u @ u)
    v = np.array([y * u[2] - z * u[1], z * u[0] - x * u[2], x * u[1] - y * u[0]])
    return u, v


def align_lines(
    centers,
    axes,
    meets: Sequence[tuple[int, int]],
    coaxial: Sequence[tuple[int, int]],
    weights=None,
    *,
    delta: float = 1e-14,
    offsets=None,
) -> np.ndarray:
    """Shift lines sideways so that joined lines meet exactly.

    Minimises ``sum_i w_i |t_i|^2`` over sideways offsets ``t_i`` (perpendicular to each axis)
    subject to the linear constraints: for each ``meets`` pair, ``c_i + t_i + s_i a_i =
    c_j + t_j + s_j a_j`` (3 rows, with free meeting parameters ``s``); for each ``coaxial``
    pair, ``(c_j + t_j - c_i - t_i)`` has no component across ``a_i`` (2 rows; or, with an
    offset ``e`` for the pair, its component across ``a_i`` is ``e``). It is solved as
    one sparse, regularised KKT system ``[[H, C^T], [C, -delta I]]`` (quasi-definite, so a
    sparse LU factorises it stably; ``delta`` keeps redundant constraints of closed loops
    solvable and equals a penalty of weight ``1/delta``); the meeting parameters carry a
    negligible weight (1e-13) so that ``H`` is positive definite.

    Parameters
    ----------
    centers : array_like, shape (n, 3), metres
        A point on each line.
    axes : array_like, shape (n, 3)
        Unit directions (kept as they are).
    meets : sequence of (int, int)
        Pairs of lines that must intersect (elbows, tee branches and runs).
    coaxial : sequence of (int, int)
        Pairs of parallel lines that must coincide (inline joints).
    weights : array_like, shape (n,), optional
        Resistance of each line to moving (default 1).
    delta : float
        Regularisation of the constraint block.
    offsets : sequence of (array_like (3,) or None), optional
        Per ``coaxial`` pair, the required sideways step (metres, perpendicular to ``a_i``)
        from line i to line j (an eccentric reducer); None or absent: coaxial.

    Returns
    -------
    ndarray, shape (n, 3), metres
        The new points; each moved perpendicular to its own axis only.
    """
    from scipy.sparse import coo_matrix, diags
    from scipy.sparse import hstack as shstack
    from scipy.sparse import vstack as svstack
    from scipy.sparse.linalg import spsolve

    centers = np.asarray(centers, float).reshape(-1, 3)
    axes = np.asarray(axes, float).reshape(-1, 3)
    n = len(centers)
    if n == 0 or (not meets and not coaxial):
        return centers.copy()
    weights = np.ones(n) if weights is None else np.asarray(weights, float).reshape(-1)
    involved = sorted({i for pair in list(meets) + list(coaxial) for i in pair})
    col = {i: 2 * k for k, i in enumerate(involved)}
    bases = {i: perpendicular_basis(axes[i]) for i in involved}
    n_off = 2 * len(involved)
    n_var = n_off + 2 * len(meets)
    rows: list[int] = []
    cols: list[int] = []
    vals: list[float] = []
    rhs: list[float] = []

    def put(row: int, i: int, vector, sign: float) -> None:
        u, v = bases[i]
        rows.extend((row, row))
        cols.extend((col[i], col[i] + 1))
        vals.extend((sign * float(u @ vector), sign * float(v @ vector)))

    row = 0
    eye = np.eye(3)
    for m, (i, j) in enumerate(meets):
        for k in range(3):
            put(row, i, eye[k], 1.0)
            put(row, j, eye[k], -1.0)
            rows.extend((row, row))
            cols.extend((n_off + 2 * m, n_off + 2 * m + 1))
            vals.extend((axes[i][k], -axes[j][k]))
            rhs.append(centers[j][k] - centers[i][k])
            row += 1
    offsets = list(offsets) if offsets is not None else []
    for pair, (i, j) in enumerate(coaxial):
        step = offsets[pair] if pair < len(offsets) and offsets[pair] is not None else np.zeros(3)
        for w in bases[i]:
            put(row, j, w, 1.0)
            put(row, i, w, -1.0)
            rhs.append(float(w @ (centers[i] - centers[j] + np.asarray(step, float))))
            row += 1
    h = np.full(n_var, 1e-13)
    for i in involved:
        h[col[i]] = h[col[i] + 1] = max(float(weights[i]), 1e-9)
    rhs_full = np.concatenate([np.zeros(n_var), np.asarray(rhs)])
    if n_var + row <= 400:  # small spools: the same system, dense
        c_dense = np.zeros((row, n_var))
        np.add.at(c_dense, (np.asarray(rows, int), np.asarray(cols, int)), vals)
        kkt_dense = np.block([[np.diag(h), c_dense.T], [c_dense, -delta * np.eye(row)]])
        solution = np.linalg.solve(kkt_dense, rhs_full)
    else:
        constraints = coo_matrix((vals, (rows, cols)), shape=(row, n_var)).tocsr()
        kkt = svstack(
            [
                shstack([diags(h), constraints.T]),
                shstack([constraints, diags(np.full(row, -delta))]),
            ]
        ).tocsc()
        solution = spsolve(kkt, rhs_full)
    new = centers.copy()
    for i in involved:
        u, v = bases[i]
        new[i] = centers[i] + solution[col[i]] * u + solution[col[i] + 1] * v
    return new


#: A joint's axes may miss each other by this many combined standard errors before the shift
#: that makes them meet is reported (as merging's diameter windows and regularisation).
FIT_UP_SIGMA = 3.0
#: ... and by at least this much (metres): three times the 2 mm prior range noise, the fits'
#: outlier cutoff; fitted axes carry a few millimetres of bias no standard error describes.
FIT_UP_FLOOR = 0.006


@dataclass(frozen=True)
class FitUp:
    """How far the axes of two joined pipes missed each other before :func:`align_lines`.

    Attributes
    ----------
    pipes : (int, int)
    miss : float
        Closest distance between the two lines near the joint (metres): lines that must meet
        (elbows, tees) at their closest points, coaxial ones across the run at the joint.
    stderr : float
        Its standard error (metres): the two axis positions' errors there in quadrature.
    allowed : float
        ``max(FIT_UP_SIGMA x stderr, FIT_UP_FLOOR)``.
    point : ndarray, shape (3,)
        Where (metres).
    """

    pipes: tuple[int, int]
    miss: float
    stderr: float
    allowed: float
    point: np.ndarray

    @property
    def deviates(self) -> bool:
        """Whether the miss is beyond what the fits' uncertainty explains."""
        return self.miss > self.allowed


def fit_up(centers, axes, meets, coaxial, center_se, axis_se_deg, skip=()) -> list[FitUp]:
    """The miss of every joined pair's lines before alignment (see :class:`FitUp`).

    ``centers`` (n, 3) m and ``axes`` (n, 3) are the lines :func:`align_lines` is given;
    ``meets`` and ``coaxial`` its pairs; ``center_se`` (n,) m and ``axis_se_deg`` (n,) each
    fit's ``center`` and ``axis_deg`` standard errors. Each line's position error at the joint
    is ``sqrt(se_center^2 + (s se_axis)^2)``, ``s`` the distance along it from its centre. A
    pair in ``skip`` (an eccentric reducer: offset on purpose), or with a standard error
    unknown, is left out: errors only when certain.
    """
    c = np.asarray(centers, float)
    a = np.asarray(axes, float)
    found = []
    for pairs, meet in ((meets, True), (coaxial, False)):
        for i, j in pairs:
            if (i, j) in skip or (j, i) in skip:
                continue
            if meet and abs(float(a[i] @ a[j])) < 1.0 - 1e-9:
                _, _, qi, qj = line_closest_points(c[i], a[i], c[j], a[j])
                point = 0.5 * (qi + qj)
                miss = float(np.linalg.norm(qi - qj))
            else:
                # coaxial (or parallel): the step across the run halfway between the centres
                point = 0.5 * (c[i] + c[j])
                d = a[i]
                step = (c[j] - c[i]) - float((c[j] - c[i]) @ d) * d
                miss = float(np.linalg.norm(step))
            sig = []
            for k in (i, j):
                s = float((point - c[k]) @ a[k])
                sig.append(np.hypot(center_se[k], s * np.radians(axis_se_deg[k])))
            se = float(np.hypot(*sig))
            if not np.isfinite(se):
                continue
            allowed = max(FIT_UP_SIGMA * se, FIT_UP_FLOOR)
            found.append(FitUp((int(i), int(j)), miss, se, allowed, point))
    return found
