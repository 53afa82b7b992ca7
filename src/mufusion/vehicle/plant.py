"""The plant: what the world does to the vehicle, deliberately richer than the planner's model.

A dynamic bicycle in Cartesian coordinates with

* wheel-speed dynamics per axle (``I_w ω̇ = T_drive − T_brake − R F_x``),
* the combined-slip Magic Formula tire of :mod:`mufusion.vehicle.tires`, whose peak is μ F_z with
  the true μ under each axle and whose stiffness does not depend on μ (or, with a
  :class:`~mufusion.vehicle.surface_tires.SurfaceTireTable`, whose coefficients follow the surface
  under each axle, as in the authors' simulator),
* quasi-static longitudinal load transfer from the current acceleration (solved in closed form,
  see :mod:`mufusion.vehicle.axles`),
* a first-order, rate-limited steering servo and first-order wheel-torque lags.

Brakes act as Coulomb friction on the wheel (they stop it, they never spin it backwards). The
vehicle does not reverse.

State: :class:`~mufusion.vehicle.plant_state.PlantState` (array indices) and
:class:`~mufusion.vehicle.plant_state.PlantStateVector` (named floats). Input:
:class:`~mufusion.vehicle.actuators.ActuatorCommand` (or an array
``[steer_rad, torque_front_nm, torque_rear_nm]``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mufusion.vehicle.actuators import ActuatorCommand, clip_command
from mufusion.vehicle.axles import (
    SLIP_SPEED_FLOOR_MPS,
    AxleOutput,
    axle_forces,
    axle_outputs,
    check_mu,
)
from mufusion.vehicle.params import TireParams, VehicleParams
from mufusion.vehicle.plant_kernel import AxleFloats, make_kernel
from mufusion.vehicle.plant_output import PlantOutput
from mufusion.vehicle.plant_state import (
    N_PLANT_STATES,
    PlantState,
    PlantStateVector,
    axle_positions,
    initial_state,
    state_vector,
)
from mufusion.vehicle.slip_control import (
    SlipControlSettings,
    WheelSlipController,
)
from mufusion.vehicle.stability_control import (
    StabilityControlSettings,
    YawStabilityController,
)
from mufusion.vehicle.surface_tires import SurfaceTireTable, tire_for_surface

__all__ = [
    "BRAKE_SIGN_SMOOTHING_RADPS",
    "DEFAULT_DT_S",
    "N_PLANT_STATES",
    "SLIP_SPEED_FLOOR_MPS",
    "AxleOutput",
    "Plant",
    "PlantOutput",
    "PlantState",
    "PlantStateVector",
    "axle_forces",
    "axle_positions",
    "initial_state",
    "plant_derivative",
]

# In the pure derivative the brake torque opposes ω through sat(ω / this) [rad/s]; the stepping
# scheme of :class:`Plant` treats the brake as exact Coulomb friction instead.
BRAKE_SIGN_SMOOTHING_RADPS = 0.5
DEFAULT_DT_S = 1.0 / 200.0


def _command_tuple(command: Any, params: VehicleParams) -> tuple[float, float, float]:
    if isinstance(command, ActuatorCommand):
        return clip_command(
            command.steer_rad, command.torque_front_nm, command.torque_rear_nm, params
        )
    values = np.asarray(command, dtype=float).reshape(-1)
    if values.shape != (3,):
        raise ValueError(
            "command must be an ActuatorCommand or [steer_rad, torque_front_nm, "
            f"torque_rear_nm], got shape {values.shape}"
        )
    return clip_command(float(values[0]), float(values[1]), float(values[2]), params)


def _chassis_rates(
    x: PlantStateVector,
    front: AxleOutput,
    rear: AxleOutput,
    command: tuple[float, float, float],
    p: VehicleParams,
    omega_front_rate: float = 0.0,
    omega_rear_rate: float = 0.0,
) -> PlantStateVector:
    """Time derivative of ``x``; the wheel-spin rates are given (the plant treats them apart)."""
    cos_d, sin_d = math.cos(x.steer_rad), math.sin(x.steer_rad)
    fx_front_body = front.fx_n * cos_d - front.fy_n * sin_d
    fy_front_body = front.fx_n * sin_d + front.fy_n * cos_d
    m = p.mass_kg
    vx, vy, yaw_rate = x.vx_mps, x.vy_mps, x.yaw_rate_radps
    cos_p, sin_p = math.cos(x.psi_rad), math.sin(x.psi_rad)
    steer_cmd, torque_f_cmd, torque_r_cmd = command
    steer_rate = (steer_cmd - x.steer_rad) / p.steer_time_constant_s
    steer_rate = min(max(steer_rate, -p.max_steer_rate_radps), p.max_steer_rate_radps)
    return PlantStateVector(
        x_m=vx * cos_p - vy * sin_p,
        y_m=vx * sin_p + vy * cos_p,
        psi_rad=yaw_rate,
        vx_mps=(fx_front_body + rear.fx_n) / m + vy * yaw_rate,
        vy_mps=(fy_front_body + rear.fy_n) / m - vx * yaw_rate,
        yaw_rate_radps=(p.cog_to_front_axle_m * fy_front_body - p.cog_to_rear_axle_m * rear.fy_n)
        / p.yaw_inertia_kgm2,
        omega_front_radps=omega_front_rate,
        omega_rear_radps=omega_rear_rate,
        steer_rad=steer_rate,
        torque_front_nm=(torque_f_cmd - x.torque_front_nm) / p.torque_time_constant_s,
        torque_rear_nm=(torque_r_cmd - x.torque_rear_nm) / p.torque_time_constant_s,
    )


def _smoothed_wheel_rate(
    omega: float, torque: float, axle: AxleOutput, p: VehicleParams
) -> float:
    """``I_w ω̇ = T_drive − T_brake sat(ω / 0.5 rad/s) − R F_x`` [rad/s²]."""
    drive, brake = max(torque, 0.0), max(-torque, 0.0)
    brake_sign = min(max(omega / BRAKE_SIGN_SMOOTHING_RADPS, -1.0), 1.0)
    return (drive - brake * brake_sign - p.wheel_radius_m * axle.fx_n) / p.wheel_inertia_kgm2


def plant_derivative(
    x: np.ndarray,
    command: ActuatorCommand | np.ndarray,
    mu_front: float,
    mu_rear: float,
    params: VehicleParams,
    surface_tires: SurfaceTireTable | None = None,
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
    surface_tires
        ``None``: the vehicle's tire on every surface. A table: each axle's tire follows the μ
        under it (:func:`~mufusion.vehicle.surface_tires.tire_for_surface`).

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
    check_mu(mu_front, mu_rear)
    state = state_vector(x)
    cmd = _command_tuple(command, params)
    front, rear = axle_outputs(
        state, state.omega_front_radps, state.omega_rear_radps, mu_front, mu_rear, params,
        tire_for_surface(mu_front, params.tire, surface_tires),
        tire_for_surface(mu_rear, params.tire, surface_tires),
    )
    rates = _chassis_rates(
        state, front, rear, cmd, params,
        omega_front_rate=_smoothed_wheel_rate(
            state.omega_front_radps, state.torque_front_nm, front, params
        ),
        omega_rear_rate=_smoothed_wheel_rate(
            state.omega_rear_radps, state.torque_rear_nm, rear, params
        ),
    )
    return np.asarray(rates)


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
    surface_tires
        ``None`` (default): the vehicle's tire on every surface, its stiffness independent of μ.
        A table (e.g. :data:`~mufusion.vehicle.surface_tires.AUTHORS_TIRES`): each axle's tire
        follows the true μ under that axle at every step, wherever that axle's forces are
        evaluated (the RK4 stages, the implicit wheel step's tangent stiffness, the output).
    kernel
        ``"auto"`` (default): the compiled kernel where the install built it, else the Python
        one; ``"compiled"`` or ``"python"`` to choose (same results, bit for bit).
    slip_control
        ``None`` (default): the torque commands reach the wheels as they are. Settings: a
        :class:`~mufusion.vehicle.slip_control.WheelSlipController` (ABS, TCS) modulates them
        at every step, as on a production vehicle; its status is in ``PlantOutput.slip_control``.
    stability_control
        ``None`` (default): no yaw stability control. Settings: a
        :class:`~mufusion.vehicle.stability_control.YawStabilityController` (ESC) brakes one
        front wheel when the vehicle rotates faster than it should (``stability_control_active_s``).

    Raises
    ------
    ValueError
        If ``dt_s`` is not in (0, 1/200], ``x0`` has the wrong shape or ``kernel`` is unknown
        (or ``"compiled"`` where it was not built).

    Notes
    -----
    The step's arithmetic runs in :mod:`mufusion.vehicle.plant_kernel` (or its compiled twin,
    :func:`~mufusion.vehicle.plant_kernel.make_kernel`), which reads the vehicle's constants and
    ``dt_s`` once, here.

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> plant = Plant(CAR, initial_state(CAR, 0.0, 0.0, 0.0, 10.0))
    >>> out = plant.step(ActuatorCommand(0.0, 0.0, 0.0), 0.8, 0.8)
    >>> round(out.time_s, 3), round(float(out.x[PlantState.X]), 3), out.front.utilization
    (0.005, 0.05, 0.0)
    """

    def __init__(
        self,
        params: VehicleParams,
        x0: np.ndarray,
        dt_s: float = DEFAULT_DT_S,
        surface_tires: SurfaceTireTable | None = None,
        kernel: str = "auto",
        slip_control: SlipControlSettings | None = None,
        stability_control: StabilityControlSettings | None = None,
    ) -> None:
        if not (0.0 < dt_s <= DEFAULT_DT_S + 1e-12):
            raise ValueError(f"dt_s must be in (0, {DEFAULT_DT_S}] s, got {dt_s!r}")
        if surface_tires is not None and not isinstance(surface_tires, SurfaceTireTable):
            raise ValueError(
                f"surface_tires must be a SurfaceTireTable or None, got {type(surface_tires)!r}"
            )
        self.params = params
        self.surface_tires = surface_tires
        self.dt_s = float(dt_s)
        self._x = state_vector(x0)
        self.time_s = 0.0
        self._kernel = make_kernel(params, self.dt_s, kernel)
        if slip_control is not None and not isinstance(slip_control, SlipControlSettings):
            raise ValueError(
                f"slip_control must be SlipControlSettings or None, got {type(slip_control)!r}"
            )
        self._slip_control = None if slip_control is None else WheelSlipController(
            params, slip_control, self.dt_s, float(self._x.vx_mps)
        )
        if stability_control is not None and not isinstance(
                stability_control, StabilityControlSettings):
            raise ValueError("stability_control must be StabilityControlSettings or None, "
                             f"got {type(stability_control)!r}")
        self._esc = None if stability_control is None else YawStabilityController(
            params, stability_control)
        self._accel_x_mps2 = 0.0  # the last step's longitudinal acceleration (the IMU's)
        self._accel_y_mps2 = 0.0  # and lateral
        # (μ_f, μ_r, tire_f, tire_r, axles) of the latest output, reused by the next step's
        # first stage.
        self._last_axles: (
            tuple[float, float, TireParams, TireParams, tuple[AxleFloats, AxleFloats]] | None
        ) = None

    @property
    def x(self) -> np.ndarray:
        """Current state, shape ``(11,)`` (a copy), indexed by :class:`PlantState`."""
        return np.asarray(self._x)

    @property
    def state(self) -> PlantStateVector:
        """Current state as named floats."""
        return self._x

    @property
    def stability_control_active_s(self) -> float:
        """How long the yaw stability control has acted so far [s] (0 without it)."""
        return 0.0 if self._esc is None else self._esc.active_s

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
        check_mu(mu_front, mu_rear)
        p = self.params
        cmd = _command_tuple(command, p)
        x0 = self._x
        omega_f0, omega_r0 = x0.omega_front_radps, x0.omega_rear_radps
        slip_status = None
        if self._slip_control is not None:
            cmd, slip_status = self._slip_control.modulate(
                cmd, omega_f0, omega_r0, self._accel_x_mps2, x0.torque_front_nm,
                x0.torque_rear_nm, self.time_s, x0.steer_rad, x0.yaw_rate_radps,
            )
        yaw_moment = force_x = 0.0
        if self._esc is not None:
            speed, slip = math.hypot(x0.vx_mps, x0.vy_mps), math.atan2(x0.vy_mps, x0.vx_mps)
            if self._esc.settings.drive_cut and (cmd[1] > 0.0 or cmd[2] > 0.0) and (
                    self._esc.cuts_drive(speed, x0.yaw_rate_radps, slip)):
                cmd = (cmd[0], min(cmd[1], 0.0), min(cmd[2], 0.0))
                self._esc.drive_cut_s += self.dt_s
            yaw_moment, force_x = self._esc.moment(
                speed, x0.yaw_rate_radps, x0.steer_rad, self._accel_y_mps2, mu_front, slip)
            if yaw_moment != 0.0:
                self._esc.active_s += self.dt_s
        kernel_cmd: tuple[float, ...] = (*cmd, yaw_moment, force_x, self._esc.front_lateral_share(
            force_x, mu_front)) if self._esc is not None and yaw_moment else cmd
        # The surface under each axle is held over the step (μ is too).
        tire_f = tire_for_surface(mu_front, p.tire, self.surface_tires)
        tire_r = tire_for_surface(mu_rear, p.tire, self.surface_tires)
        last = self._last_axles
        # The previous output evaluated the first stage's axles already if μ and the tires are
        # unchanged and both wheels spin forwards (the stage's wheel prediction
        # ω₀ + (u₀ − u₀)/R is then ω₀).
        first = None
        if last is not None and last[0] == mu_front and last[1] == mu_rear and (
            last[2] is tire_f and last[3] is tire_r
        ):
            first = last[4]
        values, axles, cos_d, sin_d = self._kernel.step(
            x0[:6] + x0[8:], omega_f0, omega_r0, kernel_cmd, mu_front, mu_rear, tire_f, tire_r,
            first,
        )
        x1 = PlantStateVector._make(values)
        self._x = x1
        self.time_s += self.dt_s
        self._last_axles = (
            (mu_front, mu_rear, tire_f, tire_r, axles)
            if x1.omega_front_radps > 0.0 and x1.omega_rear_radps > 0.0 else None
        )
        front, rear = AxleOutput(*axles[0], mu_front), AxleOutput(*axles[1], mu_rear)
        m = p.mass_kg
        accel_x = (front.fx_n * cos_d - front.fy_n * sin_d + rear.fx_n + force_x) / m
        accel_y = (front.fx_n * sin_d + front.fy_n * cos_d + rear.fy_n) / m
        self._accel_x_mps2, self._accel_y_mps2 = accel_x, accel_y
        return PlantOutput(
            x=np.asarray(x1),
            time_s=self.time_s,
            front=front,
            rear=rear,
            accel_x_mps2=accel_x,
            accel_y_mps2=accel_y,
            slip_control=slip_status,
            esc_yaw_moment_nm=yaw_moment,
        )
