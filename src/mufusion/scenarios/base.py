"""What every scenario kind has (:class:`Scenario`): vehicle, initial state, duration, seed,
estimation, planner, simulation, faults and supervision settings, and their cross-checks.

Each kind (:mod:`mufusion.scenarios.config`, :mod:`mufusion.scenarios.road_kind`) adds its road
and says where the vehicle starts on it (``start_s_m``), how to build it (``build_road``) and
where the planner may drive (``drivable_d_m``).
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from mufusion.planner.safety import SafetySettings
from mufusion.scenarios.sections import (
    EstimationConfig,
    InitialPerturbation,
    NonNegFloat,
    PlannerSettings,
    SimSettings,
    VehicleName,
    _Strict,
)
from mufusion.scenarios.shared_section import SharedSection
from mufusion.sim.faults import Fault
from mufusion.sim.settings import LaneRecoverySettings, LoopRates, ProbingSettings


class Scenario(_Strict):
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
    def _check_common(self) -> Scenario:
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
