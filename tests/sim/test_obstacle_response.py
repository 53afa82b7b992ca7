from __future__ import annotations

import numpy as np

from mufusion.planner.ocp import PlannerObstacle
from mufusion.sim.obstacle_response import ObstacleResponse, obstacle_mode, stop_within_reach
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import N_STATES, State

GRID = np.arange(0.0, 51.0)
ROAD = (-0.35, 3.85)


def state(speed: float, d: float = 0.0) -> np.ndarray:
    x = np.zeros(N_STATES)
    x[State.s], x[State.d], x[State.vx] = 60.0, d, speed
    return x


def mode(speed, ahead_m, mu, offset=0.0, brake_first=True, braking=False, d=0.0):
    front = 0.5 * TRUCK.length_m + 0.5 * (TRUCK.cog_to_front_axle_m - TRUCK.cog_to_rear_axle_m)
    ob = PlannerObstacle(s_m=60.0 + front + ahead_m, d_m=offset, length_m=1.0, width_m=1.0)
    return obstacle_mode([ob], state(speed, d), GRID, np.full(GRID.shape, mu), ROAD, TRUCK,
                         ObstacleResponse(brake_first=brake_first), braking=braking)


def test_stop_where_possible_else_evade() -> None:
    # 14 m/s, μ̂ 0.75: stop in 0.25·14 + 14²/(2·6.40) = 18.8 m of 35 − 0.5 − 0.5 = 34 m.
    assert mode(14.0, 35.0, 0.75) == "emergency"
    # 24 m/s: 6 + 45 m, more than there is: evade.
    assert mode(24.0, 35.0, 0.75) == "evade"
    # The paper's choice: evade whenever there is an obstacle.
    assert mode(14.0, 35.0, 0.75, brake_first=False) == "evade"
    assert obstacle_mode([], state(14.0), GRID, np.full(51, 0.75), ROAD, TRUCK,
                         ObstacleResponse(brake_first=True)) == "cruise"


def test_a_stop_under_way_is_not_charged_the_brake_lag_again() -> None:
    # A gap between the stop with the lag (0.25 s of dead time) and without it (0.1 s).
    decel = 0.9 * np.cos(np.pi / 12) * 0.5 * 9.81
    speed = 12.0
    gap = speed * 0.18 + speed**2 / (2 * decel)  # between the two dead times
    ahead = gap + 1.0
    assert mode(speed, ahead, 0.5) == "evade"
    assert mode(speed, ahead, 0.5, braking=True) == "emergency"


def test_obstacles_beside_the_path_or_blocking_the_road() -> None:
    # 3 m left of the vehicle: not in its path (clearance 2.3 m), nothing to stop for.
    assert mode(24.0, 20.0, 0.75, offset=3.0) == "evade"
    # Straddling so that neither side has room: stop, whatever the speed.
    assert mode(24.0, 20.0, 0.75, offset=1.6) == "emergency"


def test_a_stop_on_a_blocked_road_says_whether_the_estimate_reaches_it() -> None:
    front = 0.5 * TRUCK.length_m + 0.5 * (TRUCK.cog_to_front_axle_m - TRUCK.cog_to_rear_axle_m)

    def reach(speed, ahead_m, mu, offset=1.6, moving=0.0):
        ob = PlannerObstacle(s_m=60.0 + front + ahead_m, d_m=offset, length_m=1.0,
                             width_m=1.0, speed_mps=moving)
        return stop_within_reach([ob], state(speed), GRID, np.full(GRID.shape, mu), TRUCK,
                                 ObstacleResponse(brake_first=True))

    # The rule stops for a blocked road at any speed; the estimate reaches that stop only
    # where it would grant it anyway (14 m/s needs 18.8 m at μ̂ 0.75, 24 m/s 51 m).
    assert mode(24.0, 35.0, 0.75, offset=1.6) == mode(14.0, 35.0, 0.75, offset=1.6) == "emergency"
    assert reach(14.0, 35.0, 0.75) and not reach(24.0, 35.0, 0.75)
    assert not reach(14.0, 35.0, 0.2)
    # Beside the path there is nothing to stop for; traffic is not judged here.
    assert reach(24.0, 35.0, 0.2, offset=3.0)
    assert reach(24.0, 35.0, 0.2, moving=-10.0)


class _FailingPlanner:
    """A planner whose every solve fails (fallback plans that hold the state)."""

    def step(self, x0, t_s, **kw):
        from mufusion.planner import Plan

        n = 8
        states = np.tile(x0, (n + 1, 1))
        fz = np.full(n, 50e3)
        return Plan(t0_s=t_s, states=states, inputs=np.zeros((n, 3)),
                    rear_lateral_force_n=np.zeros(n), mu_hat=np.full(n, 0.8),
                    normal_load_front_n=fz, normal_load_rear_n=fz, force_limit_front_n=fz,
                    force_limit_rear_n=fz, status=4, ok=False, fallback=True,
                    solve_time_s=1e-4)


def _events(speed_mps: float) -> list[str]:
    from factories import run_meta
    from mufusion.configurations import FrictionEstimate
    from mufusion.estimators import Channel
    from mufusion.road import FrictionMap, Obstacle, straight_road
    from mufusion.sim.loop import ClosedLoop, LoopRates
    from mufusion.sim.world import World
    from mufusion.vehicle.actuators import ActuatorCommand
    from mufusion.vehicle.plant import Plant, initial_state

    class _Controller:
        def command(self, t_s, x_frenet, steer_rad_now, plan, curvature, torques_now_nm=None):
            return ActuatorCommand(0.0, -2000.0, -2000.0)

    class _Friction:
        channels = frozenset({Channel.TRUTH})

        def step(self, frame, truth):
            return FrictionEstimate(s_m=frame.s_ahead_m, mu_hat=truth.mu,
                                    local_available=False, local_mu=None)

    road = straight_road(300.0, friction=FrictionMap.step(0.8, 0.8, 40.0),
                         obstacles=[Obstacle(s_m=35.0, d_m=0.0, length_m=1.0, width_m=1.0)])
    world = World(road, to_planner_obstacle=lambda o: PlannerObstacle(o.s_m, o.d_m, 1.0, 1.0))
    rates = LoopRates(200.0, 50.0, 10.0)
    plant = Plant(TRUCK, initial_state(TRUCK, 20.0, 0.0, 0.0, speed_mps), dt_s=1 / 200.0)
    loop = ClosedLoop(world=world, params=TRUCK, plant=plant, planner=_FailingPlanner(),
                      controller=_Controller(), friction=_Friction(), rates=rates,
                      reference_speed_mps=10.0, lane_bounds_m=(-0.45, 0.45), meta=run_meta(),
                      emergency_on_obstacle=True)
    log = loop.run(1.0)
    return list(log.frame("events")["kind"])


def test_failed_plans_at_rest_in_front_of_an_obstacle_start_no_minimal_risk_manoeuvre() -> None:
    # At rest: ten failed plans in a row, no manoeuvre; moving (5 m/s): the manoeuvre after five.
    assert "minimal_risk" not in _events(0.0)
    assert "minimal_risk" in _events(5.0)


def _traffic_mode(ob: PlannerObstacle, brake_first: bool = True, speed: float = 20.0) -> str:
    return obstacle_mode([ob], state(speed), GRID, np.full(GRID.shape, 0.9), ROAD, TRUCK,
                         ObstacleResponse(brake_first=brake_first))


def test_traffic_outside_the_path_is_no_reason_to_evade() -> None:
    # An oncoming car in the opposing lane: cruise in both settings (a static obstacle there
    # would make the paper's rule evade: the static rule is unchanged).
    oncoming = PlannerObstacle(100.0, 3.5, 4.5, 1.8, speed_mps=-15.0)
    assert _traffic_mode(oncoming) == "cruise"
    assert _traffic_mode(oncoming, brake_first=False) == "cruise"
    assert _traffic_mode(PlannerObstacle(100.0, 3.5, 4.5, 1.8), brake_first=False) == "evade"


def test_a_lead_is_followed_while_its_speed_can_be_matched() -> None:
    front = TRUCK.cog_to_body_front_m
    decel = 0.9 * np.cos(np.pi / 12) * 0.9 * 9.81
    relative = 10.0  # 20 m/s behind a car at 10 m/s
    # Matching 10 m/s needs 10·0.25 + 10²/(2 decel) = 8.3 m of gap (dead time 0.1 + 0.15 s).
    need = relative * (0.1 + TRUCK.torque_time_constant_s) + relative**2 / (2 * decel)
    at = 60.0 + front + 2.25 + 0.5
    def lead(s_m: float) -> PlannerObstacle:
        return PlannerObstacle(s_m, 0.0, 4.5, 1.8, speed_mps=10.0)

    assert _traffic_mode(lead(at + need + 0.5)) == "cruise"
    # Closer: a conflict; the road has room on the left, so evade.
    assert _traffic_mode(lead(at + need - 0.5)) == "evade"
    # Oncoming in the own lane: a conflict at any distance.
    assert _traffic_mode(PlannerObstacle(300.0, 0.0, 4.5, 1.8, speed_mps=-5.0)) == "evade"
