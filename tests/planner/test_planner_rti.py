"""Planner: friction polygons respected, lanes respected, failures fall back without raising."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.controller import stage_commands_n
from mufusion.planner.ocp import PlannerConfig, polygon_directions
from mufusion.planner.planner import FallbackReason, Plan, TractionAdaptivePlanner
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import Input

CONFIG = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=0.45)


@pytest.fixture(scope="session")
def planner() -> TractionAdaptivePlanner:
    return TractionAdaptivePlanner(TRUCK, CONFIG)


def _closed_loop(planner, kappa: float, mu: float, steps: int = 30,
                 curve_from_m: float = 0.0) -> list[Plan]:
    planner.reset()
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    plans = []
    for i in range(steps):
        plan = planner.step(x, 0.1 * i, lambda s: np.where(s >= curve_from_m, kappa, 0.0),
                            lambda s: mu + 0 * s, [], "cruise", 15.0)
        plans.append(plan)
        x = plan.states[1]
    return plans


def _inside(force_x, force_y, radius, n_sides, tol=1e-3):
    normals, ratio = polygon_directions(n_sides)
    lhs = normals @ np.stack([force_x, force_y])
    return np.all(lhs <= (ratio + tol) * radius)


@pytest.fixture(scope="session")
def free_force_planner() -> TractionAdaptivePlanner:
    """The paper's planner: the forces free inputs (no steering-rate limit, no torque lag), the
    polygons at the static axle loads and the cruise speed tracked, without the curve speed
    reference and the body's fit it carries (the paper's method, which ``reproduce`` uses)."""
    return TractionAdaptivePlanner(TRUCK, PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=0.45,
                                                        steering_rate_limit=False,
                                                        load_transfer=False,
                                                        torque_lag=False,
                                                        curve_speed_reference=False))


# Starting inside the curve with no yaw rate needs the front force at once: the free-force
# planner has it, the rate-limited one builds it over a stage and its plans then exceed the
# (soft) rear polygon by up to 15 % while they catch up (measured); a steering that cannot jump
# meets a curve from a straight, so the rate-limited case starts 15 m before the curve.
@pytest.mark.parametrize(("which", "kappa", "curve_from_m"), [
    ("free", 0.0, 0.0), ("free", 1.0 / 60.0, 0.0),
    ("rate_limited", 0.0, 0.0), ("rate_limited", 1.0 / 60.0, 15.0),
])
def test_forces_inside_polygons_and_lane_kept(planner, free_force_planner, which, kappa,
                                              curve_from_m):
    plans = _closed_loop(free_force_planner if which == "free" else planner, kappa, mu=0.5,
                         curve_from_m=curve_from_m)
    for plan in plans:
        assert plan.ok
        u = plan.inputs
        assert _inside(u[:, Input.fxf], u[:, Input.fyf], plan.force_limit_front_n, 12)
        assert _inside(u[:, Input.fxr], plan.rear_lateral_force_n, plan.force_limit_rear_n, 12,
                       tol=2e-2)
        half_w = 0.5 * TRUCK.width_m
        assert np.all(np.abs(plan.states[:, 1]) <= 1.75 - half_w + 0.05)


def test_injected_failure_falls_back_and_loop_continues(planner, monkeypatch, caplog):
    _closed_loop(planner, 0.0, 0.9, steps=3)
    before = planner.failures

    def broken(*args, **kwargs):
        raise RuntimeError("injected")

    monkeypatch.setattr(planner.backend, "solve", broken)
    x = planner.last_plan.states[1]
    plan = planner.step(x, 0.3, lambda s: 0 * s, lambda s: 0.9 + 0 * s, [], "cruise", 15.0)
    assert plan.fallback and not plan.ok
    assert plan.fallback_reason is FallbackReason.EXCEPTION
    assert planner.failures == before + 1
    assert np.all(np.isfinite(plan.states))
    assert "failed" in caplog.text


def test_acados_unavailable_falls_back_to_casadi_with_warning(monkeypatch, caplog):
    import mufusion.planner.acados_backend as acados_backend
    from mufusion.planner.acados_loader import AcadosUnavailable
    from mufusion.planner.casadi_backend import CasadiBackend

    def missing():
        raise AcadosUnavailable("no wheel")

    monkeypatch.setattr(acados_backend, "load_acados_template", missing)
    planner = TractionAdaptivePlanner(TRUCK, PlannerConfig(horizon_steps=10))
    assert isinstance(planner.backend, CasadiBackend)
    assert "falling back" in caplog.text
    plan = planner.step(np.array([0.0, 0.0, 0.0, 0.0, 10.0, 0.0]), 0.0, lambda s: 0 * s,
                        lambda s: 0.8 + 0 * s, [], "cruise", 10.0)
    assert plan.ok and plan.states.shape == (11, 6)


def test_emergency_mode_stops_about_as_short_as_friction_allows(planner):
    planner.reset()
    x = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])
    mu = 0.8
    for i in range(40):
        plan = planner.step(x, 0.1 * i, lambda s: 0 * s, lambda s: mu + 0 * s, [], "emergency",
                            15.0)
        x = plan.states[1]
        if x[4] < 0.1:
            break
    # Braking distance v²/(2 λ μ g) at the polygon's inscribed radius; RTI within 25 %.
    ideal = 15.0**2 / (2 * 0.9 * np.cos(np.pi / 12) * mu * 9.81)
    assert x[0] < 1.25 * ideal
    assert x[0] > 0.9 * 15.0**2 / (2 * mu * 9.81)


def test_config_rejects_bad_values():
    with pytest.raises(ValueError, match="polygon_sides"):
        PlannerConfig(polygon_sides=8)
    with pytest.raises(ValueError, match="utilization_factor"):
        PlannerConfig(utilization_factor=1.5)
    with pytest.raises(ValueError, match="reference_braking_fraction"):
        PlannerConfig(reference_braking_fraction=0.0)


def test_evade_mode_spends_no_friction_on_traction_and_does_not_speed_up(planner):
    planner.reset()
    x = np.array([0.0, 0.0, 0.0, 0.0, 18.0, 0.0])
    obstacle = [(30.0, 0.0, 1.0, 1.0)]
    plan = planner.step(x, 0.0, lambda s: 0 * s, lambda s: 0.9 + 0 * s, obstacle, "evade", 20.0,
                        lane_d_min_m=-0.45, lane_d_max_m=4.0)
    assert plan.ok
    assert np.all(plan.inputs[:, Input.fxr] <= 1.0)
    assert np.all(plan.states[:, 4] <= 18.0 + 0.05)
    with pytest.raises(ValueError, match="mode"):
        planner.step(x, 0.0, lambda s: 0 * s, lambda s: 0.9 + 0 * s, [], "sprint", 20.0)


def test_emergency_stop_in_front_of_an_obstacle_beside_the_lane_centre():
    # Pop-up, truck at 14 m/s on μ 1: an obstacle 20.6 m ahead, 1.5 m left of the lane centre
    # (in the path: the truck needs 1.75 m beside it). The stop fits (≈ 15 m), so the loop asks
    # for "emergency". The corridor used to open the obstacle's left side along the cruise guess
    # (which runs past it), the stopping plan swerved into it, exceeded the rear polygon and was
    # rejected three times in a row: no braking, then a late swerve.
    planner = TractionAdaptivePlanner(TRUCK, PlannerConfig())
    flat, grip = (lambda s: 0.0 * np.asarray(s)), (lambda s: 1.0 + 0.0 * np.asarray(s))
    x = np.array([60.0, 0.0, 0.0, 0.0, 14.0, 0.0])
    for k in range(10):  # the warm start, as the loop makes it
        planner.step(x, -1.0 + 0.1 * k, flat, grip, [], "cruise", 14.0,
                     lane_d_min_m=-0.35, lane_d_max_m=3.85)
    obstacle = (80.6, 1.5, 1.0, 1.0)
    for k in range(3):
        plan = planner.step(x, 0.1 * k, flat, grip, [obstacle], "emergency", 14.0,
                            lane_d_min_m=-0.35, lane_d_max_m=3.85)
        assert plan.ok, plan.fallback_reason
        # The forces follow the torques' lag (decision 0068): the first stage's commands brake.
        commands = stage_commands_n(plan, 0, TRUCK.torque_time_constant_s)
        decel = -sum(commands) / TRUCK.mass_kg
        assert decel > 0.5 * 9.81  # braking hard from the first plan on
        assert np.abs(plan.states[:, 1]).max() < 0.1  # in lane: no swerve towards the gap
        x = plan.states[1]
