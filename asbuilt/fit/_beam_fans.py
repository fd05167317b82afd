"""Shots of one cuboid face that run along the beams: a fan through the station, not a surface.

Private helper of the cuboid joint fit (:mod:`asbuilt.fit._joint`). Lengths in metres, angles
in radians.

A pan-tilt raster's column of shots lies in one plane through the station whatever it hits,
and its range noise lies in that plane too. A raster column that grazes a box column's side
and the next column, which misses the box and reaches the wall behind, therefore lie in one
plane seen at 85-89 degrees incidence and fit it to a fraction of a millimetre: a "face"
whose shots are on the column and on the wall metres behind. Fitted as a side face, it made
box columns 0.3-0.6 m across tens of metres deep (their size along that face taken from the
wall's shots).

On a real face, shots next to each other on one raster line lie apart across the beams by
about the range times the angle between their beams, and their ranges differ by that spacing
times the tangent of the incidence. So the ranges of two such shots of one face may differ by
at most ``tan(MAX_INCIDENCE_DEG)`` times their spacing across the beams, plus the range noise:
the incidence at which the cuboid segmentation already stops trusting a face's raster spacing
(``asbuilt.fit._faces._MIN_STRETCHED_COS``, 80 degrees). A face whose shots fall apart into
groups that no such link joins holds shots spread along the beams; the group nearest the
station is the face (what lies behind it along the beams is background seen past the box),
and the others are left out of the face, to be outliers.

Past 80 degrees a real face can still go on: a beam receding from the station has its sides'
far part seen at 80-88 degrees, and its ranges along a raster line step by more than the
bound there. Such a far part lies on the plane of the near part's own shots, which a fan does
not: a group parted from the nearest ones is taken back into the face when every one of its
shots lies on the plane of the shots already taken (fitted to them alone, not to the face's
plane that the fit turned toward the fan), within the inlier cutoff grown by how far the
plane is carried past them. The near shots must span a plane for that (two raster lines or
more across it, ``_MIN_SPREAD_CUTOFFS``): one raster column on a column's side is a line,
the plane through it and the wall behind turns freely about it and predicts nothing, and the
wall stays out. A sparse raster leaves shots of a face with no raster neighbour on it: a
group is then linked to the group holding the shot nearest it in angle, by the same bound,
unless a raster link between the two failed it; only a step along the beams parts groups
(seven shots on a column's two faces had each lone shot left out, and the fit came out
35-45 degrees off). Measured on ray-cast receding beams 4-8 m long from 3-10 m (20-40 shots), the
fan rule alone cut 0.5-7 m off 64% of them.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.fit._common import row_norms
from asbuilt.fit._neighbours import components
from asbuilt.fit._small_linalg import singular_values, svd

__all__ = ["MAX_INCIDENCE_DEG", "beam_fan_shots", "neighbours", "raster_lines"]

#: Incidence (degrees) beyond which the range step between neighbouring shots of one face is
#: taken to run along the beams: the cuboid segmentation's cap on a face's stretched raster
#: spacing.
MAX_INCIDENCE_DEG = 80.0
_RANGE_PER_SPACING = math.tan(math.radians(MAX_INCIDENCE_DEG))
#: Range noise allowance of a link, in inlier cutoffs (each end's range is off by up to one).
_NOISE_CUTOFFS = 2.0
#: Shots closer than this share of the raster step in one angle are on one raster line.
_IN_LINE = 0.5
#: The near shots span a plane when their spread across the line they lie along (RMS, the
#: second principal axis) is at least this many inlier cutoffs: one raster line's shots are
#: off their line by the noise only.
_MIN_SPREAD_CUTOFFS = 3.0


def raster_lines(angles: np.ndarray, steps) -> tuple[np.ndarray, np.ndarray]:
    """The raster row and column of each shot, for :func:`neighbours`.

    Parameters
    ----------
    angles : ndarray, shape (n, 2), radians
        Each shot's pan and tilt from the station
        (:func:`asbuilt.fit._silhouette.shot_angles`).
    steps : array_like, shape (2,), radians
        The raster's pan and tilt steps.

    Returns
    -------
    ndarray, shape (n, 2), int
        Each shot's row id (tilts within ``_IN_LINE`` of a tilt step of the next) and column
        id (likewise in pan). Fill and bisection shots sit on the row or column they were shot
        along.
    """
    return np.column_stack(
        [
            _line_ids(angles[:, 1], _IN_LINE * float(steps[1])),
            _line_ids(angles[:, 0], _IN_LINE * float(steps[0])),
        ]
    )


def neighbours(angles: np.ndarray, lines: np.ndarray, among: np.ndarray):
    """The pairs of shots ``among`` (n,) bool next to each other on a raster row or column.

    ``angles`` (n, 2) radians and ``lines`` (n, 2) int as for :func:`raster_lines`. Returns
    ``i, j`` (p,) int, indices into the n shots: consecutive in pan along a row, or in tilt
    along a column, counting only the shots ``among``.
    """
    idx = among.nonzero()[0]
    firsts, seconds = [], []
    for along, line in ((0, lines[idx, 0]), (1, lines[idx, 1])):
        order = np.lexsort((angles[idx, along], line))
        same = line[order[1:]] == line[order[:-1]]
        firsts.append(idx[order[:-1][same]])
        seconds.append(idx[order[1:][same]])
    return np.concatenate(firsts), np.concatenate(seconds)


def _line_ids(values: np.ndarray, width: float) -> np.ndarray:
    """Ids (n,) int of the groups of ``values`` (n,) that lie within ``width`` of the next."""
    order = np.argsort(values, kind="stable")
    starts = np.concatenate([[0], (np.diff(values[order]) > width).astype(np.int64)])
    ids = np.empty(values.shape[0], dtype=np.int64)
    ids[order] = np.cumsum(starts)
    return ids


def beam_fan_shots(points, viewpoint, noise: float, pairs) -> np.ndarray:
    """Which shots of one face lie behind its nearest group along the beams, shape (m,) bool.

    Parameters
    ----------
    points : ndarray, shape (m, 3), metres
        The face's inlier shots.
    viewpoint : ndarray, shape (3,), metres
        The trusted station, in the same frame.
    noise : float, metres
        The inlier cutoff: how far along its beam a shot's range may be off.
    pairs : tuple of two ndarray, shape (p,), int
        The neighbouring shots among ``points`` (rows of it; :func:`neighbours`).

    Returns
    -------
    ndarray, shape (m,), bool
        True for the shots of every group but the one holding the shot nearest the station
        and those it takes back (all False when the face's shots form one group). Groups are
        the connected components of the neighbour links whose ranges differ by at most
        ``tan(MAX_INCIDENCE_DEG)`` times the mean range times the angle between the beams,
        plus ``_NOISE_CUTOFFS`` cutoffs. The other groups, nearest first, are taken too when
        all their shots lie on the plane of those taken (:func:`_on_plane_of`), or, when
        those span no plane, with the next group when that one lies on the plane of both.
    """
    m = points.shape[0]
    out = np.zeros(m, dtype=bool)
    if m < 2:
        return out
    i, j = pairs
    beams = points - viewpoint
    ranges = row_norms(beams)
    units = beams / np.maximum(ranges, 1e-12)[:, None]
    angle = 2.0 * np.arcsin(np.clip(0.5 * row_norms(units[i] - units[j]), 0.0, 1.0))
    mean_range = 0.5 * (ranges[i] + ranges[j])
    kept = np.abs(ranges[i] - ranges[j]) <= (
        _RANGE_PER_SPACING * mean_range * angle + _NOISE_CUTOFFS * noise
    )
    group = components(m, i[kept], j[kept])
    if np.all(group == group[0]):
        return out
    group = _join_unparted(group, units, ranges, noise, (i[~kept], j[~kept]))
    if np.all(group == group[0]):
        return out
    taken = group == group[int(np.argmin(ranges))]
    # The other groups nearest first, each taken when on the plane of those already taken: a
    # receding face's far part grows the plane it is checked against as it goes. Taken shots
    # on one raster line span no plane (a face's near part seen by one row): the next group
    # is taken with them when the one after it, a step on and not beside them, lies on the
    # plane of the two: a steady run along the beams that a fan, one jump from a column to the
    # wall, does not make.
    rest = sorted(np.unique(group[~taken]).tolist(), key=lambda g: float(ranges[group == g].min()))
    k = 0
    while k < len(rest):
        members = group == rest[k]
        if _on_plane_of(points[taken], points[members], viewpoint, noise):
            taken |= members
        elif k + 1 < len(rest) and not _spans_plane(points[taken], noise):
            after = group == rest[k + 1]
            # The one after must not step off the taken shots themselves: a wall's raster
            # column parted in two by the box's shots, each half a raster step off the box's
            # column, lies on any plane through that column and itself.
            onward = not np.any((taken[i] & after[j]) | (after[i] & taken[j]))
            if onward and _on_plane_of(points[taken | members], points[after], viewpoint, noise):
                taken |= members | after
                k += 1
        k += 1
    return ~taken


def _join_unparted(group, units, ranges, noise: float, parted) -> np.ndarray:
    """Groups (m,) int joined where no step along the beams parts them.

    Each group is linked to the group holding the face's shot nearest it in angle (the
    closest pair of their shots, ``units`` (m, 3) their beams' directions and ``ranges`` (m,)
    metres), by the bound of the raster links, unless a raster link between the two failed
    it (``parted``: the failed links' ends). A sparse raster leaves shots of one face without a
    neighbour on it: each was a group of its own, left out as a fan with no step seen.
    """
    cosines = units @ units.T
    failed = set(zip(group[parted[0]].tolist(), group[parted[1]].tolist()))
    links_i, links_j = [], []
    for g in np.unique(group):
        mine = group == g
        sub = np.where(mine[None, :], -2.0, cosines)[mine]  # to shots of other groups
        rows = mine.nonzero()[0]
        flat = int(sub.argmax())
        a, b = int(rows[flat // sub.shape[1]]), flat % sub.shape[1]
        h = int(group[b])
        if (g, h) in failed or (h, g) in failed:
            continue
        angle = math.acos(min(1.0, max(-1.0, float(cosines[a, b]))))
        bound = _RANGE_PER_SPACING * 0.5 * (ranges[a] + ranges[b]) * angle
        if abs(ranges[a] - ranges[b]) <= bound + _NOISE_CUTOFFS * noise:
            links_i.append(a)
            links_j.append(b)
    if not links_i:
        return group
    labels = np.unique(group, return_inverse=True)[1]
    joined = components(int(labels.max()) + 1, labels[np.array(links_i)], labels[np.array(links_j)])
    return joined[labels]


def _on_plane_of(near: np.ndarray, far: np.ndarray, viewpoint, noise: float) -> bool:
    """Whether every shot ``far`` (k, 3) lies on the plane of the shots ``near`` (m, 3) metres.

    The plane is the least-squares one of ``near`` alone; the allowance at a shot is ``noise``
    (metres, the inlier cutoff) times ``sqrt(1 + (a / s1)^2 + (b / s2)^2)``, ``a`` and ``b`` its
    offsets from their centroid along their principal axes and ``s1``, ``s2`` their RMS spreads
    along them: a plane fitted to a patch tilts by about the noise over the patch's extent, and
    carried farther off by that much more. False when ``near`` spans no plane (a spread across
    below ``_MIN_SPREAD_CUTOFFS`` cutoffs).
    """
    if not _spans_plane(near, noise):
        return False
    centroid = near.mean(axis=0)
    _, singular, basis = svd(near - centroid)
    spread = singular / math.sqrt(near.shape[0])
    offsets = np.vstack([far, viewpoint]) - centroid
    offsets = offsets @ basis.T
    allowance = noise * np.sqrt(
        1.0 + (offsets[:, 0] / spread[0]) ** 2 + (offsets[:, 1] / spread[1]) ** 2
    )
    off = np.abs(offsets[:, 2]) <= allowance
    # The station on the plane too: the plane holds the beams (the shots of one raster column,
    # whatever they hit, lie on its plane through the station), and so says nothing.
    return bool(np.all(off[:-1]) and not off[-1])


def _spans_plane(points: np.ndarray, noise: float) -> bool:
    """Whether ``points`` (m, 3) metres spread across their line by ``_MIN_SPREAD_CUTOFFS``
    inlier cutoffs ``noise`` (metres) or more (RMS, along their second principal axis)."""
    if points.shape[0] < 3:
        return False
    singular = singular_values(points - points.mean(axis=0))
    return bool(singular[1] >= _MIN_SPREAD_CUTOFFS * noise * math.sqrt(points.shape[0]))
