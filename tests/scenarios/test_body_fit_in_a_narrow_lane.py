"""The truck in a 3.0 m lane corners no faster than its plans' attitude leaves the corridor a
width (planner/body_fit.py, docs/decisions/0097)."""

from __future__ import annotations

import pytest

from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import run_scenario

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("body_fit", [True, False])
def test_the_truck_keeps_a_3_m_lane_on_a_dry_bend_only_at_its_bodys_speed(body_fit: bool) -> None:
    # 22 m/s on μ 0.3 towards a 60 m right bend whose friction rises to 0.8 20 m ahead (feasible
    # for the oracle's rigid body at 0.67 of μ g). At the polygon's 0.87 of μ̂ g the plans'
    # heading (their secant rear tire's slip) empties the corridor, the plans brake inside the
    # arc at their polygons and the tail swings 0.36 m over the edge; at the body's speed the
    # truck keeps the lane.
    cfg = load_scenario("turn", overrides=[
        "vehicle=truck", "road.lane_width_m=3.0", "turn.radius_m=60", "turn.angle_rad=1.2",
        "initial_speed_mps=22", "friction.mu_before=0.3", "friction.mu_turn=0.8",
        "friction.change_ahead_m=20", "turn.direction=right", "turn.start_ahead_m=35",
        "turn.clothoid_m=10", "duration_s=6", f"planner.body_fit={str(body_fit).lower()}",
    ])
    m = compute_metrics(run_scenario(cfg, "GT"))
    assert m.feasibility == "feasible"
    if body_fit:
        assert m.max_lane_excursion_m == 0.0
    else:
        assert m.max_lane_excursion_m > 0.2
