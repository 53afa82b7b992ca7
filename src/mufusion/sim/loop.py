"""The closed loop: plant, controller interface, planner and friction estimation at their own rates.

Each component exposes one step-like call, so one tick of the loop reads in a few lines
(do-mpc's ``u = mpc.make_step(x); y = sim.make_step(u)``): the planner runs every
``plant_hz / planner_hz`` plant steps with the current friction estimate, the controller every
``plant_hz / controller_hz`` steps, the plant every step with the true friction under each axle.
What happens is written by a :class:`~mufusion.sim.recorder.Recorder` into one
:class:`~mufusion.sim.log.RunLog`; the loop itself only steps the world.
"""

from __future__ import annotations

import dataclasses
import logging
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner import Plan, PlannerObstacle
from mufusion.planner.ocp import PlannerMode
from mufusion.sim.faults import Fault, SafetySettings, active_kinds, estimate_delay_s
from mufusion.sim.log import RunLog
from mufusion.sim.minimal_risk import minimal_risk_command
from mufusion.sim.recorder import Recorder
from mufusion.sim.records import RunMeta
from mufusion.sim.world import World
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State
from mufusion.vehicle.plant import PlantOutput, PlantState

_log = logging.getLogger(__name__)

PlanningMode = PlannerMode
MINIMAL_RISK_MODE: PlanningMode = "minimal_risk"
"""The planner's mode during the minimal-risk manoeuvre: brake to a stop in lane."""


@dataclass(frozen=True)
class LoopRates:
    """Rates of the loop's components [Hz]; the plant rate must be a multiple of the others.

    Raises
    ------
    ValueError
        If a rate is not positive and finite, or the rates do not divide into whole steps
        (the message names the rate).
    """

    plant_hz: float = 200.0
    controller_hz: float = 50.0
    planner_hz: float = 10.0

    def __post_init__(self) -> None:
        for name in ("plant_hz", "controller_hz", "planner_hz"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0:
                raise ValueError(f"{name} must be a positive rate in Hz, got {value!r}")
        _check_divides("controller_hz", self.controller_hz, "plant_hz", self.plant_hz)
        _check_divides("planner_hz", self.planner_hz, "plant_hz", self.plant_hz)
        _check_divides("planner_hz", self.planner_hz, "controller_hz", self.controller_hz)

    @property
    def controller_every(self) -> int:
        return round(self.plant_hz / self.controller_hz)

    @property
    def planner_every(self) -> int:
        return round(self.plant_hz / self.planner_hz)


def _check_divides(name: str, value: float, base_name: str, base: float) -> None:
    ratio = base / value
    if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
        raise ValueError(
            f"{name} must divide {base_name}={base:g} Hz into whole steps, got {value:g} Hz"
        )


class FrictionSource(Protocol):
    """A friction estimate over the grid ahead, once per planning step.

    The interface of :class:`~mufusion.configurations.FrictionConfiguration`; a source of your
    own plugs into :class:`ClosedLoop` by implementing these two calls.
    """

    def step(
        self,
        s_ahead_m: np.ndarray,
        mu_true_ahead: np.ndarray,
        utilization: float,
        *,
        camera_ok: bool = True,
        t_s: float | None = None,
    ) -> FrictionEstimate:
        """The estimate at distances ``s_ahead_m`` ahead (``mu_true_ahead`` is the truth there,
        ``utilization`` the peak realised tire utilization since the last step; ``camera_ok``
        False while the camera is out)."""
        ...

    def observe(
        self,
        t_s: float,
        utilization_front: float,
        utilization_rear: float,
        mu_front: float,
        mu_rear: float,
    ) -> None:
        """Called after every plant step with the realised utilization and true μ per axle."""
        ...


class Planner(Protocol):
    """A motion planner with :class:`~mufusion.planner.TractionAdaptivePlanner`'s step."""

    def step(
        self,
        x0: np.ndarray,
        t_s: float,
        curvature_of_s: Callable[[np.ndarray], np.ndarray],
        mu_hat_of_s: Callable[[np.ndarray], np.ndarray],
        obstacles: Sequence[PlannerObstacle] = (),
        mode: PlanningMode = "cruise",
        reference_speed_mps: float = 10.0,
        reference_d_m: float = 0.0,
        lane_d_min_m: float | None = None,
        lane_d_max_m: float | None = None,
    ) -> Plan: ...


class Controller(Protocol):
    """Turns the current plan into actuator commands."""

    def command(
        self,
        t_s: float,
        x_frenet: np.ndarray,
        steer_rad_now: float,
        plan: Plan,
        curvature_1pm_now: float = 0.0,
    ) -> ActuatorCommand: ...


class PlantModel(Protocol):
    """The simulated vehicle (see :class:`~mufusion.vehicle.plant.Plant`)."""

    @property
    def x(self) -> np.ndarray: ...

    def step(
        self, command: ActuatorCommand, mu_front: float, mu_rear: float
    ) -> PlantOutput: ...


@dataclass(frozen=True)
class _Anchored:
    """A friction estimate and where and when it was made."""

    t_s: float
    s_m: float
    estimate: FrictionEstimate


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

    Notes
    -----
    Reactions, each logged as an event (table ``events``):

    - The friction estimate handed to the planner must be finite and at most
      ``safety.max_estimate_age_s`` old. Otherwise the last estimate that was (re-anchored at
      the absolute positions it was made for) is used while it is young enough, else
      ``safety.mu_floor`` over the whole horizon.
    - A planning step without a usable plan (the solver failed, the planner raised or was made
      to fail) keeps the previous plan. After ``safety.max_consecutive_fallbacks`` such steps in
      a row, or at once when the friction source raises, the vehicle enters the minimal-risk
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
        self._history: deque[_Anchored] = deque(maxlen=64)
        self._last_valid: _Anchored | None = None
        self._consecutive_fallbacks = 0
        self._minimal_risk = False
        self._planner_usable = True
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
        for i in range(n_steps + 1):
            t = i * dt
            x_plant = self.plant.x
            control_tick = i % rates.controller_every == 0
            if control_tick:
                # The planner's rate divides the controller's, so this also serves planning steps.
                xf = self.world.frenet_state(x_plant)
                s_ego = float(xf[State.s])

            if i % rates.planner_every == 0:
                plan_step += 1
                estimate, plan = self._planning_step(plan_step, t, xf, util_window, plan)
                util_window = 0.0
                if progress:
                    progress(t)

            if control_tick:
                assert estimate is not None  # a planning step comes first (i = 0)
                command = self._command(t, xf, x_plant, plan, estimate)
                status = self._recorder.tick(
                    t, x_plant, xf, command, estimate.local_available, last,
                    "minimal_risk" if self._minimal_risk else "plan",
                )
                if status.in_collision or s_ego >= road_end:
                    break

            mu_front, mu_rear = self.world.friction_under_axles(x_plant, self.params)
            last = self.plant.step(command, mu_front, mu_rear)
            util_window = max(util_window, last.utilization_front, last.utilization_rear)
            self.friction.observe(
                t + dt, last.utilization_front, last.utilization_rear, mu_front, mu_rear
            )

    # -- one planning step ------------------------------------------------------------------
    def _planning_step(
        self, step: int, t: float, xf: np.ndarray, utilization: float, previous: Plan | None
    ) -> tuple[FrictionEstimate, Plan | None]:
        s_ego = float(xf[State.s])
        kinds = active_kinds(self.faults, t)
        estimate, source, age = self._usable_estimate(t, s_ego, utilization, kinds)
        obstacles = self.world.planner_obstacles(t, s_ego, behind_m=self.params.length_m)
        mode = MINIMAL_RISK_MODE if self._minimal_risk else self._mode(obstacles)
        started = time.perf_counter()
        plan: Plan | None = None
        reason = ""
        if "solver_failure" in kinds:
            reason = "injected solver failure"
        else:
            try:
                plan = self._plan(xf, t, s_ego, estimate, obstacles, mode)
            except Exception as exc:  # a planner that raises degrades, never ends the run
                reason = f"planner raised {type(exc).__name__}: {exc}"
                self._recorder.event(t, "planner_error", reason)
        step_ms = 1e3 * (time.perf_counter() - started)
        failed = plan is None or plan.fallback
        self._planner_usable = not failed
        self._consecutive_fallbacks = self._consecutive_fallbacks + 1 if failed else 0
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

    def _usable_estimate(
        self, t: float, s_ego: float, utilization: float, kinds: frozenset[str]
    ) -> tuple[FrictionEstimate, str, float]:
        """The estimate the planner gets, where it came from, and its age [s]."""
        fresh = self._estimate(t, s_ego, utilization, kinds)
        if fresh is not None:
            self._history.append(_Anchored(t, s_ego, fresh))
        candidate, source = (None if fresh is None else _Anchored(t, s_ego, fresh)), "current"
        delay = estimate_delay_s(self.faults, t)
        if delay > 0.0 and self._history:
            older = [a for a in self._history if a.t_s <= t - delay + 1e-9]
            candidate, source = (older[-1] if older else self._history[0]), "delayed"
        if candidate is not None and "estimate_nan" in kinds:
            nan = np.full(np.shape(candidate.estimate.mu_hat), np.nan)
            candidate = dataclasses.replace(
                candidate, estimate=dataclasses.replace(candidate.estimate, mu_hat=nan)
            )
        max_age = self.safety.max_estimate_age_s
        if candidate is not None and _finite(candidate) and t - candidate.t_s <= max_age + 1e-9:
            if source == "current":
                self._last_valid = candidate
                return candidate.estimate, source, 0.0
            return self._on_grid(candidate, s_ego), source, t - candidate.t_s
        why = "missing" if candidate is None else (
            "not finite" if not _finite(candidate) else f"{t - candidate.t_s:.2f} s old"
        )
        last = self._last_valid
        if last is not None and t - last.t_s <= max_age + 1e-9:
            self._recorder.event(t, "estimate_fallback", f"estimate {why}: last valid one used")
            return self._on_grid(last, s_ego), "last_valid", t - last.t_s
        self._recorder.event(
            t, "estimate_fallback", f"estimate {why}: μ = {self.safety.mu_floor} assumed"
        )
        floor = np.full(self.estimate_grid_m.size, self.safety.mu_floor)
        local = fresh if fresh is not None else (last.estimate if last is not None else None)
        return (
            FrictionEstimate(
                s_m=self.estimate_grid_m, mu_hat=floor,
                local_available=bool(local and local.local_available),
                local_mu=None if local is None else local.local_mu,
            ),
            "floor",
            np.inf if last is None else t - last.t_s,
        )

    def _estimate(
        self, t: float, s_ego: float, utilization: float, kinds: frozenset[str]
    ) -> FrictionEstimate | None:
        s_abs = s_ego + self.estimate_grid_m
        mu_true = self.world.friction(s_abs)
        util = 0.0 if "local_dropout" in kinds else utilization
        # An absent camera, or one whose values are NaN, gives nothing usable: discarded.
        camera_ok = not ({"camera_dropout", "camera_nan"} & kinds)
        try:
            return self.friction.step(
                self.estimate_grid_m, mu_true, util, camera_ok=camera_ok, t_s=t
            )
        except Exception as exc:
            self._recorder.event(t, "friction_source_error", f"{type(exc).__name__}: {exc}")
            self._enter_minimal_risk(t, "the friction source failed")
            return None

    def _on_grid(self, anchored: _Anchored, s_ego: float) -> FrictionEstimate:
        """An older estimate re-sampled on the grid ahead of ``s_ego`` (by absolute s)."""
        grid_abs = s_ego + self.estimate_grid_m
        mu_hat = np.interp(grid_abs, anchored.s_m + self.estimate_grid_m,
                           np.asarray(anchored.estimate.mu_hat, dtype=float))
        return dataclasses.replace(
            anchored.estimate, s_m=self.estimate_grid_m, mu_hat=mu_hat, fused=None, data=None
        )

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
    ) -> ActuatorCommand:
        curvature = float(self.world.curvature(np.array([float(xf[State.s])]))[0])
        if plan is not None and not (self._minimal_risk and not self._planner_usable):
            try:
                return self.controller.command(
                    t, xf, float(x_plant[PlantState.STEER]), plan, curvature
                ).clipped(self.params)
            except Exception as exc:
                self._recorder.event(t, "controller_error", f"{type(exc).__name__}: {exc}")
                self._enter_minimal_risk(t, "the controller failed")
        mu_hat = np.asarray(estimate.mu_hat, dtype=float)
        mu = float(mu_hat[0]) if mu_hat.size and np.isfinite(mu_hat[0]) else self.safety.mu_floor
        return minimal_risk_command(
            xf, curvature, self.params, min(max(mu, self.safety.mu_floor), 2.0),
            self.safety.minimal_risk_decel_fraction,
        )

    def _mode(self, obstacles: Sequence[PlannerObstacle]) -> PlanningMode:
        if not obstacles:
            return "cruise"
        return "emergency" if self.emergency_on_obstacle else "evade"

    def _warm_up(self, steps: int) -> None:
        if steps <= 0:
            return
        x_plant = self.plant.x
        xf = self.world.frenet_state(x_plant)
        s_ego = float(xf[State.s])
        s_abs = s_ego + self.estimate_grid_m
        # The local estimator has seen the tires rolling freely at the start.
        self.friction.observe(0.0, 0.0, 0.0, *self.world.friction_under_axles(x_plant, self.params))
        estimate = self.friction.step(
            self.estimate_grid_m, self.world.friction(s_abs), 0.0, t_s=0.0
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
        )


def _finite(anchored: _Anchored) -> bool:
    return bool(np.all(np.isfinite(np.asarray(anchored.estimate.mu_hat, dtype=float))))


def _describe(fault: Fault) -> str:
    text = f"{fault.kind} from {fault.start_s:g} s for {fault.duration_s:g} s"
    return text + (f", delay {fault.delay_s:g} s" if fault.delay_s else "")
