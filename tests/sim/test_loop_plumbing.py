"""The closed loop's plumbing with stand-in components: rates, logging, stops, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from factories import run_meta
from mufusion.configurations import FrictionEstimate
from mufusion.estimators import Channel
from mufusion.metrics import compute_metrics
from mufusion.planner import Plan, PlannerObstacle
from mufusion.road import FrictionMap, Obstacle, straight_road
from mufusion.sim.log import load_run
from mufusion.sim.loop import ClosedLoop, LoopRates
from mufusion.sim.world import World
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import State
from mufusion.vehicle.plant import Plant, initial_state
from mufusion.vehicle.plant_state import PlantState

N = 8


class _Planner:
    """Keeps speed on a straight line; records what it was given."""

    def __init__(self) -> None:
        self.calls: list[dict] = []

    def step(self, x0, t_s, **kw):
        self.calls.append({"t": t_s, "s": float(x0[State.s]), **kw})
        states = np.tile(x0, (N + 1, 1))
        states[:, State.s] += np.arange(N + 1) * 0.1 * x0[State.vx]
        mu = kw["mu_hat_of_s"](states[:-1, State.s])
        fz = np.full(N, 50e3)
        limit = 0.9 * mu * fz
        return Plan(t0_s=t_s, states=states, inputs=np.zeros((N, 3)),
                    rear_lateral_force_n=np.zeros(N), mu_hat=mu, normal_load_front_n=fz,
                    normal_load_rear_n=fz, force_limit_front_n=limit, force_limit_rear_n=limit,
                    status=0, ok=True, fallback=False, solve_time_s=1e-4)


class _Controller:
    def __init__(self, steer_rad: float = 0.0, torque_front_nm: float = 0.0) -> None:
        self.steer_rad = steer_rad
        self.torque_front_nm = torque_front_nm
        self.times: list[float] = []

    def command(self, t_s, x_frenet, steer_rad_now, plan, curvature, torques_now_nm=None):
        self.times.append(t_s)
        return ActuatorCommand(self.steer_rad, self.torque_front_nm, 0.0)


class _Friction:
    channels = frozenset({Channel.TRUTH})

    def __init__(self) -> None:
        self.utilizations: list[float] = []

    def step(self, frame, truth):
        self.utilizations.append(frame.utilization_peak)
        return FrictionEstimate(s_m=frame.s_ahead_m, mu_hat=truth.mu - 0.1,
                                local_available=False, local_mu=None)


RATES = LoopRates(200.0, 50.0, 10.0)


def _loop(obstacles=(), steer_rad=0.0, rates=RATES, torque_front_nm=0.0):
    road = straight_road(300.0, friction=FrictionMap.step(1.0, 0.5, 40.0), obstacles=obstacles)
    world = World(road, to_planner_obstacle=lambda o: PlannerObstacle(o.s_m, o.d_m, 1.0, 1.0))
    plant = Plant(TRUCK, initial_state(TRUCK, 20.0, 0.0, 0.0, 15.0), dt_s=1.0 / rates.plant_hz)
    planner, controller, friction = _Planner(), _Controller(steer_rad, torque_front_nm), _Friction()
    loop = ClosedLoop(
        world=world, params=TRUCK, plant=plant, planner=planner, controller=controller,
        friction=friction, rates=rates, reference_speed_mps=15.0, lane_bounds_m=(-0.45, 0.45),
        meta=run_meta(),
    )
    return loop, planner, controller, friction


def test_rates_and_tables() -> None:
    loop, planner, controller, _ = _loop()
    log = loop.run(1.0, warmup_steps=3)
    # 3 warm-up plans, then t = 0, 0.1, ..., 1.0
    assert len(planner.calls) == 3 + 11
    assert np.allclose([c["t"] for c in planner.calls[3:]], np.arange(11) * 0.1)
    assert np.allclose(controller.times, np.arange(51) * 0.02)
    assert len(log.timeseries) == 51
    assert len(log.planning_steps) == 11 and len(log.timing) == 11
    assert len(log.plans) == 11 * N
    assert len(log.estimates) == 11 * 51
    # μ̂ handed to the planner is the estimate (true − 0.1) interpolated at absolute s.
    step0 = log.estimates[log.estimates["step"] == 0]
    np.testing.assert_allclose(step0["mu_hat"], step0["mu_true"] - 0.1)
    plans0 = log.plans[log.plans["step"] == 0]
    np.testing.assert_allclose(plans0["limit_front_n"], 0.9 * plans0["mu_hat"] * 50e3)


def test_true_friction_under_axles_is_logged() -> None:
    loop, *_ = _loop()
    log = loop.run(2.0)
    ts = log.timeseries
    # friction drops from 1.0 to 0.5 at s = 40 m: the front axle sees it before the rear axle.
    front_drop = ts["t_s"][ts["mu_front"] < 0.75].min()
    rear_drop = ts["t_s"][ts["mu_rear"] < 0.75].min()
    assert front_drop < rear_drop


def test_the_log_holds_the_applied_torques_and_the_commands_apart() -> None:
    # A brake step: the command is logged as given at every tick, the wheel torque as the plant
    # applies it, a first-order lag from zero (logging the command as the torque made a braking
    # that had not yet arrived look applied).
    loop, *_ = _loop(torque_front_nm=-10_000.0)
    ts = loop.run(0.5).timeseries
    np.testing.assert_array_equal(ts["torque_front_cmd_nm"], -10_000.0)
    np.testing.assert_array_equal(ts["torque_rear_cmd_nm"], 0.0)
    lag = -10_000.0 * (1.0 - np.exp(-ts["t_s"] / TRUCK.torque_time_constant_s))
    np.testing.assert_allclose(ts["torque_front_nm"], lag, atol=5.0)
    assert ts["torque_front_nm"].iloc[0] == 0.0 and ts["torque_front_nm"].iloc[-1] < -9_000.0


def test_utilization_reaches_the_estimator() -> None:
    loop, _, _, friction = _loop(steer_rad=0.05)
    loop.run(1.0)
    assert friction.utilizations[0] == 0.0
    assert max(friction.utilizations) > 0.2


def test_each_plan_is_given_the_front_force_the_tires_deliver() -> None:
    # The plans' front-force state starts from the realised force (docs/decisions/0051, "A check
    # that judges the solver"): the planner gets the front axle's body-frame force of the plant
    # step that ends at its tick, none before the clock starts or at t = 0.
    loop, planner, _, _ = _loop(steer_rad=0.05)
    outputs = []
    plant_step = loop.plant.step

    def recording_step(*args):
        out = plant_step(*args)
        outputs.append(out)
        return out

    loop.plant.step = recording_step
    loop.run(1.0, warmup_steps=3)
    given = [c["front_force_n"] for c in planner.calls]
    assert given[:4] == [None] * 4  # three warm-up plans and the one at t = 0
    per_plan = RATES.plant_hz / RATES.planner_hz
    expected = [outputs[round(k * per_plan) - 1].front_lateral_force_n for k in range(1, 11)]
    assert given[4:] == expected
    assert min(abs(f) for f in expected[2:]) > 1e3  # the truck is steered: a real force
    # The longitudinal force states start from the wheel torques the same step leaves, over the
    # wheel radius (docs/decisions/0068).
    radius = TRUCK.wheel_radius_m
    longitudinal = [c["longitudinal_forces_n"] for c in planner.calls]
    assert longitudinal[:4] == [None] * 3 + [(0.0, 0.0)]  # the warm-up plans; at rest
    assert longitudinal[4:] == [
        (outputs[round(k * per_plan) - 1].x[PlantState.TORQUE_FRONT] / radius,
         outputs[round(k * per_plan) - 1].x[PlantState.TORQUE_REAR] / radius)
        for k in range(1, 11)]


def test_collision_stops_the_run_and_is_measured() -> None:
    obstacle = Obstacle(s_m=45.0, d_m=0.0, length_m=1.0, width_m=1.0)
    loop, *_ = _loop(obstacles=(obstacle,))
    log = loop.run(5.0)
    m = compute_metrics(log)
    assert m.collision and m.impact_speed_mps == pytest.approx(15.0, abs=1.0)
    assert log.timeseries["t_s"].iloc[-1] < 2.0


def test_passing_an_obstacle_measures_clearance() -> None:
    obstacle = Obstacle(s_m=45.0, d_m=3.0, length_m=1.0, width_m=1.0)
    log = _loop(obstacles=(obstacle,))[0].run(3.0)
    m = compute_metrics(log)
    assert not m.collision
    # footprint half-width 1.3 m, obstacle half-width 0.5 m, 3 m apart → ≈ 1.2 m.
    assert m.min_clearance_m == pytest.approx(1.2, abs=0.1)


def test_deterministic_and_round_trip(tmp_path) -> None:
    a = _loop()[0].run(1.0)
    b = _loop()[0].run(1.0)
    for table in ("timeseries", "planning_steps", "plans", "estimates"):
        assert a.frame(table).equals(b.frame(table)), table
    back = load_run(a.save(tmp_path / "run"))
    np.testing.assert_allclose(back.timeseries["s_m"], a.timeseries["s_m"], rtol=1e-8)


@pytest.mark.parametrize(
    ("rates", "match"),
    [
        (dict(plant_hz=200.0, controller_hz=30.0, planner_hz=10.0), "controller_hz"),
        (dict(plant_hz=200.0, controller_hz=50.0, planner_hz=20.0), "planner_hz"),
        (dict(plant_hz=-1.0, controller_hz=50.0, planner_hz=10.0), "plant_hz"),
    ],
)
def test_bad_rates(rates, match) -> None:
    with pytest.raises(ValueError, match=match):
        LoopRates(**rates)


def test_bad_duration() -> None:
    with pytest.raises(ValueError, match="duration_s"):
        _loop()[0].run(0.0)
