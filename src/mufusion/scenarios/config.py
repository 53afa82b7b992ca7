"""Scenario configuration: one validated (pydantic) schema per scenario kind.

A scenario is a :class:`TurnScenario` or a :class:`PopupScenario`, told apart by ``name``; each
kind has only the keys it uses (a turn has no obstacle, a pop-up no turn), so a key that would do
nothing is an error, never silently ignored. Each kind builds its own road
(:meth:`TurnScenario.build_road`) and says where the planner may drive, so no code branches on
the scenario's name.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal, TypeVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from mufusion.estimators import ErrorModel
from mufusion.planner.ocp import PlannerConfig
from mufusion.planner.safety import SafetySettings
from mufusion.road import FrictionMap, Obstacle, Road, straight_road, turn_road
from mufusion.sim.faults import Fault
from mufusion.sim.loop import LoopRates
from mufusion.sim.supervision import LaneRecoverySettings, ProbingSettings
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.slip_control import SlipControlSettings
from mufusion.vehicle.surface_tires import (
    AUTHORS_TIRES,
    AUTHORS_TIRES_INTERPOLATED,
    SurfaceTireTable,
)

VehicleName = Literal["truck", "car"]
"""The vehicle presets (:data:`mufusion.vehicle.params.PRESETS`; a test keeps them in step)."""

PositiveFloat = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
NonNegFloat = Annotated[float, Field(ge=0.0, allow_inf_nan=False)]
Friction = Annotated[float, Field(gt=0.0, le=1.5, allow_inf_nan=False)]

FOOTPRINT_MARGIN_M = 0.1
"""Extra room the planner keeps between its reference point's bounds and the lane edges [m]:
the planner bounds its reference point (and takes a curve's bulge off the outer side); the
footprint's corners reach further still when the vehicle is yawed against the lane, and the plant
tracks the plan to about a decimetre at the friction limit."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, validate_default=True)

    @model_validator(mode="before")
    @classmethod
    def _no_bool_for_numbers(cls, data: Any) -> Any:
        # Pydantic would read `true` as 1.0: a boolean is never a number here.
        if isinstance(data, dict):
            for key, value in data.items():
                field = cls.model_fields.get(key)
                if field is not None and isinstance(value, bool) and field.annotation is not bool:
                    raise ValueError(
                        f"{key}: expected a number, got the boolean {str(value).lower()}"
                    )
        return data


class RoadConfig(_Strict):
    lane_width_m: Annotated[float, Field(ge=2.5, le=5.0)] = 3.5
    approach_m: Annotated[float, Field(ge=10.0, le=500.0)] = 60.0
    """Straight road behind the vehicle's start position (room for the start and the look-back)."""
    length_m: Annotated[float, Field(ge=50.0, le=2000.0)] = 300.0
    """Total length of a straight road (``popup``) or of the straight after the turn (``turn``)."""


class TurnGeometry(_Strict):
    radius_m: Annotated[float, Field(ge=10.0, le=500.0)] = 28.0
    angle_rad: Annotated[float, Field(gt=0.0, le=math.pi)] = math.pi / 2
    """Heading change of the whole turn, clothoids included [rad]."""
    direction: Literal["left", "right"] = "right"
    """Right-hand traffic: in a right turn the outside of the curve is the opposing lane."""
    start_ahead_m: Annotated[float, Field(ge=0.0, le=200.0)] = 20.0
    """Distance from the vehicle's start to the beginning of the curve (its entry clothoid)."""
    clothoid_m: Annotated[float, Field(ge=0.0, le=50.0)] = 5.0

    @model_validator(mode="after")
    def _clothoids_fit(self) -> TurnGeometry:
        if self.clothoid_m > self.radius_m * self.angle_rad:
            raise ValueError(
                f"clothoid_m must be <= radius_m * angle_rad = "
                f"{self.radius_m * self.angle_rad:.2f} m, got {self.clothoid_m}"
            )
        return self


class TurnFriction(_Strict):
    mu_before: Friction = 0.8
    """Friction before the change point."""
    mu_turn: Friction = 0.4
    """Friction from the change point on."""
    change_ahead_m: Annotated[float, Field(ge=-50.0, le=200.0)] = 0.0
    """Where the friction changes, relative to the vehicle's start (paper: at s = 0)."""


class UniformFriction(_Strict):
    mu: Friction = 1.0
    """Friction everywhere."""


class ObstacleConfig(_Strict):
    distance_m: Annotated[float, Field(gt=0.0, le=200.0)] = 20.0
    """Distance from the vehicle's front to the obstacle's centre when it appears."""
    lateral_offset_m: Annotated[float, Field(ge=-5.0, le=5.0)] = 0.0
    """Offset of the obstacle centre from the lane centre (left positive)."""
    length_m: PositiveFloat = 1.0
    width_m: PositiveFloat = 1.0
    appear_at_s: NonNegFloat = 0.0
    """Time at which it appears [s]."""


class EstimationConfig(_Strict):
    local_error: ErrorModel = "none"
    predictive_error: ErrorModel = "none"
    initial_local_mu: Friction | None = None
    """The local estimator's held value before it first becomes available; ``None``: what it
    measured (with its error model) on the road under the vehicle just before the run starts."""
    length_scale_m: Annotated[float, Field(gt=0.0, le=500.0)] | None = None
    """GP length scale; ``None`` keeps the fusion's default."""
    local_timing: Literal["paper", "authors"] = "paper"
    """When the slip-based estimator samples and publishes (``docs/estimators.md``): the paper's
    once per planning step, or the authors' 4 Hz front-axle samples with a 3-sample buffer."""
    class_table: Literal["paper", "authors"] = "paper"
    """The camera's surface classes: the paper's Table I or the authors' 0.3-wide classes."""


class PlannerSettings(_Strict):
    horizon_steps: Annotated[int, Field(ge=10, le=80)] = 40
    dt_s: Annotated[float, Field(gt=0.01, le=0.5)] = 0.1
    utilization_factor: Annotated[float, Field(gt=0.0, le=1.0)] = 0.9
    backend: Literal["acados", "casadi"] = "acados"
    use_sampling: bool = True
    rate_hz: Annotated[float, Field(ge=1.0, le=50.0)] = 10.0
    obstacle_margin_m: Annotated[float, Field(ge=0.0, le=3.0)] = 0.5
    """Room the planner keeps between the vehicle's side and an obstacle's side [m]."""
    stiffness: Literal["fixed", "from_mu_hat"] = "fixed"
    """Cornering stiffness of the planner's rear tire and the controller's inverse tire model:
    ``fixed`` (the vehicle's tire on every surface) or ``from_mu_hat`` (the plant's tire table,
    ``sim.tires``, at the estimate μ̂, as the authors' planner and controller computed it)."""
    curve_speed_reference: bool = True
    """Track the highest speed a point mass could hold along the road with μ̂ (curves and
    friction ahead, beyond the horizon) instead of the cruise speed alone
    (``docs/feasibility.md``, "GT at the limit")."""
    # Defaults from their one home, the planner's configuration.
    reference_braking_fraction: Annotated[float, Field(gt=0.0, le=1.0)] = (
        PlannerConfig.reference_braking_fraction)
    """Share of the friction the speed reference's braking ramps before a curve or a lower μ̂
    assume: 1 brakes as late as the friction polygon allows, less starts earlier and keeps the
    rest as a reserve (the curves' limit speeds are unchanged). The default 0.8 keeps a fifth
    of it for the braking that plans lose while they turn in (docs/decisions/0031, "A braking
    reserve in the speed reference")."""
    reference_regain_limit: bool = PlannerConfig.reference_regain_limit
    """In cruise, the speed reference regains speed from the vehicle's own no faster than the
    drive's acceleration cap on the g-g ellipse allows (less while cornering); ``false``: the
    reference jumps back to the profile's speed."""
    steering_rate_limit: bool = True
    """Plan the front lateral force as a state whose rate the steering actuator's rate limit
    bounds (:mod:`mufusion.planner.front_force`); ``false``: the forces are free inputs, as in
    the paper's planner."""
    load_transfer: bool = True
    """The friction polygons' radii follow the axle loads of each stage's own planned
    longitudinal forces (pitch load transfer inside the OCP); ``false``: the loads of the
    initial guess, as in the paper's planner."""
    brake_first: bool = True
    """Stop in front of an obstacle in the path whenever the friction the planner may use
    allows it (or no side has room), and evade only otherwise; ``false``: evade whenever an
    obstacle is active, as the paper (:mod:`mufusion.sim.obstacle_response`)."""


SimTires = Literal["default", "authors", "authors_interpolated"]
_SURFACE_TIRES: dict[str, SurfaceTireTable | None] = {
    "default": None,
    "authors": AUTHORS_TIRES,
    "authors_interpolated": AUTHORS_TIRES_INTERPOLATED,
}


class SimSettings(_Strict):
    plant_rate_hz: Annotated[float, Field(ge=200.0, le=2000.0)] = 200.0
    controller_rate_hz: Annotated[float, Field(ge=50.0, le=500.0)] = 50.0
    tires: SimTires = "default"
    """The plant's tires: ``default`` (stiffness independent of μ, only the peak scales) or the
    authors' surface-dependent Magic Formula sets per μ under each axle, by interval
    (``authors``) or interpolated (``authors_interpolated``); docs/estimators.md."""
    torque_compensation: bool = True
    """The controller compensates the wheel torques' lag: the forces the plan asks for one
    torque time constant ahead, plus feedback on the measured torques, so the lagging brakes
    deliver the plan's forces on time (:class:`mufusion.planner.controller.ControllerGains`);
    ``false``: the forces planned for now, as in the paper's controller."""
    abs: bool = True
    """Anti-lock braking in the vehicle (:mod:`mufusion.vehicle.slip_control`), as on every
    production car and truck; ``false`` shows what it does."""
    tcs: bool = True
    """Traction control in the vehicle (the same controller on drive torque)."""

    def surface_tires(self) -> SurfaceTireTable | None:
        """The plant's tire table (``None`` for the default tire)."""
        return _SURFACE_TIRES[self.tires]

    def slip_control(self) -> SlipControlSettings | None:
        """The vehicle's wheel-slip control (``None`` with ABS and TCS both off)."""
        if not (self.abs or self.tcs):
            return None
        return SlipControlSettings(abs_enabled=self.abs, tcs_enabled=self.tcs)


class InitialPerturbation(_Strict):
    """Half-widths of uniform draws around the initial state; the run's seed draws them.

    All zero (the default): the run starts exactly at the scenario's initial state and draws
    nothing. Otherwise each run draws a speed, a lateral offset and a heading error uniformly
    within ``± half-width`` of the scenario's values (:func:`perturbed`), so a campaign with
    ``seeds = N`` repeats every variant from N nearby starts: an outcome decided by centimetres
    shows up as a spread, not as one verdict.
    """

    speed_mps: Annotated[float, Field(ge=0.0, le=2.0, allow_inf_nan=False)] = 0.0
    lateral_offset_m: Annotated[float, Field(ge=0.0, le=0.5, allow_inf_nan=False)] = 0.0
    heading_rad: Annotated[float, Field(ge=0.0, le=0.1, allow_inf_nan=False)] = 0.0

    @property
    def active(self) -> bool:
        """Whether any half-width is above zero."""
        return self.speed_mps > 0.0 or self.lateral_offset_m > 0.0 or self.heading_rad > 0.0


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
    faults: list[Fault] = []
    """Faults to inject (``[[faults]]`` tables: kind, start_s, duration_s, delay_s)."""
    safety: SafetySettings = SafetySettings()
    """How the loop reacts to missing, stale or failing parts (:mod:`mufusion.sim.faults`)."""
    probing: ProbingSettings = ProbingSettings()
    """Active friction probing (beyond the paper, :mod:`mufusion.sim.supervision`)."""
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
