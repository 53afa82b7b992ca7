"""The planner's configuration: its modes, cost weights, plausibility limits, obstacles and
:class:`PlannerConfig`, apart from the OCP they configure (:mod:`mufusion.planner.ocp`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from mufusion.planner.safety import SafetySettings
from mufusion.vehicle.surface_tires import SurfaceTireTable

PlannerMode = Literal["cruise", "evade", "emergency", "minimal_risk"]
StiffnessModel = Literal["fixed", "from_mu_hat"]
STIFFNESS_MODELS: tuple[str, ...] = ("fixed", "from_mu_hat")
PLANNER_MODES: tuple[str, ...] = ("cruise", "evade", "emergency", "minimal_risk")


@dataclass(frozen=True)
class CostWeights:
    """Least-squares weights (acados multiplies them by dt)."""

    speed: float = 1.0
    lateral_offset: float = 1.0
    heading_error: float = 1.0
    yaw_rate: float = 1.0
    lateral_speed: float = 1.0
    force_per_kn: float = 1e-4
    emergency_speed: float = 10.0
    evade_speed: float = 0.05
    slack_l1: float = 1e4
    slack_l2: float = 1e4
    # Exact penalty of a plan's speed above the speed ceiling (``PlannerConfig.speed_ceiling``),
    # per m/s and stage: far above the speed tracking's, far below the lane's and the rear
    # polygon's (``slack_l1``), so a plan brakes to the ceiling unless the lane or the friction
    # forbids it.
    speed_ceiling_l1: float = 1e2
    speed_ceiling_l2: float = 1e2


@dataclass(frozen=True)
class PlausibilityLimits:
    """Tolerances of the check a solver's "success" must pass before its plan is used.

    Forces are compared with the friction polygons used in the solve: a row may exceed its
    inscribed radius by ``front_polygon_tolerance`` (front, a hard constraint: only solver
    tolerance) or ``rear_polygon_tolerance`` (rear, soft: its slack may be used) as a fraction of
    the polygon radius; longitudinal forces may exceed the actuator bounds by
    ``force_bound_tolerance`` of the bound. ``d`` may leave the stage's corridor by
    ``corridor_tolerance_m`` (the corridor is soft), ``|Δψ|`` may not exceed
    ``max_heading_error_rad`` and ``v_x`` must lie in ``[-speed_tolerance_mps,
    MAX_SPEED_MPS + speed_tolerance_mps]``.
    """

    # Defaults sit outside what accepted solutions reach in the shipped scenarios (all
    # configurations, emergency mode included: front 0, rear 2.27 (1.10 before the rear tire
    # followed the plan's own load, decision 0066), bounds 0, corridor 1.5 m, heading 0.40 rad,
    # speed −0.01 m/s; `python benchmarks/planner.py --margins`) and well inside a diverged one.
    front_polygon_tolerance: float = 0.05
    rear_polygon_tolerance: float = 3.0
    force_bound_tolerance: float = 0.05
    corridor_tolerance_m: float = 5.0
    max_heading_error_rad: float = 1.5
    speed_tolerance_mps: float = 1.0

    def __post_init__(self) -> None:
        for name in ("front_polygon_tolerance", "rear_polygon_tolerance", "force_bound_tolerance"):
            value = getattr(self, name)
            if not 0.0 <= value <= 10.0:
                raise ValueError(f"{name} must be in [0, 10], got {value}")
        if not 0.0 <= self.corridor_tolerance_m <= 100.0:
            raise ValueError(
                f"corridor_tolerance_m must be in [0, 100] m, got {self.corridor_tolerance_m}"
            )
        if not 0.0 < self.max_heading_error_rad <= np.pi:
            raise ValueError(
                f"max_heading_error_rad must be in (0, pi], got {self.max_heading_error_rad}"
            )
        if not 0.0 <= self.speed_tolerance_mps <= 100.0:
            raise ValueError(
                f"speed_tolerance_mps must be in [0, 100] m/s, got {self.speed_tolerance_mps}"
            )


@dataclass(frozen=True)
class PlannerObstacle:
    """An obstacle in road coordinates: centre ``(s_m, d_m)``, extent ``length_m × width_m``.

    ``s_m`` is where the centre is at the planning step's time; ``speed_mps`` is its constant
    speed along the path (negative: oncoming; 0, the default: static), so stage ``k`` of a plan
    sees it at ``s_m + speed_mps · k · dt`` (:meth:`s_at_stages`).
    """

    s_m: float
    d_m: float
    length_m: float
    width_m: float
    speed_mps: float = 0.0

    def s_at_stages(self, s_shape: tuple[int, ...], dt_s: float) -> np.ndarray | float:
        """The centre's predicted progress [m] at stages ``1..N`` (axis 0 of ``s_shape``).

        A static obstacle's is the float ``s_m`` (so its corridor stays what it was, bit for
        bit); a moving one's an array broadcastable to ``s_shape``.

        Examples
        --------
        >>> PlannerObstacle(50.0, 0.0, 4.5, 1.8, speed_mps=10.0).s_at_stages((3,), 0.1).tolist()
        [51.0, 52.0, 53.0]
        >>> PlannerObstacle(50.0, 0.0, 4.5, 1.8).s_at_stages((3,), 0.1)
        50.0
        """
        if self.speed_mps == 0.0:
            return self.s_m
        times = dt_s * np.arange(1, s_shape[0] + 1, dtype=float)
        return self.s_m + self.speed_mps * times.reshape((-1,) + (1,) * (len(s_shape) - 1))


@dataclass(frozen=True)
class PlannerConfig:
    """Planner configuration; checked on construction.

    ``stiffness`` says which cornering stiffness the planner's linear rear tire and the
    controller's inverse Magic Formula assume: ``"fixed"`` (default), the vehicle's tire on every
    surface; ``"from_mu_hat"``, the set of ``stiffness_table`` at the estimate μ̂ of each stage
    (the authors' ``get_cornering_stiffness``: a model that knows the tire's surface dependence
    but not the surface, so a wrong μ̂ gives a wrong stiffness too).
    """

    horizon_steps: int = 40
    dt_s: float = 0.1
    utilization_factor: float = 0.9
    polygon_sides: int = 12
    weights: CostWeights = field(default_factory=CostWeights)
    backend: Literal["acados", "casadi"] = "acados"
    use_sampling: bool = True
    # Bounds on the reference point's lateral offset [m]: a 3.5 m lane minus half a truck width.
    lane_d_min_m: float = -0.45
    lane_d_max_m: float = 0.45
    obstacle_margin_m: float = 0.5
    min_speed_mps: float = 0.5
    cold_start_iterations: int = 3
    max_cruise_accel_mps2: float = 1.5
    # Recovery (see docs/planner.md, "Failures and recovery"): friction floor, minimal-risk
    # deceleration, and the fallback count after which the caller switches to "minimal_risk".
    safety: SafetySettings = field(default_factory=SafetySettings)
    plausibility: PlausibilityLimits = field(default_factory=PlausibilityLimits)
    stiffness: StiffnessModel = "fixed"
    stiffness_table: SurfaceTireTable | None = None
    # Track min(cruise speed, the point mass's highest speed along the lane centre) instead of the
    # cruise speed alone (planner/speed_profile.py).
    curve_speed_reference: bool = True
    # Share of the friction the speed reference's braking ramps before a curve assume, in (0, 1]
    # (planner/speed_profile.py): below 1 the reference starts braking earlier than the polygon
    # requires and keeps the rest as a reserve for braking the plans lose at the turn-in
    # (docs/decisions/0031, "A braking reserve in the speed reference").
    reference_braking_fraction: float = 0.8
    # Share of the polygon's lateral reach (λ cos(π/n)) the reference's curve speeds assume:
    # below 1 the reference reaches a curve slower than the polygon allows (docs/decisions/0065).
    reference_curve_fraction: float = 1.0
    # The reference regains speed from the vehicle's own no faster than the cruise traction cap
    # on the g-g ellipse allows (planner/speed_profile.py, ``regain_limited_profile_mps``).
    reference_regain_limit: bool = True
    # The regain's ellipse spans only the share of the lateral friction the braking ramps use
    # (``reference_braking_fraction``): cornering beyond it the reference asks for no drive, and
    # the driven axle keeps its reserve for the plans' lateral corrections (docs/decisions/0119).
    reference_regain_share: bool = True
    # The reference's braking ramps brake with what the vehicle's two axles reach beside the
    # curve's lateral force, pitch load transfer counted (planner/axle_reach.py), instead of the
    # point mass's √(a² − a_y²). Off: measured, not adopted (the edge draws' spin 2.15 m ->
    # 0.18 m, but a feasible hairpin truck 0 -> 5.6 cm; docs/decisions/0106).
    reference_load_transfer: bool = False
    # In cruise, no rear drive at a stage whose guessed speed is above the curve speed
    # reference by more than 0.5 m/s (planner/drive_cap.py): a plan above the reference may not
    # drive now and brake at the friction limit later. Off: measured, not adopted (the edge
    # draw's spin 2.15 m -> 5 cm, but a feasible hairpin 0 -> 0.68 m; docs/decisions/0105).
    reference_drive_cap: bool = False
    # In cruise, the speed reference (``curve_speed_reference``) also a soft upper bound on each
    # stage's planned speed (planner/speed_ceiling.py): tracked only in a least-squares sense,
    # plans rise above its braking ramps for their first stages and catch up at the friction
    # limit further on. Off: measured, not adopted (from nearby starts GT's exits barely moved
    # and F-safe's where GT kept its lane doubled; docs/decisions/0088).
    speed_ceiling: bool = False
    # Plan the front lateral force as a state whose rate the steering's rate limit bounds
    # (planner/front_force.py; beyond the paper, whose forces are free inputs).
    steering_rate_limit: bool = True
    # The friction polygons' radii follow the axle loads of the plan's own longitudinal forces
    # (pitch load transfer inside the OCP) instead of the guess's (beyond the paper).
    load_transfer: bool = True
    # Plan the longitudinal forces as states that follow their commands with the wheel torques'
    # first-order lag (planner/ocp_state.py; beyond the paper; docs/decisions/0068). The speed
    # reference then leads by one more torque lag: plans that know the brakes build up over τ
    # reach its ramps τ later.
    torque_lag: bool = True
    # Each stage's front braking also bounded by the lowest μ̂ under the front axle from the
    # stage's start to one torque lag later, where it is below the stage's (docs/decisions/0064).
    axle_friction: bool = True
    # The front polygon at the lower μ̂ of the centre of gravity's and the front axle's: the
    # front tires meet a drop l_f earlier; the rear keeps the CoG's (docs/decisions/0112).
    front_axle_polygon: bool = True
    # The cruise reference's lateral speed and heading error at the curve's steady attitude
    # for the plans' own model at the guess's speeds (planner/steady_attitude.py), not zero,
    # which prices the rotation a curve needs. Off: measured, not adopted (the edge draws'
    # narrow-lane exits shrink but as many remain, one new in a 4.0 m lane: the zero reference
    # also kept the plans' cornering speed down; docs/decisions/0113).
    steady_attitude_reference: bool = False
    # Each stage's yaw rate bounded (soft) by μ̂ g / v at the guess's speed, with a margin
    # and body slip by 0.02 μ̂ g (planner/stability.py; issue 38, mechanism B; both backends;
    # on: GT 0.28-0.30 m out there where main is 0.33-0.39 m, docs/decisions/0065).
    stability_envelope: bool = False
    # The plan's linear rear tire clipped at the axle's friction μ̂ F_zr (vehicle/
    # rear_saturation.py, ``ocp_state.ocp_rear_force_limit``): a state sliding on the rear is
    # predicted to keep sliding, not to snap back on a force many times what the road holds.
    # Off: measured, not adopted (GT's spins beyond the limit go, but on held-out grids GT and
    # F-safe leave the lane in feasible variants they kept; docs/decisions/0109).
    rear_saturation: bool = False
    # Keep the body's ends in the lane at the plan's own heading error (four soft rows per stage
    # in the OCP, linearised at each iterate) instead of taking the guess's heading swing, up to
    # 0.1 rad, off the reference point's bounds; not while evading (planner/corridor.py). Off:
    # measured, not adopted (docs/decisions/0081).
    heading_rows: bool = False
    # The corridor takes the body's reach as one geometry (the long sides' extremes of
    # x sin Δψ − κx²/2; planner/corridor.py, ``body_reach_m``) instead of the ends' swing and a
    # centred body's bulge apart, even without ``body_fit`` (which implies it: see
    # ``corridor_exact_reach``). Alone, measured and not adopted (docs/decisions/0093): it keeps
    # the truck in a 15 m hairpin where the corridor apart was empty, but its plans then use the
    # lane's width the over-count kept free, and the truck leaves S-curves by up to 0.6 m.
    exact_body_reach: bool = False
    # The corridor's slack costs ``lane_slack_lead`` times more at the first stage than at the
    # horizon's end, geometrically in between (planner/penalties.py, ``corridor_slack_scale``),
    # so a plan that cannot keep the corridor leaves it as late as it can. 1 (the default): the
    # same price at every stage; 10 kept F-safe in lane where its friction bound made the curve
    # look impossible, but GT, deferring excursions that were real, left its lane more and in
    # more variants: measured, not adopted (docs/decisions/0089).
    lane_slack_lead: float = 1.0
    # The speed reference's curve speeds capped where the plans' steady attitude (their rear
    # tire's slip angle) leaves the corridor no width, and the corridor counting the body's reach
    # as one geometry (planner/body_fit.py, docs/decisions/0097); off: the point mass's curve
    # speeds, whatever the lane's width. Acts with ``curve_speed_reference`` only.
    body_fit: bool = True
    # Cruising, each stage's rear tire takes the secant at the utilisation its guess asks for
    # plus this reserve (at most λ), not at λ: the plans' slip, and the body's attitude and fit,
    # as the tire gives them at moderate forces (planner/rear_secant.py). The vehicle's own tire
    # only (no stiffness table). ``None`` (the default): λ's secant at every stage. Measured,
    # not adopted: the narrow-lane truck's exits fall by a third, but new exits elsewhere, two
    # published grids' F-safe findings among them (docs/decisions/0121).
    rear_secant_reserve: float | None = None

    @property
    def corridor_exact_reach(self) -> bool:
        """Whether the corridor counts the body's reach as one geometry: asked for
        (``exact_body_reach``), or where the speed reference corners within the body's fit
        (``body_fit`` with ``curve_speed_reference``), which keeps the plans' attitude inside the
        room the exact count gives back (docs/decisions/0097)."""
        return self.exact_body_reach or (self.body_fit and self.curve_speed_reference)

    def __post_init__(self) -> None:
        if self.stiffness not in STIFFNESS_MODELS:
            raise ValueError(
                f"stiffness must be one of {list(STIFFNESS_MODELS)}, got {self.stiffness!r}"
            )
        if self.stiffness == "from_mu_hat" and not isinstance(
            self.stiffness_table, SurfaceTireTable
        ):
            raise ValueError("stiffness='from_mu_hat' needs a SurfaceTireTable as stiffness_table")
        if self.stiffness == "fixed" and self.stiffness_table is not None:
            raise ValueError("stiffness_table is only used with stiffness='from_mu_hat'; "
                             "with 'fixed' leave it None")
        if not 5 <= self.horizon_steps <= 200:
            raise ValueError(f"horizon_steps must be in [5, 200], got {self.horizon_steps}")
        if not 0.0 < self.dt_s <= 0.5:
            raise ValueError(f"dt_s must be in (0, 0.5] s, got {self.dt_s}")
        if not 0.0 < self.utilization_factor <= 1.0:
            raise ValueError(
                f"utilization_factor must be in (0, 1], got {self.utilization_factor}"
            )
        if self.polygon_sides < 12 or self.polygon_sides % 2:
            raise ValueError(
                f"polygon_sides must be an even number >= 12, got {self.polygon_sides}"
            )
        if self.backend not in ("acados", "casadi"):
            raise ValueError(f"backend must be 'acados' or 'casadi', got {self.backend!r}")
        if not 0.0 < self.max_cruise_accel_mps2 <= 10.0:
            raise ValueError(
                f"max_cruise_accel_mps2 must be in (0, 10] m/s², got {self.max_cruise_accel_mps2}"
            )
        if not 0.0 < self.reference_curve_fraction <= 1.0:
            raise ValueError("reference_curve_fraction must be in (0, 1], "
                             f"got {self.reference_curve_fraction}")
        if self.rear_secant_reserve is not None and not (
                isinstance(self.rear_secant_reserve, (int, float))
                and 0.0 <= self.rear_secant_reserve < 1.0):
            raise ValueError("rear_secant_reserve must be None or in [0, 1), "
                             f"got {self.rear_secant_reserve!r}")
        if not 0.0 < self.reference_braking_fraction <= 1.0:
            raise ValueError("reference_braking_fraction must be in (0, 1], "
                             f"got {self.reference_braking_fraction}")
        if not 1 <= self.cold_start_iterations <= 20:
            raise ValueError(
                f"cold_start_iterations must be in [1, 20], got {self.cold_start_iterations}"
            )
        if not 1.0 <= self.lane_slack_lead <= 1e3:
            raise ValueError(f"lane_slack_lead must be in [1, 1000], got {self.lane_slack_lead!r}")
        if self.lane_d_min_m >= self.lane_d_max_m:
            raise ValueError("lane_d_min_m must be below lane_d_max_m")
