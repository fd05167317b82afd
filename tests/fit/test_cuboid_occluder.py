"""A raster line on something in front of a box, fitted as its one face (asbuilt.fit._cuboid_occluder)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from asbuilt.errors import FitError
from asbuilt.fit import fit
from asbuilt.fit._cuboid_lone import OneLineFace
from asbuilt.fit._cuboid_occluder import behind_occluder, in_front_of
from asbuilt.fit.cuboid import fit_cuboid
from asbuilt.fit.result import BACKGROUND_SHOTS, FitResult
from asbuilt.primitives import Cuboid
from asbuilt.scan import loads_scan

SCENE = json.loads((Path(__file__).parent / "column_behind_pipe.json").read_text())


def test_a_column_behind_a_pipe_is_fitted_to_its_own_shots():
    # Before: the pipe's raster column, nearest the station, was the box's one face and the
    # fit was refused as "one raster line" (the column's 12 shots on two lines rejected).
    report = fit(loads_scan(json.dumps(SCENE["scan"]), source="scene56.json"))
    (item,) = report.fits
    result = item.result
    hits = np.array(SCENE["hits"])
    assert hits[result.inliers].tolist() == ["C1"] * 12
    assert result.diagnostics[BACKGROUND_SHOTS] >= 6  # the pipe's line, not counted as outliers
    assert any("in front of the box" in note for note in result.notes)
    # The seen face's width (the only size measured across the face) within its error.
    width = sorted(result.primitive.size)[1]
    assert abs(width - 0.5) <= max(3 * max(s for s in result.stderr["size"] if s), 0.05)


def _box():
    return Cuboid(center=[6.0, 0.0, 0.0], axes=np.eye(3), size=[0.5, 0.5, 2.0])


@pytest.mark.parametrize(
    ("point", "front"),
    [
        ([5.0, 0.0, 0.0], True),  # before the near face (x = 5.75)
        ([5.749, 0.0, 0.0], False),  # on it, within the width
        ([7.0, 0.0, 0.0], False),  # behind the box
        ([5.0, 2.0, 0.0], True),  # its beam passes the box by
    ],
)
def test_in_front_of_reads_each_beam(point, front):
    assert in_front_of(_box(), np.array([point]), np.zeros(3), 0.006).tolist() == [front]


def _refused(points, line):
    return FitResult(
        primitive=_box(),
        residuals=np.zeros(len(points)),
        inliers=line,
        stderr={},
        sigma=0.002,
        sigma_source="sensor",
        method="test",
    )


def test_a_line_behind_the_box_it_leaves_is_not_an_occluder():
    # The refused line lies behind the box the other shots fit (a wall's raster column): it is
    # no occluder, and the refusal stands.
    points = np.vstack([np.full((6, 3), [7.0, 0.0, 0.0]), np.full((8, 3), [5.75, 0.0, 0.0])])
    line = np.arange(14) < 6
    behind = behind_occluder(
        lambda subset: _refused(subset, np.ones(len(subset), bool)),
        _refused(points, line),
        points,
        np.zeros(3),
        0.006,
    )
    assert behind is None


def test_a_refused_refit_keeps_the_refusal():
    points = np.vstack([np.full((6, 3), [5.0, 0.0, 0.0]), np.full((8, 3), [5.75, 0.0, 0.0])])
    line = np.arange(14) < 6

    def refuse(subset):
        raise FitError("no box")

    assert behind_occluder(refuse, _refused(points, line), points, np.zeros(3), 0.006) is None
    assert behind_occluder(refuse, _refused(points, line), points, None, 0.006) is None


def test_the_wall_behind_a_thin_columns_one_line_is_not_taken_for_the_box():
    # The column's one raster line is nearest; the wall's shots behind it fit a 0.8 m "box"
    # with the line in front of it, but that box stands before nothing: the refusal stands.
    data = json.loads((Path(__file__).parent / "thin_column_one_line.json").read_text())
    with pytest.raises(OneLineFace):
        fit_cuboid(data["points"], sigma=data["sigma"], viewpoint=data["viewpoint"])
