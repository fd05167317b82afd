"""The raster of an object's window and the range that separates it from its background.

Pure geometry of :mod:`asbuilt.drivers.session`'s acquisition: the cell-centred serpentine
raster a window is shot with, and the split of a raster's ranges into the aimed-at object and
what lies behind it.
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from .plan import Window

__all__ = ["foreground_threshold", "grid"]


def grid(
    window: Window, n: int, min_cells: int | tuple[int, int] = 3
) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """A cell-centred raster of at least ``n`` shots over ``window``, serpentine row order.

    Parameters
    ----------
    window : Window
    n : int
        Minimum number of shots.
    min_cells : int or (int, int)
        Fewest rows and fewest columns (one number for both, or ``(rows, cols)``).

    Returns
    -------
    pan, tilt : ndarray, shape (rows * cols,), radians
        Shot directions (unit angles), in shooting order.
    shape : (int, int)
        ``(rows, cols)``; shot ``k`` is cell ``(k // cols, k % cols)`` with odd rows reversed.
    """
    min_rows, min_cols = (min_cells, min_cells) if isinstance(min_cells, int) else min_cells
    aspect = window.width / window.height
    cols = max(min_cols, int(round(math.sqrt(n * aspect))))
    rows = max(min_rows, math.ceil(n / cols))
    pans = window.pan_min + (np.arange(cols) + 0.5) * window.width / cols
    tilts = window.tilt_min + (np.arange(rows) + 0.5) * window.height / rows
    pan = np.empty(rows * cols)
    tilt = np.empty(rows * cols)
    for r in range(rows):
        order = pans if r % 2 == 0 else pans[::-1]
        pan[r * cols : (r + 1) * cols] = order
        tilt[r * cols : (r + 1) * cols] = tilts[r]
    return pan, tilt, (rows, cols)


def _cell_index(rows: int, cols: int) -> np.ndarray:
    """Shot index of each grid cell, shape (rows, cols) (undoes the serpentine order)."""
    idx = np.arange(rows * cols).reshape(rows, cols)
    idx[1::2] = idx[1::2, ::-1]
    return idx


def foreground_threshold(ranges: Iterable[float | None]) -> float:
    """Range separating the aimed-at object from the background behind it, metres.

    The valid ranges are sorted and split at their largest gap when that gap exceeds
    ``max(0.1 m, 5 % of the range before it)``; ``inf`` when there is no such gap (everything
    valid is on the object).
    """
    valid = np.sort([r for r in ranges if r is not None])
    if len(valid) < 2:
        return math.inf
    gaps = np.diff(valid)
    i = int(np.argmax(gaps))
    if gaps[i] > max(0.1, 0.05 * valid[i]):
        return float(0.5 * (valid[i] + valid[i + 1]))
    return math.inf
