"""The vehicle's own sensor signals, read off the simulated plant."""

from __future__ import annotations

from mufusion.estimators import VehicleSignals
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.plant import PlantOutput, PlantState


def vehicle_signals(t_s: float, out: PlantOutput, params: VehicleParams) -> VehicleSignals:
    """What the wheel-speed sensors, the IMU, the steering-angle sensor and the drive train
    report after a plant step ending at ``t_s`` [s] (ideal sensors: no noise, no delay)."""
    x = out.x
    return VehicleSignals(
        t_s=float(t_s),
        speed_x_mps=float(x[PlantState.VX]),
        speed_y_mps=float(x[PlantState.VY]),
        wheel_speed_front_radps=float(x[PlantState.OMEGA_FRONT]),
        wheel_speed_rear_radps=float(x[PlantState.OMEGA_REAR]),
        accel_x_mps2=float(out.accel_x_mps2),
        accel_y_mps2=float(out.accel_y_mps2),
        yaw_rate_radps=float(x[PlantState.YAW_RATE]),
        steer_rad=float(x[PlantState.STEER]),
        torque_front_nm=float(x[PlantState.TORQUE_FRONT]),
        torque_rear_nm=float(x[PlantState.TORQUE_REAR]),
        wheel_radius_m=float(params.wheel_radius_m),
        utilization_front=float(out.utilization_front),
        utilization_rear=float(out.utilization_rear),
    )
