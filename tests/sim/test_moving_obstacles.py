"""A moving obstacle is where it is at the time asked: the world's clearance, the planner's view."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.road import Obstacle, obstacle_corners, straight_road
from mufusion.sim.world import World, obstacle_now
from mufusion.vehicle.params import CAR

OB = Obstacle(100.0, 0.0, length_m=4.0, width_m=2.0, speed_mps=-10.0)


def _world() -> World:
    return World(straight_road(300.0, obstacles=(OB,)), to_planner_obstacle=lambda o: o)


def _pose_with_front_at(front_x_m: float) -> tuple[float, float, float]:
    """The CoG pose (x, y, ψ) on the lane centre, heading +x, whose footprint's front is at x."""
    return front_x_m - CAR.cog_to_body_front_m, 0.0, 0.0


@pytest.mark.parametrize(("t_s", "expected_m"), [
    (0.0, 98.0 - 60.0),  # centre at 100, near face at 98
    (2.0, 78.0 - 60.0),  # centre at 100 − 10·2 = 80, near face at 78
    (3.5, 63.0 - 60.0),
])
def test_clearance_is_taken_where_the_obstacle_is_at_that_time(t_s, expected_m) -> None:
    status = _world().footprint_status(_pose_with_front_at(60.0), t_s, 58.0, CAR)
    assert status.clearance_m == pytest.approx(expected_m, abs=1e-9)
    assert not status.in_collision


def test_a_moving_obstacle_reaches_a_vehicle_standing_still() -> None:
    # Near face at 60 when the centre is at 62: t = (100 − 62) / 10 = 3.8 s; a tick later, overlap.
    world = _world()
    assert world.footprint_status(_pose_with_front_at(60.0), 3.79, 58.0, CAR).clearance_m > 0.0
    assert world.footprint_status(_pose_with_front_at(60.0), 3.81, 58.0, CAR).in_collision


def test_passed_is_judged_against_the_obstacles_position_then() -> None:
    # The footprint's rear (at 60 − the car's length) is beyond the obstacle's far end only once
    # the obstacle has come by: its far end is at 102 at t = 0 and at 42 at t = 6 s.
    pose = _pose_with_front_at(60.0)
    world = _world()
    assert not world.footprint_status(pose, 0.0, 58.0, CAR).passed_obstacle
    assert world.footprint_status(pose, 6.0, 58.0, CAR).passed_obstacle


def test_the_planner_sees_it_where_it_is_at_the_step() -> None:
    seen = _world().planner_obstacles(2.0, 50.0)
    assert [(o.s_m, o.speed_mps) for o in seen] == [(80.0, -10.0)]
    # Behind the vehicle by more than allowed: left out (its far end at 100 − 70 + 2 = 32 m).
    assert _world().planner_obstacles(7.0, 40.0, behind_m=5.0) == []


def test_corners_at_a_time_and_a_static_obstacle_unchanged() -> None:
    path = straight_road(300.0).path
    np.testing.assert_allclose(obstacle_corners(OB, path, 2.0)[:, 0].min(), 78.0)
    static = Obstacle(100.0, 0.0, 4.0, 2.0)
    assert obstacle_now(static, 5.0) is static
    assert np.array_equal(obstacle_corners(static, path, 5.0), obstacle_corners(static, path))
