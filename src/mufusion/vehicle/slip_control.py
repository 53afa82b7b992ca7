"""Wheel-slip control between the controller's torque commands and the wheels: ABS and TCS.

Every production car and truck brakes and drives through a wheel-slip controller: a wheel whose
brake torque exceeds what the road returns locks, and a locked wheel has no lateral grip. This
module is that controller, part of the vehicle (it runs inside
:class:`~mufusion.vehicle.plant.Plant` at the plant's rate, 200 Hz, a wheel-speed sample every
5 ms as on production units) and blind to the road: it reads the wheel-speed signal, the
longitudinal IMU acceleration and the torque the actuator applies, never μ.

The scheme is the classical rule-based one (Bosch's ABS; Savaresi & Tanelli, *Active Braking
Control Systems Design for Vehicles*, ch. 2; Rajamani, *Vehicle Dynamics and Control*, ch. 14),
per axle, in four phases:

``PASS``
    The command goes through. Incipient lock is detected when the wheel's slip against the
    reference speed passes ``release_slip``, or passes ``onset_slip`` while the wheel decelerates
    faster than the body by ``wheel_accel_margin_mps2`` (past the force peak the wheel runs away
    towards lock; before it, the slip settles).
``RELEASE``
    The brake torque is dumped (commanded to zero; the actuator's lag sets how fast it falls)
    until the wheel clearly re-accelerates relative to the body (by ``wheel_accel_margin_mps2``)
    or its slip is back within ``recovered_slip``.
``HOLD``
    The torque reached is held while the wheel spins up, until its slip is back within
    ``recovered_slip`` (or ``max_hold_s`` has passed); a slip beyond ``release_slip`` that still
    grows starts a new release.
``REAPPLY``
    The torque jumps back to ``reapply_fraction`` of the torque at which the wheel began to lock
    (or stays at the held one, if higher) and builds up by that torque every ``reapply_time_s``;
    the cycle ends when the command is reached (back to ``PASS``), or when the road returns more
    than its peak before the wheel ran away (a friction rise, ``rise_recognition``), or a new
    one starts when the wheel runs away again.

Traction control is the same machine on drive torque with the signs mirrored (a spinning wheel
instead of a locking one). The reference speed is the front wheel's while nothing brakes (neither
preset drives its front axle, so it rolls freely). While braking it is the fastest wheel that no
drive torque turns, falling no faster than the IMU's deceleration plus
``reference_decel_margin_mps2`` (the usual estimate on a rear-driven vehicle: a wheel that runs
away towards lock falls far faster than that and leaves the reference behind; a driven wheel may
spin, and as its own reference it would hide the spin from traction control). The margin
matters: the IMU measures ``a_x = v̇_x − ψ̇ v_y``, and in a curve with body slip the term
``ψ̇ v_y`` (up to ``a_y β``, above 1 m/s² in a drift) makes the integrated IMU decelerate slower
than the vehicle. An estimate that may only fall with the IMU then drifts
above the wheels while they brake within their grip, reads their slip as a lock and dumps a brake
torque the road could take (docs/decisions/0080).

The phases and thresholds act on the vehicle's own signals only, so a run whose wheels never come
near their force peak is unchanged by the controller (bit for bit: it passes the command through).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.slip_phases import AxlePhaseMachine

# Importers of this module keep the settings' and the phases' names.
from mufusion.vehicle.slip_phases import SlipControlSettings as SlipControlSettings
from mufusion.vehicle.slip_phases import SlipPhase as SlipPhase


@dataclass(frozen=True)
class AxleSlipStatus:
    """What one axle's slip controller did in the step just taken.

    ``phase`` is its phase after the step; ``torque_removed_nm`` ≥ 0 how much torque it withheld
    from the command (brake or drive) [N m]; ``slip`` the slip it measured against
    ``SlipControlStatus.reference_speed_mps`` [-].
    """

    phase: SlipPhase
    torque_removed_nm: float
    slip: float

    @property
    def active(self) -> bool:
        """Whether the controller modulates this axle's torque (any phase but ``PASS``)."""
        return self.phase is not SlipPhase.PASS


@dataclass(frozen=True)
class SlipControlStatus:
    """Both axles' slip controllers after one plant step, and the cycles they have run so far."""

    front: AxleSlipStatus
    rear: AxleSlipStatus
    reference_speed_mps: float
    cycles_front: int
    cycles_rear: int


PASSIVE_AXLE = AxleSlipStatus(SlipPhase.PASS, 0.0, 0.0)

_MIN_STEER_COS = 0.2
FREE_WHEEL_TORQUE_NM = 1.0
"""Below this brake torque [N m] a released wheel rolls freely (the actuator's lag takes a dumped
torque of hundreds of N m there in about five time constants; a locked wheel has spun up long
before): if it neither spins up nor slows against the body, it rolls at the vehicle's speed."""
"""Floor of cos δ when the front wheel's speed is read as the body's (δ ≤ 1.37 rad; no preset
steers beyond 1.07)."""


class WheelSlipController:
    """ABS and TCS for one vehicle, stepped once per plant step (see the module docstring).

    Parameters
    ----------
    params
        Vehicle parameters (wheel radius).
    settings
        Switches and thresholds.
    dt_s
        The plant's step [s], > 0 (the wheel-speed sampling period).
    initial_speed_mps
        Reference speed before the first step [m/s] (the vehicle's initial speed).

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> abs_ = WheelSlipController(CAR, SlipControlSettings(), 0.005, 15.0)
    >>> free = 15.0 / CAR.wheel_radius_m
    >>> cmd, status = abs_.modulate((0.0, -800.0, -500.0), free, free, 0.0, -800.0, -500.0, 0.0)
    >>> cmd, status.front.active
    ((0.0, -800.0, -500.0), False)
    """

    def __init__(
        self,
        params: VehicleParams,
        settings: SlipControlSettings,
        dt_s: float,
        initial_speed_mps: float,
    ) -> None:
        if not (math.isfinite(dt_s) and dt_s > 0.0):
            raise ValueError(f"dt_s must be > 0 s, got {dt_s!r}")
        self.params, self.settings, self.dt_s = params, settings, float(dt_s)
        self.reference_speed_mps = max(float(initial_speed_mps), 0.0)
        self._time_s = 0.0
        self._previous_wheel_mps: tuple[float, float] | None = None
        self._front = AxlePhaseMachine(settings)
        self._rear = AxlePhaseMachine(settings)

    def modulate(
        self,
        command: tuple[float, float, float],
        omega_front_radps: float,
        omega_rear_radps: float,
        accel_x_mps2: float,
        torque_front_nm: float,
        torque_rear_nm: float,
        time_s: float,
        steer_rad: float = 0.0,
        yaw_rate_radps: float = 0.0,
    ) -> tuple[tuple[float, float, float], SlipControlStatus]:
        """The command the wheels get in the coming plant step, and what was done to it.

        Parameters
        ----------
        command
            ``(steer_rad, torque_front_nm, torque_rear_nm)`` from the controller, clipped.
        omega_front_radps, omega_rear_radps
            Wheel speeds now (the wheel-speed sensors).
        accel_x_mps2
            Longitudinal body acceleration of the last step (the IMU) [m/s²].
        torque_front_nm, torque_rear_nm
            Torques the actuators apply now [N m] (brake pressure, drive torque).
        time_s
            The plant's clock [s].
        steer_rad, yaw_rate_radps
            The front wheels' steering angle and the yaw rate (the steering-angle sensor and
            the gyro every ESC unit has) [rad], [rad/s].
        """
        radius, dt, cfg = self.params.wheel_radius_m, self.dt_s, self.settings
        steer, asked_f, asked_r = command
        # The steered front wheel rolls along its own plane, at v_x cos δ + (v_y + l_f ψ̇) sin δ:
        # read as the body's speed (v_y unknown, taken as 0). Uncorrected, a wheel at full lock
        # in a skid rolls at half the body's speed, reads as locked, and its brake was dumped
        # and never reapplied (the torque "that locked it" was none; docs/decisions/0111).
        wheel_f = ((radius * omega_front_radps
                    - self.params.cog_to_front_axle_m * yaw_rate_radps * math.sin(steer_rad))
                   / max(math.cos(steer_rad), _MIN_STEER_COS))
        wheel_r = radius * omega_rear_radps
        braking = asked_f < 0.0 or asked_r < 0.0 or torque_front_nm < 0.0 or torque_rear_nm < 0.0
        if braking:
            # While a wheel is modulated no wheel need roll at the vehicle's speed: the IMU
            # alone carries the reference through the cycle (its drift over one is small).
            controlled = (self._front.phase is not SlipPhase.PASS
                          or self._rear.phase is not SlipPhase.PASS)
            margin = 0.0 if controlled else cfg.reference_decel_margin_mps2
            floor = self.reference_speed_mps + (accel_x_mps2 - margin) * dt
            # Only a wheel that no drive torque turns witnesses the vehicle's speed: the plans
            # may brake the front while they drive the rear (or a brake's lag leaves a tail),
            # and a spinning rear wheel taken as the reference reads no slip of its own, so
            # traction control let it run away (docs/decisions/0110).
            # A released wheel whose brake torque is gone and that no longer spins up rolls at
            # the vehicle's speed: it alone is the reference then, below the IMU's too. In a
            # slide the IMU misses ψ̇ v_y (0.6 m/s² at 0.3 rad/s and 2 m/s of side slip), the
            # reference drifted above the wheels and read their free rolling as a lock, and the
            # release never ended: the brakes stayed dumped for seconds. Nor may a braked wheel
            # raise it: a steered front wheel, read in its plane without the unknown v_y, reads
            # v_x + v_y tan δ, 1.7 m/s fast in a counter-steered slide (docs/decisions/0114).
            free = self._free_wheels_mps(wheel_f, wheel_r, accel_x_mps2, torque_front_nm,
                                         torque_rear_nm)
            reference = max(free) if free else floor
            if not free:
                if wheel_f > reference and asked_f <= 0.0 and torque_front_nm <= 0.0:
                    reference = wheel_f
                if wheel_r > reference and asked_r <= 0.0 and torque_rear_nm <= 0.0:
                    reference = wheel_r
        else:
            reference = wheel_f  # the undriven front wheel rolls freely
        self.reference_speed_mps = reference
        previous = self._previous_wheel_mps
        self._previous_wheel_mps = (wheel_f, wheel_r)
        if previous is None or reference < cfg.min_speed_mps:
            self._front.reset()
            self._rear.reset()
            return command, self._status(PASSIVE_AXLE, PASSIVE_AXLE)
        denominator = max(reference, 1.0)
        inertia_per_radius = self.params.wheel_inertia_kgm2 / radius
        out = []
        statuses = []
        for machine, asked, applied, wheel, before in (
            (self._front, asked_f, torque_front_nm, wheel_f, previous[0]),
            (self._rear, asked_r, torque_rear_nm, wheel_r, previous[1]),
        ):
            slip = (wheel - reference) / denominator
            wheel_accel = (wheel - before) / dt
            relative_accel = wheel_accel - accel_x_mps2
            # The torque the road returns: the applied one less what turns the wheel, I ω̇.
            road = applied - inertia_per_radius * wheel_accel
            if asked < 0.0 and cfg.abs_enabled:
                magnitude = machine.step(time_s, -asked, max(-applied, 0.0), -slip,
                                         -relative_accel, -road)
                torque = -magnitude
            elif asked > 0.0 and cfg.tcs_enabled:
                magnitude = machine.step(time_s, asked, max(applied, 0.0), slip, relative_accel,
                                         road)
                torque = magnitude
            else:
                machine.reset()
                torque = asked
            out.append(torque)
            statuses.append(AxleSlipStatus(machine.phase, abs(asked - torque), slip))
        return (steer, out[0], out[1]), self._status(statuses[0], statuses[1])

    def _free_wheels_mps(self, wheel_f: float, wheel_r: float, accel_x_mps2: float,
                         torque_front_nm: float, torque_rear_nm: float) -> list[float]:
        """Speeds of the released wheels that roll freely: in ``RELEASE``, their torque below
        :data:`FREE_WHEEL_TORQUE_NM`, accelerating as the body does (within the margin)."""
        previous = self._previous_wheel_mps
        if previous is None or (self._front.phase is not SlipPhase.RELEASE
                                and self._rear.phase is not SlipPhase.RELEASE):
            return []  # the common case, at the plant's rate: nothing released
        margin = self.settings.wheel_accel_margin_mps2
        return [
            wheel for machine, wheel, before, torque in (
                (self._front, wheel_f, previous[0], torque_front_nm),
                (self._rear, wheel_r, previous[1], torque_rear_nm))
            if machine.phase is SlipPhase.RELEASE and abs(torque) < FREE_WHEEL_TORQUE_NM
            and abs((wheel - before) / self.dt_s - accel_x_mps2) < margin
        ]

    def _status(self, front: AxleSlipStatus, rear: AxleSlipStatus) -> SlipControlStatus:
        return SlipControlStatus(front, rear, self.reference_speed_mps, self._front.cycles,
                                 self._rear.cycles)
