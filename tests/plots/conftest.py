"""Synthetic run logs that follow the log schema exactly, for the figure and report tests.

Two roads: ``turn`` (straight, then a 90° right turn of radius 30 m, then straight; low μ from
the turn on) and ``popup`` (straight, an obstacle in the ego lane appearing at t = 0.5 s).
The motion is plausible, not simulated: constant deceleration, a smooth lateral manoeuvre.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from mufusion.configurations import Configuration
from mufusion.plots._common import footprint_xy
from mufusion.sim.log import RunLog, load_run
from mufusion.sim.records import (
    EstimateGrid,
    LoopRatesMeta,
    ObstacleTrace,
    PlannerSettings,
    PlanningStep,
    PlanStages,
    RoadTrace,
    RunMeta,
    StepTiming,
    Tick,
    VehicleGeometry,
)

LANE_WIDTH_M = 3.5
START_S_M = 20.0
LENGTH_M, WIDTH_M = 4.5, 1.8
STAGES = 20
STAGE_DT_S = 0.1
LAMBDA = 0.9


def _road(name: str) -> dict:
    s = np.arange(0.0, 160.0 + 1e-9, 0.5)
    curvature = np.zeros_like(s)
    if name == "turn":
        radius = 30.0
        arc = (s >= 60.0) & (s < 60.0 + radius * np.pi / 2)
        curvature[arc] = -1.0 / radius  # right turn
    psi = np.concatenate([[0.0], np.cumsum(curvature[:-1] * np.diff(s))])
    x = np.concatenate([[0.0], np.cumsum(np.cos(psi[:-1]) * np.diff(s))])
    y = np.concatenate([[0.0], np.cumsum(np.sin(psi[:-1]) * np.diff(s))])
    return {"s_m": s, "x_m": x, "y_m": y, "psi_rad": psi, "curvature_1pm": curvature}


def _friction(name: str, road: dict) -> dict:
    s = road["s_m"]
    mu = np.where(s >= 55.0, 0.3, 0.8) if name == "turn" else np.full_like(s, 1.0)
    return {"s_m": s, "mu": mu}


def _cartesian(road: dict, s_m: np.ndarray, d_m: np.ndarray) -> tuple[np.ndarray, ...]:
    x = np.interp(s_m, road["s_m"], road["x_m"])
    y = np.interp(s_m, road["s_m"], road["y_m"])
    psi = np.interp(s_m, road["s_m"], road["psi_rad"])
    return x - d_m * np.sin(psi), y + d_m * np.cos(psi), psi


def _lateral(name: str, config: str, s_rel: np.ndarray) -> np.ndarray:
    """A smooth lateral manoeuvre per scenario/configuration [m]."""
    if name == "turn":
        if config == "L":  # slides into the opposing lane in the turn, then recovers
            return 3.0 * np.exp(-(((s_rel - 60.0) / 15.0) ** 2))
        return -0.8 * np.sin(np.clip((s_rel - 20.0) / 60.0, 0.0, 1.0) * 2 * np.pi)
    if config == "P":
        return 1.0 * np.clip((s_rel - 5.0) / 20.0, 0.0, 1.0)
    return 2.6 * np.exp(-(((s_rel - 30.0) / 12.0) ** 2))


def make_meta(name: str = "turn", config: str = "F", width_m: float = WIDTH_M,
              lane_width_m: float = LANE_WIDTH_M, comparison_time_s: float | None = None,
              vehicle: str = "car", duration_s: float = 4.0) -> RunMeta:
    """Metadata of a synthetic run on road ``name`` ("turn" | "popup")."""
    road = _road(name)
    friction = _friction(name, road)
    obstacles = []
    if name == "popup":
        o_s, o_d, o_len, o_wid = START_S_M + 30.0, 0.0, 4.0, 2.0
        ox, oy, opsi = _cartesian(road, np.array([o_s]), np.array([o_d]))
        corners = footprint_xy(ox[0], oy[0], opsi[0], o_len, o_wid)
        obstacles.append(ObstacleTrace(
            s_m=o_s, d_m=o_d, length_m=o_len, width_m=o_wid, appear_time_s=0.5,
            corners_x_m=corners[:, 0].tolist(), corners_y_m=corners[:, 1].tolist()))
    return RunMeta(
        scenario_name=name,
        configuration=Configuration.parse(config),
        seed=0,
        scenario_config={"name": name, "initial_speed_mps": 20.0},
        vehicle=VehicleGeometry(name=vehicle, length_m=LENGTH_M, width_m=width_m,
                                wheelbase_m=2.6, cog_to_front_axle_m=1.2, cog_to_rear_axle_m=1.4),
        road=RoadTrace(s_m=road["s_m"].tolist(), x_m=road["x_m"].tolist(),
                       y_m=road["y_m"].tolist(), psi_rad=road["psi_rad"].tolist(),
                       curvature_1pm=road["curvature_1pm"].tolist(),
                       mu=friction["mu"].tolist(), lane_width_m=lane_width_m),
        obstacles=obstacles,
        planner=PlannerSettings(horizon_steps=STAGES, dt_s=STAGE_DT_S, utilization_factor=LAMBDA,
                                polygon_sides=12, obstacle_margin_m=0.5, lane_d_min_m=-0.75,
                                lane_d_max_m=0.75, backend="acados", use_sampling=True),
        rates=LoopRatesMeta(plant_hz=200.0, controller_hz=50.0, planner_hz=10.0),
        start_s_m=START_S_M,
        start_heading_rad=0.0,
        comparison_time_s=(0.0 if name == "turn" else 0.5) if comparison_time_s is None
        else comparison_time_s,
        duration_s=duration_s,
    )


def make_log(name: str = "turn", config: str = "F", duration_s: float = 4.0,
             collision_at_s: float | None = None) -> RunLog:
    """A synthetic run log of scenario ``name`` ("turn" | "popup") and configuration ``config``."""
    road = _road(name)
    friction = _friction(name, road)
    meta = make_meta(name, config, duration_s=duration_s)
    obstacles = meta.obstacles
    log = RunLog(meta)

    t = np.arange(0.0, duration_s + 1e-9, 0.02)
    speed = 20.0 - 2.0 * t
    s = START_S_M + 20.0 * t - t**2
    d = _lateral(name, config, s - START_S_M)
    x, y, psi = _cartesian(road, s, d)
    w = LANE_WIDTH_M
    collided = np.zeros(t.size, bool)
    if collision_at_s is not None:
        collided = s - START_S_M >= collision_at_s
    clearance = np.full(t.size, np.nan)
    if obstacles:
        clearance = np.where(t >= 0.5, np.abs(s - obstacles[0].s_m), np.nan)
    mu_true = np.interp(s, friction["s_m"], friction["mu"])
    for i in range(t.size):
        log.append(Tick(
            t_s=t[i], x_m=x[i], y_m=y[i], psi_rad=psi[i], vx_mps=speed[i], vy_mps=0.0,
            psidot_radps=0.0, speed_mps=speed[i], s_m=s[i], d_m=d[i], dpsi_rad=0.0,
            body_slip_rad=0.0, steer_rad=0.0, steer_cmd_rad=0.0, torque_front_nm=0.0,
            torque_rear_nm=0.0, torque_front_cmd_nm=0.0, torque_rear_cmd_nm=0.0, util_front=0.3,
            util_rear=0.2, mu_front=mu_true[i],
            mu_rear=mu_true[i], local_available=False, control_mode="plan",
            obstacle_active=bool(obstacles) and t[i] >= 0.5, clearance_m=clearance[i],
            in_collision=bool(collided[i]),
            passed_obstacle=bool(obstacles) and s[i] > obstacles[0].s_m,
            left_lane=bool(abs(d[i]) > w / 2 - WIDTH_M / 2), in_opposing_lane=bool(d[i] > w / 2),
            lane_margin_m=w / 2 - WIDTH_M / 2 - abs(d[i]),
            lane_excursion_m=max(0.0, abs(d[i]) - (w / 2 - WIDTH_M / 2)),
            opposing_depth_m=max(0.0, d[i] + WIDTH_M / 2 - w / 2), road_margin_m=1.0,
            off_road=False,
        ))

    mu_hat_level = {"GT": None, "L": 0.8, "P": 0.55, "F": 0.7, "F-safe": 0.6}.get(config, 0.7)
    k = np.arange(STAGES)
    grid = np.arange(0.0, 51.0)
    fused = config in ("F", "F-safe")
    for step, t0 in enumerate(np.arange(0.0, duration_s + 1e-9, 0.1)):
        i0 = int(np.argmin(np.abs(t - t0)))
        s_k = s[i0] + speed[i0] * k * STAGE_DT_S
        d_k = _lateral(name, config, s_k - START_S_M)
        x_k, y_k, _ = _cartesian(road, s_k, d_k)
        mu_true_k = np.interp(s_k, friction["s_m"], friction["mu"])
        mu_hat_k = mu_true_k if mu_hat_level is None else np.minimum(mu_true_k, mu_hat_level)
        fzf = np.full(STAGES, 8000.0)
        limit = LAMBDA * mu_hat_k * fzf
        angle = np.linspace(0.0, -2.0, STAGES)
        full = np.full(STAGES, 0.0)
        log.append(PlanStages(
            step=step, t_s=t0, k=k, t_k_s=t0 + k * STAGE_DT_S, s_m=s_k, d_m=d_k, dpsi_rad=full,
            psidot_radps=full, vx_mps=np.full(STAGES, speed[i0]), vy_mps=full, x_m=x_k, y_m=y_k,
            fyf_n=0.8 * limit * np.cos(angle), fxf_n=0.8 * limit * np.sin(angle), fxr_n=full,
            fyr_n=full, fzf_n=fzf, fzr_n=np.full(STAGES, 7000.0), limit_front_n=limit,
            limit_rear_n=limit, mu_hat=mu_hat_k, mu_true=mu_true_k,
        ))
        log.append(PlanningStep(
            step=step, t_s=t0, s_m=s[i0], mode="cruise", status=0, ok=True, fallback=False,
            fallback_reason="", sampled_reinit=False, robust_qp_retry=False, local_available=False,
            local_mu=np.nan, estimate_source="current", estimate_age_s=0.0,
        ))
        log.append(StepTiming(step=step, t_s=t0, solve_ms=5.0, step_ms=6.0))
        mu_grid = np.interp(s[i0] + grid, friction["s_m"], friction["mu"])
        mean = np.clip(mu_grid - 0.05, 0.1, None)
        std = 0.05 + 0.003 * grid
        data_mu = np.where(grid % 10 == 0, mu_grid - 0.1, np.nan)
        nan = np.full(grid.size, np.nan)
        log.append(EstimateGrid(
            step=step, t_s=t0, s_ahead_m=grid, s_m=s[i0] + grid, mu_true=mu_grid,
            mu_hat=mean - 1.96 * std if fused else np.minimum(mu_grid, mu_hat_level or 9),
            mean=mean if fused else nan, std=std if fused else nan,
            lower=mean - 1.96 * std if fused else nan, data_mu=data_mu,
            data_margin=np.where(np.isfinite(data_mu), 0.15, np.nan),
        ))
    return log


@pytest.fixture
def saved_log(tmp_path: Path) -> Callable[..., RunLog]:
    """Build a synthetic log, save it with RunLog.save and read it back (the real path)."""
    counter = iter(range(10_000))

    def _make(name: str = "turn", config: str = "F", **kwargs) -> RunLog:
        directory = make_log(name, config, **kwargs).save(tmp_path / f"run{next(counter)}")
        return load_run(directory)

    return _make
