"""Actuator commands: produced by the controller, obeyed by the plant."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mufusion.vehicle.params import VehicleParams


@dataclass(frozen=True)
class ActuatorCommand:
    """What the controller asks of the vehicle.

    Attributes
    ----------
    steer_rad
        Front road-wheel steering angle [rad], left positive.
    torque_front_nm, torque_rear_nm
        Net wheel torque per axle [N m]: drive positive, braking negative. The truck drives the
        rear axle only, so a positive front torque is clipped to zero.
    """

    steer_rad: float
    torque_front_nm: float
    torque_rear_nm: float

    def clipped(self, params: VehicleParams) -> ActuatorCommand:
        """The same command limited to the actuators' ranges (never beyond what they can do)."""
        return ActuatorCommand(
            steer_rad=float(np.clip(self.steer_rad, -params.max_steer_rad, params.max_steer_rad)),
            torque_front_nm=float(
                np.clip(self.torque_front_nm, -params.max_brake_torque_front_nm, 0.0)
            ),
            torque_rear_nm=float(
                np.clip(
                    self.torque_rear_nm,
                    -params.max_brake_torque_rear_nm,
                    params.max_drive_torque_nm,
                )
            ),
        )
