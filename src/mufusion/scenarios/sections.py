"""The sections of a scenario file (``[road]``, ``[turn]``, ``[friction]``, ``[obstacle]``,
``[estimation]``, ``[planner]``, ``[sim]``, ``[perturbation]``): one validated (pydantic) model
each, assembled into a scenario kind by :mod:`mufusion.scenarios.config`."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from mufusion.estimators import CAMERA_RANGE_M, ErrorModel
from mufusion.planner.ocp import PlannerConfig
from mufusion.vehicle.slip_control import SlipControlSettings
from mufusion.vehicle.stability_control import StabilityControlSettings
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
    """How long the vehicle drives before it appears [s]: it pops up when the vehicle's front
    is ``distance_m`` before it, placed ``initial_speed_mps × appear_at_s`` further down the road
    than at 0 (where a vehicle cruising at its initial speed is then). ``distance_m`` holds
    whatever the vehicle did meanwhile; only the time is that of a cruise (0: from the start)."""


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
    camera_range_m: Annotated[float, Field(ge=10.0, le=300.0)] = CAMERA_RANGE_M
    """How far ahead the camera classifies the road [m] (paper, Table I: 50 m); the estimate
    grid runs 0, 1, … up to it."""
    truth_reach_m: Annotated[float, Field(ge=10.0, le=1000.0)] | None = None
    """How far ahead GT (a source reading the truth) is told the true friction [m], at least
    ``camera_range_m``; ``None``: as far as the planner looks (300 m, docs/decisions/0071); the
    camera's range: as the estimators see the road."""
    safe_beyond_camera: bool = True
    """The safe configurations (F-safe, F-safe+shared) declare the lowest class possible beyond
    the camera's range, and the speed reference keeps curves there reachable on it
    (docs/decisions/0084); false: they hold the last value there, as the paper's do."""

    @model_validator(mode="after")
    def _truth_reaches_the_camera_range(self) -> EstimationConfig:
        if self.truth_reach_m is not None and self.truth_reach_m < self.camera_range_m:
            raise ValueError(f"truth_reach_m must be >= camera_range_m = "
                             f"{self.camera_range_m:g} m, got {self.truth_reach_m:g}")
        return self

    def estimate_grid_m(self) -> np.ndarray:
        """Distances ahead at which friction is estimated [m]: 0, 1, … up to the camera's range."""
        return np.arange(0.0, math.floor(self.camera_range_m) + 1.0)


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
    reference_curve_fraction: Annotated[float, Field(gt=0.0, le=1.0)] = (
        PlannerConfig.reference_curve_fraction)
    """Share of the friction polygon's lateral reach the speed reference's curve speeds assume:
    1 reaches a curve at the polygon's limit speed, less slower (docs/decisions/0065)."""
    speed_ceiling: bool = PlannerConfig.speed_ceiling
    """In cruise, the speed reference is also a soft upper bound on each stage's planned speed,
    so plans follow its braking ramps instead of putting them off (:mod:`mufusion.planner.
    speed_ceiling`); off (the default: measured, not adopted, docs/decisions/0088), a
    least-squares target only."""
    stability_envelope: bool = PlannerConfig.stability_envelope
    """Soft yaw-rate and body-slip bounds from μ̂ in the OCP (acados;
    :mod:`mufusion.planner.stability`, docs/decisions/0065)."""
    rear_saturation: bool = PlannerConfig.rear_saturation
    """The plans' linear rear tire clipped at the axle's friction μ̂ F_zr, so a rear that slides
    is predicted to keep sliding; off (the default: measured, not adopted, docs/decisions/0109),
    the linear tire of the authors' planner."""
    heading_rows: bool = PlannerConfig.heading_rows
    """Keep the body's ends in the lane at the plan's own heading error (two pairs of soft rows
    per stage in the OCP; :func:`mufusion.planner.corridor.heading_rows`); off (the default:
    measured, not adopted, docs/decisions/0081), the lane bounds the reference point less the
    guess's heading swing."""
    exact_body_reach: bool = PlannerConfig.exact_body_reach
    """The corridor shrinks by the body's long sides' reach at the guess's heading on the
    stage's curvature, swing and bulge as one geometry
    (:func:`mufusion.planner.corridor.body_reach_m`) even without ``body_fit``, which implies
    it; off (the default), with ``body_fit`` off or without the curve speed reference, the
    ends' swing and a centred body's bulge counted apart (alone: measured, not adopted,
    docs/decisions/0093)."""
    body_fit: bool = PlannerConfig.body_fit
    """With the curve speed reference: the reference corners no faster than the plans' steady
    attitude (the body turned by its rear tire's slip angle) leaves their corridor a width, and
    the corridor counts the body's reach as one geometry (:mod:`mufusion.planner.body_fit`,
    docs/decisions/0097); off: the point mass's curve speeds, whatever the lane's width."""
    lane_slack_lead: Annotated[float, Field(ge=1.0, le=1e3)] = PlannerConfig.lane_slack_lead
    """How many times more a plan's leaving its corridor (lane and obstacles) costs at the first
    stage than at the horizon's end, geometrically in between, so that a plan that cannot keep
    the corridor leaves it as late as it can; 1 (the default): the same price at every stage
    (measured, not adopted: GT then deferred excursions that were real, docs/decisions/0089)."""
    reference_regain_limit: bool = PlannerConfig.reference_regain_limit
    """In cruise, the speed reference regains speed from the vehicle's own no faster than the
    drive's acceleration cap on the g-g ellipse allows (less while cornering); ``false``: the
    reference jumps back to the profile's speed."""
    reference_regain_share: bool = PlannerConfig.reference_regain_share
    """The regain spans only ``reference_braking_fraction`` of the lateral friction: cornering
    beyond that share, the reference asks for no drive (docs/decisions/0119); ``false``: the
    regain's ellipse spans the whole lateral friction."""
    rear_secant_reserve: Annotated[float, Field(ge=0.0, lt=1.0)] | None = (
        PlannerConfig.rear_secant_reserve)
    """Cruising, each stage's rear tire takes the secant stiffness at the utilisation its guess
    asks for plus this reserve (at most the utilisation factor), not at the utilisation factor:
    the plans' rear slip, and the body's attitude in a narrow lane, as the tire gives them at
    moderate forces; ``null`` (the default): the utilisation factor's secant at every stage.
    Measured, not adopted (docs/decisions/0121): 0.1 takes a third of the narrow-lane truck's
    exits, and adds exits elsewhere."""
    reference_load_transfer: bool = PlannerConfig.reference_load_transfer
    """The speed reference's braking ramps brake with what the vehicle's two axles reach beside
    the curve's lateral force, pitch load transfer counted
    (:mod:`mufusion.planner.axle_reach`); off (the default: measured, not adopted,
    docs/decisions/0106), the point mass's braking, ``√(a² − a_y²)``."""
    reference_drive_cap: bool = PlannerConfig.reference_drive_cap
    """In cruise, no rear drive at a stage whose guessed speed is above the speed reference by
    more than 0.5 m/s, so a plan above the reference cannot drive now and put its braking off
    (:mod:`mufusion.planner.drive_cap`); off (the default: measured, not adopted,
    docs/decisions/0105), the drive's cap at every stage."""
    steering_rate_limit: bool = True
    """Plan the front lateral force as a state whose rate the steering actuator's rate limit
    bounds (:mod:`mufusion.planner.front_force`); ``false``: the forces are free inputs, as in
    the paper's planner."""
    load_transfer: bool = True
    """The friction polygons' radii follow the axle loads of each stage's own planned
    longitudinal forces (pitch load transfer inside the OCP); ``false``: the loads of the
    initial guess, as in the paper's planner."""
    torque_lag: bool = PlannerConfig.torque_lag
    """Plan the longitudinal forces as states that follow their commands with the wheel torques'
    first-order lag, so that the tires, the polygons and the load transfer see the forces the
    brakes and the drive can deliver, and the speed reference leads by one more torque lag
    (:mod:`mufusion.planner.ocp_state`, docs/decisions/0068); ``false``: free inputs, as in the
    paper's planner."""
    axle_friction: bool = PlannerConfig.axle_friction
    """Bound each stage's front braking by the lowest μ̂ the front axle meets from the stage's
    start to where a brake torque commanded then lands, one torque lag later, where that is
    below the stage's (centre of gravity's) μ̂ (docs/decisions/0064); ``false``: the front
    polygon at the stage's μ̂ alone, as in the paper's planner."""
    front_axle_polygon: bool = PlannerConfig.front_axle_polygon
    """Take the front friction polygon's μ̂ as the lower of the stage's (centre of gravity's)
    and the front axle's, l_f ahead, where the front tires meet a drop first
    (docs/decisions/0112); ``false``: both polygons at the stage's μ̂, as in the paper's
    planner."""
    steady_attitude_reference: bool = PlannerConfig.steady_attitude_reference
    """Track the curve's steady attitude (the lateral speed and heading error at which the
    plans' model holds the curve at the guess's speed) instead of zero, so that plans rotate
    the body into a curve as it begins; off by default, measured and not adopted
    (docs/decisions/0113): zero, as in the paper's planner."""
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
    abs_rise_recognition: bool = True
    """ABS ends a cycle's build-up when the road returns a fifth more than it did before the
    wheel ran away (a friction rise) instead of climbing to the command at the low friction's
    rate; ``false``: the build-up of docs/decisions/0052 (docs/decisions/0118)."""
    esc: bool = True
    """Yaw stability control in the vehicle (:mod:`mufusion.vehicle.stability_control`): a yaw
    moment from braking one front wheel when the vehicle rotates faster than its steering asks,
    as on every production car and truck; ``false`` shows what it does (docs/decisions/0082)."""
    esc_body_slip_return_s: Annotated[
        float, Field(gt=0.0, le=10.0, allow_inf_nan=False)] | None = 0.5
    """With the rear swung out beyond ESC's body-slip deadband, the time [s] in which ESC's
    moment returns the body slip to it (the steering no longer explains the rotation); ``null``
    switches it off, the rule of docs/decisions/0082 (docs/decisions/0115)."""
    esc_braked_wheel_lateral_loss: bool = True
    """ESC's braked wheel gives up lateral force for its braking force (the friction ellipse);
    ``false``: the braking force comes on top of the tire forces, as before
    docs/decisions/0117."""
    esc_drive_cut: bool = False
    """ESC also withholds drive torque while the rear is swung out beyond its body-slip
    deadband (production ESC's engine intervention); measured, not adopted
    (docs/decisions/0092)."""

    def surface_tires(self) -> SurfaceTireTable | None:
        """The plant's tire table (``None`` for the default tire)."""
        return _SURFACE_TIRES[self.tires]

    def slip_control(self) -> SlipControlSettings | None:
        """The vehicle's wheel-slip control (``None`` with ABS and TCS both off)."""
        if not (self.abs or self.tcs):
            return None
        return SlipControlSettings(abs_enabled=self.abs, tcs_enabled=self.tcs,
                                   rise_recognition=self.abs_rise_recognition)


    def stability_control(self) -> StabilityControlSettings | None:
        """The vehicle's yaw stability control (``None`` with ``esc`` off)."""
        if not self.esc:
            return None
        return StabilityControlSettings(
            drive_cut=self.esc_drive_cut, body_slip_return_s=self.esc_body_slip_return_s,
            braked_wheel_lateral_loss=self.esc_braked_wheel_lateral_loss)


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
