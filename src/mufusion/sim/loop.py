"""The closed loop: plant, controller interface, planner and friction estimation at their own rates.

Each component exposes one step-like call, so one tick of the loop reads in a few lines
(do-mpc's ``u = mpc.make_step(x); y = sim.make_step(u)``): the planner runs every
``plant_hz / planner_hz`` plant steps with the current friction estimate, the controller every
``plant_hz / controller_hz`` steps, the plant every step with the true friction under each axle.
What happens is written by a :class:`~mufusion.sim.recorder.Recorder` into one
:class:`~mufusion.sim.log.RunLog`; the loop itself only steps the world.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.estimators import SensorModel
from mufusion.planner import Plan, PlannerConfig
from mufusion.planner.minimal_risk import at_rest
from mufusion.planner.safety import SafetySettings
from mufusion.planner.speed_profile import MAX_LOOKAHEAD_M
from mufusion.sim.components import (
    Controller,
    FrictionSource,
    LoopRates,
    Planner,
    PlantModel,
)
from mufusion.sim.estimate_guard import EstimateGuard
from mufusion.sim.estimation import FrictionEstimation, source_grid_m
from mufusion.sim.events import EventKind
from mufusion.sim.faults import Fault, active_kinds, estimate_delay_s
from mufusion.sim.lane_recovery import LaneRecovery
from mufusion.sim.log import RunLog
from mufusion.sim.minimal_risk import MINIMAL_RISK_MODE, MinimalRisk
from mufusion.sim.obstacle_response import ObstacleResponse
from mufusion.sim.planning import Planning
from mufusion.sim.probing import Probing
from mufusion.sim.recorder import Recorder
from mufusion.sim.records import RunMeta
from mufusion.sim.settings import LaneRecoverySettings, ProbingSettings
from mufusion.sim.stop_in_lane import StopInLane
from mufusion.sim.supervisors import Supervision
from mufusion.sim.world import World
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State
from mufusion.vehicle.plant import PlantOutput, PlantState

_log = logging.getLogger(__name__)



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
        The components; see the module docstring for their calls. ``friction`` reads what
        ``sensors`` report (:func:`~mufusion.configurations.step_source`).
    rates
        Component rates.
    reference_speed_mps
        Cruise speed the planner tracks.
    lane_bounds_m
        ``(d_min, d_max)`` the planner's reference point must stay within (lane or road).
    meta
        The run's metadata (written into the log).
    estimate_grid_m
        Distances ahead at which friction is estimated [m] (paper: 0, 1, …, 50); the log's
        estimates table is on this grid for every source.
    truth_reach_m
        How far ahead a source that reads the true friction (GT) is handed it [m]: its grid
        continues ``estimate_grid_m`` to here (:func:`~mufusion.sim.estimation.source_grid_m`;
        default: as far as the planner's speed reference looks).
    emergency_on_obstacle
        Switch the planner to its emergency (stop) mode once an obstacle is active.
    faults
        Faults to inject (:mod:`mufusion.sim.faults`).
    safety
        How the loop reacts to missing, stale or failing parts.
    probing, lane_recovery
        The supervisory behaviours of :mod:`mufusion.sim.supervision` (beyond the paper).
    utilization_factor, planning_horizon_s
        The planner's λ and how far ahead it plans [s] (default: the built-in planner's), for
        the supervisors that judge the road as it does.
    obstacle_response
        Stop in front of an obstacle where possible, else evade
        (:mod:`mufusion.sim.obstacle_response`); ``emergency_on_obstacle`` overrides it.
    sensors
        The vehicle's emulated sensors: the only part of the estimation that reads the true
        friction (default: the paper's, without errors).

    Attributes
    ----------
    plan
        The plan the controller tracks (adopted at the last planning step of :meth:`run`).
    supervision
        The run's supervisors (:class:`~mufusion.sim.supervisors.Supervision`: stopping in lane,
        lane recovery, probing, the minimal-risk manoeuvre), each with what it did.

    Notes
    -----
    Reactions, each logged as an event (table ``events``, :class:`~mufusion.sim.events.EventKind`):

    - The friction estimate handed to the planner must be finite and at most
      ``safety.max_estimate_age_s`` old (:class:`~mufusion.sim.estimate_guard.EstimateGuard`):
      otherwise the last one that was, while young enough, else ``safety.mu_floor``.
    - A planning step without a usable plan (the solver failed, the planner raised or was made
      to fail) keeps the previous plan. After ``safety.max_consecutive_fallbacks`` such steps in
      a row, or at once when the friction source or the controller raises, the vehicle enters
      the minimal-risk manoeuvre (:class:`~mufusion.sim.minimal_risk.MinimalRisk`).
    - Any other exception inside the loop ends the run early with an event; the log is kept.
    """

    world: World
    params: VehicleParams
    plant: PlantModel
    planner: Planner
    controller: Controller
    friction: FrictionSource
    rates: LoopRates
    reference_speed_mps: float
    lane_bounds_m: tuple[float, float]
    meta: RunMeta
    estimate_grid_m: np.ndarray = field(default_factory=lambda: np.arange(0.0, 51.0, 1.0))
    truth_reach_m: float = MAX_LOOKAHEAD_M
    emergency_on_obstacle: bool = False
    faults: Sequence[Fault] = ()
    safety: SafetySettings = field(default_factory=SafetySettings)
    probing: ProbingSettings = field(default_factory=ProbingSettings)
    lane_recovery: LaneRecoverySettings = field(default_factory=LaneRecoverySettings)
    utilization_factor: float = PlannerConfig.utilization_factor
    planning_horizon_s: float = PlannerConfig.horizon_steps * PlannerConfig.dt_s
    obstacle_response: ObstacleResponse = field(default_factory=ObstacleResponse)
    sensors: SensorModel = field(default_factory=SensorModel)

    def run(self, duration_s: float, progress: Callable[[float], None] | None = None,
            warmup_steps: int = 0) -> RunLog:
        """Simulate ``duration_s`` seconds (or until a collision or the end of the road).

        ``progress(t)`` is called after every planning step (:attr:`plan` is then its plan).
        Before the clock starts, the planner makes ``warmup_steps`` plans at the initial state
        without obstacles (and without logging), as if it had been cruising there: its warm start.

        Raises
        ------
        ValueError
            If ``duration_s`` is not a positive finite number, or ``truth_reach_m`` ends before
            the estimate grid.
        """
        if not np.isfinite(duration_s) or duration_s <= 0:
            raise ValueError(f"duration_s must be > 0, got {duration_s!r}")
        grid = source_grid_m(self.estimate_grid_m, self.friction, self.truth_reach_m)
        log = RunLog(self.meta)
        self._recorder = recorder = Recorder(log, self.world, self.params, self.estimate_grid_m)
        event = recorder.event
        self._guard = EstimateGuard(grid, self.safety, event)
        self.supervision = Supervision(
            StopInLane(self.lane_recovery, event),
            LaneRecovery(self.lane_recovery, self.planner, self.params, self.lane_bounds_m,
                         self.world.curvature, event, self.obstacle_response.margin_m,
                         self.utilization_factor, record=log.append),
            Probing(self.probing, self.utilization_factor, self.planning_horizon_s, self.params,
                    grid, self.world.curvature, event),
            MinimalRisk(self.safety, self.params, event),
        )
        self._planning = Planning(
            self.planner, self.world, self.params, grid, self.reference_speed_mps,
            self.lane_bounds_m, self.obstacle_response, self.emergency_on_obstacle, event)
        self.plan: Plan | None = None
        self._estimation = FrictionEstimation(
            self.friction, self.sensors, self.world, self.params, grid)
        for fault in self.faults:
            event(fault.start_s, EventKind.FAULT_SCHEDULED, fault.describe())
        try:
            if warmup_steps > 0:
                self._warm_up(warmup_steps)
            self._run(duration_s, progress)
        except Exception as exc:  # never lose the log: end the run, say why
            _log.exception("closed loop ended by an error")
            t_end = float(log.timeseries["t_s"].iloc[-1]) if len(log.timeseries) else 0.0
            event(t_end, EventKind.LOOP_ERROR, f"{type(exc).__name__}: {exc}")
        return log

    def _warm_up(self, steps: int) -> None:
        """The warm-up plans before the clock starts. A friction source or planner that raises
        here degrades as it would in the loop (the run goes on, the error in its log), instead
        of ending the run before its first tick."""
        x_plant = self.plant.x
        xf = self.world.frenet_state(x_plant)
        try:
            estimate = self._estimation.initial(x_plant, float(xf[State.s]))
        except Exception as exc:
            self._recorder.event(0.0, EventKind.FRICTION_SOURCE_ERROR,
                                 f"{type(exc).__name__}: {exc}")
            self.supervision.minimal_risk.enter(0.0, "the friction source failed")
            return
        try:
            self._planning.warm_up(xf, estimate, steps, self.rates.planner_hz)
        except Exception as exc:  # the loop's steps try the planner again and escalate
            self._recorder.event(0.0, EventKind.PLANNER_ERROR,
                                 f"planner raised {type(exc).__name__}: {exc} (warm-up)")

    def _run(self, duration_s: float, progress: Callable[[float], None] | None) -> None:
        # do-mpc's loop: x = est.make_step(y); u = mpc.make_step(x); y = sim.make_step(u).
        rates = self.rates
        dt = 1.0 / rates.plant_hz
        command = ActuatorCommand(0.0, 0.0, 0.0)
        plan_step, util_window = -1, 0.0
        last: PlantOutput | None = None
        road_end = self.world.road_length_m - self.params.length_m
        estimate: FrictionEstimate | None = None
        x_plant = self.plant.x
        xf = self.world.frenet_state(x_plant)
        for i in range(round(duration_s * rates.plant_hz) + 1):
            t = i * dt
            state = self.plant.state  # named floats; the array only for the ticks below
            control_tick = i % rates.controller_every == 0
            if control_tick:
                x_plant = np.asarray(state)
                # The planner's rate divides the controller's, so this also serves planning steps.
                xf = self.world.frenet_state(x_plant)
            if i % rates.planner_every == 0:
                self._planning.front_force_n = None if last is None else last.front_lateral_force_n
                radius = self.params.wheel_radius_m
                self._planning.longitudinal_forces_n = (state.torque_front_nm / radius,
                                                        state.torque_rear_nm / radius)
                plan_step += 1
                estimate, self.plan = self._planning_step(plan_step, t, xf, util_window)
                util_window = 0.0
                if progress:
                    progress(t)
            if control_tick:
                assert estimate is not None  # a planning step comes first (i = 0)
                # While the vehicle's slip control modulates a torque, the applied torque falls
                # short of the command on purpose: the controller's lag feedback must not wind up.
                slip = None if last is None else last.slip_control
                modulated = slip is not None and (slip.front.active or slip.rear.active)
                command = self._command(t, xf, x_plant, estimate, modulated)
                status = self._recorder.tick(
                    t, x_plant, xf, command, estimate.local_available, last, self._control_mode()
                )
                if status.in_collision or float(xf[State.s]) >= road_end:
                    break
            mu_front, mu_rear = self.world.friction_under_axles(state, self.params)
            last = self.plant.step(command, mu_front, mu_rear)
            util_window = max(util_window, last.utilization_front, last.utilization_rear)
            self._estimation.observe(t + dt, last, mu_front, mu_rear)

    def _control_mode(self) -> str:
        return "minimal_risk" if self.supervision.minimal_risk.active else (
            "probing" if self.supervision.probing.active else "plan")

    def _planning_step(self, step: int, t: float, xf: np.ndarray,
                       utilization: float) -> tuple[FrictionEstimate, Plan | None]:
        """One planning step: estimate, choose the mode, plan; returns the estimate planned
        with and the plan to track (the previous one if the step gave none)."""
        s_ego = float(xf[State.s])
        kinds = active_kinds(self.faults, t)
        fresh = self._estimate(t, s_ego, utilization, kinds)
        estimate, source, age = self._guard.usable(t, s_ego, fresh, delay_s=estimate_delay_s(
            self.faults, t), corrupt="estimate_nan" in kinds)
        self._planning.drive_on(s_ego, estimate)
        obstacles = self.world.planner_obstacles(t, s_ego, behind_m=self.params.length_m)
        mrm = self.supervision.minimal_risk
        ctx = self._planning.context(t, xf, obstacles, mrm.active)
        mode = MINIMAL_RISK_MODE if mrm.active else ctx.mode_of(estimate)
        for supervisor in self.supervision.in_order:
            mode, estimate = supervisor.choose_mode(ctx, mode, estimate)
        self._planning.last_mode = mode
        started = time.perf_counter()
        plan: Plan | None = None
        reason = ""
        if "solver_failure" in kinds:
            reason = "injected solver failure"
        else:
            try:
                first = estimate
                for supervisor in self.supervision.in_order:
                    first = supervisor.adjust_inputs(ctx, mode, first)
                plan = ctx.plan(first, mode)
                for supervisor in self.supervision.in_order:
                    plan, estimate = supervisor.review(ctx, mode, estimate, plan)
            except Exception as exc:  # a planner that raises degrades, never ends the run
                reason = f"planner raised {type(exc).__name__}: {exc}"
                self._recorder.event(t, EventKind.PLANNER_ERROR, reason)
        step_ms = 1e3 * (time.perf_counter() - started)
        mrm.count(plan is None or plan.fallback,
                  at_rest_braking=mode == "emergency" and at_rest(xf))
        if plan is not None and not plan.ok:
            _log.warning("planning step %d at t=%.2f s: solver status %s", step, t, plan.status)
        self._recorder.planning_step(
            step, t, s_ego, plan, estimate, mode, step_ms, fallback_reason=reason,
            estimate_source=source, estimate_age_s=age,
        )
        mrm.check(t)
        return estimate, plan if plan is not None else self.plan

    def _estimate(self, t: float, s_ego: float, utilization: float,
                  kinds: frozenset[str]) -> FrictionEstimate | None:
        try:
            return self._estimation.estimate(t, s_ego, utilization, kinds)
        except Exception as exc:
            self._recorder.event(t, EventKind.FRICTION_SOURCE_ERROR, f"{type(exc).__name__}: {exc}")
            self.supervision.minimal_risk.enter(t, "the friction source failed")
            return None

    def _command(self, t: float, xf: np.ndarray, x_plant: np.ndarray, estimate: FrictionEstimate,
                 slip_modulated: bool = False) -> ActuatorCommand:
        curvature = self.world.curvature_at(float(xf[State.s]))
        if self.plan is not None and self.supervision.minimal_risk.trusts_planner:
            try:
                command = self.controller.command(
                    t, xf, float(x_plant[PlantState.STEER]), self.plan, curvature,
                    None if slip_modulated else (float(x_plant[PlantState.TORQUE_FRONT]),
                                                 float(x_plant[PlantState.TORQUE_REAR])),
                ).clipped(self.params)
                for supervisor in self.supervision.in_order:
                    command = supervisor.shape(t, xf, command)
                return command
            except Exception as exc:
                self._recorder.event(t, EventKind.CONTROLLER_ERROR, f"{type(exc).__name__}: {exc}")
                self.supervision.minimal_risk.enter(t, "the controller failed")
        return self.supervision.minimal_risk.command(xf, curvature, estimate)
