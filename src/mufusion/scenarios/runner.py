"""Build the world, the vehicle and the stack of one scenario, and run it in closed loop.

Conventions (paper, Sec. IV): the vehicle starts at ``s0 = road.approach_m`` on the ego-lane
centre; the paper's "s = 0" and "t_c = 0" are that position and the start of the run. In the pop-up
scenario the obstacle appears at the start, ``obstacle.distance_m`` ahead of the vehicle's front,
while the planner still holds its cruise plan from before (a warm start on the obstacle-free road),
which is the abrupt change the sampling augmentation exists for.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from mufusion.configurations import Configuration, make_configuration
from mufusion.planner import (
    PlannerConfig,
    PlannerObstacle,
    TrackingController,
    TractionAdaptivePlanner,
)
from mufusion.road import FrictionMap, Obstacle, Road, straight_road, turn_road
from mufusion.scenarios.config import ScenarioConfig
from mufusion.sim.log import RunLog
from mufusion.sim.loop import ClosedLoop, LoopRates
from mufusion.sim.world import World
from mufusion.vehicle.params import VehicleParams, vehicle_preset
from mufusion.vehicle.plant import Plant, initial_state

# The paper's comparison instants for planned forces and the fused estimate (Fig. 3k, 4k).
COMPARISON_TIME_S = {"turn": 0.0, "popup": 0.5}
# Plans made at the start state, before the obstacle appears (the planner's warm start).
WARMUP_PLANNING_STEPS = 10


def _front_overhang_m(params: VehicleParams) -> float:
    """Distance from the CoG to the front of the footprint (centred between the axles)."""
    return 0.5 * (params.cog_to_front_axle_m - params.cog_to_rear_axle_m) + 0.5 * params.length_m


def build_road(cfg: ScenarioConfig, params: VehicleParams) -> tuple[Road, float]:
    """The scenario's road and the vehicle's start progress ``s0`` [m]."""
    s0 = cfg.road.approach_m
    lane = cfg.road.lane_width_m
    if cfg.name == "turn":
        friction = FrictionMap.step(
            cfg.friction.mu_before, cfg.friction.mu_turn, s0 + cfg.friction.change_ahead_m
        )
        road = turn_road(
            radius_m=cfg.turn.radius_m,
            approach_m=s0 + cfg.turn.start_ahead_m,
            exit_m=cfg.road.length_m,
            clothoid_m=cfg.turn.clothoid_m,
            direction=cfg.turn.direction,
            lane_width_m=lane,
            friction=friction,
        )
        return road, s0
    obstacles: tuple[Obstacle, ...] = ()
    if cfg.obstacle is not None:
        ob = cfg.obstacle
        s_obstacle = s0 + _front_overhang_m(params) + ob.distance_m
        obstacles = (
            Obstacle(
                s_m=s_obstacle,
                d_m=ob.lateral_offset_m,
                length_m=ob.length_m,
                width_m=ob.width_m,
                appear_at_time_s=ob.appear_at_s,
            ),
        )
    road = straight_road(
        s0 + cfg.road.length_m,
        lane_width_m=lane,
        friction=FrictionMap.uniform(cfg.friction.mu),
        obstacles=obstacles,
    )
    return road, s0


# The planner bounds its reference point (and takes a curve's bulge off the outer side); the
# footprint's corners reach further still when the vehicle is yawed against the lane, and the
# plant tracks the plan to about a decimetre at the friction limit.
FOOTPRINT_MARGIN_M = 0.1


def planner_lane_bounds_m(cfg: ScenarioConfig, params: VehicleParams) -> tuple[float, float]:
    """Bounds on the planner's lateral offset: lane (turn) or whole road (pop-up) edges shrunk
    by half the vehicle width (TAMP framework) and by :data:`FOOTPRINT_MARGIN_M`."""
    w, half = cfg.road.lane_width_m, 0.5 * params.width_m + FOOTPRINT_MARGIN_M
    if cfg.name == "popup":
        return -0.5 * w + half, 1.5 * w - half
    return -0.5 * w + half, 0.5 * w - half


def planner_for(cfg: ScenarioConfig) -> TractionAdaptivePlanner:
    """The scenario's planner (its solver generated and compiled on first use, then cached)."""
    planner_cfg = PlannerConfig(
        horizon_steps=cfg.planner.horizon_steps,
        dt_s=cfg.planner.dt_s,
        utilization_factor=cfg.planner.utilization_factor,
        backend=cfg.planner.backend,
        use_sampling=cfg.planner.use_sampling,
    )
    return TractionAdaptivePlanner(vehicle_preset(cfg.vehicle), planner_cfg)


def run_scenario(
    cfg: ScenarioConfig,
    configuration: Configuration | str,
    *,
    progress: Callable[[float], None] | None = None,
) -> RunLog:
    """Run one scenario with one friction configuration and return its log.

    Parameters
    ----------
    cfg
        Validated scenario.
    configuration
        ``GT``, ``L``, ``P``, ``F`` (fused, paper mode) or ``F-safe`` (fused, safe mode).
    progress
        Called with the simulated time after every planning step.

    Raises
    ------
    ValueError
        If ``configuration`` is unknown.
    """
    configuration = Configuration.parse(configuration)
    params = vehicle_preset(cfg.vehicle)
    road, s0 = build_road(cfg, params)
    world = World(road=road, to_planner_obstacle=_planner_obstacle)
    rates = LoopRates(cfg.sim.plant_rate_hz, cfg.sim.controller_rate_hz, cfg.planner.rate_hz)
    planner = planner_for(cfg)
    planner_cfg = planner.config
    controller = TrackingController(params, planner_cfg)
    rng = np.random.default_rng(cfg.seed)
    friction = make_configuration(
        configuration,
        local_error=cfg.estimation.local_error,
        predictive_error=cfg.estimation.predictive_error,
        rng=rng,
        initial_local_mu=cfg.estimation.initial_local_mu,
        **(
            {"length_scale_m": cfg.estimation.length_scale_m}
            if cfg.estimation.length_scale_m is not None
            else {}
        ),
    )
    x0_x, x0_y, x0_psi = (float(v) for v in road.to_cartesian(s0, 0.0, 0.0))
    plant = Plant(params, initial_state(params, x0_x, x0_y, x0_psi, cfg.initial_speed_mps),
                  dt_s=1.0 / rates.plant_hz)
    lane_bounds = planner_lane_bounds_m(cfg, params)
    loop = ClosedLoop(
        world=world,
        params=params,
        plant=plant,
        planner=planner,
        controller=controller,
        friction=friction,
        rates=rates,
        reference_speed_mps=cfg.cruise_speed_mps,
        lane_bounds_m=lane_bounds,
        emergency_on_obstacle=cfg.emergency_on_obstacle,
        meta=_meta(cfg, configuration, params, road, s0, planner_cfg, rates),
    )
    return loop.run(cfg.duration_s, progress=progress, warmup_steps=WARMUP_PLANNING_STEPS)


def _planner_obstacle(o: Obstacle) -> PlannerObstacle:
    return PlannerObstacle(s_m=o.s_m, d_m=o.d_m, length_m=o.length_m, width_m=o.width_m)


def _meta(
    cfg: ScenarioConfig,
    configuration: Configuration,
    params: VehicleParams,
    road: Road,
    s0: float,
    planner_cfg: PlannerConfig,
    rates: LoopRates,
) -> dict:
    s = np.arange(0.0, road.length_m, 0.5)
    x, y, psi = road.to_cartesian(s, np.zeros_like(s), 0.0)
    obstacles = []
    for o in road.obstacles:
        from mufusion.road import obstacle_corners

        corners = obstacle_corners(o, road.path)
        obstacles.append(
            {
                "s_m": o.s_m,
                "d_m": o.d_m,
                "length_m": o.length_m,
                "width_m": o.width_m,
                "appear_time_s": o.appear_at_time_s,
                "corners_x_m": corners[:, 0].tolist(),
                "corners_y_m": corners[:, 1].tolist(),
            }
        )
    return {
        "scenario": cfg.model_dump(mode="json"),
        "configuration": configuration.value,
        "label": configuration.label,
        "vehicle": {
            "name": params.name,
            "length_m": params.length_m,
            "width_m": params.width_m,
            "wheelbase_m": params.wheelbase_m,
            "cog_to_front_axle_m": params.cog_to_front_axle_m,
            "cog_to_rear_axle_m": params.cog_to_rear_axle_m,
        },
        "road": {
            "s_m": s.tolist(),
            "x_m": np.round(x, 4).tolist(),
            "y_m": np.round(y, 4).tolist(),
            "psi_rad": np.round(psi, 6).tolist(),
            "curvature_1pm": np.round(road.curvature(s), 8).tolist(),
        },
        "lane_width_m": road.lane_width_m,
        "friction": {"s_m": s.tolist(), "mu": np.asarray(road.mu_at(s), float).tolist()},
        "obstacles": obstacles,
        "comparison_time_s": COMPARISON_TIME_S.get(cfg.name, 0.0),
        "utilization_factor": planner_cfg.utilization_factor,
        "polygon_sides": getattr(planner_cfg, "polygon_sides", 12),
        "planner_dt_s": planner_cfg.dt_s,
        "rates": {
            "plant_hz": rates.plant_hz,
            "controller_hz": rates.controller_hz,
            "planner_hz": rates.planner_hz,
        },
        "start_s_m": s0,
        "start_heading_rad": float(math.atan2(y[1] - y[0], x[1] - x[0])),
    }
