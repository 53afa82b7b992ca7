"""What one plant step reports: :class:`PlantOutput` (state, axles, IMU, slip control)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.vehicle.axles import AxleOutput
from mufusion.vehicle.plant_state import PlantState
from mufusion.vehicle.slip_control import SlipControlStatus

__all__ = ["PlantOutput"]


@dataclass(frozen=True)
class PlantOutput:
    """Everything the controller, the estimators and the metrics may read after one plant step.

    ``front`` / ``rear`` hold each axle's forces in its wheel frame, normal load, slips,
    utilisations and the μ used (:class:`~mufusion.vehicle.axles.AxleOutput`). Accelerations are
    in the body frame [m/s²] and exclude the velocity-rotation terms (what an IMU would measure).
    Axle positions: :func:`~mufusion.vehicle.plant_state.axle_positions` of ``x``.
    """

    x: np.ndarray
    time_s: float
    front: AxleOutput
    rear: AxleOutput
    accel_x_mps2: float
    accel_y_mps2: float
    slip_control: SlipControlStatus | None = None
    """What the wheel-slip controller (ABS, TCS) did in this step; ``None`` without one."""
    esc_yaw_moment_nm: float = 0.0
    """The yaw moment the stability control (ESC) applied in this step [N m] (0: passive or
    without ESC)."""

    @property
    def speed_mps(self) -> float:
        """Speed of the centre of gravity [m/s]."""
        return math.hypot(self.x[PlantState.VX], self.x[PlantState.VY])

    @property
    def front_lateral_force_n(self) -> float:
        """Lateral force of the front axle in the body frame [N]: ``F_x sin δ + F_y cos δ``.

        The planner's ``F_yf`` (its body-frame front force), as a force observer would supply it.
        """
        steer = float(self.x[PlantState.STEER])
        return self.front.fx_n * math.sin(steer) + self.front.fy_n * math.cos(steer)

    @property
    def utilization_front(self) -> float:
        """Realised utilisation of the front axle, ``front.utilization``."""
        return self.front.utilization

    @property
    def utilization_rear(self) -> float:
        """Realised utilisation of the rear axle, ``rear.utilization``."""
        return self.rear.utilization
