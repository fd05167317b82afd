"""Joint diameter estimation: contiguous pipes of one size share one estimate.

The paper (Kwon et al., "Primitives merging and compliance checking") notes that "the two
diameters of scanned pipes known to be contiguous in a pipe spool can be equalized". Here the
pipes joined directly (by any joint) whose fitted ODs agree within
``max(3 x the combined standard error, diameter tolerance)`` form a **run**, built by
union-find over the joints; a run breaks where the sizes clearly differ (a reducer, or a
reducing tee). Each run gets the inverse-variance weighted mean of its members' ODs (its
standard error shrinks as ``1/sqrt(sum of weights)``), and that one estimate is snapped, so three
20-point fits together decide the size better than any one alone.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["same_size", "find_runs", "joint_estimate"]


def same_size(od_a: float, se_a: float, od_b: float, se_b: float, tolerance: float) -> bool:
    """True when two OD estimates (metres, with standard errors) may be one size.

    The test is ``|od_a - od_b| <= max(3 * sqrt(se_a**2 + se_b**2), tolerance)``; unknown
    (NaN) standard errors count as zero.
    """
    se_a = se_a if np.isfinite(se_a) else 0.0
    se_b = se_b if np.isfinite(se_b) else 0.0
    return abs(od_a - od_b) <= max(3.0 * float(np.hypot(se_a, se_b)), tolerance)


class _UnionFind:
    def __init__(self, n: int):
        self.parent = list(range(n))

    def find(self, a: int) -> int:
        while self.parent[a] != a:
            self.parent[a] = self.parent[self.parent[a]]
            a = self.parent[a]
        return a

    def union(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[max(ra, rb)] = min(ra, rb)


def find_runs(
    ods: Sequence[float],
    stderrs: Sequence[float],
    pairs: Sequence[tuple[int, int]],
    tolerance: float,
) -> list[list[int]]:
    """Group pipes into runs of one size.

    Parameters
    ----------
    ods, stderrs : sequence of float, shape (n,), metres
        Each pipe's fitted OD and its standard error.
    pairs : sequence of (int, int)
        Pipes joined directly.
    tolerance : float
        ``Tolerances.diameter_tolerance``, metres.

    Returns
    -------
    list of list of int
        Every pipe index in exactly one run, runs ordered by their smallest index.
    """
    n = len(ods)
    uf = _UnionFind(n)
    for a, b in pairs:
        if same_size(ods[a], stderrs[a], ods[b], stderrs[b], tolerance):
            uf.union(a, b)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(uf.find(i), []).append(i)
    return sorted(groups.values(), key=lambda g: g[0])


def joint_estimate(
    ods: Sequence[float], stderrs: Sequence[float], floor: float = 1e-4
) -> tuple[float, float]:
    """Inverse-variance weighted mean of several OD estimates of one size.

    Parameters
    ----------
    ods, stderrs : sequence of float, metres
        Estimates and their standard errors (unknown ones, NaN, get the largest known error,
        or ``floor`` when none is known).
    floor : float
        Smallest standard error allowed, metres (keeps weights finite on noise-free data).

    Returns
    -------
    od, stderr : float
        The weighted mean and its standard error ``1 / sqrt(sum of weights)``, metres, scaled
        up by the Birge ratio ``sqrt(chi2 / (n - 1))`` when the estimates scatter more than their
        errors say (``chi2 = sum w_i (od_i - mean)^2``), so that inconsistent fits do not
        produce an over-confident joint estimate.
    """
    ods = np.asarray(ods, dtype=float)
    se = np.asarray(stderrs, dtype=float)
    known = np.isfinite(se) & (se > 0)
    fill = float(se[known].max()) if known.any() else floor
    se = np.where(known, se, fill)
    se = np.maximum(se, floor)
    weights = 1.0 / se**2
    mean = float(np.sum(weights * ods) / np.sum(weights))
    stderr = float(1.0 / np.sqrt(np.sum(weights)))
    if len(ods) > 1:
        chi2 = float(np.sum(weights * (ods - mean) ** 2))
        stderr *= max(1.0, float(np.sqrt(chi2 / (len(ods) - 1))))
    return mean, stderr
