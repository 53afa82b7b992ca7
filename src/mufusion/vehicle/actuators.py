"""Actuator commands: produced by the controller, obeyed by the plant."""

from __future__ import annotations

from dataclasses import dataclass

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
        # min/max on plain floats: the same values as np.clip (NaN passes through), without
        # numpy's per-call overhead (this runs at the plant's and the controller's rates).
        return ActuatorCommand(*clip_command(
            self.steer_rad, self.torque_front_nm, self.torque_rear_nm, params
        ))


def clip_command(
    steer_rad: float, torque_front_nm: float, torque_rear_nm: float, params: VehicleParams
) -> tuple[float, float, float]:
    """``(steer, front torque, rear torque)`` limited to the actuators' ranges, as floats.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> clip_command(0.0, 500.0, -1e9, TRUCK) == (0.0, 0.0, -TRUCK.max_brake_torque_rear_nm)
    True
    """
    steer_max = params.max_steer_rad
    return (
        _clip(float(steer_rad), -steer_max, steer_max),
        _clip(float(torque_front_nm), -params.max_brake_torque_front_nm, 0.0),
        _clip(float(torque_rear_nm), -params.max_brake_torque_rear_nm,
              params.max_drive_torque_nm),
    )


def _clip(value: float, low: float, high: float) -> float:
    # As np.clip(value, low, high) for low <= high, NaN included (max/min keep their first
    # argument when a comparison with NaN is false).
    return min(max(value, low), high)
