"""Planner behaviour: friction-adaptive speed before a curve, evasion, SAA on a pop-up obstacle."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.ocp import PlannerObstacle
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import State

CURVE_START_M = 40.0
CURVE_RADIUS_M = 50.0


def _curvature(s):
    return np.where(np.asarray(s) >= CURVE_START_M, 1.0 / CURVE_RADIUS_M, 0.0)


def _loop(planner, steps, mu_of_s, obstacle_at_step=None, obstacle_offset=(30.0, 0.0), v=15.0,
          lane=(-0.45, 3.95)):
    planner.reset()
    x = np.array([0.0, 0.0, 0.0, 0.0, v, 0.0])
    obstacles, plans, clearance = [], [], np.inf
    for i in range(steps):
        if obstacle_at_step is not None and i == obstacle_at_step:
            obstacles = [PlannerObstacle(x[State.s] + obstacle_offset[0], obstacle_offset[1],
                                         1.0, 1.0)]
        plan = planner.step(x, 0.1 * i, _curvature if obstacle_at_step is None else
                            (lambda s: 0.0 * np.asarray(s)), mu_of_s, obstacles, "cruise", v,
                            lane_d_min_m=lane[0], lane_d_max_m=lane[1])
        plans.append(plan)
        x = plan.states[1]
        for ob in obstacles:
            if abs(x[State.s] - ob.s_m) < 0.5 * (TRUCK.length_m + ob.length_m):
                gap = abs(x[State.d] - ob.d_m) - 0.5 * (TRUCK.width_m + ob.width_m)
                clearance = min(clearance, gap)
    return plans, clearance


def _speed_at_curve_entry(planner, mu):
    # One lane only: on the two-lane road the plan would widen the curve instead of slowing.
    plans, _ = _loop(planner, 10, lambda s: mu + 0.0 * np.asarray(s), lane=(-0.45, 0.45))
    plan = plans[-1]
    return float(np.interp(CURVE_START_M, plan.states[:, State.s], plan.states[:, State.vx]))


def test_lower_friction_ahead_slows_before_the_curve(two_lane_planner):
    v_low = _speed_at_curve_entry(two_lane_planner, 0.3)
    v_high = _speed_at_curve_entry(two_lane_planner, 0.9)
    assert v_low < v_high - 1.0
    # Steady cornering needs v² / R ≤ λ μ g; once in the curve the plan's speed gets there.
    plans, _ = _loop(two_lane_planner, 25, lambda s: 0.3 + 0.0 * np.asarray(s),
                     lane=(-0.45, 0.45))
    states = plans[-1].states
    in_curve = states[:, State.s] >= CURVE_START_M
    v_limit = np.sqrt(0.9 * 0.3 * 9.81 * CURVE_RADIUS_M)
    assert states[in_curve, State.vx].min() <= 1.05 * v_limit


@pytest.mark.parametrize("mu_low,mu_high", [(0.3, 0.5), (0.5, 0.7), (0.7, 1.0)])
def test_raising_friction_never_makes_the_plan_more_conservative(two_lane_planner, mu_low,
                                                                   mu_high):
    assert _speed_at_curve_entry(two_lane_planner, mu_high) >= (
        _speed_at_curve_entry(two_lane_planner, mu_low) - 0.05
    )


def test_obstacle_ahead_gives_evasive_plan_within_the_road(two_lane_planner):
    plans, clearance = _loop(two_lane_planner, 40, lambda s: 0.9 + 0.0 * np.asarray(s),
                             obstacle_at_step=5, obstacle_offset=(35.0, 0.0), v=20.0)
    assert clearance > 0.0
    half_w = 0.5 * TRUCK.width_m
    for plan in plans:
        d = plan.states[:, State.d]
        assert np.all(d >= -1.75 + half_w - 0.05) and np.all(d <= 5.25 - half_w + 0.05)


def test_popup_slightly_left_is_passed_on_the_side_with_room(
    two_lane_planner, two_lane_planner_no_sampling
):
    # Slightly left of centre: the shifted plan (d = 0) would put the corridor on the right, where
    # the lane edge leaves no room. That side is never opened (planner.passing), so the plain RTI
    # passes on the left too; before, only the sampling's re-initialisation switched sides and the
    # plain RTI collided.
    mu = lambda s: 0.9 + 0.0 * np.asarray(s)  # noqa: E731
    plans_rti, clearance_rti = _loop(two_lane_planner_no_sampling, 40, mu, 10, (30.0, 0.3), 20.0)
    plans_saa, clearance_saa = _loop(two_lane_planner, 40, mu, 10, (30.0, 0.3), 20.0)
    assert clearance_rti > 0.0
    assert clearance_saa > 0.0
    assert not any(p.sampled_reinit for p in plans_rti)
    for plans in (plans_rti, plans_saa):
        assert max(p.states[:, State.d].max() for p in plans) > 2.0  # left of the obstacle
