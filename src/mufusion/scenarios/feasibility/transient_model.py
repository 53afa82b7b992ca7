"""The plant's single-track equations in CasADi, with the progress along the lane as the
independent variable: the transient oracle's model (:mod:`.transient`).

Each function takes the CasADi module ``ca`` (imported by the caller, where it is used: the
library imports CasADi only for its reference backend and this oracle).
"""

from __future__ import annotations

from mufusion.scenarios.feasibility.common import GRAVITY_MPS2
from mufusion.vehicle.params import TireParams, VehicleParams

_SLIP_EPS = 1e-6
"""Smoothing of the slip vector's magnitude (the Magic Formula's direction is undefined at 0)."""


def unit_tire(ca, kappa, alpha, mu, tire: TireParams):
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


def spatial_model(ca, params: VehicleParams, tire_f: TireParams, tire_r: TireParams):
    """CasADi function ``(x, u, p) → (dx/ds, F_x front, F_x rear, u_f², u_r²)``, ``u_i`` the
    axle's tire utilisation ``|F_i| / (μ_i F_z,i)``.

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
    gxf, gyf = unit_tire(ca, kappa_f, alpha_f, mu_f, tire_f)
    gxr, gyr = unit_tire(ca, kappa_r, alpha_r, mu_r, tire_r)
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
    util2_f = (gxf * gxf + gyf * gyf) / (mu_f * mu_f)
    util2_r = (gxr * gxr + gyr * gyr) / (mu_r * mu_r)
    return ca.Function("spatial", [x, u, p], [rates / s_dot, fx_f, fx_r, util2_f, util2_r])


def rk4_function(ca, model, ds_m: float):
    x, u, p = ca.MX.sym("x", 7), ca.MX.sym("u", 3), ca.MX.sym("p", 3)

    def f(state):
        return model(state, u, p)[0]

    k1 = f(x)
    k2 = f(x + 0.5 * ds_m * k1)
    k3 = f(x + 0.5 * ds_m * k2)
    k4 = f(x + ds_m * k3)
    return ca.Function("rk4", [x, u, p], [x + ds_m / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)])
