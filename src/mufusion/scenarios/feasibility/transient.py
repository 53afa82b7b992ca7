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
``E* = 0`` comes with a trajectory that does.

Independent variable: the progress ``s`` along the lane centre (the true friction and the
curvature are then known per node). Lane test at the footprint's four corners, the body turned
by its heading error ψ against the lane at curvature κ: ``d = n + x sin ψ + y cos ψ − κ x² / 2``
(:func:`~mufusion.scenarios.feasibility.attitude.footprint_span_m`'s geometry).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.road import Road
from mufusion.scenarios.feasibility.common import GRAVITY_MPS2, require_positive
from mufusion.vehicle.params import TireParams, VehicleParams

MIN_SPEED_MPS = 2.0
"""Lowest speed the solution may take [m/s]: the spatial model divides by the speed."""

EXCURSION_WEIGHT_PER_M = 1e4
"""Price of the excursion against the manoeuvre's time (as a multiple of the time at the entry
speed): 1 mm of excursion costs ten such times, so no time saved ever buys one."""

EXCURSION_TOLERANCE_M = 1e-4
"""An optimal excursion below this counts as none [m] (the solver's tolerance on the corners)."""

_SLIP_EPS = 1e-6
"""Smoothing of the slip vector's magnitude (the Magic Formula's direction is undefined at 0)."""


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
    s_m, time_s, speed_mps, lateral_m, heading_rad, excursion_at_m
        The trajectory per node: progress, time, speed along the body, lateral offset and heading
        error of the centre of gravity, the deepest corner beyond its edge (≤ 0 inside).
    """

    excursion_m: float
    converged: bool
    status: str
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


def _unit_tire(ca, kappa, alpha, mu, tire: TireParams):
    """:func:`~mufusion.vehicle.plant_kernel.unit_tire` in CasADi, the slip magnitude smoothed
    by :data:`_SLIP_EPS`: forces per unit load ``(g_x, g_y)``."""
    sx = tire.longitudinal_stiffness_per_load * kappa / mu
    sy = tire.cornering_stiffness_per_load_1_per_rad * alpha / mu
    sx2 = sx * sx
    lam2 = sx2 + sy * sy + _SLIP_EPS**2
    lam = ca.sqrt(lam2)
    weight_x = sx2 / lam2
    shape = weight_x * tire.shape_longitudinal + (1.0 - weight_x) * tire.shape_lateral
    curv = weight_x * tire.curvature_longitudinal + (1.0 - weight_x) * tire.curvature_lateral
    bs = lam / shape
    phi = ca.sin(shape * ca.atan(bs - curv * (bs - ca.atan(bs))))
    scale = mu * phi / lam
    return scale * sx, scale * sy


def _spatial_model(ca, params: VehicleParams, tire_f: TireParams, tire_r: TireParams):
    """CasADi function ``(x, u, p) → (dx/ds, F_x front, F_x rear)``.

    ``x = (n, ψ, v_x, v_y, ψ̇, δ, t)``, ``u = (δ_cmd, κ_f, κ_r)``, ``p = (κ_road, μ_f, μ_r)``.
    The plant's rates (:meth:`~mufusion.vehicle.plant_kernel.PlantKernel.rates`) divided by
    the progress rate ``ṡ = (v_x cos ψ − v_y sin ψ) / (1 − n κ)``.
    """
    x, u, p = ca.SX.sym("x", 7), ca.SX.sym("u", 3), ca.SX.sym("p", 3)
    n, psi, vx, vy, r, steer = x[0], x[1], x[2], x[3], x[4], x[5]
    steer_cmd, kappa_f, kappa_r = u[0], u[1], u[2]
    curvature, mu_f, mu_r = p[0], p[1], p[2]
    lf, lr, h = params.cog_to_front_axle_m, params.cog_to_rear_axle_m, params.cog_height_m
    wheelbase, m = lf + lr, params.mass_kg
    lateral_f = vy + lf * r
    cos_d, sin_d = ca.cos(steer), ca.sin(steer)
    u_f = vx * cos_d + lateral_f * sin_d
    w_f = -vx * sin_d + lateral_f * cos_d
    alpha_f = -ca.atan(w_f / u_f)
    alpha_r = -ca.atan((vy - lr * r) / vx)
    gxf, gyf = _unit_tire(ca, kappa_f, alpha_f, mu_f, tire_f)
    gxr, gyr = _unit_tire(ca, kappa_r, alpha_r, mu_r, tire_r)
    # Quasi-static pitch load transfer in the plant's closed form (axles.axle_outputs).
    g_front = gxf * cos_d - gyf * sin_d
    accel = GRAVITY_MPS2 * (g_front * lr + gxr * lf) / (wheelbase + h * (g_front - gxr))
    fzf = m / wheelbase * (GRAVITY_MPS2 * lr - accel * h)
    fzr = m / wheelbase * (GRAVITY_MPS2 * lf + accel * h)
    fx_f, fy_f, fx_r, fy_r = gxf * fzf, gyf * fzf, gxr * fzr, gyr * fzr
    fx_body = fx_f * cos_d - fy_f * sin_d
    fy_body = fx_f * sin_d + fy_f * cos_d
    s_dot = (vx * ca.cos(psi) - vy * ca.sin(psi)) / (1.0 - n * curvature)
    rates = ca.vertcat(
        vx * ca.sin(psi) + vy * ca.cos(psi),
        r - curvature * s_dot,
        (fx_body + fx_r) / m + vy * r,
        (fy_body + fy_r) / m - vx * r,
        (lf * fy_body - lr * fy_r) / params.yaw_inertia_kgm2,
        (steer_cmd - steer) / params.steer_time_constant_s,
        1.0,
    )
    return ca.Function("spatial", [x, u, p], [rates / s_dot, fx_f, fx_r])


def _rk4(ca, model, ds_m: float):
    x, u, p = ca.MX.sym("x", 7), ca.MX.sym("u", 3), ca.MX.sym("p", 3)

    def f(state):
        return model(state, u, p)[0]

    k1 = f(x)
    k2 = f(x + 0.5 * ds_m * k1)
    k3 = f(x + 0.5 * ds_m * k2)
    k4 = f(x + ds_m * k3)
    return ca.Function("rk4", [x, u, p], [x + ds_m / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)])


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
        Initial guesses: the point mass's speed profile at these shares of μ g; the best
        converged solve wins.
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
    model = _spatial_model(ca, params, tire_f, tire_r)
    step = _rk4(ca, model, ds_m)
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
    _, fx_f, fx_r = model.map(n_nodes + 1)(X, U, P)
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

    best: tuple[float, str, np.ndarray] | None = None
    for share in guess_shares:
        v = _guess_speed_mps(curvature, np.minimum(mu_f, mu_r), entry_speed_mps, ds_m, share)
        v[0] = entry_speed_mps
        opti.set_initial(X[2, :], v)
        opti.set_initial(X[4, :], v * curvature)
        opti.set_initial(X[5, :], params.wheelbase_m * curvature)
        opti.set_initial(U[0, :], params.wheelbase_m * curvature)
        opti.set_initial(X[6, :], np.concatenate([[0.0], np.cumsum(ds_m / v[:-1])]))
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
            best = (e_star, status, values)
        elif best is None and not ok:
            last_failed = (status, values)
        if best is not None and best[0] <= EXCURSION_TOLERANCE_M:
            break  # the body fits: a second guess cannot do better
    if best is None:
        status, values = last_failed
        return _verdict(math.inf, False, status, s, values, curvature, front_m, rear_m,
                        half_w, half_lane)
    e_star, status, values = best
    return _verdict(max(e_star, 0.0), True, status, s, values, curvature, front_m, rear_m,
                    half_w, half_lane)


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


def _verdict(e_star, converged, status, s, values, curvature, front_m, rear_m, half_w,
             half_lane) -> TransientVerdict:
    corners = _corner_offsets(np, values, curvature, front_m, rear_m, half_w)
    beyond = np.max(np.abs(corners), axis=0) - half_lane
    return TransientVerdict(
        excursion_m=e_star, converged=converged, status=status, s_m=s, time_s=values[6],
        speed_mps=values[2], lateral_m=values[0], heading_rad=values[1], excursion_at_m=beyond,
    )
