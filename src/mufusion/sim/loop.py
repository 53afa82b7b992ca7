"""The closed loop: plant, controller interface, planner and friction estimation at their own rates.

Each component exposes one step-like call, so one tick of the loop reads in a few lines
(do-mpc's ``u = mpc.make_step(x); y = sim.make_step(u)``): the planner runs every
``plant_hz / planner_hz`` plant steps with the current friction estimate, the controller every
``plant_hz / controller_hz`` steps, the plant every step with the true friction under each axle.
Everything a metric or a figure needs is appended to one :class:`~mufusion.sim.log.RunLog`.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from mufusion.sim.log import RunLog
from mufusion.sim.world import World
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State
from mufusion.vehicle.plant import PlantOutput, PlantState

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class LoopRates:
    """Rates of the loop's components [Hz]; the plant rate must be a multiple of the others."""

    plant_hz: float = 200.0
    controller_hz: float = 50.0
    planner_hz: float = 10.0

    def __post_init__(self) -> None:
        for name in ("plant_hz", "controller_hz", "planner_hz"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"{name} must be a positive rate in Hz, got {value!r}")
        for name in ("controller_hz", "planner_hz"):
            ratio = self.plant_hz / getattr(self, name)
            if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
                raise ValueError(
                    f"{name} must divide plant_hz={self.plant_hz} into whole steps, "
                    f"got {getattr(self, name)}"
                )

        ratio = self.controller_hz / self.planner_hz
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"planner_hz must divide controller_hz={self.controller_hz} into whole steps, "
                f"got {self.planner_hz}"
            )

    @property
    def controller_every(self) -> int:
        return round(self.plant_hz / self.controller_hz)

    @property
    def planner_every(self) -> int:
        return round(self.plant_hz / self.planner_hz)


class FrictionSource(Protocol):
    def step(self, s_ahead_m: np.ndarray, mu_true_ahead: np.ndarray, utilization: float) -> Any: ...


class Planner(Protocol):
    def step(self, x0: np.ndarray, t_s: float, **kwargs: Any) -> Any: ...


class Controller(Protocol):
    def command(
        self, t_s: float, x_frenet: np.ndarray, steer_rad_now: float, plan: Any, curvature: float
    ) -> ActuatorCommand: ...


@dataclass
class ClosedLoop:
    """One closed-loop run's state: the clock, the components and the log.

    Parameters
    ----------
    world
        Road, lanes, true friction and obstacles.
    params
        Vehicle parameters (for the footprint and the plant).
    plant, planner, controller, friction
        The components; see the module docstring for their calls.
    rates
        Component rates.
    reference_speed_mps
        Cruise speed the planner tracks.
    lane_bounds_m
        ``(d_min, d_max)`` the planner's reference point must stay within (lane or road).
    estimate_grid_m
        Distances ahead at which friction is estimated [m] (paper: 0, 1, …, 50).
    emergency_on_obstacle
        Switch the planner to its emergency (stop) mode once an obstacle is active.
    meta
        Extra metadata for the log.
    """

    world: World
    params: VehicleParams
    plant: Any
    planner: Planner
    controller: Controller
    friction: FrictionSource
    rates: LoopRates
    reference_speed_mps: float
    lane_bounds_m: tuple[float, float]
    estimate_grid_m: np.ndarray = field(default_factory=lambda: np.arange(0.0, 51.0, 1.0))
    emergency_on_obstacle: bool = False
    meta: dict[str, Any] = field(default_factory=dict)

    def run(
        self,
        duration_s: float,
        progress: Callable[[float], None] | None = None,
        warmup_steps: int = 0,
    ) -> RunLog:
        """Simulate ``duration_s`` seconds (or until a collision or the end of the road).

        ``progress`` is called with the simulated time after every planning step. Before the
        clock starts, the planner makes ``warmup_steps`` plans at the initial state without
        obstacles (and without logging), as if it had been cruising there: its warm start.

        Raises
        ------
        ValueError
            If ``duration_s`` is not a positive finite number.
        """
        if not np.isfinite(duration_s) or duration_s <= 0:
            raise ValueError(f"duration_s must be > 0, got {duration_s!r}")
        rates = self.rates
        dt = 1.0 / rates.plant_hz
        n_steps = round(duration_s * rates.plant_hz)
        log = RunLog(meta=dict(self.meta))
        plan = None
        command = ActuatorCommand(0.0, 0.0, 0.0)
        plan_step = -1
        util_window = 0.0
        local_available = False
        last: PlantOutput | None = None
        road_end = self.world.road_length_m - self.params.length_m
        self._warm_up(warmup_steps)

        for i in range(n_steps + 1):
            t = i * dt
            x_plant = self.plant.x
            if i % rates.controller_every == 0:
                # The planner's rate divides the controller's, so this also serves planning steps.
                xf = self.world.frenet_state(x_plant)
                s_ego = float(xf[State.s])

            if i % rates.planner_every == 0:
                plan_step += 1
                estimate = self._estimate(s_ego, util_window)
                util_window = 0.0
                local_available = bool(getattr(estimate, "local_available", False))
                plan = self._plan(t, xf, estimate, plan_step, log)
                if progress:
                    progress(t)

            if i % rates.controller_every == 0:
                steer_now = float(x_plant[PlantState.STEER])
                command = self.controller.command(
                    t, xf, steer_now, plan, float(self.world.curvature(np.array([s_ego]))[0])
                ).clipped(self.params)
                collided = self._log_tick(log, t, x_plant, xf, command, local_available, last)
                if collided or s_ego >= road_end:
                    break

            mu_front, mu_rear = self.world.friction_under_axles(x_plant, self.params)
            last = self.plant.step(command, mu_front, mu_rear)
            util_window = max(util_window, last.utilization_front, last.utilization_rear)
        return log

    def _warm_up(self, steps: int) -> None:
        xf = self.world.frenet_state(self.plant.x)
        s_ego = float(xf[State.s])
        grid_abs = s_ego + self.estimate_grid_m
        estimate = self._estimate(s_ego, 0.0)
        mu_hat_grid = np.asarray(estimate.mu_hat, dtype=float)
        for k in range(steps):
            self.planner.step(
                xf,
                -(steps - k) / self.rates.planner_hz,
                curvature_of_s=self.world.curvature,
                mu_hat_of_s=lambda s: np.interp(np.asarray(s, float), grid_abs, mu_hat_grid),
                obstacles=[],
                mode="cruise",
                reference_speed_mps=self.reference_speed_mps,
                reference_d_m=0.0,
                lane_d_min_m=self.lane_bounds_m[0],
                lane_d_max_m=self.lane_bounds_m[1],
            )

    # -- one planning step ------------------------------------------------------------------
    def _estimate(self, s_ego: float, utilization: float) -> Any:
        s_abs = s_ego + self.estimate_grid_m
        mu_true = self.world.friction(s_abs)
        return self.friction.step(self.estimate_grid_m, mu_true, utilization)

    def _plan(self, t: float, xf: np.ndarray, estimate: Any, step: int, log: RunLog) -> Any:
        s_ego = float(xf[State.s])
        grid_abs = s_ego + self.estimate_grid_m
        mu_hat_grid = np.asarray(estimate.mu_hat, dtype=float)

        def mu_hat_of_s(s: np.ndarray) -> np.ndarray:
            # Beyond the camera's range the last estimate is held (TAMP framework).
            return np.interp(np.asarray(s, dtype=float), grid_abs, mu_hat_grid)

        obstacles = self.world.planner_obstacles(t, s_ego, behind_m=self.params.length_m)
        mode = ("emergency" if self.emergency_on_obstacle else "evade") if obstacles else "cruise"
        started = time.perf_counter()
        plan = self.planner.step(
            xf,
            t,
            curvature_of_s=self.world.curvature,
            mu_hat_of_s=mu_hat_of_s,
            obstacles=obstacles,
            mode=mode,
            reference_speed_mps=self.reference_speed_mps,
            reference_d_m=0.0,
            lane_d_min_m=self.lane_bounds_m[0],
            lane_d_max_m=self.lane_bounds_m[1],
        )
        step_ms = 1e3 * (time.perf_counter() - started)
        if not plan.ok:
            _log.warning("planning step %d at t=%.2f s: solver status %s", step, t, plan.status)
        self._log_plan(log, step, t, plan, estimate, mode, step_ms, grid_abs)
        return plan

    # -- logging ----------------------------------------------------------------------------
    def _log_plan(
        self,
        log: RunLog,
        step: int,
        t: float,
        plan: Any,
        estimate: Any,
        mode: str,
        step_ms: float,
        grid_abs: np.ndarray,
    ) -> None:
        local_mu = getattr(estimate, "local_mu", None)
        log.append(
            "planning_steps",
            {
                "step": step,
                "t_s": t,
                "s_m": float(grid_abs[0]),
                "mode": mode,
                "status": int(plan.status),
                "ok": bool(plan.ok),
                "fallback": bool(plan.fallback),
                "sampled_reinit": bool(plan.sampled_reinit),
                "local_available": bool(getattr(estimate, "local_available", False)),
                "local_mu": np.nan if local_mu is None else float(local_mu),
            },
        )
        log.append(
            "timing",
            {"step": step, "t_s": t, "solve_ms": 1e3 * plan.solve_time_s, "step_ms": step_ms},
        )
        states = np.asarray(plan.states)[:-1]
        n = states.shape[0]
        s_k, d_k = states[:, State.s], states[:, State.d]
        x_k, y_k = self.world.to_cartesian(s_k, d_k)
        inputs = np.asarray(plan.inputs)
        log.append_block(
            "plans",
            {
                "step": np.full(n, step),
                "t_s": np.full(n, t),
                "k": np.arange(n),
                "t_k_s": t + np.arange(n) * float(self.meta.get("planner_dt_s", 0.1)),
                "s_m": s_k,
                "d_m": d_k,
                "dpsi_rad": states[:, State.dpsi],
                "psidot_radps": states[:, State.psidot],
                "vx_mps": states[:, State.vx],
                "vy_mps": states[:, State.vy],
                "x_m": x_k,
                "y_m": y_k,
                "fyf_n": inputs[:, 0],
                "fxf_n": inputs[:, 1],
                "fxr_n": inputs[:, 2],
                "fyr_n": np.asarray(plan.rear_lateral_force_n),
                "fzf_n": np.asarray(plan.normal_load_front_n),
                "fzr_n": np.asarray(plan.normal_load_rear_n),
                "limit_front_n": np.asarray(plan.force_limit_front_n),
                "limit_rear_n": np.asarray(plan.force_limit_rear_n),
                "mu_hat": np.asarray(plan.mu_hat),
                "mu_true": self.world.friction(s_k),
            },
        )
        fused = getattr(estimate, "fused", None)
        n_grid = grid_abs.size
        nan = np.full(n_grid, np.nan)
        data_mu, data_margin = _data_on_grid(estimate, self.estimate_grid_m)
        log.append_block(
            "estimates",
            {
                "step": np.full(n_grid, step),
                "t_s": np.full(n_grid, t),
                "s_ahead_m": self.estimate_grid_m,
                "s_m": grid_abs,
                "mu_true": self.world.friction(grid_abs),
                "mu_hat": np.asarray(estimate.mu_hat, dtype=float),
                "mean": nan if fused is None else np.asarray(fused.mean),
                "std": nan if fused is None else np.asarray(fused.std),
                "lower": nan if fused is None else np.asarray(fused.lower),
                "data_mu": data_mu,
                "data_margin": data_margin,
            },
        )

    def _log_tick(
        self,
        log: RunLog,
        t: float,
        x_plant: np.ndarray,
        xf: np.ndarray,
        command: ActuatorCommand,
        local_available: bool,
        last: PlantOutput | None,
    ) -> bool:
        pose = self.world.pose(x_plant)
        status = self.world.footprint_status(pose, t, float(xf[State.s]), self.params)
        log.append(
            "timeseries",
            {
                "t_s": t,
                "x_m": pose[0],
                "y_m": pose[1],
                "psi_rad": pose[2],
                "vx_mps": float(xf[State.vx]),
                "vy_mps": float(xf[State.vy]),
                "psidot_radps": float(xf[State.psidot]),
                "speed_mps": float(np.hypot(xf[State.vx], xf[State.vy])),
                "s_m": float(xf[State.s]),
                "d_m": float(xf[State.d]),
                "dpsi_rad": float(xf[State.dpsi]),
                "steer_rad": float(x_plant[PlantState.STEER]),
                "steer_cmd_rad": command.steer_rad,
                "torque_front_nm": command.torque_front_nm,
                "torque_rear_nm": command.torque_rear_nm,
                "util_front": np.nan if last is None else float(last.utilization_front),
                "util_rear": np.nan if last is None else float(last.utilization_rear),
                "mu_front": status.mu_front,
                "mu_rear": status.mu_rear,
                "local_available": local_available,
                "obstacle_active": status.obstacle_active,
                "clearance_m": status.clearance_m,
                "in_collision": status.in_collision,
                "passed_obstacle": status.passed_obstacle,
                "left_lane": status.left_lane,
                "in_opposing_lane": status.in_opposing_lane,
            },
        )
        return status.in_collision


def _data_on_grid(estimate: Any, grid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fusion input data (value, margin) placed on the estimate grid, NaN where there is none."""
    data_mu = np.full(grid.size, np.nan)
    data_margin = np.full(grid.size, np.nan)
    data = getattr(estimate, "data", None)
    if data is None:
        return data_mu, data_margin
    idx = np.clip(np.searchsorted(grid, np.asarray(data.s_m)), 0, grid.size - 1)
    data_mu[idx] = np.asarray(data.mu)
    data_margin[idx] = np.asarray(data.margin)
    return data_mu, data_margin
