"""Joint diameter estimation over runs of contiguous pipes."""

from __future__ import annotations

import numpy as np
import pytest
from synthetic_pipes import Pipe, report_of

from asbuilt.catalog import load_catalog
from asbuilt.merge import merge_model
from asbuilt.merge.joint import find_runs, joint_estimate, same_size
from asbuilt.merge.snap import snap_diameter


def test_joint_estimate_is_the_inverse_variance_mean():
    od, se = joint_estimate([0.100, 0.102, 0.104], [0.003, 0.003, 0.003])
    assert od == pytest.approx(0.102)
    assert se == pytest.approx(0.003 / np.sqrt(3))
    od, se = joint_estimate([0.100, 0.101], [0.001, 0.002])  # consistent: chi2 < 1
    assert od == pytest.approx((0.100 / 1e-6 + 0.101 / 4e-6) / (1 / 1e-6 + 1 / 4e-6))
    assert se == pytest.approx(1 / np.sqrt(1 / 1e-6 + 1 / 4e-6))


def test_joint_estimate_handles_unknown_errors():
    od, se = joint_estimate([0.1, 0.1004], [float("nan"), float("nan")], floor=1e-3)
    assert od == pytest.approx(0.1002) and se == pytest.approx(1e-3 / np.sqrt(2))


def test_scattered_estimates_widen_the_joint_error_by_the_birge_ratio():
    ods, ses = [0.100, 0.110, 0.105], [0.001, 0.001, 0.001]
    od, se = joint_estimate(ods, ses)
    chi2 = sum((o - 0.105) ** 2 for o in ods) / 0.001**2
    assert od == pytest.approx(0.105)
    assert se == pytest.approx(0.001 / np.sqrt(3) * np.sqrt(chi2 / 2))


@pytest.mark.parametrize(
    ("a", "b", "expected"),
    [
        ((0.1143, 0.001), (0.1150, 0.001), True),
        ((0.1143, 0.001), (0.0889, 0.001), False),
        ((0.1143, 0.0), (0.1170, 0.0), False),  # 2.7 mm apart with no error: beyond 2 mm
        ((0.1143, float("nan")), (0.1160, 0.0), True),
    ],
)
def test_same_size(a, b, expected):
    assert same_size(*a, *b, tolerance=0.002) is expected


def test_runs_break_where_sizes_differ():
    ods = [0.1143, 0.1145, 0.0889, 0.0890, 0.1140]
    ses = [0.001] * 5
    runs = find_runs(ods, ses, [(0, 1), (1, 2), (2, 3), (3, 4)], 0.002)
    assert runs == [[0, 1], [2, 3], [4]]


def test_three_pipes_decide_together_what_none_decides_alone():
    """A 3 mm-error fit of an NPS 3 pipe may be ambiguous alone; the run's estimate snaps."""
    steel = load_catalog("asme-b36.10m")
    fits = [0.0935, 0.0870, 0.0885]
    se = 0.003
    alone = snap_diameter(fits[0], se, steel, tolerance=0.002)
    assert alone.status == "ambiguous"
    pipes = [
        Pipe("P1", (0, 0, 0), (1.8, 0, 0), fits[0], se / 2),
        Pipe("P2", (2, 0.2, 0), (2, 1.8, 0), fits[1], se / 2),
        Pipe("P3", (2.2, 2, 0), (4, 2, 0), fits[2], se / 2),
    ]
    model = merge_model(report_of(pipes))
    pipes_out = [c for c in model.components if c.type == "pipe"]
    assert {c.nominal for c in pipes_out} == {"3"}
    for comp in pipes_out:
        assert comp.snap["status"] == "snapped"
        assert comp.snap["run"] == ["P1", "P2", "P3"]
        assert comp.snap["reason"].startswith("joint estimate of the run P1, P2, P3: ")
        assert comp.snap["od_joint"] == pytest.approx(np.mean(fits))
        mean = np.mean(fits)
        birge = np.sqrt(sum((f - mean) ** 2 for f in fits) / se**2 / 2)
        assert comp.snap["od_joint_stderr"] == pytest.approx(se / np.sqrt(3) * max(1, birge))
        assert min(abs(comp.snap["od_fit"] - f) for f in fits) < 1e-12


def test_a_run_of_different_sizes_gets_a_reducer_not_an_average():
    pipes = [Pipe("P1", (0, 0, 0), (1.9, 0, 0), 0.1143), Pipe("P2", (2.1, 0, 0), (4, 0, 0), 0.0889)]
    model = merge_model(report_of(pipes))
    assert [c.nominal for c in model.components if c.type == "pipe"] == ["4", "3"]
    assert [c.type for c in model.components] == ["pipe", "reducer", "pipe"]
