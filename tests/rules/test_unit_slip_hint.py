"""hint-mismatch under a unit slip: a fit hundreds of times its hint's OD is the file's units,
not lagging (seen in review: millimetre numbers in a metre file were told "lagging or
insulation about 83485.3 mm thick")."""

import dataclasses

import pytest
from rules_builders import B36, model, pipe

from asbuilt.rules import check_model, load_rules
from asbuilt.scan.model import Scan

HINT_4 = {"nominal": '4"', "od": 0.1143}


def hinted(cid, y, od, *, se=0.0005, insulation=0.0, **options):
    """A pipe with a 4" hint whose cladding fits OD ``od`` (the scan's numbers, metres as
    declared) over ``insulation``; merging's ``od_fit`` is the pipe inside."""
    inside = od - 2 * insulation
    p = pipe(
        cid, [0, y, 1], [2, y, 1], od, status="no-size", od_fit=inside, od_stderr=se, **options
    )
    snap = {**p.snap, "hint": dict(HINT_4)}
    return dataclasses.replace(p, snap=snap, insulation=insulation)


def hint_findings(units, *components):
    found = check_model(
        model(*components, scan=Scan(units=units, objects=())), load_rules(), catalog=B36
    )
    return [f for f in found if f.slug == "hint-mismatch"]


@pytest.mark.parametrize("insulation", [0.0, 25.0])
def test_every_pipe_in_mm_read_as_m_is_a_unit_slip_not_lagging(insulation):
    # 114.3 mm pipes in a file that says metres: the whole scan is a slip (unit_slip)
    (f,) = hint_findings(
        "m",
        hinted("P1", 0, 114.3 + 2 * insulation, se=0.5, insulation=insulation),
        pipe("P2", [0, 2, 1], [2, 2, 1], 60.3, status="no-size", od_stderr=0.5),
    )
    assert "lagging or insulation about" not in f.message
    assert "thicker than the" not in f.message
    assert f.message.endswith(
        "; the fit is 1000 times the hint's OD, a unit slip rather than lagging: the scan's "
        "numbers look like mm, not m; read so, P1's OD is 114.3 mm, the hint's size"
    )
    first = f.suggestions[0]
    assert first.description == (
        "check the scan's \"units\": its numbers look like mm, not m; read so, P1's OD is "
        "114.3 mm, the hint's size"
    )
    assert first.change == {"field": "units", "value": "mm"} and not first.unambiguous


@pytest.mark.parametrize(
    "units, od, slip",
    [
        ("m", 114.3, "mm"),  # ratio 1000
        ("m", 11.43, "cm"),  # ratio 100
        ("in", 114.3 * 0.0254, "mm"),  # mm numbers in an inch file: ratio 25.4
        ("ft", 4.5 * 0.3048, "in"),  # inch numbers in a foot file: ratio 12
    ],
)
def test_one_pipe_a_units_ratio_off_its_hint_is_told_to_check_the_units(units, od, slip):
    # P1 is a plausible size, so the scan as a whole is no slip; P2 alone is a units ratio off
    # its hint, further than any lagging (half the difference over 0.5 m)
    scale = od / 0.1143
    found = hint_findings(
        units,
        pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", status="snapped"),
        hinted("P2", 2, od, se=0.0005 * scale),
    )
    (f,) = [f for f in found if f.objects == ("P2",)]
    assert "lagging or insulation about" not in f.message
    assert f"a unit slip rather than lagging: the scan's numbers look like {slip}" in f.message
    assert f.suggestions[0].change == {"field": "units", "value": slip}


def test_a_fit_no_lagging_and_no_unit_explains_proposes_neither():
    # 2.5 m against a 4" hint: 1.19 m of "lagging", and no unit reading makes it 114.3 mm
    found = hint_findings(
        "m",
        pipe("P1", [0, 0, 1], [2, 0, 1], 0.1143, nominal="4", status="snapped"),
        hinted("P2", 2, 2.5),
    )
    (f,) = [f for f in found if f.objects == ("P2",)]
    assert "lagging or insulation about" not in f.message
    assert f.message.endswith(
        "; more than any lagging or insulation explains (at most 500.0 mm thick): check the "
        'hint, the fit and the scan\'s "units"'
    )
    assert not any((s.change or {}).get("field") == "units" for s in f.suggestions)


def test_a_lagged_pipe_is_still_told_lagging():
    # a 4" pipe under 52.4 mm of lagging fits NPS 8 (219.1 mm): plausible lagging, no units
    (f,) = hint_findings("m", hinted("P1", 0, 0.2191))
    assert "lagging or insulation about 52.4 mm thick" in f.message
    assert not any((s.change or {}).get("field") == "units" for s in f.suggestions)
