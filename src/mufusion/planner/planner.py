"""Traction-adaptive MPC planner (Svensson & Törngren, Sec. II; TAMP framework).

Each :meth:`TractionAdaptivePlanner.step` shifts the previous plan, evaluates the per-stage friction
estimate, normal loads and rear stiffness at the guess's predicted positions, builds the lateral
corridor and runs one real-time iteration. A failed or non-finite solve keeps the shifted plan,
is counted and logged, and never raises.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from mufusion.planner.ocp import (
    CostWeights,
    PlannerConfig,
    PlannerObstacle,
    lateral_corridor,
    stage_parameters,
)
from mufusion.planner.sampling import (
    SHIFTED_DISCOUNT,
    VIOLATION_WEIGHT,
    SamplingConfig,
    candidate_rollouts,
    tracking_cost,
    violation_m,
)
from mufusion.planner.speed_profile import curve_speed_reference_mps
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    State,
    frenet_bicycle_dynamics,
    rear_lateral_force_n,
)

_log = logging.getLogger(__name__)

__all__ = ["CostWeights", "Plan", "PlannerConfig", "PlannerObstacle", "TractionAdaptivePlanner"]


@dataclass(frozen=True)
class Plan:
    """One planning step's result (stage k at time ``t0_s + k·dt``)."""

    t0_s: float
    states: np.ndarray
    inputs: np.ndarray
    rear_lateral_force_n: np.ndarray
    mu_hat: np.ndarray
    normal_load_front_n: np.ndarray
    normal_load_rear_n: np.ndarray
    force_limit_front_n: np.ndarray
    force_limit_rear_n: np.ndarray
    status: int
    ok: bool
    fallback: bool
    solve_time_s: float
    sampled_reinit: bool = False
    dt_s: float = 0.1


def rollout(
    x0: np.ndarray, inputs: np.ndarray, curvature: np.ndarray, rear_stiffness: np.ndarray,
    params: VehicleParams, dt_s: float,
) -> np.ndarray:
    """RK4 roll-out of the planner model; ``inputs (N, 3, ...)`` → states ``(N+1, 6, ...)``."""
    xs = [np.asarray(x0, dtype=float)]
    for k in range(inputs.shape[0]):
        x, u, c, cr = xs[-1], inputs[k], curvature[k], rear_stiffness[k]
        k1 = frenet_bicycle_dynamics(x, u, c, cr, params)
        k2 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k1, u, c, cr, params)
        k3 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k2, u, c, cr, params)
        k4 = frenet_bicycle_dynamics(x + dt_s * k3, u, c, cr, params)
        xs.append(x + dt_s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4))
    return np.stack(xs)


class TractionAdaptivePlanner:
    """Real-time traction-adaptive planner; keeps the warm start between calls."""

    def __init__(
        self,
        params: VehicleParams,
        config: PlannerConfig | None = None,
        sampling: SamplingConfig | None = None,
    ) -> None:
        self.params = params
        self.config = config or PlannerConfig()
        self.failures = 0
        self.sampling = sampling or SamplingConfig()
        self._prev: Plan | None = None
        self._backend = None
        if self.config.backend == "acados":
            try:
                from mufusion.planner.acados_backend import AcadosBackend

                self._backend = AcadosBackend(params, self.config)
            except Exception as exc:  # any build/load failure → reference backend
                _log.warning("acados unavailable (%s); falling back to the CasADi backend", exc)
        if self._backend is None:
            from mufusion.planner.casadi_backend import CasadiBackend

            self._backend = CasadiBackend(params, self.config)

    # -- the guess ------------------------------------------------------------------------------
    def _initial_guess(self, x0: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        n, dt = self.config.horizon_steps, self.config.dt_s
        prev = self._prev
        if prev is not None and np.all(np.isfinite(prev.states)):
            shift = int(np.clip(round((t_s - prev.t0_s) / dt), 0, n))
            if shift <= n - 1 and abs(prev.states[shift, State.s] - x0[State.s]) < 10.0:
                xs = np.concatenate([prev.states[shift:], np.repeat(prev.states[-1:], shift, 0)])
                us = np.concatenate([prev.inputs[shift:], np.repeat(prev.inputs[-1:], shift, 0)])
                xs = xs.copy()
                xs[0] = x0
                return xs, us
        # Cold start: coast at the current speed along the current offset.
        k = np.arange(n + 1)[:, None]
        xs = np.tile(x0, (n + 1, 1)).astype(float)
        xs[:, State.s] = x0[State.s] + k[:, 0] * dt * max(x0[State.vx], 0.0)
        xs[1:, State.dpsi] = xs[1:, State.psidot] = xs[1:, State.vy] = 0.0
        return xs, np.zeros((n, N_INPUTS))

    # -- one planning step ----------------------------------------------------------------------
    def step(
        self,
        x0: np.ndarray,
        t_s: float,
        curvature_of_s: Callable[[np.ndarray], np.ndarray],
        mu_hat_of_s: Callable[[np.ndarray], np.ndarray],
        obstacles: Sequence[PlannerObstacle] = (),
        mode: Literal["cruise", "evade", "emergency"] = "cruise",
        reference_speed_mps: float = 10.0,
        reference_d_m: float = 0.0,
        lane_d_min_m: float | None = None,
        lane_d_max_m: float | None = None,
    ) -> Plan:
        """Plan from ``x0`` (Frenet state, shape (6,)) at time ``t_s`` [s].

        Parameters
        ----------
        x0
            Current state (s, d, Δψ, ψ̇, v_x, v_y) in the road-aligned frame.
        t_s
            Time of ``x0`` [s]; stage k of the plan is at ``t_s + k·dt``.
        curvature_of_s, mu_hat_of_s
            Road curvature [1/m] and friction estimate [-] as functions of absolute progress [m].
        obstacles
            :class:`PlannerObstacle` (or ``(s_m, d_m, length_m, width_m)`` tuples).
        mode
            ``"cruise"`` (track speed and offset), ``"evade"`` (obstacles ahead: speed is
            held at most at its current value with a light weight, so the tires' friction goes to
            the lateral manoeuvre rather than to regaining speed) or ``"emergency"`` (stop short).
        reference_speed_mps, reference_d_m
            Cruise references.
        lane_d_min_m, lane_d_max_m
            Bounds on the reference point's lateral offset [m] (lane or road edges already shrunk
            by half the vehicle width); default from the config.

        Returns
        -------
        Plan

        Raises
        ------
        ValueError
            If ``x0`` is not a finite 6-vector or ``mode`` is unknown.
        """
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (N_STATES,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"x0 must be a finite array of shape (6,), got {x0!r}")
        if mode not in ("cruise", "evade", "emergency"):
            raise ValueError(f"mode must be 'cruise', 'evade' or 'emergency', got {mode!r}")
        if mode == "evade":
            reference_speed_mps = min(reference_speed_mps, float(x0[State.vx]))
        cfg, par = self.config, self.params
        lo_lane = cfg.lane_d_min_m if lane_d_min_m is None else lane_d_min_m
        hi_lane = cfg.lane_d_max_m if lane_d_max_m is None else lane_d_max_m
        obstacles = [
            o if isinstance(o, PlannerObstacle) else PlannerObstacle(*map(float, o))
            for o in obstacles
        ]
        started = time.perf_counter()
        guess_x, guess_u = self._initial_guess(x0, t_s)
        sampled = False
        if cfg.use_sampling:
            v_ref = 0.0 if mode == "emergency" else reference_speed_mps
            guess_x, guess_u, sampled = self._sample(
                x0, guess_x, guess_u, curvature_of_s, mu_hat_of_s, obstacles, v_ref,
                reference_d_m, lo_lane, hi_lane,
            )
        # One real-time iteration per step; a cold start has no converged plan to iterate from,
        # so it takes a few (re-linearised at each iterate, as the next steps would).
        iterations = 1 if self._prev is not None else cfg.cold_start_iterations
        xs, us = guess_x, guess_u
        for _ in range(iterations):
            guess_x, guess_u = xs, us
            stage = stage_parameters(
                guess_x, guess_u, curvature_of_s, mu_hat_of_s, par, cfg.utilization_factor
            )
            d_lo, d_hi = lateral_corridor(
                guess_x, obstacles, lo_lane, hi_lane, par, cfg.obstacle_margin_m,
                curvature_of_s(guess_x[1:, State.s]),
            )
            speed_ref: float | np.ndarray = reference_speed_mps
            if cfg.curve_speed_reference and mode != "emergency":
                speed_ref = curve_speed_reference_mps(
                    guess_x[:, State.s], curvature_of_s, mu_hat_of_s, reference_speed_mps,
                    cfg.utilization_factor * np.cos(np.pi / cfg.polygon_sides),
                    cfg.horizon_steps * cfg.dt_s,
                )
            yref, weights = self._reference(stage["curvature"], mode, speed_ref, reference_d_m)
            status = -1
            try:
                status, xs, us = self._backend.solve(
                    x0, guess_x, guess_u, stage["p"], yref, weights, d_lo, d_hi,
                    0.0 if mode == "emergency" else cfg.min_speed_mps,
                    # No traction while evading or stopping: the rear tires' friction is kept
                    # for lateral force and braking. In cruise, traction is capped at a heavy
                    # vehicle's acceleration, not at the friction limit: regaining speed at the
                    # limit after an evasion leaves the driven axle no lateral reserve.
                    par.mass_kg * cfg.max_cruise_accel_mps2 if mode == "cruise" else 0.0,
                )
                good = status in (0, 2) and np.all(np.isfinite(xs)) and np.all(np.isfinite(us))
            except Exception as exc:  # never raise inside the loop
                _log.warning("planner backend raised %r", exc)
                good = False
            if not good:
                break
        fallback = False
        if not good:
            self.failures += 1
            fallback = True
            _log.warning("planner solve failed (status %s, %d failures so far); keeping the "
                         "shifted plan", status, self.failures)
            xs, us = guess_x, guess_u
        fyr = rear_lateral_force_n(xs[:-1].T, stage["rear_stiffness"], par)
        plan = Plan(
            t0_s=float(t_s), states=xs, inputs=us, rear_lateral_force_n=np.asarray(fyr),
            mu_hat=stage["mu_hat"], normal_load_front_n=stage["fzf"],
            normal_load_rear_n=stage["fzr"], force_limit_front_n=stage["radius_front"],
            force_limit_rear_n=stage["radius_rear"], status=int(status), ok=bool(good),
            fallback=fallback, solve_time_s=time.perf_counter() - started,
            sampled_reinit=sampled, dt_s=cfg.dt_s,
        )
        self._prev = plan
        return plan

    def _sample(self, x0, guess_x, guess_u, curvature_of_s, mu_hat_of_s, obstacles, v_ref, d_ref,
                lo_lane, hi_lane):
        """SAA: replace the shifted guess by the best sampled roll-out when that beats it."""
        cfg, par, sc = self.config, self.params, self.sampling
        try:
            shifted_violation = float(violation_m(
                guess_x[:, :, None], obstacles, lo_lane, hi_lane, par, cfg.obstacle_margin_m
            )[0])
            if self._prev is not None and shifted_violation <= sc.trigger_violation_m:
                return guess_x, guess_u, False
            lateral = np.append(np.linspace(lo_lane, hi_lane, sc.n_lateral), d_ref)
            speeds = np.append(np.asarray(sc.speed_fractions) * v_ref, x0[State.vx])
            with np.errstate(all="ignore"):  # diverging candidates are discarded below
                xs, us = candidate_rollouts(
                    x0, lateral, speeds, curvature_of_s, mu_hat_of_s, par,
                    cfg.utilization_factor, cfg.horizon_steps, cfg.dt_s, sc,
                )
            both = np.concatenate([guess_x[:, :, None], xs], axis=2)
            with np.errstate(all="ignore"):
                tracking = tracking_cost(both, v_ref, d_ref)
            tracking[0] *= SHIFTED_DISCOUNT
            cost = tracking + VIOLATION_WEIGHT * violation_m(
                both, obstacles, lo_lane, hi_lane, par, cfg.obstacle_margin_m
            )
            cost = np.where(np.isfinite(cost), cost, np.inf)
            best = int(np.argmin(cost))
            if best == 0 or not np.isfinite(cost[best]):
                return guess_x, guess_u, False
            return xs[:, :, best - 1], us[:, :, best - 1], True
        except Exception as exc:  # sampling is an aid; never let it break the loop
            _log.warning("sampling augmentation failed: %r", exc)
            return guess_x, guess_u, False

    def _reference(
        self, curvature: np.ndarray, mode: str, v_ref: float | np.ndarray, d_ref: float
    ):
        w: CostWeights = self.config.weights
        n = self.config.horizon_steps
        f_w = w.force_per_kn * 1e-6
        speed_w, v = {
            "emergency": (w.emergency_speed, 0.0),
            "evade": (w.evade_speed, v_ref),
        }.get(mode, (w.speed, v_ref))
        weights = np.array([0.0, w.lateral_offset, w.heading_error, w.yaw_rate, speed_w,
                            w.lateral_speed, f_w, f_w, f_w])
        yref = np.zeros((n + 1, N_STATES + N_INPUTS))
        yref[:, State.d] = d_ref
        yref[:, State.vx] = v
        kappa = np.append(curvature, curvature[-1])
        # In a curve of curvature κ the steady yaw rate is κ v.
        yref[:, State.psidot] = kappa * v
        return yref, weights


