"""Backend-independent description of the traction-adaptive OCP (Svensson & Törngren, Sec. II).

Small factories assemble the pieces: per-stage parameters (curvature, rear stiffness, polygon
radii), friction polygons, actuator bounds on the longitudinal forces, the lateral corridor from
lanes and obstacles, and the cost weights.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from typing import Literal

import numpy as np

from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import (
    Input,
    State,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
)


class Param(IntEnum):
    """Per-stage parameter vector ``p``."""

    curvature = 0
    rear_stiffness = 1
    radius_front = 2
    radius_rear = 3


N_PARAMS = len(Param)


@dataclass(frozen=True)
class CostWeights:
    """Least-squares weights (acados multiplies them by dt)."""

    speed: float = 1.0
    lateral_offset: float = 1.0
    heading_error: float = 1.0
    yaw_rate: float = 1.0
    lateral_speed: float = 1.0
    force_per_kn: float = 1e-4
    emergency_speed: float = 10.0
    evade_speed: float = 0.05
    slack_l1: float = 1e4
    slack_l2: float = 1e4


@dataclass(frozen=True)
class PlannerObstacle:
    """An obstacle in road coordinates: centre ``(s_m, d_m)``, extent ``length_m × width_m``."""

    s_m: float
    d_m: float
    length_m: float
    width_m: float


@dataclass(frozen=True)
class PlannerConfig:
    """Planner configuration; checked on construction."""

    horizon_steps: int = 40
    dt_s: float = 0.1
    utilization_factor: float = 0.9
    polygon_sides: int = 12
    weights: CostWeights = field(default_factory=CostWeights)
    backend: Literal["acados", "casadi"] = "acados"
    use_sampling: bool = True
    # Bounds on the reference point's lateral offset [m]: a 3.5 m lane minus half a truck width.
    lane_d_min_m: float = -0.45
    lane_d_max_m: float = 0.45
    obstacle_margin_m: float = 0.5
    min_speed_mps: float = 0.5
    cold_start_iterations: int = 3
    max_cruise_accel_mps2: float = 1.5
    # Track min(cruise speed, the point mass's highest speed along the lane centre) instead of the
    # cruise speed alone (planner/speed_profile.py).
    curve_speed_reference: bool = True

    def __post_init__(self) -> None:
        if not 5 <= self.horizon_steps <= 200:
            raise ValueError(f"horizon_steps must be in [5, 200], got {self.horizon_steps}")
        if not 0.0 < self.dt_s <= 0.5:
            raise ValueError(f"dt_s must be in (0, 0.5] s, got {self.dt_s}")
        if not 0.0 < self.utilization_factor <= 1.0:
            raise ValueError(
                f"utilization_factor must be in (0, 1], got {self.utilization_factor}"
            )
        if self.polygon_sides < 12:
            raise ValueError(f"polygon_sides must be >= 12, got {self.polygon_sides}")
        if self.backend not in ("acados", "casadi"):
            raise ValueError(f"backend must be 'acados' or 'casadi', got {self.backend!r}")
        if not 0.0 < self.max_cruise_accel_mps2 <= 10.0:
            raise ValueError(
                f"max_cruise_accel_mps2 must be in (0, 10] m/s², got {self.max_cruise_accel_mps2}"
            )
        if not 1 <= self.cold_start_iterations <= 20:
            raise ValueError(
                f"cold_start_iterations must be in [1, 20], got {self.cold_start_iterations}"
            )
        if self.lane_d_min_m >= self.lane_d_max_m:
            raise ValueError("lane_d_min_m must be below lane_d_max_m")


def longitudinal_force_bounds_n(params: VehicleParams) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on ``(F_xf, F_xr)`` [N] from the actuators: the front axle only brakes (the
    :class:`~mufusion.vehicle.actuators.ActuatorCommand` clips front drive torque), the rear
    drives and brakes. Inputs, so they are hard."""
    r = params.wheel_radius_m
    lower = np.array([-params.max_brake_torque_front_nm / r, -params.max_brake_torque_rear_nm / r])
    upper = np.array([0.0, params.max_drive_torque_nm / r])
    return lower, upper


def polygon_directions(n_sides: int) -> tuple[np.ndarray, float]:
    """Outward normals ``(n, 2)`` over ``(F_x, F_y)`` and the inscribed-radius ratio ``cos(π/n)``.

    A regular n-gon inscribed in the circle of radius R is ``{f : n_j · f ≤ R cos(π/n)}``.
    """
    theta = 2.0 * np.pi * np.arange(n_sides) / n_sides
    return np.stack([np.cos(theta), np.sin(theta)], axis=1), float(np.cos(np.pi / n_sides))


def stage_parameters(
    guess_states: np.ndarray,
    guess_inputs: np.ndarray,
    curvature_of_s,
    mu_hat_of_s,
    params: VehicleParams,
    utilization_factor: float,
) -> dict[str, np.ndarray]:
    """Per-stage parameters from the initial guess (predicted ``s_k`` and ``a_x,k``).

    Returns arrays of length N: ``mu_hat``, ``fzf``, ``fzr``, ``radius_front``, ``radius_rear``,
    ``rear_stiffness``, ``curvature`` and the stacked ``p`` of shape ``(N, N_PARAMS)``.
    """
    s_k = guess_states[:-1, State.s]
    ax = (guess_inputs[:, Input.fxf] + guess_inputs[:, Input.fxr]) / params.mass_kg
    fzf, fzr = normal_loads_n(ax, params)
    fzf = np.maximum(fzf, 0.05 * params.mass_kg * 9.81)
    fzr = np.maximum(fzr, 0.05 * params.mass_kg * 9.81)
    mu = np.clip(np.asarray(mu_hat_of_s(s_k), dtype=float), 0.05, 2.0)
    kappa = np.asarray(curvature_of_s(s_k), dtype=float) * np.ones_like(s_k)
    c_r = rear_cornering_stiffness_n_per_rad(params, fzr, utilization_factor)
    radius_front = utilization_factor * mu * fzf
    radius_rear = utilization_factor * mu * fzr
    p = np.zeros((s_k.size, N_PARAMS))
    p[:, Param.curvature] = kappa
    p[:, Param.rear_stiffness] = c_r
    p[:, Param.radius_front] = radius_front
    p[:, Param.radius_rear] = radius_rear
    return {
        "mu_hat": mu, "fzf": fzf, "fzr": fzr, "radius_front": radius_front,
        "radius_rear": radius_rear, "rear_stiffness": c_r, "curvature": kappa, "p": p,
    }


MAX_SWING_HEADING_RAD = 0.1
"""Largest heading error whose corner swing :func:`lateral_corridor` takes off the lane bounds."""


def lateral_corridor(
    guess_states: np.ndarray,
    obstacles: Sequence[PlannerObstacle],
    lane_d_min_m: float,
    lane_d_max_m: float,
    params: VehicleParams,
    margin_m: float,
    curvature_1pm: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the reference point's ``d`` per stage 1..N, shape ``(N,)`` each.

    ``lane_d_min_m``/``lane_d_max_m`` bound the reference point itself (the caller has already
    shrunk the lane or road edges by half the vehicle width, TAMP framework). On a curve of
    curvature κ (``curvature_1pm`` at the stages' predicted positions) the body's ends, aligned
    with the lane at its middle, stick out of the curve by ``|κ| (l/2)² / 2``; that much is taken
    off the outer bound (right of a left curve, left of a right curve). A heading error Δψ (the
    guess's, as RTI linearises there) swings the front corners by ``a_f sin Δψ`` and the rear ones
    by ``a_r sin Δψ`` the other way (``a_f``, ``a_r``: CoG to the body's front and rear); the
    bounds shrink by that too. An obstacle
    overlapping the vehicle's footprint at the guess's predicted ``s_k`` closes the side opposite
    to the guess's ``d_k`` (pass left if the guess is left of the obstacle's centre), which keeps
    the problem convex.
    """
    s_k = guess_states[1:, State.s]
    d_k = guess_states[1:, State.d]
    half_w = 0.5 * params.width_m
    lo = np.full(s_k.shape, float(lane_d_min_m))
    hi = np.full(s_k.shape, float(lane_d_max_m))
    half_len = 0.5 * params.length_m
    if curvature_1pm is not None:
        kappa = np.asarray(curvature_1pm, dtype=float) * np.ones_like(s_k)
        bulge = 0.5 * np.abs(kappa) * half_len**2
        hi = np.where(kappa < 0.0, hi - bulge, hi)
        lo = np.where(kappa > 0.0, lo + bulge, lo)
    shift = 0.5 * (params.cog_to_front_axle_m - params.cog_to_rear_axle_m)
    a_front, a_rear = half_len + shift, half_len - shift
    # Only lane-keeping headings count in full: in an evasive manoeuvre the heading reaches
    # 0.3-0.5 rad and the full swing (> 1 m each side) would close the corridor the manoeuvre
    # needs; the obstacle margin covers the corners there.
    sin_dpsi = np.sin(np.clip(guess_states[1:, State.dpsi], -MAX_SWING_HEADING_RAD,
                              MAX_SWING_HEADING_RAD))
    hi = hi - a_front * np.maximum(sin_dpsi, 0.0) - a_rear * np.maximum(-sin_dpsi, 0.0)
    lo = lo + a_front * np.maximum(-sin_dpsi, 0.0) + a_rear * np.maximum(sin_dpsi, 0.0)
    # A corridor too tight for the vehicle leaves its midpoint rather than an empty interval.
    mid = 0.5 * (lo + hi)
    lo, hi = np.minimum(lo, mid), np.maximum(hi, mid)
    for ob in obstacles:
        overlap = np.abs(s_k - ob.s_m) < half_len + 0.5 * ob.length_m + margin_m
        clear = 0.5 * ob.width_m + half_w + margin_m
        left = d_k >= ob.d_m
        lo = np.where(overlap & left, np.maximum(lo, ob.d_m + clear), lo)
        hi = np.where(overlap & ~left, np.minimum(hi, ob.d_m - clear), hi)
    return lo, hi
