"""Straight-line braking of a point mass after a dead time: the stopping distance and its inverse.

One home for ``d = v·t_dead + v² / (2a)``: the planner's stop-or-evade decision
(:mod:`mufusion.planner.passing`) and the feasibility oracle (:mod:`mufusion.scenarios.feasibility`)
both read it from here.
"""

from __future__ import annotations

import math


def stopping_distance_m(speed_mps: float, decel_mps2: float, dead_time_s: float) -> float:
    """Distance [m] to stop from ``speed_mps``: ``v t_dead + v² / (2 a)``.

    Raises
    ------
    ValueError
        If the speed is negative, the deceleration not positive or the dead time negative.

    Examples
    --------
    >>> round(stopping_distance_m(14.0, 7.0, 0.25), 2)
    17.5
    """
    if not (math.isfinite(speed_mps) and speed_mps >= 0.0):
        raise ValueError(f"speed_mps must be finite and >= 0, got {speed_mps!r}")
    if not (math.isfinite(decel_mps2) and decel_mps2 > 0.0):
        raise ValueError(f"decel_mps2 must be finite and > 0, got {decel_mps2!r}")
    if not (math.isfinite(dead_time_s) and dead_time_s >= 0.0):
        raise ValueError(f"dead_time_s must be finite and >= 0, got {dead_time_s!r}")
    return speed_mps * dead_time_s + 0.5 * speed_mps**2 / decel_mps2


def braking_limited_speed_mps(distance_m: float, decel_mps2: float, dead_time_s: float) -> float:
    """Highest speed from which a stop fits in ``distance_m``: ``v²/(2a) + v·t = D`` solved for v.

    Examples
    --------
    >>> round(braking_limited_speed_mps(20.0, 5.0, 0.0), 6)  # √(2·5·20)
    14.142136
    """
    if distance_m <= 0.0:
        return 0.0
    t = dead_time_s
    return decel_mps2 * (-t + math.sqrt(t * t + 2.0 * distance_m / decel_mps2))
