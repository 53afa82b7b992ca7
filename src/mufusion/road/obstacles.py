"""Obstacles: road-aligned rectangles at (s, d) that may pop up when the ego vehicle arrives.

Geometry is evaluated in the Cartesian plane: an obstacle is the rectangle centred at the
Cartesian image of its ``(s, d)``, aligned with the path heading there; the ego footprint is the
oriented rectangle of the vehicle pose. Clearance is their exact signed distance
(:func:`~mufusion.road.geometry.signed_clearance_m`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mufusion.road.geometry import rectangle_corners, signed_clearance_m
from mufusion.road.path import ReferencePath


@dataclass(frozen=True)
class Obstacle:
    """A rectangular obstacle, its trigger and its constant speed along the path.

    Attributes
    ----------
    s_m, d_m
        Centre in Frenet coordinates [m].
    length_m, width_m
        Size along and across the road [m], > 0.
    appear_at_ego_s_m
        The obstacle appears once the ego progress reaches this value [m] (None: no such trigger).
    appear_at_time_s
        The obstacle appears at this time [s] (None: no such trigger). Without any trigger it is
        present from the start; with both, whichever comes first.
    speed_mps
        Constant speed along the reference path [m/s]: positive moves with the ego vehicle's
        direction of travel, negative towards it (oncoming); 0 (the default) is static. ``s_m``
        is the centre's progress at time 0 (:meth:`s_at_time`).
    """

    s_m: float
    d_m: float
    length_m: float = 1.0
    width_m: float = 1.0
    appear_at_ego_s_m: float | None = None
    appear_at_time_s: float | None = None
    speed_mps: float = 0.0

    def __post_init__(self) -> None:
        for name in ("s_m", "d_m", "speed_mps"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"Obstacle.{name} must be finite, got {getattr(self, name)!r}")
        for name in ("length_m", "width_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"Obstacle.{name} must be finite and > 0, got {value!r}")

    @property
    def moving(self) -> bool:
        """Whether the obstacle moves (``speed_mps != 0``)."""
        return self.speed_mps != 0.0

    def s_at_time(self, time_s: float) -> float:
        """The centre's progress along the path at ``time_s`` [s] [m].

        Examples
        --------
        >>> Obstacle(100.0, 3.5, speed_mps=-10.0).s_at_time(2.0)
        80.0
        """
        return self.s_m + self.speed_mps * time_s

    @classmethod
    def pop_up(
        cls, s_m: float, d_m: float, distance_ahead_m: float, length_m: float = 1.0,
        width_m: float = 1.0,
    ) -> Obstacle:
        """The paper's pop-up obstacle: appears when the ego is ``distance_ahead_m`` before it."""
        return cls(s_m, d_m, length_m, width_m, appear_at_ego_s_m=s_m - distance_ahead_m)


def obstacle_active(
    obstacle: Obstacle, ego_s_m: np.ndarray | float, time_s: np.ndarray | float
) -> np.ndarray:
    """Whether ``obstacle`` is present for ego progress ``ego_s_m`` [m] at ``time_s`` [s].

    Examples
    --------
    >>> obstacle_active(Obstacle.pop_up(100.0, 0.0, 20.0), np.array([70.0, 80.0]), 0.0).tolist()
    [False, True]
    """
    s, t = np.broadcast_arrays(np.asarray(ego_s_m, float), np.asarray(time_s, float))
    if obstacle.appear_at_ego_s_m is None and obstacle.appear_at_time_s is None:
        return np.ones(s.shape, dtype=bool)
    active = np.zeros(s.shape, dtype=bool)
    if obstacle.appear_at_ego_s_m is not None:
        active |= s >= obstacle.appear_at_ego_s_m
    if obstacle.appear_at_time_s is not None:
        active |= t >= obstacle.appear_at_time_s
    return active


def obstacle_active_at(obstacle: Obstacle, ego_s_m: float, time_s: float) -> bool:
    """:func:`obstacle_active` for one ego progress [m] and time [s], in plain floats.

    The same comparisons (NaN compares false) without numpy's per-call cost: the closed loop
    asks at every controller tick.

    Examples
    --------
    >>> obstacle_active_at(Obstacle.pop_up(100.0, 0.0, 20.0), 80.0, 0.0)
    True
    """
    if obstacle.appear_at_ego_s_m is None and obstacle.appear_at_time_s is None:
        return True
    return bool(
        (obstacle.appear_at_ego_s_m is not None and ego_s_m >= obstacle.appear_at_ego_s_m)
        or (obstacle.appear_at_time_s is not None and time_s >= obstacle.appear_at_time_s)
    )


def obstacle_corners(obstacle: Obstacle, path: ReferencePath, time_s: float = 0.0) -> np.ndarray:
    """Cartesian corners of the obstacle where it is at ``time_s`` [s], shape ``(4, 2)``.

    A moving obstacle's centre is at :meth:`Obstacle.s_at_time`; a static one's is ``s_m`` at
    any time (``s_m + 0·t`` is ``s_m`` exactly).
    """
    x, y, heading = path.to_cartesian(obstacle.s_at_time(time_s), obstacle.d_m, 0.0)
    return rectangle_corners(x, y, heading, obstacle.length_m, obstacle.width_m)


def footprint_clearance_m(
    obstacle: Obstacle,
    path: ReferencePath,
    x_m: np.ndarray | float,
    y_m: np.ndarray | float,
    heading_rad: np.ndarray | float,
    length_m: float,
    width_m: float,
    time_s: float = 0.0,
) -> np.ndarray:
    """Signed clearance [m] between ego footprints (Cartesian poses) and the obstacle.

    Parameters
    ----------
    obstacle, path
        The obstacle and the path that places it.
    x_m, y_m, heading_rad
        Footprint centre [m] and heading [rad]; broadcast to a batch shape ``B``.
    length_m, width_m
        Footprint size [m].
    time_s
        The instant [s]: a moving obstacle is where it is then (:meth:`Obstacle.s_at_time`).

    Returns
    -------
    ndarray
        Shape ``B``: > 0 distance when apart, < 0 minus the penetration depth when colliding.
    """
    ego = rectangle_corners(x_m, y_m, heading_rad, length_m, width_m)
    return signed_clearance_m(ego, obstacle_corners(obstacle, path, time_s))
