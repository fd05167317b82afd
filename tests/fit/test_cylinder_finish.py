"""The last stage of a cylinder fit (:mod:`asbuilt.fit._cylinder_finish`)."""

from __future__ import annotations

import numpy as np
import pytest

from asbuilt.fit._cylinder_finish import end_gaps


def test_end_gaps_are_the_step_to_the_next_row_in():
    rows = np.repeat([0.0, 3.0, 6.0, 9.5], 4) + np.tile([0.0, 0.001, -0.001, 0.002], 4)
    gaps = end_gaps(rows, 0.2, 0.002)
    assert gaps[0] == pytest.approx(3.001, abs=0.003)
    assert gaps[1] == pytest.approx(3.5, abs=0.003)
    # One row only: the nearest-neighbour spacing stands for the step.
    assert end_gaps(np.zeros(5), 0.2, 0.002) == (0.2, 0.2)
