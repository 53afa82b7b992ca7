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

from mufusion._threads import one_blas_thread
from mufusion.configurations import (
    CONFIGURATION_NAMES,
    Configuration,
    FrictionConfiguration,
    FrictionSource,
    make_estimator,
)
from mufusion.configurations.plugins import (
    CONTROLLERS,
    PLANNERS,
    import_from_cwd,
    is_builtin,
    make_component_plugin,
    make_friction_plugin,
)
from mufusion.estimators import SurfaceClass, class_table, local_timing, make_sensor_model
from mufusion.planner import (
    ControllerGains,
    PlannerConfig,
    PlannerObstacle,
    TrackingController,
    TractionAdaptivePlanner,
)
from mufusion.planner.speed_profile import MAX_LOOKAHEAD_M
from mufusion.road import Obstacle, Road, obstacle_corners
from mufusion.scenarios.config import AnyScenario, PopupScenario, perturbed, planner_lane_bounds_m
from mufusion.scenarios.feasibility import classify_scenario
from mufusion.scenarios.road_kind import RoadScenario
from mufusion.scenarios.shared_section import scenario_inbox
from mufusion.sim.components import Controller, Planner
from mufusion.sim.log import RunLog
from mufusion.sim.loop import ClosedLoop
from mufusion.sim.obstacle_response import ObstacleResponse
from mufusion.sim.records import (
    LoopRatesMeta,
    ObstacleTrace,
    PlannerSettings,
    RoadTrace,
    RunMeta,
    VehicleGeometry,
)
from mufusion.sim.solver_output import captured_output
from mufusion.sim.world import World
from mufusion.vehicle.params import VehicleParams, vehicle_preset
from mufusion.vehicle.plant import Plant, initial_state

Scenario = AnyScenario

WARMUP_PLANNING_STEPS = 10
"""Plans made at the start state, before the obstacle appears (the planner's warm start)."""
ROAD_TRACE_STEP_M = 0.5
"""Spacing of the road samples recorded in a run's metadata (for figures) [m]."""


def planner_config(cfg: Scenario, params: VehicleParams) -> PlannerConfig:
    """The planner's configuration for a scenario (its lane bounds included)."""
    lo, hi = planner_lane_bounds_m(cfg, params)
    return PlannerConfig(
        horizon_steps=cfg.planner.horizon_steps,
        dt_s=cfg.planner.dt_s,
        utilization_factor=cfg.planner.utilization_factor,
        backend=cfg.planner.backend,
        use_sampling=cfg.planner.use_sampling,
        curve_speed_reference=cfg.planner.curve_speed_reference,
        reference_braking_fraction=cfg.planner.reference_braking_fraction,
        reference_curve_fraction=cfg.planner.reference_curve_fraction,
        speed_ceiling=cfg.planner.speed_ceiling,
        stability_envelope=cfg.planner.stability_envelope,
        rear_saturation=cfg.planner.rear_saturation,
        heading_rows=cfg.planner.heading_rows,
        exact_body_reach=cfg.planner.exact_body_reach,
        lane_slack_lead=cfg.planner.lane_slack_lead,
        reference_regain_limit=cfg.planner.reference_regain_limit,
        reference_regain_share=cfg.planner.reference_regain_share,
        reference_load_transfer=cfg.planner.reference_load_transfer,
        rear_secant_reserve=cfg.planner.rear_secant_reserve,
        reference_drive_cap=cfg.planner.reference_drive_cap,
        steering_rate_limit=cfg.planner.steering_rate_limit,
        load_transfer=cfg.planner.load_transfer,
        torque_lag=cfg.planner.torque_lag, axle_friction=cfg.planner.axle_friction,
        front_axle_polygon=cfg.planner.front_axle_polygon,
        steady_attitude_reference=cfg.planner.steady_attitude_reference,
        body_fit=cfg.planner.body_fit, lane_d_min_m=lo, lane_d_max_m=hi,
        safety=cfg.safety,
        obstacle_margin_m=cfg.planner.obstacle_margin_m,
        stiffness=cfg.planner.stiffness,
        stiffness_table=(
            cfg.sim.surface_tires() if cfg.planner.stiffness == "from_mu_hat" else None
        ),
    )


def planner_for(cfg: Scenario) -> TractionAdaptivePlanner:
    """The scenario's planner (its solver generated and compiled on first use, then cached)."""
    params = vehicle_preset(cfg.vehicle)
    return TractionAdaptivePlanner(params, planner_config(cfg, params))


def build_loop(
    cfg: Scenario,
    *,
    friction: Configuration | str | FrictionSource = Configuration.F,
    planner: str | Planner | None = None,
    controller: str | Controller | None = None,
) -> ClosedLoop:
    """Assemble the closed loop of one scenario: world, vehicle, sensors and the stack.

    Parameters
    ----------
    cfg
        Validated scenario.
    friction
        A built-in configuration (``GT``, ``L``, ``P``, ``F``, ``F-safe``, ``F+shared``,
        ``F-safe+shared``: the last two read the ``[shared]`` reports file), a plug-in's name
        (``"module:attribute"`` or an entry point of ``mufusion.friction_sources``, see
        :mod:`mufusion.configurations.plugins`; made afresh for this run), or a friction source
        object (:class:`~mufusion.configurations.FrictionSource`; its label is its ``name``
        attribute, else its class name).
    planner, controller
        None for the package's own; else a plug-in's name (groups ``mufusion.planners``,
        ``mufusion.controllers``; a factory is called ``factory(params, planner_config)``) or
        the object.

    Returns
    -------
    ClosedLoop
        Ready to ``run(cfg.duration_s, warmup_steps=WARMUP_PLANNING_STEPS)``; its
        ``meta.configuration`` is the friction source's label.

    Raises
    ------
    ValueError
        If ``friction`` names no configuration or plug-in, a plug-in is unusable
        (:class:`~mufusion.configurations.plugins.PluginError`, naming it), or a friction source
        object's label is a built-in configuration's name.
    """
    # The start's perturbation has its own stream, so the estimators' draws (from the seed
    # itself) are the same with and without it.
    cfg = perturbed(cfg, np.random.default_rng(np.random.SeedSequence(cfg.seed, spawn_key=(1,))))
    params = vehicle_preset(cfg.vehicle)
    road = cfg.build_road(params)
    s0 = cfg.start_s_m
    world = World(road=road, to_planner_obstacle=_planner_obstacle)
    rates = cfg.rates()
    classes = class_table(cfg.estimation.class_table)
    source, label = _friction_source(friction, classes, cfg)
    own_config = planner_config(cfg, params)
    the_planner: Planner = (
        planner_for(cfg) if planner is None
        else make_component_plugin(planner, PLANNERS, params, own_config)
        if isinstance(planner, str) else planner
    )
    config = getattr(the_planner, "config", own_config)
    the_controller: Controller = (
        TrackingController(
            params, config, ControllerGains(torque_compensation=cfg.sim.torque_compensation)
        ) if controller is None
        else make_component_plugin(controller, CONTROLLERS, params, config)
        if isinstance(controller, str) else controller
    )
    sensors = make_sensor_model(
        classes=classes,
        local_error=cfg.estimation.local_error,
        predictive_error=cfg.estimation.predictive_error,
        rng=np.random.default_rng(cfg.seed),
        initial_local_mu=cfg.estimation.initial_local_mu,
        local_timing=local_timing(cfg.estimation.local_timing),
        range_m=cfg.estimation.camera_range_m,
    )
    x0_x, x0_y, x0_psi = (
        float(v) for v in road.to_cartesian(
            s0, cfg.initial_lateral_offset_m, cfg.initial_heading_error_rad
        )
    )
    plant = Plant(params, initial_state(params, x0_x, x0_y, x0_psi, cfg.initial_speed_mps),
                  dt_s=1.0 / rates.plant_hz, surface_tires=cfg.sim.surface_tires(),
                  slip_control=cfg.sim.slip_control(),
                  stability_control=cfg.sim.stability_control())
    return ClosedLoop(
        world=world,
        params=params,
        plant=plant,
        planner=the_planner,
        controller=the_controller,
        friction=source,
        sensors=sensors,
        rates=rates,
        reference_speed_mps=cfg.cruise_speed_mps,
        lane_bounds_m=(config.lane_d_min_m, config.lane_d_max_m),
        emergency_on_obstacle=(
            isinstance(cfg, PopupScenario | RoadScenario) and cfg.emergency_on_obstacle),
        faults=tuple(cfg.faults),
        safety=cfg.safety,
        probing=cfg.probing,
        lane_recovery=cfg.lane_recovery,
        utilization_factor=config.utilization_factor,
        planning_horizon_s=config.horizon_steps * config.dt_s,
        estimate_grid_m=cfg.estimation.estimate_grid_m(),
        truth_reach_m=(MAX_LOOKAHEAD_M if cfg.estimation.truth_reach_m is None
                       else cfg.estimation.truth_reach_m),
        obstacle_response=ObstacleResponse(
            brake_first=cfg.planner.brake_first,
            utilization_factor=config.utilization_factor,
            polygon_sides=config.polygon_sides, margin_m=config.obstacle_margin_m,
            planning_period_s=1.0 / rates.planner_hz,
        ),
        meta=run_meta(cfg, label, params, road, config).model_copy(update={
            "planner_plugin": _component_name(planner),
            "controller_plugin": _component_name(controller),
            "planner_backend": type(the_planner.backend).__name__
            if isinstance(the_planner, TractionAdaptivePlanner) else None,
        }),
    )


def _component_name(component: object) -> str | None:
    if component is None or isinstance(component, str):
        return component
    return type(component).__name__


def _friction_source(
    friction: Configuration | str | FrictionSource,
    classes: tuple[SurfaceClass, ...],
    cfg: Scenario,
) -> tuple[FrictionSource, str]:
    """The friction source ``friction`` names, made for one run, and its label (a shared
    configuration gets the scenario's ``[shared]`` reports file, if any)."""
    if is_builtin(friction):
        name = Configuration.parse(friction)  # type: ignore[arg-type]
        inbox = scenario_inbox(cfg.shared, cfg.seed) if name.shares_reports else None
        source = make_estimator(name, classes=classes,
                                length_scale_m=cfg.estimation.length_scale_m,
                                shared=cfg.shared.settings(), inbox=inbox,
                                safe_beyond_camera=cfg.estimation.safe_beyond_camera)
        return source, name.value
    if isinstance(friction, str):
        import_from_cwd()
        return make_friction_plugin(friction), friction
    label = str(getattr(friction, "name", type(friction).__name__))
    if label in CONFIGURATION_NAMES and not isinstance(friction, FrictionConfiguration):
        raise ValueError(f"friction source {friction!r} is labelled {label!r}, a built-in "
                         "configuration's name: give it a name of its own")
    return friction, label


def run_scenario(
    cfg: Scenario,
    configuration: Configuration | str | FrictionSource,
    *,
    progress: Callable[[float], None] | None = None,
    planner: str | Planner | None = None,
    controller: str | Controller | None = None,
) -> RunLog:
    """Run one scenario with one friction source and return its log (:func:`build_loop`).

    Parameters
    ----------
    cfg
        Validated scenario.
    configuration
        ``GT``, ``L``, ``P``, ``F`` (fused, paper mode), ``F-safe`` (fused, safe mode), a
        plug-in's name or a friction source (see :func:`build_loop`'s ``friction``).
    progress
        Called with the simulated time after every planning step.
    planner, controller
        None for the package's own, else a plug-in's name or the object (see
        :func:`build_loop`).

    Raises
    ------
    ValueError
        If ``configuration`` names no configuration or usable plug-in, or a planner or
        controller plug-in is unusable.

    Notes
    -----
    The run limits the BLAS thread pools (the OpenBLAS of numpy, scipy and CasADi) to one
    thread. What the solver library prints meanwhile (to file descriptor 1) is captured into the
    log's ``solver_messages``.
    """
    loop = build_loop(cfg, friction=configuration, planner=planner, controller=controller)
    return run_loop(loop, cfg.duration_s, progress=progress)


def run_loop(
    loop: ClosedLoop, duration_s: float, *, progress: Callable[[float], None] | None = None
) -> RunLog:
    """Run a loop of :func:`build_loop` as :func:`run_scenario` does (its warm-up, one BLAS
    thread, the solver's messages into the log); the loop keeps what its supervisors did
    (:attr:`~mufusion.sim.loop.ClosedLoop.supervision`)."""
    # One BLAS thread: the fusion's small matrix products gain nothing from a thread pool, and
    # on a busy machine its spinning threads made runs several times slower. The libraries are
    # scanned here, after the loop's solver was built: CasADi's OpenBLAS (the reference
    # backend's IPOPT) is loaded by then (mufusion._threads).
    # The solver library's printf goes into the log, not onto the terminal (sim.solver_output).
    with one_blas_thread(), captured_output() as messages:
        log = loop.run(duration_s, progress=progress, warmup_steps=WARMUP_PLANNING_STEPS)
    log.solver_messages = messages
    return log


def _planner_obstacle(o: Obstacle) -> PlannerObstacle:
    # ``o`` is placed at the planning step's time (World.planner_obstacles).
    return PlannerObstacle(s_m=o.s_m, d_m=o.d_m, length_m=o.length_m, width_m=o.width_m,
                           speed_mps=o.speed_mps)


def run_meta(
    cfg: Scenario,
    configuration: Configuration | str,
    params: VehicleParams,
    road: Road,
    planner_cfg: PlannerConfig,
) -> RunMeta:
    """The metadata of a run: everything a metric, figure or verdict needs besides the tables."""
    s = np.arange(0.0, road.length_m, ROAD_TRACE_STEP_M)
    x, y, psi = road.to_cartesian(s, np.zeros_like(s), 0.0)
    obstacles = []
    for o in road.obstacles:
        corners = obstacle_corners(o, road.path)
        obstacles.append(
            ObstacleTrace(
                s_m=o.s_m, d_m=o.d_m, length_m=o.length_m, width_m=o.width_m,
                appear_time_s=o.appear_at_time_s, corners_x_m=corners[:, 0].tolist(),
                corners_y_m=corners[:, 1].tolist(), speed_mps=o.speed_mps,
                appear_ego_s_m=o.appear_at_ego_s_m,
            )
        )
    rates = cfg.rates()
    feasibility = classify_scenario(cfg, params)
    return RunMeta(
        scenario_name=cfg.name,
        configuration=str(configuration),
        seed=cfg.seed,
        scenario_config=cfg.model_dump(mode="json"),
        vehicle=VehicleGeometry(
            name=params.name,
            length_m=params.length_m,
            width_m=params.width_m,
            wheelbase_m=params.wheelbase_m,
            cog_to_front_axle_m=params.cog_to_front_axle_m,
            cog_to_rear_axle_m=params.cog_to_rear_axle_m,
        ),
        road=RoadTrace(
            s_m=s.tolist(),
            x_m=np.round(x, 4).tolist(),
            y_m=np.round(y, 4).tolist(),
            psi_rad=np.round(psi, 6).tolist(),
            curvature_1pm=np.round(road.curvature(s), 8).tolist(),
            mu=np.asarray(road.mu_at(s), float).tolist(),
            lane_width_m=road.lane_width_m,
            opposing_lane_width_m=road.opposing_lane_width_m,
        ),
        obstacles=obstacles,
        planner=PlannerSettings(
            horizon_steps=planner_cfg.horizon_steps,
            dt_s=planner_cfg.dt_s,
            utilization_factor=planner_cfg.utilization_factor,
            polygon_sides=planner_cfg.polygon_sides,
            obstacle_margin_m=planner_cfg.obstacle_margin_m,
            lane_d_min_m=planner_cfg.lane_d_min_m,
            lane_d_max_m=planner_cfg.lane_d_max_m,
            backend=planner_cfg.backend,
            use_sampling=planner_cfg.use_sampling,
        ),
        rates=LoopRatesMeta(
            plant_hz=rates.plant_hz, controller_hz=rates.controller_hz, planner_hz=rates.planner_hz
        ),
        start_s_m=cfg.start_s_m,
        start_heading_rad=float(math.atan2(y[1] - y[0], x[1] - x[0])),
        comparison_time_s=cfg.comparison_time_s,
        duration_s=cfg.duration_s,
        feasibility=feasibility.feasibility_class.value,
        feasibility_margin_mps=(
            feasibility.margin_mps if math.isfinite(feasibility.margin_mps) else None
        ),
    )
