"""Reducing-outlet tees are built with ASME B16.9 Table 8's own C and M for their run x outlet
pair, not the equal tee's of the run size.

Truth: rows of B16.9 Table 8 copied by hand from the published table (pipingengineer.org,
"Butt weld reducing tees and crosses metric dimensions as per ASME B16.9": NPS1 x NPS2, C and M
in mm), independent of the shipped data the code reads. NPS 6 equal tee: C = M = 143 mm;
NPS 6 x 2 1/2: C 143, M 121. ODs from ASME B36.10M.
"""

from __future__ import annotations

import numpy as np
import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.merge import merge_model
from asbuilt.merge.spool import connection_mismatches
from asbuilt.rules import check_model

#: (run, outlet, C, M) mm, typed from the table.
TABLE_8 = [
    ("6", "2 1/2", 143, 121),
    ("6", "5", 143, 137),
    ("4", "2", 105, 89),
    ("2", "3/4", 64, 44),
    ("3", "1 1/4", 86, 70),
    ("8", "5", 178, 162),
    ("10", "4", 216, 184),
    ("12", "8", 254, 229),
    ("1 1/2", "1/2", 57, 57),
]
#: ASME B36.10M outside diameters, metres.
OD = {
    "3/4": 0.0267,
    "1/2": 0.0213,
    "1 1/4": 0.0422,
    "1 1/2": 0.0483,
    "2": 0.0603,
    "2 1/2": 0.0730,
    "3": 0.0889,
    "4": 0.1143,
    "5": 0.1413,
    "6": 0.1683,
    "8": 0.2191,
    "10": 0.2730,
    "12": 0.3238,
}
LINKS = [("P1", "P3"), ("P1", "P2")]


def _tee_pipes(run_od, outlet_od, c, m):
    """Run P1, P3 along x ending ``c`` either side of a junction at the origin (z = 1), outlet
    P2 along +y from ``m``."""
    return [
        Pipe("P1", (-c - 1.2, 0, 1), (-c, 0, 1), run_od),
        Pipe("P3", (c, 0, 1), (c + 1.2, 0, 1), run_od),
        Pipe("P2", (0, m, 1), (0, m + 1.2, 1), outlet_od),
    ]


def _tee(model):
    (tee,) = [c for c in model.components if c.type == "tee"]
    return tee


def _outlet_reach(tee) -> float:
    """Distance of the built tee's outlet end from its run axis, metres."""
    g = tee.geometry
    d = (g.run_end - g.run_start) / np.linalg.norm(g.run_end - g.run_start)
    v = g.branch_end - g.run_start
    return float(np.linalg.norm(v - (v @ d) * d))


@pytest.mark.parametrize(("run", "outlet", "c", "m"), TABLE_8)
def test_a_reducing_tee_has_its_pairs_c_and_m(run, outlet, c, m):
    model = merge_model(report_of(_tee_pipes(OD[run], OD[outlet], c / 1000, m / 1000), LINKS))
    tee = _tee(model)
    g = tee.geometry
    assert _outlet_reach(tee) == pytest.approx(m / 1000, abs=1e-6)
    assert np.linalg.norm(g.run_end - g.center) == pytest.approx(c / 1000, abs=1e-6)
    assert np.linalg.norm(g.run_start - g.center) == pytest.approx(c / 1000, abs=1e-6)
    assert tee.snap["standard"] is True
    assert not [n for n in tee.snap["notes"] if "equal tee" in n]
    found, bad = connection_mismatches(model.components, tolerance=1e-4)
    assert bad == []


def test_nps_6_by_2_1_2_outlet_end_is_121_mm_from_the_run_axis():
    """The brief's case: it was built 143 mm out (the equal 6 inch tee's M)."""
    model = merge_model(report_of(_tee_pipes(OD["6"], OD["2 1/2"], 0.143, 0.121), LINKS))
    tee = _tee(model)
    assert _outlet_reach(tee) == pytest.approx(0.121, abs=1e-6)
    assert any("6 x 2 1/2" in n and "M 121 mm" in n for n in tee.snap["notes"])
    p2 = next(c for c in model.components if c.id == "P2")
    # the outlet pipe starts at the tee's outlet end
    assert min(p2.geometry.start[1], p2.geometry.end[1]) == pytest.approx(0.121, abs=1e-6)
    assert [f.code for f in check_model(model)] == []


def test_a_branch_into_the_middle_of_a_pipe_gets_the_pairs_m():
    """A branch meeting the inside of one run pipe (the pipe is split at the tee)."""
    pipes = [
        Pipe("P1", (-1.5, 0, 1), (1.5, 0, 1), OD["6"]),
        Pipe("P2", (0, 0.121, 1), (0, 1.321, 1), OD["2 1/2"]),
    ]
    model = merge_model(report_of(pipes, links=[("P1", "P2")]))
    tee = _tee(model)
    assert _outlet_reach(tee) == pytest.approx(0.121, abs=1e-6)
    g = tee.geometry
    assert np.linalg.norm(g.run_end - g.run_start) == pytest.approx(0.286, abs=1e-6)


def test_a_pair_b16_9_does_not_make_keeps_the_equal_tee_and_the_finding():
    """NPS 6 x 2 is not in Table 8: built as before (equal 6 inch tee's C = M = 143 mm), and
    AB105 says so."""
    model = merge_model(report_of(_tee_pipes(OD["6"], OD["2"], 0.143, 0.143), LINKS))
    tee = _tee(model)
    assert _outlet_reach(tee) == pytest.approx(0.143, abs=1e-6)
    assert any("equal tee's dimensions" in n for n in tee.snap["notes"])
    assert [f.code for f in check_model(model)] == ["AB105"]


def test_shipped_metric_rows_agree_with_the_inch_page():
    """Every shipped pair with an inch row: C and M in mm are the inch values (printed to 0.01,
    i.e. eighths) x 25.4, rounded to the millimetre."""
    from importlib import resources

    try:
        import tomllib
    except ModuleNotFoundError:  # pragma: no cover
        import tomli as tomllib

    text = (resources.files("asbuilt.catalogs") / "asme-b16.9-tees.toml").read_text("utf-8")
    table = tomllib.loads(text)
    checked = 0
    for run, outlets in table["dimensions_inch"].items():
        for outlet, inches in outlets.items():
            mm = table["dimensions"][run][outlet]
            for value, inch in zip(mm, inches, strict=True):
                assert abs(value - round(inch * 8) / 8 * 25.4) <= 0.5, (run, outlet)
                checked += 1
    assert checked == 2 * 49
    # every pair the outlets list makes has dimensions
    for run, outlets in table["outlets"].items():
        assert set(outlets) == set(table["dimensions"][run]), run
