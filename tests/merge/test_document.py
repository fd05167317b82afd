"""A merged model survives the asbuilt-model document round trip (asbuilt.export.model_json)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.export.model_json import dumps_model, model_from_document
from asbuilt.merge import merge_model
from asbuilt.merge.spool import connection_mismatches, ports


def merged():
    pipes = [
        Pipe("P1", (0, 0, 0), (1.9, 0, 0), 0.1150, nominal='4"', group="SP-1"),
        Pipe("P2", (2.1, 0, 0), (3.8, 0, 0), 0.1140, group="SP-1"),
        Pipe("P3", (2, 0.15, 0), (2, 2, 0.02), 0.1145, group="SP-1"),
        Pipe("P4", (4.0, 0.2, 0), (4.0, 2.0, 0), 0.0889, group="SP-1"),
        Pipe("P5", (4.0, 2.2, 0), (4.0, 4.0, 0), 0.0890, group="SP-1"),
    ]
    return merge_model(report_of(pipes))


def test_round_trip_keeps_geometry_sizes_snaps_and_corrections(tmp_path):
    model = merged()
    assert {c.type for c in model.components} >= {"pipe", "tee", "elbow"}
    text = dumps_model(model)
    (tmp_path / "model.json").write_text(text)
    document = json.loads((tmp_path / "model.json").read_text())
    assert document["catalog"] == "asme-b36.10m"
    back = model_from_document(document)
    assert [c.id for c in back.components] == [c.id for c in model.components]
    assert [s.id for s in back.spools] == [s.id for s in model.spools] == ["SP-1"]
    for a, b in zip(model.components, back.components):
        assert (a.type, a.nominal, a.schedule, a.spool) == (b.type, b.nominal, b.schedule, b.spool)
        for (pa, da), (pb, db) in zip(ports(a), ports(b)):
            assert np.allclose(pa, pb, atol=1e-9) and np.allclose(da, db, atol=1e-9)
        assert b.snap.get("status") == a.snap.get("status")
        assert [c.what for c in b.corrections] == [c.what for c in a.corrections]
        assert [c.size for c in b.corrections] == pytest.approx([c.size for c in a.corrections])
    assert connection_mismatches(back.components, tolerance=1e-4)[1] == []
    p1 = next(c for c in back.components if c.id == "P1")
    assert p1.snap["hint"]["agrees"] is True
    assert p1.snap["candidates"][0]["nominal"] == "4"
