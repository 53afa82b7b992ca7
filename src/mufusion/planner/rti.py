"""One planning step's real-time iterations and the plan they give (the stages of
:meth:`~mufusion.planner.TractionAdaptivePlanner.step` after its guess).

Each iteration evaluates the stage parameters (sanitised μ̂, normal loads, rear stiffness) at
the guess's predicted positions, builds the lateral corridor and the tracking reference, and
solves the OCP once; a solve that fails, raises, or returns a non-finite or implausible solution
ends the iterations with its reason (:func:`~mufusion.planner.safeguards.check_solution`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from mufusion.planner.axle_reach import PitchTransfer
from mufusion.planner.backend import PlannerBackend
from mufusion.planner.body_fit import body_fit_cap, body_fitted_curvature
from mufusion.planner.config import PlannerConfig, PlannerMode, PlannerObstacle
from mufusion.planner.drive_cap import drive_caps_n
from mufusion.planner.minimal_risk import minimal_risk_rollout
from mufusion.planner.ocp import (
    axle_loads_n,
    lateral_corridor,
    plan_polygon_radii_n,
    plan_rear_stiffness,
    stage_parameters,
    tracking_reference,
    with_lane_band,
)
from mufusion.planner.plan import FallbackReason, Plan, StageParameters
from mufusion.planner.rear_secant import with_rear_secant_at_guess
from mufusion.planner.safeguards import (
    SOFT_CHECKS,
    SanitizedFriction,
    judge_solution,
)
from mufusion.planner.sampling import SamplingConfig
from mufusion.planner.speed_ceiling import speed_ceiling_mps
from mufusion.planner.speed_profile import curve_speed_reference_mps
from mufusion.planner.steady_attitude import steady_cornering_attitude
from mufusion.planner.under_axles import lowest_under_axles, sharpest_under_axles
from mufusion.planner.unseen_road import UnseenRoad
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State, rear_lateral_force_n

_log = logging.getLogger(__name__)


@dataclass(frozen=True)
class StepProblem:
    """What one planning step plans from, with, and around."""

    x0: np.ndarray
    """The state (s, d, Δψ, ψ̇, v_x, v_y) the plan starts from."""
    mode: PlannerMode
    curvature_of_s: Callable[[np.ndarray], np.ndarray]
    mu_of_s: SanitizedFriction
    obstacles: list[PlannerObstacle]
    reference_speed_mps: float
    reference_d_m: float
    lane_d_min_m: float
    lane_d_max_m: float
    unseen_road: UnseenRoad | None = None
    """Where μ̂ ends and what the speed reference assumes beyond (None: μ̂ as it holds)."""


@dataclass(frozen=True)
class Iterated:
    """The real-time iterations' outcome: the last iterate, the guess it started from and the
    stage parameters it was solved with."""

    xs: np.ndarray
    us: np.ndarray
    guess_x: np.ndarray
    guess_u: np.ndarray
    stage: StageParameters
    status: int
    reason: FallbackReason
    """``NONE`` if every iteration succeeded, else why the last one failed."""
    retried: bool
    """The fast QP failed at some iteration and the robust one was tried."""
    soft_only: bool = False
    """An ``IMPLAUSIBLE`` iterate failed only the checks on the OCP's soft rows
    (:data:`~mufusion.planner.safeguards.SOFT_CHECKS`)."""


LANE_BACKSTOP_M = 0.5
"""How far outside the lane the reference point's own bound lies where the heading rows keep
the body's ends in the lane [m]."""


def iterate(
    backend: PlannerBackend,
    par: VehicleParams,
    cfg: PlannerConfig,
    problem: StepProblem,
    guess_x: np.ndarray,
    guess_u: np.ndarray,
    iterations: int,
) -> Iterated:
    """``iterations`` real-time iterations of ``problem`` from the guess, until one fails."""
    x0, mode = problem.x0, problem.mode
    curvature_of_s, mu_of_s = problem.curvature_of_s, problem.mu_of_s
    reference_speed_mps = problem.reference_speed_mps
    braking = mode in ("emergency", "minimal_risk")
    # Cruising only, with the vehicle's own tire (docs/decisions/0121).
    secant_reserve = (cfg.rear_secant_reserve if mode == "cruise" and cfg.stiffness_table is None
                      else None)
    xs, us = guess_x, guess_u
    reason = FallbackReason.NONE
    retried = False
    soft_only = False
    for _ in range(iterations):
        guess_x, guess_u = xs, us
        speed_ref: float | np.ndarray = reference_speed_mps
        ceiling: np.ndarray | None = None
        if cfg.curve_speed_reference and mode in ("cruise", "evade"):
            # Before the stage parameters: those count the sanitised μ̂ of the stages.
            # The reference brakes with the friction the axles meet when the torque lands
            # (docs/decisions/0055): the rear axle behind the CoG, the front axle ahead of
            # it and one torque lag further.
            # The same span bounds the curvature: the curve's speed is reached before the front
            # axle, and a brake torque commanded for it, enter the curve (docs/decisions/0066).
            # Plans whose forces follow the torques' lag reach the reference's ramps one lag
            # later still, so it leads by one more (docs/decisions/0068).
            lags = 2.0 if cfg.torque_lag else 1.0
            ahead_m = (par.cog_to_front_axle_m
                       + lags * max(float(x0[State.vx]), 0.0) * par.torque_time_constant_s)
            mu_ref = lowest_under_axles(mu_of_s, par.cog_to_rear_axle_m, ahead_m)
            # Beyond the estimate, the friction its source declares possible
            # (docs/decisions/0084).
            unseen = None if problem.unseen_road is None else (
                lowest_under_axles(problem.unseen_road.cap(mu_of_s), par.cog_to_rear_axle_m,
                                   ahead_m), max(float(x0[State.vx]), 0.0))
            kappa_ref = sharpest_under_axles(curvature_of_s, par.cog_to_rear_axle_m, ahead_m)
            accel_fraction = (cfg.reference_curve_fraction * cfg.utilization_factor
                              * np.cos(np.pi / cfg.polygon_sides))
            if cfg.body_fit:
                # No faster than the body, turned by its rear tire's slip, fits the band its
                # lane bounds leave it (docs/decisions/0097).
                kappa_ref = body_fitted_curvature(
                    kappa_ref, mu_ref,
                    body_fit_cap(par, cfg.lane_d_max_m - cfg.lane_d_min_m,
                                 cfg.utilization_factor, cfg.corridor_exact_reach,
                                 cfg.stiffness_table, secant_reserve),
                    accel_fraction)
            speed_ref = curve_speed_reference_mps(
                guess_x[:, State.s], kappa_ref, mu_ref, reference_speed_mps, accel_fraction,
                cfg.horizon_steps * cfg.dt_s, cfg.reference_braking_fraction,
                (max(float(x0[State.vx]), 0.0), cfg.max_cruise_accel_mps2,
                 cfg.reference_braking_fraction if cfg.reference_regain_share else 1.0)
                if cfg.reference_regain_limit and mode == "cruise" else None,
                unseen,
                # With ``reference_load_transfer`` (off: measured, not adopted) the ramps brake
                # with what the two axles reach beside the curve's lateral force
                # (docs/decisions/0106).
                PitchTransfer.of(par) if cfg.reference_load_transfer else None,
            )
            if cfg.speed_ceiling and mode == "cruise":
                # The reference's speeds are the point mass's highest: a ceiling, not only a
                # target (a least-squares target let plans put off its braking ramps step after
                # step; docs/decisions/0088). Not while evading: the lane recovery's plans keep
                # the speed they have.
                ceiling = speed_ceiling_mps(
                    speed_ref[1:], float(x0[State.vx]), mu_ref(guess_x[:-1, State.s]),
                    cfg.reference_braking_fraction * accel_fraction, cfg.dt_s)
        stage = stage_parameters(guess_x, guess_u, curvature_of_s, mu_of_s, par,
                                 cfg.utilization_factor, cfg.stiffness_table,
                                 par.torque_time_constant_s if cfg.axle_friction else None,
                                 cfg.polygon_sides, cfg.front_axle_polygon)
        if secant_reserve is not None:
            stage = with_rear_secant_at_guess(stage, guess_x, guess_u, par,
                                              cfg.utilization_factor, secant_reserve)
        kappa = curvature_of_s(guess_x[1:, State.s])
        p = stage.p
        if cfg.heading_rows and mode != "evade":
            # The rows keep the body's ends in the lane at the plan's own heading; the bound on
            # d keeps the obstacles, and the lane only as a backstop that cannot duplicate the
            # rows (parallel active rows leave the QP degenerate).
            n_stages = guess_x.shape[0] - 1
            p = with_lane_band(p, np.full(n_stages, float(problem.lane_d_min_m)),
                               np.full(n_stages, float(problem.lane_d_max_m)))
            d_lo, d_hi = lateral_corridor(
                guess_x, problem.obstacles, problem.lane_d_min_m - LANE_BACKSTOP_M,
                problem.lane_d_max_m + LANE_BACKSTOP_M, par, cfg.obstacle_margin_m, kappa,
                cfg.dt_s, max_swing_rad=0.0, exact_reach=cfg.corridor_exact_reach)
        else:
            # Without the rows (the default), and while evading, the corridor counts the
            # guess's swing up to MAX_SWING_HEADING_RAD: evading, the heading reaches 0.3-0.5
            # rad and the obstacle margin covers the corners.
            d_lo, d_hi = lateral_corridor(
                guess_x, problem.obstacles, problem.lane_d_min_m, problem.lane_d_max_m, par,
                cfg.obstacle_margin_m, kappa, cfg.dt_s, exact_reach=cfg.corridor_exact_reach)
        yref, weights = tracking_reference(
            cfg, stage.curvature_1pm, stage.mu_hat, mode, float(x0[State.vx]),
            speed_ref, problem.reference_d_m,
            _steady_attitude(guess_x, stage, par) if cfg.steady_attitude_reference
            and mode == "cruise" else None,
        )
        status = -1
        try:
            status, xs, us = backend.solve(
                x0, guess_x, guess_u, p, yref, weights, d_lo, d_hi,
                0.0 if braking else cfg.min_speed_mps,
                _drive_cap_n(par, cfg, mode, guess_x, speed_ref),
                stage.front_brake_limit_n,
                ceiling,
            )
            retried = retried or backend.last_solve_retried
            if status not in (0, 2):
                reason = FallbackReason.SOLVER_STATUS
            else:
                reason, failed = judge_solution(xs, us, stage, d_lo, d_hi, par,
                                                cfg.polygon_sides, cfg.plausibility,
                                                load_transfer=cfg.load_transfer,
                                                rear_saturation=cfg.rear_saturation)
                soft_only = bool(failed) and set(failed) <= SOFT_CHECKS
        except Exception as exc:  # never raise inside the loop
            _log.warning("planner backend raised %r", exc)
            reason = FallbackReason.EXCEPTION
        if reason is not FallbackReason.NONE:
            break
    return Iterated(xs, us, guess_x, guess_u, stage, status, reason, retried, soft_only)


def _steady_attitude(guess_x: np.ndarray, stage: StageParameters,
                     par: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """The curve's steady attitude per stage 0..N at the guess's speeds (the last stage's
    curvature and stiffness held at N)."""
    return steady_cornering_attitude(np.append(stage.curvature_1pm, stage.curvature_1pm[-1]),
                                     guess_x[:, State.vx],
                                     np.append(stage.rear_stiffness_n_per_rad,
                                               stage.rear_stiffness_n_per_rad[-1]), par)


def _drive_cap_n(par: VehicleParams, cfg: PlannerConfig, mode: PlannerMode,
                 guess_x: np.ndarray, speed_ref: float | np.ndarray) -> float | np.ndarray:
    """The rear drive's bound for one solve: per stage, or one for all stages."""
    # No traction while evading or stopping: the rear tires' friction is kept for lateral
    # force and braking. In cruise, traction is capped at a heavy vehicle's acceleration, not at
    # the friction limit: regaining speed at the limit after an evasion leaves the driven axle
    # no lateral reserve. With ``reference_drive_cap`` (off: measured, not adopted,
    # docs/decisions/0105), none at stages above the curve speed reference.
    if mode != "cruise":
        return 0.0
    cap = par.mass_kg * cfg.max_cruise_accel_mps2
    if not cfg.reference_drive_cap or np.ndim(speed_ref) == 0:
        return cap
    n = cfg.horizon_steps
    return drive_caps_n(guess_x[:n, State.vx], np.asarray(speed_ref)[:n], cap)


def plan_of(
    par: VehicleParams,
    cfg: PlannerConfig,
    problem: StepProblem,
    solved: Iterated,
    states_inputs: tuple[np.ndarray, np.ndarray],
    t_s: float,
    started_s: float,
    sampled: bool,
    consecutive_fallbacks: int,
) -> Plan:
    """The step's plan from its states and inputs (the last iterate, or the guess if the
    iterations failed) and what they were solved with; ``started_s``: the step's
    ``time.perf_counter()`` at the start, for its solve time."""
    xs, us = states_inputs
    stage = solved.stage
    good = solved.reason is FallbackReason.NONE
    fyr = rear_lateral_force_n(xs[:-1].T, plan_rear_stiffness(
        stage.rear_stiffness_n_per_rad, stage.fzr_n, us.T, par, cfg.load_transfer), par)
    # The loads and radii the plan was solved with (its own, with load transfer).
    limit_front, limit_rear = plan_polygon_radii_n(us, stage, par, cfg.load_transfer)
    load_front, load_rear = stage.fzf_n, stage.fzr_n
    if cfg.load_transfer:
        load_front, load_rear = axle_loads_n(us, par)
    return Plan(
        t0_s=float(t_s), states=xs, inputs=us, rear_lateral_force_n=np.asarray(fyr),
        mu_hat=stage.mu_hat, normal_load_front_n=load_front,
        normal_load_rear_n=load_rear, force_limit_front_n=limit_front,
        force_limit_rear_n=limit_rear, status=int(solved.status), ok=good,
        fallback=not good, solve_time_s=time.perf_counter() - started_s,
        sampled_reinit=sampled, robust_qp_retry=solved.retried, dt_s=cfg.dt_s,
        fallback_reason=solved.reason,
        consecutive_fallbacks=consecutive_fallbacks,
        mu_sanitized_stages=problem.mu_of_s.last_count, mode=problem.mode,
    )


def held_plan(par: VehicleParams, cfg: PlannerConfig, problem: StepProblem, t_s: float,
              sampling: SamplingConfig | None = None) -> Plan:
    """The plan of a stop at rest: the vehicle held where it is with the brakes on (the
    minimal-risk roll-out below the model's slip-speed floor,
    :func:`~mufusion.planner.minimal_risk.minimal_risk_rollout`), marked ``held``, no solve.
    Where the braking the wheels deliver ends the stop whatever is planned, the OCP's kinetic
    braking would take the speed below its bound and the QP is infeasible; a held stop is a
    plan, not a fallback (docs/decisions/0098)."""
    started = time.perf_counter()
    xs, us = minimal_risk_rollout(problem.x0, problem.reference_d_m, problem.curvature_of_s,
                                  problem.mu_of_s, par, cfg, sampling)
    stage = stage_parameters(xs, us, problem.curvature_of_s, problem.mu_of_s, par,
                             cfg.utilization_factor, cfg.stiffness_table, None,
                             cfg.polygon_sides, cfg.front_axle_polygon)
    held = Iterated(xs, us, xs, us, stage, 0, FallbackReason.NONE, False)
    return replace(plan_of(par, cfg, problem, held, (xs, us), t_s, started, False, 0),
                   held=True)
