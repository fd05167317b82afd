"""numpy's own LAPACK calls on small float64 matrices, without :mod:`numpy.linalg`'s wrappers.

A sparse scan's fit solves, decomposes and inverts a few dozen 3 x 3 or 5 x 5 matrices, where
:func:`numpy.linalg.eigh` and its siblings spend about three quarters of their 15 microseconds
in Python (argument checks, type promotion, an error-state context with a callback that turns
a LAPACK failure into :class:`numpy.linalg.LinAlgError`). The functions here call the same
generalised ufuncs (``numpy.linalg._umath_linalg``) with the same signatures, so their results
are the same bits; a LAPACK failure (or a non-finite input) leaves NaN in the output, and then
the public function is called instead and decides, raising or returning exactly as before.
Inputs other than float64 arrays go to the public function too.

``numpy.linalg._umath_linalg`` is private: when it is missing, or (checked once at import on a
small matrix) lacks one of these functions or gives other bits than the public one (another
numpy), every function here is the public one.
"""

from __future__ import annotations

import numpy as np

try:  # numpy >= 2
    from numpy.linalg import _umath_linalg as _gufuncs
except ImportError:  # pragma: no cover - older or other numpy builds
    _gufuncs = None


def _same_as_public(gufuncs) -> bool:
    """Whether ``gufuncs`` has the seven gufuncs with these signatures and they give the
    public functions' bits on a small matrix: a numpy that renamed or changed them (they are
    private) falls back to :mod:`numpy.linalg` instead of failing or differing."""
    a = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.25], [0.5, 0.25, 2.0]])
    b = np.array([[1.0], [2.0], [3.0]])
    try:
        with np.errstate(all="ignore"):
            checks = (
                (gufuncs.eigh_lo(a, signature="d->dd"), np.linalg.eigh(a)),
                ((gufuncs.eigvalsh_lo(a, signature="d->d"),), (np.linalg.eigvalsh(a),)),
                ((gufuncs.solve(a, b, signature="dd->d"),), (np.linalg.solve(a, b),)),
                ((gufuncs.solve1(a, b[:, 0], signature="dd->d"),), (np.linalg.solve(a, b[:, 0]),)),
                ((gufuncs.svd(a, signature="d->d"),), (np.linalg.svd(a, compute_uv=False),)),
                ((gufuncs.inv(a, signature="d->d"),), (np.linalg.inv(a),)),
                (gufuncs.svd_s(a, signature="d->ddd"), np.linalg.svd(a, full_matrices=False)),
            )
        return all(
            all(np.array_equal(mine, theirs) for mine, theirs in zip(ours, public, strict=True))
            for ours, public in checks
        )
    except Exception:  # noqa: BLE001 - any failure means: do not use them
        return False


if _gufuncs is not None and not _same_as_public(_gufuncs):  # pragma: no cover - other numpy
    _gufuncs = None

__all__ = ["eigh", "eigvalsh", "inv", "singular_values", "solve", "svd"]

_FLOAT64 = np.dtype(np.float64)


def _direct(*arrays) -> bool:
    """Whether the gufuncs may take these arrays directly (float64 ndarrays)."""
    return _gufuncs is not None and all(
        type(a) is np.ndarray and a.dtype == _FLOAT64 for a in arrays
    )


def eigh(a: np.ndarray):
    """:func:`numpy.linalg.eigh` (lower triangle) of float64 ``a`` (..., m, m): ``(w, v)``."""
    if _direct(a) and a.ndim >= 2 and a.shape[-1] == a.shape[-2]:
        with np.errstate(all="ignore"):
            w, v = _gufuncs.eigh_lo(a, signature="d->dd")
        if np.isfinite(w).all():
            return w, v
    return tuple(np.linalg.eigh(a))


def eigvalsh(a: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.eigvalsh` (lower triangle) of float64 ``a`` (..., m, m)."""
    if _direct(a) and a.ndim >= 2 and a.shape[-1] == a.shape[-2]:
        with np.errstate(all="ignore"):
            w = _gufuncs.eigvalsh_lo(a, signature="d->d")
        if np.isfinite(w).all():
            return w
    return np.linalg.eigvalsh(a)


def solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.solve` of float64 ``a`` (..., m, m) and ``b`` (..., m, k), or ``b``
    (m,) with ``a`` (m, m)."""
    if _direct(a, b) and a.ndim >= 2 and a.shape[-1] == a.shape[-2]:
        # numpy's own choice of gufunc: solve1 for one right-hand side vector
        gufunc = _gufuncs.solve1 if b.ndim == 1 else _gufuncs.solve if b.ndim == a.ndim else None
        if gufunc is not None:
            with np.errstate(all="ignore"):
                x = gufunc(a, b, signature="dd->d")
            if np.isfinite(x).all():
                return x
    return np.linalg.solve(a, b)


def inv(a: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.inv` of float64 ``a`` (..., m, m)."""
    if _direct(a) and a.ndim >= 2 and a.shape[-1] == a.shape[-2]:
        with np.errstate(all="ignore"):
            x = _gufuncs.inv(a, signature="d->d")
        if np.isfinite(x).all():
            return x
    return np.linalg.inv(a)


def svd(a: np.ndarray):
    """:func:`numpy.linalg.svd` of float64 ``a`` (..., m, n) with ``full_matrices=False``:
    ``(u, s, vh)``."""
    if _direct(a) and a.ndim >= 2:
        with np.errstate(all="ignore"):
            u, s, vh = _gufuncs.svd_s(a, signature="d->ddd")
        if np.isfinite(s).all():
            return u, s, vh
    return tuple(np.linalg.svd(a, full_matrices=False))


def singular_values(a: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.svd` of float64 ``a`` (..., m, n) with ``compute_uv=False``."""
    if _direct(a) and a.ndim >= 2:
        with np.errstate(all="ignore"):
            s = _gufuncs.svd(a, signature="d->d")
        if np.isfinite(s).all():
            return s
    return np.linalg.svd(a, compute_uv=False)
