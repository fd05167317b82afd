"""Every fitting kind the take-off can count is accepted by the shipped JSON report schema."""

import datetime as dt
import json

import jsonschema
import numpy as np
import pytest

from asbuilt.export.model_json import model_from_document
from asbuilt.model import Bend, Component, Cross, Model, Reducer, Straight, Tee
from asbuilt.report import report_data
from asbuilt.report.json_report import dumps_report, report_schema
from asbuilt.report.takeoff import FITTING_KINDS, take_off

STAMP = dt.datetime(2026, 11, 21, 7, 0, tzinfo=dt.timezone.utc)

# ASME B36.10M outside diameters (m) and STD walls: NPS 6, 168.3 x 7.11 mm; NPS 4,
# 114.3 x 6.02 mm. ASME B16.9: 90 degree LR elbow NPS 6 radius 229 mm; reducer 6 x 4 H 140 mm.
OD6, WALL6, OD4, WALL4 = 0.1683, 0.00711, 0.1143, 0.00602
LR6, H64 = 0.229, 0.140


def every_fitting_model() -> Model:
    """NPS 6 elbow, tee, cross, 45 degree lateral and coupling, a concentric and an eccentric 6 x 4
    reducer."""
    r6, r4 = OD6 / 2, OD4 / 2
    six = {"nominal": "6", "schedule": "STD"}
    step = r6 - r4  # an eccentric reducer's axes are the difference of the radii apart
    return Model(
        components=(
            Component("E1", "elbow", Bend([0, 0, 0], [LR6, LR6, 0], [0, LR6, 0], r6, WALL6), **six),
            Component(
                "T1",
                "tee",
                Tee([2, 0, 0], [1.85, 0, 0], [2.15, 0, 0], [2, 0.15, 0], r6, r6, WALL6),
                **six,
            ),
            Component(
                "L1",
                "tee",  # a lateral: merging builds it tee-shaped, its angle in snap
                Tee([2, 1, 0], [1.7, 1, 0], [2.3, 1, 0], [2.2, 1.2, 0], r6, r6, WALL6),
                **six,
                snap={"standard": False, "angle_deg": 45.0, "status": "fitting"},
            ),
            Component(
                "X1",
                "cross",
                Cross(
                    [2, 3, 0], [1.85, 3, 0], [2.15, 3, 0], [2, 2.85, 0], [2, 3.15, 0], r6, r6, WALL6
                ),
                **six,
            ),
            Component("K1", "coupling", Straight([3, 0, 0], [3.1, 0, 0], r6, WALL6), **six),
            Component(
                "R1",
                "reducer",
                Reducer([4, 0, 0], [4 + H64, 0, 0], r6, r4, WALL4),
                nominal="6x4",
                schedule="STD",
            ),
            Component(
                "R2",
                "reducer",
                Reducer([5, 0, 0], [5 + H64, 0, -step], r6, r4, WALL4, [0, 0, -step]),
                nominal="6x4",
                schedule="STD",
            ),
        ),
        catalog="asme-b36.10m",
    )


def test_every_fitting_kind_validates_against_the_schema():
    model = every_fitting_model()
    kinds = {f.type for f in take_off(model).fittings}
    assert kinds == set(FITTING_KINDS)  # the model has one of each kind the take-off counts
    document = json.loads(dumps_report(report_data(model, generated=STAMP)))
    validator = jsonschema.Draft202012Validator(report_schema())
    errors = [f"{list(e.path)}: {e.message}" for e in validator.iter_errors(document)]
    assert errors == []
    assert {f["type"] for f in document["takeoff"]["fittings"]} == {
        "elbow",
        "tee",
        "cross",
        "lateral",
        "coupling",
        "concentric reducer",
        "eccentric reducer",
    }


def test_schema_fitting_types_are_the_take_off_kinds():
    fitting = report_schema()["properties"]["takeoff"]["properties"]["fittings"]["items"]
    assert fitting["properties"]["type"]["enum"] == list(FITTING_KINDS)


@pytest.mark.parametrize("shape", ["straight", "cylinder"])
def test_a_reducer_without_reducer_geometry_counts_as_concentric(shape):
    # A model document may give a reducer a straight's or cylinder's geometry: no offset, so
    # it is concentric (the take-off used to fail with "tuple.index(x): x not in tuple").
    geometry = {
        "straight": {"start": [0, 0, 0], "end": [0.14, 0, 0], "od": OD6},
        "cylinder": {"center": [0.07, 0, 0], "axis": [1, 0, 0], "radius": OD6 / 2, "length": 0.14},
    }[shape]
    component = {"id": "R1", "type": "reducer", "shape": shape, **geometry}
    model = model_from_document(
        {"format": "asbuilt-model", "version": 1, "components": [component]}
    )
    (count,) = take_off(model).fittings
    assert count.type == "concentric reducer" and count.components == ("R1",)
    document = json.loads(dumps_report(report_data(model, generated=STAMP)))
    jsonschema.Draft202012Validator(report_schema()).validate(document)
    assert np.isfinite(document["takeoff"]["totals"]["pipe_length"])
