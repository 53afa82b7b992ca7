"""The recorder: turns what the closed loop saw and decided into the log's typed records.

The loop steps the world and hands the recorder its quantities; everything about columns,
Cartesian conversions and the footprint's status lives here, so the loop reads as the loop.
"""

from __future__ import annotations

import math

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner import Plan
from mufusion.sim.events import EventKind
from mufusion.sim.log import RunLog, finite_or_nan
from mufusion.sim.records import (
    EstimateGrid,
    Event,
    PlanningStep,
    PlanStages,
    StepTiming,
    Tick,
)
from mufusion.sim.world import FootprintStatus, World
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import Input, State
from mufusion.vehicle.plant import PlantOutput, PlantState


class Recorder:
    """Writes one run's records into a :class:`~mufusion.sim.log.RunLog`.

    Parameters
    ----------
    log
        The log to append to.
    world
        Road, friction and obstacles (for Cartesian positions, true μ and the footprint).
    params
        Vehicle parameters (footprint).
    estimate_grid_m
        Distances ahead at which friction is estimated [m].
    """

    def __init__(
        self, log: RunLog, world: World, params: VehicleParams, estimate_grid_m: np.ndarray
    ) -> None:
        self.log = log
        self.world = world
        self.params = params
        self.grid_m = np.asarray(estimate_grid_m, dtype=float)

    def tick(
        self,
        t_s: float,
        x_plant: np.ndarray,
        xf: np.ndarray,
        command: ActuatorCommand,
        local_available: bool,
        last: PlantOutput | None,
        control_mode: str,
    ) -> FootprintStatus:
        """Record one controller tick; returns the footprint's status (collision, lane)."""
        pose = self.world.pose(x_plant)
        status = self.world.footprint_status(pose, t_s, float(xf[State.s]), self.params)
        vx, vy = float(xf[State.vx]), float(xf[State.vy])
        slip = None if last is None else last.slip_control
        self.log.append(
            Tick(
                t_s=t_s,
                x_m=pose[0],
                y_m=pose[1],
                psi_rad=pose[2],
                vx_mps=vx,
                vy_mps=vy,
                psidot_radps=float(xf[State.psidot]),
                speed_mps=math.hypot(vx, vy),
                s_m=float(xf[State.s]),
                d_m=float(xf[State.d]),
                dpsi_rad=float(xf[State.dpsi]),
                # Body slip angle β = atan2(v_y, v_x); 0 at standstill.
                body_slip_rad=math.atan2(vy, vx) if vx > 0.1 else 0.0,
                steer_rad=float(x_plant[PlantState.STEER]),
                steer_cmd_rad=command.steer_rad,
                torque_front_nm=float(x_plant[PlantState.TORQUE_FRONT]),
                torque_rear_nm=float(x_plant[PlantState.TORQUE_REAR]),
                torque_front_cmd_nm=command.torque_front_nm,
                torque_rear_cmd_nm=command.torque_rear_nm,
                util_front=math.nan if last is None else float(last.utilization_front),
                util_rear=math.nan if last is None else float(last.utilization_rear),
                mu_front=status.mu_front,
                mu_rear=status.mu_rear,
                local_available=local_available,
                control_mode=control_mode,
                obstacle_active=status.obstacle_active,
                clearance_m=status.clearance_m,
                in_collision=status.in_collision,
                passed_obstacle=status.passed_obstacle,
                left_lane=status.left_lane,
                in_opposing_lane=status.in_opposing_lane,
                lane_margin_m=status.lane_margin_m,
                lane_excursion_m=status.lane_excursion_m,
                opposing_depth_m=status.opposing_depth_m,
                road_margin_m=status.road_margin_m,
                off_road=status.off_road,
                wheel_slip_front=math.nan if last is None else last.front.slip_ratio,
                wheel_slip_rear=math.nan if last is None else last.rear.slip_ratio,
                slip_control_front=slip is not None and slip.front.active,
                slip_control_rear=slip is not None and slip.rear.active,
                slip_torque_removed_front_nm=0.0 if slip is None else slip.front.torque_removed_nm,
                slip_torque_removed_rear_nm=0.0 if slip is None else slip.rear.torque_removed_nm,
                slip_cycles=0 if slip is None else slip.cycles_front + slip.cycles_rear,
                esc_yaw_moment_nm=0.0 if last is None else last.esc_yaw_moment_nm,
            )
        )
        return status

    def planning_step(
        self,
        step: int,
        t_s: float,
        s_ego_m: float,
        plan: Plan | None,
        estimate: FrictionEstimate,
        mode: str,
        step_ms: float,
        *,
        fallback_reason: str = "",
        estimate_source: str = "current",
        estimate_age_s: float = 0.0,
    ) -> None:
        """Record one planning step: outcome, timing, the plan's stages and the estimate.

        ``plan`` is None when the step produced no plan of its own (the planner raised or was
        made to fail); the loop then keeps the previous plan, which is not logged again.
        """
        reason = fallback_reason or (
            plan.fallback_reason.value if plan is not None and plan.fallback else ""
        )
        self.log.append(
            PlanningStep(
                step=step,
                t_s=t_s,
                s_m=s_ego_m,
                mode=mode,
                status=-1 if plan is None else int(plan.status),
                ok=plan is not None and bool(plan.ok),
                fallback=plan is None or bool(plan.fallback),
                fallback_reason=reason,
                sampled_reinit=plan is not None and bool(plan.sampled_reinit),
                robust_qp_retry=plan is not None and bool(plan.robust_qp_retry),
                local_available=bool(estimate.local_available),
                local_mu=finite_or_nan(estimate.local_mu),
                estimate_source=estimate_source,
                estimate_age_s=estimate_age_s,
                held=plan is not None and bool(plan.held),
            )
        )
        solve_ms = math.nan if plan is None else 1e3 * plan.solve_time_s
        self.log.append(StepTiming(step=step, t_s=t_s, solve_ms=solve_ms, step_ms=step_ms))
        if plan is not None:
            self._plan(step, t_s, plan)
        self._estimate(step, t_s, s_ego_m, estimate)

    def event(self, t_s: float, kind: EventKind, detail: str) -> None:
        """Record a fault, a reaction to one, or a change of control mode."""
        # The kind's plain string: the log's column holds what it held before the enum.
        self.log.append(Event(t_s=t_s, kind=EventKind(kind).value, detail=detail))

    def _plan(self, step: int, t_s: float, plan: Plan) -> None:
        states = np.asarray(plan.states)[:-1]
        n = states.shape[0]
        s_k, d_k = states[:, State.s], states[:, State.d]
        x_k, y_k = self.world.to_cartesian(s_k, d_k)
        inputs = np.asarray(plan.inputs)
        self.log.append(
            PlanStages(
                step=step,
                t_s=t_s,
                k=np.arange(n),
                t_k_s=t_s + np.arange(n, dtype=np.float64) * plan.dt_s,
                s_m=s_k,
                d_m=d_k,
                dpsi_rad=states[:, State.dpsi],
                psidot_radps=states[:, State.psidot],
                vx_mps=states[:, State.vx],
                vy_mps=states[:, State.vy],
                x_m=x_k,
                y_m=y_k,
                fyf_n=inputs[:, Input.fyf],
                fxf_n=inputs[:, Input.fxf],
                fxr_n=inputs[:, Input.fxr],
                fyr_n=np.asarray(plan.rear_lateral_force_n),
                fzf_n=np.asarray(plan.normal_load_front_n),
                fzr_n=np.asarray(plan.normal_load_rear_n),
                limit_front_n=np.asarray(plan.force_limit_front_n),
                limit_rear_n=np.asarray(plan.force_limit_rear_n),
                mu_hat=np.asarray(plan.mu_hat),
                mu_true=self.world.friction(s_k),
            )
        )

    def _estimate(self, step: int, t_s: float, s_ego_m: float, estimate: FrictionEstimate) -> None:
        # On the sensors' grid for every source: GT's estimate reaches further ahead
        # (sim.estimation.source_grid_m), the plans table has what it planned with there.
        grid = self.grid_m
        n = grid.size
        grid_abs = s_ego_m + grid
        nan = np.full(n, np.nan)
        fused = estimate.fused
        data_mu, data_margin = nan.copy(), nan.copy()
        if estimate.data is not None:
            # Fusion input placed on the estimate grid (each datum at its grid point).
            within = np.asarray(estimate.data.s_m) <= grid[-1]
            idx = np.clip(np.searchsorted(grid, estimate.data.s_m[within]), 0, n - 1)
            data_mu[idx] = estimate.data.mu[within]
            data_margin[idx] = estimate.data.margin[within]
        self.log.append(
            EstimateGrid(
                step=step,
                t_s=t_s,
                s_ahead_m=grid,
                s_m=grid_abs,
                mu_true=self.world.friction(grid_abs),
                mu_hat=np.asarray(estimate.mu_hat, dtype=float)[:n],
                mean=nan if fused is None else np.asarray(fused.mean)[:n],
                std=nan if fused is None else np.asarray(fused.std)[:n],
                lower=nan if fused is None else np.asarray(fused.lower)[:n],
                data_mu=data_mu,
                data_margin=data_margin,
            )
        )
