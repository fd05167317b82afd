"""check_model as a whole: ordering, selection, config defaults; properties with hypothesis."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from rules_builders import B36, column, model, pipe

from asbuilt.findings import SEVERITIES
from asbuilt.rules import check_model, load_rules, sort_findings
from asbuilt.rules._context import verdict
from asbuilt.rules.fixes import rotate_geometry


def test_sorted_by_severity_then_position():
    built = model(
        column("C9", [9, 0, 0], 0.6, axes_deg=0.01),  # error at x = 9
        column("C1", [1, 0, 0], 0.6, axes_deg=0.01),  # error at x = 1
        pipe("P1", [0, 5, 1], [2, 5, 1], 0.1143, n=10),  # warning (too few points)
    )
    found = check_model(built, catalog=B36)
    ranks = [SEVERITIES.index(f.severity) for f in found]
    assert ranks == sorted(ranks)
    errors = [f for f in found if f.severity == "error"]
    assert [f.objects[0] for f in errors] == ["C1", "C9"]
    assert sort_findings(reversed(found)) == found


def test_no_rules_no_findings():
    built = model(column("C1", [1, 0, 0], 0.6, axes_deg=0.01))
    config = load_rules().with_selection(select=["AB2"], ignore=["AB2"])
    assert check_model(built, config, catalog=B36) == ()


def test_unmerged_model_without_catalog_skips_size_rules():
    built = model(pipe("P1", [0, 0, 1], [2, 0, 1], 0.1182))
    assert not [f for f in check_model(built) if f.code.startswith("AB1")]


def test_catalog_by_name_uses_the_shipped_catalog():
    built = model(pipe("P1", [0, 0, 1], [2, 0, 1], 0.1182), catalog="asme-b36.10m")
    (f,) = [f for f in check_model(built) if f.slug == "nonstandard-diameter"]
    assert "NPS 4 = 114.3 mm" in f.message


@given(
    m=st.floats(0, 10),
    a=st.floats(0, 10),
    s=st.floats(0, 5),
    extra=st.floats(0, 5),
)
def test_verdict_is_monotone_in_the_measurement(m, a, s, extra):
    order = {"pass": 0, "unverifiable": 1, "violation": 2}
    assert order[verdict(m + extra, a, s, 2.0)] >= order[verdict(m, a, s, 2.0)]


@given(m=st.floats(0, 10), a=st.floats(0.01, 10), s=st.floats(0, 5))
def test_an_error_always_clears_the_limit_by_two_standard_errors(m, a, s):
    if verdict(m, a, s, 2.0) == "violation":
        assert m - 2 * s > a


@settings(max_examples=50)
@given(angle=st.floats(-180, 180), ax=st.floats(-1, 1), ay=st.floats(-1, 1))
def test_rotation_keeps_lengths_and_centre(angle, ax, ay):
    from asbuilt.model import Straight

    axis = np.array([ax, ay, 1.0])
    axis /= np.linalg.norm(axis)
    t = np.radians(angle)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    r = np.eye(3) + np.sin(t) * k + (1 - np.cos(t)) * k @ k
    g = Straight([0, 0, 0], [2, 1, 0.5], 0.05)
    centre = 0.5 * (g.start + g.end)
    turned = rotate_geometry(g, r, centre)
    assert np.isclose(turned.length, g.length)
    np.testing.assert_allclose(0.5 * (turned.start + turned.end), centre, atol=1e-12)


@given(st.sampled_from([s for s in B36.sizes]))
def test_size_table_reads_every_hint_form(size):
    nominal, dn, od = size
    for hint in (nominal, f'{nominal}"', f"NPS {nominal}", f"{nominal} in", f"DN{dn}"):
        assert B36.od(hint) == od


def test_config_may_be_a_path(tmp_path):
    path = tmp_path / "rules.toml"
    path.write_text('select = ["out-of-plumb"]\n', encoding="utf-8")
    built = model(
        column("C1", [1, 0, 0], 0.6, axes_deg=0.01), pipe("P1", [0, 5, 1], [2, 5, 1], 0.1143, n=10)
    )
    assert {f.slug for f in check_model(built, str(path))} == {"out-of-plumb"}
