"""The planner's and controller's cornering stiffness: fixed, or following μ̂ (the authors')."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.controller import TrackingController, front_slip_angle_for_force_rad
from mufusion.planner.ocp import PlannerConfig, stage_parameters
from mufusion.planner.plan import Plan
from mufusion.planner.sampling import SamplingConfig, candidate_rollouts
from mufusion.scenarios import load_scenario
from mufusion.scenarios.runner import planner_config
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import (
    State,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
    secant_stiffness_factor,
    surface_stiffness_per_load,
)
from mufusion.vehicle.surface_tires import (
    AUTHORS_TIRES,
    AUTHORS_TIRES_INTERPOLATED,
    lateral_force_n,
    tire_for_surface,
)

N = 40
LAMBDA = 0.9


def _guess(speed_mps: float = 15.0) -> tuple[np.ndarray, np.ndarray]:
    xs = np.zeros((N + 1, 6))
    xs[:, State.s] = speed_mps * 0.1 * np.arange(N + 1)
    xs[:, State.vx] = speed_mps
    return xs, np.zeros((N, 3))


def _mu_step(s: np.ndarray) -> np.ndarray:
    # μ̂ 0.8 for the first 30 m of the plan, 0.4 beyond.
    return np.where(np.asarray(s) < 30.0, 0.8, 0.4)


def test_config_checks_the_stiffness_setting() -> None:
    with pytest.raises(ValueError, match="stiffness must be one of"):
        PlannerConfig(stiffness="linear")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="needs a SurfaceTireTable"):
        PlannerConfig(stiffness="from_mu_hat")
    with pytest.raises(ValueError, match="only used with stiffness='from_mu_hat'"):
        PlannerConfig(stiffness_table=AUTHORS_TIRES)
    assert PlannerConfig(stiffness="from_mu_hat", stiffness_table=AUTHORS_TIRES).stiffness_table


def test_fixed_stiffness_is_the_vehicles_tire_at_every_stage() -> None:
    xs, us = _guess()
    fixed = stage_parameters(xs, us, lambda s: 0.0 * s, _mu_step, TRUCK, LAMBDA)
    _, fzr = normal_loads_n(np.zeros(N), TRUCK)
    expected = rear_cornering_stiffness_n_per_rad(TRUCK, fzr, LAMBDA)
    np.testing.assert_array_equal(fixed.rear_stiffness_n_per_rad, expected)
    assert np.unique(fixed.rear_stiffness_n_per_rad).size == 1


def test_stiffness_from_mu_hat_follows_each_stages_estimate() -> None:
    xs, us = _guess()
    stage = stage_parameters(xs, us, lambda s: 0.0 * s, _mu_step, TRUCK, LAMBDA, AUTHORS_TIRES)
    mu = stage.mu_hat
    assert set(np.unique(mu)) == {0.4, 0.8}
    for value, b, c in ((0.8, 12.0, 2.3), (0.4, 5.0, 2.0)):
        at = mu == value
        factor = secant_stiffness_factor(tire_for_surface(value, TRUCK.tire, AUTHORS_TIRES),
                                         LAMBDA)
        np.testing.assert_allclose(stage.rear_stiffness_n_per_rad[at],
                                   b * c * value * factor * stage.fzr_n[at], rtol=1e-12)
    # On the snow stages the authors' planner assumes a rear tire 5.5 times softer.
    stiffness = stage.rear_stiffness_n_per_rad
    ratio = stiffness[mu == 0.8][0] / stiffness[mu == 0.4][0]
    assert ratio == pytest.approx(22.08 * 0.6688 / (4.0 * 0.6214), rel=1e-3)


@pytest.mark.parametrize("mu", [0.2, 0.5, 0.6, 0.7])
def test_interpolated_secant_factor_is_within_half_a_percent_of_the_blended_curves(mu) -> None:
    exact = secant_stiffness_factor(tire_for_surface(mu, TRUCK.tire, AUTHORS_TIRES_INTERPOLATED),
                                    LAMBDA)
    tangent = surface_stiffness_per_load(mu, TRUCK.tire, AUTHORS_TIRES_INTERPOLATED)
    secant = surface_stiffness_per_load(mu, TRUCK.tire, AUTHORS_TIRES_INTERPOLATED, LAMBDA)
    assert float(secant / tangent) == pytest.approx(exact, rel=5e-3)


def test_sampling_rollouts_use_the_same_stiffness_as_the_ocp() -> None:
    x0 = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    args = (x0, np.array([0.0, 0.5]), np.array([15.0]), lambda s: 0.02 + 0.0 * s, _mu_step, TRUCK,
            LAMBDA, N, 0.1, SamplingConfig())
    fixed_x, _ = candidate_rollouts(*args)
    again_x, _ = candidate_rollouts(*args, stiffness_table=None)
    soft_x, _ = candidate_rollouts(*args, stiffness_table=AUTHORS_TIRES)
    np.testing.assert_array_equal(fixed_x, again_x)
    # A different rear tire in the model gives a different predicted body motion.
    assert not np.allclose(fixed_x[:, State.vy], soft_x[:, State.vy])


def _plan(fyf: float, mu_hat: float) -> Plan:
    n = N
    states = np.zeros((n + 1, 6))
    states[:, State.vx] = 15.0
    states[:, State.s] = 1.5 * np.arange(n + 1)
    inputs = np.tile([fyf, 0.0, 0.0], (n, 1)).astype(float)
    ones = np.ones(n)
    return Plan(0.0, states, inputs, 0 * ones, mu_hat * ones, 5e4 * ones, 3e4 * ones,
                3.6e4 * ones, 2.2e4 * ones, 0, True, False, 0.0)


@pytest.mark.parametrize("mu_hat", [0.4, 0.8])
def test_controller_inverts_the_tire_the_planner_assumes(mu_hat) -> None:
    force = 0.5 * mu_hat * 5e4
    soft = PlannerConfig(stiffness="from_mu_hat", stiffness_table=AUTHORS_TIRES)
    steer = {}
    for config in (PlannerConfig(), soft):
        ctrl = TrackingController(TRUCK, config)
        x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
        angle = 0.0
        for _ in range(100):  # rate-limited steps converge on the feed-forward angle
            angle = ctrl.command(0.0, x, angle, _plan(force, mu_hat), 0.0).steer_rad
        steer[config.stiffness] = angle
    # Straight, no yaw: the steering angle is the slip angle the inverse tire model gives.
    alpha = front_slip_angle_for_force_rad(force, 5e4, mu_hat,
                                           tire_for_surface(mu_hat, TRUCK.tire, AUTHORS_TIRES))
    assert steer["from_mu_hat"] == pytest.approx(alpha, rel=1e-6)
    assert float(lateral_force_n(alpha, 5e4, mu_hat, AUTHORS_TIRES)) == pytest.approx(
        force, rel=1e-2)
    # Softer than the default tire on snow (4 vs 7 /rad): more steering; stiffer on 0.8.
    default_alpha = front_slip_angle_for_force_rad(force, 5e4, mu_hat, TRUCK.tire)
    assert steer["fixed"] == pytest.approx(default_alpha, rel=1e-6)
    assert (steer["from_mu_hat"] > steer["fixed"]) == (mu_hat == 0.4)


def test_scenario_keys_select_plant_tires_and_planner_stiffness() -> None:
    cfg = load_scenario("turn", ["sim.tires=authors", "planner.stiffness=from_mu_hat"])
    assert cfg.sim.surface_tires() is AUTHORS_TIRES
    pc = planner_config(cfg, TRUCK)
    assert pc.stiffness == "from_mu_hat" and pc.stiffness_table is AUTHORS_TIRES
    cfg = load_scenario("turn", ["sim.tires=authors_interpolated"])
    assert cfg.sim.surface_tires() is AUTHORS_TIRES_INTERPOLATED
    assert planner_config(cfg, TRUCK).stiffness_table is None
    assert load_scenario("turn").sim.surface_tires() is None
    with pytest.raises(ValueError, match=r"sim\.tires"):
        load_scenario("popup", ["planner.stiffness=from_mu_hat"])
