"""Neighbourhoods of sparse points: k nearest neighbours, the local plane normals of the
cuboid segmentation (:mod:`asbuilt.fit._faces`), and connected groups of linked shots.

Everything is numpy (metres, unit vectors); a k-d tree (scipy) above 256 points.
"""

from __future__ import annotations

import numpy as np

from asbuilt.fit._small_linalg import eigh

__all__ = ["components", "knn", "local_normals"]


def knn(points: np.ndarray, k: int) -> np.ndarray:
    """Indices of each point's ``k`` nearest neighbours (itself excluded).

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    k : int
        Clipped to ``n - 1``.

    Returns
    -------
    ndarray, shape (n, k), int
    """
    n = points.shape[0]
    k = max(1, min(k, n - 1))
    if n > 256:
        from scipy.spatial import cKDTree

        _, index = cKDTree(points).query(points, k=k + 1)
        return index[:, 1:]
    # Squared distances coordinate by coordinate, summed in the order ``sum(axis=2)`` of the
    # (n, n, 3) differences adds them (same bits): that array's rows of three cost more to
    # broadcast and reduce than three (n, n) ones.
    cols = points.T
    d2 = (cols[0][:, None] - cols[0]) ** 2
    d2 += (cols[1][:, None] - cols[1]) ** 2
    d2 += (cols[2][:, None] - cols[2]) ** 2
    np.fill_diagonal(d2, np.inf)
    index = np.argpartition(d2, k - 1, axis=1)[:, :k]
    order = np.take_along_axis(d2, index, axis=1).argsort(axis=1)
    return np.take_along_axis(index, order, axis=1)


def local_normals(points: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unoriented unit normals and plane RMS of each point's k-neighbourhood (PCA).

    Parameters
    ----------
    points : ndarray, shape (n, 3), metres
    k : int
        Neighbours per point (the point itself is added).

    Returns
    -------
    normals : ndarray, shape (n, 3)
        Eigenvector of the smallest eigenvalue of the neighbourhood covariance.
    rms : ndarray, shape (n,), metres
        Root of that eigenvalue, corrected for the 3 fitted parameters.
    index : ndarray, shape (n, k), int
        The neighbours (:func:`knn`).
    """
    index = knn(points, k)
    hood = np.concatenate([points[:, None, :], points[index]], axis=1)
    # The neighbourhoods' means: their rows summed one after another and divided, as
    # ``hood.mean(axis=1)`` reduces along that axis, without the strided reduction.
    total = hood[:, 0] + hood[:, 1]
    for j in range(2, hood.shape[1]):
        total += hood[:, j]
    centred = hood - (total / hood.shape[1])[:, None, :]
    cov = np.einsum("nki,nkj->nij", centred, centred) / hood.shape[1]
    values, vectors = eigh(cov)
    dof = max(hood.shape[1] - 3, 1)
    rms = np.sqrt(np.clip(values[:, 0], 0.0, None) * hood.shape[1] / dof)
    return vectors[:, :, 0], rms, index


def components(m: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Connected-component label (m,) int (the least member's index) of m nodes joined by the
    edges i-j (each (e,) int); min-label propagation with pointer jumping (a face or a scan
    has tens of shots: cheaper than importing and calling scipy's graph routines)."""
    group = np.arange(m)
    while True:
        low = np.minimum(group[i], group[j])
        fresh = group.copy()
        np.minimum.at(fresh, i, low)
        np.minimum.at(fresh, j, low)
        fresh = fresh[fresh]
        if not (fresh != group).any():  # np.array_equal of two (m,) int arrays, unwrapped
            return group
        group = fresh
