"""One axle's ABS/TCS phase machine (:class:`AxlePhaseMachine`), apart from the controller that
reads the wheels (:mod:`mufusion.vehicle.slip_control`, whose docstring describes the phases)."""

from __future__ import annotations

from enum import IntEnum
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mufusion.vehicle.slip_control import SlipControlSettings


class SlipPhase(IntEnum):
    """Phase of one axle's slip controller (see the module docstring)."""

    PASS = 0
    RELEASE = 1
    HOLD = 2
    REAPPLY = 3


class AxlePhaseMachine:
    """One axle's phase machine on torque magnitudes (brake or drive, signs taken off): the four
    phases of :mod:`mufusion.vehicle.slip_control`'s docstring."""

    __slots__ = ("cycles", "held", "lock", "phase", "settings", "since")

    def __init__(self, settings: SlipControlSettings) -> None:
        self.settings = settings
        self.phase = SlipPhase.PASS
        self.lock = 0.0  # torque at which the wheel began to run away [N m]
        self.held = 0.0  # torque the current hold or reapply starts from [N m]
        self.since = 0.0  # when the current phase began [s]
        self.cycles = 0

    def reset(self) -> None:
        self.phase = SlipPhase.PASS

    def step(self, t: float, asked: float, applied: float, excess: float, runaway: float) -> float:
        """Torque magnitude to command [N m].

        ``asked``: the command's magnitude; ``applied``: the actuator's torque magnitude now;
        ``excess``: the slip in the command's direction (braking: −λ); ``runaway``: how much
        faster than the body the wheel's circumference moves in that direction [m/s²].
        """
        cfg = self.settings
        phase = self.phase
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
        return 0.0
