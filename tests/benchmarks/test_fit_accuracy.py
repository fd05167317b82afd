"""benchmarks/fit_accuracy.py runs end to end (a smoke run) and its error measures are right."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))

import fit_accuracy  # noqa: E402

from asbuilt.primitives import Cuboid  # noqa: E402
from asbuilt.sim.geometry import rotation_zyx  # noqa: E402


def test_quick_run_writes_tables(tmp_path):
    out = tmp_path / "fit.md"
    assert (
        fit_accuracy.main(["--quick", "--only", "sphere", "--only", "plane", "--out", str(out)])
        == 0
    )
    text = out.read_text()
    assert "#### Targets" in text
    assert "#### Spheres, clean" in text and "#### Planes (walls, plates), with 20% edge" in text
    assert "| 0.5 | 30 | 5 | " in text  # sphere cell: diameter, points, trials


@pytest.mark.parametrize("yaw", [0.0, 30.0, 90.0])
def test_cuboid_errors_are_permutation_and_sign_free(yaw):
    axes = rotation_zyx(yaw, 0, 0)
    truth = {"axes": axes, "size": np.array([0.3, 0.4, 3.0])}
    # the same box described with permuted, flipped axes and sizes
    fitted = Cuboid(
        center=np.zeros(3),
        axes=np.array([axes[2], -axes[0], -axes[1]]),
        size=np.array([3.03, 0.3, 0.4]),
    )
    err = fit_accuracy.cuboid_errors(fitted, truth)
    np.testing.assert_allclose(err["size_rel"], [0.0, 0.0, 0.01], atol=1e-12)
    assert err["orientation"] == pytest.approx(0.0, abs=1e-6)
    turned = Cuboid(center=np.zeros(3), axes=rotation_zyx(yaw + 2.0, 0, 0), size=truth["size"])
    assert fit_accuracy.cuboid_errors(turned, truth)["orientation"] == pytest.approx(2.0)


def test_trials_are_exact_and_on_the_surface():
    rng = np.random.default_rng(0)
    trial = fit_accuracy.cylinder_trial(rng, 114.3, 3, 30)
    assert trial.clean.shape == trial.dirty.shape == (30, 3)
    changed = np.any(trial.clean != trial.dirty, axis=1)
    assert changed.sum() == 6  # 20% edge outliers
    assert trial.bound["radius"] > 0 and trial.bound["axis"] > 0


# --------------------------------------------------------------------------- operator window


def test_quick_run_reports_both_windows(tmp_path):
    out = tmp_path / "fit.md"
    argv = ["--quick", "--only", "cuboid", "--operator-window", "--out", str(out)]
    assert fit_accuracy.main(argv) == 0
    text = out.read_text()
    assert "#### Exact silhouette window vs operator window" in text
    assert "#### Cuboids (columns, beams, piers), exact window, clean" in text
    assert "#### Cuboids (columns, beams, piers), operator window, with 20% edge" in text
    assert "(every cell), exact silhouette window |" in text
    assert "(every cell), operator window |" in text
    assert "| cuboid | clean | across-size median error % |" in text


def _sphere_cells(operator):
    ours = fit_accuracy._ours()["sphere"]
    return fit_accuracy.run_cells(
        "sphere",
        [(0.5, 20)],
        fit_accuracy.sphere_trial,
        3,
        0,
        ours,
        None,
        7,
        lambda *a: None,
        operator=operator,
    )[(0.5, 20)]


def test_exact_window_trials_do_not_depend_on_the_flag():
    plain, both = _sphere_cells(False), _sphere_cells(True)
    assert set(plain) == {("ours", "clean"), ("ours", "outliers")}
    assert set(both) == set(plain) | {("ours", "clean@operator"), ("ours", "outliers@operator")}
    for version in ("clean", "outliers"):
        np.testing.assert_array_equal(
            plain[("ours", version)].values("radius"), both[("ours", version)].values("radius")
        )
    assert both[("ours", "clean@operator")].trials == 3


def test_operator_twin_has_the_same_object_and_a_wider_raster():
    rng = np.random.default_rng(11)
    twin = fit_accuracy._twin(rng)
    exact = fit_accuracy.cuboid_trial(rng, 0.4, 2, 30)
    operator = fit_accuracy.cuboid_trial(twin, 0.4, 2, 30, operator=True)
    np.testing.assert_array_equal(exact.truth["axes"], operator.truth["axes"])
    np.testing.assert_array_equal(exact.truth["size"], operator.truth["size"])
    assert operator.clean.shape == exact.clean.shape == (30, 3)
    assert not np.array_equal(exact.clean, operator.clean)


def test_window_table_medians_and_worst_cells():
    from fit_report import Cell, window_table

    def cell(values, bound):
        c = Cell()
        for v in values:
            c.add("radius", v)
            c.bound("radius", bound)
        return c

    # RMSE / CRB per cell: exact 1, 2, 3; operator 2, 4, 6
    results = {
        "sphere": {
            (d, 20): {
                ("ours", "clean"): cell([0.001 * k, -0.001 * k], 0.001),
                ("ours", "clean@operator"): cell([0.002 * k, -0.002 * k], 0.001),
            }
            for k, d in ((1, 0.2), (2, 0.5), (3, 1.0))
        }
    }
    lines = window_table(results).splitlines()
    assert lines[2] == "| sphere | clean | radius RMSE / CRB | 2.00 | 3.00 | 4.00 | 6.00 |"
    assert len(lines) == 3  # no outlier version, no row for it


def test_window_cells_table_lists_cells_above_the_chi_square_limit():
    from fit_report import Cell, window_cells_table

    def cell(scale):
        c = Cell()
        for v in scale * np.array([1.0, -1.0] * 25):
            c.add("radius", v)
            c.bound("radius", 0.001)
        return c

    # RMSE / CRB 1.0 (exact) vs 2.0 (operator): listed; 1.0 vs 1.1 (within the limit): not
    results = {
        "sphere": {
            (0.2, 20): {("ours", "clean"): cell(0.001), ("ours", "clean@operator"): cell(0.002)},
            (0.5, 20): {("ours", "clean"): cell(0.001), ("ours", "clean@operator"): cell(0.0011)},
        }
    }
    lines = window_cells_table(results).splitlines()
    assert lines[2:] == ["| sphere | 0.2 / 20 | radius | 1.00 | 2.00 | 2.00 mm |"]


# --------------------------------------------------------------------------- scan session


@pytest.mark.parametrize("faces, n", [(2, 30), (3, 20), (2, 40)])
def test_session_trial_has_exactly_n_points_with_edge_shots(faces, n):
    rng = np.random.default_rng(5)
    twin = fit_accuracy._twin(rng)
    exact = fit_accuracy.cuboid_trial(rng, 0.4, faces, n)
    session = fit_accuracy.cuboid_trial(twin, 0.4, faces, n, session=True)
    np.testing.assert_array_equal(exact.truth["size"], session.truth["size"])
    np.testing.assert_array_equal(exact.truth["axes"], session.truth["axes"])
    assert session.clean.shape == session.dirty.shape == (n, 3)
    changed = np.any(session.clean != session.dirty, axis=1)
    assert changed.sum() == round(0.2 * n)
    assert np.isfinite(session.bound["orientation"])


def _cuboid_cell(session):
    ours = fit_accuracy._ours()["cuboid"]
    return fit_accuracy.run_cells(
        "cuboid",
        [(0.4, 2, 30)],
        fit_accuracy.cuboid_trial,
        2,
        0,
        ours,
        None,
        7,
        lambda *a: None,
        operator=True,
        session=session,
    )[(0.4, 2, 30)]


def test_session_versions_leave_the_other_versions_alone():
    plain, both = _cuboid_cell(False), _cuboid_cell(True)
    assert set(both) == set(plain) | {("ours", "clean@session"), ("ours", "outliers@session")}
    for version in ("clean", "outliers", "clean@operator", "outliers@operator"):
        for name in ("size_a", "size_b", "size_len", "orientation"):
            np.testing.assert_array_equal(
                plain[("ours", version)].values(name), both[("ours", version)].values(name)
            )


def test_quick_run_reports_the_session(tmp_path):
    out = tmp_path / "fit.md"
    argv = ["--quick", "--only", "cuboid", "--operator-window", "--session", "--out", str(out)]
    assert fit_accuracy.main(argv) == 0
    text = out.read_text()
    assert (
        "#### Cuboids (columns, beams, piers), scan session over an operator window, clean" in text
    )
    assert "(every cell), scan session (edge bisection) over an operator window |" in text
    # the other windows' rows are still there
    assert "(every cell), operator window |" in text
