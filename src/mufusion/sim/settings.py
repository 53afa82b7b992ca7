"""The closed loop's settings that a scenario sets: the components' rates, friction probing and
lane recovery (what the supervisory layers do: :mod:`mufusion.sim.supervision`).

They are part of the scenario schema, so they live apart from the loop and its layers: reading
and validating a scenario file imports this module only, not the fusion and the planner the loop
uses (a bad file is refused in well under a second; docs/performance.md, "Input errors").
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass


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
            if not math.isfinite(value) or value <= 0:
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


@dataclass(frozen=True)
class ProbingSettings:
    """When and how hard the loop may probe the friction (see the module docstring)."""

    enabled: bool = True
    # The estimator measures above a utilisation of 0.5; braking with a share of the weight on
    # each axle, that is 0.5 μ g of deceleration. The ceiling covers the highest friction the
    # camera's classes declare (dry, 0.8 ± 0.2: 4.9 m/s² on μ 1.0); the ramp's 10 m/s³ reaches it
    # in 0.5 s, and the probe ends at the first planning step that sees the estimate. A ceiling of
    # 3 m/s² never measured on μ 0.9 (docs/decisions/0045, "A probe that measures on dry roads").
    max_decel_mps2: float = 5.0
    ramp_s: float = 0.5
    max_duration_s: float = 0.8
    max_speed_loss_mps: float = 2.0
    stale_after_s: float = 1.0
    min_band: float = 0.1
    straight_curvature_1pm: float = 0.01
    straight_ahead_m: float = 10.0
    clear_distance_m: float = 60.0
    cooldown_s: float = 2.0
    min_speed_mps: float = 5.0
    # The road the trigger reads reaches as far as the planner's horizon at the current speed,
    # past the estimate's grid (the camera's range) with the friction the estimate declares
    # possible there: a curve the braking must already start for, beyond the camera, needs a
    # measurement as much as one inside it (docs/decisions/0101). Off: the grid only.
    beyond_camera: bool = True

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if f.name in ("enabled", "beyond_camera"):
                if not isinstance(value, bool):
                    raise ValueError(f"probing.{f.name} must be true or false, got {value!r}")
                continue
            if isinstance(value, bool) or not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"probing.{f.name} must be a finite number > 0, got {value!r}")
        if self.max_decel_mps2 > 8.0:
            raise ValueError(
                f"probing.max_decel_mps2 must be <= 8 m/s² (a probe, not an emergency stop), "
                f"got {self.max_decel_mps2}"
            )


@dataclass(frozen=True)
class LaneRecoverySettings:
    """When the loop may relax μ̂ towards the posterior mean (see the module docstring)."""

    enabled: bool = True
    violation_tolerance_m: float = 0.05
    steps: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0)
    # Easing the held relaxation off: how far past its friction radius the candidate's rear may
    # go beyond the plan it replaces (or beyond 1), as a fraction of the radius.
    rear_overuse_tolerance: float = 0.05
    # Evading, when every candidate and a plan at the posterior's upper 95 % edge hit the
    # obstacle: brake in lane instead (see the module docstring).
    brake_when_futile: bool = True
    # Evading, when every candidate hits the obstacle and the plan at the posterior's upper
    # 95 % edge passes it: drive that plan, not a candidate predicted to hit (0086).
    evade_at_upper_edge: bool = True
    # Evading, the futility check plans with the most friction the estimates allow at the tires'
    # limit (μ̂ / λ): braking in lane hits for certain, and the reserve λ keeps for tracking is
    # spent, as brake assist spends it on braking (docs/decisions/0103).
    evade_at_tires_limit: bool = True
    # When the futility check's evasion hits too: brake in lane only where that stop meets the
    # obstacle no wider than the evasion would (a frontal impact, not a graze, is what braking
    # may trade for a lower speed); else drive the check's evasion (docs/decisions/0126).
    futility_weighs_contact: bool = True
    # Evading, the candidate with the most relaxation is planned first: where it does no better
    # than the friction-limited plan the search ends there (one solve, not one per step); where
    # it does better the smaller ones follow in increasing order as before, and the smallest
    # that keeps the lane and the obstacle's margin is adopted (docs/decisions/0091).
    evade_top_first: bool = False
    # The guarantee of the lower bound given up faster where a measurement vouches for more: the
    # surface the local estimate measured at twice the pace of the road beyond it
    # (sim/supervision.py, RelaxationGain; docs/decisions/0122). Off: one pace everywhere.
    measured_surface_first: bool = True
    # Evading, the share of the planner's obstacle margin a plan must keep: one passing closer
    # has met its friction limit and is searched on like one leaving the lane. Plans at the
    # estimate's limit keep their corridor's gap to within centimetres (0.44-0.46 m of 0.5 m
    # measured), so half of it separates those from the plans that only scrape past
    # (docs/decisions/0085). 0: only a plan that hits is searched on (as before).
    obstacle_margin_share: float = 0.5
    # Evading, among candidates short of that share and within the band's tolerance, the one
    # less short ranks first; ranked by the band's violation first, the search preferred the
    # least relaxed evasion, the furthest short, step after step (docs/decisions/0127).
    shortfall_before_band: bool = True
    # Long enough for the brakes' lag and the local estimator's buffer at 10 Hz planning, short
    # enough that an evasion from the probe's end stays within reach of one from its start.
    stop_probe_s: float = 0.3

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):  # the switches, named where they are defined
            value = getattr(self, f.name)
            if f.type in (bool, "bool") and not isinstance(value, bool):
                raise ValueError(f"lane_recovery.{f.name} must be true or false, got {value!r}")
        if not (math.isfinite(self.obstacle_margin_share)
                and 0.0 <= self.obstacle_margin_share <= 1.0):
            raise ValueError(
                "lane_recovery.obstacle_margin_share must be finite and in [0, 1] (a share of "
                f"the planner's obstacle margin), got {self.obstacle_margin_share!r}"
            )
        if not (math.isfinite(self.stop_probe_s) and 0.0 <= self.stop_probe_s <= 1.0):
            raise ValueError(
                "lane_recovery.stop_probe_s must be finite and in [0, 1] s (0: no braking "
                f"probe), got {self.stop_probe_s!r}"
            )
        if not (math.isfinite(self.violation_tolerance_m) and self.violation_tolerance_m >= 0.0):
            raise ValueError(
                "lane_recovery.violation_tolerance_m must be finite and >= 0 m, "
                f"got {self.violation_tolerance_m!r}"
            )
        if not (math.isfinite(self.rear_overuse_tolerance)
                and 0.0 <= self.rear_overuse_tolerance <= 1.0):
            raise ValueError(
                "lane_recovery.rear_overuse_tolerance must be finite and in [0, 1] (a fraction "
                f"of the rear friction radius), got {self.rear_overuse_tolerance!r}"
            )
        steps = tuple(self.steps)
        if not steps or any(not 0.0 < a <= 1.0 for a in steps) or list(steps) != sorted(steps):
            raise ValueError(
                f"lane_recovery.steps must be increasing fractions in (0, 1], got {self.steps!r}"
            )
