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

__all__ = ["eigh", "eigvalsh", "inv", "pinv", "singular_values", "solve", "svd"]


def _raise_singular(error, flag):
    raise np.linalg.LinAlgError("Singular matrix")


def _raise_not_converged(error, flag):
    raise np.linalg.LinAlgError("Eigenvalues did not converge")


def _raise_svd_not_converged(error, flag):
    raise np.linalg.LinAlgError("SVD did not converge")


def solve(normal: np.ndarray, right: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.solve` of float64 stacks ``normal`` (..., m, m) and ``right``
    (..., m, k) (LinAlgError when a matrix is singular)."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.solve(normal, right)
    with np.errstate(
        call=_raise_singular, invalid="call", over="ignore", divide="ignore", under="ignore"
    ):
        return _umath_linalg.solve(normal, right, signature="dd->d")


def eigh(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`numpy.linalg.eigh` of a float64 symmetric matrix (..., m, m) from its lower
    triangle: eigenvalues ascending (..., m) and eigenvectors as columns (..., m, m)."""
    if _umath_linalg is None:  # pragma: no cover
        return tuple(np.linalg.eigh(matrix))
    with np.errstate(
        call=_raise_not_converged, invalid="call", over="ignore", divide="ignore", under="ignore"
    ):
        return _umath_linalg.eigh_lo(matrix, signature="d->dd")


def eigvalsh(matrix: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.eigvalsh` of a float64 symmetric matrix (..., m, m) from its lower
    triangle: eigenvalues ascending (..., m)."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.eigvalsh(matrix)
    with np.errstate(
        call=_raise_not_converged, invalid="call", over="ignore", divide="ignore", under="ignore"
    ):
        return _umath_linalg.eigvalsh_lo(matrix, signature="d->d")


def inv(matrix: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.inv` of a float64 matrix (..., m, m) (LinAlgError when singular)."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.inv(matrix)
    with np.errstate(
        call=_raise_singular, invalid="call", over="ignore", divide="ignore", under="ignore"
    ):
        return _umath_linalg.inv(matrix, signature="d->d")


#: numpy.linalg's error state for its SVD gufuncs: a failure to converge raises, as there.
_SVD_ERRORS = {
    "call": _raise_svd_not_converged,
    "invalid": "call",
    "over": "ignore",
    "divide": "ignore",
    "under": "ignore",
}


def svd(matrix: np.ndarray, full_matrices: bool = False):
    """:func:`numpy.linalg.svd` of a float64 matrix (..., m, k): ``(u, s, vh)``, reduced
    unless ``full_matrices`` (the public function's default is full)."""
    if _umath_linalg is None:  # pragma: no cover
        return tuple(np.linalg.svd(matrix, full_matrices=full_matrices))
    gufunc = _umath_linalg.svd_f if full_matrices else _umath_linalg.svd_s
    with np.errstate(**_SVD_ERRORS):
        return gufunc(matrix, signature="d->ddd")


def singular_values(matrix: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.svd` of a float64 matrix (..., m, k) with ``compute_uv=False``: the
    singular values, descending."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.svd(matrix, compute_uv=False)
    with np.errstate(**_SVD_ERRORS):
        return _umath_linalg.svd(matrix, signature="d->d")


def pinv(matrix: np.ndarray) -> np.ndarray:
    """:func:`numpy.linalg.pinv` of a float64 matrix (m, k) at its default ``rcond`` (1e-15):
    numpy's own steps (reduced SVD, singular values at most ``rcond`` times the largest set to
    zero, ``vt.T @ (s^-1 u.T)``) on :func:`svd`, without the public function's checks."""
    if _umath_linalg is None:  # pragma: no cover
        return np.linalg.pinv(matrix)
    u, s, vt = svd(matrix)
    cutoff = np.asarray(1e-15)[..., np.newaxis] * np.maximum.reduce(s, axis=-1, keepdims=True)
    large = s > cutoff
    s = np.divide(1, s, where=large, out=s)
    s[~large] = 0
    return np.matmul(
        np.swapaxes(vt, -1, -2), np.multiply(s[..., np.newaxis], np.swapaxes(u, -1, -2))
    )
