"""Snapping a fitted OD to a catalog size: exact, between, far, ambiguous, hints."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from asbuilt.catalog import load_catalog
from asbuilt.merge.snap import snap_diameter

STEEL = load_catalog("asme-b36.10m")
TOL = 0.002


@pytest.mark.parametrize(
    ("od", "se", "status", "nominal"),
    [
        (0.1143, 0.0003, "snapped", "4"),  # exact size
        (0.1155, 0.0003, "snapped", "4"),  # 1.2 mm off, inside the 2 mm floor
        (0.1180, 0.0003, "no-size", None),  # 3.7 mm off, window 2 mm
        (0.1180, 0.0015, "snapped", "4"),  # same, but 3 se = 4.5 mm covers it
        (0.1080, 0.0040, "ambiguous", None),  # 12 mm window holds NPS 3 1/2 and 4
        (0.500, 0.001, "no-size", None),  # between NPS 18 (457) and 20 (508)
        (3.000, 0.001, "no-size", None),  # a tank, far from any size
    ],
)
def test_snap_cases(od, se, status, nominal):
    result = snap_diameter(od, se, STEEL, tolerance=TOL)
    assert result.status == status
    assert (result.size.nominal if result.size else None) == nominal
    assert result.window == pytest.approx(max(3 * se, TOL))
    assert result.reason


def test_no_size_names_the_nearest_and_keeps_the_fitted_od():
    result = snap_diameter(0.1180, 0.0003, STEEL, tolerance=TOL)
    assert result.od == 0.1180
    assert result.candidates[0].nominal == "4"
    assert "nearest NPS 4" in result.reason


def test_ambiguous_lists_both_candidates():
    result = snap_diameter(0.1080, 0.0040, STEEL, tolerance=TOL)
    assert {c.nominal for c in result.candidates} == {"3 1/2", "4"}
    assert "NPS 3 1/2" in result.reason and "NPS 4" in result.reason
    mapping = result.as_mapping(STEEL)
    assert mapping["status"] == "ambiguous" and mapping["od_catalog"] is None
    assert {c["nominal"] for c in mapping["candidates"]} == {"3 1/2", "4"}


def test_unknown_stderr_uses_the_tolerance_only():
    result = snap_diameter(0.1150, float("nan"), STEEL, tolerance=TOL)
    assert result.status == "snapped" and result.window == TOL


@pytest.mark.parametrize(
    ("hint", "status", "agrees", "nominal"),
    [
        ('4"', "hint", True, "4"),  # hint chooses between two sizes in the window
        ("DN90", "hint", True, "3 1/2"),
        ("NPS 6", "ambiguous", False, None),  # hint far outside the window: flagged, not used
        ("banana", "ambiguous", None, None),  # not a size: recorded, not used
    ],
)
def test_hint_decides_only_inside_the_window(hint, status, agrees, nominal):
    result = snap_diameter(0.1080, 0.0040, STEEL, tolerance=TOL, hint=hint)
    assert result.status == status
    assert result.hint["agrees"] is agrees
    assert (result.size.nominal if result.size else None) == nominal


def test_hint_disagreeing_with_a_clear_fit_is_flagged_and_the_fit_wins():
    result = snap_diameter(0.1143, 0.0003, STEEL, tolerance=TOL, hint='6"')
    assert result.status == "snapped" and result.size.nominal == "4"
    assert result.hint["agrees"] is False
    assert "outside" in result.hint["reason"]


def test_hint_agreeing_with_a_clear_fit():
    result = snap_diameter(0.1143, 0.0003, STEEL, tolerance=TOL, hint="DN100")
    assert result.status == "snapped" and result.hint["agrees"] is True


@given(
    index=st.integers(0, len(STEEL.sizes) - 1),
    offset=st.floats(-0.01, 0.01),
    se=st.floats(0.0, 0.005),
)
def test_a_snapped_size_is_always_the_nearest_and_inside_the_window(index, offset, se):
    od = STEEL.sizes[index].od + offset
    result = snap_diameter(od, se, STEEL, tolerance=TOL)
    if result.status == "snapped":
        nearest = min(STEEL.sizes, key=lambda s: abs(s.od - od))
        assert result.size is nearest
        assert abs(result.size.od - od) <= result.window
        others = [s for s in STEEL.sizes if s is not nearest]
        assert all(abs(s.od - od) > result.window for s in others)


@given(index=st.integers(0, len(STEEL.sizes) - 1), se=st.floats(0.0, 0.0006))
def test_an_exact_catalog_od_snaps_to_itself(index, se):
    size = STEEL.sizes[index]
    result = snap_diameter(size.od, se, STEEL, tolerance=TOL)
    # NPS 1/8 and 1/4 are 3.4 mm apart: with a 2 mm window they are both in reach of each
    # other only when the estimate sits between them, never at one of them
    assert result.status == "snapped" and result.size is size
