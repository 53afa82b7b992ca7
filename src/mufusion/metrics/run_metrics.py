"""Per-run metrics, computed from a :class:`~mufusion.sim.log.RunLog` only (never the live loop)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import pandas as pd

from mufusion.metrics.criticality import criticality_summary
from mufusion.sim.events import ERROR_EVENTS, EventKind
from mufusion.sim.log import RunLog


@dataclass(frozen=True)
class RunMetrics:
    """The outcome of one run, as reported in ``summary.json``.

    Attributes
    ----------
    collision
        Whether the vehicle's footprint ever overlapped an obstacle.
    impact_speed_mps
        Speed at the first contact, ``None`` without collision.
    min_clearance_m
        Smallest footprint-to-obstacle distance while passing it; ``None`` if the vehicle never
        passed the obstacle (no obstacle, collision, or run ended before it).
    max_abs_lateral_offset_m
        Largest ``|d|`` of the vehicle's reference point from the ego-lane centre.
    left_lane, entered_opposing_lane
        Whether any corner of the footprint left the ego lane / entered the opposing lane
        (``max_lane_excursion_m > 0`` / ``max_opposing_lane_depth_m > 0``).
    max_lane_excursion_m
        Deepest footprint point outside the ego lane [m]; 0 if it never left.
    time_outside_lane_s
        Time with some of the footprint outside the ego lane [s].
    min_lane_margin_m
        Smallest distance of the footprint to an ego-lane edge [m]; negative when outside.
    max_opposing_lane_depth_m
        How deep the footprint reached into the opposing lane [m]; 0 if never.
    max_body_slip_rad
        Largest ``|β| = |atan2(v_y, v_x)|`` [rad] while moving faster than 2 m/s.
    spun
        ``max_body_slip_rad`` above :data:`SPIN_BODY_SLIP_RAD`, or a heading error to the road
        above π/2: the vehicle lost its yaw stability.
    off_road
        Whether any of the footprint left the road (both lanes).
    max_front_utilization
        Largest realised front-tire utilisation ``|F_f| / (μ F_z)`` [-] (1: the tires slide).
    planned_utilization_at_comparison
        Largest planned front-force utilisation ``|F_f| / F_zf`` over the plan made at the
        comparison instant (the paper's Fig. 3k / 4k); ``None`` if no plan was made then.
    utilization_vs_gt
        ``planned_utilization_at_comparison`` relative to the GT run's, minus one (paper: −32.6 %
        for P, −5.6 % for F); filled in by :func:`attach_gt_comparison`.
    max_force_excess
        Largest planned front tire force (F_xf, F_yf: the forces the planner decides, as in the
        paper's Fig. 3k/4k) above the true limit ``μ_gt(s_k) F_z,k``, as a fraction of that limit
        (0 when every planned force was physically available). The rear lateral force is left
        out: in the planner it is not a decision but follows the predicted state, and after a
        slide its linear-tire value says nothing about what was planned.
    planner_median_ms, planner_p99_ms
        Wall-clock time per planning step.
    fallbacks
        Planning steps that fell back to the shifted previous plan or a braking plan.
    sampling_reinits
        Planning steps whose initial guess came from the sampling augmentation.
    robust_qp_retries
        Planning steps whose fast QP failed and were solved again in the robust mode
        (:mod:`mufusion.planner.acados_backend`); a retry that also fails is a fallback.
    solver_messages
        Messages the solver library printed during the run (e.g. ``SQP_RTI: QP solver returned
        error status 3``), kept in the log's ``solver_messages.txt``
        (:mod:`mufusion.sim.solver_output`).
    feasibility, feasibility_margin_mps
        The physics oracle's class of the variant (feasible / marginal / infeasible) and its
        margin [m/s] (:mod:`mufusion.scenarios.feasibility`), from the run's metadata.
    planner_backend
        The OCP solver the package's planner ran (``AcadosBackend``; ``CasadiBackend`` where
        acados could not be loaded), from the run's metadata (None: a plug-in planner).
    faults_injected
        Faults the scenario injected (``[[faults]]``).
    estimate_fallbacks
        Planning steps that did not get a current, finite estimate: the last valid one or the
        friction floor was used instead (see :class:`~mufusion.sim.loop.ClosedLoop`).
    component_errors
        Exceptions raised by a component (friction source, planner, controller) or the loop.
    minimal_risk
        Whether the vehicle entered the minimal-risk manoeuvre; ``minimal_risk_at_s`` when.
    faults, reactions
        The injected fault kinds, and the loop's reactions counted by kind
        (e.g. ``"estimate_fallback×3, minimal_risk×1"``; empty when none).
    wheel_lock_max_s
        Longest time a wheel stayed locked [s]: slip ratio at or below
        :data:`LOCKED_SLIP` moving forwards faster than :data:`SLIP_MIN_SPEED_MPS`, the vehicle
        not spinning (``|β|`` ≤ :data:`SPIN_BODY_SLIP_RAD`) (0 if never; ``None`` in
        records written before wheel slips were logged). With slip control on it stays within
        one ABS cycle (:data:`ONE_ABS_CYCLE_S`).
    wheel_lock_within_abs_cycle
        ``wheel_lock_max_s`` ≤ :data:`ONE_ABS_CYCLE_S`: no wheel stayed locked for longer than
        one ABS cycle (``None`` in records written before wheel slips were logged).
    slip_control_cycles
        Cycles the vehicle's wheel-slip control (ABS, TCS) ran, both axles.
    slip_control_active_s
        Time with the slip control modulating either axle's torque [s].
    stability_control_active_s
        Time with the stability control (ESC) applying a yaw moment [s] (ticks whose plant step
        had one; 0 without ESC).
    min_time_to_collision_s, min_time_to_brake_s
        Smallest time to collision and time to brake over the run [s] (along the path, constant
        velocities; braking at ``λ μ g``): :mod:`mufusion.metrics.criticality`, docs/metrics.md.
        ``None`` without an obstacle ahead in the path that the vehicle closes in on.
    max_required_decel_mps2, max_required_decel_over_mu_g, max_required_decel_over_mu_hat_g
        Largest deceleration a collision-free outcome required [m/s²], and its largest ratio to
        ``μ g`` (true μ under the vehicle) and to ``μ̂ g`` (the planner's estimate there).
    start_speed_mps, start_lateral_offset_m, start_heading_error_rad
        The state the run started from (its first tick): the scenario's, or the draw of its
        ``perturbation`` (:func:`mufusion.scenarios.config.perturbed`). ``None`` in records
        written before they were kept.
    """

    collision: bool
    impact_speed_mps: float | None
    min_clearance_m: float | None
    max_abs_lateral_offset_m: float
    left_lane: bool
    entered_opposing_lane: bool
    max_lane_excursion_m: float
    time_outside_lane_s: float
    min_lane_margin_m: float
    max_opposing_lane_depth_m: float
    max_body_slip_rad: float
    spun: bool
    off_road: bool
    max_front_utilization: float
    planned_utilization_at_comparison: float | None
    utilization_vs_gt: float | None
    max_force_excess: float
    planner_median_ms: float | None
    planner_p99_ms: float | None
    fallbacks: int
    sampling_reinits: int
    final_speed_mps: float
    duration_s: float
    feasibility: str = "unknown"
    feasibility_margin_mps: float | None = None
    planner_backend: str | None = None
    faults_injected: int = 0
    # Defaults to 0: records written before the robust retry existed had none.
    robust_qp_retries: int = 0
    solver_messages: int = 0
    estimate_fallbacks: int = 0
    component_errors: int = 0
    minimal_risk: bool = False
    minimal_risk_at_s: float | None = None
    faults: str = ""
    reactions: str = ""
    start_speed_mps: float | None = None
    start_lateral_offset_m: float | None = None
    start_heading_error_rad: float | None = None
    wheel_lock_max_s: float | None = None
    wheel_lock_within_abs_cycle: bool | None = None
    slip_control_cycles: int = 0
    slip_control_active_s: float = 0.0
    stability_control_active_s: float = 0.0
    min_time_to_collision_s: float | None = None
    min_time_to_brake_s: float | None = None
    max_required_decel_mps2: float | None = None
    max_required_decel_over_mu_g: float | None = None
    max_required_decel_over_mu_hat_g: float | None = None

    def to_dict(self) -> dict[str, Any]:
        return {k: _clean(v) for k, v in asdict(self).items()}


def _clean(v: Any) -> Any:
    if isinstance(v, float | np.floating):
        return None if not math.isfinite(float(v)) else round(float(v), 6)
    if isinstance(v, np.bool_):
        return bool(v)
    if isinstance(v, np.integer):
        return int(v)
    return v


def _planned_utilization(plans: pd.DataFrame, t_c: float) -> float | None:
    if plans.empty:
        return None
    step_times = plans["t_s"].unique()
    idx = int(np.argmin(np.abs(step_times - t_c)))
    plan = plans[plans["t_s"] == step_times[idx]]
    force = np.hypot(plan["fxf_n"].to_numpy(), plan["fyf_n"].to_numpy())
    return float(np.max(force / plan["fzf_n"].to_numpy()))


def _max_force_excess(plans: pd.DataFrame) -> float:
    if plans.empty:
        return 0.0
    front = np.hypot(plans["fxf_n"], plans["fyf_n"]) / (plans["mu_true"] * plans["fzf_n"])
    return float(max(0.0, np.nanmax(front) - 1.0))


def compute_metrics(log: RunLog) -> RunMetrics:
    """Compute the run's metrics from its log.

    Raises
    ------
    ValueError
        If the log has no time series (an empty or foreign log).
    """
    ts = log.timeseries
    if ts.empty:
        raise ValueError("log has no timeseries rows: nothing to measure")
    collided = ts["in_collision"].astype(bool).to_numpy()
    collision = bool(collided.any())
    impact = float(ts["speed_mps"].to_numpy()[np.argmax(collided)]) if collision else None

    min_clearance = None
    if not collision and "passed_obstacle" in ts and ts["passed_obstacle"].astype(bool).any():
        clearance = ts["clearance_m"].to_numpy(dtype=float)
        if np.isfinite(clearance).any():
            min_clearance = float(np.nanmin(clearance))

    timing = log.timing
    steps = log.planning_steps
    t_c = log.meta.comparison_time_s
    return RunMetrics(
        collision=collision,
        impact_speed_mps=impact,
        min_clearance_m=min_clearance,
        max_abs_lateral_offset_m=float(np.max(np.abs(ts["d_m"]))),
        **_graded(ts, 1.0 / log.meta.rates.controller_hz),
        planned_utilization_at_comparison=_planned_utilization(log.plans, t_c),
        utilization_vs_gt=None,
        max_force_excess=_max_force_excess(log.plans),
        planner_median_ms=float(np.median(timing["step_ms"])) if not timing.empty else None,
        planner_p99_ms=(
            float(np.percentile(timing["step_ms"], 99)) if not timing.empty else None
        ),
        fallbacks=int(steps["fallback"].astype(bool).sum()) if not steps.empty else 0,
        sampling_reinits=(
            int(steps["sampled_reinit"].astype(bool).sum()) if not steps.empty else 0
        ),
        robust_qp_retries=(
            int(steps["robust_qp_retry"].astype(bool).sum()) if not steps.empty else 0
        ),
        solver_messages=len(log.solver_messages),
        final_speed_mps=float(ts["speed_mps"].iloc[-1]),
        duration_s=float(ts["t_s"].iloc[-1]),
        feasibility=log.meta.feasibility,
        feasibility_margin_mps=log.meta.feasibility_margin_mps,
        planner_backend=log.meta.planner_backend,
        **_reliability(log),
        start_speed_mps=float(ts["speed_mps"].iloc[0]),
        start_lateral_offset_m=float(ts["d_m"].iloc[0]),
        start_heading_error_rad=float(ts["dpsi_rad"].iloc[0]),
        **_wheels(ts, 1.0 / log.meta.rates.controller_hz),
        **criticality_summary(log),
    )


SPIN_BODY_SLIP_RAD = 0.35
"""Body slip [rad] (20°) beyond which a run counts as spun: far past the ≈ 0.1 rad a stability
controller starts intervening at, and more than a driver recovers without counter-steer."""
SLIP_MIN_SPEED_MPS = 2.0
"""Body slip is not judged below this speed [m/s] (its angle means nothing near standstill)."""


def _graded(ts: pd.DataFrame, tick_s: float) -> dict[str, Any]:
    """Graded lane and stability outcomes from the time series (one row per control tick)."""
    margin = ts["lane_margin_m"].to_numpy(dtype=float)
    opposing = ts["opposing_depth_m"].to_numpy(dtype=float)
    moving = ts["speed_mps"].to_numpy(dtype=float) > SLIP_MIN_SPEED_MPS
    slip = np.abs(ts["body_slip_rad"].to_numpy(dtype=float))[moving]
    max_slip = float(slip.max()) if slip.size else 0.0
    heading = float(np.abs(ts["dpsi_rad"].to_numpy(dtype=float)).max())
    util = ts["util_front"].to_numpy(dtype=float)
    return {
        "left_lane": bool((margin < 0.0).any()),
        "entered_opposing_lane": bool((opposing > 0.0).any()),
        "max_lane_excursion_m": float(max(0.0, -margin.min())),
        "time_outside_lane_s": float((margin < 0.0).sum() * tick_s),
        "min_lane_margin_m": float(margin.min()),
        "max_opposing_lane_depth_m": float(max(0.0, opposing.max())),
        "max_body_slip_rad": max_slip,
        "spun": bool(max_slip > SPIN_BODY_SLIP_RAD or heading > np.pi / 2),
        "off_road": bool(ts["off_road"].astype(bool).any()),
        "max_front_utilization": float(np.nanmax(util)) if np.isfinite(util).any() else 0.0,
    }


LOCKED_SLIP = -0.9
"""A wheel whose slip ratio is at or below this turns at a tenth of its free-rolling speed or
less: locked (it has lost nearly all its lateral grip)."""
ONE_ABS_CYCLE_S = 0.5
"""Longest lock [s] one ABS cycle lets through: production ABS cycles at 2–15 Hz (the slowest,
pneumatic truck brakes, at 2 Hz), and a lock lasts at most until the dumped brake torque has
fallen below what the sliding tire returns (a few brake time constants: car 0.05 s, truck
0.15 s). docs/vehicle.md, "Wheel-slip control"."""


def _longest_run_s(flags: np.ndarray, tick_s: float) -> float:
    """Longest stretch of consecutive true ``flags``, in seconds of ticks."""
    if not flags.any():
        return 0.0
    edges = np.diff(np.concatenate(([0], flags.astype(np.int8), [0])))
    return float((np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)).max() * tick_s)


def _wheels(ts: pd.DataFrame, tick_s: float) -> dict[str, Any]:
    """Wheel-lock and slip-control outcomes (absent columns: a record from before they were)."""
    if "wheel_slip_front" not in ts or ts["wheel_slip_front"].isna().all():
        return {}
    # A lock is counted while the vehicle moves forwards and does not spin: sliding sideways
    # (|β| past SPIN_BODY_SLIP_RAD) or backwards after a spin its wheels roll across or against
    # their own plane, where a slip ratio says nothing about the brakes.
    moving = (ts["vx_mps"].to_numpy(dtype=float) > SLIP_MIN_SPEED_MPS) & (
        np.abs(ts["body_slip_rad"].to_numpy(dtype=float)) <= SPIN_BODY_SLIP_RAD)
    locked = moving & (
        (ts["wheel_slip_front"].to_numpy(dtype=float) <= LOCKED_SLIP)
        | (ts["wheel_slip_rear"].to_numpy(dtype=float) <= LOCKED_SLIP)
    )
    active = ts["slip_control_front"].astype(bool) | ts["slip_control_rear"].astype(bool)
    longest = _longest_run_s(locked, tick_s)
    return {
        "wheel_lock_max_s": longest,
        "wheel_lock_within_abs_cycle": longest <= ONE_ABS_CYCLE_S,
        "slip_control_cycles": int(ts["slip_cycles"].iloc[-1]),
        "slip_control_active_s": float(active.sum() * tick_s),
        "stability_control_active_s": float(
            (ts["esc_yaw_moment_nm"] != 0.0).sum() * tick_s if "esc_yaw_moment_nm" in ts else 0.0),
    }


def _reliability(log: RunLog) -> dict[str, Any]:
    events, steps = log.events, log.planning_steps
    kinds = events["kind"].astype(str) if not events.empty else pd.Series(dtype=str)
    mrm = events[kinds == EventKind.MINIMAL_RISK] if not events.empty else events
    scheduled = kinds == EventKind.FAULT_SCHEDULED
    return {
        "faults_injected": int(scheduled.sum()),
        "estimate_fallbacks": (
            int(steps["estimate_source"].isin(["last_valid", "floor"]).sum())
            if not steps.empty else 0
        ),
        "component_errors": int(kinds.isin(ERROR_EVENTS).sum()),
        "minimal_risk": bool(len(mrm)),
        "minimal_risk_at_s": float(mrm["t_s"].iloc[0]) if len(mrm) else None,
        "faults": ", ".join(
            sorted({str(d).split(" ", 1)[0] for d in events["detail"][scheduled]})
        ) if not events.empty else "",
        "reactions": ", ".join(
            f"{kind}×{count}"
            for kind, count in kinds[~scheduled].value_counts().sort_index().items()
        ),
    }


def attach_gt_comparison(metrics: RunMetrics, gt: RunMetrics) -> RunMetrics:
    """Return ``metrics`` with ``utilization_vs_gt`` set from the same scenario's GT run."""
    ours, ref = metrics.planned_utilization_at_comparison, gt.planned_utilization_at_comparison
    ratio = None if ours is None or not ref else ours / ref - 1.0
    return RunMetrics(**{**asdict(metrics), "utilization_vs_gt": ratio})
