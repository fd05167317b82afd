"""Spool building pieces: ports of each fitting geometry and the connection checker."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.catalog import FittingDims
from asbuilt.merge.contiguity import Joint
from asbuilt.merge.spool import PipeSpec, build_spools, connection_mismatches, ports
from asbuilt.model import Bend, Component, Reducer, Straight, Tee
from asbuilt.primitives import Sphere


def comp(cid, geometry, spool="S1", kind="pipe"):
    return Component(id=cid, type=kind, geometry=geometry, spool=spool)


def test_ports_of_each_geometry():
    straight = comp("A", Straight([0, 0, 0], [2, 0, 0], 0.05))
    assert [tuple(p) for p, _ in ports(straight)] == [(0, 0, 0), (2, 0, 0)]
    assert [tuple(d) for _, d in ports(straight)] == [(-1, 0, 0), (1, 0, 0)]
    bend = comp("E", Bend([2, 0, 0], [2.5, 0.5, 0], [2, 0.5, 0], 0.05), kind="elbow")
    (p0, d0), (p1, d1) = ports(bend)
    assert np.allclose(d0, [-1, 0, 0]) and np.allclose(d1, [0, 1, 0])
    reducer = comp("R", Reducer([0, 0, 0], [0, 0, 0.1], 0.05, 0.04), kind="reducer")
    assert np.allclose(ports(reducer)[1][1], [0, 0, 1])
    tee = comp("T", Tee([0, 0, 0], [-0.1, 0, 0], [0.1, 0, 0], [0, 0.1, 0], 0.05, 0.04), kind="tee")
    assert [tuple(np.round(d, 9)) for _, d in ports(tee)] == [(-1, 0, 0), (1, 0, 0), (0, 1, 0)]
    assert ports(comp("S", Sphere([0, 0, 0], 1.0), kind="sphere")) == []


def test_the_checker_finds_gaps_and_kinks_and_ignores_other_spools():
    a = comp("A", Straight([0, 0, 0], [1, 0, 0], 0.05))
    ok = comp("B", Straight([1, 0, 0], [2, 0, 0], 0.05))
    assert connection_mismatches([a, ok]) == (1, [])
    gap = comp("B", Straight([1.0005, 0, 0], [2, 0, 0], 0.05))
    found, bad = connection_mismatches([a, gap], tolerance=1e-4)
    assert found == 1 and bad[0][:2] == ("A", "B") and bad[0][2] == pytest.approx(5e-4)
    kink = comp("B", Straight([1, 0, 0], [2, np.tan(np.radians(1)), 0], 0.05))
    found, bad = connection_mismatches([a, kink], tolerance=1e-4)
    assert found == 1 and bad[0][3] == pytest.approx(np.radians(1), rel=1e-3)
    other = comp("B", Straight([1.0005, 0, 0], [2, 0, 0], 0.05), spool="S2")
    assert connection_mismatches([a, other], tolerance=1e-4) == (0, [])


def spec(pid, start, end, od=0.1143, dims=None):
    start, end = np.array(start, float), np.array(end, float)
    axis = (end - start) / np.linalg.norm(end - start)
    dims = dims or FittingDims(
        bend_radius=0.152, tee_run=0.105, tee_outlet=0.105, reducer_length=0.102, source="test"
    )
    base = Component(id=pid, type="pipe", geometry=Straight(start, end, od / 2), sources=(pid,))
    return PipeSpec(
        id=pid,
        center=(start + end) / 2,
        axis=axis,
        length=float(np.linalg.norm(end - start)),
        od=od,
        wall=0.006,
        dims=dims,
        run=0,
        component=base,
        nominal="4",
        schedule="STD",
    )


def test_build_spools_places_an_elbow_and_trims():
    pipes = [spec("A", (0, 0, 0), (1.8, 0, 0)), spec("B", (2, 0.2, 0), (2, 2, 0))]
    comps, spools = build_spools(pipes, [Joint("elbow", ((0, 1), (1, 0)))], [None, None])
    assert [c.id for c in comps] == ["A", "A-B", "B"]
    assert comps[0].geometry.end == pytest.approx([1.848, 0, 0])
    assert comps[1].geometry.bend_radius == pytest.approx(0.152)
    assert spools[0].pipe_length == pytest.approx(1.848 * 2)
    assert connection_mismatches(comps) == (2, [])


@pytest.mark.parametrize("order", ["object last", "object first"])
def test_a_generated_name_gives_way_to_an_object_of_that_id(order):
    # An object the user named "A-B": the elbow between A and B takes "A-B~2", never the
    # object's own id, whichever comes first.
    pipes = [spec("A", (0, 0, 0), (1.8, 0, 0)), spec("B", (2, 0.2, 0), (2, 2, 0))]
    named = spec("A-B", (5, 0, 0), (7, 0, 0))
    pipes = pipes + [named] if order == "object last" else [named] + pipes
    elbow = (0, 1) if order == "object last" else (1, 2)
    joints = [Joint("elbow", ((elbow[0], 1), (elbow[1], 0)))]
    comps, _ = build_spools(pipes, joints, [None] * 3)
    kinds = {c.id: c.type for c in comps}
    assert kinds["A-B"] == "pipe" and kinds["A-B~2"] == "elbow"
    # a column "A-B" elsewhere in the scan (not a pipe) is kept clear of too
    comps, _ = build_spools(
        pipes[:2] if order == "object last" else pipes[1:],
        [Joint("elbow", ((0, 1), (1, 0)))],
        [None] * 2,
        taken_ids=["A-B"],
    )
    assert [c.id for c in comps] == ["A", "A-B~2", "B"]


def test_a_fitting_too_big_for_its_pipe_is_dropped_with_a_note():
    big = FittingDims(bend_radius=2.0, tee_run=1, tee_outlet=1, reducer_length=1, source="x")
    pipes = [spec("A", (0, 0, 0), (0.5, 0, 0), dims=big), spec("B", (0.6, 0.1, 0), (0.6, 3, 0))]
    comps, spools = build_spools(pipes, [Joint("elbow", ((0, 1), (1, 0)))], [None, None])
    assert [c.type for c in comps] == ["pipe", "pipe"]
    assert "would not fit" in comps[0].snap["merge_notes"][0]
    assert len(spools) == 1  # still one spool: the pipes are joined, just not by a fitting


def test_spool_ids_skip_every_taken_object_id():
    pipes = [spec("A", (0, 0, 0), (1.8, 0, 0)), spec("B", (2, 0.2, 0), (2, 2, 0))]
    joints = [Joint("elbow", ((0, 1), (1, 0)))]
    _, spools = build_spools(pipes, joints, [None, None])
    assert [s.id for s in spools] == ["S1"]
    # a column "S1" and a tank "S2" in the scan: the spool takes the next free name
    _, spools = build_spools(pipes, joints, [None, None], taken_ids=["S1", "S2", "A"])
    assert [s.id for s in spools] == ["S3"]
    # a group named like an object is not used as the spool's name either
    _, spools = build_spools(pipes, joints, ["C1", "C1"], taken_ids=["C1"])
    assert [s.id for s in spools] == ["S1"]


def test_merged_spool_does_not_take_a_scan_object_id():
    import json
    from pathlib import Path

    from asbuilt.pipeline import build_model
    from asbuilt.scan import loads_scan

    root = Path(__file__).resolve().parents[2]
    scan = json.loads((root / "samples" / "spool.json").read_text())
    bay = json.loads((root / "samples" / "structural-bay.json").read_text())
    for obj in scan["objects"]:
        obj.pop("group", None)  # no group: the spool gets a generated name
    column = next(o for o in bay["objects"] if o["id"] == "C1")
    assert bay.get("units", "m") == scan.get("units", "m")
    scan["objects"].append({"id": "S1", "kind": "cuboid", "points": column["points"]})
    model = build_model(loads_scan(json.dumps(scan), source="s1.json"), check=False)
    (spool,) = model.spools
    assert spool.id != "S1" and model.component("S1").spool is None
    assert spool.id not in {obj["id"] for obj in scan["objects"]}


# Walls of each end, from ASME B36.10M (/work/shared/reference/standards.md): NPS 6 OD 168.3 mm,
# SCH 40 wall 7.11 mm; NPS 4 OD 114.3 mm, 6.02 mm; NPS 2 OD 60.3 mm, 3.91 mm. A B16.9 reducer
# or reducing tee is made to each connecting pipe's schedule, so each end's bore is its pipe's.
BORE6, BORE4, BORE2 = 0.1683 / 2 - 0.00711, 0.1143 / 2 - 0.00602, 0.0603 / 2 - 0.00391


def _merged(pipes):
    from synthetic_pipes import report_of

    from asbuilt.merge import merge_model

    model = merge_model(report_of(pipes), schedule="40")
    return {c.id: c for c in model.components}


def _bore(geometry, which: str) -> float:
    """Inner radius (m) of a pipe, reducer end or tee end."""
    if which == "pipe":
        return geometry.outer_radius - geometry.wall
    if which == "start":
        return geometry.outer_radius_start - geometry.wall_start
    if which == "end":
        return geometry.outer_radius_end - geometry.wall_end
    if which == "run":
        return geometry.outer_radius - geometry.wall
    return geometry.branch_outer_radius - geometry.branch_wall


def test_a_reducer_has_each_pipes_bore_at_its_end():
    """NPS 6 x 4 between SCH 40 pipes: no step in the bore at either weld (it was 1.09 mm at
    the NPS 6 end when the reducer took the thinner NPS 4 wall throughout)."""
    from synthetic_pipes import Pipe

    comps = _merged(
        [Pipe("P1", (0, 0, 0), (1.9, 0, 0), 0.1683), Pipe("P2", (2.1, 0, 0), (4, 0, 0), 0.1143)]
    )
    reducer = comps["P1-P2"].geometry
    assert _bore(comps["P1"].geometry, "pipe") == pytest.approx(BORE6, abs=1e-9)
    assert _bore(comps["P2"].geometry, "pipe") == pytest.approx(BORE4, abs=1e-9)
    assert _bore(reducer, "start") == pytest.approx(BORE6, abs=1e-9)
    assert _bore(reducer, "end") == pytest.approx(BORE4, abs=1e-9)
    # and small to large: the start end is the small pipe's
    comps = _merged(
        [Pipe("P1", (0, 0, 0), (1.9, 0, 0), 0.1143), Pipe("P2", (2.1, 0, 0), (4, 0, 0), 0.1683)]
    )
    reducer = comps["P1-P2"].geometry
    assert (_bore(reducer, "start"), _bore(reducer, "end")) == pytest.approx(
        (BORE4, BORE6), abs=1e-9
    )


def test_a_reducing_tee_has_the_run_bore_and_the_branch_bore():
    """NPS 6 run with an NPS 2 outlet (SCH 40): the run keeps 7.11 mm, the outlet 3.91 mm."""
    from synthetic_pipes import Pipe

    comps = _merged(
        [
            Pipe("P1", (0, 0, 0), (1.8, 0, 0), 0.1683),
            Pipe("P2", (2.2, 0, 0), (4, 0, 0), 0.1683),
            Pipe("P3", (2, 0.2, 0), (2, 2, 0), 0.0603),
        ]
    )
    tee = comps["P1-P2-P3"].geometry
    assert _bore(tee, "run") == pytest.approx(BORE6, abs=1e-9)
    assert _bore(tee, "branch") == pytest.approx(BORE2, abs=1e-9)


def test_a_run_that_reduces_at_a_tee_gets_a_tee_and_a_reducer_with_each_pipes_bore():
    """NPS 6 x 4 run with an NPS 2 outlet: a NPS 6 tee and a 6 x 4 reducer on the NPS 4 side."""
    from synthetic_pipes import Pipe

    comps = _merged(
        [
            Pipe("P1", (0, 0, 0), (1.8, 0, 0), 0.1683),
            Pipe("P2", (2.4, 0, 0), (4, 0, 0), 0.1143),
            Pipe("P3", (2, 0.2, 0), (2, 2, 0), 0.0603),
        ]
    )
    (tee,) = [c.geometry for c in comps.values() if c.type == "tee"]
    (reducer,) = [c.geometry for c in comps.values() if c.type == "reducer"]
    assert (_bore(tee, "run"), _bore(tee, "branch")) == pytest.approx((BORE6, BORE2), abs=1e-9)
    assert (_bore(reducer, "start"), _bore(reducer, "end")) == pytest.approx(
        (BORE6, BORE4), abs=1e-9
    )


def _b36_10m(nps: str, schedule: str) -> tuple[float, float]:
    """(OD, wall) in metres of NPS ``nps`` in ``schedule``, read as text from
    catalogs/asme-b36.10m.csv (not through asbuilt.catalog)."""
    import csv
    from pathlib import Path

    path = Path(__file__).parents[2] / "catalogs" / "asme-b36.10m.csv"
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    for row in csv.DictReader(lines):
        if row["nominal"] == nps:
            return float(row["od"]) / 1000, float(row[f"wall_{schedule.lower()}"]) / 1000
    raise KeyError(nps)


@pytest.mark.parametrize("large_first", [True, False])
def test_an_elbow_between_two_sizes_has_each_pipes_od_and_bore_at_its_end(large_first):
    """NPS 6 and NPS 4 SCH 40 at an elbow: each end is its pipe's size and wall (B16.9
    reducing elbow). It was the NPS 6 OD with the NPS 4 wall at both ends: a 1.09 mm bore step
    at the NPS 6 weld, a 27 mm (radius) OD step and 27 mm bore step at the NPS 4 weld."""
    from synthetic_pipes import Pipe

    (od6, w6), (od4, w4) = _b36_10m("6", "40"), _b36_10m("4", "40")
    first, second = (od6, od4) if large_first else (od4, od6)
    comps = _merged(
        [
            Pipe("P1", (0, 0, 1), (1.8, 0, 1), first),
            Pipe("P2", (2.0, 0.2, 1), (2.0, 2.0, 1), second),
        ]
    )
    elbow = comps["P1-P2"]
    assert elbow.type == "elbow"
    g = elbow.geometry
    welds = {}
    for point, radius, wall in zip((g.start, g.end), g.radii, g.walls):
        (pipe,) = [
            p.geometry
            for p in (comps["P1"], comps["P2"])
            if min(np.linalg.norm(p.geometry.start - point), np.linalg.norm(p.geometry.end - point))
            < 1e-9
        ]
        # the fitting's end matches the pipe welded there, outside and inside
        assert radius == pytest.approx(pipe.outer_radius, abs=1e-12)
        assert radius - wall == pytest.approx(pipe.outer_radius - pipe.wall, abs=1e-12)
        welds[round(2 * radius, 4)] = (2 * radius, 2 * (radius - wall))
    assert welds[round(od6, 4)] == pytest.approx((od6, od6 - 2 * w6), abs=1e-9)
    assert welds[round(od4, 4)] == pytest.approx((od4, od4 - 2 * w4), abs=1e-9)
    # the larger end first, as B16.9 names reducing elbows (and readers of one size see it)
    assert g.outer_radius == pytest.approx(od6 / 2) and g.wall == pytest.approx(w6)
    assert "reducing elbow" in " ".join(elbow.snap["notes"])
