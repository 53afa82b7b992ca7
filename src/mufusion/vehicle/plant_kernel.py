"""The plant's step in plain floats: the equations of :mod:`mufusion.vehicle.axles`,
:mod:`mufusion.vehicle.tires` and :func:`mufusion.vehicle.plant.plant_derivative`, evaluated
without building a record per Runge–Kutta stage.

The plant steps 200 times per simulated second and evaluates both axles' tires six or seven
times per step; at that rate the interpreter's per-call and per-object costs dominate. Every
expression here keeps the operand order of the reference functions, so the results are bitwise
equal to them (``tests/vehicle/test_plant_kernel.py`` checks it); only the bookkeeping differs:
the vehicle's constants are read once, a chassis state is a tuple of the nine quantities its
rates depend on, and ``b if b > a else a`` stands for ``max(a, b)`` (the same value, NaN and
signed zeros included, without a built-in call).
"""

from __future__ import annotations

import functools
import math
from typing import Literal, Protocol, get_args

from mufusion.vehicle.axles import SLIP_SPEED_FLOOR_MPS
from mufusion.vehicle.params import GRAVITY_MPS2, TireParams, VehicleParams

# As in tires.py: below this |λ_req| the force is linear in the slip.
_SMALL_SLIP_SQUARED = 1e-12 * 1e-12
# Step of the finite difference dF_x/dκ in the implicit wheel update [-].
SLIP_DIFFERENCE_STEP = 1e-5

_atan, _sin, _cos, _sqrt = math.atan, math.sin, math.cos, math.sqrt

# Per axle, in this order: F_x, F_y [N] (wheel frame), F_z [N], κ, α [rad], realised and
# requested utilisation (0 on an unloaded axle), wheel-centre speed along the wheel [m/s].
AxleFloats = tuple[float, float, float, float, float, float, float, float]

# Which implementation steps the plant: "compiled" (the Cython twin in _plant_kernel_c, built by
# the install), "python" (this module) or "auto" (compiled where it was built).
KernelKind = Literal["auto", "compiled", "python"]
KERNEL_KINDS: tuple[str, ...] = get_args(KernelKind)

# What one plant step returns: the new state (PlantStateVector's layout), the axles there, and
# the steering angle's cosine and sine there.
StepResult = tuple[tuple[float, ...], tuple[AxleFloats, AxleFloats], float, float]

# The actuators' command ``(steer_rad, torque_front_nm, torque_rear_nm)``, optionally followed by
# the stability control's ``(yaw_moment_nm, force_x_n, front_lateral_share)``: the direct yaw
# moment, the longitudinal body force of the wheel it brakes and the share of the front axle's
# lateral force left beside it (single-track differential braking; stability_control.py).
Command = tuple[float, ...]


class Kernel(Protocol):
    """What :class:`~mufusion.vehicle.plant.Plant` needs of a kernel (either implementation)."""

    def step(
        self,
        chassis0: tuple[float, ...],
        omega_f0: float,
        omega_r0: float,
        command: Command,
        mu_f: float,
        mu_r: float,
        tire_f: TireParams,
        tire_r: TireParams,
        first_axles: tuple[AxleFloats, AxleFloats] | None,
    ) -> StepResult:
        """See :meth:`PlantKernel.step`."""
        ...


def unit_tire(
    kappa: float, alpha: float, mu: float, tire: TireParams
) -> tuple[float, float, float, float]:
    """``tire_forces_scalar(kappa, alpha, 1.0, mu, tire)``: forces per unit load, Φ, λ_req."""
    sx = tire.longitudinal_stiffness_per_load * kappa / mu
    sy = tire.cornering_stiffness_per_load_1_per_rad * alpha / mu
    sx2 = sx * sx
    lam2 = sx2 + sy * sy
    if lam2 < _SMALL_SLIP_SQUARED:
        return mu * sx, mu * sy, 0.0, 0.0
    lam = _sqrt(lam2)
    weight_x = sx2 / lam2
    shape = weight_x * tire.shape_longitudinal + (1.0 - weight_x) * tire.shape_lateral
    curv = weight_x * tire.curvature_longitudinal + (1.0 - weight_x) * tire.curvature_lateral
    bs = lam / shape
    phi = _sin(shape * _atan(bs - curv * (bs - _atan(bs))))
    # mu · 1.0 · Φ / λ with the unit load dropped (multiplying by 1.0 is exact).
    scale = mu * phi / lam
    return scale * sx, scale * sy, phi, lam


def loaded_tire_fx(
    kappa: float, alpha: float, normal_load_n: float, mu: float, tire: TireParams
) -> float:
    """``tire_forces_scalar(kappa, alpha, normal_load_n, mu, tire)[0]``."""
    if normal_load_n <= 0.0:
        return 0.0
    sx = tire.longitudinal_stiffness_per_load * kappa / mu
    sy = tire.cornering_stiffness_per_load_1_per_rad * alpha / mu
    sx2 = sx * sx
    lam2 = sx2 + sy * sy
    if lam2 < _SMALL_SLIP_SQUARED:
        return mu * normal_load_n * sx
    lam = _sqrt(lam2)
    weight_x = sx2 / lam2
    shape = weight_x * tire.shape_longitudinal + (1.0 - weight_x) * tire.shape_lateral
    curv = weight_x * tire.curvature_longitudinal + (1.0 - weight_x) * tire.curvature_lateral
    bs = lam / shape
    phi = _sin(shape * _atan(bs - curv * (bs - _atan(bs))))
    return mu * normal_load_n * phi / lam * sx


def _follow_axle(omega0: float, speed1: float, speed0: float, radius: float) -> float:
    """Wheel spin that keeps the slip ratio while the axle's speed goes ``speed0 → speed1``."""
    if omega0 > 0.0:
        omega = omega0 + (speed1 - speed0) / radius
        return 0.0 if 0.0 > omega else omega
    return 0.0


class PlantKernel:
    """One vehicle's constants and the float-level pieces of :class:`~.plant.Plant`'s step.

    A chassis state is the tuple ``(X, Y, ψ, v_x, v_y, ψ̇, δ, T_f, T_r)`` (the plant state
    without the wheel spins); its rates have the same layout.
    """

    __slots__ = (
        "dt",
        "g_lf",
        "g_lr",
        "h",
        "inertia",
        "lf",
        "lr",
        "mass",
        "max_steer_rate",
        "min_denominator",
        "radius",
        "steer_tau",
        "torque_tau",
        "weight",
        "wheelbase",
        "yaw_inertia",
    )

    def __init__(self, params: VehicleParams, dt_s: float) -> None:
        lf, lr = params.cog_to_front_axle_m, params.cog_to_rear_axle_m
        self.dt = dt_s
        self.lf, self.lr, self.h = lf, lr, params.cog_height_m
        self.wheelbase = lf + lr
        self.min_denominator = 0.1 * self.wheelbase
        self.g_lr, self.g_lf = GRAVITY_MPS2 * lr, GRAVITY_MPS2 * lf
        self.weight = params.mass_kg / self.wheelbase
        self.mass = params.mass_kg
        self.yaw_inertia = params.yaw_inertia_kgm2
        self.radius = params.wheel_radius_m
        self.inertia = params.wheel_inertia_kgm2
        self.steer_tau = params.steer_time_constant_s
        self.max_steer_rate = params.max_steer_rate_radps
        self.torque_tau = params.torque_time_constant_s

    def wheel_speeds(
        self, vx: float, vy: float, yaw_rate: float, steer: float
    ) -> tuple[float, float, float, float, float, float]:
        """``axles.wheel_speeds`` plus the steering angle's cosine and sine:
        ``(u_f, w_f, u_r, w_r, cos δ, sin δ)``."""
        lateral_f = vy + self.lf * yaw_rate
        cos_d, sin_d = _cos(steer), _sin(steer)
        return (vx * cos_d + lateral_f * sin_d, -vx * sin_d + lateral_f * cos_d, vx,
                vy - self.lr * yaw_rate, cos_d, sin_d)

    def axles(
        self,
        speeds: tuple[float, float, float, float, float, float],
        omega_f: float, omega_r: float, mu_f: float, mu_r: float,
        tire_f: TireParams, tire_r: TireParams,
    ) -> tuple[AxleFloats, AxleFloats]:
        """``axles.axle_outputs`` in floats (see :data:`AxleFloats`), front and rear."""
        u_f, w_f, u_r, w_r, cos_d, sin_d = speeds
        radius = self.radius
        den_f, den_r = abs(u_f), abs(u_r)
        den_f = SLIP_SPEED_FLOOR_MPS if SLIP_SPEED_FLOOR_MPS > den_f else den_f
        den_r = SLIP_SPEED_FLOOR_MPS if SLIP_SPEED_FLOOR_MPS > den_r else den_r
        kappa_f = (radius * omega_f - u_f) / den_f
        kappa_r = (radius * omega_r - u_r) / den_r
        alpha_f = -_atan(w_f / den_f)
        alpha_r = -_atan(w_r / den_r)
        gxf, gyf, used_f, asked_f = unit_tire(kappa_f, alpha_f, mu_f, tire_f)
        gxr, gyr, used_r, asked_r = unit_tire(kappa_r, alpha_r, mu_r, tire_r)
        # Quasi-static pitch load transfer in closed form (axles.axle_outputs).
        h, weight, min_denominator = self.h, self.weight, self.min_denominator
        g_front = gxf * cos_d - gyf * sin_d
        denominator = self.wheelbase + h * (g_front - gxr)
        if min_denominator > denominator:
            denominator = min_denominator
        accel = GRAVITY_MPS2 * (g_front * self.lr + gxr * self.lf) / denominator
        fzf = weight * (self.g_lr - accel * h)
        fzf = 0.0 if 0.0 > fzf else fzf
        fzr = weight * (self.g_lf + accel * h)
        fzr = 0.0 if 0.0 > fzr else fzr
        return (
            (gxf * fzf, gyf * fzf, fzf, kappa_f, alpha_f, used_f if fzf > 0.0 else 0.0,
             asked_f if fzf > 0.0 else 0.0, u_f),
            (gxr * fzr, gyr * fzr, fzr, kappa_r, alpha_r, used_r if fzr > 0.0 else 0.0,
             asked_r if fzr > 0.0 else 0.0, u_r),
        )

    def rates(
        self, psi: float, vx: float, vy: float, yaw_rate: float, steer: float, torque_f: float,
        torque_r: float, cos_d: float, sin_d: float, front: AxleFloats, rear: AxleFloats,
        command: Command,
    ) -> tuple[float, ...]:
        """``plant._chassis_rates`` of a chassis state, without the wheel-spin rates."""
        yaw_moment, force_x, lateral = command[3:6] if len(command) > 3 else (0.0, 0.0, 1.0)
        fx_f, fy_f, fx_r, fy_r = front[0], front[1] * lateral, rear[0], rear[1]
        fx_front_body = fx_f * cos_d - fy_f * sin_d
        fy_front_body = fx_f * sin_d + fy_f * cos_d
        m = self.mass
        cos_p, sin_p = _cos(psi), _sin(psi)
        steer_cmd, torque_f_cmd, torque_r_cmd = command[0], command[1], command[2]
        max_rate = self.max_steer_rate
        steer_rate = (steer_cmd - steer) / self.steer_tau
        # min(max(rate, -max_rate), max_rate)
        if -max_rate > steer_rate:
            steer_rate = -max_rate
        if max_rate < steer_rate:
            steer_rate = max_rate
        torque_tau = self.torque_tau
        return (
            vx * cos_p - vy * sin_p,
            vx * sin_p + vy * cos_p,
            yaw_rate,
            (fx_front_body + fx_r + force_x) / m + vy * yaw_rate,
            (fy_front_body + fy_r) / m - vx * yaw_rate,
            (self.lf * fy_front_body - self.lr * fy_r + yaw_moment) / self.yaw_inertia,
            steer_rate,
            (torque_f_cmd - torque_f) / torque_tau,
            (torque_r_cmd - torque_r) / torque_tau,
        )

    def chassis_step(
        self,
        chassis0: tuple[float, ...],
        omega_f0: float,
        omega_r0: float,
        command: Command,
        mu_f: float,
        mu_r: float,
        tire_f: TireParams,
        tire_r: TireParams,
        first_axles: tuple[AxleFloats, AxleFloats] | None = None,
    ) -> tuple[list[float], float, float]:
        """One classical RK4 step of the chassis with each wheel following its axle's speed.

        ``first_axles``: the axles at ``chassis0`` with the wheels at ``omega_f0``,
        ``omega_r0`` if already known (the previous step's output). Returns the new chassis
        state and the front and rear axle speeds at ``chassis0``.
        """
        dt, radius = self.dt, self.radius
        axles, rates, speeds_of = self.axles, self.rates, self.wheel_speeds
        _, _, psi0, vx0, vy0, r0, steer0, tf0, tr0 = chassis0
        speeds0 = speeds_of(vx0, vy0, r0, steer0)
        u_f0, u_r0 = speeds0[0], speeds0[2]
        if first_axles is None:
            first_axles = axles(
                speeds0, _follow_axle(omega_f0, u_f0, u_f0, radius),
                _follow_axle(omega_r0, u_r0, u_r0, radius), mu_f, mu_r, tire_f, tire_r,
            )
        k1 = rates(psi0, vx0, vy0, r0, steer0, tf0, tr0, speeds0[4], speeds0[5], *first_axles,
                   command)

        def stage(scale: float, k: tuple[float, ...]) -> tuple[float, ...]:
            # The state x₀ + scale · k (its position does not enter the rates).
            vx, vy, r, steer = vx0 + scale * k[3], vy0 + scale * k[4], r0 + scale * k[5], (
                steer0 + scale * k[6])
            speeds = speeds_of(vx, vy, r, steer)
            front, rear = axles(
                speeds, _follow_axle(omega_f0, speeds[0], u_f0, radius),
                _follow_axle(omega_r0, speeds[2], u_r0, radius), mu_f, mu_r, tire_f, tire_r,
            )
            return rates(psi0 + scale * k[2], vx, vy, r, steer, tf0 + scale * k[7],
                         tr0 + scale * k[8], speeds[4], speeds[5], front, rear, command)

        half = 0.5 * dt
        k2 = stage(half, k1)
        k3 = stage(half, k2)
        k4 = stage(dt, k3)
        sixth = dt / 6.0
        chassis = [
            a + sixth * (b1 + 2.0 * b2 + 2.0 * b3 + b4)
            for a, b1, b2, b3, b4 in zip(chassis0, k1, k2, k3, k4, strict=True)
        ]
        return chassis, u_f0, u_r0

    def implicit_wheels(
        self,
        chassis1: list[float],
        omega_f0: float,
        omega_r0: float,
        u_f0: float,
        u_r0: float,
        mu_f: float,
        mu_r: float,
        tire_f: TireParams,
        tire_r: TireParams,
    ) -> tuple[float, float]:
        """Linearly implicit Euler step of both wheel spins at the new chassis state."""
        dt, radius, inertia = self.dt, self.radius, self.inertia
        speeds = self.wheel_speeds(chassis1[3], chassis1[4], chassis1[5], chassis1[6])
        predicted_f = _follow_axle(omega_f0, speeds[0], u_f0, radius)
        predicted_r = _follow_axle(omega_r0, speeds[2], u_r0, radius)
        front, rear = self.axles(speeds, predicted_f, predicted_r, mu_f, mu_r, tire_f, tire_r)
        new = []
        for omega0, predicted, torque, axle, mu, tire in (
            (omega_f0, predicted_f, chassis1[7], front, mu_f, tire_f),
            (omega_r0, predicted_r, chassis1[8], rear, mu_r, tire_r),
        ):
            fx, fz, kappa, alpha, wheel_speed = axle[0], axle[2], axle[3], axle[4], axle[7]
            # Tangent stiffness dF_x/dω (clamped at 0 beyond the peak) for the implicit step.
            fx_plus = loaded_tire_fx(kappa + SLIP_DIFFERENCE_STEP, alpha, fz, mu, tire)
            slope = max((fx_plus - fx) / SLIP_DIFFERENCE_STEP, 0.0) * radius / max(
                abs(wheel_speed), SLIP_SPEED_FLOOR_MPS
            )
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

    def step(
        self,
        chassis0: tuple[float, ...],
        omega_f0: float,
        omega_r0: float,
        command: Command,
        mu_f: float,
        mu_r: float,
        tire_f: TireParams,
        tire_r: TireParams,
        first_axles: tuple[AxleFloats, AxleFloats] | None,
    ) -> StepResult:
        """One plant step: the chassis's RK4 step, the wheels' implicit step, the new axles.

        Parameters are those of :meth:`chassis_step`. Returns the new plant state as the
        :class:`~mufusion.vehicle.plant_state.PlantStateVector` layout (11 floats), the axles at
        it (with the new wheel spins) and the steering angle's cosine and sine there.
        """
        chassis, u_f0, u_r0 = self.chassis_step(
            chassis0, omega_f0, omega_r0, command, mu_f, mu_r, tire_f, tire_r, first_axles
        )
        omega_f, omega_r = self.implicit_wheels(
            chassis, omega_f0, omega_r0, u_f0, u_r0, mu_f, mu_r, tire_f, tire_r
        )
        speeds = self.wheel_speeds(chassis[3], chassis[4], chassis[5], chassis[6])
        axles = self.axles(speeds, omega_f, omega_r, mu_f, mu_r, tire_f, tire_r)
        return (*chassis[:6], omega_f, omega_r, *chassis[6:]), axles, speeds[4], speeds[5]


@functools.lru_cache(maxsize=1)
def compiled_kernel_available() -> bool:
    """Whether the compiled kernel was built (``pip install`` compiles it; a bare source tree
    has only this module)."""
    try:
        from mufusion.vehicle._plant_kernel_c import CompiledPlantKernel  # noqa: F401
    except ImportError:
        return False
    return True


def make_kernel(params: VehicleParams, dt_s: float, kind: str = "auto") -> Kernel:
    """The plant's kernel for one vehicle: a :class:`PlantKernel` or its compiled twin.

    Both give bitwise the same steps (``tests/vehicle/test_plant_kernel.py``); the compiled one
    takes a fraction of the time. ``kind`` is one of :data:`KERNEL_KINDS`.

    Raises
    ------
    ValueError
        If ``kind`` is unknown, or ``"compiled"`` and the compiled kernel was not built.
    """
    if kind not in KERNEL_KINDS:
        raise ValueError(f"kernel must be one of {', '.join(KERNEL_KINDS)}; got {kind!r}")
    kernel = PlantKernel(params, dt_s)
    if kind == "python" or (kind == "auto" and not compiled_kernel_available()):
        return kernel
    try:
        from mufusion.vehicle._plant_kernel_c import CompiledPlantKernel
    except ImportError as exc:
        raise ValueError(
            "kernel='compiled' needs the compiled plant kernel, which this installation lacks "
            "(reinstall with `pip install -e .`)"
        ) from exc
    return CompiledPlantKernel(kernel, GRAVITY_MPS2, SLIP_SPEED_FLOOR_MPS, SLIP_DIFFERENCE_STEP)
