"""What a friction source receives: the vehicle's sensor signals, never the true friction.

A friction source (the paper's L, P, F, or one of your own) sees the road only through these
records. Once per planning step it gets a :class:`SensorFrame`: the camera's surface-class reports
along the road ahead (:class:`CameraReport`), the slip-based estimator's report under the vehicle
(:class:`~mufusion.estimators.local.LocalEstimate`), the peak tire utilisation of the interval and
the latest :class:`VehicleSignals`. After every plant step it may also get the
:class:`VehicleSignals` of that step (wheel speeds, IMU, steering angle, wheel torques, tire
utilisation). None of these records has a field for the true friction.

The truth is a separate channel, :class:`TrueFriction`, handed only to a source that declares
:attr:`Channel.TRUTH` among its channels (the ground-truth configuration GT and nothing else in
the package). What the emulated sensors report is produced by
:class:`~mufusion.estimators.sensor_model.SensorModel`, which reads the truth as a simulated
sensor does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from mufusion.estimators.local import LocalEstimate


class Channel(str, Enum):
    """A channel of what a friction source may read; a source declares the ones it reads.

    The slip estimator's report and the vehicle signals reach every source. Only a source that
    declares :attr:`TRUTH` is handed the true friction; the camera's reports reach a source that
    declares :attr:`CAMERA_CLASSES` or :attr:`CAMERA_MU`, and its μ reports (whose emulated errors
    draw from the run's random generator) only one that declares :attr:`CAMERA_MU`, so that the
    random draws of the other sensors do not depend on sources that never look.
    """

    CAMERA_CLASSES = "camera_classes"
    """The camera's surface class, its lowest μ and its margin at each distance ahead."""
    CAMERA_MU = "camera_mu"
    """The camera's μ report at each distance ahead (the class value, with its error model)."""
    TRUTH = "truth"
    """The true friction ahead: ground truth, not a sensor (GT only). In the closed loop it
    reaches as far as the planner looks, not just the camera's range (docs/decisions/0071)."""


SENSOR_CHANNELS: frozenset[Channel] = frozenset(set(Channel) - {Channel.TRUTH})
"""Every channel a vehicle's sensors deliver: what a source reads unless it declares otherwise."""


@dataclass(frozen=True)
class VehicleSignals:
    """The vehicle's own sensor signals at one instant (SI units; braking torques negative).

    Attributes
    ----------
    t_s
        Time the signals refer to [s].
    speed_x_mps, speed_y_mps
        Body-frame velocity [m/s] (as a speed-over-ground sensor reports it).
    wheel_speed_front_radps, wheel_speed_rear_radps
        Wheel spin of each axle [rad/s].
    accel_x_mps2, accel_y_mps2
        Body-frame accelerations as an IMU measures them [m/s²].
    yaw_rate_radps
        Yaw rate [rad/s].
    steer_rad
        Front road-wheel angle [rad].
    torque_front_nm, torque_rear_nm
        Wheel torque each axle applies [N m].
    wheel_radius_m
        Effective wheel radius [m] (for the wheel slip ``1 − v_x / (ω r)``).
    utilization_front, utilization_rear
        Realised tire-force utilisation ``hypot(F_x, F_y) / (μ F_z)`` of each axle [-], as the
        paper's emulated slip-based estimator uses it.
    """

    t_s: float
    speed_x_mps: float
    speed_y_mps: float
    wheel_speed_front_radps: float
    wheel_speed_rear_radps: float
    accel_x_mps2: float
    accel_y_mps2: float
    yaw_rate_radps: float
    steer_rad: float
    torque_front_nm: float
    torque_rear_nm: float
    wheel_radius_m: float
    utilization_front: float
    utilization_rear: float


@dataclass(frozen=True)
class CameraReport:
    """The camera's surface-class reports along the grid ahead; arrays read-only, shape (n,).

    Attributes
    ----------
    available
        False while the camera delivers nothing usable (dropped out, or its values were invalid
        and discarded); the arrays then hold no data.
    class_index
        Index of the reported class in the camera's class table; −1 where nothing is reported
        (beyond the camera's range, or the camera unavailable).
    mu_low
        Lowest μ of the reported class [-]; NaN where nothing is reported.
    margin
        95 % half-width of a report in that class [-]; NaN where nothing is reported.
    mu
        The camera's μ report [-] (NaN where nothing is reported); None unless the source
        declares :attr:`Channel.CAMERA_MU`.
    """

    available: bool
    class_index: np.ndarray
    mu_low: np.ndarray
    margin: np.ndarray
    mu: np.ndarray | None = None

    @property
    def in_range(self) -> np.ndarray:
        """Boolean mask of the grid points with a report."""
        return self.class_index >= 0


@dataclass(frozen=True)
class SensorFrame:
    """Everything a friction source reads at one planning step.

    Attributes
    ----------
    t_s
        Time of the planning step [s].
    s_ahead_m
        Distances ahead of the vehicle [m], read-only, strictly increasing from 0 (paper:
        0, 1, ..., 50 m); the estimate is wanted there.
    utilization_peak
        Peak realised tire utilisation over the last planning interval, both axles [-] (0 while
        the slip estimator is out).
    slip
        The slip-based estimator's report (held value with its error, margin, whether it
        measured this step).
    camera
        The camera's reports; None unless the source declares :attr:`Channel.CAMERA_CLASSES` or
        :attr:`Channel.CAMERA_MU`.
    signals
        The vehicle's signals after the latest plant step (None before the first step).
    s_ego_m
        The vehicle's progress along the road's map [m], from its localisation (what
        map-referenced data such as shared friction reports are placed against; NaN where the
        caller gives none).
    """

    t_s: float
    s_ahead_m: np.ndarray
    utilization_peak: float
    slip: LocalEstimate
    camera: CameraReport | None = None
    signals: VehicleSignals | None = None
    s_ego_m: float = math.nan


@dataclass(frozen=True)
class TrueFriction:
    """The true friction ahead: the ground-truth channel, handed only to a source declaring
    :attr:`Channel.TRUTH`.

    Attributes
    ----------
    s_ahead_m
        Distances ahead [m] (those of the frame), read-only.
    mu
        True μ there [-], read-only; ``mu[0]`` is under the vehicle.
    """

    s_ahead_m: np.ndarray
    mu: np.ndarray
