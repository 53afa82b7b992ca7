"""Physics feasibility oracle: can a point mass on the true friction do what a scenario asks?

Planner-independent pure functions over plain numbers (SI units in every name):
:func:`turn_feasibility` (the friction-limited speed profile of a point mass through the curve,
``v² κ ≤ λ μ(s) g``, with the friction changing before, at or inside it, along the lane centre
and along the lines the lane's play allows; the lateral part capped where the vehicle's body,
turned by its rear tire's slip, would no longer fit the lane:
:mod:`~mufusion.scenarios.feasibility.attitude`) and
:func:`popup_feasibility` (stop short of the obstacle, or steer around it). Each returns a frozen
dataclass with a :class:`FeasibilityClass`, a signed margin in m/s (the highest entry speed at
which the manoeuvre still fits, minus the entry speed) and the quantities used.
:mod:`~mufusion.scenarios.feasibility.road` judges any road (the profile along its path, the
pop-up envelopes for static obstacles in the own lane).
:func:`classify_scenario` reads them off a :class:`~mufusion.scenarios.config.ScenarioConfig`.
:func:`least_lane_excursion` (:mod:`~mufusion.scenarios.feasibility.transient`) is the offline
second opinion on a turn: the least lane excursion any controller of the plant's own equations
reaches over the whole manoeuvre (an optimal-control problem, seconds to minutes per variant).
Derivation: ``docs/feasibility.md``.
"""

from __future__ import annotations

import math

from mufusion.planner import PlannerConfig
from mufusion.scenarios.config import AnyScenario, TurnScenario
from mufusion.scenarios.feasibility.attitude import BodyInLane
from mufusion.scenarios.feasibility.common import (
    MARGINAL_BAND_FRACTION,
    FeasibilityClass,
    classify_speed_margin,
)
from mufusion.scenarios.feasibility.popup import (
    BrakingEnvelope,
    EvasionEnvelope,
    PopupFeasibility,
    popup_feasibility,
)
from mufusion.scenarios.feasibility.road import (
    RoadFeasibility,
    in_own_lane,
    obstacle_distance_m,
    path_limit,
    road_feasibility,
)
from mufusion.scenarios.feasibility.transient import (
    TrajectoryGuess,
    TransientVerdict,
    least_lane_excursion,
)
from mufusion.scenarios.feasibility.turn import (
    TurnFeasibility,
    TurnLimit,
    clothoid_offsets_m,
    effective_radius_m,
    turn_feasibility,
)
from mufusion.scenarios.road_kind import RoadScenario
from mufusion.vehicle.braking import braking_limited_speed_mps
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import secant_stiffness_factor
from mufusion.vehicle.surface_tires import tire_for_surface

__all__ = [
    "MARGINAL_BAND_FRACTION",
    "BrakingEnvelope",
    "EvasionEnvelope",
    "FeasibilityClass",
    "PopupFeasibility",
    "RoadFeasibility",
    "TrajectoryGuess",
    "TransientVerdict",
    "TurnFeasibility",
    "TurnLimit",
    "braking_limited_speed_mps",
    "classify_scenario",
    "classify_speed_margin",
    "clothoid_offsets_m",
    "effective_radius_m",
    "least_lane_excursion",
    "popup_feasibility",
    "summary_fields",
    "turn_feasibility",
]


Verdict = TurnFeasibility | PopupFeasibility | RoadFeasibility


def classify_scenario(cfg: AnyScenario, params: VehicleParams) -> Verdict:
    """The oracle's verdict on one scenario variant.

    Dead times are the vehicle's actuator time constants (brakes: ``torque_time_constant_s``,
    steering: ``steer_time_constant_s``); the brake limit is the wheel-torque capacity; a turn's
    friction is the lower under the two axles (``cog_to_front_axle_m``, ``cog_to_rear_axle_m``); the
    evasion keeps the planner's obstacle margin and may use the whole road (ego and opposing
    lane), as the pop-up planner does. A road is judged along its path and at each static
    obstacle in its own lane (:mod:`~mufusion.scenarios.feasibility.road`), its evasion room
    the lanes the planner may use.

    Examples
    --------
    >>> from mufusion.scenarios import load_scenario
    >>> from mufusion.vehicle.params import TRUCK
    >>> classify_scenario(load_scenario("turn"), TRUCK).feasibility_class.value
    'feasible'
    """
    lam = cfg.planner.utilization_factor
    max_decel = (params.max_brake_torque_front_nm + params.max_brake_torque_rear_nm) / (
        params.wheel_radius_m * params.mass_kg)
    if isinstance(cfg, TurnScenario):
        return turn_feasibility(
            entry_speed_mps=cfg.initial_speed_mps, radius_m=cfg.turn.radius_m,
            turn_angle_rad=cfg.turn.angle_rad, turn_start_ahead_m=cfg.turn.start_ahead_m,
            clothoid_m=cfg.turn.clothoid_m, mu_before=cfg.friction.mu_before,
            mu_turn=cfg.friction.mu_turn, friction_change_ahead_m=cfg.friction.change_ahead_m,
            utilization_factor=lam, dead_time_s=params.torque_time_constant_s,
            lane_width_m=cfg.road.lane_width_m, vehicle_width_m=params.width_m,
            vehicle_length_m=params.length_m, max_decel_mps2=max_decel,
            front_axle_ahead_m=params.cog_to_front_axle_m,
            rear_axle_behind_m=params.cog_to_rear_axle_m,
            body=_body(cfg, params, cfg.road.lane_width_m),
        )
    if isinstance(cfg, RoadScenario):
        return _classify_road(cfg, params, max_decel)
    ob = cfg.obstacle
    lane = cfg.road.lane_width_m
    return _popup(cfg.initial_speed_mps, cfg.friction.mu, ob.distance_m, ob.length_m,
                  ob.width_m, ob.lateral_offset_m, 1.5 * lane, 0.5 * lane, lam, params, max_decel)


def _body(cfg: AnyScenario, params: VehicleParams, lane_width_m: float) -> BodyInLane:
    """The vehicle's body in its lane, on the tire the plant gives it at each μ."""
    table = cfg.sim.surface_tires()
    return BodyInLane.of(params, lane_width_m,
                         None if table is None else
                         (lambda mu: tire_for_surface(mu, params.tire, table)))


def _popup(
    speed_mps: float, mu: float, distance_m: float, length_m: float, width_m: float,
    offset_m: float, left_edge_m: float, right_edge_m: float, lam: float,
    params: VehicleParams, max_decel: float,
) -> PopupFeasibility:
    """:func:`popup_feasibility` for the vehicle on a road whose edges lie ``left_edge_m`` and
    ``right_edge_m`` from the lane centre."""
    half_w = 0.5 * params.width_m
    slip = 1.0 / (secant_stiffness_factor(params.tire, lam)
                  * params.tire.cornering_stiffness_per_load_1_per_rad)
    return popup_feasibility(
        speed_mps=speed_mps, mu=mu, obstacle_distance_m=distance_m,
        obstacle_length_m=length_m, obstacle_width_m=width_m,
        obstacle_offset_m=offset_m, vehicle_width_m=params.width_m,
        room_left_m=left_edge_m - half_w, room_right_m=max(right_edge_m - half_w, 0.0),
        clearance_margin_m=PlannerConfig().obstacle_margin_m, utilization_factor=lam,
        brake_dead_time_s=params.torque_time_constant_s,
        steer_dead_time_s=params.steer_time_constant_s,
        steer_rate_radps=params.max_steer_rate_radps, max_steer_rad=params.max_steer_rad,
        wheelbase_m=params.wheelbase_m, slip_rad_per_g=slip, max_decel_mps2=max_decel,
    )


def _classify_road(cfg: RoadScenario, params: VehicleParams, max_decel: float) -> RoadFeasibility:
    lam, v0, s0 = cfg.planner.utilization_factor, cfg.initial_speed_mps, cfg.start_s_m
    road = cfg.build_road(params)
    path = path_limit(
        path=road.path, friction=road.friction, start_s_m=s0, entry_speed_mps=v0,
        utilization_factor=lam, dead_time_s=params.torque_time_constant_s,
        max_decel_mps2=max_decel, front_axle_ahead_m=params.cog_to_front_axle_m,
        rear_axle_behind_m=params.cog_to_rear_axle_m,
        body=_body(cfg, params, road.lane_width_m),
    )
    right, left = cfg.drivable_d_m()
    judged = []
    front = params.cog_to_body_front_m
    for i, ob in enumerate(road.obstacles):
        if not in_own_lane(ob, road.lane_width_m) or ob.s_m <= s0:
            continue
        distance = max(obstacle_distance_m(ob, s0, front, v0), 1e-3)
        ahead = [s0 + front + distance * k / 20.0 for k in range(21)]
        mu = min(road.friction.mu_at_point(s) for s in ahead)
        judged.append((i, _popup(v0, mu, distance, ob.length_m, ob.width_m, ob.d_m, left,
                                 -right, lam, params, max_decel)))
    return road_feasibility(v0, path, tuple(judged))

def summary_fields(result: Verdict) -> dict[str, str | float | None]:
    """The verdict as flat ``summary.json`` fields (a non-finite margin becomes ``None``).

    Examples
    --------
    >>> from mufusion.scenarios import load_scenario
    >>> from mufusion.vehicle.params import TRUCK
    >>> sorted(summary_fields(classify_scenario(load_scenario("popup"), TRUCK)))
    ['feasibility', 'feasibility_margin_mps']
    """
    margin = result.margin_mps
    return {
        "feasibility": result.feasibility_class.value,
        "feasibility_margin_mps": round(margin, 3) if math.isfinite(margin) else None,
    }
