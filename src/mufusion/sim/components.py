"""The closed loop's components as interfaces: what the loop calls on each, and their rates.

A friction source, planner, controller or plant of your own plugs into
:class:`~mufusion.sim.loop.ClosedLoop` by implementing the calls below (a friction source:
:class:`~mufusion.configurations.FrictionSource`, which reads a sensor frame); the package's own
(:class:`~mufusion.configurations.FrictionConfiguration`,
:class:`~mufusion.planner.TractionAdaptivePlanner`, :class:`~mufusion.planner.TrackingController`,
:class:`~mufusion.vehicle.plant.Plant`) are what the runner wires in.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Protocol

import numpy as np

from mufusion.configurations import FrictionSource
from mufusion.planner import Plan, PlannerMemory, PlannerObstacle, UnseenRoad
from mufusion.planner.config import PlannerMode
from mufusion.sim.settings import LoopRates  # the scenario schema reads it from there
from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.plant import PlantOutput, PlantStateVector

PlanningMode = PlannerMode

__all__ = [
    "Controller",
    "FrictionSource",
    "LoopRates",
    "Planner",
    "PlanningMode",
    "PlantModel",
]


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
        front_force_n: float | None = None,
        longitudinal_forces_n: tuple[float, float] | None = None,
        unseen_road: UnseenRoad | None = None,
    ) -> Plan:
        """One plan. ``unseen_road``: where the estimate ends and what its source declares
        beyond it (docs/decisions/0084); the loop passes it only to a step that takes it, and
        logs once (``unseen_road_ignored``) when a source declares one to a step that does not.
        """
        ...

    @property
    def memory(self) -> PlannerMemory:
        """What the next ``step`` continues from."""
        ...

    def restore(self, memory: PlannerMemory) -> None:
        """Continue from ``memory`` instead of the latest step (lane recovery's candidates)."""


class Controller(Protocol):
    """Turns the current plan into actuator commands."""

    def command(
        self,
        t_s: float,
        x_frenet: np.ndarray,
        steer_rad_now: float,
        plan: Plan,
        curvature_1pm_now: float = 0.0,
        torques_now_nm: tuple[float, float] | None = None,
    ) -> ActuatorCommand:
        """``torques_now_nm``: the measured (front, rear) wheel torques [N m], or ``None``."""
        ...


class PlantModel(Protocol):
    """The simulated vehicle (see :class:`~mufusion.vehicle.plant.Plant`)."""

    @property
    def x(self) -> np.ndarray: ...

    @property
    def state(self) -> PlantStateVector:
        """The state as named floats (what ``x`` holds, without building an array)."""
        ...

    def step(
        self, command: ActuatorCommand, mu_front: float, mu_rear: float
    ) -> PlantOutput: ...
