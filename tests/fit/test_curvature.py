"""Whether a wide curved fit measured its curvature (asbuilt.fit._curvature)."""

from __future__ import annotations

import numpy as np

from asbuilt.fit._curvature import curvature_measured


def test_a_flat_end_with_a_lone_rim_shot_measures_no_curvature():
    # 24 shots on a flat face (a drum's end) at 2 mm noise and one 30 mm off it (a rim or
    # side shot), all explained within 1.5 mm by a curved fit that bends to the lone shot:
    # that shot alone sets the curvature.
    rng = np.random.default_rng(3)
    u, v = rng.uniform(-0.8, 0.8, 24), rng.uniform(-0.8, 0.8, 24)
    face = np.column_stack([u, 8.0 + rng.normal(0.0, 0.002, 24), 1.5 + v])
    points = np.vstack([face, [[0.9, 8.03, 1.5]]])
    residuals = np.append(rng.normal(0.0, 0.0015, 24), 0.0)
    assert not curvature_measured(points, residuals, 0.002, 5)


def test_a_wide_tank_seen_over_a_metre_measures_its_curvature():
    # A 10 m tank seen over 1 m of its width (a sagitta of 12 mm) at 2 mm noise.
    rng = np.random.default_rng(4)
    angle = rng.uniform(-0.05, 0.05, 30)
    noise = rng.normal(0.0, 0.002, 30)
    radius = 10.0 + noise
    points = np.column_stack(
        [radius * np.sin(angle), 18.0 - radius * np.cos(angle), rng.uniform(0.0, 2.0, 30)]
    )
    assert curvature_measured(points, noise, 0.002, 5)


def test_a_tank_seen_through_wide_scatter_must_stand_out_from_it():
    # Shots scattered 8 mm about the fit (the sensor said 2 mm): a 10 m tank's 12 mm sagitta
    # over 1 m no longer stands out from the scatter (F test); a 2 m tank's 89 mm over 1.2 m
    # of arc, at the same scatter, does.
    rng = np.random.default_rng(5)
    noise = rng.normal(0.0, 0.008, 30)
    for radius, half, measured in ((10.0, 0.05, False), (2.0, 0.3, True)):
        angle = rng.uniform(-half, half, 30)
        bent = radius + noise
        points = np.column_stack(
            [bent * np.sin(angle), 18.0 - bent * np.cos(angle), rng.uniform(0.0, 2.0, 30)]
        )
        assert curvature_measured(points, noise, 0.002, 5) is measured
