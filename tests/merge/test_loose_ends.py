"""A pipe end merging leaves joined to nothing though it runs into a fitting or another pipe.

Merging joins each pipe end to one other, at most three pipes at a tee (the catalog has no
crosses): a fourth pipe at a tee, or a pipe ending on another's side at an angle no tee makes,
was left loose without a word. Now merging records it (``snap["loose_ends"]``) and
``asbuilt check`` reports it as AB304 ``unjoined-end``. Geometry hand-drawn: NPS 4 (OD 114.3 mm)
pipes, ``joint_distance`` 0.15 m, a tee's run ends 105 mm from its centre (B16.9 C).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.export.model_json import dumps_model, load_model
from asbuilt.merge import merge_model
from asbuilt.rules import check_model, load_rules

OD = 0.1143

#: a run along x split at x = 2, branches along y stopping 0.15 m from the run axis
RUN = [Pipe("P1", (0, 0, 0), (1.9, 0, 0), OD), Pipe("P2", (2.1, 0, 0), (4, 0, 0), OD)]
UP = Pipe("P3", (2, 0.15, 0), (2, 2, 0), OD)
DOWN = Pipe("P4", (2, -0.15, 0), (2, -2, 0), OD)
#: a cross's fourth pipe 60 mm along the run from the outlet's line (the skew tolerance is
#: 29 mm): no cross (merge.crosses), the tee and a loose P4 with a note saying why
OFFSET = [*RUN, UP, Pipe("P4", (2.06, -0.15, 0), (2.06, -2, 0), OD)]
#: a fourth pipe rising from the tee, square to both run and outlet: no note, one AB304
RISING = [*RUN, UP, Pipe("P4", (2, 0, 0.15), (2, 0, 2), OD)]

LOOSE = [
    # (four pipes meeting as a cross are a cross now: merge.crosses, tests/merge/test_crosses.py)
    # a fourth pipe rising from the tee, square to both run and outlet: no B16.9 fitting
    pytest.param(
        [*RUN, UP, Pipe("P4", (2, 0, 0.15), (2, 0, 2), OD)],
        [],
        "P4",
        "P1-P2-P3",
        "no ASME B16.9 fitting joins a fourth pipe",
        id="fourth-out-of-plane",
    ),
    # a pipe ending on another's side at 55 degrees: no tee (B16.9 outlets are square)
    pytest.param(
        [Pipe("P1", (0, 0, 0), (4, 0, 0), OD), Pipe("P2", (2, 0.06, 0), (3, 1.5, 0), OD)],
        [],
        "P2",
        "P1",
        "at 55 degrees",
        id="oblique-on-a-pipe",
    ),
    # a pipe ending on the outside of an elbow
    pytest.param(
        [
            Pipe("P1", (0, 0, 0), (3.8, 0, 0), OD),
            Pipe("P5", (4, 0, 0.2), (4, 0, 2), OD),
            Pipe("P2", (3.955, 0.1, 0.045), (3.955, 2, 0.045), OD),
        ],
        [],
        "P2",
        "P1-P5",
        "the elbow already joins P1 and P5",
        id="on-an-elbow",
    ),
]


def _unjoined(model, config=None):
    return [f for f in check_model(model, config=config) if f.slug == "unjoined-end"]


@pytest.mark.parametrize(("pipes", "links", "pipe", "target", "why"), LOOSE)
def test_a_loose_pipe_end_at_a_fitting_or_pipe_is_one_finding(pipes, links, pipe, target, why):
    model = merge_model(report_of(pipes, links=links))
    (record,) = [r for c in model.components for r in c.snap.get("loose_ends", ())]
    assert record["touches"] == target and not record["noted"]
    (f,) = _unjoined(model)
    assert (f.code, f.severity, f.objects) == ("AB304", "warning", (pipe, target))
    assert (
        f.message.startswith(f"{pipe} ends ") and f" {target} but is not joined to it" in f.message
    )
    assert why in f.message
    assert f.location is not None and f.suggestions and pipe in f.suggestions[0].description


def test_a_fourth_pipe_off_the_outlets_line_is_one_merge_note():
    """Before crosses were built, the fourth pipe of a cross was this AB304; off the outlet's
    line now, merging's note says why no cross is built and the AB304 is left to it."""
    model = merge_model(report_of(OFFSET))
    (record,) = [r for c in model.components for r in c.snap.get("loose_ends", ())]
    assert record["touches"] == "P1-P2-P3" and record["noted"]
    found = [f for f in check_model(model) if f.code in ("AB302", "AB304")]
    (f,) = found
    assert f.code == "AB302" and "P4" in f.objects
    assert "their axes are 60 mm apart" in f.message and "no cross is built" in f.message


def test_the_fourth_pipe_finding_reads_as_documented(tmp_path):
    path = tmp_path / "rules.toml"
    path.write_text('ignore = ["merge-note"]\n')
    (f,) = _unjoined(merge_model(report_of(OFFSET)), config=load_rules(path))
    assert f.message == (
        "P4 ends 92.9 mm from the tee P1-P2-P3 but is not joined to it: the tee already joins "
        "P1, P2 and P3, and P4 does not meet it as a cross's fourth pipe (merging builds a "
        "cross where both outlets are of one size on one line; its notes say what is off)"
    )
    assert f.suggestions[0].description == (
        "if P4 is welded to P1-P2-P3 on site, the fitting is a cross: check the pipes' "
        "positions and sizes (a cross's outlets are on one line, of one size) or model it by "
        "hand; if not, scan P4 up to its end"
    )
    assert f.measured == pytest.approx(0.15 - OD / 2, abs=1e-4)
    assert list(f.location) == pytest.approx([2.06, -0.15, 0])


JOINED = [
    pytest.param([*RUN, UP], [], id="tee"),
    pytest.param([RUN[0], Pipe("P2", (2.1, 0.2, 0), (2.1, 2, 0), OD)], [], id="elbow"),
    pytest.param([*RUN, Pipe("P3", (2.1, 0.15, 0), (3.2, 1.5, 0), OD)], [], id="lateral"),
    # crossing over the tee 0.3 m above it: the pipes do not meet
    pytest.param([*RUN, UP, Pipe("P4", (1, -1, 0.3), (1, 1, 0.3), OD)], [], id="passes-above"),
    # a rack: three parallel pipes 0.2 m apart, ends side by side
    pytest.param(
        [
            Pipe(f"P{k}", (0.1 * (k == 3), 0.2 * k, 0), (4 + 0.1 * (k == 3), 0.2 * k, 0), OD)
            for k in (1, 2, 3)
        ],
        [],
        id="rack",
    ),
    # ending 0.34 m short of a pipe's side: beyond joint_distance
    pytest.param(
        [Pipe("P1", (0, 0, 0), (4, 0, 0), OD), Pipe("P2", (2, 0.4, 0), (3, 1.5, 0), OD)],
        [],
        id="short",
    ),
    # its axis passes 130 mm above the other's: the pipes do not meet
    pytest.param(
        [Pipe("P1", (0, 0, 0), (4, 0, 0), OD), Pipe("P2", (2, 0.1, 0.13), (2, 2, 0.13), OD)],
        [],
        id="axis-misses",
    ),
]


@pytest.mark.parametrize(("pipes", "links"), JOINED)
def test_no_finding_where_every_end_is_joined_or_free(pipes, links):
    model = merge_model(report_of(pipes, links=links))
    assert not [c.id for c in model.components if c.snap.get("loose_ends")]
    assert not _unjoined(model)


#: the scan links the run to the fourth pipe, whose end the tee P1-P2-P3 took: merging's note
#: (AB302) says so already
LINKED_FOURTH = [("P1", "P4"), ("P1", "P3")]


def test_a_link_merging_already_notes_is_one_finding():
    model = merge_model(report_of(OFFSET, links=LINKED_FOURTH))
    (record,) = [r for c in model.components for r in c.snap.get("loose_ends", ())]
    assert record["touches"] == "P1-P2-P3" and record["noted"]
    found = check_model(model)
    assert [f.code for f in found if f.code in ("AB302", "AB304")] == ["AB302"]


@pytest.mark.parametrize(
    "rules",
    ['ignore = ["merge-note"]', '[unjoined-end]\nseverity = "error"'],
    ids=["merge-note-ignored", "unjoined-end-graver"],
)
def test_the_linked_fourth_pipe_is_reported_when_the_note_would_not_say_it(rules, tmp_path):
    path = tmp_path / "rules.toml"
    path.write_text(rules + "\n")
    model = merge_model(report_of(OFFSET, links=LINKED_FOURTH))
    (f,) = _unjoined(model, config=load_rules(path))
    assert f.objects == ("P4", "P1-P2-P3")


@pytest.mark.parametrize(
    "rules", ['ignore = ["AB304"]', 'ignore = ["unjoined-end"]', 'select = ["AB2"]']
)
def test_the_rule_can_be_deselected(rules, tmp_path):
    path = tmp_path / "rules.toml"
    path.write_text(rules + "\n")
    assert not _unjoined(merge_model(report_of(RISING)), config=load_rules(path))


def test_the_severity_is_configurable(tmp_path):
    path = tmp_path / "rules.toml"
    path.write_text('[unjoined-end]\nseverity = "error"\n')
    (f,) = _unjoined(merge_model(report_of(RISING)), config=load_rules(path))
    assert f.severity == "error"


def test_the_model_document_carries_the_loose_end(tmp_path):
    model = merge_model(report_of(RISING))
    text = dumps_model(model)
    (entry,) = [c for c in json.loads(text)["components"] if c["snap"].get("loose_ends")]
    assert entry["id"] == "P4" and entry["snap"]["loose_ends"][0]["touches"] == "P1-P2-P3"
    path = tmp_path / "model.json"
    path.write_text(text)
    (f,) = _unjoined(load_model(path))
    assert f.objects == ("P4", "P1-P2-P3")


#: an NPS 4 90 degree elbow at (2, 0, 0): P1's shots reach its weld (B16.9 long radius, 152 mm
#: centre to end); the riser P2's stop 0.75 m from the corner, beyond joint_distance (its foot
#: hidden from the station)
HIDDEN_ELBOW = [
    Pipe("P1", (0, 0, 0), (1.848, 0, 0), OD),
    Pipe("P2", (2, 0.75, 0), (2, 3, 0), OD),
]


def test_ends_whose_axes_meet_beyond_the_reach_are_one_finding_that_a_link_settles():
    model = merge_model(report_of(HIDDEN_ELBOW))
    assert not [c for c in model.components if c.type == "elbow"]
    records = {c.id: r for c in model.components for r in c.snap.get("loose_ends", ())}
    assert set(records) == {"P1", "P2"}
    first = records["P1"]
    assert first["touches"] == "P2" and first["corner"] == pytest.approx([2, 0, 0], abs=1e-9)
    assert (first["gap"], first["beyond"]) == pytest.approx((0.152, 0.75))
    assert first["bend_deg"] == pytest.approx(90.0)
    (f,) = _unjoined(model)
    assert f.message == (
        "P1 ends 152.0 mm short of a corner with P2 but is not joined to it: their axes meet "
        "152.0 mm past its end and 750.0 mm past P2's, where a 90 degree elbow would join "
        "them, beyond merging's reach (joint_distance plus the shot spacing)"
    )
    assert "link P1 and P2 in the scan" in f.suggestions[0].description
    linked = merge_model(report_of(HIDDEN_ELBOW, links=[("P1", "P2")]))
    assert [c.type for c in linked.components].count("elbow") == 1
    assert not _unjoined(linked)


def test_a_pipe_continuing_another_s_line_beyond_the_reach_is_a_finding():
    pipes = [Pipe("P1", (0, 0, 0), (1.9, 0, 0), OD), Pipe("P2", (2.6, 0.01, 0), (4, 0.01, 0), OD)]
    model = merge_model(report_of(pipes))
    (f,) = _unjoined(model)
    assert f.message.startswith("P1 ends 700.0 mm short of P2 but is not joined to it: P2 ")
    assert "continues its line 700.0 mm past its end" in f.message


@pytest.mark.parametrize(
    "pipes",
    [
        # the corner 2.25 m past P2's end: farther than FACING_REACH
        [HIDDEN_ELBOW[0], Pipe("P2", (2, 2.25, 0), (2, 4, 0), OD)],
        # the riser's axis passes 0.2 m beside the corner: no elbow joins them
        [HIDDEN_ELBOW[0], Pipe("P2", (2, 0.75, 0.2), (2, 3, 0.2), OD)],
        # the corner behind P1's end: P2 runs past P1's end, not toward it
        [Pipe("P1", (0, 0, 0), (1.5, 0, 0), OD), Pipe("P2", (1.2, 0.75, 0), (1.2, 3, 0), OD)],
        # a 120 degree turn: no elbow makes it
        [HIDDEN_ELBOW[0], Pipe("P2", (2 - 0.375, 0.65, 0), (2 - 1.5, 2.6, 0), OD)],
    ],
    ids=["too-far", "beside", "behind", "too-sharp"],
)
def test_no_finding_for_ends_that_do_not_face_each_other(pipes):
    model = merge_model(report_of(pipes))
    assert not _unjoined(model)


def _facing(kind: str, gap: float) -> list:
    """Two NPS 4 pipes facing each other from ``gap`` metres: at a corner (P2's end 0.8 gap
    off P1's axis), or in line."""
    if kind == "corner":
        return [
            Pipe("P1", (0, 0, 1), (2, 0, 1), OD),
            Pipe("P2", (2 + gap, 0.8 * gap, 1), (2 + gap, 3, 1), OD),
        ]
    return [Pipe("P1", (0, 0, 1), (2, 0, 1), OD), Pipe("P2", (2 + gap, 0, 1), (4 + gap, 0, 1), OD)]


@pytest.mark.parametrize(
    "kind, gap",
    [("corner", g) for g in (0.4, 0.6, 0.8, 0.9, 1.2)]
    + [("inline", g) for g in (0.6, 1.0, 1.1, 1.4)],
)
def test_a_facing_end_is_linkable_exactly_when_a_link_would_join_it(kind, gap):
    """The record's ``linkable`` (offered to the user as a scan link to accept) agrees with what
    merging does when the scan links the pair: the same pipes in one spool."""
    pipes = _facing(kind, gap)
    records = [
        r for c in merge_model(report_of(pipes)).components for r in c.snap.get("loose_ends") or ()
    ]
    assert records and all("linkable" in r for r in records)
    linked = merge_model(report_of(pipes, links=[("P1", "P2")]))
    spools = {c.id: c.spool for c in linked.components}
    joined = spools["P1"] is not None and spools["P1"] == spools["P2"]
    assert {r["linkable"] for r in records} == {joined}


@pytest.mark.parametrize(("gap", "offered"), [(0.6, True), (1.2, False)])
def test_unjoined_end_offers_the_link_only_where_it_would_join(gap, offered):
    model = merge_model(report_of(_facing("corner", gap)))
    (finding,) = [f for f in check_model(model) if f.slug == "unjoined-end"]
    changes = [s for s in finding.suggestions if s.change]
    if offered:
        (link,) = changes
        assert link.change == {"objects": ["P1", "P2"], "field": "link"}
        assert not link.unambiguous  # only a person knows an elbow is there
        assert link.description.endswith("merging then joins them with an elbow")
        assert "accept the link" in finding.suggestions[-1].description
    else:
        assert changes == []
        assert "too far apart for a scan link to join" in finding.suggestions[-1].description


# Parallel pipes side by side whose solids touch or pass through each other along their length
# (independent review 59, defect 2: an NPS 8 and an NPS 6, axes 150 mm apart, 44 mm into each
# other over 2.2 m) were recorded as loose ends on each other, and AB304 suggested a weldolet
# for what is no branch: each end's swept reach met the other pipe beside it. They are the clash
# rule's (tests/rules/test_clash.py). B36.10M outside diameters.
OD6, OD8 = 0.1683, 0.2191
BIG = Pipe("P1", (0, -1.1, 0), (0, 1.1, 0), OD8)
SIDE_BY_SIDE = {
    "side-by-side": [BIG, Pipe("P2", (0.15, -1.1, 0), (0.15, 1.1, 0), OD6)],
    "vertical-stack": [BIG, Pipe("P2", (0, -1.1, 0.15), (0, 1.1, 0.15), OD6)],
    "staggered": [BIG, Pipe("P2", (0.15, 0.1, 0), (0.15, 2.5, 0), OD6)],
    "same-size-70-mm-apart": [
        Pipe("P1", (0, -1.5, 0), (0, 1.5, 0), OD),
        Pipe("P2", (0.07, -1.5, 0), (0.07, 1.5, 0), OD),
    ],
    "touching": [BIG, Pipe("P2", ((OD8 + OD6) / 2, -1.1, 0), ((OD8 + OD6) / 2, 1.1, 0), OD6)],
    "1-mm-apart": [
        BIG,
        Pipe("P2", ((OD8 + OD6) / 2 + 0.001, -1.1, 0), ((OD8 + OD6) / 2 + 0.001, 1.1, 0), OD6),
    ],
}


@pytest.mark.parametrize("case", list(SIDE_BY_SIDE))
def test_pipes_side_by_side_are_not_loose_on_each_other(case):
    model = merge_model(report_of(SIDE_BY_SIDE[case]))
    assert not [r for c in model.components for r in c.snap.get("loose_ends") or ()]
    assert not _unjoined(model)


def test_a_pipe_converging_on_another_s_side_is_still_a_loose_end():
    """5 degrees off the other, its end touching its side: it ends on it (no fitting makes
    that), its body 13 mm clear of the other 0.15 m back, so it does not run alongside."""
    t = np.radians(5.0)
    r = OD / 2
    end = np.array([0.0, 2 * r, 0.0])
    start = end + 1.5 * np.array([-np.cos(t), np.sin(t), 0.0])
    pipes = [Pipe("P1", (-2, 0, 0), (2, 0, 0), OD), Pipe("P2", tuple(start), tuple(end), OD)]
    model = merge_model(report_of(pipes))
    (record,) = model.components[[c.id for c in model.components].index("P2")].snap["loose_ends"]
    assert record["touches"] == "P1" and record["angle_deg"] == pytest.approx(5.0)
    (f,) = _unjoined(model)
    assert (f.code, f.objects) == ("AB304", ("P2", "P1"))
