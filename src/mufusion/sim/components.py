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
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from mufusion.configurations import FrictionSource
from mufusion.planner import Plan, PlannerMemory, PlannerObstacle
from mufusion.planner.ocp import PlannerMode
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
    ) -> Plan: ...

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
