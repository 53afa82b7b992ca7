"""The plans' steady cornering attitude: the lateral speed and heading error that hold a curve.

The tracking reference asks each stage for ``v_y = 0`` and ``Δψ = 0``. In a steady curve neither
is zero for the plans' own single-track model (:mod:`mufusion.vehicle.planner_model`): the rear
tire carries its share of the lateral force only at a slip angle, and the body turns by it, its
nose into the curve at speed, so that the centre of gravity still moves along the lane. A
reference of zero prices that attitude, ``v_y² + Δψ²`` per stage, against the curve itself, so a
plan puts off the rotation the curve needs and makes it up later, at a larger heading
(docs/decisions/0113). :func:`steady_cornering_attitude` gives the attitude at which the model is
in equilibrium on the lane's centre line; the reference then prices the departure from it.
"""

from __future__ import annotations

import numpy as np

from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import MIN_SPEED_FOR_SLIP_MPS


def steady_cornering_attitude(
    curvature_1pm: np.ndarray,
    speed_mps: np.ndarray,
    rear_stiffness_n_per_rad: np.ndarray,
    params: VehicleParams,
) -> tuple[np.ndarray, np.ndarray]:
    """Lateral speed and heading error at which the plans' model holds a curve at a speed.

    With ``ψ̇ = κ v`` on the centre line, ``ψ̈ = 0`` and ``v̇_y = 0`` give the rear tire's share
    ``F_yr = m κ v² l_f / L``; the linear rear tire ``F_yr = C_r (l_r ψ̇ − v_y) / max(v, 1 m/s)``
    then gives ``v_y``, and ``ḋ = v sin Δψ + v_y cos Δψ = 0`` gives ``Δψ = −atan(v_y / v)``.
    At low speed the rear axle follows the path and ``v_y → l_r κ v`` (kinematic); as the speed
    grows the rear's slip angle turns ``v_y`` negative in a left curve and the nose points in.

    Parameters
    ----------
    curvature_1pm, speed_mps, rear_stiffness_n_per_rad
        Broadcastable arrays: the lane's curvature [1/m], the speed [m/s] (negative values are
        taken as 0) and the plans' rear cornering stiffness [N/rad], > 0.
    params
        Vehicle parameters (mass, axle distances).

    Returns
    -------
    lateral_speed_mps, heading_error_rad
        ``v_y`` and ``Δψ`` per element, the broadcast shape.

    Raises
    ------
    ValueError
        If a rear stiffness is not positive and finite, or a curvature or speed is not finite.

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> vy, dpsi = steady_cornering_attitude(np.array([0.01]), np.array([25.0]),
    ...                                      np.array([2e5]), TRUCK)
    >>> round(float(vy[0]), 3), round(float(dpsi[0]), 4)
    (-1.769, 0.0706)
    """
    kappa, v, c_r = np.broadcast_arrays(np.asarray(curvature_1pm, dtype=float),
                                        np.asarray(speed_mps, dtype=float),
                                        np.asarray(rear_stiffness_n_per_rad, dtype=float))
    if not (np.all(np.isfinite(c_r)) and np.all(c_r > 0.0)):
        raise ValueError("rear_stiffness_n_per_rad must be positive and finite")
    if not (np.all(np.isfinite(kappa)) and np.all(np.isfinite(v))):
        raise ValueError("curvature_1pm and speed_mps must be finite")
    v = np.maximum(v, 0.0)
    l_f, l_r = params.cog_to_front_axle_m, params.cog_to_rear_axle_m
    rear_force_n = params.mass_kg * kappa * v * v * l_f / params.wheelbase_m
    slip_angle_rad = rear_force_n / c_r
    lateral_speed = l_r * kappa * v - slip_angle_rad * np.maximum(v, MIN_SPEED_FOR_SLIP_MPS)
    return lateral_speed, -np.arctan2(lateral_speed, v)
