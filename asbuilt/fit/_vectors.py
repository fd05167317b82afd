"""Small vector helpers of the cuboid fit: cross products and unit rows without numpy's
per-call overhead (these run thousands of times a fit on (k, 3) arrays of a few rows)."""

from __future__ import annotations

import math

import numpy as np

from asbuilt.fit._common import row_norms

__all__ = ["cross_rows", "cross3", "unit_rows", "perpendicular_basis"]


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of (k, 3) arrays (``a`` may also be one (3,) vector)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[:, 0], b[:, 1], b[:, 2]
    out = np.empty((b.shape[0], 3))
    out[:, 0] = a1 * b2 - a2 * b1
    out[:, 1] = a2 * b0 - a0 * b2
    out[:, 2] = a0 * b1 - a1 * b0
    return out


def cross3(a, b) -> np.ndarray:
    """Cross product of two (3,) vectors (faster than ``np.cross`` for one pair)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def unit_rows(vectors: np.ndarray, norms: np.ndarray | None = None):
    """Unit rows of ``vectors`` (k, 3) and which rows had a length (k,) bool; ``norms`` (k,),
    their lengths, may be passed when already computed."""
    if norms is None:
        norms = row_norms(vectors)
    ok = norms > 1e-12
    # The same division as ``vectors[ok] / norms[ok, None]``, in one call (a hot path).
    out = np.divide(vectors, norms[:, None], out=np.zeros_like(vectors), where=ok[:, None])
    return out, ok


def perpendicular_basis(direction: np.ndarray) -> np.ndarray:
    """Two unit columns, shape (3, 2), perpendicular to ``direction`` and to each other.

    The construction of :func:`asbuilt.fit._common.orthonormal_basis` (``u = d x e_least``,
    ``v = d x u``) with its own rounding (the norm by a numpy dot): about one direction in ten
    differs from it in the last bit, and the cuboid fits are pinned to this one, so the two are
    not merged without a new equivalence proof of those fits."""
    # Python floats: the same IEEE arithmetic as numpy's scalars, without their overhead.
    d = direction.tolist()
    helper = [0.0, 0.0, 0.0]
    helper[min(range(3), key=lambda k: abs(d[k]))] = 1.0  # the first smallest, as argmin
    first = cross3(d, helper)
    first /= math.sqrt(first @ first)  # np.linalg.norm's own sum for a vector, without its checks
    f = first.tolist()
    second = cross3(d, f)
    return np.array([[f[0], second[0]], [f[1], second[1]], [f[2], second[2]]])
