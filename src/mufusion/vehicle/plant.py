"""The plant: what the world does to the vehicle, deliberately richer than the planner's model.

A dynamic bicycle in Cartesian coordinates with

* wheel-speed dynamics per axle (``I_w ω̇ = T_drive − T_brake − R F_x``),
* the combined-slip Magic Formula tire of :mod:`mufusion.vehicle.tires`, whose peak is μ F_z with
  the true μ under each axle and whose stiffness does not depend on μ,
* quasi-static longitudinal load transfer from the current acceleration (solved in closed form,
  see :func:`_axle_forces`),
* a first-order, rate-limited steering servo and first-order wheel-torque lags.

Low speed: slip ratio and slip angle divide by ``max(|u|, SLIP_SPEED_FLOOR_MPS)``, so below
1 m/s the tires act as stiff viscous dampers and the vehicle comes to rest without a singularity;
brakes act as Coulomb friction on the wheel (they stop it, they never spin it backwards). The
vehicle does not reverse.

State vector: :class:`PlantState`. Input: :class:`~mufusion.vehicle.actuators.ActuatorCommand`
(or an array ``[steer_rad, torque_front_nm, torque_rear_nm]``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum
from typing import Any

import numpy as np

from mufusion.vehicle.actuators import ActuatorCommand
from mufusion.vehicle.params import GRAVITY_MPS2, VehicleParams
from mufusion.vehicle.tires import tire_forces_scalar

# Slip quantities divide by at least this speed [m/s] (the "regularise below ~1 m/s").
SLIP_SPEED_FLOOR_MPS = 1.0
# In the pure derivative the brake torque opposes ω through sat(ω / this) [rad/s]; the stepping
# scheme of :class:`Plant` treats the brake as exact Coulomb friction instead.
BRAKE_SIGN_SMOOTHING_RADPS = 0.5
DEFAULT_DT_S = 1.0 / 200.0


class PlantState(IntEnum):
    """Indices of the plant state vector (SI units, radians)."""

    X = 0  # CoG position, east [m]
    Y = 1  # CoG position, north [m]
    PSI = 2  # yaw angle [rad], counter-clockwise from X
    VX = 3  # longitudinal body velocity [m/s]
    VY = 4  # lateral body velocity [m/s], left positive
    YAW_RATE = 5  # [rad/s]
    OMEGA_FRONT = 6  # front wheel spin [rad/s]
    OMEGA_REAR = 7  # rear wheel spin [rad/s]
    STEER = 8  # front road-wheel angle [rad]
    TORQUE_FRONT = 9  # applied front wheel torque [N m], braking negative
    TORQUE_REAR = 10  # applied rear wheel torque [N m]


N_PLANT_STATES = len(PlantState)


@dataclass(frozen=True)
class PlantOutput:
    """Everything the controller, the estimators and the metrics may read after one plant step.

    Forces are in each axle's wheel frame (``fx`` along the wheel, ``fy`` across it) [N];
    ``fz`` are normal loads [N]. Utilisations are fractions of μ F_z of that axle: realised ones
    are ``hypot(fx, fy) / (μ F_z)`` ≤ 1; requested ones are what a linear tire would deliver for
    the same slip (≥ 0, exceed 1 when the tire slides). Accelerations are in the body frame
    [m/s²] and exclude the velocity-rotation terms (what an IMU would measure).
    """

    x: np.ndarray
    time_s: float
    utilization_front: float
    utilization_rear: float
    requested_utilization_front: float
    requested_utilization_rear: float
    fx_front_n: float
    fy_front_n: float
    fz_front_n: float
    fx_rear_n: float
    fy_rear_n: float
    fz_rear_n: float
    slip_angle_front_rad: float
    slip_angle_rear_rad: float
    slip_ratio_front: float
    slip_ratio_rear: float
    accel_x_mps2: float
    accel_y_mps2: float
    front_axle_xy_m: tuple[float, float]
    rear_axle_xy_m: tuple[float, float]
    mu_front: float
    mu_rear: float

    @property
    def speed_mps(self) -> float:
        """Speed of the centre of gravity [m/s]."""
        return math.hypot(self.x[PlantState.VX], self.x[PlantState.VY])


@dataclass(frozen=True)
class AxleForces:
    """Tire forces and slips of both axles at one state (wheel frames; N, rad, -).

    ``used_*`` / ``asked_*`` are the realised / requested utilisations, ``speed_*`` the wheel
    centre's speed along the wheel and ``den_*`` the (floored) speed the slips divide by.
    """

    fxf: float
    fyf: float
    fzf: float
    fxr: float
    fyr: float
    fzr: float
    kappa_f: float
    alpha_f: float
    kappa_r: float
    alpha_r: float
    used_f: float
    asked_f: float
    used_r: float
    asked_r: float
    speed_f: float
    speed_r: float
    den_f: float
    den_r: float


def _check_mu(mu_front: float, mu_rear: float) -> None:
    if not (mu_front > 0.0 and math.isfinite(mu_front)):
        raise ValueError(f"mu_front must be a finite number > 0, got {mu_front!r}")
    if not (mu_rear > 0.0 and math.isfinite(mu_rear)):
        raise ValueError(f"mu_rear must be a finite number > 0, got {mu_rear!r}")


def _wheel_speeds(vx: float, vy: float, yaw_rate: float, steer: float, p: VehicleParams):
    """Velocity of each wheel centre in its own frame: (u_f, w_f, u_r, w_r) [m/s]."""
    lateral_f = vy + p.cog_to_front_axle_m * yaw_rate
    cos_d, sin_d = math.cos(steer), math.sin(steer)
    u_f = vx * cos_d + lateral_f * sin_d
    w_f = -vx * sin_d + lateral_f * cos_d
    return u_f, w_f, vx, vy - p.cog_to_rear_axle_m * yaw_rate


def _axle_forces(
    vx: float,
    vy: float,
    yaw_rate: float,
    steer: float,
    omega_f: float,
    omega_r: float,
    mu_f: float,
    mu_r: float,
    p: VehicleParams,
) -> AxleForces:
    u_f, w_f, u_r, w_r = _wheel_speeds(vx, vy, yaw_rate, steer, p)
    radius = p.wheel_radius_m
    den_f = max(abs(u_f), SLIP_SPEED_FLOOR_MPS)
    den_r = max(abs(u_r), SLIP_SPEED_FLOOR_MPS)
    kappa_f = (radius * omega_f - u_f) / den_f
    kappa_r = (radius * omega_r - u_r) / den_r
    alpha_f = -math.atan(w_f / den_f)
    alpha_r = -math.atan(w_r / den_r)
    # Forces per unit load: slip does not depend on F_z and the tire scales linearly with it.
    gxf, gyf, used_f, asked_f = tire_forces_scalar(kappa_f, alpha_f, 1.0, mu_f, p.tire)
    gxr, gyr, used_r, asked_r = tire_forces_scalar(kappa_r, alpha_r, 1.0, mu_r, p.tire)
    # Quasi-static pitch load transfer: m a = F_zf g_f + F_zr g_r with
    # F_zf = m (g l_r − a h)/L, F_zr = m (g l_f + a h)/L, solved for a in closed form.
    lf, lr, h = p.cog_to_front_axle_m, p.cog_to_rear_axle_m, p.cog_height_m
    wheelbase = lf + lr
    g_front = gxf * math.cos(steer) - gyf * math.sin(steer)
    denominator = max(wheelbase + h * (g_front - gxr), 0.1 * wheelbase)
    accel = GRAVITY_MPS2 * (g_front * lr + gxr * lf) / denominator
    weight = p.mass_kg / wheelbase
    fzf = max(weight * (GRAVITY_MPS2 * lr - accel * h), 0.0)
    fzr = max(weight * (GRAVITY_MPS2 * lf + accel * h), 0.0)
    return AxleForces(
        fxf=gxf * fzf,
        fyf=gyf * fzf,
        fzf=fzf,
        fxr=gxr * fzr,
        fyr=gyr * fzr,
        fzr=fzr,
        kappa_f=kappa_f,
        alpha_f=alpha_f,
        kappa_r=kappa_r,
        alpha_r=alpha_r,
        used_f=used_f if fzf > 0.0 else 0.0,
        asked_f=asked_f if fzf > 0.0 else 0.0,
        used_r=used_r if fzr > 0.0 else 0.0,
        asked_r=asked_r if fzr > 0.0 else 0.0,
        speed_f=u_f,
        speed_r=u_r,
        den_f=den_f,
        den_r=den_r,
    )


def axle_forces(
    x: np.ndarray, mu_front: float, mu_rear: float, params: VehicleParams
) -> AxleForces:
    """Tire forces, slips and utilisations of both axles at plant state ``x``.

    Parameters
    ----------
    x
        Plant state, shape ``(11,)``.
    mu_front, mu_rear
        True road friction under each axle [-], > 0.
    params
        Vehicle parameters.

    Raises
    ------
    ValueError
        If a μ is not > 0 or ``x`` has the wrong shape.
    """
    _check_mu(mu_front, mu_rear)
    s = _validate_state(x).tolist()
    return _axle_forces(s[3], s[4], s[5], s[8], s[6], s[7], mu_front, mu_rear, params)


def _command_tuple(command: Any, params: VehicleParams) -> tuple[float, float, float]:
    if not isinstance(command, ActuatorCommand):
        values = np.asarray(command, dtype=float).reshape(-1)
        if values.shape != (3,):
            raise ValueError(
                "command must be an ActuatorCommand or [steer_rad, torque_front_nm, "
                f"torque_rear_nm], got shape {values.shape}"
            )
        command = ActuatorCommand(float(values[0]), float(values[1]), float(values[2]))
    clipped = command.clipped(params)
    return clipped.steer_rad, clipped.torque_front_nm, clipped.torque_rear_nm


def _chassis_rates(
    x: list[float] | tuple[float, ...] | np.ndarray,
    forces: AxleForces,
    command: tuple[float, float, float],
    p: VehicleParams,
) -> list[float]:
    """Derivatives of every state except the wheel speeds (returned as 0)."""
    psi, vx, vy, yaw_rate, steer = x[2], x[3], x[4], x[5], x[8]
    cos_d, sin_d = math.cos(steer), math.sin(steer)
    fx_front_body = forces.fxf * cos_d - forces.fyf * sin_d
    fy_front_body = forces.fxf * sin_d + forces.fyf * cos_d
    m = p.mass_kg
    cos_p, sin_p = math.cos(psi), math.sin(psi)
    steer_cmd, torque_f_cmd, torque_r_cmd = command
    steer_rate = (steer_cmd - steer) / p.steer_time_constant_s
    steer_rate = min(max(steer_rate, -p.max_steer_rate_radps), p.max_steer_rate_radps)
    return [
        vx * cos_p - vy * sin_p,
        vx * sin_p + vy * cos_p,
        yaw_rate,
        (fx_front_body + forces.fxr) / m + vy * yaw_rate,
        (fy_front_body + forces.fyr) / m - vx * yaw_rate,
        (p.cog_to_front_axle_m * fy_front_body - p.cog_to_rear_axle_m * forces.fyr)
        / p.yaw_inertia_kgm2,
        0.0,
        0.0,
        steer_rate,
        (torque_f_cmd - x[9]) / p.torque_time_constant_s,
        (torque_r_cmd - x[10]) / p.torque_time_constant_s,
    ]


def _validate_state(x: Any) -> np.ndarray:
    arr = np.asarray(x, dtype=float)
    if arr.shape != (N_PLANT_STATES,):
        raise ValueError(f"x must have shape ({N_PLANT_STATES},), got {arr.shape}")
    return arr


def plant_derivative(
    x: np.ndarray,
    command: ActuatorCommand | np.ndarray,
    mu_front: float,
    mu_rear: float,
    params: VehicleParams,
) -> np.ndarray:
    """Time derivative of the plant state (pure function).

    Parameters
    ----------
    x
        Plant state, shape ``(11,)``, indexed by :class:`PlantState`.
    command
        Actuator command (clipped to the actuator limits before use), or an array
        ``[steer_rad, torque_front_nm, torque_rear_nm]``.
    mu_front, mu_rear
        True road friction under the front and the rear axle [-], > 0.
    params
        Vehicle parameters.

    Returns
    -------
    x_dot
        Shape ``(11,)``. The brake torque opposes the wheel spin through ``sat(ω / 0.5 rad/s)``
        here; :class:`Plant` integrates the brake as exact Coulomb friction instead.

    Raises
    ------
    ValueError
        If a μ is not > 0 or ``x`` / ``command`` have the wrong shape.

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> x0 = initial_state(CAR, 0.0, 0.0, 0.0, 10.0)
    >>> xd = plant_derivative(x0, ActuatorCommand(0.0, 0.0, 0.0), 1.0, 1.0, CAR)
    >>> round(float(xd[PlantState.X]), 6), round(float(xd[PlantState.VX]), 6)
    (10.0, 0.0)
    """
    _check_mu(mu_front, mu_rear)
    state = _validate_state(x).tolist()
    cmd = _command_tuple(command, params)
    forces = _axle_forces(
        state[3], state[4], state[5], state[8], state[6], state[7], mu_front, mu_rear, params
    )
    rates = _chassis_rates(state, forces, cmd, params)
    radius, inertia = params.wheel_radius_m, params.wheel_inertia_kgm2
    for index, torque, fx in (
        (PlantState.OMEGA_FRONT, state[9], forces.fxf),
        (PlantState.OMEGA_REAR, state[10], forces.fxr),
    ):
        omega = state[index]
        drive, brake = max(torque, 0.0), max(-torque, 0.0)
        brake_sign = min(max(omega / BRAKE_SIGN_SMOOTHING_RADPS, -1.0), 1.0)
        rates[index] = (drive - brake * brake_sign - radius * fx) / inertia
    return np.asarray(rates)


def initial_state(
    params: VehicleParams, X: float, Y: float, psi: float, speed_mps: float
) -> np.ndarray:
    """A plant state driving straight at ``speed_mps`` with free-rolling wheels.

    Parameters
    ----------
    params
        Vehicle parameters (wheel radius).
    X, Y
        Position of the centre of gravity [m].
    psi
        Yaw angle [rad].
    speed_mps
        Forward speed [m/s], ≥ 0.

    Raises
    ------
    ValueError
        If ``speed_mps`` is negative or not finite.
    """
    if not (math.isfinite(speed_mps) and speed_mps >= 0.0):
        raise ValueError(f"speed_mps must be finite and >= 0, got {speed_mps!r}")
    x = np.zeros(N_PLANT_STATES)
    x[PlantState.X], x[PlantState.Y], x[PlantState.PSI] = X, Y, psi
    x[PlantState.VX] = speed_mps
    x[PlantState.OMEGA_FRONT] = x[PlantState.OMEGA_REAR] = speed_mps / params.wheel_radius_m
    return x


def axle_positions(x: np.ndarray, params: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """Cartesian positions of the front and rear axle centres [m].

    Parameters
    ----------
    x
        Plant state(s), shape ``(11, ...)``.
    params
        Vehicle parameters (axle distances from the CoG).

    Returns
    -------
    front_xy, rear_xy
        Each of shape ``(2, ...)``.
    """
    arr = np.asarray(x, dtype=float)
    heading = np.stack([np.cos(arr[PlantState.PSI]), np.sin(arr[PlantState.PSI])])
    cog = np.stack([arr[PlantState.X], arr[PlantState.Y]])
    return cog + params.cog_to_front_axle_m * heading, cog - params.cog_to_rear_axle_m * heading


class Plant:
    """Integrates the plant at a fixed rate and reports what the sensors and metrics need.

    Scheme per step (explicit chassis, implicit wheels, because the wheel-spin mode is far
    faster than any plant rate at low speed): the chassis and actuator states take one classical
    RK4 step in which each wheel follows the speed of its axle (``ω = ω₀ + (u − u₀)/R``, so the
    slip ratio stays put); then each wheel speed takes a linearly implicit Euler step of
    ``I_w ω̇ = T_drive − R F_x(ω)`` around that prediction, and the brake acts as Coulomb friction
    (it can hold a wheel at rest but never reverses it).

    Parameters
    ----------
    params
        Vehicle parameters.
    x0
        Initial state, shape ``(11,)`` (see :func:`initial_state`).
    dt_s
        Step [s], at most 1/200 s.

    Raises
    ------
    ValueError
        If ``dt_s`` is not in (0, 1/200] or ``x0`` has the wrong shape.
    """

    def __init__(
        self, params: VehicleParams, x0: np.ndarray, dt_s: float = DEFAULT_DT_S
    ) -> None:
        if not (0.0 < dt_s <= DEFAULT_DT_S + 1e-12):
            raise ValueError(f"dt_s must be in (0, {DEFAULT_DT_S}] s, got {dt_s!r}")
        self.params = params
        self.dt_s = float(dt_s)
        self._x = _validate_state(x0).tolist()
        self.time_s = 0.0

    @property
    def x(self) -> np.ndarray:
        """Current state, shape ``(11,)`` (a copy)."""
        return np.asarray(self._x)

    def _stage(
        self,
        x: list[float],
        base: tuple[float, float, float, float, float],
        cmd: tuple[float, float, float],
        mu_f: float,
        mu_r: float,
    ) -> list[float]:
        p = self.params
        omega_f0, omega_r0, u_f0, u_r0, radius = base
        u_f, _, u_r, _ = _wheel_speeds(x[3], x[4], x[5], x[8], p)
        omega_f = max(omega_f0 + (u_f - u_f0) / radius, 0.0) if omega_f0 > 0.0 else 0.0
        omega_r = max(omega_r0 + (u_r - u_r0) / radius, 0.0) if omega_r0 > 0.0 else 0.0
        forces = _axle_forces(x[3], x[4], x[5], x[8], omega_f, omega_r, mu_f, mu_r, p)
        return _chassis_rates(x, forces, cmd, p)

    def step(
        self, command: ActuatorCommand | np.ndarray, mu_front: float, mu_rear: float
    ) -> PlantOutput:
        """Advance one step with the given command and the true friction under each axle.

        Parameters
        ----------
        command
            Actuator command (clipped to the limits), or ``[steer, torque_front, torque_rear]``.
        mu_front, mu_rear
            True road friction under the front and rear axle [-], > 0.

        Returns
        -------
        PlantOutput
            State and tire quantities at the end of the step.

        Raises
        ------
        ValueError
            If a μ is not > 0.
        """
        _check_mu(mu_front, mu_rear)
        p, dt = self.params, self.dt_s
        cmd = _command_tuple(command, p)
        x0 = self._x
        u_f0, _, u_r0, _ = _wheel_speeds(x0[3], x0[4], x0[5], x0[8], p)
        base = (x0[6], x0[7], u_f0, u_r0, p.wheel_radius_m)

        def stage(x: list[float]) -> list[float]:
            return self._stage(x, base, cmd, mu_front, mu_rear)

        k1 = stage(x0)
        k2 = stage([a + 0.5 * dt * b for a, b in zip(x0, k1, strict=True)])
        k3 = stage([a + 0.5 * dt * b for a, b in zip(x0, k2, strict=True)])
        k4 = stage([a + dt * b for a, b in zip(x0, k3, strict=True)])
        x1 = [
            a + dt / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
            for a, b1, b2, b3, b4 in zip(x0, k1, k2, k3, k4, strict=True)
        ]
        u_f1, _, u_r1, _ = _wheel_speeds(x1[3], x1[4], x1[5], x1[8], p)
        radius = p.wheel_radius_m
        predicted_f = max(x0[6] + (u_f1 - u_f0) / radius, 0.0) if x0[6] > 0.0 else 0.0
        predicted_r = max(x0[7] + (u_r1 - u_r0) / radius, 0.0) if x0[7] > 0.0 else 0.0
        x1[6], x1[7] = self._implicit_wheels(
            x0, x1, predicted_f, predicted_r, mu_front, mu_rear
        )
        self._x = x1
        self.time_s += dt
        return self._output(x1, mu_front, mu_rear)

    def _implicit_wheels(
        self,
        x0: list[float],
        x1: list[float],
        predicted_f: float,
        predicted_r: float,
        mu_f: float,
        mu_r: float,
    ) -> tuple[float, float]:
        p, dt = self.params, self.dt_s
        radius, inertia = p.wheel_radius_m, p.wheel_inertia_kgm2
        forces = _axle_forces(x1[3], x1[4], x1[5], x1[8], predicted_f, predicted_r, mu_f, mu_r, p)
        new = []
        for omega0, predicted, torque, fx, fz, kappa, alpha, mu, den in (
            (x0[6], predicted_f, x1[9], forces.fxf, forces.fzf, forces.kappa_f,
             forces.alpha_f, mu_f, forces.den_f),
            (x0[7], predicted_r, x1[10], forces.fxr, forces.fzr, forces.kappa_r,
             forces.alpha_r, mu_r, forces.den_r),
        ):
            # Tangent stiffness dF_x/dω (clamped at 0 beyond the peak) for the implicit step.
            step = 1e-5
            fx_plus, _, _, _ = tire_forces_scalar(kappa + step, alpha, fz, mu, p.tire)
            slope = max((fx_plus - fx) / step, 0.0) * radius / den
            effective = inertia + dt * radius * slope
            drive, brake = max(torque, 0.0), max(-torque, 0.0)
            free = (
                inertia * omega0 + dt * (drive - radius * fx + radius * slope * predicted)
            ) / effective
            hold = dt * brake / effective
            if free > hold:
                new.append(free - hold)
            elif free < -hold:
                new.append(free + hold)
            else:
                new.append(0.0)
        return new[0], new[1]

    def _output(self, x: list[float], mu_f: float, mu_r: float) -> PlantOutput:
        p = self.params
        forces = _axle_forces(x[3], x[4], x[5], x[8], x[6], x[7], mu_f, mu_r, p)
        steer = x[8]
        cos_d, sin_d = math.cos(steer), math.sin(steer)
        m = p.mass_kg
        cos_p, sin_p = math.cos(x[2]), math.sin(x[2])
        lf, lr = p.cog_to_front_axle_m, p.cog_to_rear_axle_m
        return PlantOutput(
            x=np.asarray(x),
            time_s=self.time_s,
            utilization_front=forces.used_f,
            utilization_rear=forces.used_r,
            requested_utilization_front=forces.asked_f,
            requested_utilization_rear=forces.asked_r,
            fx_front_n=forces.fxf,
            fy_front_n=forces.fyf,
            fz_front_n=forces.fzf,
            fx_rear_n=forces.fxr,
            fy_rear_n=forces.fyr,
            fz_rear_n=forces.fzr,
            slip_angle_front_rad=forces.alpha_f,
            slip_angle_rear_rad=forces.alpha_r,
            slip_ratio_front=forces.kappa_f,
            slip_ratio_rear=forces.kappa_r,
            accel_x_mps2=(forces.fxf * cos_d - forces.fyf * sin_d + forces.fxr) / m,
            accel_y_mps2=(forces.fxf * sin_d + forces.fyf * cos_d + forces.fyr) / m,
            front_axle_xy_m=(x[0] + lf * cos_p, x[1] + lf * sin_p),
            rear_axle_xy_m=(x[0] - lr * cos_p, x[1] - lr * sin_p),
            mu_front=mu_f,
            mu_rear=mu_r,
        )
