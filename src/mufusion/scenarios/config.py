"""Scenario configuration: one validated (pydantic) schema per scenario kind.

A scenario is a :class:`TurnScenario`, a :class:`PopupScenario` or a
:class:`~mufusion.scenarios.road_kind.RoadScenario` (any road), told apart by ``name``; each
kind has only the keys it uses (a turn has no obstacle, a pop-up no turn), so a key that would do
nothing is an error, never silently ignored. Each kind builds its own road
(:meth:`TurnScenario.build_road`), says where the vehicle starts on it (``start_s_m``) and where
the planner may drive (``drivable_d_m``), so no code branches on the scenario's name.
"""

from __future__ import annotations

from typing import Annotated, Literal, TypeVar

import numpy as np
from pydantic import Field, model_validator

from mufusion.road import FrictionMap, Obstacle, Road, straight_road, turn_road
from mufusion.scenarios.base import Scenario
from mufusion.scenarios.road_kind import RoadScenario
from mufusion.scenarios.sections import (
    FOOTPRINT_MARGIN_M,
    InitialPerturbation,
    NonNegFloat,
    ObstacleConfig,
    RoadConfig,
    TurnFriction,
    TurnGeometry,
    UniformFriction,
)
from mufusion.vehicle.params import VehicleParams

_S = TypeVar("_S", bound=Scenario)


class _PaperScenario(Scenario):
    """The paper's two kinds: a ``[road]`` of a straight approach and one lane width."""

    road: RoadConfig = RoadConfig()

    @property
    def start_s_m(self) -> float:
        """The vehicle's start progress ``s0`` [m] (the paper's "s = 0")."""
        return self.road.approach_m


class TurnScenario(_PaperScenario):
    """Paper scenario 1: a turn on low friction after high friction; keep the lane."""

    name: Literal["turn"]
    turn: TurnGeometry = TurnGeometry()
    friction: TurnFriction = TurnFriction()

    def build_road(self, params: VehicleParams) -> Road:
        """Straight, the turn (clothoids, arc), straight; friction steps at the change point."""
        s0 = self.start_s_m
        friction = FrictionMap.step(
            self.friction.mu_before, self.friction.mu_turn, s0 + self.friction.change_ahead_m
        )
        return turn_road(
            radius_m=self.turn.radius_m,
            approach_m=s0 + self.turn.start_ahead_m,
            exit_m=self.road.length_m,
            clothoid_m=self.turn.clothoid_m,
            direction=self.turn.direction,
            lane_width_m=self.road.lane_width_m,
            friction=friction,
            angle_rad=self.turn.angle_rad,
        )

    def drivable_d_m(self) -> tuple[float, float]:
        """Where the vehicle may drive: its own lane (the opposing lane is not for driving)."""
        w = self.road.lane_width_m
        return -0.5 * w, 0.5 * w


class PopupScenario(_PaperScenario):
    """Paper scenario 2: an obstacle appears ahead in the lane; avoid it."""

    name: Literal["popup"]
    friction: UniformFriction = UniformFriction()
    obstacle: ObstacleConfig
    emergency_on_obstacle: bool = False
    """Switch the planner to its emergency (stop) mode when an obstacle appears."""
    comparison_time_s: NonNegFloat = 0.5

    @model_validator(mode="after")
    def _obstacle_on_the_road(self) -> PopupScenario:
        # Where a cruise at the initial speed puts it, the obstacle must still lie on the road.
        ahead_m = self.initial_speed_mps * self.obstacle.appear_at_s + self.obstacle.distance_m
        if ahead_m >= self.road.length_m:
            raise ValueError(
                "obstacle.appear_at_s must leave the obstacle on the road: initial_speed_mps × "
                f"appear_at_s + distance_m = {ahead_m:.1f} m, road.length_m = "
                f"{self.road.length_m:.1f} m")
        return self

    def build_road(self, params: VehicleParams) -> Road:
        """A straight two-lane road, the obstacle ``distance_m`` ahead of the vehicle's front
        when it appears: at once, or (``appear_at_s`` > 0) once the vehicle's front is
        ``distance_m`` before it, that much further down the road as a cruise at the initial
        speed covers in ``appear_at_s``."""
        s0, ob = self.start_s_m, self.obstacle
        front_m = params.cog_to_body_front_m
        cruise_m = self.initial_speed_mps * ob.appear_at_s
        obstacle = Obstacle(
            s_m=s0 + front_m + ob.distance_m + cruise_m,
            d_m=ob.lateral_offset_m,
            length_m=ob.length_m,
            width_m=ob.width_m,
            appear_at_ego_s_m=s0 + cruise_m if ob.appear_at_s > 0.0 else None,
            appear_at_time_s=0.0 if ob.appear_at_s == 0.0 else None,
        )
        return straight_road(
            s0 + self.road.length_m,
            lane_width_m=self.road.lane_width_m,
            friction=FrictionMap.uniform(self.friction.mu),
            obstacles=(obstacle,),
        )

    def drivable_d_m(self) -> tuple[float, float]:
        """Where the vehicle may drive: the whole road (both lanes) to evade."""
        w = self.road.lane_width_m
        return -0.5 * w, 1.5 * w


AnyScenario = TurnScenario | PopupScenario | RoadScenario
"""A validated scenario of any kind."""

ScenarioConfig = Annotated[AnyScenario, Field(discriminator="name")]
"""A validated scenario of any kind, told apart by ``name`` (pydantic's tagged union)."""

SCENARIO_KINDS: dict[str, type[TurnScenario] | type[PopupScenario] | type[RoadScenario]] = {
    "turn": TurnScenario,
    "popup": PopupScenario,
    "road": RoadScenario,
}


def perturbed(cfg: _S, rng: np.random.Generator) -> _S:
    """The scenario with its initial-state perturbation drawn from ``rng`` and applied.

    Returns ``cfg`` itself when :attr:`Scenario.perturbation` is all zero (nothing is drawn).
    Otherwise three uniform draws, always in the order speed, lateral offset, heading (a zero
    half-width scales its draw to nothing, so the others do not depend on it), move
    ``initial_speed_mps``, ``initial_lateral_offset_m`` and ``initial_heading_error_rad``; the
    cruise speed stays the scenario's (``reference_speed_mps`` is fixed to it), and the returned
    scenario has no perturbation left, so it is the concrete start that was driven (its
    ``model_dump`` goes into the run's metadata, and the feasibility oracle classifies its speed).

    Examples
    --------
    >>> import numpy as np
    >>> from mufusion.scenarios.loading import load_scenario
    >>> cfg = load_scenario("turn", ["perturbation.lateral_offset_m=0.2"])
    >>> a = perturbed(cfg, np.random.default_rng(1))
    >>> abs(a.initial_lateral_offset_m) <= 0.2, a.initial_speed_mps == cfg.initial_speed_mps
    (True, True)
    >>> plain = load_scenario("turn")  # no perturbation: the scenario itself, nothing drawn
    >>> perturbed(plain, np.random.default_rng(1)) is plain
    True
    """
    pert = cfg.perturbation
    if not pert.active:
        return cfg
    unit = rng.uniform(-1.0, 1.0, size=3)
    return cfg.model_copy(update={
        "reference_speed_mps": cfg.cruise_speed_mps,
        "initial_speed_mps": cfg.initial_speed_mps + pert.speed_mps * float(unit[0]),
        "initial_lateral_offset_m": (
            cfg.initial_lateral_offset_m + pert.lateral_offset_m * float(unit[1])
        ),
        "initial_heading_error_rad": (
            cfg.initial_heading_error_rad + pert.heading_rad * float(unit[2])
        ),
        "perturbation": InitialPerturbation(),
    })


def planner_lane_bounds_m(cfg: AnyScenario, params: VehicleParams) -> tuple[float, float]:
    """Bounds on the planner's lateral offset: the drivable band's edges shrunk by half the
    vehicle width (TAMP framework) and by :data:`FOOTPRINT_MARGIN_M`."""
    lo, hi = cfg.drivable_d_m()
    half = 0.5 * params.width_m + FOOTPRINT_MARGIN_M
    return lo + half, hi - half
