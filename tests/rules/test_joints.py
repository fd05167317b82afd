"""joint-gap: gaps measured by hand; elbow centre-to-end from ASME B16.9 (NPS 4 LR: 152 mm)."""

import dataclasses
import json

import numpy as np
import pytest
from rules_builders import B36, model, pipe

from asbuilt.model import Bend, Component
from asbuilt.rules import check_model
from asbuilt.rules.joints import joint_geometry
from asbuilt.scan.model import Scan, ScanObject


def gaps(*components):
    found = check_model(model(*components), catalog=B36_FITTINGS)
    return [f for f in found if f.slug == "joint-gap"]


@pytest.mark.parametrize(
    "gap, expected",
    [(0.0, None), (0.002, None), (0.0029, None), (0.05, "gap"), (0.12, "gap"), (-0.04, "overlap")],
)
def test_collinear_gap(gap, expected):
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    b = pipe("P2", [2 + gap, 0, 1], [4, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    found = gaps(a, b)
    if expected is None:
        assert not found
        return
    (f,) = found
    assert f.message.startswith(f"{expected} of {abs(gap) * 1000:.1f} mm")
    assert f.measured == pytest.approx(abs(gap))
    assert f.objects == ("P1", "P2")


@pytest.mark.parametrize("linked", [False, True], ids=["unlinked", "linked"])
@pytest.mark.parametrize("merged", [False, True], ids=["unmerged", "merged"])
def test_a_linked_gap_is_checked_like_an_unlinked_one(linked, merged):
    """A scan link says the pipes should be joined, not that they are: every linked pair was
    skipped as joined, so a 50 mm gap between linked collinear pipes went unreported (as with
    ``asbuilt check --no-merge``) while the same pipes unlinked were reported."""
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    b = pipe("P2", [2.05, 0, 1], [4, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    scan = Scan(
        units="m",
        objects=tuple(
            ScanObject(id=c.id, kind="cylinder", points=np.zeros((6, 3)), index=k)
            for k, c in enumerate((a, b))
        ),
        links=(("P1", "P2"),) if linked else (),
    )
    found = [
        f
        for f in check_model(model(a, b, scan=scan, merged=merged), catalog=B36)
        if f.slug == "joint-gap"
    ]
    assert [(f.objects, f.measured) for f in found] == [(("P1", "P2"), pytest.approx(0.05))]


#: ASME B16.9 (the standards reference): NPS 4 equal tee run C 105 mm, 4 x 3 reducer H 102 mm.
B36_FITTINGS = dataclasses.replace(
    B36, tee_run={"4": 0.105, "6": 0.143}, reducer={"4": 0.102, "6": 0.140}
)


@pytest.mark.parametrize("branch", [True, False], ids=["branch", "no-branch"])
@pytest.mark.parametrize("gap, found", [(0.210, False), (0.212, False), (0.26, True)])
def test_a_tee_run_explains_a_collinear_gap_where_a_branch_crosses(branch, gap, found):
    """An unmerged tee (``--no-merge``): the run's gap is the tee's 2 x C where a third pipe's
    axis crosses it; without a branch nothing explains it."""
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    b = pipe("P2", [2 + gap, 0, 1], [4, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    middle = 2 + gap / 2
    c = pipe("P3", [middle, 0.105, 1], [middle, 1.5, 1], 0.1143, nominal="4", length_se=0.0005)
    found_gaps = linked_gaps(a, b, *((c,) if branch else ()))
    if branch and not found:
        assert not found_gaps
        return
    (f,) = found_gaps
    if branch:
        assert f.measured == pytest.approx(gap - 0.210)
        assert "tee's run (2 x C) of 210.0 mm" in f.message
    else:
        assert f.measured == pytest.approx(gap)
        assert "which no catalog fitting explains" in f.message


def linked_gaps(*components, catalog=B36_FITTINGS):
    """joint-gap findings on P1-P2 of an unmerged model whose scan links P1 and P2."""
    scan = Scan(
        units="m",
        objects=tuple(
            ScanObject(id=c.id, kind="cylinder", points=np.zeros((6, 3)), index=k)
            for k, c in enumerate(components)
        ),
        links=(("P1", "P2"),),
    )
    found = check_model(model(*components, scan=scan, merged=False), catalog=catalog)
    return [f for f in found if f.slug == "joint-gap" and f.objects == ("P1", "P2")]


def test_a_tee_run_explains_a_gap_only_with_the_fittings_table():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    b = pipe("P2", [2.21, 0, 1], [4, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    c = pipe("P3", [2.105, 0.105, 1], [2.105, 1.5, 1], 0.1143, nominal="4", length_se=0.0005)
    assert not linked_gaps(a, b, c)
    assert [f.objects for f in linked_gaps(a, b, c, catalog=B36)] == [("P1", "P2")]


@pytest.mark.parametrize("gap, found", [(0.102, False), (0.15, True)])
def test_a_reducer_explains_the_gap_between_two_sizes(gap, found):
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    b = pipe("P2", [2 + gap, 0, 1], [4, 0, 1], 0.0889, nominal="3", length_se=0.0005)
    result = linked_gaps(a, b)
    assert bool(result) == found
    if found:
        assert result[0].measured == pytest.approx(gap - 0.102)
        assert "NPS 4 reducer's H of 102.0 mm" in result[0].message


def test_an_unsnapped_pipe_takes_the_nearest_size_for_the_fitting():
    """``--no-merge``: fitted ODs 1 mm off the catalog's still name the reducer."""
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1153, length_se=0.0005)
    b = pipe("P2", [2.102, 0, 1], [4, 0, 1], 0.0880, length_se=0.0005)
    assert not linked_gaps(a, b)


def test_uncertain_ends_make_a_small_gap_unverifiable():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", length_se=0.01)
    b = pipe("P2", [2.02, 0, 1], [4, 0, 1], 0.1143, nominal="4", length_se=0.01)
    (f,) = gaps(a, b)
    assert f.unverifiable and f.severity == "warning"


def test_elbow_distance_explains_a_corner():
    # two NPS 4 pipes at 90 degrees whose ends stop 152 mm from the corner: an LR elbow fits
    a = pipe("P1", [0, 0, 1], [2 - 0.152, 0, 1], 0.1143, nominal="4")
    b = pipe("P2", [2, 0.152, 1], [2, 2, 1], 0.1143, nominal="4")
    assert not gaps(a, b)


def test_corner_without_room_for_an_elbow_is_flagged():
    a = pipe("P1", [0, 0, 1], [2 - 0.06, 0, 1], 0.1143, nominal="4", length_se=0.001)
    b = pipe("P2", [2, 0.06, 1], [2, 2, 1], 0.1143, nominal="4", length_se=0.001)
    (f,) = gaps(a, b)
    assert f.measured == pytest.approx(0.152 - 0.06)
    assert f.message.startswith("overlap")


def test_pipes_joined_through_a_fitting_are_not_checked():
    a = pipe("P1", [0, 0, 1], [2 - 0.152, 0, 1], 0.1143, nominal="4")
    elbow = Component(
        id="P1-P2",
        type="elbow",
        geometry=Bend([2 - 0.152, 0, 1], [2, 0.152, 1], [2 - 0.152, 0.152, 1], 0.1143 / 2),
    )
    b = pipe("P2", [2, 0.152, 1], [2, 2, 1], 0.1143, nominal="4")
    assert not gaps(a, elbow, b)


def test_joint_geometry_of_a_corner():
    from asbuilt.model import Straight

    geo = joint_geometry(
        Straight([0, 0, 0], [1, 0, 0], 0.05), Straight([1.2, 0.3, 0], [1.2, 2, 0], 0.05)
    )
    assert geo["angle_deg"] == pytest.approx(90.0)
    np.testing.assert_allclose(geo["corner"], [1.2, 0, 0], atol=1e-12)
    assert geo["da"] == pytest.approx(0.2) and geo["db"] == pytest.approx(0.3)


def test_merge_notes_are_findings_once_per_note():
    # A note merging left on both pipes of a link it could not make is one finding naming both;
    # a note on one pipe is its own finding.
    link = "the scan links P1 and P2, but they are 2.93 m apart: not joined"
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4")
    b = pipe("P2", [4.93, 0, 1], [6, 0, 1], 0.1143, nominal="4")
    a.snap["merge_notes"] = [link, "extended 269 mm at its end beyond its last shot"]
    b.snap["merge_notes"] = [link]
    found = [f for f in check_model(model(a, b), catalog=B36) if f.slug == "merge-note"]
    assert sorted((f.objects, f.message) for f in found) == [
        (("P1",), "extended 269 mm at its end beyond its last shot"),
        (("P1", "P2"), link),
    ]
    assert all(f.code == "AB302" and f.severity == "warning" for f in found)


def test_elbow_fallback_reads_a_dn_size_by_its_nps():
    # EN 10220 has no fittings table: a long-radius elbow's centre-to-end falls back to 1.5 NPS
    # (ASME B16.9 long radius). DN 150 is NPS 6: 1.5 x 6 in = 228.6 mm at 90 degrees; the bare
    # "150" was read as NPS 150 (5.7 m).
    from asbuilt.rules._catalog import size_table
    from asbuilt.rules.joints import _elbow_centre_to_end

    table = size_table("en-10220")
    assert _elbow_centre_to_end(table, "150", 0.1683, 90.0) == pytest.approx(0.2286)


def test_fit_up_is_one_finding_per_pair_with_the_miss_and_its_standard_error():
    # merging records the miss on both pipes (and on every piece of a split pipe): one finding
    entry = {"miss": 0.030, "stderr": 0.004, "allowed": 0.012, "at": [2.0, 0.0, 1.0]}
    a1 = pipe("P1.1", [0, 0, 1], [1, 0, 1], 0.1683, nominal="6")
    a2 = pipe("P1.2", [1.3, 0, 1], [1.8, 0, 1], 0.1683, nominal="6")
    b = pipe("P2", [2, 0.2, 1.03], [2, 2, 1.03], 0.1683, nominal="6")
    for piece in (a1, a2):
        object.__setattr__(piece, "sources", ("P1",))
        piece.snap["fit_up"] = [{**entry, "with": "P2"}]
    b.snap["fit_up"] = [{**entry, "with": "P1"}]
    (f,) = [f for f in check_model(model(a1, a2, b), catalog=B36) if f.slug == "fit-up"]
    assert f.code == "AB303" and f.severity == "warning"
    assert f.objects == ("P1.1", "P1.2", "P2")
    assert (f.measured, f.stderr, f.allowed) == (0.030, 0.004, 0.012)
    assert "30.0 mm (+- 4.0 mm)" in f.message


# A linked pair no fitting realises: merging says why (AB302) and joint-gap measured the same
# gap again (AB301), two findings on one pair for one problem. The pair is reported once, as
# merging's note, which names the cause (too far apart, axes that miss, a bend past an elbow).

_PIPE_NPS4 = 0.1143  # ASME B36.10M NPS 4 OD


def _linked_scene(p2_start, p2_end) -> dict:
    """A station 5 m from an NPS 4 pipe P1 on x (x -2.5..-0.1 m) and a pipe P2 the scan links
    to it."""
    return {
        "format": "asbuilt-scene",
        "version": 1,
        "units": "m",
        "seed": 7,
        "points": 32,
        "stations": [
            {
                "id": "S1",
                "position": [0.0, 0.0, 1.5],
                "range_sigma": 0.002,
                "angular_sigma_deg": 0.01,
            }
        ],
        "objects": [
            {
                "id": "P1",
                "kind": "cylinder",
                "geometry": {
                    "type": "cylinder",
                    "start": [-2.5, 5.0, 1.0],
                    "end": [-0.1, 5.0, 1.0],
                    "od": _PIPE_NPS4,
                },
            },
            {
                "id": "P2",
                "kind": "cylinder",
                "geometry": {
                    "type": "cylinder",
                    "start": p2_start,
                    "end": p2_end,
                    "od": _PIPE_NPS4,
                },
            },
        ],
        "links": [["P1", "P2"]],
    }


@pytest.mark.parametrize(
    "p2_start, p2_end, cause",
    [
        ([2.9, 5.0, 1.0], [5.3, 5.0, 1.0], "apart (a link may bridge"),  # 3 m gap in line
        ([0.1, 5.0, 1.4], [2.5, 5.0, 1.4], "their axes do not meet"),  # parallel, 0.4 m up
        ([0.0, 5.0, 1.1], [-1.0, 5.0, 2.8], "degree bend, beyond an elbow"),  # 120 degrees
    ],
    ids=["too-far", "offset", "past-an-elbow"],
)
def test_a_link_merging_could_not_make_is_one_finding_not_two(p2_start, p2_end, cause):
    from asbuilt.pipeline import build_model
    from asbuilt.scan import loads_scan
    from asbuilt.sim.scene import scene_from_dict
    from asbuilt.sim.simulate import simulate_scan

    doc = simulate_scan(scene_from_dict(_linked_scene(p2_start, p2_end)), seed=7)
    found = build_model(loads_scan(json.dumps(doc))).findings
    on_pair = [f for f in found if set(f.objects) == {"P1", "P2"}]
    assert [(f.code, f.slug) for f in on_pair] == [("AB302", "merge-note")]
    assert cause in on_pair[0].message


def _unrealised_link(gap=0.5):
    """P1 and P2 in line ``gap`` apart, linked, carrying merging's note that it could not
    join them (as merging leaves it: on both pipes), and no fitting between them."""
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    b = pipe("P2", [2 + gap, 0, 1], [4, 0, 1], 0.1143, nominal="4", length_se=0.0005)
    note = "the scan links P1 and P2, but they are 0.50 m apart: not joined"
    a.snap["merge_notes"] = [note]
    b.snap["merge_notes"] = [note]
    scan = Scan(
        units="m",
        objects=tuple(
            ScanObject(id=c.id, kind="cylinder", points=np.zeros((6, 3)), index=k)
            for k, c in enumerate((a, b))
        ),
        links=(("P1", "P2"),),
    )
    return model(a, b, scan=scan, merged=False)


def test_joint_gap_leaves_a_pair_to_the_merge_note_that_says_why():
    found = check_model(_unrealised_link(), catalog=B36)
    assert [(f.code, f.objects) for f in found if f.code in ("AB301", "AB302")] == [
        ("AB302", ("P1", "P2"))
    ]


@pytest.mark.parametrize(
    "rules",
    [
        'ignore = ["merge-note"]',  # the note is not reported: the gap is
        'select = ["AB301"]',
        '[joint-gap]\nseverity = "error"',  # a gate on gaps keeps its error
    ],
    ids=["merge-note-ignored", "joint-gap-alone", "joint-gap-graver"],
)
def test_joint_gap_still_reports_the_pair_when_the_note_would_not_say_it(rules, tmp_path):
    from asbuilt.rules import load_rules

    path = tmp_path / "rules.toml"
    path.write_text(rules + "\n")
    found = check_model(_unrealised_link(), config=load_rules(path), catalog=B36)
    gap = [f for f in found if f.code == "AB301"]
    assert [(f.objects, f.measured) for f in gap] == [(("P1", "P2"), pytest.approx(0.5))]


def test_a_note_on_one_pipe_of_the_pair_leaves_the_gap_to_joint_gap():
    m = _unrealised_link()
    a, b = m.components
    b.snap["merge_notes"] = ["extended 269 mm at its end beyond its last shot"]
    a.snap["merge_notes"] = ["extended 269 mm at its end beyond its last shot"]
    found = check_model(m, catalog=B36)
    assert [f.objects for f in found if f.code == "AB301"] == [("P1", "P2")]
