"""Faces of a cuboid fit that the station saw edge-on, or cannot have seen at all.

Private helper of the cuboid joint fit (:mod:`asbuilt.fit._joint`): a face whose shots all
see it beyond ``MAX_INCIDENCE_DEG`` and lie on one plane through the station is a fan of beams,
not a measured face (:func:`_grazing_faces`), and a fit with a trusted viewpoint can be refitted
without the faces turned away from it or seen edge-on (:func:`_without_unseen_faces`). Lengths
in metres, centred frame.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.fit import _faces
from asbuilt.fit._beam_fans import MAX_INCIDENCE_DEG

#: Cosine of the incidence beyond which a face's shots see it edge-on (:func:`_grazing_face`).
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
        fan = np.linalg.svd(beams, compute_uv=False)[-1] / math.sqrt(beams.shape[0])
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
