"""Likelihood of a fit's residuals as a mixture of Gaussian inliers and uniform outliers.

Private helper of :mod:`asbuilt.fit` (Torr's robust mixture, as in GRIC: Torr 1998, "Geometric
motion segmentation and model selection"); lengths in metres.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mixture_score", "mixing_cost"]


def mixture_score(residuals, mask, extent, floor) -> float:
    """Minus twice the log-likelihood of a fit's residuals as Gaussian inliers and uniform outliers.

    ``m (1 + ln(2 pi s^2)) + (n - m) 2 ln W`` with ``s`` the inliers' maximum-likelihood sigma
    and ``W`` the extent outliers may spread over (the mixture of Torr's GRIC, 1998).

    Parameters
    ----------
    residuals : ndarray, shape (n,), metres
    mask : ndarray, shape (n,), bool
        Inliers.
    extent : float, metres
    floor : float, metres
        Smallest sigma.

    Returns
    -------
    float
    """
    kept = residuals[mask]
    variance = max(float(np.mean(kept * kept)), floor * floor)
    m, n = kept.size, residuals.size
    return m * (1.0 + np.log(2.0 * np.pi * variance)) + (n - m) * 2.0 * np.log(max(extent, floor))


def mixing_cost(counts) -> float:
    """``-2 ln`` of a mixture's proportions at their maximum-likelihood values: ``-2 sum_k c_k
    ln(c_k / n)`` over the counts ``c_k`` of the points in each component (``n`` their sum).

    The term of the mixture likelihood that :func:`mixture_score` leaves out: the description
    length of which component each point belongs to (Rissanen's minimum description length).
    With the counts of inliers and outliers, it makes each outlier cost more than the uniform
    density over the points' extent; without it a box split into small flat patches of a
    sphere, fitting 60% of the shots to 0.2 mm, beats the sphere fitting them all to the noise.
    With the counts of each face's points too, it prices the segmentation, so that one noisy
    face split into parallel slices does not win by fitting each slice closer than the noise.

    Parameters
    ----------
    counts : sequence of int
        Points per component (inliers and outliers, or each face's inliers and the outliers).

    Returns
    -------
    float
    """
    counts = np.asarray([c for c in counts if c > 0], dtype=np.float64)
    if counts.size < 2:
        return 0.0
    return float(-2.0 * (counts * np.log(counts / counts.sum())).sum())
