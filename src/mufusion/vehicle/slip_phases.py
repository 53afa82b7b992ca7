"""One axle's ABS/TCS phase machine (:class:`AxlePhaseMachine`) and its thresholds
(:class:`SlipControlSettings`), apart from the controller that reads the wheels
(:mod:`mufusion.vehicle.slip_control`, whose docstring describes the phases)."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import IntEnum


class SlipPhase(IntEnum):
    """Phase of one axle's slip controller (see the module docstring)."""

    PASS = 0
    RELEASE = 1
    HOLD = 2
    REAPPLY = 3


@dataclass(frozen=True)
class SlipControlSettings:
    """ABS and TCS switches and thresholds (slips as ratios, accelerations in m/s²).

    Attributes
    ----------
    abs_enabled, tcs_enabled
        Anti-lock braking and traction control on (the default, as on every production vehicle)
        or off (to show what they do).
    onset_slip
        Slip beyond which a wheel decelerating faster than the body (by
        ``wheel_accel_margin_mps2``) is taken to be locking [-], in (0, 0.5).
    release_slip
        Slip beyond which the brake is released whatever the wheel's acceleration [-], in
        (onset_slip, 1).
    wheel_accel_margin_mps2
        How much faster than the body a wheel's circumference must decelerate (brake) or
        accelerate (drive) to count as running away [m/s²], > 0.
    recovered_slip
        Slip below which a released wheel has spun up again [-], in (0, onset_slip].
    max_hold_s
        Longest hold before the torque builds up again [s], > 0.
    reapply_fraction
        Share of the torque at which the wheel began to lock that the build-up starts from
        (or the held torque, if higher) [-], in (0, 1].
    reapply_time_s
        Time in which the torque then builds by the torque at which the wheel began to lock
        [s], > 0; it keeps rising at that rate until the command is reached or the wheel runs
        away again.
    min_speed_mps
        Below this reference speed the controller passes the command through (the brakes hold a
        stopped vehicle) [m/s], ≥ 0.
    reference_decel_margin_mps2
        How much faster than the IMU's deceleration the reference speed may fall while braking,
        to follow wheels that decelerate within their grip [m/s²], > 0 (the IMU misses the
        curve's ``ψ̇ v_y``; a locking wheel decelerates many times faster).
    rise_recognition
        End a cycle's build-up when the road returns more than the most it had returned before
        the wheel last ran away, by ``rise_margin`` of that (a friction rise: built up at the
        low friction's rate the brake would take a second to reach what the new road holds,
        "sail-on"; docs/decisions/0118). The road's
        torque is the applied one less what turns the wheel, ``T − I ω̇`` (brake pressure and
        wheel-speed signal). ``False``: the build-up keeps its rate up to the command.
    rise_margin
        Share by which the road's torque must exceed that most [-], > 0 (on one road it cannot
        exceed the force peak the wheel went through but by the load's changes).
    """

    abs_enabled: bool = True
    tcs_enabled: bool = True
    onset_slip: float = 0.12
    release_slip: float = 0.25
    wheel_accel_margin_mps2: float = 10.0
    recovered_slip: float = 0.05
    max_hold_s: float = 0.3
    reapply_fraction: float = 0.7
    reapply_time_s: float = 0.3
    min_speed_mps: float = 2.0
    reference_decel_margin_mps2: float = 2.0
    rise_recognition: bool = True
    rise_margin: float = 0.2

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.type in (bool, "bool"):
                if not isinstance(value, bool):
                    raise ValueError(f"{f.name} must be true or false, got {value!r}")
            elif isinstance(value, bool) or not (
                isinstance(value, (int, float)) and math.isfinite(value)
            ):
                raise ValueError(f"{f.name} must be a finite number, got {value!r}")
        if not 0.0 < self.onset_slip < 0.5:
            raise ValueError(f"onset_slip must be in (0, 0.5), got {self.onset_slip!r}")
        if not self.onset_slip < self.release_slip < 1.0:
            raise ValueError(
                f"release_slip must be in (onset_slip = {self.onset_slip}, 1), "
                f"got {self.release_slip!r}")
        if not 0.0 < self.recovered_slip <= self.onset_slip:
            raise ValueError(
                f"recovered_slip must be in (0, onset_slip = {self.onset_slip}], "
                f"got {self.recovered_slip!r}")
        if not 0.0 < self.reapply_fraction <= 1.0:
            raise ValueError(
                f"reapply_fraction must be in (0, 1], got {self.reapply_fraction!r}")
        for name in ("wheel_accel_margin_mps2", "max_hold_s", "reapply_time_s",
                     "reference_decel_margin_mps2", "rise_margin"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)!r}")
        if not self.min_speed_mps >= 0.0:
            raise ValueError(f"min_speed_mps must be >= 0 m/s, got {self.min_speed_mps!r}")



class AxlePhaseMachine:
    """One axle's phase machine on torque magnitudes (brake or drive, signs taken off): the four
    phases of :mod:`mufusion.vehicle.slip_control`'s docstring."""

    __slots__ = ("cycles", "grip", "held", "lock", "phase", "run_up", "settings", "since")

    def __init__(self, settings: SlipControlSettings) -> None:
        self.settings = settings
        self.phase = SlipPhase.PASS
        self.lock = 0.0  # torque at which the wheel began to run away [N m]
        self.held = 0.0  # torque the current hold or reapply starts from [N m]
        self.since = 0.0  # when the current phase began [s]
        self.cycles = 0
        # The road's largest torque since the command began in this direction (the peak the
        # wheel went through before it first ran away, and any since) [N m].
        self.run_up = 0.0
        self.grip = 0.0  # that torque when the wheel last ran away [N m]

    def reset(self) -> None:
        self.phase = SlipPhase.PASS
        self.run_up = 0.0

    def step(self, t: float, asked: float, applied: float, excess: float, runaway: float,
             road: float = 0.0) -> float:
        """Torque magnitude to command [N m].

        ``asked``: the command's magnitude; ``applied``: the actuator's torque magnitude now;
        ``excess``: the slip in the command's direction (braking: −λ); ``runaway``: how much
        faster than the body the wheel's circumference moves in that direction [m/s²];
        ``road``: the torque the road returns in that direction, ``T − I ω̇`` [N m].
        """
        cfg = self.settings
        phase = self.phase
        if phase is not SlipPhase.RELEASE and road > self.run_up:
            self.run_up = road
        if phase is SlipPhase.RELEASE:
            # Dump until the wheel clearly spins up again (or its slip has recovered already).
            if runaway < -cfg.wheel_accel_margin_mps2 or excess < cfg.recovered_slip:
                self.phase, self.since, self.held = SlipPhase.HOLD, t, applied
                return min(applied, asked)
            return 0.0
        if phase is SlipPhase.HOLD:
            if excess > cfg.release_slip and runaway > 0.0:
                return self._release(t, applied)  # it locks again while held
            if excess < cfg.recovered_slip or t - self.since >= cfg.max_hold_s:
                self.phase, self.since = SlipPhase.REAPPLY, t
            return min(self.held, asked)
        if excess > cfg.release_slip or (
            excess > cfg.onset_slip and runaway > cfg.wheel_accel_margin_mps2
        ):
            return self._release(t, applied)
        if phase is SlipPhase.PASS:
            return asked
        if cfg.rise_recognition and road > (1.0 + cfg.rise_margin) * self.grip:
            # On one road the wheel cannot take more than the peak it went through before it ran
            # away (but by its load's changes): the road now grips more, a friction rise. Built
            # up at the low friction's rate the torque would take a second to reach what the new
            # road holds.
            self.phase = SlipPhase.PASS
            return asked
        # Straight back to a share of the torque that locked the wheel (the peak lies below it,
        # not far), then slowly on towards and past it.
        start = max(self.held, cfg.reapply_fraction * self.lock)
        cap = start + (t - self.since) * self.lock / cfg.reapply_time_s
        if cap >= asked:
            self.phase = SlipPhase.PASS
            return asked
        return cap

    def _release(self, t: float, applied: float) -> float:
        """A new cycle: remember the torque that was too much, and dump it."""
        self.phase, self.since, self.cycles = SlipPhase.RELEASE, t, self.cycles + 1
        self.lock = max(applied, 1e-3)
        self.grip = self.run_up
        return 0.0
