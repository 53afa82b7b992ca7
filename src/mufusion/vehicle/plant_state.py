"""The plant's state, by name: array indices for numpy callers, a typed record for the plant itself.

Two views of the same eleven numbers, declared in the same order (a test checks they agree):

* :class:`PlantState` — integer indices into a numpy state array (``x[PlantState.VX]``), used by the
  simulator and the tests, and as the layout of :func:`~mufusion.vehicle.plant.plant_derivative`'s
  result;
* :class:`PlantStateVector` — a named tuple of plain floats with units in the field names
  (``x.vx_mps``), used inside the plant's integrator, where numpy's per-call overhead and enum
  look-ups would dominate the step time.
"""

from __future__ import annotations

import math
from enum import IntEnum
from typing import Any, NamedTuple

import numpy as np

from mufusion.vehicle.params import VehicleParams


class PlantState(IntEnum):
    """Indices of the plant state vector (SI units, radians)."""

    X = 0  # CoG position, east [m]
    Y = 1  # CoG position, north [m]
    PSI = 2  # yaw angle [rad], counter-clockwise from X
    VX = 3  # longitudinal body velocity [m/s]
    VY = 4  # lateral body velocity [m/s], left positive
    YAW_RATE = 5  # [rad/s]
    OMEGA_FRONT = 6  # front wheel spin [rad/s]
    OMEGA_REAR = 7  # rear wheel spin [rad/s]
    STEER = 8  # front road-wheel angle [rad]
    TORQUE_FRONT = 9  # applied front wheel torque [N m], braking negative
    TORQUE_REAR = 10  # applied rear wheel torque [N m]


N_PLANT_STATES = len(PlantState)


class PlantStateVector(NamedTuple):
    """The plant state as named floats, in :class:`PlantState` order.

    Time derivatives use the same record (each field then holds the rate of that quantity, e.g.
    ``vx_mps`` in m/s²), so an integrator can combine states and rates field by field.
    """

    x_m: float
    y_m: float
    psi_rad: float
    vx_mps: float
    vy_mps: float
    yaw_rate_radps: float
    omega_front_radps: float
    omega_rear_radps: float
    steer_rad: float
    torque_front_nm: float
    torque_rear_nm: float


def validate_state(x: Any) -> np.ndarray:
    """``x`` as a float array of shape ``(11,)``; ``ValueError`` naming ``x`` otherwise."""
    arr = np.asarray(x, dtype=float)
    if arr.shape != (N_PLANT_STATES,):
        raise ValueError(f"x must have shape ({N_PLANT_STATES},), got {arr.shape}")
    return arr


def state_vector(x: Any) -> PlantStateVector:
    """A validated numpy (or sequence) state as a :class:`PlantStateVector`.

    Raises
    ------
    ValueError
        If ``x`` does not have shape ``(11,)``.
    """
    return PlantStateVector._make(validate_state(x).tolist())


def initial_state(
    params: VehicleParams, X: float, Y: float, psi: float, speed_mps: float
) -> np.ndarray:
    """A plant state driving straight at ``speed_mps`` with free-rolling wheels.

    Parameters
    ----------
    params
        Vehicle parameters (wheel radius).
    X, Y
        Position of the centre of gravity [m].
    psi
        Yaw angle [rad].
    speed_mps
        Forward speed [m/s], ≥ 0.

    Returns
    -------
    np.ndarray
        Shape ``(11,)``, indexed by :class:`PlantState`.

    Raises
    ------
    ValueError
        If ``speed_mps`` is negative or not finite.

    Examples
    --------
    >>> from mufusion.vehicle.params import CAR
    >>> x = initial_state(CAR, 0.0, 0.0, 0.0, 10.0)
    >>> float(x[PlantState.VX]), round(float(x[PlantState.OMEGA_FRONT] * CAR.wheel_radius_m), 9)
    (10.0, 10.0)
    """
    if not (math.isfinite(speed_mps) and speed_mps >= 0.0):
        raise ValueError(f"speed_mps must be finite and >= 0, got {speed_mps!r}")
    x = np.zeros(N_PLANT_STATES)
    x[PlantState.X], x[PlantState.Y], x[PlantState.PSI] = X, Y, psi
    x[PlantState.VX] = speed_mps
    x[PlantState.OMEGA_FRONT] = x[PlantState.OMEGA_REAR] = speed_mps / params.wheel_radius_m
    return x


def axle_positions(x: np.ndarray, params: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """Cartesian positions of the front and rear axle centres [m].

    Parameters
    ----------
    x
        Plant state(s), shape ``(11, ...)``.
    params
        Vehicle parameters (axle distances from the CoG).

    Returns
    -------
    front_xy, rear_xy
        Each of shape ``(2, ...)``.
    """
    arr = np.asarray(x, dtype=float)
    heading = np.stack([np.cos(arr[PlantState.PSI]), np.sin(arr[PlantState.PSI])])
    cog = np.stack([arr[PlantState.X], arr[PlantState.Y]])
    return cog + params.cog_to_front_axle_m * heading, cog - params.cog_to_rear_axle_m * heading
