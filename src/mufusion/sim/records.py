"""The run log's schema: one typed record per table, one model for the run's metadata.

Every column of a saved run is a field below (units in the names); the recorder writes these
records, :func:`mufusion.sim.log.load_run` checks a saved run against them, and metrics, figures
and the report read the tables by these names. Nothing else spells out a column.

Tables (one record type each):

``timeseries`` — :class:`Tick`
    one row per controller tick: plant state (Cartesian and Frenet), actuator command, tire
    utilisation per axle, true friction per axle, footprint status.
``planning_steps`` — :class:`PlanningStep`
    one row per planning step: mode, solver status, fallback, local estimate.
``plans`` — :class:`PlanStages`
    one block per planning step, one row per stage: planned state and tire forces, the limits.
``estimates`` — :class:`EstimateGrid`
    one block per planning step, one row per grid point ahead: true μ, μ̂, the GP posterior.
``timing`` — :class:`StepTiming`
    wall-clock times; the only part of a run that is not a deterministic function of its inputs.
``events`` — :class:`Event`
    injected faults, the system's reactions and mode changes, one row each.
``recovery_candidates`` — :class:`RecoveryCandidate`
    each plan lane recovery weighed: what its ranking read of it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import numpy.typing as npt
from pydantic import BaseModel, ConfigDict

from mufusion.configurations import CONFIGURATION_NAMES, Configuration

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class Tick:
    """One controller tick (table ``timeseries``)."""

    table: ClassVar[str] = "timeseries"

    t_s: float
    x_m: float
    y_m: float
    psi_rad: float
    vx_mps: float
    vy_mps: float
    psidot_radps: float
    speed_mps: float
    s_m: float
    d_m: float
    dpsi_rad: float
    body_slip_rad: float
    steer_rad: float
    steer_cmd_rad: float
    torque_front_nm: float
    """Wheel torque the front axle applies [N m] (the plant's lagged state; braking negative)."""
    torque_rear_nm: float
    torque_front_cmd_nm: float
    """The controller's front torque command [N m], which the plant follows with its lag."""
    torque_rear_cmd_nm: float
    util_front: float
    util_rear: float
    mu_front: float
    mu_rear: float
    local_available: bool
    control_mode: str
    obstacle_active: bool
    clearance_m: float
    in_collision: bool
    passed_obstacle: bool
    left_lane: bool
    in_opposing_lane: bool
    lane_margin_m: float
    """Smallest signed distance of the footprint to the ego lane's edges (negative outside)."""
    lane_excursion_m: float
    opposing_depth_m: float
    road_margin_m: float
    off_road: bool
    # The wheels and the vehicle's wheel-slip control (ABS, TCS) in the plant step that ended at
    # this tick (NaN / false / 0 before the first step and without slip control).
    wheel_slip_front: float = math.nan
    """Longitudinal slip ratio of the front wheels [-] (−1: locked)."""
    wheel_slip_rear: float = math.nan
    slip_control_front: bool = False
    """Whether the slip controller modulated the front torque (ABS or TCS in any phase but pass)."""
    slip_control_rear: bool = False
    slip_torque_removed_front_nm: float = 0.0
    """Torque the slip controller withheld from the front command [N m], ≥ 0."""
    slip_torque_removed_rear_nm: float = 0.0
    slip_cycles: int = 0
    """Slip-control cycles (releases) started so far, both axles."""
    esc_yaw_moment_nm: float = 0.0
    """Yaw moment of the vehicle's stability control (ESC) in that step [N m] (0: passive)."""


@dataclass(frozen=True)
class PlanningStep:
    """One planning step's outcome (table ``planning_steps``)."""

    table: ClassVar[str] = "planning_steps"

    step: int
    t_s: float
    s_m: float
    mode: str
    status: int
    ok: bool
    fallback: bool
    fallback_reason: str
    """Why the step has no fresh plan: the loop's reason (an injected solver failure, the
    planner raised) or the planner's :class:`~mufusion.planner.FallbackReason` value
    (``solver_status``, ``non_finite``, ``implausible``, ``exception``); empty otherwise."""
    sampled_reinit: bool
    robust_qp_retry: bool
    """The fast QP failed and the robust one was tried (the plan's ``robust_qp_retry``)."""
    local_available: bool
    local_mu: float
    estimate_source: str
    """``current``, ``delayed`` (an injected delay), ``last_valid`` or ``floor``."""
    estimate_age_s: float
    held: bool = False
    """The step held a stop at rest with the brakes on instead of solving (the plan's
    ``held``; docs/decisions/0098)."""


@dataclass(frozen=True)
class StepTiming:
    """Wall-clock time of one planning step (table ``timing``)."""

    table: ClassVar[str] = "timing"

    step: int
    t_s: float
    solve_ms: float
    step_ms: float


@dataclass(frozen=True)
class PlanStages:
    """The stages of one plan (table ``plans``); arrays of one length, scalars repeat."""

    table: ClassVar[str] = "plans"

    step: int
    t_s: float
    k: npt.NDArray[np.int64]
    t_k_s: FloatArray
    s_m: FloatArray
    d_m: FloatArray
    dpsi_rad: FloatArray
    psidot_radps: FloatArray
    vx_mps: FloatArray
    vy_mps: FloatArray
    x_m: FloatArray
    y_m: FloatArray
    fyf_n: FloatArray
    fxf_n: FloatArray
    fxr_n: FloatArray
    fyr_n: FloatArray
    fzf_n: FloatArray
    fzr_n: FloatArray
    limit_front_n: FloatArray
    limit_rear_n: FloatArray
    mu_hat: FloatArray
    mu_true: FloatArray


@dataclass(frozen=True)
class EstimateGrid:
    """One planning step's friction estimate over the grid ahead (table ``estimates``).

    ``mean``, ``std``, ``lower`` (the GP posterior) and ``data_mu``, ``data_margin`` (the fusion
    input placed on the grid) are NaN where a configuration has none.
    """

    table: ClassVar[str] = "estimates"

    step: int
    t_s: float
    s_ahead_m: FloatArray
    s_m: FloatArray
    mu_true: FloatArray
    mu_hat: FloatArray
    mean: FloatArray
    std: FloatArray
    lower: FloatArray
    data_mu: FloatArray
    data_margin: FloatArray


@dataclass(frozen=True)
class Event:
    """A fault, the system's reaction to one, or a change of control mode (table ``events``)."""

    table: ClassVar[str] = "events"

    t_s: float
    kind: str
    detail: str


@dataclass(frozen=True)
class RecoveryCandidate:
    """A plan lane recovery weighed at a planning step (table ``recovery_candidates``): the plan
    it reviewed (``alpha`` the relaxation held into the step) and each candidate after it, in
    the order planned, with what its ranking read of each (docs/decisions/0127)."""

    table: ClassVar[str] = "recovery_candidates"

    t_s: float
    alpha: float
    """The relaxation towards the posterior mean the plan was planned with [-]."""
    violation_m: float
    """How far its predicted footprint leaves the band (evading: the road) [m]."""
    hits: bool
    """Whether it is predicted to hit an obstacle."""
    shortfall_m: float
    """How far it passes closer than its share of the obstacle margin [m] (NaN: no plan)."""
    fallback: bool
    """Whether the solve failed (no friction-limited plan)."""


ROW_RECORDS: tuple[type, ...] = (Tick, PlanningStep, StepTiming, Event, RecoveryCandidate)
BLOCK_RECORDS: tuple[type, ...] = (PlanStages, EstimateGrid)
RECORD_TYPES: dict[str, type] = {
    Tick.table: Tick,
    PlanningStep.table: PlanningStep,
    PlanStages.table: PlanStages,
    EstimateGrid.table: EstimateGrid,
    StepTiming.table: StepTiming,
    Event.table: Event,
    RecoveryCandidate.table: RecoveryCandidate,
}
"""Table name → record type, in the order the tables are written."""


def columns(record_type: type) -> tuple[str, ...]:
    """The column names of a record type (its field names, in order)."""
    return tuple(f.name for f in dataclasses.fields(record_type))


# -------------------------------------------------------------------------------------------
# Metadata
# -------------------------------------------------------------------------------------------


class _Meta(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class VehicleGeometry(_Meta):
    """What figures and metrics need of the vehicle: its name and footprint."""

    name: str
    length_m: float
    width_m: float
    wheelbase_m: float
    cog_to_front_axle_m: float
    cog_to_rear_axle_m: float


class RoadTrace(_Meta):
    """The reference path sampled along s, its lane width and the true friction on the centre."""

    s_m: list[float]
    x_m: list[float]
    y_m: list[float]
    psi_rad: list[float]
    curvature_1pm: list[float]
    mu: list[float]
    lane_width_m: float
    opposing_lane_width_m: float | None = None
    """The opposing lane's width [m]; None: ``lane_width_m`` (0: a one-way road)."""


class ObstacleTrace(_Meta):
    """An obstacle in road coordinates and its Cartesian corners (at time 0).

    A moving obstacle's centre is at ``s_m + speed_mps · t`` at time ``t`` (:meth:`s_at_time`):
    its position per tick follows from these two numbers and is not logged.
    """

    s_m: float
    d_m: float
    length_m: float
    width_m: float
    appear_time_s: float | None
    """When it appears [s]; None when it is there from the start or appears by position."""
    corners_x_m: list[float]
    corners_y_m: list[float]
    speed_mps: float = 0.0
    """Constant speed along the path [m/s] (negative: oncoming; 0: static, and in records
    written before obstacles moved)."""
    appear_ego_s_m: float | None = None
    """The ego progress [m] at which it appears (None: no such trigger, or a record written
    before it was kept)."""

    def s_at_time(self, time_s: np.ndarray | float) -> np.ndarray | float:
        """The centre's progress [m] at ``time_s`` [s]."""
        return self.s_m + self.speed_mps * time_s


class PlannerSettings(_Meta):
    """The planner's settings a figure or verdict needs (the plan's step is ``dt_s``)."""

    horizon_steps: int
    dt_s: float
    utilization_factor: float
    polygon_sides: int
    obstacle_margin_m: float
    lane_d_min_m: float
    lane_d_max_m: float
    backend: str
    use_sampling: bool


class LoopRatesMeta(_Meta):
    """Rates of the loop's components [Hz]."""

    plant_hz: float
    controller_hz: float
    planner_hz: float


class RunMeta(_Meta):
    """Everything about a run that is not a time series (``meta.json``).

    ``scenario_config`` is the validated scenario as JSON (provenance: the run can be repeated
    from it); the fields next to it are what metrics, figures and the report read.
    """

    scenario_name: str
    configuration: str
    """The friction source's label: a built-in configuration's name (``"GT"``, …, ``"F-safe"``) or
    a plug-in's (its import path or entry-point name)."""
    seed: int
    scenario_config: dict[str, Any]
    vehicle: VehicleGeometry
    road: RoadTrace
    obstacles: list[ObstacleTrace]
    planner: PlannerSettings
    rates: LoopRatesMeta
    start_s_m: float
    start_heading_rad: float
    comparison_time_s: float
    duration_s: float
    feasibility: str = "unknown"
    """The physics oracle's class of the variant: feasible, marginal, infeasible (or unknown)."""
    feasibility_margin_mps: float | None = None
    """The oracle's margin: highest entry speed at which the manoeuvre fits, minus the entry
    speed [m/s]."""
    planner_plugin: str | None = None
    """The planner's name if it is not the package's (a plug-in's, or the object's class)."""
    controller_plugin: str | None = None
    """The controller's name if it is not the package's."""
    planner_backend: str | None = None
    """The OCP solver the package's planner ran (``AcadosBackend``, ``CasadiBackend``): a planner
    configured for acados that cannot load it runs the CasADi reference instead, and says so
    here (None: a plug-in planner, or a record written before this field)."""

    @property
    def builtin(self) -> Configuration | None:
        """The built-in configuration the run used; None for a plug-in."""
        name = self.configuration
        return Configuration(name) if name in CONFIGURATION_NAMES else None

    @property
    def label(self) -> str:
        """The configuration's legend text (a plug-in's: its name)."""
        builtin = self.builtin
        return builtin.label if builtin is not None else self.configuration

    @property
    def lane_width_m(self) -> float:
        return self.road.lane_width_m
