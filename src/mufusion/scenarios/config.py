"""Scenario configuration: one validated (pydantic) schema per scenario kind.

A scenario is a :class:`TurnScenario` or a :class:`PopupScenario`, told apart by ``name``; each
kind has only the keys it uses (a turn has no obstacle, a pop-up no turn), so a key that would do
nothing is an error, never silently ignored. Each kind builds its own road
(:meth:`TurnScenario.build_road`) and says where the planner may drive, so no code branches on
the scenario's name.
"""

from __future__ import annotations

from typing import Annotated, Literal, TypeVar

import numpy as np
from pydantic import Field, model_validator

from mufusion.planner.safety import SafetySettings
from mufusion.road import FrictionMap, Obstacle, Road, straight_road, turn_road
from mufusion.scenarios.sections import (
    FOOTPRINT_MARGIN_M,
    EstimationConfig,
    InitialPerturbation,
    NonNegFloat,
    ObstacleConfig,
    PlannerSettings,
    RoadConfig,
    SimSettings,
    TurnFriction,
    TurnGeometry,
    UniformFriction,
    VehicleName,
    _Strict,
)
from mufusion.scenarios.shared_section import SharedSection
from mufusion.sim.faults import Fault
from mufusion.sim.settings import LaneRecoverySettings, LoopRates, ProbingSettings
from mufusion.vehicle.params import VehicleParams


class _Scenario(_Strict):
    """What every scenario kind has: vehicle, speeds, duration, seed, estimation, solver."""

    description: str = ""
    vehicle: VehicleName = "truck"
    initial_speed_mps: Annotated[float, Field(gt=0.0, le=40.0)] = 12.0
    initial_lateral_offset_m: Annotated[float, Field(ge=-1.0, le=1.0, allow_inf_nan=False)] = 0.0
    """Start offset of the centre of gravity from the lane centre [m], left positive."""
    initial_heading_error_rad: Annotated[
        float, Field(ge=-0.2, le=0.2, allow_inf_nan=False)
    ] = 0.0
    """Start heading relative to the lane [rad], left positive."""
    perturbation: InitialPerturbation = InitialPerturbation()
    """Seeded draws around the initial state (speed, offset, heading); none by default."""
    reference_speed_mps: Annotated[float, Field(gt=0.0, le=40.0)] | None = None
    """Cruise speed the planner tracks; defaults to the initial speed."""
    duration_s: Annotated[float, Field(gt=0.0, le=120.0)] = 10.0
    seed: Annotated[int, Field(ge=0)] = 0
    comparison_time_s: NonNegFloat = 0.0
    """Instant whose plan and estimate are compared between configurations (the paper's
    Fig. 3k/4k): planned-force utilisation against GT is measured there."""
    road: RoadConfig = RoadConfig()
    estimation: EstimationConfig = EstimationConfig()
    planner: PlannerSettings = PlannerSettings()
    sim: SimSettings = SimSettings()
    faults: list[Fault] = Field(default_factory=list)
    """Faults to inject (``[[faults]]`` tables: kind, start_s, duration_s, delay_s)."""
    safety: SafetySettings = SafetySettings()
    """How the loop reacts to missing, stale or failing parts (:mod:`mufusion.sim.faults`)."""
    probing: ProbingSettings = ProbingSettings()
    """Active friction probing (beyond the paper, :mod:`mufusion.sim.supervision`)."""
    shared: SharedSection = SharedSection()
    """Shared friction reports, read by F+shared and F-safe+shared (decision 0060)."""
    lane_recovery: LaneRecoverySettings = LaneRecoverySettings()
    """Relaxing μ̂ towards the posterior mean when no friction-limited plan keeps the lane."""

    @model_validator(mode="after")
    def _check_common(self) -> _Scenario:
        for i, fault in enumerate(self.faults):
            if fault.start_s >= self.duration_s:
                raise ValueError(
                    f"faults.{i}.start_s must be before duration_s = {self.duration_s} s "
                    f"(a fault after the end does nothing), got {fault.start_s}"
                )
        pert = self.perturbation
        if self.initial_speed_mps - pert.speed_mps <= 0.0:
            raise ValueError(
                f"perturbation.speed_mps must be below initial_speed_mps = "
                f"{self.initial_speed_mps} m/s (a draw would start at rest or reversing), "
                f"got {pert.speed_mps}"
            )
        if abs(self.initial_lateral_offset_m) + pert.lateral_offset_m > 1.0:
            raise ValueError(
                "perturbation.lateral_offset_m plus |initial_lateral_offset_m| must be at most "
                f"1.0 m (the start stays near the lane centre), got {pert.lateral_offset_m} + "
                f"{abs(self.initial_lateral_offset_m)}"
            )
        if abs(self.initial_heading_error_rad) + pert.heading_rad > 0.2:
            raise ValueError(
                "perturbation.heading_rad plus |initial_heading_error_rad| must be at most "
                f"0.2 rad, got {pert.heading_rad} + {abs(self.initial_heading_error_rad)}"
            )
        if self.comparison_time_s >= self.duration_s:
            raise ValueError(
                f"duration_s must exceed comparison_time_s = {self.comparison_time_s} s "
                f"(the instant the runs are compared at), got {self.duration_s}"
            )
        if self.planner.stiffness == "from_mu_hat" and self.sim.tires == "default":
            raise ValueError(
                "planner.stiffness = 'from_mu_hat' follows μ̂ through the plant's tire table, but "
                "sim.tires = 'default' has a stiffness independent of μ; set sim.tires to "
                "'authors' or 'authors_interpolated' (or planner.stiffness = 'fixed')"
            )
        try:
            self.rates()
        except ValueError as err:  # re-raised with the scenario's key names
            raise ValueError(
                str(err)
                .replace("plant_hz", "sim.plant_rate_hz")
                .replace("controller_hz", "sim.controller_rate_hz")
                .replace("planner_hz", "planner.rate_hz")
            ) from None
        return self

    @property
    def cruise_speed_mps(self) -> float:
        return self.reference_speed_mps or self.initial_speed_mps

    def rates(self) -> LoopRates:
        """The loop's component rates."""
        return LoopRates(self.sim.plant_rate_hz, self.sim.controller_rate_hz, self.planner.rate_hz)

    @property
    def start_s_m(self) -> float:
        """The vehicle's start progress ``s0`` [m] (the paper's "s = 0")."""
        return self.road.approach_m


_S = TypeVar("_S", bound=_Scenario)


class TurnScenario(_Scenario):
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


class PopupScenario(_Scenario):
    """Paper scenario 2: an obstacle appears ahead in the lane; avoid it."""

    name: Literal["popup"]
    friction: UniformFriction = UniformFriction()
    obstacle: ObstacleConfig
    emergency_on_obstacle: bool = False
    """Switch the planner to its emergency (stop) mode when an obstacle appears."""
    comparison_time_s: NonNegFloat = 0.5

    def build_road(self, params: VehicleParams) -> Road:
        """A straight two-lane road, the obstacle ``distance_m`` ahead of the vehicle's front."""
        s0, ob = self.start_s_m, self.obstacle
        front_m = params.cog_to_body_front_m
        obstacle = Obstacle(
            s_m=s0 + front_m + ob.distance_m,
            d_m=ob.lateral_offset_m,
            length_m=ob.length_m,
            width_m=ob.width_m,
            appear_at_time_s=ob.appear_at_s,
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


ScenarioConfig = Annotated[TurnScenario | PopupScenario, Field(discriminator="name")]
"""A validated scenario of either kind."""

SCENARIO_KINDS: dict[str, type[TurnScenario] | type[PopupScenario]] = {
    "turn": TurnScenario,
    "popup": PopupScenario,
}


def perturbed(cfg: _S, rng: np.random.Generator) -> _S:
    """The scenario with its initial-state perturbation drawn from ``rng`` and applied.

    Returns ``cfg`` itself when :attr:`_Scenario.perturbation` is all zero (nothing is drawn).
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


def planner_lane_bounds_m(
    cfg: TurnScenario | PopupScenario, params: VehicleParams
) -> tuple[float, float]:
    """Bounds on the planner's lateral offset: the drivable band's edges shrunk by half the
    vehicle width (TAMP framework) and by :data:`FOOTPRINT_MARGIN_M`."""
    lo, hi = cfg.drivable_d_m()
    half = 0.5 * params.width_m + FOOTPRINT_MARGIN_M
    return lo + half, hi - half
