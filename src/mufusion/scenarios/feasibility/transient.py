"""The transient oracle: the least lane excursion any driver of the plant's physics can reach.

The point-mass oracle (:mod:`~mufusion.scenarios.feasibility.turn`) asks whether a speed
profile exists; its rigid body only checks the steady arc's attitude. What it leaves out is the
transient: the yaw response, the rear tire's slip building up while the vehicle still brakes,
pitch load transfer, the actuators' lags. This module answers the question with the plant's own
equations instead: an optimal-control problem over the whole manoeuvre, solved once, offline,
with the true friction known everywhere,

    minimise E  subject to  every footprint corner within  w/2 + E  of the lane centre,

over the single-track model of :class:`~mufusion.vehicle.plant.Plant`: the combined-slip Magic
Formula of :mod:`mufusion.vehicle.tires` on each axle at the true μ under it, quasi-static pitch
load transfer in the plant's closed form, steering through the plant's first-order lag within
its rate and angle limits, each axle's longitudinal force through the torque lag within the
actuators' limits (front: brake only). What it grants the driver: ideal wheel-slip control (the
slip ratios are decisions, so no ABS cycle is lost), no wheel inertia, and full knowledge of the
road. It leaves out the stability control's yaw moment (differential braking). So ``E* > 0`` says
that no controller of this vehicle keeps the body in the lane (within the optimiser's reach: the
problem is non-convex and IPOPT's optimum is local, so the solve starts from two guesses), and
``E* = 0`` comes with a trajectory that does: the least time from the start that found it, a
local optimum too (docs/decisions/0116).

Independent variable: the progress ``s`` along the lane centre (the true friction and the
curvature are then known per node). Lane test at the footprint's four corners, the body turned
by its heading error ψ against the lane at curvature κ: ``d = n + x sin ψ + y cos ψ − κ x² / 2``
(:func:`~mufusion.scenarios.feasibility.attitude.footprint_span_m`'s geometry).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from mufusion._threads import load_casadi_ipopt, one_blas_thread
from mufusion.road import Road
from mufusion.scenarios.feasibility.common import GRAVITY_MPS2, require_positive
from mufusion.scenarios.feasibility.transient_model import rk4_function, spatial_model
from mufusion.vehicle.params import TireParams, VehicleParams

MIN_SPEED_MPS = 2.0
"""Lowest speed the solution may take [m/s]: the spatial model divides by the speed."""

EXCURSION_WEIGHT_PER_M = 1e4
"""Price of the excursion against the manoeuvre's time (as a multiple of the time at the entry
speed): 1 mm of excursion costs ten such times, so no time saved ever buys one."""

EXCURSION_TOLERANCE_M = 1e-4
"""An optimal excursion below this counts as none [m] (the solver's tolerance on the corners)."""

@dataclass(frozen=True)
class TransientVerdict:
    """The least lane excursion over one manoeuvre and the trajectory that reaches it.

    Attributes
    ----------
    excursion_m
        ``E*``: the deepest any footprint corner lies beyond its lane edge on the best trajectory
        found [m]; 0 (to the solver's tolerance) when the body can be kept in the lane.
    converged
        IPOPT reported an optimum (``Solve_Succeeded`` or ``Solved_To_Acceptable_Level``) from at
        least one initial guess.
    status
        IPOPT's return status of the best solve.
    guess
        The initial guess the best solve started from: ``"trajectory"`` (a
        :class:`TrajectoryGuess`, e.g. a recorded run's) or ``"point mass at 0.8 μ g"``.
    s_m, time_s, speed_mps, lateral_m, heading_rad, excursion_at_m
        The trajectory per node: progress, time, speed along the body, lateral offset and heading
        error of the centre of gravity, the deepest corner beyond its edge (≤ 0 inside).
    """

    excursion_m: float
    converged: bool
    status: str
    guess: str
    s_m: np.ndarray
    time_s: np.ndarray
    speed_mps: np.ndarray
    lateral_m: np.ndarray
    heading_rad: np.ndarray
    excursion_at_m: np.ndarray

    @property
    def worst_s_m(self) -> float:
        """Progress [m] at which the deepest corner is furthest out (or closest to its edge)."""
        return float(self.s_m[int(np.argmax(self.excursion_at_m))])


# The run log's timeseries columns of each guess field (sim.records.TickRecord's names).
_TIMESERIES_COLUMNS = {
    "s_m": "s_m", "time_s": "t_s", "lateral_m": "d_m", "heading_rad": "dpsi_rad",
    "vx_mps": "vx_mps", "vy_mps": "vy_mps", "yaw_rate_radps": "psidot_radps",
    "steer_rad": "steer_rad", "steer_cmd_rad": "steer_cmd_rad",
    "slip_front": "wheel_slip_front", "slip_rear": "wheel_slip_rear",
}


@dataclass(frozen=True)
class TrajectoryGuess:
    """A trajectory to start the search from, sampled along the lane centre's progress.

    Every field is an array of the same length; ``s_m`` increases strictly. A recorded run that
    kept its lane is (up to the model's discretisation) a point with ``E = 0``, so a solve that
    starts from it tests whether the oracle's model admits what the plant did, and reaches
    ``E* = 0`` in far fewer iterations than from a speed profile (:meth:`from_timeseries`).
    Slip ratios are the wheels' ``(R ω − u) / u``; NaN (no wheel signal yet) counts as 0.
    """

    s_m: np.ndarray
    time_s: np.ndarray
    lateral_m: np.ndarray
    heading_rad: np.ndarray
    vx_mps: np.ndarray
    vy_mps: np.ndarray
    yaw_rate_radps: np.ndarray
    steer_rad: np.ndarray
    steer_cmd_rad: np.ndarray
    slip_front: np.ndarray
    slip_rear: np.ndarray

    def __post_init__(self) -> None:
        s = np.asarray(self.s_m, dtype=float)
        if s.ndim != 1 or s.size < 2 or not np.all(np.isfinite(s)) or np.any(np.diff(s) <= 0.0):
            raise ValueError("s_m must be a finite, strictly increasing array of >= 2 samples")
        for name in _GUESS_FIELDS:
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != s.shape:
                raise ValueError(f"{name} must have the shape of s_m {s.shape}, got {value.shape}")
            slip = name.startswith("slip")  # NaN: no wheel signal yet
            if np.any(np.isinf(value) if slip else ~np.isfinite(value)):
                raise ValueError(f"{name} must be finite{' or NaN' if slip else ''}")

    @classmethod
    def from_timeseries(cls, timeseries: Any) -> TrajectoryGuess:
        """The guess of a run log's ``timeseries.csv`` (a pandas DataFrame): the samples up to
        the first standstill or reversal of the progress, where ``s`` still increases."""
        s = timeseries["s_m"].to_numpy(dtype=float)
        steps = np.diff(s) > 0.0
        keep = len(s) if np.all(steps) else int(np.argmin(steps)) + 1
        return cls(**{field: timeseries[column].to_numpy(dtype=float)[:keep]
                      for field, column in _TIMESERIES_COLUMNS.items()})

    def at(self, s_m: np.ndarray) -> dict[str, np.ndarray]:
        """Each field at the progress ``s_m`` (linear; held beyond the ends, NaN slip as 0)."""
        return {name: np.interp(s_m, self.s_m, np.nan_to_num(getattr(self, name)))
                for name in _GUESS_FIELDS}


_GUESS_FIELDS = tuple(f.name for f in fields(TrajectoryGuess) if f.name != "s_m")
"""The fields of :class:`TrajectoryGuess` sampled along ``s_m``."""


def _guess_speed_mps(curvature: np.ndarray, mu: np.ndarray, entry_speed_mps: float,
                     ds_m: float, share: float) -> np.ndarray:
    """A speed profile to start from: the point mass at ``share`` of μ g, backward pass."""
    limit = np.sqrt(share * mu * GRAVITY_MPS2 / np.maximum(np.abs(curvature), 1e-9))
    v = np.minimum(limit, entry_speed_mps)
    for k in range(len(v) - 2, -1, -1):
        v[k] = min(v[k], math.sqrt(v[k + 1] ** 2 + 2.0 * share * mu[k] * GRAVITY_MPS2 * ds_m))
    return np.maximum(v, MIN_SPEED_MPS)


def least_lane_excursion(
    road: Road,
    params: VehicleParams,
    start_s_m: float,
    entry_speed_mps: float,
    end_s_m: float,
    *,
    ds_m: float = 1.0,
    tires: tuple[TireParams, TireParams] | None = None,
    guess_shares: tuple[float, ...] = (0.8, 0.5),
    guess: TrajectoryGuess | None = None,
    max_utilization: float = 1.0,
    max_iter: int = 1500,
) -> TransientVerdict:
    """Solve for the least lane excursion from ``start_s_m`` to ``end_s_m`` on the true road.

    Parameters
    ----------
    road
        The road (its lane centre, lane width and true friction).
    params
        The vehicle; its tire on both axles unless ``tires`` gives ``(front, rear)``.
    start_s_m, entry_speed_mps
        Where the vehicle starts on the lane centre, straight and at rest in yaw [m], [m/s].
    end_s_m
        Where the manoeuvre ends [m] (a stretch after the curve, so that no attitude is left for
        after it); ``> start_s_m + 10 ds_m`` and within the road.
    ds_m
        Node spacing along the lane centre [m] (RK4 per interval).
    guess_shares
        Initial guesses: the point mass's speed profile at these shares of the friction the
        driver may use (``max_utilization`` μ g); the best converged solve wins.
    guess
        A trajectory to start from first (:class:`TrajectoryGuess`, e.g. the recorded run's);
        the speed profiles follow unless it reaches ``E* = 0``.
    max_utilization
        The largest share of each axle's friction the driver may use, in (0, 1]: 1 is
        physics; a planner's utilisation factor λ asks whether a driver with that reserve
        could keep the lane (the reserve it keeps by design).
    max_iter
        IPOPT's iteration limit per solve.

    Returns
    -------
    TransientVerdict

    Raises
    ------
    ValueError
        If a number is out of range (the message names it).
    """
    import casadi as ca  # the reference backend's dependency; imported where it is used

    require_positive("entry_speed_mps", entry_speed_mps)
    require_positive("ds_m", ds_m)
    if isinstance(max_utilization, bool) or not (
            isinstance(max_utilization, (int, float)) and 0.0 < max_utilization <= 1.0):
        raise ValueError(f"max_utilization must be in (0, 1], got {max_utilization!r}")
    if not (math.isfinite(start_s_m) and 0.0 <= start_s_m):
        raise ValueError(f"start_s_m must be finite and >= 0, got {start_s_m!r}")
    if not (math.isfinite(end_s_m) and start_s_m + 10 * ds_m < end_s_m <= road.length_m):
        raise ValueError(
            f"end_s_m must be in ({start_s_m + 10 * ds_m}, {road.length_m}], got {end_s_m!r}")
    tire_f, tire_r = tires if tires is not None else (params.tire, params.tire)
    n_nodes = math.floor((end_s_m - start_s_m) / ds_m)
    s = start_s_m + ds_m * np.arange(n_nodes + 1)
    curvature = np.asarray(road.curvature(s), dtype=float)
    mu_f = np.asarray(road.mu_at(s + params.cog_to_front_axle_m), dtype=float)
    mu_r = np.asarray(road.mu_at(s - params.cog_to_rear_axle_m), dtype=float)
    model = spatial_model(ca, params, tire_f, tire_r)
    step = rk4_function(ca, model, ds_m)
    front_m, rear_m = params.cog_to_body_front_m, params.cog_to_body_rear_m
    half_w, half_lane = 0.5 * params.width_m, 0.5 * road.lane_width_m
    radius = params.wheel_radius_m
    tau_f = params.torque_time_constant_s
    fx_bounds = (
        (-params.max_brake_torque_front_nm / radius, 0.0),
        (-params.max_brake_torque_rear_nm / radius, params.max_drive_torque_nm / radius),
    )

    opti = ca.Opti()
    X = opti.variable(7, n_nodes + 1)
    U = opti.variable(3, n_nodes + 1)
    excursion = opti.variable()
    P = np.vstack([curvature, mu_f, mu_r])
    opti.subject_to(X[:, 0] == ca.DM([0.0, 0.0, entry_speed_mps, 0.0, 0.0, 0.0, 0.0]))
    opti.subject_to(U[1:, 0] == 0.0)  # no force at the start: it builds through the lag
    step_map = step.map(n_nodes)
    opti.subject_to(X[:, 1:] == step_map(X[:, :-1], U[:, :-1], P[:, :-1]))
    _, fx_f, fx_r, util2_f, util2_r = model.map(n_nodes + 1)(X, U, P)
    if max_utilization < 1.0:  # the driver keeps a reserve on both axles
        opti.subject_to(util2_f <= max_utilization**2)
        opti.subject_to(util2_r <= max_utilization**2)
    dt = X[6, 1:] - X[6, :-1]
    for fx, (lo, hi) in zip((fx_f, fx_r), fx_bounds, strict=True):
        # The command a first-order lag needs to move F_x from node k to k+1 in dt, times dt.
        command_dt = fx[:-1] * dt + tau_f * (fx[1:] - fx[:-1])
        opti.subject_to(opti.bounded(lo * dt, command_dt, hi * dt))
    steer_gap = U[0, :] - X[5, :]
    max_gap = params.max_steer_rate_radps * params.steer_time_constant_s
    opti.subject_to(opti.bounded(-max_gap, steer_gap, max_gap))
    opti.subject_to(opti.bounded(-params.max_steer_rad, X[5, :], params.max_steer_rad))
    opti.subject_to(X[2, :] >= MIN_SPEED_MPS)
    opti.subject_to(U[1, :] <= 0.0)
    opti.subject_to(opti.bounded(-0.5, U[1:, :], 0.5))
    corners = _corner_offsets(ca, X, curvature, front_m, rear_m, half_w)
    corners = ca.vec(corners)
    opti.subject_to(corners - excursion <= half_lane)
    opti.subject_to(corners + excursion >= -half_lane)
    opti.subject_to(excursion >= 0.0)
    # E first (a millimetre outweighs the whole manoeuvre's time); then the least time, which
    # makes the optimum unique and tells how fast the body can be kept in the lane.
    t_ref = (end_s_m - start_s_m) / entry_speed_mps
    opti.minimize(EXCURSION_WEIGHT_PER_M * excursion + X[6, -1] / t_ref)
    opti.solver("ipopt", {"print_time": False, "expand": True},
                {"print_level": 0, "sb": "yes", "max_iter": max_iter, "tol": 1e-8,
                 "acceptable_tol": 1e-6})

    def from_trajectory(trajectory: TrajectoryGuess) -> None:
        at = trajectory.at(s)
        opti.set_initial(X, np.vstack([
            at["lateral_m"], at["heading_rad"], np.maximum(at["vx_mps"], MIN_SPEED_MPS),
            at["vy_mps"], at["yaw_rate_radps"], at["steer_rad"], at["time_s"] - at["time_s"][0]]))
        opti.set_initial(U, np.vstack([at["steer_cmd_rad"], np.clip(at["slip_front"], -0.5, 0.0),
                                       np.clip(at["slip_rear"], -0.5, 0.5)]))

    def from_speed_profile(share: float) -> None:
        v = _guess_speed_mps(curvature, np.minimum(mu_f, mu_r), entry_speed_mps, ds_m,
                             share * max_utilization)
        v[0] = entry_speed_mps
        opti.set_initial(X, 0.0)
        opti.set_initial(U, 0.0)
        opti.set_initial(X[2, :], v)
        opti.set_initial(X[4, :], v * curvature)
        opti.set_initial(X[5, :], params.wheelbase_m * curvature)
        opti.set_initial(U[0, :], params.wheelbase_m * curvature)
        opti.set_initial(X[6, :], np.concatenate([[0.0], np.cumsum(ds_m / v[:-1])]))

    starts: list[tuple[str, Callable[[], None]]] = [
        (f"point mass at {share * max_utilization:g} μ g",
         functools.partial(from_speed_profile, share))
        for share in guess_shares]
    if guess is not None:
        starts.insert(0, ("trajectory", functools.partial(from_trajectory, guess)))
    best: tuple[float, str, str, np.ndarray] | None = None
    load_casadi_ipopt()
    with one_blas_thread():  # the same answer on any machine's core count (mufusion._threads)
        for label, start in starts:
            start()
            opti.set_initial(excursion, 1.0)
            try:
                sol = opti.solve()
                status, ok = str(sol.stats()["return_status"]), True
                values = np.asarray(sol.value(X))
                e_star = float(sol.value(excursion))
            except RuntimeError:
                stats = opti.stats()
                status, ok = str(stats.get("return_status", "failed")), False
                values, e_star = np.asarray(opti.debug.value(X)), math.inf
            if ok and (best is None or e_star < best[0]):
                best = (e_star, status, label, values)
            elif best is None and not ok:
                last_failed = (status, label, values)
            if best is not None and best[0] <= EXCURSION_TOLERANCE_M:
                break  # the body fits: another guess cannot keep it better
    if best is None:
        status, label, values = last_failed
        return _verdict(math.inf, False, status, label, s, values, curvature, front_m, rear_m,
                        half_w, half_lane)
    e_star, status, label, values = best
    return _verdict(max(e_star, 0.0), True, status, label, s, values, curvature, front_m,
                    rear_m, half_w, half_lane)


def _corner_offsets(ops, X, curvature, front_m, rear_m, half_w):
    """Lateral offsets of the four corners per node, stacked ``(4, nodes)`` (``ops``: numpy
    or CasADi)."""
    n, psi = X[0, :], X[1, :]
    sin_p, cos_p = ops.sin(psi), ops.cos(psi)
    rows = []
    for x in (front_m, -rear_m):
        bulge = 0.5 * np.asarray(curvature) * x * x
        bulge_row = bulge if ops is np else ops.DM(bulge).T
        for y in (half_w, -half_w):
            rows.append(n + x * sin_p + y * cos_p - bulge_row)
    return np.vstack(rows) if ops is np else ops.vertcat(*rows)


def _verdict(e_star, converged, status, guess, s, values, curvature, front_m, rear_m, half_w,
             half_lane) -> TransientVerdict:
    corners = _corner_offsets(np, values, curvature, front_m, rear_m, half_w)
    beyond = np.max(np.abs(corners), axis=0) - half_lane
    return TransientVerdict(
        excursion_m=e_star, converged=converged, status=status, guess=guess, s_m=s,
        time_s=values[6], speed_mps=values[2], lateral_m=values[0], heading_rad=values[1],
        excursion_at_m=beyond,
    )
