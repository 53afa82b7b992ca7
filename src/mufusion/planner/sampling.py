"""Sampling augmentation of the RTI initial guess (SAA-RTI, Svensson et al., arXiv 1903.04240).

Candidate manoeuvres (lateral targets × speed targets) are rolled out with the planner's own model
under a simple tracking law saturated at the friction limits, all at once in numpy. Each roll-out
and the shifted previous plan are scored on tracking plus a heavy penalty on how far they go
beyond the road and into obstacles (planner/footprint.py); the best becomes the initial guess
when it beats the shifted plan. Because the obstacle corridor's side is chosen by the
guess, this is what lets the planner switch sides.
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.planner.config import PlannerConfig, PlannerObstacle
from mufusion.planner.footprint import stage_violations_m, tracking_cost
from mufusion.planner.ocp import longitudinal_force_bounds_n
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.planner_model import (
    MIN_SPEED_FOR_SLIP_MPS,
    N_INPUTS,
    N_STATES,
    Input,
    State,
    frenet_bicycle_dynamics,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
)
from mufusion.vehicle.surface_tires import SurfaceTireTable

_log = logging.getLogger(__name__)

# Cost of one metre of obstacle/road violation (at its worst stage) relative to tracking [1/m].
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


@dataclass(frozen=True)
class RK4Workspace:
    """Scratch arrays for :func:`rk4_step` on states of one shape, reused from step to step."""

    k1: np.ndarray
    k2: np.ndarray
    k3: np.ndarray
    k4: np.ndarray
    stage: np.ndarray

    @classmethod
    def for_states(cls, shape: tuple[int, ...]) -> RK4Workspace:
        """Workspace for states of ``shape`` ``(6, ...)``."""
        return cls(*(np.empty(shape) for _ in range(5)))


def rk4_step(
    x: np.ndarray,
    u: np.ndarray,
    curvature_1pm: np.ndarray | float,
    rear_stiffness: np.ndarray | float,
    params: VehicleParams,
    dt_s: float,
    *,
    out: np.ndarray | None = None,
    workspace: RK4Workspace | None = None,
) -> np.ndarray:
    """One classical RK4 step of the planner's model (as acados' ERK with one stage).

    ``x + dt/6 (k1 + 2 k2 + 2 k3 + k4)``, summed in that order.

    Parameters
    ----------
    x, u
        States ``(6, ...)`` and input forces ``(3, ...)`` [N], held over the step.
    curvature_1pm, rear_stiffness
        Path curvature [1/m] and rear cornering stiffness [N/rad], held over the step.
    params
        Vehicle parameters.
    dt_s
        Step [s].
    out
        Array for the new state (default: a new one).
    workspace
        Scratch arrays of the states' broadcast shape: the stages are evaluated into them instead
        of into new arrays (the same values; the sampling roll-outs step 40 × 40 states this way).

    Returns
    -------
    numpy.ndarray
        The state after ``dt_s`` (``out`` when given).

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> x = np.array([0.0, 0.0, 0.0, 0.0, 10.0, 0.0])
    >>> float(rk4_step(x, np.zeros(3), 0.0, 1e5, TRUCK, 0.1)[State.s])
    1.0
    """
    w = workspace
    k1, k2, k3, k4, stage = (None,) * 5 if w is None else (w.k1, w.k2, w.k3, w.k4, w.stage)
    f, args = frenet_bicycle_dynamics, (u, curvature_1pm, rear_stiffness, params)
    # The step sizes as 0-d arrays (numpy multiplies by these faster than by Python floats;
    # same values); out given positionally (None: allocate, as the operators would).
    half, full, sixth = np.array(0.5 * dt_s), np.array(dt_s), np.array(dt_s / 6.0)
    add, mul = np.add, np.multiply
    k1 = f(x, *args, k1)
    k2 = f(add(x, mul(half, k1, stage), stage), *args, k2)
    k3 = f(add(x, mul(half, k2, stage), stage), *args, k3)
    k4 = f(add(x, mul(full, k3, stage), stage), *args, k4)
    # k1..k4 are this call's own arrays: summed in place, left to right.
    total = add(k1, mul(2, k2, k2), k1)
    total = add(total, mul(2, k3, k3), total)
    total = add(total, k4, total)
    return add(x, mul(sixth, total, total), out)


def _per_candidate(value: np.ndarray | float, m_count: int) -> np.ndarray:
    """``value`` as a float array of shape ``(m_count,)``: ``value * ones``, or ``value`` itself
    when it already has that shape (x · 1 = x bit for bit, signalling NaNs aside, which no
    arithmetic produces)."""
    array = np.asarray(value, dtype=float)
    return array if array.shape == (m_count,) else array * np.ones(m_count)


@functools.lru_cache(maxsize=1)
def compiled_rollouts_available() -> bool:
    """Whether the install built the compiled roll-out loop (``_rollouts_c``)."""
    try:
        from mufusion.planner._rollouts_c import rollouts  # noqa: F401
    except ImportError:
        return False
    return True


ROLLOUT_KINDS = ("auto", "compiled", "numpy")


def _rollout_constants(
    params: VehicleParams, utilization_factor: float, dt_s: float, config: SamplingConfig
) -> tuple[float, ...]:
    """The Python floats the numpy roll-out computes with, computed as it computes them, in the
    order the compiled loop reads them."""
    m, lf, lr = params.mass_kg, params.cog_to_front_axle_m, params.cog_to_rear_axle_m
    iz = params.yaw_inertia_kgm2
    share_front = lr / params.wheelbase_m
    lower, upper = longitudinal_force_bounds_n(params)
    return (
        m, lf, lr, iz, MIN_SPEED_FOR_SLIP_MPS,
        GRAVITY_MPS2 * lr, GRAVITY_MPS2 * lf, params.cog_height_m, params.wheelbase_m,
        share_front, share_front * m, iz / lf * config.yaw_rate_gain_1_per_s,
        m * config.speed_gain_1_per_s, config.min_lookahead_m, config.lookahead_time_s,
        config.heading_gain_1_per_s, float(lower[0]), float(lower[1]), float(upper[0]),
        float(upper[1]), utilization_factor, dt_s,
    )


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
    kind: str = "auto",
) -> tuple[np.ndarray, np.ndarray]:
    """Roll out every (lateral target, speed target) pair.

    ``stiffness_table``: the rear stiffness follows μ̂ through it, as in the OCP (``None``: the
    vehicle's fixed tire). ``kind``: ``"numpy"`` steps all candidates with numpy arrays,
    ``"compiled"`` with the compiled loop (the same values, bit for bit, at a fraction of the
    time), ``"auto"`` (default) the compiled loop where the install built it.

    Returns
    -------
    states, inputs
        ``(N+1, 6, M)`` and ``(N, 3, M)`` with ``M = len(lateral) × len(speed)``.

    Raises
    ------
    ValueError
        If ``kind`` is unknown, or ``"compiled"`` where the loop was not built.
    """
    if kind not in ROLLOUT_KINDS:
        raise ValueError(f"kind must be one of {', '.join(ROLLOUT_KINDS)}; got {kind!r}")
    compiled = kind == "compiled" or (kind == "auto" and compiled_rollouts_available())
    d_t, v_t = (a.ravel() for a in np.meshgrid(lateral_targets_m, speed_targets_mps))
    m_count = d_t.size
    # Trajectories are written in place: each step's state and inputs are rows of these.
    xs = np.empty((horizon_steps + 1, N_STATES, m_count))
    us = np.empty((horizon_steps, N_INPUTS, m_count))
    xs[0] = np.asarray(x0, dtype=float)[:, None]
    if compiled:
        try:
            from mufusion.planner._rollouts_c import rollouts
        except ImportError as exc:
            raise ValueError(
                "kind='compiled' needs the compiled roll-out loop, which this installation "
                "lacks (reinstall with `pip install -e .`)"
            ) from exc

        stiffness_of: Callable[[np.ndarray, np.ndarray], np.ndarray] | None = None
        # The vehicle's tire: the stiffness is its load times a factor that μ̂ does not change,
        # computed once here and multiplied in the loop (factor · 1 = the factor, so each step's
        # product is the one the full call makes).
        per_load = (float(rear_cornering_stiffness_n_per_rad(params, 1.0, utilization_factor))
                    if stiffness_table is None else 0.0)
        if stiffness_table is not None:
            def stiffness_of(rear_load_n: np.ndarray, mu: np.ndarray) -> np.ndarray:
                return rear_cornering_stiffness_n_per_rad(
                    params, rear_load_n, utilization_factor, mu_hat=mu, table=stiffness_table
                )

        rollouts(
            xs, us, np.ascontiguousarray(d_t, dtype=float),
            np.ascontiguousarray(v_t, dtype=float), curvature_of_s, mu_hat_of_s, stiffness_of,
            _rollout_constants(params, utilization_factor, dt_s, config), per_load,
        )
        return xs, us
    workspace = RK4Workspace.for_states(xs[0].shape)
    lower, upper = longitudinal_force_bounds_n(params)
    m = params.mass_kg
    share_front = params.cog_to_rear_axle_m / params.wheelbase_m
    speed_force_n_per_mps = m * config.speed_gain_1_per_s
    ax = np.zeros(m_count)
    for k in range(horizon_steps):
        x, u = xs[k], us[k]
        s, vx = x[State.s], x[State.vx]
        v = np.maximum(vx, 1.0)
        kappa = _per_candidate(curvature_of_s(s), m_count)
        mu = _per_candidate(mu_hat_of_s(s), m_count)
        fzf, fzr = normal_loads_n(ax, params)
        # A diverged candidate (discarded by the caller) may sit where μ̂ is not finite.
        mu_stiffness = np.where(np.isfinite(mu) & (mu > 0.0), mu, 1.0)
        c_r = rear_cornering_stiffness_n_per_rad(
            params, fzr, utilization_factor, mu_hat=mu_stiffness, table=stiffness_table
        )
        fyf = steering_force_n(x, d_t, kappa, v, params, config)
        f_long = speed_force_n_per_mps * (v_t - vx)
        braking = f_long < 0.0
        fxf = np.where(braking, share_front * f_long, 0.0)
        fxr = np.where(braking, (1.0 - share_front) * f_long, f_long)
        # Saturate at the friction limits (longitudinal first, lateral gets what remains).
        limit_mu = utilization_factor * mu
        limit_f, limit_r = limit_mu * fzf, limit_mu * fzr
        # np.minimum(np.maximum(...)) is np.clip's definition, at a fraction of its overhead.
        fxf = np.minimum(
            np.maximum(fxf, np.maximum(lower[0], -0.8 * limit_f)), upper[0], out=u[Input.fxf]
        )
        fxr = np.minimum(
            np.maximum(fxr, np.maximum(lower[1], -0.8 * limit_r)),
            np.minimum(upper[1], 0.8 * limit_r),
            out=u[Input.fxr],
        )
        lat_room = np.sqrt(np.maximum(limit_f**2 - fxf**2, 0.0)) * 0.95
        np.minimum(np.maximum(fyf, -lat_room), lat_room, out=u[Input.fyf])
        x = rk4_step(x, u, kappa, c_r, params, dt_s, out=xs[k + 1], workspace=workspace)
        np.maximum(x[State.vx], 0.0, out=x[State.vx])
        ax = (fxf + fxr) / m
    return xs, us


def sampled_guess(
    x0: np.ndarray,
    guess_x: np.ndarray,
    guess_u: np.ndarray,
    curvature_of_s: Callable[[np.ndarray], np.ndarray],
    mu_hat_of_s: Callable[[np.ndarray], np.ndarray],
    obstacles: Sequence[PlannerObstacle],
    v_ref: float,
    d_ref: float,
    lo_lane: float,
    hi_lane: float,
    par: VehicleParams,
    cfg: PlannerConfig,
    sc: SamplingConfig,
    *,
    continuing: bool,
) -> tuple[np.ndarray, np.ndarray, bool]:
    """SAA: replace the shifted guess by the best sampled roll-out when that beats it.

    Returns the guess and whether it is a sampled roll-out. ``continuing``: the guess continues
    a previous plan (then sampling is tried only if that plan violates more than
    ``sc.trigger_violation_m``). Never raises: sampling is an aid.
    """
    try:
        road, overlap = stage_violations_m(
            guess_x[:, :, None], obstacles, lo_lane, hi_lane, par, cfg.obstacle_margin_m,
            cfg.dt_s,
        )
        shifted_violation = float((road + overlap).sum())
        if continuing and shifted_violation <= sc.trigger_violation_m:
            return guess_x, guess_u, False
        lateral = np.append(np.linspace(lo_lane, hi_lane, sc.n_lateral), d_ref)
        speeds = np.append(np.asarray(sc.speed_fractions) * v_ref, x0[State.vx])
        with np.errstate(all="ignore"):  # diverging candidates are discarded below
            xs, us = candidate_rollouts(
                x0, lateral, speeds, curvature_of_s, mu_hat_of_s, par,
                cfg.utilization_factor, cfg.horizon_steps, cfg.dt_s, sc,
                stiffness_table=cfg.stiffness_table,
            )
        both = np.concatenate([guess_x[:, :, None], xs], axis=2)
        with np.errstate(all="ignore"):
            tracking = tracking_cost(both, v_ref, d_ref)
        tracking[0] *= SHIFTED_DISCOUNT
        # Each violation by how far it goes, not by how long: the targets lie within the road,
        # so a roll-out beyond its edge is the tracking law's overshoot, which the OCP pulls
        # back; summed over the stages, a 0.16 m overshoot held for the rest of the horizon
        # outweighed a guess 0.3 m into an obstacle, and the corridor passed it on the side
        # with no time to clear it (docs/decisions/0073). A diverged candidate's cost overflows
        # or is NaN: it ranks last, silently.
        with np.errstate(all="ignore"):
            road, overlap = stage_violations_m(
                both, obstacles, lo_lane, hi_lane, par, cfg.obstacle_margin_m, cfg.dt_s
            )
            cost = tracking + VIOLATION_WEIGHT * (road.max(axis=0) + overlap.max(axis=0))
        cost = np.where(np.isfinite(cost), cost, np.inf)
        best = int(np.argmin(cost))
        if best == 0 or not np.isfinite(cost[best]):
            return guess_x, guess_u, False
        return xs[:, :, best - 1], us[:, :, best - 1], True
    except Exception as exc:  # sampling is an aid; never let it break the loop
        _log.warning("sampling augmentation failed: %r", exc)
        return guess_x, guess_u, False
