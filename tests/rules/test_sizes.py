"""Size rules against hand-computed catalog distances (ASME B36.10M ODs from the standard)."""

import dataclasses

import numpy as np
import pytest
from rules_builders import B36, model, pipe

from asbuilt.rules import check_model, load_rules
from asbuilt.scan.model import Scan, ScanObject


def only(findings, slug):
    return [f for f in findings if f.slug == slug]


def run(*components, scan=None, select=None):
    config = load_rules()
    if select:
        config = config.with_selection(select=[select])
    return check_model(model(*components, scan=scan), config, catalog=B36)


# -- nonstandard-diameter ------------------------------------------------------------------------


def test_nonstandard_diameter_message_names_nearest_size():
    (f,) = only(
        run(pipe("P3", [0, 0, 1], [2, 0, 1], 0.1182, status="no-size")), "nonstandard-diameter"
    )
    assert f.severity == "error" and f.code == "AB101" and f.objects == ("P3",)
    assert f.message == (
        "OD 118.2 mm +- 0.5 mm is no ASME B36.10M size (nearest NPS 4 = 114.3 mm, 3.9 mm off; "
        "a size is taken within the 2.0 mm diameter tolerance)"
    )
    assert f.measured == pytest.approx(0.0039)
    assert f.allowed == pytest.approx(0.002)
    np.testing.assert_allclose(f.location, [1, 0, 1])
    # the two nearest sizes, each a change a person may accept; none applied blindly
    changes = [s.change for s in f.suggestions if s.change]
    assert [c["value"] for c in changes] == ["4", "3"]
    assert not any(s.unambiguous for s in f.suggestions)


def test_snapped_pipe_is_not_nonstandard():
    assert not only(
        run(pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", status="snapped")),
        "nonstandard-diameter",
    )


@pytest.mark.parametrize(
    "od, od_se, expected",
    [
        (0.1143 + 0.0019, 0.0005, None),  # within 2 mm: snaps, no finding
        (0.1143 + 0.0021, 0.0005, None),  # within the 3-sigma window max(1.5, 2) = 2.0? no: 2.1
        (0.1143 + 0.0035, 0.0005, "error"),  # 3.5 - 2 x 0.5 = 2.5 > 2
        (0.1143 + 0.0035, 0.001, "warning"),  # window 3 mm: no size; 3.5 - 2 > ... 1.5 < 2
    ],
)
def test_nonstandard_at_the_tolerance_edge_without_merge_status(od, od_se, expected):
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], od, fit=True, radius_se=od_se / 2)
    found = only(run(comp), "nonstandard-diameter")
    window = max(3 * od_se, 0.002)
    if abs(od - 0.1143) <= window:
        assert not found
        return
    if expected is None:
        # 2.1 mm off with a 2 mm window: no size, but 2.1 - 2 x 0.5 < 2: unverifiable
        assert found and found[0].severity == "warning" and found[0].unverifiable
        return
    assert found[0].severity == expected
    assert found[0].unverifiable == (expected == "warning")


@pytest.mark.parametrize(
    "units, scale, slip",
    [
        ("m", 1000.0, "mm"),  # millimetre numbers in a file that says metres: 114.3 m "pipes"
        ("mm", 0.001 / 0.0254, "in"),  # inch numbers said to be millimetres: 4.5 mm "pipes"
        ("m", 1.0, None),  # right units, a nonstandard pipe: no units suggestion
    ],
)
def test_a_scan_in_the_wrong_units_is_told_so(units, scale, slip):
    # the fit's uncertainty is in the file's numbers too
    se = 0.0005 * scale
    pipes = [
        pipe("P1", [0, 0, 1], [2, 0, 1], 0.1150 * scale, status="no-size", od_stderr=se),
        pipe("P2", [0, 2, 1], [2, 2, 1], 0.0603 * scale, status="no-size", od_stderr=se),
    ]
    if slip is None:
        pipes = [pipe("P1", [0, 0, 1], [2, 0, 1], 0.1182, status="no-size")]
    scan = Scan(units=units, objects=())
    found = only(run(*pipes, scan=scan), "nonstandard-diameter")
    assert len(found) == len(pipes)
    first = found[0].suggestions[0]
    if slip is None:
        assert "units" not in first.description
        return
    assert first.description.startswith(
        f'check the scan\'s "units": its numbers look like {slip}, not {units}; read so, every '
        "pipe of the scan is a catalog size (this one NPS 4 = 114.3 mm)"
    )
    assert first.change == {"field": "units", "value": slip} and not first.unambiguous


@pytest.mark.parametrize("evidence", ["hints", "noise"])
def test_a_unit_slip_with_wide_windows_is_told_by_the_hints_and_the_noise(evidence):
    """Millimetre numbers in a metre file, fitted with 3.3 mm standard errors (2 mm noise, 20
    shots): read as centimetres the pipes fall within a window (100 mm) of NPS 44-48, which
    are 51 mm apart, as closely as they do of NPS 4 read as millimetres. The operator's 4"
    hints, or the fits' 2 mm RMS (20 mm as centimetres: no range finder's noise), say mm
    (seen in review: the check said cm and proposed NPS 46)."""
    import dataclasses

    hints = evidence == "hints"
    # with the hints, an RMS plausible in both readings (0.5 mm / 5 mm): the hints decide
    rms = 0.5 if hints else 2.0
    pipes = []
    for cid, y, od in (("P1", 0.0, 116.41), ("P2", 2000.0, 111.09)):
        p = pipe(
            cid, [0, y, 1], [2000, y, 1], od, status="no-size", od_stderr=3.3, rms=rms, sigma=rms
        )
        if hints:
            p = dataclasses.replace(p, snap={**p.snap, "hint": {"nominal": '4"', "od": 0.1143}})
        pipes.append(p)
    # the shipped catalog: its NPS 44-48 are what a centimetre reading falls among
    found = only(run_shipped(*pipes, scan=Scan(units="m", objects=())), "nonstandard-diameter")
    assert [f.suggestions[0].change for f in found] == [{"field": "units", "value": "mm"}] * 2
    assert all("(this one NPS 4 = 114.3 mm)" in f.suggestions[0].description for f in found)


def test_one_plausible_cylinder_means_the_units_are_right():
    # a 118 mm nonstandard pipe beside a 114 m one: the scan's units stand, no suggestion
    pipes = [
        pipe("P1", [0, 0, 1], [2, 0, 1], 114.3, status="no-size"),
        pipe("P2", [0, 2, 1], [2, 2, 1], 0.1182, status="no-size"),
    ]
    for finding in only(run(*pipes, scan=Scan(units="m", objects=())), "nonstandard-diameter"):
        assert not any("units" in s.description for s in finding.suggestions)


# -- ambiguous-size ------------------------------------------------------------------------------


def test_ambiguous_size_lists_candidates_and_suggests_scanning():
    cands = [{"nominal": "3/4", "od": 0.0267}, {"nominal": "1", "od": 0.0286}]
    comp = pipe(
        "P2", [0, 0, 1], [1, 0, 1], 0.0276, status="ambiguous", od_stderr=0.0012, candidates=cands
    )
    (f,) = only(run(comp), "ambiguous-size")
    assert f.severity == "warning"
    assert "2 sizes" in f.message and "NPS 3/4 = 26.7 mm" in f.message
    texts = " ".join(s.description for s in f.suggestions)
    assert "scan more points" in texts and "hint" in texts
    assert not any(s.unambiguous for s in f.suggestions)


def _run_member(cid, start, end, od_fit, od_stderr, run_ids=("P1", "P2")):
    """A pipe snapped to NPS 8 with the other pipes of its run (merging's joint estimate)."""
    comp = pipe(cid, start, end, 0.2191, status="snapped", od_fit=od_fit, od_stderr=od_stderr)
    snap = {**comp.snap, "od_catalog": 0.2191, "nominal": "8", "run": list(run_ids)}
    return dataclasses.replace(comp, snap=snap, nominal="8")


@pytest.mark.parametrize(
    "od_fit, od_stderr, nearer",
    [
        (0.1871, 0.0150, "NPS 6 (168.3 mm)"),  # the review's reducer: 2.1 standard errors off
        (0.1871, 0.0200, None),  # 1.6 standard errors off: within what the fit allows
        (0.2050, 0.0050, None),  # 2.8 off, but NPS 8 is still the nearest size
        (0.2170, 0.0024, None),  # a well measured NPS 8
    ],
)
def test_a_run_member_whose_own_fit_points_to_another_size(od_fit, od_stderr, nearer):
    # Merging equalised P2 with P1 (their ODs agree within 3 standard errors); an NPS 6 P2
    # after a reducer would have fitted so too, and the reducer would be missing silently.
    p1 = _run_member("P1", [0, 0, 1], [2, 0, 1], 0.2179, 0.0024)
    p2 = _run_member("P2", [2, 0, 1], [4, 0, 1], od_fit, od_stderr)
    found = only(run(p1, p2), "ambiguous-size")
    if nearer is None:
        assert not found
        return
    (f,) = found
    assert f.objects == ("P2",) and f.severity == "warning" and f.code == "AB102"
    assert f"is nearer {nearer} than the 219.1 mm it was given with P1" in f.message
    assert "a reducer may be missing" in f.message


def test_a_lone_pipe_is_not_judged_by_its_run():
    comp = _run_member("P2", [0, 0, 1], [2, 0, 1], 0.1871, 0.0150, run_ids=("P2",))
    assert not only(run(comp), "ambiguous-size")


def test_ambiguous_from_catalog_window():
    # no merge status: 3 x 1.2 mm = 3.6 mm window holds NPS 3/4 (26.7) only? 27.6 - 26.7 = 0.9;
    # 33.4 is 5.8 away, so add an artificial neighbour through a wide uncertainty instead
    comp = pipe("P2", [0, 0, 1], [1, 0, 1], 0.0300, radius_se=0.0012)
    (f,) = only(run(comp), "ambiguous-size")
    assert "NPS 3/4" in f.message and "NPS 1 " in f.message


def test_clear_size_is_not_ambiguous():
    assert not only(run(pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143)), "ambiguous-size")


# -- hint-mismatch -------------------------------------------------------------------------------


def scan_with_hint(object_id, hint):
    obj = ScanObject(id=object_id, kind="cylinder", points=np.zeros((7, 3)), nominal=hint)
    return Scan(units="m", objects=(obj,))


def test_hint_mismatch_is_found_and_fix_is_unambiguous():
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143)
    (f,) = only(run(comp, scan=scan_with_hint("P1", '3"')), "hint-mismatch")
    assert '3"' in f.message and "88.9 mm" in f.message
    assert f.measured == pytest.approx(0.1143 - 0.0889)
    fix = f.suggestions[0]
    assert fix.unambiguous and fix.change["value"] == "4" and fix.change["reject_hint"]
    assert "lagging" not in f.message  # one size up: a misread hint, not lagging


def run_shipped(*components, scan=None):
    """Checked against the shipped ASME B36.10M catalog: every size, for counting size steps
    (B36 above leaves NPS 5 and others out)."""
    return check_model(model(*components, scan=scan), load_rules(), catalog="asme-b36.10m")


@pytest.mark.parametrize(
    "hint, od, fitted, steps, lagging",
    [
        # a 4" pipe under 50 mm of lagging (OD 214.3 mm) snaps NPS 8
        ('4"', 0.2191, "8", 3, "52.4 mm"),
        # a 2" pipe under 40 mm of lagging (OD 140.3 mm) snaps NPS 5
        ('2"', 0.1413, "5", 5, "40.5 mm"),
        ('4"', 0.1683, "6", 2, "27.0 mm"),  # two sizes up is no misread neighbour either
        # steps are the catalog's: NPS 3 1/2 lies between 3 and 4 in ASME B36.10M
        ('3"', 0.1143, "4", 2, "12.7 mm"),
    ],
)
def test_a_fit_sizes_above_the_hint_is_no_unambiguous_fix(hint, od, fitted, steps, lagging):
    """The operator said what the pipe is; lagging, a clamp or a coating make the fit larger, so
    the fitted size is suggested but not applied by --fix, and the message names the cause."""
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], od)
    (f,) = only(run_shipped(comp, scan=scan_with_hint("P1", hint)), "hint-mismatch")
    fix = f.suggestions[0]
    assert fix.change["value"] == fitted and not fix.unambiguous
    assert not any(s.unambiguous for s in f.suggestions)
    assert f"the fit is {steps} catalog sizes above the hint" in f.message
    assert f"lagging or insulation about {lagging} thick" in f.message


def test_a_fit_sizes_below_the_hint_is_no_unambiguous_fix_nor_lagging():
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], 0.0603)
    (f,) = only(run_shipped(comp, scan=scan_with_hint("P1", '4"')), "hint-mismatch")
    assert f.suggestions[0].change["value"] == "2" and not f.suggestions[0].unambiguous
    assert "lagging" not in f.message


@pytest.mark.parametrize("hint, od, fitted", [('4"', 0.1016, "3 1/2"), ('6"', 0.2191, "8")])
def test_a_fit_one_catalog_size_off_the_hint_is_still_an_unambiguous_fix(hint, od, fitted):
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], od)
    (f,) = only(run_shipped(comp, scan=scan_with_hint("P1", hint)), "hint-mismatch")
    assert f.suggestions[0].unambiguous and f.suggestions[0].change["value"] == fitted
    assert "lagging" not in f.message


@pytest.mark.parametrize("hint", ['4"', "NPS 4", "DN100", "4"])
def test_agreeing_hint_gives_nothing(hint):
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1150)
    assert not only(run(comp, scan=scan_with_hint("P1", hint)), "hint-mismatch")


def test_hint_within_uncertainty_is_not_a_mismatch():
    # 3.5 mm off but the OD is known to +-2.5 mm only: 3.5 - 5 < 2, no clear disagreement
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1178, radius_se=0.00125)
    assert not only(run(comp, scan=scan_with_hint("P1", '4"')), "hint-mismatch")


def test_merge_hint_record_is_used():
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, status="snapped")
    comp.snap["hint"] = {"nominal": "6in", "agrees": False, "od": 0.1683, "size": "6"}
    (f,) = only(run(comp), "hint-mismatch")
    assert "6in" in f.message


# -- contiguous-diameter-mismatch ---------------------------------------------------------------


def test_contiguous_mismatch_suggests_shared_size():
    a = pipe(
        "P1",
        [0, 0, 1],
        [2, 0, 1],
        0.1143,
        nominal="4",
        od_fit=0.1146,
        status="snapped",
        od_stderr=0.0004,
    )
    b = pipe(
        "P2",
        [2.05, 0, 1],
        [4, 0, 1],
        0.0889,
        nominal="3",
        od_fit=0.1010,  # a poor fit snapped to NPS 3; its window (15 mm) also holds NPS 4
        status="snapped",
        od_stderr=0.005,
    )
    (f,) = only(run(a, b), "contiguous-diameter-mismatch")
    assert f.severity == "error" and f.objects == ("P1", "P2")
    assert "NPS 4" in f.message and "NPS 3" in f.message
    fix = f.suggestions[0]
    assert fix.unambiguous and fix.change["value"] == "4" and fix.change["objects"] == ["P2"]


def test_two_clearly_different_sizes_get_no_shared_size_neither_is():
    # An NPS 4 pipe (fit 114.5 mm) and an NPS 3 one (88.8 mm) through an elbow: their
    # inverse-variance mean snaps to NPS 3 1/2 (101.6 mm), 36 and 40 standard errors from the
    # fits; --fix applied it once. Only the reducer is suggested now.
    a = pipe("E1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", od_fit=0.1145, status="snapped")
    b = pipe("E2", [2.05, 0, 1], [4, 0, 1], 0.0889, nominal="3", od_fit=0.0888, status="snapped")
    (f,) = only(run(a, b), "contiguous-diameter-mismatch")
    assert [s.description for s in f.suggestions] == [
        "if the size really changes, add a reducer between E1 and E2"
    ]
    assert not any(s.unambiguous for s in f.suggestions)


def test_same_size_contiguous_pipes_are_fine():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4")
    b = pipe("P2", [2.05, 0, 1], [4, 0, 1], 0.1143, nominal="4")
    assert not only(run(a, b), "contiguous-diameter-mismatch")


def test_far_apart_pipes_are_not_contiguous():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4")
    b = pipe("P2", [2.5, 0, 1], [4, 0, 1], 0.0889, nominal="3")
    assert not only(run(a, b), "contiguous-diameter-mismatch")


def test_reducer_between_pipes_explains_the_change():
    from asbuilt.model import Component, Reducer

    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4")
    red = Component(
        id="R1", type="reducer", geometry=Reducer([2, 0, 1], [2.102, 0, 1], 0.1143 / 2, 0.0889 / 2)
    )
    b = pipe("P2", [2.102, 0, 1], [4, 0, 1], 0.0889, nominal="3")
    # the pipes' ends are 0.102 m apart (within joint_distance) but joined through a reducer
    found = only(run(a, red, b), "contiguous-diameter-mismatch")
    assert not found


def test_unmerged_model_is_not_judged_for_contiguous_sizes():
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4")
    b = pipe("P2", [2.05, 0, 1], [4, 0, 1], 0.0889, nominal="3")
    built = model(a, b, merged=False)
    assert not [
        f for f in check_model(built, catalog=B36) if f.slug == "contiguous-diameter-mismatch"
    ]


def test_different_sizes_whose_fits_agree_are_unverifiable():
    # snapped to different sizes, but the fitted ODs differ by 2.6 mm +- 4 mm
    a = pipe(
        "P1",
        [0, 0, 1],
        [2, 0, 1],
        0.1143,
        nominal="4",
        od_fit=0.1146,
        status="snapped",
        od_stderr=0.0004,
    )
    b = pipe(
        "P2",
        [2.05, 0, 1],
        [4, 0, 1],
        0.0889,
        nominal="3",
        od_fit=0.1120,
        status="snapped",
        od_stderr=0.004,
    )
    (f,) = only(run(a, b), "contiguous-diameter-mismatch")
    assert f.unverifiable and f.severity == "warning"


def test_nonstandard_without_catalog_uses_the_merge_record():
    comp = pipe(
        "P3",
        [0, 0, 1],
        [2, 0, 1],
        0.1182,
        status="no-size",
        candidates=[{"nominal": "4", "od": 0.1143}],
    )
    (f,) = [f for f in check_model(model(comp)) if f.slug == "nonstandard-diameter"]
    assert "nearest NPS 4 = 114.3 mm, 3.9 mm off" in f.message
    assert f.severity == "error"


def test_a_hint_naming_no_catalog_size_is_reported():
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143)
    (f,) = only(run(comp, scan=scan_with_hint("P1", "NPS 5 1/2")), "hint-mismatch")
    assert f.message == "the hint 'NPS 5 1/2' names no ASME B36.10M size, so it was not used"
    assert "DN100" in f.suggestions[0].description


def test_a_hint_that_is_no_size_is_reported_as_unreadable():
    """Not "names no catalog size" (audit): the catalog is not at fault."""
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143)
    (f,) = only(run(comp, scan=scan_with_hint("P1", "100 mm")), "hint-mismatch")
    assert f.message == "the hint '100 mm' cannot be read as a nominal size, so it was not used"
    assert "DN100" in f.suggestions[0].description


def test_pipes_merged_to_one_undecided_size_are_not_a_mismatch():
    # Merging joined P1 and P2 through an elbow and gave both one OD (110.2 mm) between NPS 3 1/2
    # and 4: the fits (104.3 +- 4.0 and 111.8 +- 2.0 mm) do not clearly disagree, and the
    # undecided size is ambiguous-size's finding, not a size change.
    common = dict(status="ambiguous", candidates=[("4", 0.1143), ("3 1/2", 0.1016)])
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1102, od_fit=0.1043, od_stderr=0.004, **common)
    b = pipe("P2", [2.05, 0, 1], [4, 0, 1], 0.1102, od_fit=0.1118, od_stderr=0.002, **common)
    assert not only(run(a, b), "contiguous-diameter-mismatch")


def test_fits_disagreeing_under_one_modelled_size_say_so_and_leave_the_size_open():
    common = dict(status="ambiguous", candidates=[("4", 0.1143), ("3 1/2", 0.1016)])
    a = pipe("P1", [0, 0, 1], [2, 0, 1], 0.1080, od_fit=0.1016, od_stderr=0.0005, **common)
    b = pipe("P2", [2.05, 0, 1], [4, 0, 1], 0.1080, od_fit=0.1143, od_stderr=0.0005, **common)
    (f,) = only(run(a, b), "contiguous-diameter-mismatch")
    assert f.message == (
        "the fits of P1 (101.6 mm) and the contiguous P2 (114.3 mm) disagree by 12.7 mm with no "
        "reducer"
    )
    assert not any(s.unambiguous for s in f.suggestions)


@pytest.mark.parametrize("spacing", [0.08, 0.10, 0.14])
def test_pipes_side_by_side_in_a_rack_are_not_contiguous(spacing):
    # NPS 2 and NPS 2 1/2 running side by side, ends level: close ends, but no fitting joins
    # two pipes that run the same way.
    a = pipe("R0", [0, 0, 1], [3, 0, 1], 0.0730, nominal="2-1/2")
    b = pipe("R1", [0, spacing, 1], [3, spacing, 1], 0.0603, nominal="2")
    found = check_model(model(a, b), catalog=B36)
    assert not [f for f in found if f.slug in ("contiguous-diameter-mismatch", "joint-gap")]


def test_a_tanks_hint_is_not_a_pipe_size():
    # samples/plant.json's tank TK1 says "3000 ID": a vessel's size, not a catalog pipe size.
    from dataclasses import replace

    tank = replace(pipe("TK1", [0, 0, 0], [0, 0, 4], 3.0), type="cylinder")
    assert not only(run(tank, scan=scan_with_hint("TK1", "3000 ID")), "hint-mismatch")


def test_a_pipe_sized_with_its_run_is_judged_and_described_by_the_run():
    # Merging sized P1-P3 together (116.5 +- 0.29 mm): P2 alone fits 116.1 mm, 1.8 mm from NPS
    # 4, and its error read "OD 116.1 mm ... 1.8 mm off", within the 2 mm it was judged against.
    import dataclasses

    comp = pipe("P2", [0, 0, 1], [2, 0, 1], 0.1161, status="no-size", od_fit=0.1161)
    snap = {**comp.snap, "run": ["P1", "P2", "P3"], "od_joint": 0.1165, "od_joint_stderr": 0.00029}
    (f,) = only(run(dataclasses.replace(comp, snap=snap)), "nonstandard-diameter")
    assert (
        "OD 116.5 mm +- 0.3 mm is no ASME B36.10M size (nearest NPS 4 = 114.3 mm, 2.2 mm off; "
        "a size is taken within the 2.0 mm diameter tolerance) (the run " in f.message
    )
    assert f.message.endswith("(the run P1, P2, P3 measured together; this pipe alone 116.1 mm)")
    assert f.measured == pytest.approx(0.0022)


# A tee at x = 2 with run ends 0.143 m either side (NPS 6 C, ASME B16.9) and its outlet 0.143 m
# along +y; pipes of the sizes given meet its ports (NPS 6 OD 168.3 mm, NPS 4 114.3 mm).
@pytest.mark.parametrize(
    ("run_od", "left", "right", "branch", "reported"),
    [
        pytest.param(0.1683, 0.1683, 0.1683, 0.1683, set(), id="equal-tee"),
        pytest.param(0.1683, 0.1683, 0.1683, 0.1143, set(), id="smaller-outlet"),
        pytest.param(
            0.1143, 0.1143, 0.1143, 0.1683, {("P1", "P2"), ("P2", "P3")}, id="outlet-larger"
        ),
        pytest.param(0.1683, 0.1683, 0.1143, 0.1683, {("P1", "P3")}, id="run-reduces"),
    ],
)
def test_a_tee_explains_a_smaller_outlet_only(run_od, left, right, branch, reported):
    """Any pair touching a tee was exempt from contiguous-diameter-mismatch: ASME B16.9 tees
    reduce on the outlet only, so a run changing size at the tee, or an outlet larger than
    the run, is a mismatch."""
    from asbuilt.model import Component, Tee

    sizes = {0.1683: "6", 0.1143: "4"}
    tee = Component(
        id="T1",
        type="tee",
        geometry=Tee(
            [2, 0, 1], [1.857, 0, 1], [2.143, 0, 1], [2, 0.143, 1], run_od / 2, branch / 2
        ),
    )
    p1 = pipe("P1", [0, 0, 1], [1.857, 0, 1], left, nominal=sizes[left])
    p3 = pipe("P3", [2.143, 0, 1], [4, 0, 1], right, nominal=sizes[right])
    p2 = pipe("P2", [2, 0.143, 1], [2, 2, 1], branch, nominal=sizes[branch])
    found = only(run(p1, tee, p3, p2), "contiguous-diameter-mismatch")
    assert {tuple(sorted(set(f.objects) - {"T1"})) for f in found} == reported
    assert all(
        f.severity == "error" and "tees reduce on the outlet only" in f.message for f in found
    )


@pytest.mark.parametrize(
    "od, od_se, expected",
    [
        # a well measured OD: judged against the 2 mm diameter tolerance (ASME B36.10M NPS 4 is
        # 114.3 mm, NPS 5 141.3 mm)
        (
            0.1213,
            0.0005,
            "OD 121.3 mm +- 0.5 mm is no ASME B36.10M size (nearest NPS 4 = 114.3 "
            "mm, 7.0 mm off; a size is taken within the 2.0 mm diameter tolerance)",
        ),
        # a sparse scan's OD known to 2.5 mm: a size would have been taken within 3 x 2.5 mm
        (
            0.1260,
            0.0025,
            "OD 126.0 mm +- 2.5 mm is no ASME B36.10M size (nearest NPS 4 = 114.3 "
            "mm, 11.7 mm off; a size is taken within 7.5 mm: 3 standard errors, at least the 2.0 mm "
            "diameter tolerance)",
        ),
    ],
)
def test_nonstandard_diameter_says_how_well_the_od_is_known_and_the_limit(od, od_se, expected):
    comp = pipe("P1", [0, 0, 1], [2, 0, 1], od, status="no-size", od_fit=od, od_stderr=od_se)
    (f,) = only(run(comp), "nonstandard-diameter")
    assert f.message == expected
    assert f.stderr == pytest.approx(od_se)
