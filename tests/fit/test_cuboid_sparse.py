"""Cuboid fits from 10-12 shots (``benchmarks/sparse_cuboids.py``'s trials): the right frame
or a refusal, never a frame tens of degrees off with a standard error of a degree."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit import fit_points

DATA = json.loads((Path(__file__).with_name("sparse_cuboid_trials.json")).read_text())


def _axis_error_deg(axes: np.ndarray, truth: np.ndarray) -> float:
    """The largest angle (degrees) between a true axis and the fitted axis nearest it."""
    cosines = np.abs(axes @ truth.T).max(axis=0)
    return float(np.degrees(np.arccos(np.clip(cosines.min(), -1.0, 1.0))))


def _trials(expect: str) -> list:
    return [pytest.param(t, id=t["name"]) for t in DATA["trials"] if t["expect"] == expect]


@pytest.mark.parametrize("trial", _trials("fit"))
def test_true_faces_are_found_among_every_plane_hypothesis(trial):
    """Three seen faces of 2-4 shots each: planes through two raster lines of different faces
    held as many shots as a face, the six best first planes were all such planes, and the fit
    kept one face (or a frame 34-42 degrees off) leaving good shots out. Every triple is now a
    hypothesis: the frame that explains every shot is found."""
    result = fit_points(
        "cuboid", np.array(trial["points"]), sigma=DATA["sigma"], viewpoint=DATA["station"]
    )
    assert _axis_error_deg(result.primitive.axes, np.array(trial["axes"])) < 3.0
    assert result.inliers.all()


@pytest.mark.parametrize("trial", _trials("refused"))
def test_frames_the_shots_cannot_tell_apart_are_refused(trial):
    """Each of these had returned a frame 8-46 degrees off with standard errors under a
    degree; now refused.

    - 0.4 m, 10 shots, trial 12: one raster column on each of two faces and two shots on the
      top: the box may turn about the columns, and a plane through both columns fits as well.
    - 0.6 m, 8 shots, trial 19 (sizes 35% off): the true frame leaves the one shot on the top
      out, the chosen frame 34 degrees off leaves a side's shot out as seen past its box (so
      not counted against it); a face of its own holds the top shot exactly, so the true frame
      fits as well.
    - 0.4 m, 7 shots, trial 28 (sizes 130% off): the true frame's segmentation explained 6 of
      the 7 shots (the top's one shot on no face) and was never fitted.
    - 0.4 m, 8 shots, trial 34: refused at the sensor's 2 mm, then refitted without it at a
      noise level below the sensor's, where the rival frame rejects a shot.
    - 0.2 m, 8 shots, trial 11 (8.5 degrees off, standard errors 0.8 degree): every frame
      fitted is 8 degrees off, but one 4 degrees from the winner, with other faces under the
      shots, fits them significantly better once the top's lone shot has a face of its own.
    """
    with pytest.raises(FitError, match="fit box frames .* degrees apart equally well"):
        fit_points(
            "cuboid", np.array(trial["points"]), sigma=DATA["sigma"], viewpoint=DATA["station"]
        )


def test_ambiguity_is_also_refused_without_the_sensor_sigma():
    """The noise-level search must not find a level at which the ambiguity passes."""
    (trial,) = [t for t in DATA["trials"] if t["name"] == "0.4 m, 3 faces, 10 shots, trial 12"]
    with pytest.raises(FitError, match="degrees apart"):
        fit_points("cuboid", np.array(trial["points"]), viewpoint=DATA["station"])


@pytest.mark.parametrize("short_reach", [3.0, 1.5, 0.8])
def test_two_raster_lines_of_unequal_reach_are_found(short_reach):
    """Two raster columns on one fitted face, one cut short (by the floor, or a shorter view of
    the column): the points' longest spread tilts away from the lines, across it each line
    spreads over centimetres, yet the lines are the lines."""
    from types import SimpleNamespace

    from asbuilt.fit._cuboid_sparse import on_two_lines

    rng = np.random.default_rng(7)
    width = 0.006  # metres: 3 sigma of 2 mm
    along = np.array([0.0, 1.0, 0.0])
    tall = np.arange(0.0, 3.0, 0.1)
    short = np.arange(0.0, short_reach, 0.1)
    points = np.concatenate(
        [
            np.column_stack([np.zeros_like(tall), tall, np.zeros_like(tall)]),
            np.column_stack([np.full_like(short, 0.3), short, np.zeros_like(short)]),
        ]
    )
    points[:, 0] += rng.normal(0.0, 0.002, points.shape[0])
    face = SimpleNamespace(offset=np.zeros(1), normals=lambda: np.array([[0.0, 0.0, 1.0]]))
    trial = (face, None, None, np.ones(points.shape[0], dtype=bool))
    found = on_two_lines(trial, points - points.mean(axis=0), width)
    assert found is not None
    assert abs(float(found @ along)) > np.cos(np.radians(0.5))
    # One line alone is not two.
    one = points[: tall.size]
    trial = (face, None, None, np.ones(one.shape[0], dtype=bool))
    assert on_two_lines(trial, one - one.mean(axis=0), width) is None
