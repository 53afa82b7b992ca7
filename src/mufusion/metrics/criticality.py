"""Criticality measures of a run with obstacles: time to collision, time to brake, and the
deceleration a collision-free outcome requires against what the road's friction offers.

Everything is measured along the reference path with constant velocities (the obstacle's speed
along the path, the vehicle's progress rate now), per controller tick and obstacle; the run's
summary takes the worst tick (:func:`criticality_summary`). Definitions and formulas:
docs/metrics.md, "Criticality measures". The functions of arrays are pure; :func:`criticality`
reads a run's log only.

A tick counts for an obstacle when the obstacle is present, its far end lies ahead of the
vehicle's front and the front edge overlaps it sideways: the front edge's centre at
``(s_f, d_f) = (s + a cos Δψ, d + a sin Δψ)`` (``a`` from the CoG to the footprint's front),
``|d_f − d_o| < (w |cos Δψ| + w_o) / 2`` (the widths: geometry, no margin). At the start of an
evasion the nose swings clear of the obstacle before the centre does; judged by the centre,
the obstacle would still be in the path, nose beside it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from mufusion.road import Obstacle, obstacle_active
from mufusion.sim.log import RunLog
from mufusion.sim.records import ObstacleTrace, RunMeta
from mufusion.vehicle.params import GRAVITY_MPS2

FloatArray = npt.NDArray[np.float64]


def time_to_collision_s(gap_m: np.ndarray, closing_speed_mps: np.ndarray) -> FloatArray:
    """Time until the gap closes at constant velocities [s]: ``gap / v_rel``.

    ``inf`` where the vehicle does not close in (``v_rel ≤ 0``) or the gap is NaN (no obstacle
    in the path); 0 where the gap is already closed (``gap ≤ 0``, closing).

    Examples
    --------
    >>> time_to_collision_s(np.array([30.0, 30.0, -1.0]), np.array([10.0, -2.0, 5.0])).tolist()
    [3.0, inf, 0.0]
    """
    gap, rel = np.broadcast_arrays(np.asarray(gap_m, float), np.asarray(closing_speed_mps, float))
    closing = np.isfinite(gap) & (rel > 0.0)
    # np.where computes both branches; a closing speed of a few ulp overflows to inf, which is
    # the time it gives.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        ttc = np.where(closing, np.maximum(gap, 0.0) / rel, np.inf)
    return ttc.astype(float)


def required_deceleration_mps2(gap_m: np.ndarray, closing_speed_mps: np.ndarray) -> FloatArray:
    """The constant deceleration that brings the closing speed to 0 just at the gap [m/s²]:
    ``v_rel² / (2 gap)``.

    0 where the vehicle does not close in or no obstacle is in the path; ``inf`` where the gap
    is already closed while closing. Relative to the obstacle: for a static or a leading
    obstacle it is the deceleration to stop short of it or match its speed; for an oncoming one
    the standard definition (commonroad-crime's ``ALongReq``) still asks for the relative speed
    to vanish, which braking alone cannot give (the ratio then says how far out of reach).

    Examples
    --------
    >>> required_deceleration_mps2(np.array([25.0, 25.0]), np.array([10.0, 0.0])).tolist()
    [2.0, 0.0]
    """
    gap, rel = np.broadcast_arrays(np.asarray(gap_m, float), np.asarray(closing_speed_mps, float))
    closing = np.isfinite(gap) & (rel > 0.0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        need = np.where(gap > 0.0, rel**2 / (2.0 * gap), np.inf)
    return np.where(closing, need, 0.0).astype(float)


def time_to_brake_s(
    gap_m: np.ndarray,
    closing_speed_mps: np.ndarray,
    obstacle_speed_mps: np.ndarray | float,
    deceleration_mps2: np.ndarray | float,
) -> FloatArray:
    """Time left until full braking no longer stops short or matches the obstacle's speed [s].

    Braking at ``a`` after ``τ`` at constant velocity consumes ``v_rel τ + v_rel² / (2a)`` of
    the gap, so ``TTB = TTC − v_rel / (2a)``; negative when braking now is already too late.
    ``inf`` where the vehicle does not close in; NaN for an oncoming obstacle (speed < 0: a
    vehicle that keeps coming is not avoided by braking) and where ``a ≤ 0``.

    Examples
    --------
    >>> # 30 m, closing at 10 m/s, braking at 5 m/s²: 3 s − 1 s.
    >>> time_to_brake_s(np.array([30.0]), np.array([10.0]), 0.0, 5.0).tolist()
    [2.0]
    >>> time_to_brake_s(np.array([30.0]), np.array([25.0]), -15.0, 5.0).tolist()
    [nan]
    """
    gap, rel, v_o, decel = np.broadcast_arrays(
        np.asarray(gap_m, float), np.asarray(closing_speed_mps, float),
        np.asarray(obstacle_speed_mps, float), np.asarray(deceleration_mps2, float))
    ttc = time_to_collision_s(gap, rel)
    with np.errstate(divide="ignore", invalid="ignore"):
        ttb = np.where(np.isfinite(ttc), ttc - rel / (2.0 * decel), np.inf)
    return np.where((v_o < 0.0) | ~(decel > 0.0), np.nan, ttb).astype(float)


@dataclass(frozen=True)
class Criticality:
    """Per-tick criticality of a run, the worst obstacle at each tick (shape ``(T,)`` each).

    Attributes
    ----------
    t_s
        Tick times [s].
    time_to_collision_s, time_to_brake_s
        :func:`time_to_collision_s`; :func:`time_to_brake_s` braking at ``λ μ g`` with the true
        μ under the vehicle (the lower axle's) and the planner's λ.
    required_deceleration_mps2
        :func:`required_deceleration_mps2`.
    required_over_mu_g
        ``required_deceleration_mps2 / (μ g)``, μ the true friction under the vehicle: above 1
        no tire can deliver it.
    required_over_mu_hat_g
        The same against the planner's estimate μ̂ under the vehicle (the first grid point of
        the latest planning step's estimate); NaN where the log has none.
    """

    t_s: FloatArray
    time_to_collision_s: FloatArray
    time_to_brake_s: FloatArray
    required_deceleration_mps2: FloatArray
    required_over_mu_g: FloatArray
    required_over_mu_hat_g: FloatArray


def _present(obstacle: ObstacleTrace, t_s: np.ndarray, s_m: np.ndarray) -> np.ndarray:
    """Whether the obstacle is there at each tick (its triggers, as the world applies them)."""
    return obstacle_active(Obstacle(
        obstacle.s_m, obstacle.d_m, obstacle.length_m, obstacle.width_m,
        appear_at_ego_s_m=obstacle.appear_ego_s_m, appear_at_time_s=obstacle.appear_time_s,
    ), s_m, t_s)


def _mu_hat_under_vehicle(log: RunLog, t_s: np.ndarray) -> FloatArray:
    """μ̂ at the first grid point of the latest planning step at or before each tick."""
    est = log.estimates
    if est.empty or "mu_hat" not in est:
        return np.full(t_s.shape, np.nan)
    first = est.sort_values(["t_s", "s_ahead_m"]).groupby("step", sort=False).first()
    first = first.sort_values("t_s")
    steps_t = first["t_s"].to_numpy(float)
    idx = np.searchsorted(steps_t, t_s, side="right") - 1
    mu = first["mu_hat"].to_numpy(float)
    return np.where(idx >= 0, mu[np.clip(idx, 0, len(mu) - 1)], np.nan)


def _ego_geometry(meta: RunMeta) -> tuple[float, float]:
    """Distance from the CoG to the footprint's front [m] and the footprint's width [m]."""
    v = meta.vehicle
    # The footprint is centred midway between the axles (sim.world).
    return 0.5 * v.length_m + 0.5 * (v.cog_to_front_axle_m - v.cog_to_rear_axle_m), v.width_m


def criticality(log: RunLog) -> Criticality | None:
    """The run's per-tick criticality; None without obstacles (or without ticks).

    The vehicle's progress rate is ``(v_x cos Δψ − v_y sin Δψ) / (1 − κ d)`` (the Frenet
    kinematics); an obstacle's is its ``speed_mps``.
    """
    meta, ts = log.meta, log.timeseries
    if not meta.obstacles or ts.empty:
        return None
    t = ts["t_s"].to_numpy(float)
    s, d = ts["s_m"].to_numpy(float), ts["d_m"].to_numpy(float)
    dpsi = ts["dpsi_rad"].to_numpy(float)
    kappa = np.interp(s, np.asarray(meta.road.s_m, float), np.asarray(meta.road.curvature_1pm,
                                                                      float))
    v_ego = ((ts["vx_mps"].to_numpy(float) * np.cos(dpsi) - ts["vy_mps"].to_numpy(float)
              * np.sin(dpsi)) / (1.0 - kappa * d))
    front_m, width_m = _ego_geometry(meta)
    s_front, d_front = s + front_m * np.cos(dpsi), d + front_m * np.sin(dpsi)
    half_width = 0.5 * width_m * np.abs(np.cos(dpsi))
    mu_true = np.minimum(ts["mu_front"].to_numpy(float), ts["mu_rear"].to_numpy(float))
    decel = meta.planner.utilization_factor * mu_true * GRAVITY_MPS2
    ttc = np.full(t.shape, np.inf)
    ttb = np.full(t.shape, np.inf)
    need = np.zeros(t.shape)
    for ob in meta.obstacles:
        s_o = ob.s_at_time(t)
        gap = np.asarray(s_o - 0.5 * ob.length_m - s_front, float)
        ahead = s_o + 0.5 * ob.length_m > s_front  # its far end ahead of the front
        relevant = (_present(ob, t, s) & ahead
                    & (np.abs(d_front - ob.d_m) < half_width + 0.5 * ob.width_m))
        gap = np.where(relevant, gap, np.nan)
        rel = v_ego - ob.speed_mps
        ttc = np.minimum(ttc, time_to_collision_s(gap, rel))
        ttb = np.fmin(ttb, time_to_brake_s(gap, rel, ob.speed_mps, decel))
        need = np.maximum(need, required_deceleration_mps2(gap, rel))
    with np.errstate(divide="ignore", invalid="ignore"):
        over_mu = need / (mu_true * GRAVITY_MPS2)
        over_mu_hat = need / (_mu_hat_under_vehicle(log, t) * GRAVITY_MPS2)
    return Criticality(t, ttc, ttb, need, over_mu, over_mu_hat)


def criticality_summary(log: RunLog) -> dict[str, Any]:
    """The run's worst criticality for ``summary.json``: the smallest TTC and TTB [s], the
    largest required deceleration [m/s²] and its largest ratios to ``μ g`` and ``μ̂ g``.

    Each is None when it never applied (no obstacle, never closing in, no estimate). A gap
    already closed (a collision: TTC 0) asks for an unbounded deceleration, which is left out of
    the maxima: the run's ``collision`` reports it.
    """
    crit = criticality(log)
    return {
        "min_time_to_collision_s": None if crit is None else _finite_min(crit.time_to_collision_s),
        "min_time_to_brake_s": None if crit is None else _finite_min(crit.time_to_brake_s),
        "max_required_decel_mps2": (
            None if crit is None else _positive_max(crit.required_deceleration_mps2)),
        "max_required_decel_over_mu_g": (
            None if crit is None else _positive_max(crit.required_over_mu_g)),
        "max_required_decel_over_mu_hat_g": (
            None if crit is None else _positive_max(crit.required_over_mu_hat_g)),
    }


def _finite_min(values: np.ndarray) -> float | None:
    finite = values[np.isfinite(values)]
    return float(finite.min()) if finite.size else None


def _positive_max(values: np.ndarray) -> float | None:
    """The largest finite value above 0, None if none."""
    kept = values[np.isfinite(values) & (values > 0.0)]
    return float(kept.max()) if kept.size else None
