"""Moving obstacles in closed loop: an oncoming vehicle in the opposing lane and a slower lead.

The ``road`` scenario kind is not needed: the pop-up scenario's loop is built as usual and its
road swapped for a straight one carrying the moving obstacle (:func:`moving_run`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mufusion.metrics import compute_metrics
from mufusion.road import FrictionMap, Obstacle, straight_road
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import _planner_obstacle, build_loop, run_loop, run_meta
from mufusion.sim.world import World
from mufusion.vehicle.params import vehicle_preset

pytestmark = pytest.mark.slow

LANE_M = 3.5


def moving_run(obstacle_at: dict[str, float], duration_s: float, speed_mps: float = 20.0):
    """A 20 m/s run of the pop-up scenario's truck on a straight road with one moving obstacle.

    ``obstacle_at``: the obstacle's ``Obstacle`` fields, ``s_m`` measured from the vehicle's
    start.
    """
    cfg = load_scenario("popup", [f"duration_s={duration_s}", f"initial_speed_mps={speed_mps}"])
    params = vehicle_preset(cfg.vehicle)
    fields = dict(obstacle_at)
    fields["s_m"] += cfg.start_s_m
    road = straight_road(cfg.start_s_m + 600.0, lane_width_m=LANE_M,
                         friction=FrictionMap.uniform(cfg.friction.mu),
                         obstacles=(Obstacle(**fields),))
    loop = build_loop(cfg, friction="GT")
    config = loop.planner.config
    loop = dataclasses.replace(
        loop, world=World(road=road, to_planner_obstacle=_planner_obstacle),
        meta=run_meta(cfg, "GT", params, road, config),
    )
    return run_loop(loop, duration_s)


def test_an_oncoming_vehicle_in_the_opposing_lane_passes_without_evasion() -> None:
    # A car at 15 m/s in the middle of the opposing lane, 150 m ahead: met after ≈ 4.3 s.
    log = moving_run(dict(s_m=150.0, d_m=LANE_M, length_m=4.5, width_m=1.8, speed_mps=-15.0),
                     duration_s=6.0)
    ts, steps = log.timeseries, log.planning_steps
    metrics = compute_metrics(log)
    assert not metrics.collision
    assert ts["passed_obstacle"].astype(bool).any()  # they did meet
    assert set(steps["mode"]) == {"cruise"}  # nothing to evade, nothing to stop for
    assert not metrics.left_lane and not metrics.entered_opposing_lane
    assert metrics.max_abs_lateral_offset_m < 0.2
    # Its corners were placed where it was: beside the truck the gap is the lanes' geometry.
    beside = ts[ts["passed_obstacle"].astype(bool)].iloc[0]
    assert beside["clearance_m"] < LANE_M - 0.5 * (1.8 + log.meta.vehicle.width_m) + 0.3
    assert log.meta.obstacles[0].speed_mps == -15.0
    assert metrics.min_time_to_collision_s is None  # never in the truck's path


def test_a_slower_lead_in_the_own_lane_is_followed_not_hit() -> None:
    # A car at 10 m/s in the truck's lane, 40 m ahead of its start: the truck closes at 10 m/s.
    log = moving_run(dict(s_m=40.0, d_m=0.0, length_m=4.5, width_m=1.8, speed_mps=10.0),
                     duration_s=10.0)
    ts = log.timeseries
    metrics = compute_metrics(log)
    assert not metrics.collision
    clearance = ts["clearance_m"].to_numpy(float)
    assert np.nanmin(clearance) > 1.0
    # It matched the lead's speed behind it (it did not pass: the lead stays ahead).
    assert not ts["passed_obstacle"].astype(bool).any()
    assert abs(float(ts["speed_mps"].iloc[-1]) - 10.0) < 1.0
    assert not metrics.left_lane
    # Never critical: braking was never too late, never beyond the friction the road offers.
    assert metrics.min_time_to_brake_s is not None and metrics.min_time_to_brake_s > 0.0
    assert metrics.max_required_decel_over_mu_g is not None
    assert metrics.max_required_decel_over_mu_g < 0.5
