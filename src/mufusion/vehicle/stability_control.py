"""Yaw stability control (ESC) in the vehicle: a yaw moment from braking one front wheel.

Production ESC compares the measured yaw rate with the one the driver's steering asks for and,
when the vehicle turns faster (oversteer), brakes the outer front wheel: the braking force acts
half a track off the centre line and turns the vehicle back (van Zanten, "Bosch ESP systems: 5
years of experience", SAE 2000-01-1633; Rajamani, *Vehicle Dynamics and Control*, ch. 8). The
plant is single-track, so the braking appears as it does in single-track ESC models: a direct yaw
moment ``M_z`` about the centre of gravity and the longitudinal force ``|M_z| / (t/2)`` of the
braked wheel. That wheel can deliver at most its friction, ``μ F_z,wheel`` (its ABS keeps it near
the peak), which bounds the moment, and it gives up lateral force for it, on the friction
ellipse: half of the front axle's lateral force scales with ``√(1 − r²)``, ``r = F_x / μ
F_z,wheel`` (at the bound that wheel steers no more; docs/decisions/0117).

Two yaw rates explain a vehicle's rotation: the single-track steady state for the measured
steering angle and speed, ``v δ / L`` (both presets' tires have the same stiffness per unit load
front and rear, so the understeer gradient is zero), and the rate at which the velocity vector
turns, ``a_y / v`` (in cornering ``ψ̇ = a_y / v − β̇``: a yaw rate beyond it is the body slip
growing, the vehicle rotating rather than cornering). Oversteer is a yaw rate beyond both (each
counted in the direction of the rotation); the controller acts when that excess passes a
deadband, with the moment that would remove it within ``response_time_s``:
``M_z = −sign(ψ̇) I_z · excess / τ``, bounded as above. Acting on the steering's rate alone
braked trucks that corner with little steering at speed (docs/decisions/0061). With the rear
swung out beyond the body-slip deadband it also bounds the body slip, as production ESC does
(van Zanten): the rotation is then explained by ``a_y / v`` alone, less the rate that returns
the slip to the deadband in ``body_slip_return_s`` (docs/decisions/0115). It reads the
vehicle's own signals only (yaw-rate sensor, steering angle, wheel-speed/IMU speed and lateral
acceleration); the bound is the physics of the braked wheel, not something the controller knows.

On by default in scenarios (``sim.esc``; docs/decisions/0082), as in production vehicles;
docs/decisions/0061 measured it first on the general grid's failures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

from mufusion.vehicle.params import VehicleParams

GRAVITY_MPS2 = 9.81


@dataclass(frozen=True)
class StabilityControlSettings:
    """ESC thresholds (SI units).

    Attributes
    ----------
    yaw_rate_deadband_radps
        Excess of the yaw rate over what explains it before the controller acts [rad/s], ≥ 0
        (production activation thresholds are a few degrees per second).
    response_time_s
        Time in which the moment would remove the excess [s], > 0 (a brake's build-up time).
    min_speed_mps
        Below this speed the controller is passive [m/s], ≥ 0.
    body_slip_deadband_rad
        Body slip against the rotation (the rear swung out) below which the controller is
        passive [rad], ≥ 0: production ESC keeps out of normal cornering, where a yaw-rate
        excess alone is a steering transient (docs/decisions/0082).
    """

    yaw_rate_deadband_radps: float = 0.05
    body_slip_deadband_rad: float = 0.05
    response_time_s: float = 0.2
    min_speed_mps: float = 3.0
    body_slip_return_s: float | None = 0.5
    """With the rear swung out beyond ``body_slip_deadband_rad``: the time [s], > 0, in which
    the moment would also return the body slip to that deadband. The rotation is then explained
    by the velocity's turning ``a_y / v`` alone, less the rate that returns the slip; the
    steering's rate no longer counts (a driver steering into a slide does not make it stable)
    and the yaw-rate deadband does not apply (the body-slip deadband gates the controller, and
    the moment grows from zero at it). Production ESC bounds the body slip as well as the yaw
    rate (van Zanten, SAE 2000-01-1633); docs/decisions/0115. ``None``: the rule before (the
    larger of the two rates, beyond the yaw-rate deadband)."""
    braked_wheel_lateral_loss: bool = True
    """The braked wheel gives up lateral force for the braking force it delivers: its lateral
    force scales with the friction ellipse, ``√(1 − (F_x / μ F_z,wheel)²)``, so the front axle
    keeps ``(1 + √(1 − r²)) / 2`` of its lateral force at ``r = F_x / μ F_z,wheel``
    (:meth:`YawStabilityController.front_lateral_share`; docs/decisions/0117). ``False``: the
    braking force comes on top of the axle's tire forces, as before 0117."""
    drive_cut: bool = False
    """Also withhold drive torque while the body slip points against the rotation beyond
    ``body_slip_deadband_rad`` (the rear swung out): production ESC's engine intervention
    (docs/decisions/0092)."""

    def __post_init__(self) -> None:
        for name in ("drive_cut", "braked_wheel_lateral_loss"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name} must be true or false, got {getattr(self, name)!r}")
        if self.body_slip_return_s is not None and not (
                isinstance(self.body_slip_return_s, (int, float))
                and not isinstance(self.body_slip_return_s, bool)
                and math.isfinite(self.body_slip_return_s) and self.body_slip_return_s > 0.0):
            raise ValueError("body_slip_return_s must be a finite number > 0 s or None, got "
                             f"{self.body_slip_return_s!r}")
        for f in fields(self):
            if f.name in ("drive_cut", "braked_wheel_lateral_loss", "body_slip_return_s"):
                continue
            value = getattr(self, f.name)
            if isinstance(value, bool) or not (
                isinstance(value, (int, float)) and math.isfinite(value) and value >= 0.0
            ):
                raise ValueError(f"{f.name} must be a finite number >= 0, got {value!r}")
        if not self.response_time_s > 0.0:
            raise ValueError(f"response_time_s must be > 0 s, got {self.response_time_s!r}")


class YawStabilityController:
    """The ESC of one vehicle (see the module docstring).

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> esc = YawStabilityController(TRUCK, StabilityControlSettings())
    >>> esc.moment(15.0, 0.2, 3.4 * 0.2 / 15.0, 3.0, 0.9, 0.0)  # turning as the steering asks
    (0.0, 0.0)
    >>> mz, fx = esc.moment(15.0, -0.6, -0.09, -6.0, 0.9, 0.1)  # a right turn, the rear out
    >>> mz > 0.0 > fx
    True
    """

    def __init__(self, params: VehicleParams, settings: StabilityControlSettings) -> None:
        self.params, self.settings = params, settings
        wheelbase = params.cog_to_front_axle_m + params.cog_to_rear_axle_m
        self._wheelbase_m = wheelbase
        self._half_track_m = 0.5 * params.track_width_m
        # Static load on one front wheel [N].
        self._front_wheel_load_n = (
            0.5 * params.mass_kg * GRAVITY_MPS2 * params.cog_to_rear_axle_m / wheelbase)
        self.active_s = 0.0
        """How long the controller has acted so far [s] (summed over the steps it acted in)."""
        self.drive_cut_s = 0.0
        """How long it has withheld drive torque so far [s] (``drive_cut``)."""

    def cuts_drive(self, speed_mps: float, yaw_rate_radps: float, body_slip_rad: float) -> bool:
        """Whether the rear is swung out so that ``drive_cut`` withholds drive torque for the coming
        plant step (the caller checks ``settings.drive_cut``)."""
        cfg = self.settings
        return (speed_mps > cfg.min_speed_mps
                and -body_slip_rad * math.copysign(1.0, yaw_rate_radps)
                > cfg.body_slip_deadband_rad)

    def front_lateral_share(self, force_x_n: float, mu_front: float) -> float:
        """The share of the front axle's lateral force left while one front wheel brakes with
        ``force_x_n`` [N] on friction ``mu_front``: ``(1 + √(1 − r²)) / 2`` with ``r = |F_x| /
        μ F_z,wheel`` (at most 1, the moment's bound), 1 with ``braked_wheel_lateral_loss``
        off. The other front wheel keeps its half; the braked one's lateral force scales on the
        friction ellipse.

        >>> from mufusion.vehicle.params import CAR
        >>> esc = YawStabilityController(CAR, StabilityControlSettings())
        >>> esc.front_lateral_share(0.0, 0.8), esc.front_lateral_share(-1e9, 0.8)
        (1.0, 0.5)
        """
        if not self.settings.braked_wheel_lateral_loss:
            return 1.0
        r = min(abs(force_x_n) / (mu_front * self._front_wheel_load_n), 1.0)
        return 0.5 * (1.0 + math.sqrt(1.0 - r * r))

    def moment(
        self, speed_mps: float, yaw_rate_radps: float, steer_rad: float, accel_y_mps2: float,
        mu_front: float, body_slip_rad: float,
    ) -> tuple[float, float]:
        """``(yaw_moment_nm, force_x_n)`` for the coming plant step (zeros when passive).

        ``mu_front`` is the road's friction under the front wheels: it bounds what the braked
        wheel delivers (the plant's physics, not a signal the controller reads).
        ``body_slip_rad`` is the estimated body slip ``atan(v_y / v_x)`` (production ESC
        estimates it from the same sensors); the controller acts only while it points against
        the rotation by more than ``body_slip_deadband_rad``.
        """
        cfg = self.settings
        if not speed_mps > cfg.min_speed_mps:
            return 0.0, 0.0
        swung_out = -body_slip_rad * math.copysign(1.0, yaw_rate_radps)
        if not swung_out > cfg.body_slip_deadband_rad:
            return 0.0, 0.0
        # Each rate explains the rotation only in its direction.
        cornering = accel_y_mps2 / speed_mps
        turning = abs(cornering) if cornering * yaw_rate_radps > 0.0 else 0.0
        if cfg.body_slip_return_s is None:
            steering = speed_mps * steer_rad / self._wheelbase_m
            steered = abs(steering) if steering * yaw_rate_radps > 0.0 else 0.0
            explained, deadband = max(steered, turning), cfg.yaw_rate_deadband_radps
        else:
            # The rear is out: a rotation beyond the velocity's turning grows the body slip,
            # whatever the steering asks, and the slip beyond the deadband is to be returned.
            returning = (swung_out - cfg.body_slip_deadband_rad) / cfg.body_slip_return_s
            explained, deadband = turning - returning, 0.0
        excess = abs(yaw_rate_radps) - explained
        if not excess > deadband:
            return 0.0, 0.0
        moment = -math.copysign(
            self.params.yaw_inertia_kgm2 * excess / cfg.response_time_s, yaw_rate_radps)
        cap = mu_front * self._front_wheel_load_n * self._half_track_m
        moment = min(max(moment, -cap), cap)
        return moment, -abs(moment) / self._half_track_m
