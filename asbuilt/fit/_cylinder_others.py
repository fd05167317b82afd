"""Other cylinders among a pipe's shots: a tee's header, a rack neighbour, said, not guessed.

Private helper of the cylinder fit. A raster window over a short tee branch also takes in the
header it leaves, larger and longer, and one over a pipe in a rack takes in its neighbours.
The fit of every shot then settles on the one with the most shots (the header, a neighbour)
or, when none has most of them, is refused. A black-box review's ray caster (branches of
0.3-0.95 diameters off headers, rack neighbours 1.5-3 diameters apart, windows one to three
times the silhouette) had 69 of 90 branches fitted as their header, with only the outlier
share to warn, and 37 of 90 rack pipes refused without a word on why.

Which cylinder the operator meant cannot be read from the returns: the window's centre would
tell, but a scan holds only the beams that came back, and with no wall behind the pipes the
returns' extent is the pipes', not the window's (the review's branches: the middle of the
returns lay on the header in 43 of 90 scans). So the fit stays the fit of the most shots,
and says what else is there:

- a kept fit whose rejected shots hold ``FEWEST_SHOTS`` or more that fit another cylinder
  gets a note and the diagnostics ``OTHER_SHOTS``, ``OTHER_RADIUS`` (metres) and
  ``OTHER_ANGLE`` (degrees between the axes), which the scan-quality rule ``another-object``
  reports with its remedy;
- a fit refused because no cylinder explains most of the shots (``NO_MAJORITY``) names the
  cylinders that the surfaces of its shots (cut at range jumps as seen from the station, and
  where beams between them came back with nothing) fit, when there are two or more.

A cylinder found among the shots stands when it keeps ``FEWEST_SHOTS`` inliers or more, its
radius is known to ``DETERMINED_RADIUS`` of itself, it is not nearly a plane over its shots
and its inliers cover ``FEWEST_ARC_DEGREES`` of arc or more (a wall behind the pipe is no
pipe), and it is not one of the other cylinders found again (a
pipe's own rejected silhouette shots fit that pipe again): its axis is more than
``APART_DEGREES`` from theirs, or its radius differs by more than ``APART_RADIUS`` of the
larger, or its centre lies more than that share of the larger radius off their axis and
theirs off its axis (a branch leaves its header square, a neighbour lies beside). Lengths in metres.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from asbuilt.errors import FitError
from asbuilt.fit._common import radius_text
from asbuilt.fit._cylinder_background import DETERMINED_RADIUS, depth_segments, segment_noise
from asbuilt.fit._cylinder_end_plane import END_PLANE_SHOTS
from asbuilt.fit._cylinder_planes import plane_like

__all__ = [
    "APART_DEGREES",
    "APART_RADIUS",
    "FEWEST_ARC_DEGREES",
    "FEWEST_SHOTS",
    "MOST_CYLINDERS",
    "NO_MAJORITY",
    "OTHER_ANGLE",
    "OTHER_RADIUS",
    "OTHER_SHOTS",
    "apart",
    "cylinder_of",
    "cylinders_named",
    "with_other_cylinder",
]

#: A cylinder among the shots is reported only with at least this many inliers (and shots on
#: the face across its end, when its fit left such a face out): fewer leave its radius and
#: axis to a handful of shots (mixed returns and edge shots come in ones and twos, a
#: neighbour's raster line in fives and sixes).
FEWEST_SHOTS = 10
#: ... and its inliers must cover at least this arc about its axis (degrees): a pipe a raster
#: reaches shows 90-180 degrees of itself to the station, while a wall or floor bent into a
#: cylinder covers a few degrees of a cylinder metres wide (the review's scenes: 1-19 degrees,
#: every pipe, branch and neighbour 78 or more).
FEWEST_ARC_DEGREES = 60.0
#: Another cylinder differs from each one already found by more than this angle between the
#: axes (degrees) ...
APART_DEGREES = 15.0
#: ... or by more than this share of the larger radius, in radius or between the axes (a
#: pipe's rejected silhouette shots refitted alone scatter about the pipe by less).
APART_RADIUS = 0.25
#: A refusal names at most this many cylinders, fullest first.
MOST_CYLINDERS = 3
#: How the refusals that :func:`cylinders_named` adds to begin: no cylinder has most of the
#: shots (other refusals, a pipe seen edge-on or through a wall, are about the shots' own
#: pipe; a floor's blocks fitted as cylinders there would only mislead).
NO_MAJORITY = "No cylinder explains most of these points"
#: Diagnostics keys of the other cylinder a kept fit's rejected shots hold.
OTHER_SHOTS = "other_cylinder_shots"
OTHER_RADIUS = "other_cylinder_radius"
OTHER_ANGLE = "other_cylinder_axis_deg"


def cylinder_of(fit, points, mask, sigma, tolerances, view, others):
    """The fit of ``points[mask]`` and its inliers among all ``points`` ((n,) bool), if it
    stands as another cylinder (module docstring) apart from ``others`` (cylinders); else
    None."""
    try:
        found = fit(points[mask], sigma, tolerances, view)
    except FitError:
        return None
    inliers = np.zeros(len(points), dtype=bool)
    inliers[mask] = found.inliers
    cylinder = found.primitive
    # A flanged branch's face, left out as the surface across its end, is its shots too.
    face = int(found.diagnostics.get(END_PLANE_SHOTS, 0))
    if (
        np.count_nonzero(inliers) + face < FEWEST_SHOTS
        or not found.stderr["radius"] <= DETERMINED_RADIUS * cylinder.radius
        or plane_like(found, points[mask])
        or not found.diagnostics.get("arc_deg", 0.0) >= FEWEST_ARC_DEGREES
    ):
        return None
    if not all(apart(cylinder, other) for other in others):
        return None
    return found, inliers


def apart(one, other) -> bool:
    """Whether two cylinders are not one pipe found twice (module docstring)."""
    cosine = abs(float(np.dot(one.axis, other.axis)))
    if np.degrees(np.arccos(min(1.0, cosine))) > APART_DEGREES:
        return True
    larger = max(one.radius, other.radius)
    if abs(one.radius - other.radius) > APART_RADIUS * larger:
        return True
    return bool(
        min(_off_axis(one.center, other), _off_axis(other.center, one)) > APART_RADIUS * larger
    )


def _off_axis(point: np.ndarray, cylinder) -> float:
    """Distance (metres) of ``point`` (3,) metres from ``cylinder``'s axis line."""
    offset = point - cylinder.center
    return float(np.linalg.norm(offset - np.dot(offset, cylinder.axis) * cylinder.axis))


def _candidates(points, view, noise, among, whole: bool) -> list[np.ndarray]:
    """Masks (n,) bool to fit: the shots ``among`` ((n,) bool) together if ``whole``, then
    (with a station) each of their surfaces cut at range jumps that holds ``FEWEST_SHOTS`` or
    more."""
    masks = [among] if whole and np.count_nonzero(among) >= FEWEST_SHOTS else []
    if view is None:
        return masks
    index = np.flatnonzero(among)
    for members in depth_segments(points[among], view, noise, gaps=True):
        if len(members) >= FEWEST_SHOTS and len(members) < len(index):
            mask = np.zeros(len(points), dtype=bool)
            mask[index[members]] = True
            masks.append(mask)
    return masks


def with_other_cylinder(fit, points: np.ndarray, view, sigma, tolerances, result):
    """``result`` with a note and diagnostics when its rejected shots fit another cylinder.

    Parameters
    ----------
    fit : callable
        ``fit(points, sigma, tolerances, viewpoint)``, the cylinder fit of a subset (raises
        FitError when refused).
    points : ndarray, shape (n, 3), metres
    view : ndarray, shape (3,), metres, or None
        The station.
    sigma : float or None, metres
        The sensor's range noise.
    tolerances : Tolerances
    result : FitResult
        The fit of every shot.

    Returns
    -------
    FitResult
        ``result`` itself when fewer than ``FEWEST_SHOTS`` shots were rejected or they hold no
        other cylinder; else ``result`` with the fullest such cylinder in a note and the
        diagnostics ``OTHER_SHOTS``, ``OTHER_RADIUS`` (metres), ``OTHER_ANGLE`` (degrees).
    """
    rejected = ~np.asarray(result.inliers, dtype=bool)
    if np.count_nonzero(rejected) < FEWEST_SHOTS:
        return result
    noise = segment_noise(sigma, tolerances)
    best = None
    for mask in _candidates(points, view, noise, rejected, whole=True):
        found = cylinder_of(fit, points, mask, sigma, tolerances, view, [result.primitive])
        if found is not None and (best is None or found[1].sum() > best[1].sum()):
            best = found
    if best is None:
        return result
    other, inliers = best
    kept = int(np.count_nonzero(inliers))
    cosine = abs(float(np.dot(other.primitive.axis, result.primitive.axis)))
    angle = float(np.degrees(np.arccos(min(1.0, cosine))))
    note = (
        f"{kept} of the {len(points)} shots, left out of this fit, fit another cylinder"
        f" (r {radius_text(other.primitive.radius)}, its axis {angle:.0f} degrees from this one's):"
        " a header the branch leaves, a pipe beside it, or the object itself if the raster was"
        " aimed at it. If the object is that one, give it only its own shots."
    )
    diagnostics = {
        **result.diagnostics,
        OTHER_SHOTS: float(kept),
        OTHER_RADIUS: float(other.primitive.radius),
        OTHER_ANGLE: angle,
    }
    return dataclasses.replace(result, notes=(*result.notes, note), diagnostics=diagnostics)


def cylinders_named(fit, points: np.ndarray, view, sigma, tolerances) -> str:
    """The cylinders the surfaces of the shots fit, as a sentence for a refusal ("" when
    fewer than two stand).

    Parameters are as in :func:`with_other_cylinder`; the surfaces are the shots cut at range
    jumps as seen from ``view`` (none without a station: "").
    """
    if view is None:
        return ""
    noise = segment_noise(sigma, tolerances)
    everything = np.ones(len(points), dtype=bool)
    found = []
    for mask in _candidates(points, view, noise, everything, whole=False):
        one = cylinder_of(fit, points, mask, sigma, tolerances, view, [])
        if one is not None:
            found.append(one)
    found.sort(key=lambda one: -int(np.count_nonzero(one[1])))
    kept: list = []
    for one in found:
        if all(apart(one[0].primitive, other.primitive) for other, _ in kept):
            kept.append(one)
    if len(kept) < 2:
        return ""
    listed = ", ".join(
        f"r {radius_text(one.primitive.radius)} over {int(np.count_nonzero(inliers))} shots"
        for one, inliers in kept[:MOST_CYLINDERS]
    )
    return (
        f" The shots hold {len(kept)} cylinders ({listed}): a rack's neighbours or a tee's"
        " header in the raster window. Give the object only its own pipe's shots."
    )
