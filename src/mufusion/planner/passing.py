"""Passing or stopping: which side of an obstacle the corridor opens, and when to stop instead.

Two decisions the corridor of :func:`mufusion.planner.ocp.lateral_corridor` and the closed loop
take about an obstacle in the vehicle's path:

* **Side.** The corridor closes the side opposite to the initial guess (which keeps the problem
  convex). A side on which the vehicle's reference point cannot pass at all, because the
  obstacle's clearance bound lies beyond the road bound (an obstacle near the road's edge), is
  never the one to open: :func:`passing_left` opens the other side then, whatever the guess.
* **Stop or pass.** :func:`stopping_possible` says whether the vehicle can stop in front of the
  obstacle with the friction the planner may use; braking in lane is preferred to a swerve at the
  limit (into the opposing lane) whenever it is (the closed loop's ``brake_first``), and it is the
  only option when neither side has room (:func:`blocks_road`).
"""

from __future__ import annotations

import math

import numpy as np

from mufusion.vehicle.braking import stopping_distance_m
from mufusion.vehicle.params import GRAVITY_MPS2

__all__ = ["blocks_road", "in_path", "passing_left", "stopping_distance_m", "stopping_possible"]


def in_path(obstacle_s_m: float, obstacle_d_m: float, clearance_m: float, s_m: float,
            d_m: float) -> bool:
    """Whether an obstacle lies ahead in the vehicle's path.

    Ahead of the reference point (``obstacle_s_m > s_m``) and closer laterally than the
    clearance the vehicle needs to pass it (``|obstacle_d_m − d_m| < clearance_m``: half the
    obstacle's and the vehicle's widths plus the planner's margin).

    Examples
    --------
    >>> in_path(20.0, 1.5, 1.75, 0.0, 0.0), in_path(20.0, 1.5, 1.75, 0.0, -0.3)
    (True, False)
    """
    return obstacle_s_m > s_m and abs(obstacle_d_m - d_m) < clearance_m


def passing_left(
    guess_d_m: np.ndarray,
    obstacle_d_m: float,
    clearance_m: float,
    d_min_m: np.ndarray | float,
    d_max_m: np.ndarray | float,
) -> np.ndarray:
    """Whether the corridor passes the obstacle on its left, per stage.

    Parameters
    ----------
    guess_d_m
        The initial guess's lateral offsets at the stages [m].
    obstacle_d_m
        The obstacle centre's lateral offset [m].
    clearance_m
        Half the obstacle's width, half the vehicle's and the margin [m]: the reference point
        must stay this far from the obstacle's centre line.
    d_min_m, d_max_m
        Lane or road bounds of the reference point at the stages [m].

    Returns
    -------
    numpy.ndarray of bool
        Left where the guess is left of the obstacle's centre, unless only the other side has
        room (``obstacle_d_m ± clearance_m`` within the bounds).

    Examples
    --------
    >>> # Obstacle 1.5 m left of the centre, truck 2.6 m wide, 0.5 m margin, road −0.35…3.85 m:
    >>> passing_left(np.array([0.0]), 1.5, 2.3, -0.35, 3.85).tolist()
    [True]
    >>> passing_left(np.array([-0.1]), 0.0, 2.3, -5.0, 5.0).tolist()  # room both sides: the guess
    [False]
    """
    guess_left = np.asarray(guess_d_m, dtype=float) >= obstacle_d_m
    left_room = obstacle_d_m + clearance_m <= np.asarray(d_max_m, dtype=float)
    right_room = obstacle_d_m - clearance_m >= np.asarray(d_min_m, dtype=float)
    return np.where(left_room & ~right_room, True, np.where(right_room & ~left_room, False,
                                                            guess_left))


def blocks_road(obstacle_d_m: float, clearance_m: float, d_min_m: float, d_max_m: float) -> bool:
    """Whether neither side of the obstacle leaves the reference point room to pass.

    Examples
    --------
    >>> blocks_road(1.5, 2.3, -0.35, 3.85), blocks_road(1.75, 2.3, -0.35, 3.85)
    (False, True)
    """
    return obstacle_d_m + clearance_m > d_max_m and obstacle_d_m - clearance_m < d_min_m


def stopping_possible(
    *,
    speed_mps: float,
    gap_m: float,
    mu_hat: float,
    utilization_factor: float,
    polygon_sides: int,
    dead_time_s: float,
) -> bool:
    """Whether the vehicle stops within ``gap_m`` braking at what the planner may use.

    The deceleration is the friction polygon's inscribed share of the λ-circle,
    ``λ cos(π/n) μ̂ g`` (what the planner grants in pure braking); ``dead_time_s`` covers the
    brakes' lag and the time until the next plan acts (one planning period).

    Parameters
    ----------
    speed_mps
        Current speed [m/s], ≥ 0.
    gap_m
        From the vehicle's front to the obstacle's near face, less the margin to keep [m].
    mu_hat
        Friction estimate to brake on (the lowest between the vehicle and the obstacle) [-].
    utilization_factor, polygon_sides
        The planner's λ and polygon.
    dead_time_s
        Time before full braking [s].

    Examples
    --------
    >>> kw = dict(mu_hat=0.75, utilization_factor=0.9, polygon_sides=12, dead_time_s=0.25)
    >>> stopping_possible(speed_mps=14.0, gap_m=34.0, **kw)
    True
    >>> stopping_possible(speed_mps=24.0, gap_m=34.0, **kw)
    False
    """
    if not (math.isfinite(mu_hat) and mu_hat > 0.0):
        return False
    if gap_m <= 0.0:
        return False
    decel = utilization_factor * math.cos(math.pi / polygon_sides) * mu_hat * GRAVITY_MPS2
    return stopping_distance_m(max(speed_mps, 0.0), decel, dead_time_s) <= gap_m
