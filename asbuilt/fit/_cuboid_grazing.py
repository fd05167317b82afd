"""Faces of a cuboid fit that the station saw edge-on, or cannot have seen at all.

Private helper of the cuboid joint fit (:mod:`asbuilt.fit._joint`): a face whose shots all
see it beyond ``MAX_INCIDENCE_DEG`` and lie on one plane through the station is a fan of beams,
not a measured face (:func:`_grazing_faces`), and a fit with a trusted viewpoint can be refitted
without the faces turned away from it or seen edge-on (:func:`_without_unseen_faces`). A
frame is :func:`plausible` as a box seen from the station when every face faces it; a true
side face seen edge-on can win back the rank it lost (:func:`edge_on_side_face`, judged by
:func:`msac_cost`). Lengths in metres, centred frame.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from asbuilt.fit import _faces
from asbuilt.fit._beam_fans import MAX_INCIDENCE_DEG
from asbuilt.fit._small_linalg import singular_values

if TYPE_CHECKING:
    from asbuilt.fit._joint import FaceModel

#: Cosine of the incidence beyond which a face's shots see it edge-on (:func:`_grazing_faces`).
_GRAZING_COS = math.cos(math.radians(MAX_INCIDENCE_DEG))


def _grazing_faces(model, x, label, inliers, viewpoint, width: float) -> list:
    """The faces of a fit whose inliers (n,) bool are a fan of beams: three or more, all seen
    from ``viewpoint`` (3,) metres at more than ``MAX_INCIDENCE_DEG``, within ``width``
    metres (RMS, the inlier cutoff) of one plane through the station, while the other faces
    leave the frame's rotation free about some axis (they are normal to fewer than two axes).

    One raster column's shots lie in a plane through the station, whatever they hit and
    range noise and all, so a frame free to turn turns a face onto that plane: such a face
    measures nothing, it only takes up the rotation the other faces leave free. A real face
    seen edge-on is not in a plane through the station (a beam's side seen from below by one
    raster row: a row of shots at a tilt lies on a cone, not a plane), and a face the other
    two fix (a box's top seen from just below its level) is measured by its offset anyway.
    """
    m = model.offset.shape[0]
    if m < 2:
        return []
    normals = model.normals()
    counts = np.bincount(label[inliers], minlength=m)
    out = []
    for f in range(m):
        beams = x[inliers & (label == f)] - viewpoint
        if beams.shape[0] == 0:
            continue
        others = {int(model.face_axis[g]) for g in range(m) if g != f and counts[g] >= 3}
        if len(others) >= 2:
            continue
        if beams.shape[0] < 3:
            continue
        cosine = np.abs(beams @ normals[f]) / np.linalg.norm(beams, axis=1)
        if not np.all(cosine < _GRAZING_COS):
            continue
        # RMS distance of the shots from the plane through the station that fits them best.
        fan = singular_values(beams)[-1] / math.sqrt(beams.shape[0])
        if fan <= width:
            out.append(f)
    return out


def _without_unseen_faces(trial, x: np.ndarray, view: np.ndarray, width: float):
    """The frame (:class:`asbuilt.fit._faces.Frame`) of a fit with a trusted viewpoint ``view``
    (3,) metres (centred frame) without its faces that the station cannot have seen: turned
    away from it, or seen edge-on from every shot (:func:`_grazing_faces`); their shots are
    left unlabelled. None when every face is seen, or none is.

    The floor a column stands on, reached by beams past its foot, is a plane across its axis
    turned away from a station above it; the frame explaining the most shots takes it for the
    bottom face, and no frame of the segmentation offers the column's front face alone.
    """
    model, label, _, inliers = trial[:4]
    m = model.offset.shape[0]
    facing = model.normals() @ view - model.offset > 0.0
    unseen = set(np.flatnonzero(~facing).tolist()) | set(
        _grazing_faces(model, x, label, inliers, view, width)
    )
    kept = [f for f in range(m) if f not in unseen]
    if not unseen or not kept:
        return None
    remap = np.full(m, -1, dtype=np.int64)
    remap[kept] = np.arange(len(kept))
    labels = np.where(inliers, remap[label], -1)
    if not all(np.count_nonzero(labels == k) >= 3 for k in range(len(kept))):
        return None
    return _faces.Frame(
        model.axes.copy(),
        model.face_axis[kept].copy(),
        model.face_sign[kept].copy(),
        model.offset[kept].copy(),
        labels,
    )


def plausible(model: FaceModel, view: np.ndarray, trusted: bool) -> bool:
    """Whether a fitted frame can be a box seen from ``view`` (3,) metres (centred frame):
    :func:`asbuilt.fit._faces.is_box`, and with a ``trusted`` viewpoint every face facing it
    (a face turned away, such as a back face opposite a seen one, cannot have been hit).
    Without one, no two opposite faces: no single station sees both (a scan from several
    stations says so with each object's ``station``). Such a frame is chosen only when the
    segmentation offers no plausible one."""
    if not _faces.is_box(model.face_axis, model.face_sign, model.offset):
        return False
    if not trusted:
        return not _faces.has_opposite(model.face_axis)
    return bool((model.normals() @ view - model.offset > 0.0).all())


def msac_cost(residual: np.ndarray, cap: float) -> float:
    """MSAC cost (Torr and Zisserman 2000): squared residuals (n,) metres, each capped at cap^2."""
    return float(np.sum(np.minimum(residual**2, cap * cap)))


#: Shots a fit with a face seen edge-on must keep on its other faces, where the chosen fit
#: rejects them, to be chosen instead (:func:`edge_on_side_face`): a raster line's worth.
HELD_SHOTS = 3


def edge_on_side_face(best, trials, x, view, noise, cutoff, cap, lines):
    """``best`` (a plausible fit with no face seen edge-on, with a trusted viewpoint ``view``
    (3,) metres, centred frame), or the fit of ``trials`` that a true side face seen edge-on
    demoted below it.

    A face whose shots all see it beyond ``MAX_INCIDENCE_DEG`` from the station and lie on one
    plane through it ranks last (:func:`_grazing_faces`: a frame free to turn puts a face on
    one raster column's fan of beams). But a column's narrow side, seen at 83 degrees by the
    one raster column that reaches it, is such a face too, and the frame ranked first instead
    may be turned 20-45 degrees to a wrong corner through two raster columns of different faces,
    rejecting a whole raster column of the wide face as outliers (simulated two-station
    columns: 8 views of 60 at 0.2 m and 20 shots; ``benchmarks/two_station_boxes.py``). The
    turned frame there rejects shots that the edge-on frame holds on its other, well-seen
    faces; a frame turned onto a fan of beams holds the fan on its edge-on face instead. So a
    plausible edge-on fit is chosen (the lowest cost of such fits) when its MSAC cost over all
    shots (cut at ``cap`` metres) is lower and its other faces hold at least ``HELD_SHOTS`` of
    the shots ``best`` rejects or leaves farther than ``cap`` from its faces (kept only by
    widening the noise level past the sensor's), each on a face that the shots ``best`` keeps on other raster
    columns fix on their own (not one raster line): three raster columns on a tank fit a face
    through two of them and a side seen edge-on through the third as exactly as a circle does,
    and there the rejected shots are needed to make the face, not predicted by it. ``trials``
    are fits (:func:`~asbuilt.fit._joint.fit_frame` tuples); ``x`` (n, 3) metres, centred; ``noise`` metres and
    ``cutoff`` as for :func:`~asbuilt.fit._joint.fit_frame`; ``lines`` (n, 2) int, each shot's raster row and
    column (:func:`asbuilt.fit._beam_fans.raster_lines`: a column, one pan angle, is a line on
    any plane).
    """
    # Rejected, or kept only at a noise level the fit widened past the sensor's.
    rejected = ~best[3] | (np.abs(best[2]) > cap)
    columns = lines[:, 1]
    chosen, cost = best, msac_cost(best[2], cap)
    for trial in trials:
        model, label, residual, inliers, scale = trial[:5]
        if not (model.grazing and plausible(model, view, True)):
            continue
        trial_cost = msac_cost(residual, cap)
        if not trial_cost < cost:
            continue
        width = cutoff * max(scale, noise)
        held = 0
        for f in range(model.offset.shape[0]):
            if f in model.edge_on:
                continue
            on_face = inliers & (label == f)
            for column in np.unique(columns[on_face & rejected]).tolist():
                # The shots ``best`` rejects on this raster column count when the face's
                # shots that ``best`` keeps on other columns fix the face (not one raster
                # line, which lies in every plane through it): a prediction that came true.
                # Three raster columns on a tank fit two columns as a face and the third as a
                # side seen edge-on, with nothing left over to test.
                fixing = x[on_face & ~rejected & (columns != column)]
                if fixing.shape[0] >= 3 and not _faces.on_one_line(fixing, width):
                    held += int(np.count_nonzero(on_face & rejected & (columns == column)))
        if held >= HELD_SHOTS:
            chosen, cost = trial, trial_cost
    return chosen
