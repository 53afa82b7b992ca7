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
from typing import Literal, Protocol

import numpy as np

from mufusion.configurations import FrictionEstimate
from mufusion.planner import Plan, PlannerObstacle
from mufusion.sim.log import RunLog
from mufusion.sim.recorder import Recorder
from mufusion.sim.records import RunMeta
from mufusion.sim.world import World
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State
from mufusion.vehicle.plant import PlantOutput, PlantState

_log = logging.getLogger(__name__)

PlanningMode = Literal["cruise", "evade", "emergency"]


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
    """A friction estimate over the grid ahead, once per planning step (see
    :mod:`mufusion.configurations`)."""

    def step(
        self, s_ahead_m: np.ndarray, mu_true_ahead: np.ndarray, utilization: float
    ) -> FrictionEstimate: ...


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
        log = RunLog(self.meta)
        recorder = Recorder(log, self.world, self.params, self.estimate_grid_m)
        command = ActuatorCommand(0.0, 0.0, 0.0)
        plan_step = -1
        util_window = 0.0
        last: PlantOutput | None = None
        road_end = self.world.road_length_m - self.params.length_m
        self._warm_up(warmup_steps)

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
                estimate = self._estimate(s_ego, util_window)
                util_window = 0.0
                obstacles = self.world.planner_obstacles(t, s_ego, behind_m=self.params.length_m)
                mode = self._mode(obstacles)
                started = time.perf_counter()
                plan = self._plan(xf, t, estimate, obstacles, mode)
                step_ms = 1e3 * (time.perf_counter() - started)
                if not plan.ok:
                    _log.warning(
                        "planning step %d at t=%.2f s: solver status %s", plan_step, t, plan.status
                    )
                recorder.planning_step(plan_step, t, s_ego, plan, estimate, mode, step_ms)
                if progress:
                    progress(t)

            if control_tick:
                assert plan is not None and estimate is not None  # planned at i = 0
                steer_now = float(x_plant[PlantState.STEER])
                command = self.controller.command(
                    t, xf, steer_now, plan, float(self.world.curvature(np.array([s_ego]))[0])
                ).clipped(self.params)
                status = recorder.tick(
                    t, x_plant, xf, command, estimate.local_available, last, "plan"
                )
                if status.in_collision or s_ego >= road_end:
                    break

            mu_front, mu_rear = self.world.friction_under_axles(x_plant, self.params)
            last = self.plant.step(command, mu_front, mu_rear)
            util_window = max(util_window, last.utilization_front, last.utilization_rear)
        return log

    def _mode(self, obstacles: Sequence[PlannerObstacle]) -> PlanningMode:
        if not obstacles:
            return "cruise"
        return "emergency" if self.emergency_on_obstacle else "evade"

    def _warm_up(self, steps: int) -> None:
        xf = self.world.frenet_state(self.plant.x)
        estimate = self._estimate(float(xf[State.s]), 0.0)
        for k in range(steps):
            self._plan(xf, -(steps - k) / self.rates.planner_hz, estimate, [], "cruise")

    def _estimate(self, s_ego: float, utilization: float) -> FrictionEstimate:
        s_abs = s_ego + self.estimate_grid_m
        return self.friction.step(self.estimate_grid_m, self.world.friction(s_abs), utilization)

    def _plan(
        self,
        xf: np.ndarray,
        t: float,
        estimate: FrictionEstimate,
        obstacles: Sequence[PlannerObstacle],
        mode: PlanningMode,
    ) -> Plan:
        grid_abs = float(xf[State.s]) + self.estimate_grid_m
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
