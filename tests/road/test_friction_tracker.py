"""FrictionTracker: the friction under a moving point, exactly as projecting it every time."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mufusion.road import FrictionMap, FrictionTracker, turn_road


def _friction_maps() -> list[FrictionMap]:
    return [
        FrictionMap.step(0.8, 0.4, 84.0),  # changes inside the clothoid into the turn
        FrictionMap((0.0, 70.0, 90.0, 110.0, 112.0), (0.9, 0.5, 0.3, 0.7, 0.2),
                    mu_opposing=(0.6, 0.6, 0.2, 0.2, 0.9)),
    ]


@pytest.mark.parametrize("friction", _friction_maps())
def test_tracked_friction_equals_projecting_every_step(friction: FrictionMap) -> None:
    road = turn_road(28.0, 60.0, 60.0, 5.0, "right", friction=friction)
    path = road.path
    rng = np.random.default_rng(11)
    tracker = FrictionTracker(path, friction)
    # A point weaving across the lane boundary while driving through the turn at 20 m/s.
    steps = 0
    for s in np.arange(50.0, 160.0, 0.1):
        d = 1.75 + 1.2 * math.sin(0.3 * s) + rng.normal(0.0, 0.02)
        x, y, _ = (float(v) for v in path.to_cartesian(s, d))
        expected_s, expected_d, _ = path.to_frenet_point(x, y)
        assert tracker.mu_at(x, y) == friction.mu_at_point(expected_s, expected_d), s
        steps += 1
    # It does skip projections (most steps are far from a change), yet sees every change.
    assert tracker.projections < steps // 2


def test_a_jump_far_away_is_projected() -> None:
    friction = FrictionMap.step(0.8, 0.4, 84.0)
    road = turn_road(28.0, 60.0, 60.0, 5.0, "left", friction=friction)
    tracker = FrictionTracker(road.path, friction)
    assert tracker.mu_at(10.0, 0.0) == 0.8
    x, y, _ = (float(v) for v in road.path.to_cartesian(100.0, 0.0))
    assert tracker.mu_at(x, y) == 0.4 and tracker.projections == 2
    tracker.reset()
    assert tracker.mu_at(x, y) == 0.4 and tracker.projections == 3
