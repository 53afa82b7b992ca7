"""The world's per-tick geometry (warm-started, plain floats) against the exact stateless functions.

The closed loop asks the world for the Frenet state, the friction under the axles and the
footprint status at every tick. The world answers from projections warm-started at the previous
tick; here every answer is recomputed with the road's stateless array functions (global
projection, quadrature positions, array rectangles) on a weaving trajectory with jumps, and must
agree to 1e-9 (values) and exactly (flags).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mufusion.road import (
    FrictionMap,
    Obstacle,
    footprint_clearance_m,
    footprint_corner_offsets_m,
    lane_margin_m,
    obstacle_active,
    opposing_lane_depth_m,
    road_margin_m,
    turn_road,
)
from mufusion.sim.world import World
from mufusion.vehicle.params import CAR, TRUCK
from mufusion.vehicle.planner_model import State
from mufusion.vehicle.plant import PlantState, axle_positions, initial_state

TOL = 1e-9


def _road():
    friction = FrictionMap((0.0, 60.0, 95.0, 120.0), (0.9, 0.5, 0.3, 0.8),
                           mu_opposing=(0.7, 0.6, 0.5, 0.4))
    obstacles = (
        Obstacle(70.0, 0.2, 2.0, 1.5),
        Obstacle(110.0, 3.0, 1.0, 1.0, appear_at_ego_s_m=90.0),
        Obstacle(140.0, -0.5, 1.0, 1.0, appear_at_time_s=5.0),
    )
    return turn_road(radius_m=28.0, approach_m=60.0, exit_m=60.0, clothoid_m=5.0,
                     friction=friction, obstacles=obstacles)


def _poses(road, rng: np.random.Generator, n: int) -> np.ndarray:
    """A weaving drive along the road (0.1 m per tick) with a few random jumps: (x, y, ψ)."""
    s = np.arange(n) * 0.1 + 40.0
    jumps = rng.choice(n, 6, replace=False)
    s[jumps] = rng.uniform(0.0, road.length_m, 6)
    d = 2.0 * np.sin(0.05 * s) + 1.0 + 0.3 * rng.standard_normal(n)
    dpsi = 0.3 * np.sin(0.11 * s) + 0.05 * rng.standard_normal(n)
    x, y, psi = road.to_cartesian(s, d, dpsi)
    return np.stack([x, y, psi], axis=-1)


@pytest.mark.parametrize("params", [TRUCK, CAR])
def test_world_answers_equal_the_exact_stateless_functions(params) -> None:
    road = _road()
    world = World(road, to_planner_obstacle=lambda o: o)
    rng = np.random.default_rng(2024)
    poses = _poses(road, rng, 800)
    shift = 0.5 * (params.cog_to_front_axle_m - params.cog_to_rear_axle_m)
    flags_seen = set()
    for k, (x, y, psi) in enumerate(poses.tolist()):
        t = 0.02 * k
        state = initial_state(params, x, y, psi, 10.0)
        xf = world.frenet_state(state)
        s, d, dpsi = (float(v) for v in road.to_frenet(x, y, psi))
        assert abs(xf[State.s] - s) <= TOL and abs(xf[State.d] - d) <= TOL
        assert abs(math.remainder(xf[State.dpsi] - dpsi, 2 * math.pi)) <= TOL
        assert xf[State.vx] == state[PlantState.VX]

        front, rear = axle_positions(state, params)
        mu_ref = road.mu_at_xy(np.array([front[0], rear[0]]), np.array([front[1], rear[1]]))
        assert world.friction_under_axles(state, params) == tuple(mu_ref.tolist())

        status = world.footprint_status((x, y, psi), t, s, params)
        cx, cy = x + shift * math.cos(psi), y + shift * math.sin(psi)
        s_c, d_c, dpsi_c = road.to_frenet(cx, cy, psi)
        corners = footprint_corner_offsets_m(road.path, s_c, d_c, dpsi_c, params.length_m,
                                             params.width_m)
        w = road.lane_width_m
        assert abs(status.lane_margin_m - float(lane_margin_m(corners, w))) <= TOL
        assert abs(status.opposing_depth_m - float(opposing_lane_depth_m(corners, w))) <= TOL
        assert abs(status.road_margin_m - float(road_margin_m(corners, w))) <= TOL
        assert status.lane_excursion_m == max(0.0, -status.lane_margin_m)
        length, width = params.length_m, params.width_m
        assert status.left_lane == bool(road.left_ego_lane(s_c, d_c, dpsi_c, length, width))
        assert status.in_opposing_lane == bool(
            road.entered_opposing_lane(s_c, d_c, dpsi_c, length, width)
        )
        assert status.off_road == bool(road.left_road(s_c, d_c, dpsi_c, length, width))
        assert (status.mu_front, status.mu_rear) == tuple(mu_ref.tolist())

        active = [o for o in road.obstacles if bool(obstacle_active(o, s, t))]
        assert status.obstacle_active == bool(active)
        if active:
            clearance = min(float(footprint_clearance_m(o, road.path, cx, cy, psi, length,
                                                        width)) for o in active)
            assert abs(status.clearance_m - clearance) <= TOL
            assert status.in_collision == (clearance <= 0.0)
            passed = any(float(s_c) - 0.5 * length > o.s_m + 0.5 * o.length_m for o in active)
            assert status.passed_obstacle == passed
        else:
            assert math.isnan(status.clearance_m) and not status.in_collision
        flags_seen.add((status.left_lane, status.in_opposing_lane, status.off_road,
                        status.in_collision))
    # The drive covered inside, outside, opposing lane, off road and collisions.
    assert {f[0] for f in flags_seen} == {True, False}
    assert {f[1] for f in flags_seen} == {True, False}
    assert {f[2] for f in flags_seen} == {True, False}
    assert {f[3] for f in flags_seen} == {True, False}


def test_footprint_status_hand_calculation_on_a_straight() -> None:
    # Footprint centred between the axles: for a pose at the road's heading with the centre at
    # d = 0.5 m and yawed by 10°, the corners lie at 0.5 ± (L/2) sin 10° ± (W/2) cos 10°.
    road = turn_road(approach_m=100.0)
    world = World(road, to_planner_obstacle=lambda o: o)
    params = TRUCK
    shift = 0.5 * (params.cog_to_front_axle_m - params.cog_to_rear_axle_m)
    yaw = math.radians(10.0)
    cx, cy = 50.0, 0.5
    pose = (cx - shift * math.cos(yaw), cy - shift * math.sin(yaw), yaw)
    status = world.footprint_status(pose, 0.0, 50.0, params)
    reach = 0.5 * params.length_m * math.sin(yaw) + 0.5 * params.width_m * math.cos(yaw)
    assert status.lane_margin_m == pytest.approx(1.75 - (0.5 + reach), abs=1e-12)
    assert status.opposing_depth_m == pytest.approx(max(0.0, 0.5 + reach - 1.75), abs=1e-12)
    assert status.road_margin_m == pytest.approx(min(0.5 - reach + 1.75, 5.25 - 0.5 - reach),
                                                 abs=1e-12)
    assert status.left_lane == (0.5 + reach > 1.75)
