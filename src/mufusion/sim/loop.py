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

from mufusion.configurations import FrictionEstimate, channels_of, step_source
from mufusion.estimators import SensorModel, VehicleSignals
from mufusion.planner import Plan, PlannerObstacle
from mufusion.planner.safety import SafetySettings
from mufusion.sim.components import (
    Controller,
    FrictionSource,
    LoopRates,
    Planner,
    PlanningMode,
    PlantModel,
)
from mufusion.sim.estimate_guard import EstimateGuard
from mufusion.sim.faults import Fault, active_kinds, estimate_delay_s
from mufusion.sim.log import RunLog
from mufusion.sim.minimal_risk import minimal_risk_command
from mufusion.sim.obstacle_response import ObstacleResponse, obstacle_mode
from mufusion.sim.recorder import Recorder
from mufusion.sim.records import RunMeta
from mufusion.sim.sensing import vehicle_signals
from mufusion.sim.supervision import (
    LaneRecoverySettings,
    Prober,
    ProbingSettings,
    planned_footprint_violation_m,
    planned_obstacle_clearance_m,
    plausible_estimate,
    relaxed_estimate,
)
from mufusion.sim.world import World
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State
from mufusion.vehicle.plant import PlantOutput, PlantState

_log = logging.getLogger(__name__)

MINIMAL_RISK_MODE: PlanningMode = "minimal_risk"
"""The planner's mode during the minimal-risk manoeuvre: brake to a stop in lane."""
AT_REST_MPS = 0.1
"""Below this speed [m/s] a vehicle stopping for an obstacle has stopped."""


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
        Distances ahead at which friction is estimated [m] (paper: 0, 1, …, 50).
    emergency_on_obstacle
        Switch the planner to its emergency (stop) mode once an obstacle is active.
    faults
        Faults to inject (:mod:`mufusion.sim.faults`).
    safety
        How the loop reacts to missing, stale or failing parts.
    probing, lane_recovery
        The supervisory behaviours of :mod:`mufusion.sim.supervision` (beyond the paper).
    obstacle_response
        Stop in front of an obstacle where possible, else evade
        (:mod:`mufusion.sim.obstacle_response`); ``emergency_on_obstacle`` overrides it.
    sensors
        The vehicle's emulated sensors: the only part of the estimation that reads the true
        friction (default: the paper's, without errors).

    Notes
    -----
    Reactions, each logged as an event (table ``events``):

    - The friction estimate handed to the planner must be finite and at most
      ``safety.max_estimate_age_s`` old (:class:`~mufusion.sim.estimate_guard.EstimateGuard`):
      otherwise the last one that was, while young enough, else ``safety.mu_floor``.
    - A planning step without a usable plan (the solver failed, the planner raised or was made
      to fail) keeps the previous plan. After ``safety.max_consecutive_fallbacks`` such steps in
      a row (not counting those at rest in front of an obstacle, :data:`AT_REST_MPS`), or at
      once when the friction source raises, the vehicle enters the minimal-risk
      manoeuvre: the planner plans a stop in lane (``MINIMAL_RISK_MODE``); while it cannot, the
      loop brakes in lane itself (:func:`~mufusion.sim.minimal_risk.minimal_risk_command`).
      The manoeuvre is latched until the end of the run.
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
    emergency_on_obstacle: bool = False
    faults: Sequence[Fault] = ()
    safety: SafetySettings = field(default_factory=SafetySettings)
    probing: ProbingSettings = field(default_factory=ProbingSettings)
    lane_recovery: LaneRecoverySettings = field(default_factory=LaneRecoverySettings)
    utilization_factor: float = 0.9
    obstacle_response: ObstacleResponse = field(default_factory=ObstacleResponse)
    sensors: SensorModel = field(default_factory=SensorModel)

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
        log = RunLog(self.meta)
        self._recorder = Recorder(log, self.world, self.params, self.estimate_grid_m)
        self._guard = EstimateGuard(self.estimate_grid_m, self.safety, self._recorder.event)
        self._prober = Prober(self.probing, self.utilization_factor)
        self._consecutive_fallbacks = 0
        self._minimal_risk = False
        self._planner_usable = True
        self._local_available = False
        self._last_mode: PlanningMode = "cruise"
        self._stop_probe_since: float | None = None  # the braking probe's start, while it runs
        self._stop_probe_spent = False  # one braking probe per run: its measurement stands
        self._stop_alpha: float | None = None  # the relaxation of the stop in lane, while held
        self._recovery_alpha = 0.0  # lane recovery's relaxation adopted at the last step
        # The front axle's body-frame lateral force of the last plant step: each plan's force
        # state starts from it (None before the first step: the warm-up plans start from theirs).
        self._front_force_n: float | None = None
        # The friction source's interface: its channels, and its per-plant-step call if it has one.
        self._channels = channels_of(self.friction)
        self._observe: Callable[[VehicleSignals], None] | None = getattr(
            self.friction, "observe", None)
        self._last_output: tuple[float, PlantOutput] | None = None  # (its time, the output)
        for fault in self.faults:
            self._recorder.event(fault.start_s, "fault_scheduled", _describe(fault))
        try:
            self._warm_up(warmup_steps)
            self._run(duration_s, progress)
        except Exception as exc:  # never lose the log: end the run, say why
            _log.exception("closed loop ended by an error")
            t_end = float(log.timeseries["t_s"].iloc[-1]) if len(log.timeseries) else 0.0
            self._recorder.event(t_end, "loop_error", f"{type(exc).__name__}: {exc}")
        return log

    def _run(self, duration_s: float, progress: Callable[[float], None] | None) -> None:
        rates = self.rates
        dt = 1.0 / rates.plant_hz
        n_steps = round(duration_s * rates.plant_hz)
        command = ActuatorCommand(0.0, 0.0, 0.0)
        plan_step = -1
        util_window = 0.0
        last: PlantOutput | None = None
        road_end = self.world.road_length_m - self.params.length_m
        xf = self.world.frenet_state(self.plant.x)
        s_ego = float(xf[State.s])
        plan: Plan | None = None
        estimate: FrictionEstimate | None = None
        x_plant = self.plant.x
        for i in range(n_steps + 1):
            t = i * dt
            state = self.plant.state  # named floats; the array only for the ticks below
            control_tick = i % rates.controller_every == 0
            if control_tick:
                x_plant = np.asarray(state)
                # The planner's rate divides the controller's, so this also serves planning steps.
                xf = self.world.frenet_state(x_plant)
                s_ego = float(xf[State.s])

            if i % rates.planner_every == 0:
                self._front_force_n = None if last is None else last.front_lateral_force_n
                plan_step += 1
                estimate, plan = self._planning_step(plan_step, t, xf, util_window, plan)
                util_window = 0.0
                if progress:
                    progress(t)

            if control_tick:
                assert estimate is not None  # a planning step comes first (i = 0)
                # While the vehicle's slip control modulates a torque, the applied torque falls
                # short of the command on purpose: the controller's lag feedback must not wind up.
                slip = None if last is None else last.slip_control
                modulated = slip is not None and (slip.front.active or slip.rear.active)
                command = self._command(t, xf, x_plant, plan, estimate, modulated)
                status = self._recorder.tick(
                    t, x_plant, xf, command, estimate.local_available, last, self._control_mode()
                )
                if status.in_collision or s_ego >= road_end:
                    break

            mu_front, mu_rear = self.world.friction_under_axles(state, self.params)
            last = self.plant.step(command, mu_front, mu_rear)
            util_window = max(util_window, last.utilization_front, last.utilization_rear)
            self.sensors.observe(
                t + dt, last.utilization_front, last.utilization_rear, mu_front, mu_rear
            )
            self._last_output = (t + dt, last)
            if self._observe is not None:
                self._observe(vehicle_signals(t + dt, last, self.params))

    def _control_mode(self) -> str:
        if self._minimal_risk:
            return "minimal_risk"
        return "probing" if self._prober.active else "plan"

    # -- one planning step ------------------------------------------------------------------
    def _planning_step(
        self, step: int, t: float, xf: np.ndarray, utilization: float, previous: Plan | None
    ) -> tuple[FrictionEstimate, Plan | None]:
        s_ego = float(xf[State.s])
        kinds = active_kinds(self.faults, t)
        fresh = self._estimate(t, s_ego, utilization, kinds)
        estimate, source, age = self._guard.usable(
            t, s_ego, fresh, delay_s=estimate_delay_s(self.faults, t),
            corrupt="estimate_nan" in kinds,
        )
        self._local_available = estimate.local_available
        obstacles = self.world.planner_obstacles(t, s_ego, behind_m=self.params.length_m)
        mode = MINIMAL_RISK_MODE if self._minimal_risk else self._mode(obstacles, xf, estimate)
        if mode == "evade" and self.lane_recovery.enabled and not self._minimal_risk:
            mode, estimate = self._stop_in_lane(t, xf, estimate, obstacles)
        elif self._stop_probe_since is not None:
            self._end_stop_probe(t, f"the stop-or-evade rule chose {mode}")
        self._last_mode = mode
        self._consider_probe(t, xf, estimate, obstacles)
        started = time.perf_counter()
        plan: Plan | None = None
        reason = ""
        if "solver_failure" in kinds:
            reason = "injected solver failure"
        else:
            try:
                recovering = self.lane_recovery.enabled and not self._minimal_risk
                first = (self._held_relaxation(estimate) if recovering and mode != "evade"
                         else estimate)
                plan = self._plan(xf, t, s_ego, first, obstacles, mode)
                if recovering:
                    plan, estimate = self._recover_lane(t, xf, s_ego, plan, estimate, obstacles,
                                                        mode)
            except Exception as exc:  # a planner that raises degrades, never ends the run
                reason = f"planner raised {type(exc).__name__}: {exc}"
                self._recorder.event(t, "planner_error", reason)
        step_ms = 1e3 * (time.perf_counter() - started)
        failed = plan is None or plan.fallback
        self._planner_usable = not failed
        # Stopped for an obstacle, the manoeuvre's stop is done: a failed plan (the model is stiff
        # at rest) keeps the vehicle held and starts nothing.
        held = mode == "emergency" and float(xf[State.vx]) < AT_REST_MPS
        self._consecutive_fallbacks = 0 if not failed else self._consecutive_fallbacks + (not held)
        if plan is not None and not plan.ok:
            _log.warning("planning step %d at t=%.2f s: solver status %s", step, t, plan.status)
        self._recorder.planning_step(
            step, t, s_ego, plan, estimate, mode, step_ms, fallback_reason=reason,
            estimate_source=source, estimate_age_s=age,
        )
        if self._consecutive_fallbacks >= self.safety.max_consecutive_fallbacks:
            self._enter_minimal_risk(t, f"{self._consecutive_fallbacks} planning steps in a row "
                                        "without a usable plan")
        return estimate, plan if plan is not None else previous

    def _recover_lane(
        self,
        t: float,
        xf: np.ndarray,
        s_ego: float,
        plan: Plan,
        estimate: FrictionEstimate,
        obstacles: Sequence[PlannerObstacle],
        mode: PlanningMode,
    ) -> tuple[Plan, FrictionEstimate]:
        """Re-plan with μ̂ relaxed towards the posterior mean if the plan cannot keep the lane.

        ``plan`` was planned with ``estimate`` relaxed by the fraction the previous step adopted
        (:meth:`_held_relaxation`); ``estimate`` itself is unrelaxed.
        """
        # Evading, the plan leaves the lane by design and a held relaxation would only make the
        # swerve harder (measured: off the road 4 → 13 of 108 F-safe pop-up runs): each step
        # searches from the unrelaxed μ̂ there, and nothing is held into the steps after.
        hold = mode != "evade"
        if not hold:
            self._recovery_alpha = 0.0
        held = self._recovery_alpha
        # Without a posterior (GT, L, P) there is nothing to relax: skip the footprint check,
        # which would run at every planning step.
        if relaxed_estimate(estimate, 1.0) is None:
            self._recovery_alpha = 0.0
            return plan, estimate
        planned_with = relaxed_estimate(estimate, held) if held > 0.0 else estimate
        assert planned_with is not None
        tolerance = self.lane_recovery.violation_tolerance_m
        before = self._footprint_violation_m(plan)
        alphas = (0.0, *self.lane_recovery.steps)
        # No friction-limited plan at all (the solve failed) counts as not keeping the lane.
        if before <= tolerance and not plan.fallback:
            if held == 0.0:
                return plan, estimate
            # The lane is kept with the relaxation held: try one step less of it, so that the
            # guarantee of the lower bound returns as soon as the lane allows.
            lower = alphas[alphas.index(held) - 1]
            memory = self.planner.memory
            candidate_estimate = relaxed_estimate(estimate, lower) if lower > 0.0 else estimate
            assert candidate_estimate is not None
            candidate = self._plan(xf, t, s_ego, candidate_estimate, obstacles, mode)
            if not candidate.fallback and self._footprint_violation_m(candidate) <= tolerance:
                self._recovery_alpha = lower
                self._recorder.event(
                    t, "lane_recovery", f"the lane is kept with μ̂ relaxed {lower:.2f} of the way "
                    f"to the posterior mean (was {held:.2f})")
                return candidate, candidate_estimate
            self.planner.restore(memory)
            return plan, planned_with
        # Each candidate starts from the one before (a continuation in α: the later candidates
        # have had more iterations), and the next step continues the plan adopted: the planner
        # keeps its latest plan as the next warm start (and that plan's front force as where
        # the next plan's force starts), which after the search would be the last candidate
        # tried, not the one the controller tracks.
        # A plan predicted to hit an obstacle is never preferred to one predicted to pass it,
        # however much further the latter leaves the lane (evading, the road band).
        def rank(candidate: Plan, violation: float) -> tuple[bool, float]:
            hits = planned_obstacle_clearance_m(candidate.states, obstacles, self.params) < 0.0
            return (hits, np.inf if candidate.fallback else violation)

        best = (rank(plan, before), before, plan, planned_with, held, self.planner.memory)
        for alpha in (a for a in alphas if a > held):
            relaxed = relaxed_estimate(estimate, alpha)
            assert relaxed is not None
            candidate = self._plan(xf, t, s_ego, relaxed, obstacles, mode)
            violation = self._footprint_violation_m(candidate)
            key = rank(candidate, violation)
            if not candidate.fallback and key < best[0]:
                best = (key, violation, candidate, relaxed, alpha, self.planner.memory)
            if not candidate.fallback and violation <= tolerance and not key[0]:
                break
        (every_one_hits, _), violation, plan, adopted, alpha, memory = best
        self.planner.restore(memory)
        if mode == "evade" and every_one_hits and self.lane_recovery.brake_when_futile:
            braking = self._brake_if_futile(t, xf, s_ego, estimate, obstacles)
            if braking is not None:
                self._recovery_alpha = 0.0
                return braking, estimate
        self._recovery_alpha = alpha if hold else 0.0
        problem = "no friction-limited plan" if plan.fallback and alpha == 0.0 else (
            "the friction-limited plan failed" if alpha > 0.0 and before <= tolerance
            else f"the plan left the lane by {before:.2f} m"
        )
        held_note = f" (from {held:.2f} held)" if held > 0.0 else ""
        self._recorder.event(
            t, "lane_recovery",
            f"{problem}; μ̂ relaxed {alpha:.2f} of the way to the posterior mean{held_note}, the "
            f"plan leaves the lane by {violation:.2f} m" if alpha > 0.0 else f"{problem}; "
            "relaxing μ̂ towards the posterior mean did not help",
        )
        return plan, adopted

    def _brake_if_futile(
        self,
        t: float,
        xf: np.ndarray,
        s_ego: float,
        estimate: FrictionEstimate,
        obstacles: Sequence[PlannerObstacle],
    ) -> Plan | None:
        """The stop in lane, if an evasion with μ̂ at the posterior's upper 95 % edge also hits.

        Called when every lane-recovery candidate is predicted to hit an obstacle; ``estimate``
        is unrelaxed. Returns None (and the planner continues the adopted candidate) when that
        evasion passes, or when either plan fails.
        """
        memory = self.planner.memory
        top = plausible_estimate(estimate)
        if top is not None:
            check = self._plan(xf, t, s_ego, top, obstacles, "evade")
            gap = planned_obstacle_clearance_m(check.states, obstacles, self.params)
            if not check.fallback and gap < 0.0:
                brake = self._plan(xf, t, s_ego, estimate, obstacles, "emergency")
                if not brake.fallback:
                    self._recorder.event(
                        t, "futile_evasion",
                        f"every evasion hits the obstacle, at the posterior's upper 95 % edge too "
                        f"({gap:.2f} m); braking in lane")
                    return brake
        self.planner.restore(memory)
        return None

    def _held_relaxation(self, estimate: FrictionEstimate) -> FrictionEstimate:
        """``estimate`` relaxed by the fraction lane recovery adopted at the previous step."""
        if self._recovery_alpha > 0.0:
            relaxed = relaxed_estimate(estimate, self._recovery_alpha)
            if relaxed is not None:
                return relaxed
        self._recovery_alpha = 0.0
        return estimate

    def _stop_in_lane(
        self,
        t: float,
        xf: np.ndarray,
        estimate: FrictionEstimate,
        obstacles: Sequence[PlannerObstacle],
    ) -> tuple[PlanningMode, FrictionEstimate]:
        """Stop in lane instead of evading, if a relaxed μ̂ grants it or a braking probe may.

        See :mod:`mufusion.sim.supervision` ("Stopping in lane for an obstacle"). Returns the
        mode and the estimate to plan with: ``("emergency", relaxed)``, ``("emergency",
        estimate)`` while probing, else ``("evade", estimate)``.
        """
        # Once the evasion is under way it is kept (and without a posterior nothing relaxes).
        if self._last_mode == "evade" or estimate.fused is None:
            return "evade", estimate
        for alpha in self.lane_recovery.steps:
            relaxed = relaxed_estimate(estimate, alpha)
            if relaxed is None:
                break  # the mean adds nothing to μ̂: no α will
            if self._mode(obstacles, xf, relaxed) == "emergency":
                self._end_stop_probe(t, f"the stop fits with μ̂ relaxed {alpha:.2f} of the way "
                                        "to the posterior mean")
                if alpha != self._stop_alpha:
                    self._recorder.event(
                        t, "lane_recovery", f"stop in lane, μ̂ relaxed {alpha:.2f} of the way to "
                        "the posterior mean (μ̂ grants no stop: evading would leave the lane)")
                self._stop_alpha = alpha
                return "emergency", relaxed
        self._stop_alpha = None
        since = self._stop_probe_since
        probing = since is not None
        may_probe = (
            not estimate.local_available
            and not self._stop_probe_spent
            and self.lane_recovery.stop_probe_s > 0.0
            and (since is None or t - since < self.lane_recovery.stop_probe_s - 1e-9)
        )
        plausible = plausible_estimate(estimate) if may_probe else None
        if plausible is not None and self._mode(obstacles, xf, plausible) == "emergency":
            if not probing:
                self._stop_probe_since = t
                self._recorder.event(
                    t, "stop_probe", "neither μ̂ nor the posterior mean grants the stop, the "
                    "posterior's 95 % band does: braking in lane to measure the friction")
            return "emergency", estimate
        self._end_stop_probe(t, "the stop is not granted; evading" if probing else "")
        return "evade", estimate

    def _end_stop_probe(self, t: float, why: str) -> None:
        if self._stop_probe_since is not None:
            self._recorder.event(t, "stop_probe_end", f"{why} after "
                                 f"{t - self._stop_probe_since:.2f} s")
            self._stop_probe_since = None
            self._stop_probe_spent = True

    def _footprint_violation_m(self, plan: Plan) -> float:
        states = plan.states[1:]
        return planned_footprint_violation_m(
            states, self.world.curvature(states[:, State.s]), self.lane_bounds_m, self.params
        )

    def _consider_probe(
        self,
        t: float,
        xf: np.ndarray,
        estimate: FrictionEstimate,
        obstacles: Sequence[PlannerObstacle],
    ) -> None:
        if self._prober.active or self._minimal_risk:
            return
        s_ego = float(xf[State.s])
        speed = float(np.hypot(xf[State.vx], xf[State.vy]))
        near = any(o.s_m - s_ego < self.probing.clear_distance_m for o in obstacles)
        kappa = self.world.curvature(s_ego + self.estimate_grid_m)
        why = self._prober.reason_to_probe(t, speed, estimate, kappa, near)
        if why is not None:
            self._prober.start(t, speed)
            self._recorder.event(t, "probe_start", why)

    def _estimate(
        self, t: float, s_ego: float, utilization: float, kinds: frozenset[str]
    ) -> FrictionEstimate | None:
        s_abs = s_ego + self.estimate_grid_m
        mu_true = self.world.friction(s_abs)
        util = 0.0 if "local_dropout" in kinds else utilization
        # An absent camera, or one whose values are NaN, gives nothing usable: discarded.
        camera_ok = not ({"camera_dropout", "camera_nan"} & kinds)
        try:
            return step_source(
                self.friction, self.sensors, self.estimate_grid_m, mu_true, util,
                camera_ok=camera_ok, t_s=t, channels=self._channels,
                signals=None if self._last_output is None else vehicle_signals(
                    *self._last_output, self.params),
            )
        except Exception as exc:
            self._recorder.event(t, "friction_source_error", f"{type(exc).__name__}: {exc}")
            self._enter_minimal_risk(t, "the friction source failed")
            return None

    def _enter_minimal_risk(self, t: float, why: str) -> None:
        if not self._minimal_risk:
            self._minimal_risk = True
            self._recorder.event(t, "minimal_risk", why)

    def _command(
        self,
        t: float,
        xf: np.ndarray,
        x_plant: np.ndarray,
        plan: Plan | None,
        estimate: FrictionEstimate,
        slip_modulated: bool = False,
    ) -> ActuatorCommand:
        curvature = self.world.curvature_at(float(xf[State.s]))
        if plan is not None and not (self._minimal_risk and not self._planner_usable):
            try:
                command = self.controller.command(
                    t, xf, float(x_plant[PlantState.STEER]), plan, curvature,
                    None if slip_modulated else (float(x_plant[PlantState.TORQUE_FRONT]),
                                                 float(x_plant[PlantState.TORQUE_REAR])),
                ).clipped(self.params)
                return self._probe_command(t, xf, command)
            except Exception as exc:
                self._recorder.event(t, "controller_error", f"{type(exc).__name__}: {exc}")
                self._enter_minimal_risk(t, "the controller failed")
        mu_hat = np.asarray(estimate.mu_hat, dtype=float)
        mu = float(mu_hat[0]) if mu_hat.size and np.isfinite(mu_hat[0]) else self.safety.mu_floor
        return minimal_risk_command(
            xf, curvature, self.params, min(max(mu, self.safety.mu_floor), 2.0),
            self.safety.minimal_risk_decel_fraction,
        )

    def _probe_command(self, t: float, xf: np.ndarray, command: ActuatorCommand) -> ActuatorCommand:
        """While probing: the controller's steering, the probe's braking (or harder)."""
        prober = self._prober
        if not prober.active:
            return command
        speed = float(np.hypot(xf[State.vx], xf[State.vy]))
        why = prober.reason_to_stop(t, speed, self._local_available)
        if why is not None:
            lost = prober.stop(t, speed)
            self._recorder.event(t, "probe_end", f"{why}; {lost:.2f} m/s lost")
            return command
        p = self.params
        force = p.mass_kg * prober.decel_mps2(t)
        share_front = p.cog_to_rear_axle_m / p.wheelbase_m
        r = p.wheel_radius_m
        return ActuatorCommand(
            command.steer_rad,
            min(command.torque_front_nm, -share_front * force * r),
            min(command.torque_rear_nm, -(1.0 - share_front) * force * r),
        ).clipped(p)

    def _mode(
        self, obstacles: Sequence[PlannerObstacle], xf: np.ndarray, estimate: FrictionEstimate
    ) -> PlanningMode:
        if obstacles and self.emergency_on_obstacle:
            return "emergency"
        return obstacle_mode(
            obstacles, xf, self.estimate_grid_m, estimate.mu_hat, self.lane_bounds_m,
            self.params, self.obstacle_response, braking=self._last_mode == "emergency",
        )

    def _warm_up(self, steps: int) -> None:
        if steps <= 0:
            return
        x_plant = self.plant.x
        xf = self.world.frenet_state(x_plant)
        s_ego = float(xf[State.s])
        s_abs = s_ego + self.estimate_grid_m
        # The local estimator has seen the tires rolling freely at the start.
        self.sensors.observe(0.0, 0.0, 0.0, *self.world.friction_under_axles(x_plant, self.params))
        estimate = step_source(
            self.friction, self.sensors, self.estimate_grid_m, self.world.friction(s_abs), 0.0,
            t_s=0.0, channels=self._channels,
        )
        for k in range(steps):
            self._plan(xf, -(steps - k) / self.rates.planner_hz, s_ego, estimate, [], "cruise")

    def _plan(
        self,
        xf: np.ndarray,
        t: float,
        s_anchor_m: float,
        estimate: FrictionEstimate,
        obstacles: Sequence[PlannerObstacle],
        mode: PlanningMode,
    ) -> Plan:
        grid_abs = s_anchor_m + self.estimate_grid_m
        mu_hat_grid = np.asarray(estimate.mu_hat, dtype=float)

        def mu_hat_of_s(s: np.ndarray) -> np.ndarray:
            # Beyond the camera's range the last estimate is held (TAMP framework).
            return np.interp(np.asarray(s, dtype=float), grid_abs, mu_hat_grid)

        return self.planner.step(
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
            front_force_n=self._front_force_n,
        )


def _describe(fault: Fault) -> str:
    text = f"{fault.kind} from {fault.start_s:g} s for {fault.duration_s:g} s"
    return text + (f", delay {fault.delay_s:g} s" if fault.delay_s else "")
