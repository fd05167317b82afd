"""A cuboid's viewpoint that the shots contradict (a wrong station or sensor position).

Private helper of :func:`asbuilt.fit.cuboid.fit_cuboid`. The fit trusts its viewpoint: it
orients the faces (none may be turned away from it), and shots seen past the box from it are
background that does not count against ``max_outlier_fraction``. A ``station`` copied from
another set-up, or a sensor position on the wrong side of the object, turns that trust against
the shots: a face the sensor really saw is turned away from the stated viewpoint, so its shots
are rejected, and as they lie behind the face kept and farther from the viewpoint they are
discounted as background (a box seen on one face, 25 of 35 shots rejected and the fit kept),
or the fit is refused for its outliers, or a subset's fit keeps shots that lie on a face's
plane but far off the box.

So when the shots do not lie on a pan-tilt raster's rows and columns as seen from the viewpoint
(shots that do were taken from there) and the fit as seen from it is refused, or leaves out more than
``DOUBTFUL_REJECTED`` of the shots (counted as outliers or not), the shots are fitted without
the viewpoint too. If that fit keeps all but fewer than ``BLIND_REJECTED`` of them and more
than ``UNSEEN_FRACTION`` of its inliers lie on faces turned away from the viewpoint (all of
them when it lies inside the box), the viewpoint and the shots contradict each other: no shot
from there reaches such a face. So does a fit from the viewpoint that keeps such a box itself
(the search falls back on frames the viewpoint cannot have seen when it has no other). The
fit is then refused (:func:`refusal`), not replaced by the
fit of the shots alone as a cylinder's is (:data:`asbuilt.fit._cylinder_finish.VIEW_IGNORED`):
a box's corner seen from the wrong side and a convex surface (a pipe's arc, two chords) seen
from the right one look the same, so the shots alone cannot say which is wrong, and with
``kind: auto`` the kind that honours the viewpoint must win. A viewpoint the shots do not
contradict keeps its fit (a column before a wall in a wide window puts half its shots on the
wall, left out as background seen past the box).
"""

from __future__ import annotations

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._silhouette import raster_grid

#: More than this fraction of the viewpoint-free fit's inliers on faces turned away from the
#: viewpoint contradicts it (the cylinder fit's share of shots its pipe would hide).
UNSEEN_FRACTION = 1.0 / 3.0

#: The fit of the shots alone speaks against the viewpoint only if it rejects fewer than this
#: fraction of them (as :data:`asbuilt.fit.cylinder.OVERRULE_REJECTED`): one that rejects a
#: third or more is as doubtful as the viewpoint.
BLIND_REJECTED = 1.0 / 3.0

#: A fit from the viewpoint that leaves out more than this fraction of the shots is checked
#: against the fit of the shots alone: the least a contradicted viewpoint makes it leave out
#: (a third of the ``1 - BLIND_REJECTED`` the fit alone keeps, on faces turned away from it).
DOUBTFUL_REJECTED = UNSEEN_FRACTION * (1.0 - BLIND_REJECTED)


def turned_away(result, points: np.ndarray, view: np.ndarray) -> tuple[int, bool]:
    """How many inliers of a cuboid fit ``result`` of ``points`` (n, 3) metres lie on faces
    turned away from ``view`` (3,) metres, and whether ``view`` lies inside the box (every face
    turned away).

    Each inlier is given the face of the box it lies nearest outside of (in box coordinates,
    the axis where it reaches farthest past the half size). A box seen on one face only has no
    known inside (its depth is made up, placed by a viewpoint it was not given): none count.
    """
    box = result.primitive
    if int(result.diagnostics.get("faces", 0)) < 2:
        return 0, False
    half = 0.5 * np.asarray(box.size, dtype=np.float64)
    axes = np.asarray(box.axes, dtype=np.float64)
    seen = axes @ (np.asarray(view, dtype=np.float64) - box.center)
    inside = bool(np.all(np.abs(seen) < half))
    local = (points[result.inliers] - box.center) @ axes.T
    k = np.argmax(np.abs(local) - half, axis=1)
    sign = np.sign(local[np.arange(local.shape[0]), k])
    facing = sign * seen[k] > half[k]
    return int(np.count_nonzero(~facing)), inside


def refusal(seen: str | None, kept: int, n: int, away: int, inside: bool) -> str:
    """The message refusing a cuboid whose viewpoint the shots contradict: ``seen`` what the fit
    from the viewpoint did (None: it is the box described), ``kept`` of the ``n`` shots the
    fit without it keeps, ``away`` of them on faces turned away from the viewpoint, ``inside``
    whether it lies inside that box."""
    where = " (the viewpoint lies inside that box)" if inside else ""
    box = (
        "the only box found keeps"
        if seen is None
        else f"fitted as seen from it, the box {seen}; without it, one box keeps"
    )
    return (
        f"cuboid: the shots contradict the viewpoint: {box} {kept} of the {n} shots, {away} of "
        f"them on faces turned away from the viewpoint{where}, which no shot from it can reach. "
        "Check the scan's sensor position or the object's station (shots taken from two "
        'stations belong in one object per station, each with its "station"); if they are '
        "right, these shots are not one box seen from there: give only the box's shots, or fit "
        "it as a hull."
    )


def checked(result, error, points: np.ndarray, view: np.ndarray, fit_alone):
    """The cuboid fit from ``view`` (3,) metres of ``points`` (n, 3) metres, ``result`` (a
    FitResult, None when refused with the FitError ``error``), unless the shots contradict the
    viewpoint (see the module docstring): then a FitError saying so. ``fit_alone()`` fits the
    shots without the viewpoint (called only when the fit from it is in doubt)."""
    n = points.shape[0]
    if result is not None:
        # With no box the viewpoint can have seen, the search keeps one it cannot have: faces
        # turned away from it, or around it.
        away, inside = turned_away(result, points, view)
        if inside or away > UNSEEN_FRACTION * result.n_inliers:
            if _taken_from(points, view):
                return result
            raise FitError(refusal(None, result.n_inliers, n, away, inside))
        if n - result.n_inliers <= DOUBTFUL_REJECTED * n:
            return result
    if _taken_from(points, view):
        return _kept(result, error)
    # The fit is refused, or leaves out many shots (as background seen past the box, perhaps,
    # which then do not count against the outlier limit): a wrong viewpoint does both. Do the
    # shots alone say so?
    try:
        alone = fit_alone()
    except FitError:
        alone = None
    if alone is None or n - alone.n_inliers >= BLIND_REJECTED * n:
        return _kept(result, error)
    away, inside = turned_away(alone, points, view)
    if not (inside or away > UNSEEN_FRACTION * alone.n_inliers):
        return _kept(result, error)
    if result is None:
        seen = f"is refused ({str(error).removeprefix('cuboid: ').split(';')[0]})"
    else:
        seen = f"leaves out {n - result.n_inliers} of the {n} shots"
    raise FitError(refusal(seen, alone.n_inliers, n, away, inside))


def _taken_from(points: np.ndarray, view: np.ndarray) -> bool:
    """Whether ``points`` (n, 3) metres lie on a pan-tilt raster's rows and columns as seen
    from ``view`` (3,) metres: then they were taken from there (from another station a
    raster's lattice does not line up), whatever a fit of them alone suggests. Background in a
    wide window can make that fit a box with the wall for its back face, turned away: a
    black-box review's columns and piers before walls and floors, right stations, 16 of 480
    fits refused with this message. Asked only where a refusal is in view: reading the raster
    costs about 0.14 ms, a few percent of a cuboid fit."""
    return raster_grid(points, view) is not None


def _kept(result, error):
    """``result``, or the refusal ``error`` when there is none."""
    if result is None:
        raise error
    return result
