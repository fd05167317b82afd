"""numpy.linalg's solve, eigh, eigvalsh, inv and svd of small stacked matrices, without the
public functions' argument checks and wrapping.

Private helper of the cylinder fit. On the few 3 x 3 matrices its starts solve and decompose,
and the few (m, 3) and (m, 5) ones its checks and covariance take apart,
:func:`numpy.linalg.solve`, :func:`numpy.linalg.eigh` and the others spend more on checking and
wrapping their arguments than on LAPACK. These call the same generalised ufuncs (numpy's private
``_umath_linalg``, there since numpy 1.8) under the same floating-point error handling, so they
return the same values bit for bit and raise the same LinAlgError; float64 arrays only.
"""

from __future__ import annotations

import numpy as np

try:
    from numpy.linalg import _umath_linalg
except ImportError:  # pragma: no cover - a numpy without it: the public functions
    _umath_linalg = None
if _umath_linalg is not None and not all(
    hasattr(_umath_linalg, name)
    for name in ("solve", "eigh_lo", "eigvalsh_lo", "inv", "svd", "svd_s", "svd_f")
):  # pragma: no cover - renamed in some numpy: the public functions
    _umath_linalg = None

try:  # the context variable np.errstate sets, and how it makes the value it sets
    from numpy._core._ufunc_config import _extobj_contextvar as _ERROR_STATE
    from numpy._core.umath import _make_extobj
except ImportError:  # pragma: no cover - another numpy: np.errstate each call
    _ERROR_STATE = None

__all__ = ["eigh", "eigvalsh", "inv", "singular_values", "solve", "svd"]


def _errors(raise_error) -> tuple[dict, object]:
    """numpy.linalg's floating-point error state around its gufuncs (a failure raises through
    ``raise_error``), as np.errstate's arguments and as the value np.errstate would set, made
    once: on these small matrices creating and entering an np.errstate each call costs about
    half as much as the decomposition itself. (Its buffer size is the one at import, numpy's
    default unless changed before: these gufuncs run on float64 without casting, unbuffered.)"""
    errors = {"call": raise_error, "invalid": "call", "over": "ignore", "divide": "ignore"}
    errors["under"] = "ignore"
    state = None if _ERROR_STATE is None else _make_extobj(all=None, **errors)
    return errors, state


def _raise_singular(error, flag):
    raise np.linalg.LinAlgError("Singular matrix")


def _raise_not_converged(error, flag):
    raise np.linalg.LinAlgError("Eigenvalues did not converge")


def _raise_svd_not_converged(error, flag):
    raise np.linalg.LinAlgError("SVD did not converge")


_SINGULAR = _errors(_raise_singular)
_NOT_CONVERGED = _errors(_raise_not_converged)
_SVD_NOT_CONVERGED = _errors(_raise_svd_not_converged)


def _under(errors, gufunc, *args, signature: str):
    """``gufunc(*args)`` under the error state ``errors`` (:func:`_errors`), set and reset as
    np.errstate does."""
    arguments, state = errors
    if state is None:  # pragma: no cover - another numpy
        with np.errstate(**arguments):
            return gufunc(*args, signature=signature)
    token = _ERROR_STATE.set(state)
    try:
        return gufunc(*args, signature=signature)
    finally:
        _ERROR_STATE.reset(token)


def solve(normal: np.ndarray, right: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.solve` of float64 stacks ``normal`` (..., m, m) and ``right``
    (..., m, k) (LinAlgError when a matrix is singular)."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.solve(normal, right)
    return _under(_SINGULAR, _umath_linalg.solve, normal, right, signature="dd->d")


def eigh(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`numpy.linalg.eigh` of a float64 symmetric matrix (..., m, m) from its lower
    triangle: eigenvalues ascending (..., m) and eigenvectors as columns (..., m, m)."""
    if _umath_linalg is None:  # pragma: no cover
        return tuple(np.linalg.eigh(matrix))
    return _under(_NOT_CONVERGED, _umath_linalg.eigh_lo, matrix, signature="d->dd")


def eigvalsh(matrix: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.eigvalsh` of a float64 symmetric matrix (..., m, m) from its lower
    triangle: eigenvalues ascending (..., m)."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.eigvalsh(matrix)
    return _under(_NOT_CONVERGED, _umath_linalg.eigvalsh_lo, matrix, signature="d->d")


def inv(matrix: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.inv` of a float64 matrix (..., m, m) (LinAlgError when singular)."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.inv(matrix)
    return _under(_SINGULAR, _umath_linalg.inv, matrix, signature="d->d")


def svd(matrix: np.ndarray, full_matrices: bool = False):
    """:func:`numpy.linalg.svd` of a float64 matrix (..., m, k): ``(u, s, vh)``, reduced
    unless ``full_matrices`` (the public function's default is full)."""
    if _umath_linalg is None:  # pragma: no cover
        return tuple(np.linalg.svd(matrix, full_matrices=full_matrices))
    gufunc = _umath_linalg.svd_f if full_matrices else _umath_linalg.svd_s
    return _under(_SVD_NOT_CONVERGED, gufunc, matrix, signature="d->ddd")


def singular_values(matrix: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.svd` of a float64 matrix (..., m, k) with ``compute_uv=False``: the
    singular values, descending."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.svd(matrix, compute_uv=False)
    return _under(_SVD_NOT_CONVERGED, _umath_linalg.svd, matrix, signature="d->d")
