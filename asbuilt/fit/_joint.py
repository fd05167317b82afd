"""The joint orthogonal-distance fit of a cuboid's seen faces, and the choice among frames.

Step 2 of :mod:`asbuilt.fit.cuboid`: one rotation (3 small-angle parameters applied with
Rodrigues' formula, so the axes stay exactly orthonormal) and one offset per seen face minimise
the squared orthogonal distances of the points to their nearest face plane (Gauss-Newton with
an analytic Jacobian, Tukey biweight IRLS, a least-squares refit on the inliers), and of the
segmentation's frames the one every point supports best is kept (MSAC, Torr and Zisserman
2000). Working state only: :func:`asbuilt.fit.cuboid.fit_cuboid` builds the result.
"""

from __future__ import annotations

import math

import numpy as np

from asbuilt.fit import _faces, _vectors
from asbuilt.fit._beam_fans import beam_fan_shots, neighbours
from asbuilt.fit._common import within_noise
from asbuilt.fit._cuboid_background import only_background, seen_past
from asbuilt.fit._cuboid_grazing import (
    HELD_SHOTS,
    _grazing_faces,
    _without_unseen_faces,
    edge_on_side_face,
    msac_cost,
    plausible,
)
from asbuilt.fit._cuboid_lone import lone_shot_lines
from asbuilt.fit._cuboid_sparse import (
    SPARSE_SHOTS,
    corner_frames,
    line_split_frames,
    line_split_spread,
    lone_face_shots,
    range_cost,
    rival,
)
from asbuilt.fit._mixture import mixing_cost
from asbuilt.fit._rectangle import min_area_rectangle
from asbuilt.fit._small_linalg import solve

#: Tukey biweight tuning constant (95% efficiency at the normal; Beaton and Tukey 1974).
_TUKEY_C = 4.685
#: Median absolute deviation to sigma for normal residuals.
_MAD_TO_SIGMA = 1.4826
_IRLS_ITERATIONS = 6
_REFIT_ITERATIONS = 4
_EYE3 = np.eye(3)
_EYE3.setflags(write=False)
_ADD = np.add.reduce
_MAX = np.maximum.reduce


def rodrigues(omega: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of the rotation vector ``omega`` (3,), radians."""
    angle = math.sqrt(float(omega @ omega))
    if angle < 1e-15:
        return _EYE3
    k0, k1, k2 = (omega / angle).tolist()  # Python floats build the small matrix faster
    kx = np.array([[0.0, -k2, k1], [k2, 0.0, -k0], [-k1, k0, 0.0]])
    return _EYE3 + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)


class FaceModel:
    """Mutable working state of the joint fit: axes rows (3, 3), faces, offsets (centred frame)."""

    def __init__(self, axes, face_axis, face_sign, face_offset, rot_basis):
        self.axes = np.array(axes, dtype=np.float64)
        self.face_axis = face_axis
        self.face_sign = face_sign
        self.offset = np.array(face_offset, dtype=np.float64)
        # (3, q): free rotation directions, world frame (``_EYE3``, read-only: every direction)
        self.rot_basis = rot_basis
        # The faces every inlier of which sees at grazing incidence from the trusted viewpoint
        # (set by the fit: :func:`_grazing_faces`); a frame with any ranks below the others.
        self.edge_on: tuple[int, ...] = ()
        # From few shots: how far (degrees) a frame that fits them as well lies, else None
        # (set by :func:`best_fit`; the fit is then refused).
        self.rival = None
        # Raster lines that other frames split otherwise, or a face of two lines that two faces
        # meeting between them fit as well: (the lines' unit direction (3,), degrees to the
        # farthest such frame), else None (set by :func:`best_fit`; the fit's turn about the
        # lines is then that uncertain).
        self.turn = None
        # The fits of those other splits (their sizes differ from this frame's).
        self.split_rivals: list = []
        # (axes, face_sign, face_axis, normals): :meth:`normals` of those very arrays.
        self._normals = None

    @property
    def grazing(self) -> bool:
        """Whether a face is seen edge-on by every one of its inliers (:attr:`edge_on`)."""
        return bool(self.edge_on)

    def normals(self) -> np.ndarray:
        """Outward unit normals (m, 3) of the faces, read-only.

        Kept until the axes or the faces are replaced (a Gauss-Newton step asks for them
        again after the assignment that preceded it, with the same axes)."""
        key = (self.axes, self.face_sign, self.face_axis)
        kept = self._normals
        if kept is not None and kept[0] is key[0] and kept[1] is key[1] and kept[2] is key[2]:
            return kept[3]
        normals = self.face_sign[:, None] * self.axes[self.face_axis]
        normals.setflags(write=False)
        self._normals = (*key, normals)
        return normals

    def all_residuals(self, x: np.ndarray) -> np.ndarray:
        """Signed distance (n, m) of each point to each face plane."""
        return x @ self.normals().T - self.offset[None, :]

    def assign(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        res = self.all_residuals(x)
        label = np.abs(res).argmin(axis=1)
        return label, res[np.arange(x.shape[0]), label]

    def jacobian(self, x: np.ndarray, label: np.ndarray, normal=None) -> np.ndarray:
        """d residual / d (rotation in ``rot_basis``, offsets): shape (n, q + m).

        ``normal`` (n, 3), each point's face normal, may be passed when already computed.
        """
        if normal is None:
            normal = self.normals()[label]
        q = self.rot_basis.shape[1]
        # Filled in place (a hot path): rotation columns, then -1 in each point's face column
        # (-0.0 elsewhere, as negating a 0/1 indicator gives).
        jac = np.empty((x.shape[0], q + self.offset.shape[0]))
        rows = _vectors.cross_rows(normal, x)
        # Free to turn about every axis (the shared identity basis): the rows are the columns.
        jac[:, :q] = rows if self.rot_basis is _EYE3 else rows @ self.rot_basis
        jac[:, q:] = -0.0
        jac[np.arange(x.shape[0]), q + label] = -1.0
        return jac

    def step(self, x, label, weights) -> float:
        """One weighted Gauss-Newton step; returns the step's size (radians + metres)."""
        normal = self.normals()[label]
        residual = np.einsum("ij,ij->i", x, normal) - self.offset[label]
        jac = self.jacobian(x, label, normal)
        weighted = jac.T * weights
        matrix = weighted @ jac
        # The diagonal as a strided view (``trace`` sums the same view): cheaper than ``.flat``.
        diagonal = matrix.ravel()[:: matrix.shape[0] + 1]
        diagonal += 1e-12 * max(float(_ADD(diagonal)), 1e-30)
        delta = solve(matrix, -(weighted @ residual)[:, None])[:, 0]
        q = self.rot_basis.shape[1]
        turn = delta[:q] if self.rot_basis is _EYE3 else self.rot_basis @ delta[:q]
        rotation = rodrigues(turn)
        self.axes = self.axes @ rotation.T
        self.offset = self.offset + delta[q:]
        return float(_MAX(np.abs(delta)))


def _tukey(u: np.ndarray) -> np.ndarray:
    return np.where(np.abs(u) < 1.0, (1.0 - u**2) ** 2, 0.0)


def median(values: np.ndarray) -> float:
    """Median of a 1-D array (np.partition; cheaper than np.median for small arrays)."""
    k = values.shape[0]
    if k == 0:
        return float("nan")
    part = values.copy()  # np.partition's copy, partitioned in place without its wrapper
    part.partition([(k - 1) // 2, k // 2])
    return 0.5 * float(part[(k - 1) // 2] + part[k // 2])


def _robust_scale(residual: np.ndarray, floor: float) -> float:
    return max(_MAD_TO_SIGMA * median(np.abs(residual)), floor)


def _robust_fit(model, x, noise, floor, cutoff, keep=None):
    """IRLS with Tukey's biweight, then a plain least-squares refit on the inliers.

    The scale starts at the noise level and is re-estimated (median absolute residual) on the
    biweight's support each iteration; inliers are within ``cutoff`` times the larger of that
    scale and the noise level (the sensor's sigma when given). ``keep`` (n,) bool, optional:
    only these points may support the fit (the others are outliers whatever their residual:
    shots a face's plane holds only as a fan of beams, :mod:`asbuilt.fit._beam_fans`). Updates
    ``model`` in place; returns label (n,), residual (n,) metres, inliers (n,) bool, scale
    (metres) and the number of Gauss-Newton steps.
    """
    iterations = 0
    label, residual = model.assign(x)
    scale = max(noise, floor)
    for _ in range(_IRLS_ITERATIONS):
        iterations += 1
        support = np.abs(residual) < _TUKEY_C * scale
        if keep is not None:
            support &= keep
        if np.count_nonzero(support) < 3:
            break
        scale = _robust_scale(residual[support], floor)
        weights = _tukey(residual / (_TUKEY_C * scale))
        if keep is not None:
            weights = np.where(keep, weights, 0.0)
        moved = model.step(x, label, weights)
        label, residual = model.assign(x)
        if moved < 1e-5:
            break
    inliers = np.abs(residual) <= cutoff * max(scale, noise)
    if keep is not None:
        inliers &= keep
    for _ in range(_REFIT_ITERATIONS):
        if np.count_nonzero(inliers) < 3:
            break
        iterations += 1
        moved = model.step(x[inliers], label[inliers], np.ones(np.count_nonzero(inliers)))
        label, residual = model.assign(x)
        if moved < 1e-9:
            break
    if inliers.any():
        scale = _robust_scale(residual[inliers], floor)
    # The final cut is never tighter than the noise level: orthogonal residuals of oblique shots
    # are smaller than the range noise, and a few points' median underestimates it, so a cut at
    # the residuals' own scale alone would drop good shots seen head-on.
    inliers = np.abs(residual) <= cutoff * max(scale, noise)
    if keep is not None:
        inliers &= keep
    return label, residual, inliers, scale, iterations


def _grow(model, x, label, inliers, threshold, gap, viewpoint, trusted):
    """A model with the faces the refined frame reveals among the rejected points, or None.

    ``viewpoint`` (3,) orients a lone face; when ``trusted`` a face turned away from it is not
    added.

    Segmentation works with a frame from the first planes' consensus sets; once the joint fit
    has refined it, a face whose points were off by a fraction of a degree may line up.
    """
    faces = []
    for f in range(model.offset.shape[0]):
        mask = inliers & (label == f)
        faces.append((int(model.face_axis[f]), float(model.face_sign[f] * model.offset[f]), mask))
    grown = _faces.extra_faces(x, model.axes, faces, threshold, gap, viewpoint if trusted else None)
    if len(grown) == len(faces):
        return None
    frame = _faces.frame_from(x, model.axes, grown, threshold, viewpoint)
    return FaceModel(frame.axes, frame.face_axis, frame.face_sign, frame.face_offset, _EYE3)


def expand_frame(frame, subset: np.ndarray, n: int):
    """``frame`` segmented on the points ``subset`` (m,), its labels spread over all n (-1)."""
    labels = -np.ones(n, dtype=np.int64)
    labels[subset] = frame.labels
    return _faces.Frame(frame.axes, frame.face_axis, frame.face_sign, frame.face_offset, labels)


def _beam_fans(model, x, label, inliers, width, viewpoint, raster) -> np.ndarray:
    """Inliers (n,) bool that a fitted face holds only as shots along the beams behind its
    nearest group (:func:`asbuilt.fit._beam_fans.beam_fan_shots`; ``width`` metres, the inlier
    cutoff; ``raster``, the shots' angles (n, 2) and raster lines (n, 2):
    :func:`asbuilt.fit._beam_fans.raster_lines`).

    Neighbours on a face's raster lines are counted among the shots not behind its plane: a
    shot between two of its shots that hit another face, or something in front, parts them;
    a mixed return or the background seen past an edge, behind it, does not. Of the shots so
    parted from their face's nearest group, only those farther from the station than every
    other inlier (by twice ``width``) are returned: background seen past the box.
    """
    out = np.zeros(x.shape[0], dtype=bool)
    angles, lines = raster
    signed = model.all_residuals(x)
    for f in range(model.offset.shape[0]):
        mine = inliers & (label == f)
        count = int(np.count_nonzero(mine))
        if count < 2:
            continue
        first, second = neighbours(angles, lines, mine | (signed[:, f] > width))
        local = np.full(x.shape[0], -1, dtype=np.int64)
        local[mine] = np.arange(count)
        both = mine[first] & mine[second]
        out[mine] = beam_fan_shots(
            x[mine], viewpoint, width, (local[first[both]], local[second[both]])
        )
    if out.any():
        # Only what lies past the rest of the box is background seen past it: a beam seen
        # along its length has its side's shots spread along the beams too, but its other
        # faces reach as far.
        ranges = np.linalg.norm(x - viewpoint, axis=1)
        rest = inliers & ~out
        if rest.any():
            out &= ranges > ranges[rest].max() + 2.0 * width
    return out


#: Rounds of leaving out a face's beam-fan shots and refitting (each can move the faces and
#: hand a face new shots).
_FAN_ROUNDS = 3


def _turns(frame) -> np.ndarray:
    """The rotation basis (3, q) a frame's joint fit may turn in: every direction, or those
    square to its ``fixed_turn``."""
    if frame.fixed_turn is None:
        return _EYE3
    return _vectors.perpendicular_basis(frame.fixed_turn)


def _start(frame, x: np.ndarray, keep=None) -> FaceModel:
    """The joint fit's starting model from a segmentation frame; ``keep`` (n,) bool, optional,
    the points a lone face's in-plane axes may come from."""
    if frame.n_faces != 1:
        return FaceModel(
            frame.axes, frame.face_axis, frame.face_sign, frame.face_offset, _turns(frame)
        )
    normal = frame.axes[int(frame.face_axis[0])]
    basis = _vectors.perpendicular_basis(normal)
    members = frame.labels == 0
    if keep is not None and np.count_nonzero(members & keep) >= 3:
        members = members & keep
    rect = min_area_rectangle(x[members] @ basis)
    in_plane = rect @ basis.T
    axes = np.vstack([normal, in_plane[0], _vectors.cross3(normal, in_plane[0])])
    model = FaceModel(axes, np.array([0]), frame.face_sign.copy(), frame.face_offset.copy(), None)
    model.rot_basis = axes[1:].T.copy()
    return model


def fit_frame(frame, x, noise, floor, cutoff, gap, viewpoint, trusted, raster=None):
    """Robust joint fit starting from one segmentation frame (plus faces it then reveals).

    With a ``trusted`` viewpoint and ``raster``, the shots' angles and raster lines
    (:func:`asbuilt.fit._beam_fans.raster_lines`), shots a face holds only as
    a fan of beams behind its nearest group (the wall behind a column, in the plane of a
    raster column grazing the column's side) are left out and the frame is fitted again from
    its start without them: they become outliers.

    Returns model, label (n,), residual (n,) metres, inliers (n,) bool, scale (metres),
    Gauss-Newton steps and whether only one face is seen.
    """
    one_face = frame.n_faces == 1
    fans = trusted and raster is not None
    steps = 0
    keep = None

    def settle(make):
        """Fit ``make(keep)``'s model, leaving out beam-fan shots round by round."""
        nonlocal steps, keep
        model = make(keep)
        fit = _robust_fit(model, x, noise, floor, cutoff, keep)
        steps += fit[4]
        for _ in range(_FAN_ROUNDS if fans else 0):
            label, _, inliers, scale = fit[:4]
            fan = _beam_fans(
                model, x, label, inliers, cutoff * max(scale, noise), viewpoint, raster
            )
            if not fan.any():
                break
            keep = ~fan if keep is None else keep & ~fan
            # From the start again: the fit that held the fan's shots has turned the faces
            # toward them, and a face left with one line of shots would not turn back.
            model = make(keep)
            fit = _robust_fit(model, x, noise, floor, cutoff, keep)
            steps += fit[4]
        return model, fit

    model, (label, residual, inliers, scale, _) = settle(lambda kept: _start(frame, x, kept))
    if not one_face:
        grown = _grow(model, x, label, inliers, cutoff * scale, gap, viewpoint, trusted)
        if grown is not None:
            start = (grown.axes.copy(), grown.face_axis, grown.face_sign, grown.offset.copy())
            model, (label, residual, inliers, scale, _) = settle(
                lambda kept: FaceModel(*start, _turns(frame))
            )
    if fans:
        width = cutoff * max(scale, noise)
        model.edge_on = tuple(_grazing_faces(model, x, label, inliers, viewpoint, width))
    return model, label, residual, inliers, scale, steps, one_face


def _same_frame(a, b) -> bool:
    """Whether two segmentation frames have the same axes and faces."""
    return (
        np.array_equal(a.face_axis, b.face_axis)
        and np.array_equal(a.face_sign, b.face_sign)
        and np.allclose(a.axes, b.axes)
        and np.allclose(a.face_offset, b.face_offset)
        and (a.fixed_turn is None) == (b.fixed_turn is None)
    )


def _on_a_line(trial, x: np.ndarray, width: float, raster: np.ndarray | None = None) -> bool:
    """Whether some face of a fit has its inliers within ``width`` metres (RMS) of one line:
    a single raster column or row, which leaves the face's own direction about that line to
    the other faces (three columns on two narrow faces fit either corner). Only the
    ``raster`` (n,) bool points count when given: a bisection's hits next to an edge, a few
    millimetres apart on one row, leave it one line of the raster all the same."""
    model, label, _, inliers = trial[:4]
    counted = inliers if raster is None else inliers & raster
    for f in range(model.offset.shape[0]):
        members = x[counted & (label == f)]
        if members.shape[0] < 2:
            continue
        if _faces.on_one_line(members, width):
            return True
    return False


#: A first frame's fit that rejected shots stands without the other frames only if they can
#: only be background (:func:`_rejected_are_background`) and its inliers pass the chi-square
#: test at the noise level with this upper tail probability: with the same inliers, another
#: frame can still label them better (a 0.2 m column's two narrow faces fitted 2.2 degrees
#: off, chi-square 59 for a limit of 55.5, where the exhaustive search's frame gave 12.9 and
#: 0.13 degree).
_CHI2_TAIL = 1e-3


def _rejected_are_background(trial, x: np.ndarray, noise: float, cutoff: float) -> bool:
    """Whether the shots a plausible fit with a trusted viewpoint rejected can only be
    background (:func:`asbuilt.fit._cuboid_background.only_background`, at the inlier cutoff
    ``cutoff`` times ``noise``), and its inliers' residuals pass the chi-square test at
    ``noise`` (metres; tail ``_CHI2_TAIL``), so that no other frame need be tried. ``x`` (n,
    3) metres, centred."""
    model, _, residual, inliers = trial[:4]
    rejected = x[~inliers]
    n_params = model.rot_basis.shape[1] + model.offset.shape[0]
    if not within_noise(residual[inliers], noise, n_params, _CHI2_TAIL):
        return False
    return only_background(
        model.axes,
        model.face_axis,
        model.all_residuals(rejected),
        x[inliers],
        rejected,
        x.shape[0],
        cutoff * noise,
    )


def counted_outliers(trial, x: np.ndarray, view: np.ndarray, trusted: bool, width: float) -> int:
    """How many shots a frame's fit rejects that count against its outlier limit: all of them,
    but with a ``trusted`` viewpoint ``view`` (3,) metres (centred frame) those seen past the
    box (:func:`asbuilt.fit._cuboid_background.seen_past`; ``width`` metres, the inlier
    cutoff). ``x`` (n, 3) metres, centred."""
    count = int(np.count_nonzero(~trial[3]))
    if not trusted or count == 0:
        return count
    return count - int(np.count_nonzero(seen_past_shots(trial, x, view, width)))


def seen_past_shots(trial, x: np.ndarray, view: np.ndarray, width: float) -> np.ndarray:
    """Which of the n shots a frame's fit rejects are background seen past the box, shape (n,)
    bool (:func:`asbuilt.fit._cuboid_background.seen_past`; ``view`` (3,) metres, the trusted
    viewpoint, and ``x`` (n, 3) metres, centred; ``width`` metres, the inlier cutoff)."""
    model, _, _, inliers = trial[:4]
    rejected = ~inliers
    out = np.zeros(x.shape[0], dtype=bool)
    if not rejected.any() or not inliers.any():
        return out
    ranges = np.linalg.norm(x - view, axis=1)
    out[rejected] = seen_past(
        model.all_residuals(x[rejected]), ranges[rejected], ranges[inliers], width
    )
    return out


def _one_station_frames(trial, x: np.ndarray, width: float) -> list:
    """Frames (:class:`asbuilt.fit._faces.Frame`) that one station can have seen, from a fit
    with two opposite faces: a face of such a pair whose inliers lie within ``width`` metres
    (RMS) of one line (a single raster column or row) lies in every plane through that line,
    so it may as well be the face across the axis no seen face is normal to: a side face seen
    at grazing incidence, one line of shots far from the near face's edge. Each such face is
    moved there (offset at its points, facing away from the other faces' points), the fewest
    shots first; the joint fit then decides. Empty when no face qualifies or every axis has a
    seen face.
    """
    model, label, _, inliers = trial[:4]
    counts = np.bincount(model.face_axis, minlength=3)
    free = (counts == 0).nonzero()[0]
    if free.size != 1 or counts.max() < 2:
        return []
    u = int(free[0])
    proj = x @ model.axes[u]
    faces = [f for f in range(model.offset.shape[0]) if counts[model.face_axis[f]] >= 2]
    faces.sort(key=lambda f: int(np.count_nonzero(inliers & (label == f))))
    out = []
    for f in faces:
        mine = inliers & (label == f)
        members = x[mine]
        others = inliers & (label != f)
        if members.shape[0] < 2 or not others.any():
            continue
        if not _faces.on_one_line(members, width):
            continue
        value = float(proj[mine].mean())
        sign = (
            -1.0 if 2 * np.count_nonzero(proj[others] > value) > np.count_nonzero(others) else 1.0
        )
        face_axis = model.face_axis.copy()
        face_sign = model.face_sign.copy()
        face_offset = model.offset.copy()
        face_axis[f], face_sign[f], face_offset[f] = u, sign, sign * value
        if not _faces.is_box(face_axis, face_sign, face_offset):
            continue
        labels = np.where(inliers, label, -1)
        out.append(_faces.Frame(model.axes.copy(), face_axis, face_sign, face_offset, labels))
    return out


def complexity(trial) -> float:
    """The model part of a frame fit's information criterion: ``ln n`` per fitted parameter
    (rotation and one offset per face: BIC, Schwarz 1978) and the description length of which
    face (or the outliers) each point is on (:func:`~asbuilt.fit._mixture.mixing_cost`)."""
    model, label, residual, inliers = trial[:4]
    n = residual.shape[0]
    kept = int(np.count_nonzero(inliers))
    faces = np.bincount(label[inliers], minlength=model.offset.shape[0]).tolist()
    params = model.rot_basis.shape[1] + model.offset.shape[0]
    return params * math.log(n) + mixing_cost([*faces, n - kept])


def _information(trial, sigma: float, cutoff: float) -> float:
    """Information criterion of a frame's fit (lower is better): the MSAC cost over all points
    in units of ``sigma`` (metres; each capped at ``cutoff`` squared) plus its
    :func:`complexity`."""
    residual = trial[2]
    cost = float(np.sum(np.minimum((residual / sigma) ** 2, cutoff * cutoff)))
    return cost + complexity(trial)


#: Most of the shots a frame with no opposite faces may leave out and still replace, without a
#: viewpoint, a fit with opposite faces that explains more of them (a tenth of n below the
#: ``max_outlier_fraction`` refusal limit of 45%): a box seen from two stations keeps its
#: opposite faces (half its shots on the far side), and the noise-level search of a fit
#: without a sigma does not settle on a band narrower than the shots' scatter, which fits a
#: one-station frame to a subset (a pipe's raster fitted as a cuboid kept 11 of 20 at 0.7 mm
#: where its noise was 30 mm).
_ONE_STATION_OUTLIERS = 0.4


def best_fit(frames, exhaustive, fit_args, max_outlier_fraction, raster=None, known_noise=False):
    """The robust joint fit of the segmentation frame that every point supports best.

    The best-scoring frame of ``frames`` is fitted first. A plausible fit (:func:`plausible`)
    that keeps every point, or (with a trusted viewpoint and ``known_noise``) rejects only
    shots that can only be background (:func:`_rejected_are_background`), cannot be beaten
    unless one of its faces is a single line of shots (:func:`_on_a_line`); ``known_noise``:
    the noise level is the sensor's, not one the caller is trying (a wrong level leaves good
    shots rejected, and their fit looks settled). Otherwise the frames of an exhaustive
    segmentation (``exhaustive()``:
    every first-face hypothesis is tried, not only until a frame explains every segmented
    point, or most of them) that explain at least as many points as the first are fitted and
    compared: three raster columns on two narrow faces fit either corner, and only the shots
    the segmentation left out, or the fit rejected, decide. A plausible fit beats an
    implausible one; among those, the lowest MSAC cost over all n points, cut at the noise
    level, wins (background shots that happen to line up with a wrong frame's extra face
    lower its cost a little, but that face is a back face or a plane through the box).
    Without a trusted viewpoint, vertical raster columns on two faces of a column fit four
    planes in another frame as closely as two: there a fit with opposite faces is doubtful
    (and implausible: no single station sees both), and frames are compared by
    :func:`_information`, which charges each face its offset and its points' labels. If the
    winner still rejects more than ``max_outlier_fraction`` of the points, the frames are
    taken in turn and the plausible one keeping the most points wins. ``fit_args`` are
    :func:`fit_frame`'s arguments after the frame; ``raster`` (n,) bool, optional, the points
    that are not edge-bisection shots (for :func:`_on_a_line`). Returns :func:`fit_frame`'s
    tuple.
    """
    x, noise, floor, cutoff, _, view, trusted = fit_args[:7]
    n = x.shape[0]
    cap = cutoff * max(noise, floor)
    done: list[tuple] = []  # (frame, fit): each frame is fitted once

    def fitted(frame):
        for other, trial in done:
            if other is frame or _same_frame(other, frame):
                return trial
        trial = fit_frame(frame, *fit_args)
        done.append((frame, trial))
        return trial

    def rank(trial, by_cost):
        if not by_cost:
            quality = int(np.count_nonzero(trial[3]))
        elif trusted:
            quality = -msac_cost(trial[2], cap)
        else:
            quality = -_information(trial, cap / cutoff, cutoff)
        # A fit with a face seen edge-on from every shot (a fan of beams) comes after every
        # other plausible fit.
        return (plausible(trial[0], view, trusted), not trial[0].grazing, quality)

    best = fitted(frames[0])
    best_rank = rank(best, True)
    # (Without a trusted viewpoint a fit with opposite faces is implausible, so doubtful too.)
    settled = best[3].all() or (
        trusted and known_noise and _rejected_are_background(best, x, cap / cutoff, cutoff)
    )
    # From few shots every frame is compared (and checked for a rival below): a frame that
    # keeps every shot may still be one of several.
    sparse = n <= SPARSE_SHOTS
    if (
        sparse
        or not (best_rank[0] and best_rank[1] and settled)
        or _on_a_line(best, x, cap, raster)
    ):
        first = int(np.count_nonzero(frames[0].labels >= 0))
        frames = exhaustive()
        for frame in frames:
            fewer = np.count_nonzero(frame.labels >= 0) < first
            # With a trusted viewpoint, while no plausible fit stands (a face seen edge-on
            # from every shot took in a raster line's fan of beams: the frame explaining the
            # most shots had it), a frame explaining fewer is fitted too.
            doubtful = trusted and not (best_rank[0] and best_rank[1])
            if (
                fewer
                and not doubtful
                and (trusted or best_rank[0] or _faces.has_opposite(frame.face_axis))
            ):
                # Without a viewpoint, while only frames with opposite faces (which no single
                # station sees) stand, one that a station can have seen is fitted even if its
                # faces explain fewer shots: the rest may be mixed returns along the beams of
                # one raster line, which lie in one plane (through the station) and pass for
                # a face. It must still keep most shots (a box seen from two stations keeps
                # its opposite faces).
                continue
            trial = fitted(frame)
            if fewer and counted_outliers(trial, x, view, trusted, cap) > _ONE_STATION_OUTLIERS * n:
                continue
            trial_rank = rank(trial, True)
            if trial_rank > best_rank:
                best, best_rank = trial, trial_rank
    if trusted and not (best_rank[0] and best_rank[1]):
        # No fit that a station can have seen: the fits without their unseen faces.
        for _, trial in list(done):
            frame = _without_unseen_faces(trial, x, view, cutoff * max(trial[4], noise))
            if frame is None:
                continue
            sub = fitted(frame)
            sub_rank = rank(sub, True)
            if sub_rank > best_rank:
                best, best_rank = sub, sub_rank
    if not trusted and not best_rank[0]:
        # Without a viewpoint opposite faces are doubtful; a face of an opposite pair that is
        # one line of shots may be the side face seen at grazing incidence instead.
        for frame in _one_station_frames(best, x, cap):
            trial = fitted(frame)
            trial_rank = rank(trial, True)
            if trial_rank > best_rank:
                best, best_rank = trial, trial_rank
    if counted_outliers(best, x, view, trusted, cap) > max_outlier_fraction * n:
        best_rank = rank(best, False)
        for frame in frames:
            trial = fitted(frame)
            trial_rank = rank(trial, False)
            if trial_rank > best_rank:
                best, best_rank = trial, trial_rank
            if (
                best_rank[0]
                and best_rank[1]
                and counted_outliers(best, x, view, trusted, cap) <= max_outlier_fraction * n
            ):
                break
    lines = fit_args[7][1] if len(fit_args) > 7 and fit_args[7] is not None else None
    if (
        trusted
        and lines is not None
        and best_rank[0]
        and best_rank[1]
        and np.count_nonzero(~best[3] | (np.abs(best[2]) > cap)) >= HELD_SHOTS
    ):
        trials = [trial for _, trial in done]
        best = edge_on_side_face(best, trials, x, view, noise, cutoff, cap, lines)
    if sparse:
        sigma = cap / cutoff
        # A face of two raster lines may be two faces meeting between them: fitted as a rival.
        for frame in corner_frames(best, x, cutoff * max(best[4], noise), view, _faces.Frame):
            fitted(frame)
        if trusted:
            # A frame whose segmentation explains fewer shots is compared too (the first
            # loop skipped it): the true frame leaves out a shot alone on a face of its own
            # (:func:`lone_face_shots`). It can tie the winner only if it leaves out no more
            # shots than the winner rejects plus one per axis without a seen face (a second
            # shot on that face would have made it a segmented face).
            lost = int(np.count_nonzero(~best[3]))
            for frame in frames:
                free = 3 - np.unique(frame.face_axis).size
                if n - np.count_nonzero(frame.labels >= 0) <= lost + free:
                    fitted(frame)
        lone: dict[int, np.ndarray] = {}

        def alone(trial) -> np.ndarray:
            """The shots ``trial`` rejects that a face of their own holds (with a viewpoint)."""
            if id(trial) not in lone:
                lone[id(trial)] = (
                    lone_face_shots(trial, x, view, cap) if trusted else np.zeros(n, dtype=bool)
                )
            return lone[id(trial)]

        def counted(trial) -> int:
            if not trusted:
                return counted_outliers(trial, x, view, trusted, cap)
            past = seen_past_shots(trial, x, view, cap)
            return int(np.count_nonzero(~trial[3] & ~past & ~alone(trial)))

        found = rival(
            best,
            [trial for _, trial in done],
            # A shot alone on a face of its own costs nothing (its face fits it exactly).
            lambda trial: (
                (msac_cost(trial[2], cap) - cap**2 * np.count_nonzero(alone(trial))) / sigma**2
            ),
            counted,
            # A rival with a face seen edge-on counts: that face is free to turn, the
            # very freedom that makes the frame uncertain.
            lambda trial: plausible(trial[0], view, trusted),
        )
        if found is not None:
            best[0].rival = found[1]
    if best[0].rival is not None:
        return best
    # Two faces holding a few parallel lines of shots between them may split the lines
    # otherwise, as exactly, and one face's lines may be two faces', at any shot count.
    frames_split, lined, along = line_split_frames(best, x, cap, view, _faces.Frame)
    split = [fitted(frame) for frame in frames_split]
    # Two lines and one shot beside them that turned the frame: the corners between the lines
    # are compared too.
    lone = lone_shot_lines(best, x, cap)
    if split or best[6] or lone is not None:
        sigma = cap / cutoff

        def cost(trial, free=None) -> float:
            # Along the beams, with a trusted viewpoint: the orthogonal cost favours the
            # frame turning the most shots toward grazing incidence (:func:`range_cost`).
            # Shots ``free`` cost nothing where the fit leaves them out as background seen
            # past its box (a lone shot that only turned the frame, :func:`lone_shot_lines`).
            skip = None if free is None else free & seen_past_shots(trial, x, view, cap)
            if trusted:
                msac = range_cost(trial, x, view, cap, skip)
            else:
                msac = msac_cost(trial[2] if skip is None else trial[2][~skip], cap)
            return msac / sigma**2

        # Other splits of the lines that fit as well are not refused: the fit keeps its frame
        # and reports their spread (the turn about the lines, and their sizes) as uncertainty.
        best[0].turn, best[0].split_rivals = line_split_spread(
            best,
            split,
            lined,
            along,
            x,
            view,
            cap,
            cost,
            lambda trial: counted_outliers(trial, x, view, trusted, cap),
            lambda trial: plausible(trial[0], view, trusted),
            fitted,
            _faces.Frame,
            lone,
        )
    return best
