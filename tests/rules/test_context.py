import pytest

from asbuilt.rules._context import verdict, verdict_min


@pytest.mark.parametrize(
    "measured, allowed, stderr, expected",
    [
        (1.0, 2.0, 0.1, "pass"),
        (2.0, 2.0, 0.1, "pass"),  # at the limit: compliant
        (2.1, 2.0, 0.1, "unverifiable"),  # over, but within 2 standard errors
        (2.2, 2.0, 0.1, "unverifiable"),  # exactly 2 standard errors over: not more than
        (2.21, 2.0, 0.1, "violation"),
        (0.5, 2.0, 1.5, "unverifiable"),  # 2 s = 3 > 2: cannot resolve the limit at all
        (5.0, 2.0, None, "violation"),  # no stderr: taken as exact
        (2.0, 2.0, float("nan"), "pass"),
    ],
)
def test_verdict(measured, allowed, stderr, expected):
    assert verdict(measured, allowed, stderr, 2.0) == expected


@pytest.mark.parametrize(
    "measured, required, stderr, expected",
    [
        (0.02, 0.01, 0.001, "pass"),
        (0.0095, 0.01, 0.001, "unverifiable"),
        (0.007, 0.01, 0.001, "violation"),
        (0.02, 0.01, 0.006, "unverifiable"),  # 2 s > required
    ],
)
def test_verdict_min(measured, required, stderr, expected):
    assert verdict_min(measured, required, stderr, 2.0) == expected


def test_axis_of_an_eccentric_reducer_is_its_run():
    import numpy as np

    from asbuilt.model import Reducer
    from asbuilt.rules._context import axis_of

    g = Reducer([0, 0, 1], [0.14, 0, 1.027], 0.08415, 0.05715, offset=[0, 0, 0.027])
    axis, length, centre = axis_of(g)
    assert axis == pytest.approx([1, 0, 0]) and length == pytest.approx(0.14)
    assert centre == pytest.approx(np.array([0.07, 0, 1.0135]))
