"""GT passes a pop-up on the side the road leaves room on (docs/decisions/0073).

The car 22 m from an obstacle 1.0 m left of the lane centre: passing right needs the car's
centre 0.8 m right, within the lane; passing left needs 2.8 m, which no car reaches in 22 m at
these speeds (the oracle: feasible by the right-hand evasion, +5.7 and +6.6 m/s). On 0072's code
GT went left and hit the obstacle at 14.2 and 23.0 m/s: the sampler's guess went left because
the right-hand roll-out's overshoot of the road's edge, summed over the horizon, outweighed the
left one's overlap with the obstacle, and the corridor opened the left side because the guess's
heading swing narrowed the right-hand passage below the margin.
"""

from __future__ import annotations

import logging

import pytest

from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import classify_scenario
from mufusion.scenarios.runner import run_scenario
from mufusion.vehicle.params import CAR


@pytest.mark.parametrize("mu, speed_mps", [(0.35, 18.0), (0.8, 24.0)])
def test_gt_passes_on_the_side_with_room(mu: float, speed_mps: float) -> None:
    cfg = load_scenario("popup", ["vehicle=car", f"friction.mu={mu}",
                                  f"initial_speed_mps={speed_mps}", "obstacle.distance_m=22",
                                  "obstacle.lateral_offset_m=1.0"])
    assert classify_scenario(cfg, CAR).feasibility_class == "feasible"
    logging.disable(logging.WARNING)
    try:
        log = run_scenario(cfg, "GT")
    finally:
        logging.disable(logging.NOTSET)
    metrics = compute_metrics(log)
    assert not metrics.collision
    assert metrics.min_clearance_m > 0.1
    # The right-hand side: up to the tick the obstacle is passed, the car is right of the lane
    # centre by more than half the shift the right needs once it is alongside (< 5 m to go).
    ts = log.timeseries
    passed = ts["passed_obstacle"].to_numpy().argmax()
    assert passed > 0
    alongside = ts.iloc[:passed]
    alongside = alongside[alongside["clearance_m"] < 5.0]
    assert len(alongside) > 0
    assert alongside["d_m"].max() < -0.4
