"""Tire forces of the plant's two axles: wheel-frame slips, the tire model and pitch load transfer.

Low speed: slip ratio and slip angle divide by ``max(|u|, SLIP_SPEED_FLOOR_MPS)``, so below
1 m/s the tires act as stiff viscous dampers and the vehicle comes to rest without a singularity.
Both stiffness and peak scale with the normal load, so the force per unit load depends on slip
only and the quasi-static load transfer has a closed-form solution (no algebraic loop).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from mufusion.vehicle.params import GRAVITY_MPS2, TireParams, VehicleParams
from mufusion.vehicle.plant_state import PlantStateVector, state_vector
from mufusion.vehicle.surface_tires import SurfaceTireTable, tire_for_surface
from mufusion.vehicle.tires import tire_forces_scalar

# Slip quantities divide by at least this speed [m/s] (the "regularise below ~1 m/s").
SLIP_SPEED_FLOOR_MPS = 1.0


class AxleOutput(NamedTuple):
    """Tire quantities of one axle at one state (its wheel frame: ``fx`` along the wheel).

    ``utilization`` is the realised fraction of μ F_z, ``hypot(fx, fy) / (μ F_z)`` ≤ 1;
    ``requested_utilization`` is what a linear tire would deliver for the same slip (≥ 0, above 1
    when the tire slides). ``wheel_speed_mps`` is the wheel centre's speed along the wheel.
    """

    fx_n: float
    fy_n: float
    fz_n: float
    slip_ratio: float
    slip_angle_rad: float
    utilization: float
    requested_utilization: float
    wheel_speed_mps: float
    mu: float

    @property
    def slip_speed_mps(self) -> float:
        """The (floored) speed the slips divide by [m/s]."""
        return max(abs(self.wheel_speed_mps), SLIP_SPEED_FLOOR_MPS)


def check_mu(mu_front: float, mu_rear: float) -> None:
    """``ValueError`` naming ``mu_front`` / ``mu_rear`` unless both are finite and > 0."""
    if not (mu_front > 0.0 and math.isfinite(mu_front)):
        raise ValueError(f"mu_front must be a finite number > 0, got {mu_front!r}")
    if not (mu_rear > 0.0 and math.isfinite(mu_rear)):
        raise ValueError(f"mu_rear must be a finite number > 0, got {mu_rear!r}")


def wheel_speeds(x: PlantStateVector, p: VehicleParams) -> tuple[float, float, float, float]:
    """Velocity of each wheel centre in its own frame: ``(u_f, w_f, u_r, w_r)`` [m/s]."""
    vx, steer = x.vx_mps, x.steer_rad
    lateral_f = x.vy_mps + p.cog_to_front_axle_m * x.yaw_rate_radps
    cos_d, sin_d = math.cos(steer), math.sin(steer)
    u_f = vx * cos_d + lateral_f * sin_d
    w_f = -vx * sin_d + lateral_f * cos_d
    return u_f, w_f, vx, x.vy_mps - p.cog_to_rear_axle_m * x.yaw_rate_radps


def axle_outputs(
    x: PlantStateVector,
    omega_front_radps: float,
    omega_rear_radps: float,
    mu_front: float,
    mu_rear: float,
    p: VehicleParams,
    tire_front: TireParams | None = None,
    tire_rear: TireParams | None = None,
) -> tuple[AxleOutput, AxleOutput]:
    """Front and rear :class:`AxleOutput` at chassis state ``x`` and the given wheel spins.

    The wheel spins are arguments (not read from ``x``) because the plant's integrator evaluates
    the forces with predicted wheel speeds. ``tire_front`` / ``tire_rear``: the tire on each
    axle's surface (:func:`~mufusion.vehicle.surface_tires.tire_for_surface`); ``None`` is the
    vehicle's own ``p.tire``. Plain floats, no validation: the inner loop's call.
    """
    u_f, w_f, u_r, w_r = wheel_speeds(x, p)
    radius = p.wheel_radius_m
    den_f = max(abs(u_f), SLIP_SPEED_FLOOR_MPS)
    den_r = max(abs(u_r), SLIP_SPEED_FLOOR_MPS)
    kappa_f = (radius * omega_front_radps - u_f) / den_f
    kappa_r = (radius * omega_rear_radps - u_r) / den_r
    alpha_f = -math.atan(w_f / den_f)
    alpha_r = -math.atan(w_r / den_r)
    # Forces per unit load: slip does not depend on F_z and the tire scales linearly with it.
    gxf, gyf, used_f, asked_f = tire_forces_scalar(
        kappa_f, alpha_f, 1.0, mu_front, p.tire if tire_front is None else tire_front
    )
    gxr, gyr, used_r, asked_r = tire_forces_scalar(
        kappa_r, alpha_r, 1.0, mu_rear, p.tire if tire_rear is None else tire_rear
    )
    # Quasi-static pitch load transfer: m a = F_zf g_f + F_zr g_r with
    # F_zf = m (g l_r − a h)/L, F_zr = m (g l_f + a h)/L, solved for a in closed form.
    lf, lr, h = p.cog_to_front_axle_m, p.cog_to_rear_axle_m, p.cog_height_m
    wheelbase = lf + lr
    steer = x.steer_rad
    g_front = gxf * math.cos(steer) - gyf * math.sin(steer)
    denominator = max(wheelbase + h * (g_front - gxr), 0.1 * wheelbase)
    accel = GRAVITY_MPS2 * (g_front * lr + gxr * lf) / denominator
    weight = p.mass_kg / wheelbase
    fzf = max(weight * (GRAVITY_MPS2 * lr - accel * h), 0.0)
    fzr = max(weight * (GRAVITY_MPS2 * lf + accel * h), 0.0)
    front = AxleOutput(
        fx_n=gxf * fzf,
        fy_n=gyf * fzf,
        fz_n=fzf,
        slip_ratio=kappa_f,
        slip_angle_rad=alpha_f,
        utilization=used_f if fzf > 0.0 else 0.0,
        requested_utilization=asked_f if fzf > 0.0 else 0.0,
        wheel_speed_mps=u_f,
        mu=mu_front,
    )
    rear = AxleOutput(
        fx_n=gxr * fzr,
        fy_n=gyr * fzr,
        fz_n=fzr,
        slip_ratio=kappa_r,
        slip_angle_rad=alpha_r,
        utilization=used_r if fzr > 0.0 else 0.0,
        requested_utilization=asked_r if fzr > 0.0 else 0.0,
        wheel_speed_mps=u_r,
        mu=mu_rear,
    )
    return front, rear


def axle_forces(
    x: np.ndarray,
    mu_front: float,
    mu_rear: float,
    params: VehicleParams,
    surface_tires: SurfaceTireTable | None = None,
) -> tuple[AxleOutput, AxleOutput]:
    """Tire forces, slips and utilisations of both axles at plant state ``x``.

    Parameters
    ----------
    x
        Plant state, shape ``(11,)``, indexed by
        :class:`~mufusion.vehicle.plant_state.PlantState`.
    mu_front, mu_rear
        True road friction under each axle [-], > 0.
    params
        Vehicle parameters.
    surface_tires
        ``None``: the vehicle's tire on every surface (stiffness independent of μ). A table:
        each axle's tire follows the μ under it (:func:`tire_for_surface`).

    Returns
    -------
    front, rear
        One :class:`AxleOutput` per axle.

    Raises
    ------
    ValueError
        If a μ is not > 0 or ``x`` has the wrong shape.

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> from mufusion.vehicle.plant_state import initial_state
    >>> front, rear = axle_forces(initial_state(CAR, 0.0, 0.0, 0.0, 10.0), 0.8, 0.8, CAR)
    >>> front.slip_ratio, round((front.fz_n + rear.fz_n) / (CAR.mass_kg * GRAVITY_MPS2), 12)
    (0.0, 1.0)
    """
    check_mu(mu_front, mu_rear)
    s = state_vector(x)
    return axle_outputs(
        s, s.omega_front_radps, s.omega_rear_radps, mu_front, mu_rear, params,
        tire_for_surface(mu_front, params.tire, surface_tires),
        tire_for_surface(mu_rear, params.tire, surface_tires),
    )
