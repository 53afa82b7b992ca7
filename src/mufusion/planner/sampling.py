"""Sampling augmentation of the RTI initial guess (SAA-RTI, Svensson et al., arXiv 1903.04240).

Candidate manoeuvres (lateral targets × speed targets) are rolled out with the planner's own model
under a simple tracking law saturated at the friction limits, all at once in numpy. Each roll-out
and the shifted previous plan are scored on tracking plus a heavy penalty on obstacle and road
violations; the best becomes the initial guess when it beats the shifted plan. Because the
obstacle corridor's side is chosen by the guess, this is what lets the planner switch sides.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.planner.ocp import PlannerObstacle, longitudinal_force_bounds_n
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    frenet_bicycle_dynamics,
    rear_cornering_stiffness_n_per_rad,
)
from mufusion.vehicle.planner_rk4 import BatchRK4
from mufusion.vehicle.surface_tires import SurfaceTireTable

# Cost of one metre of obstacle/road violation relative to tracking (per stage) [1/m].
VIOLATION_WEIGHT = 1e4
# The shifted previous plan's tracking cost is discounted for consistency between cycles (TAMP:
# ×0.3); its violation is not, so a plan made obsolete by a pop-up obstacle loses.
SHIFTED_DISCOUNT = 0.3


@dataclass(frozen=True)
class SamplingConfig:
    """Candidate grid and tracking-law gains."""

    n_lateral: int = 9
    speed_fractions: tuple[float, ...] = (0.0, 0.5, 1.0)
    # Sample only when the shifted plan violates the current constraints by more than this [m].
    trigger_violation_m: float = 0.05
    heading_gain_1_per_s: float = 2.5
    yaw_rate_gain_1_per_s: float = 6.0
    speed_gain_1_per_s: float = 1.0
    min_lookahead_m: float = 5.0
    lookahead_time_s: float = 0.5


def violation_m(
    states: np.ndarray,
    obstacles: Sequence[PlannerObstacle],
    lane_d_min_m: float,
    lane_d_max_m: float,
    params: VehicleParams,
    margin_m: float,
) -> np.ndarray:
    """Summed footprint violation [m] of trajectories ``states (N+1, 6, M)`` → ``(M,)``."""
    s, d = states[1:, State.s], states[1:, State.d]
    half_w = 0.5 * params.width_m
    total = np.maximum(lane_d_min_m - d, 0.0) + np.maximum(d - lane_d_max_m, 0.0)
    for ob in obstacles:
        overlap = np.abs(s - ob.s_m) < 0.5 * params.length_m + 0.5 * ob.length_m + margin_m
        clear = 0.5 * ob.width_m + half_w + margin_m
        total = total + np.where(overlap, np.maximum(clear - np.abs(d - ob.d_m), 0.0), 0.0)
    return total.sum(axis=0)


def tracking_cost(states: np.ndarray, v_ref: float, d_ref: float) -> np.ndarray:
    """Speed and lateral tracking cost of trajectories ``(N+1, 6, M)`` → ``(M,)``."""
    x = states[1:]
    return ((x[:, State.vx] - v_ref) ** 2 + 0.5 * (x[:, State.d] - d_ref) ** 2).sum(axis=0)


def steering_force_n(
    x: np.ndarray,
    d_target_m: np.ndarray | float,
    curvature_1pm: np.ndarray | float,
    speed_mps: np.ndarray | float,
    params: VehicleParams,
    config: SamplingConfig,
) -> np.ndarray:
    """Front lateral force [N] of the roll-outs' steering law (before friction saturation).

    Pure pursuit of ``d_target_m`` at a speed-dependent look-ahead gives a desired heading error;
    the desired yaw rate follows the path's curvature plus a heading correction; the force is the
    steady share of the front axle plus a yaw-rate correction. ``speed_mps`` is already floored.
    """
    m, lf, iz = params.mass_kg, params.cog_to_front_axle_m, params.yaw_inertia_kgm2
    share_front = params.cog_to_rear_axle_m / params.wheelbase_m
    v = speed_mps
    lookahead = np.maximum(config.min_lookahead_m, config.lookahead_time_s * v)
    dpsi_des = np.arctan2(d_target_m - x[State.d], lookahead)
    r_des = curvature_1pm * v + config.heading_gain_1_per_s * (dpsi_des - x[State.dpsi])
    return share_front * m * v * r_des + iz / lf * config.yaw_rate_gain_1_per_s * (
        r_des - x[State.psidot]
    )


def rk4_step(
    x: np.ndarray,
    u: np.ndarray,
    curvature_1pm: np.ndarray | float,
    rear_stiffness: np.ndarray | float,
    params: VehicleParams,
    dt_s: float,
) -> np.ndarray:
    """One classical RK4 step of the planner's model (as acados' ERK with one stage)."""
    k1 = frenet_bicycle_dynamics(x, u, curvature_1pm, rear_stiffness, params)
    k2 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k1, u, curvature_1pm, rear_stiffness, params)
    k3 = frenet_bicycle_dynamics(x + 0.5 * dt_s * k2, u, curvature_1pm, rear_stiffness, params)
    k4 = frenet_bicycle_dynamics(x + dt_s * k3, u, curvature_1pm, rear_stiffness, params)
    return x + dt_s / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def candidate_rollouts(
    x0: np.ndarray,
    lateral_targets_m: np.ndarray,
    speed_targets_mps: np.ndarray,
    curvature_of_s,
    mu_hat_of_s,
    params: VehicleParams,
    utilization_factor: float,
    horizon_steps: int,
    dt_s: float,
    config: SamplingConfig,
    stiffness_table: SurfaceTireTable | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Roll out every (lateral target, speed target) pair.

    ``stiffness_table``: the rear stiffness follows μ̂ through it, as in the OCP (``None``: the
    vehicle's fixed tire).

    Returns
    -------
    states, inputs
        ``(N+1, 6, M)`` and ``(N, 3, M)`` with ``M = len(lateral) × len(speed)``.
    """
    d_t, v_t = (a.ravel() for a in np.meshgrid(lateral_targets_m, speed_targets_mps))
    m_count = d_t.size
    # The trajectories are written in place. Each step is the straightforward formulation's
    # arithmetic operand by operand (the tracking law below, rk4_step in BatchRK4) in numpy
    # calls on preallocated buffers, so the result is the straightforward loop's bit for bit
    # (tests/planner/test_sampling_rollouts.py compares them).
    states = np.empty((horizon_steps + 1, N_STATES, m_count))
    inputs = np.empty((horizon_steps, N_INPUTS, m_count))
    states[0] = np.asarray(x0, dtype=float)[:, None]
    rk4 = BatchRK4(params, m_count)
    law = _TrackingLaw(params, config, utilization_factor, d_t, v_t)
    for k in range(horizon_steps):
        x, u, x_next = states[k], inputs[k], states[k + 1]
        s_k = x[_S]
        kappa = _batch(curvature_of_s(s_k), m_count)
        mu = _batch(mu_hat_of_s(s_k), m_count)
        c_r = law.inputs(x, kappa, mu, u, stiffness_table)
        rk4.step(x, u, kappa, c_r, dt_s, x_next)
        vx_next = x_next[_VX]
        np.maximum(vx_next, _ZERO, out=vx_next)
    return states, inputs


def _batch(values: np.ndarray | float, m_count: int) -> np.ndarray:
    """``values`` as a float array of shape ``(m_count,)`` (broadcast as ``values * ones``)."""
    array = np.asarray(values, dtype=float)
    return array if array.shape == (m_count,) else array * np.ones(m_count)


# Positional ``out`` (numpy's keyword handling costs more than the arithmetic on these small
# arrays), except for maximum/minimum, whose positional form is deprecated.
_add, _sub, _mul, _div = np.add, np.subtract, np.multiply, np.divide
_max, _min, _square, _sqrt, _atan2 = np.maximum, np.minimum, np.square, np.sqrt, np.arctan2
_ZERO = np.array(0.0)
# Plain ints: indexing with an IntEnum member costs three times as much.
_S, _D, _DPSI, _PSIDOT, _VX = (int(i) for i in (State.s, State.d, State.dpsi, State.psidot,
                                                  State.vx))
_FYF, _FXF, _FXR = (int(i) for i in Input)


def _const(value: float) -> np.ndarray:
    # A 0-d array: numpy converts a Python float operand on every call, which costs as much
    # as the operation itself here; the 0-d array holds the same double.
    return np.array(float(value))


class _TrackingLaw:
    """The roll-outs' inputs for a batch of M candidates, in numpy calls on fixed buffers.

    Operand by operand what the straightforward formulation computes per step (the tests
    hold the two equal bit for bit): :func:`normal_loads_n` under the previous step's
    acceleration, :func:`rear_cornering_stiffness_n_per_rad`, :func:`steering_force_n`, the
    speed law, then the saturation at the friction limits (longitudinal first, the lateral
    force gets what remains).
    """

    def __init__(self, params: VehicleParams, config: SamplingConfig, utilization: float,
                 d_target_m: np.ndarray, v_target_mps: np.ndarray) -> None:
        self.params, self.utilization = params, utilization
        m, lf, wheelbase = params.mass_kg, params.cog_to_front_axle_m, params.wheelbase_m
        share_front = params.cog_to_rear_axle_m / wheelbase
        lower, upper = longitudinal_force_bounds_n(params)
        # As normal_loads_n, steering_force_n and rear_cornering_stiffness_n_per_rad group them.
        self.g_lr = _const(GRAVITY_MPS2 * params.cog_to_rear_axle_m)
        self.g_lf = _const(GRAVITY_MPS2 * lf)
        self.h, self.mass, self.wheelbase = (_const(v) for v in (params.cog_height_m, m,
                                                                 wheelbase))
        # The vehicle's tire: C_r = (stiffness per load) · F_zr, with that factor exactly.
        self.stiffness = _const(rear_cornering_stiffness_n_per_rad(params, 1.0, utilization))
        self.min_speed, self.min_lookahead = _const(1.0), _const(config.min_lookahead_m)
        self.lookahead_time = _const(config.lookahead_time_s)
        self.heading_gain = _const(config.heading_gain_1_per_s)
        self.share_front_mass = _const(share_front * m)
        self.yaw_term = _const(params.yaw_inertia_kgm2 / lf * config.yaw_rate_gain_1_per_s)
        self.long_gain = _const(m * config.speed_gain_1_per_s)
        self.share_front, self.share_rear = _const(share_front), _const(1.0 - share_front)
        self.mu_factor = _const(utilization)
        self.lower = [_const(v) for v in lower.tolist()]
        self.upper = [_const(v) for v in upper.tolist()]
        self.neg_08, self.pos_08, self.lat_share = _const(-0.8), _const(0.8), _const(0.95)
        self.d_target, self.v_target = d_target_m, v_target_mps
        n = d_target_m.size
        self.ax = np.zeros(n)  # the previous step's longitudinal acceleration
        (self.v, self.fzf, self.fzr, self.fyf, self.f_long, self.limit_f, self.limit_r,
         self.room, self.t1, self.t2) = (np.empty(n) for _ in range(10))
        self.braking = np.empty(n, dtype=bool)

    def inputs(self, x: np.ndarray, kappa: np.ndarray, mu: np.ndarray, u: np.ndarray,
               stiffness_table: SurfaceTireTable | None) -> np.ndarray:
        """Write the inputs ``u (3, M)`` at states ``x (6, M)``; returns the rear stiffness."""
        vx, t1, t2, v = x[_VX], self.t1, self.t2, self.v
        fzf, fzr, fyf, f_long = self.fzf, self.fzr, self.fyf, self.f_long
        limit_f, limit_r, room = self.limit_f, self.limit_r, self.room
        _max(vx, self.min_speed, out=v)
        # normal_loads_n: F_zf = m (g l_r − a_x h) / L, F_zr = m (g l_f + a_x h) / L
        _mul(self.ax, self.h, t1)
        _sub(self.g_lr, t1, fzf)
        _mul(self.mass, fzf, fzf)
        _div(fzf, self.wheelbase, fzf)
        _add(self.g_lf, t1, fzr)
        _mul(self.mass, fzr, fzr)
        _div(fzr, self.wheelbase, fzr)
        if stiffness_table is None:  # the vehicle's tire: μ̂ does not enter
            c_r = _mul(self.stiffness, fzr)
        else:
            # A diverged candidate (discarded by the caller) may sit where μ̂ is not finite.
            mu_stiffness = np.where(np.isfinite(mu) & (mu > 0.0), mu, 1.0)
            c_r = rear_cornering_stiffness_n_per_rad(
                self.params, fzr, self.utilization, mu_hat=mu_stiffness, table=stiffness_table
            )
        # steering_force_n: pure pursuit of the target, desired yaw rate, front force.
        _mul(self.lookahead_time, v, t1)
        _max(self.min_lookahead, t1, out=t1)
        _sub(self.d_target, x[_D], t2)
        _atan2(t2, t1, t2)
        _sub(t2, x[_DPSI], t2)
        _mul(self.heading_gain, t2, t2)
        _mul(kappa, v, t1)
        _add(t1, t2, room)  # r_des (the buffer is free until the saturation)
        _mul(self.share_front_mass, v, t1)
        _mul(t1, room, t1)
        _sub(room, x[_PSIDOT], t2)
        _mul(self.yaw_term, t2, t2)
        _add(t1, t2, fyf)
        # The speed law: braking split by the static load shares, traction on the rear axle.
        _sub(self.v_target, vx, f_long)
        _mul(self.long_gain, f_long, f_long)
        np.less(f_long, _ZERO, self.braking)
        fxf = np.where(self.braking, _mul(self.share_front, f_long, t1), _ZERO)
        fxr = np.where(self.braking, _mul(self.share_rear, f_long, t2), f_long)
        # Saturation at λ μ̂ F_z: np.minimum(np.maximum(...)) is np.clip's definition.
        _mul(self.mu_factor, mu, t1)
        _mul(t1, fzf, limit_f)
        _mul(t1, fzr, limit_r)
        _mul(self.neg_08, limit_f, t1)
        _max(self.lower[0], t1, out=t1)
        _max(fxf, t1, out=fxf)
        fxf = _min(fxf, self.upper[0], out=u[_FXF])
        _mul(self.neg_08, limit_r, t1)
        _max(self.lower[1], t1, out=t1)
        _max(fxr, t1, out=fxr)
        _mul(self.pos_08, limit_r, t2)
        _min(self.upper[1], t2, out=t2)
        fxr = _min(fxr, t2, out=u[_FXR])
        _square(limit_f, t1)
        _square(fxf, t2)
        _sub(t1, t2, t1)
        _max(t1, _ZERO, out=t1)
        _sqrt(t1, t1)
        _mul(t1, self.lat_share, room)
        np.negative(room, t2)
        _max(fyf, t2, out=t1)
        _min(t1, room, out=u[_FYF])
        # a_x of this step for the next step's loads: (F_xf + F_xr) / m
        _add(fxf, fxr, self.ax)
        _div(self.ax, self.mass, self.ax)
        return c_r
