"""Crosses in the take-off (asbuilt.report.takeoff): counted as "cross" (not a tee), by run x
outlet size, in the spool's fitting counts, and as a column of the HTML spool table."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "merge"))
from synthetic_pipes import Pipe, report_of  # noqa: E402

from asbuilt.merge import merge_model  # noqa: E402
from asbuilt.report.takeoff import FITTING_KINDS, take_off  # noqa: E402

NPS = {"4": 0.1143, "6": 0.1683}


def _model(run, outlet):
    return merge_model(
        report_of(
            [
                Pipe("P1", (0, 0, 0), (1.85, 0, 0), NPS[run]),
                Pipe("P2", (2.15, 0, 0), (4, 0, 0), NPS[run]),
                Pipe("P3", (2, 0.15, 0), (2, 2, 0), NPS[outlet]),
                Pipe("P4", (2, -0.15, 0), (2, -2, 0), NPS[outlet]),
            ]
        )
    )


@pytest.mark.parametrize(("run", "outlet", "size"), [("4", "4", "4"), ("6", "4", "6 x 4")])
def test_a_cross_is_counted_as_a_cross_of_its_sizes(run, outlet, size):
    t = take_off(_model(run, outlet))
    (row,) = t.fittings
    assert (row.type, row.count, row.components) == ("cross", 1, ("P1-P2-P3-P4",))
    assert row.size.replace("NPS ", "").replace('"', "") == size
    (spool,) = t.spools
    assert dict(spool.fittings) == {"cross": 1} and spool.pipes == 4
    assert "cross" in FITTING_KINDS


def test_the_html_spool_table_has_a_crosses_column_only_where_one_is():
    from asbuilt.report._html_takeoff import _takeoff

    class Data:
        takeoff = take_off(_model("6", "4"))

    assert "<th" in _takeoff(Data) and "Crosses" in _takeoff(Data)
    Data.takeoff = take_off(merge_model(report_of([Pipe("P1", (0, 0, 0), (2, 0, 0), NPS["4"])])))
    assert "Crosses" not in _takeoff(Data)
