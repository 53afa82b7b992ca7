"""Pop-up obstacle feasibility: the braking and the evasion envelope of a point mass.

The obstacle appears ``D`` ahead of the vehicle's front (measured to the obstacle's centre, as
the scenario places it), so the front reaches its near face after ``D − l_obs/2``. *Braking*:
``v²/(2a) + v·t_brake ≤ D − l_obs/2`` with ``a = min(λ μ g, brake limit)``. *Evasion* at constant
speed: the lateral acceleration ``a_y`` (at most ``λ μ g``) changes no faster than the steering
turns at its rate limit (the angle per acceleration is the kinematic ``L / v²`` plus the front
slip ``k / g``), after the servo's lag, and the manoeuvre must stop its lateral motion before
the footprint leaves the road (a lane change, not a swerve off the road); the lateral shift when
the front reaches the obstacle must clear it by the margin. The variant is feasible if either
envelope is. Derivation: ``docs/feasibility.md``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from mufusion.scenarios.feasibility.common import (
    GRAVITY_MPS2,
    FeasibilityClass,
    classify_speed_margin,
    require_fraction,
    require_positive,
)
from mufusion.vehicle.braking import braking_limited_speed_mps, stopping_distance_m


@dataclass(frozen=True)
class BrakingEnvelope:
    """Stopping in front of the obstacle (distances [m], speeds [m/s], deceleration [m/s²])."""

    available_distance_m: float
    stopping_distance_m: float
    spare_distance_m: float
    deceleration_mps2: float
    max_speed_mps: float
    margin_mps: float
    feasibility_class: FeasibilityClass


@dataclass(frozen=True)
class EvasionEnvelope:
    """Steering around the obstacle on its better side.

    ``side`` is ``"none"`` when the obstacle does not reach into the vehicle's path (no shift
    needed) and the side with the larger speed margin otherwise; ``required_shift_m`` is the
    lateral shift of the vehicle's centre that clears the obstacle by the margin,
    ``achievable_shift_m`` what the point mass reaches by the time its front gets there.
    """

    side: Literal["left", "right", "none"]
    required_shift_m: float
    achievable_shift_m: float
    spare_shift_m: float
    time_to_obstacle_s: float
    steer_ramp_s: float
    lateral_accel_mps2: float
    max_speed_mps: float
    margin_mps: float
    feasibility_class: FeasibilityClass


@dataclass(frozen=True)
class PopupFeasibility:
    """Verdict on a pop-up variant: the better of the two envelopes."""

    feasibility_class: FeasibilityClass
    margin_mps: float
    speed_mps: float
    braking: BrakingEnvelope
    evasion: EvasionEnvelope


@dataclass(frozen=True)
class _Steering:
    wheelbase_m: float
    slip_rad_per_g: float
    rate_radps: float
    max_rad: float
    dead_time_s: float


def _shift_m(
    speed_mps: float, time_s: float, a_max: float, room_m: float, st: _Steering
) -> tuple[float, float, float]:
    """Lateral shift [m] after ``time_s``, the ramp time [s] and the plateau [m/s²].

    The lateral acceleration follows the fastest lane change that comes to rest laterally at
    ``room_m``: after the servo's lag it ramps at the steering's rate to the plateau ``a``, holds
    it for ``h``, ramps to ``−a`` (counter-steer), holds for ``h`` and ramps back to zero. Its peak
    shift is ``a (2 t_r + h)(t_r + h)`` with ``t_r = a / j``; ``h`` makes it equal ``room_m``. The
    plateau is the friction's (or the steering angle's) limit, lowered to ``(room j² / 2)^(1/3)``
    when even ``h = 0`` would overshoot the room. The shift at any time rises with the plateau
    and with ``h``, so more friction never shrinks it.
    """
    steer_per_accel = st.wheelbase_m / speed_mps**2 + st.slip_rad_per_g / GRAVITY_MPS2
    jerk = st.rate_radps / steer_per_accel
    a = min(a_max, st.max_rad / steer_per_accel, (0.5 * room_m * jerk * jerk) ** (1.0 / 3.0))
    ramp = a / jerk
    t = time_s - st.dead_time_s
    if t <= 0.0 or a <= 0.0:
        return 0.0, ramp, a
    hold = max(0.5 * (math.sqrt(ramp * ramp + 4.0 * room_m / a) - 3.0 * ramp), 0.0)
    y = v = acc = 0.0
    for duration, j in ((ramp, jerk), (hold, 0.0), (2.0 * ramp, -jerk), (hold, 0.0),
                        (ramp, jerk)):
        d = min(duration, t)
        y += v * d + acc * d * d / 2.0 + j * d**3 / 6.0
        v += acc * d + j * d * d / 2.0
        acc += j * d
        t -= d
        if t <= 0.0:
            break
    return y, ramp, a


def _max_speed(
    shift_needed_m: float, path_m: float, a_max: float, room_m: float, st: _Steering
) -> float:
    """Highest speed at which the shift is reached in time (the shift falls with speed)."""
    lo, hi = 0.01, 1000.0
    if _shift_m(hi, path_m / hi, a_max, room_m, st)[0] >= shift_needed_m:
        return hi
    for _ in range(80):  # bisection in log space
        mid = math.sqrt(lo * hi)
        reached = _shift_m(mid, path_m / mid, a_max, room_m, st)[0] >= shift_needed_m
        lo, hi = (mid, hi) if reached else (lo, mid)
    return lo


def popup_feasibility(
    *,
    speed_mps: float,
    mu: float,
    obstacle_distance_m: float,
    obstacle_length_m: float,
    obstacle_width_m: float,
    obstacle_offset_m: float,
    vehicle_width_m: float,
    room_left_m: float,
    room_right_m: float,
    clearance_margin_m: float,
    utilization_factor: float,
    brake_dead_time_s: float,
    steer_dead_time_s: float,
    steer_rate_radps: float,
    max_steer_rad: float,
    wheelbase_m: float,
    slip_rad_per_g: float,
    max_decel_mps2: float = math.inf,
) -> PopupFeasibility:
    """Whether a point mass at ``speed_mps`` can stop before, or steer around, the obstacle.

    Parameters
    ----------
    speed_mps, mu
        Speed when the obstacle appears [m/s] and the true friction [-].
    obstacle_distance_m
        From the vehicle's front to the obstacle's centre [m].
    obstacle_length_m, obstacle_width_m, obstacle_offset_m
        Obstacle size [m] and its centre's offset from the vehicle's centre line [m], left +.
    vehicle_width_m
        Footprint width [m].
    room_left_m, room_right_m
        How far the vehicle's centre may move left / right and keep its footprint on the road
        [m], ≥ 0.
    clearance_margin_m
        Required gap between footprint and obstacle [m], ≥ 0.
    utilization_factor
        λ in (0, 1].
    brake_dead_time_s, steer_dead_time_s
        Dead times of the brakes and of the steering servo [s], ≥ 0.
    steer_rate_radps, max_steer_rad
        Steering rate and angle limits [rad/s], [rad].
    wheelbase_m
        Axle distance [m] (kinematic steering angle ``L a_y / v²``).
    slip_rad_per_g
        Front slip angle per g of lateral acceleration at the λ-limit [rad] (the tire curve's
        secant there).
    max_decel_mps2
        Deceleration the brakes can give [m/s²] (default: no limit beyond friction).

    Returns
    -------
    PopupFeasibility

    Raises
    ------
    ValueError
        If a parameter is not finite or outside its range; the message names it.

    Examples
    --------
    >>> r = popup_feasibility(speed_mps=20.0, mu=1.0, obstacle_distance_m=20.0,
    ...     obstacle_length_m=1.0, obstacle_width_m=1.0, obstacle_offset_m=0.0,
    ...     vehicle_width_m=2.6, room_left_m=3.95, room_right_m=0.45, clearance_margin_m=0.5,
    ...     utilization_factor=0.9, brake_dead_time_s=0.15, steer_dead_time_s=0.05,
    ...     steer_rate_radps=0.9, max_steer_rad=0.6, wheelbase_m=3.4, slip_rad_per_g=0.2365)
    >>> r.braking.feasibility_class.value, r.evasion.side, r.evasion.feasibility_class.value
    ('infeasible', 'left', 'marginal')
    """
    for name, value in (
        ("speed_mps", speed_mps), ("mu", mu), ("obstacle_distance_m", obstacle_distance_m),
        ("obstacle_length_m", obstacle_length_m), ("obstacle_width_m", obstacle_width_m),
        ("vehicle_width_m", vehicle_width_m), ("steer_rate_radps", steer_rate_radps),
        ("max_steer_rad", max_steer_rad), ("wheelbase_m", wheelbase_m),
    ):
        require_positive(name, value)
    for name, value in (
        ("room_left_m", room_left_m), ("room_right_m", room_right_m),
        ("clearance_margin_m", clearance_margin_m), ("brake_dead_time_s", brake_dead_time_s),
        ("steer_dead_time_s", steer_dead_time_s), ("slip_rad_per_g", slip_rad_per_g),
    ):
        require_positive(name, value, allow_zero=True)
    require_fraction("utilization_factor", utilization_factor)
    if not math.isfinite(obstacle_offset_m):
        raise ValueError(f"obstacle_offset_m must be finite, got {obstacle_offset_m!r}")
    if not max_decel_mps2 > 0.0:
        raise ValueError(f"max_decel_mps2 must be > 0, got {max_decel_mps2!r}")

    a_max = utilization_factor * mu * GRAVITY_MPS2
    path = obstacle_distance_m - 0.5 * obstacle_length_m
    decel = min(a_max, max_decel_mps2)
    stop = stopping_distance_m(speed_mps, decel, brake_dead_time_s)
    v_brake = braking_limited_speed_mps(path, decel, brake_dead_time_s)
    braking = BrakingEnvelope(
        available_distance_m=path, stopping_distance_m=stop, spare_distance_m=path - stop,
        deceleration_mps2=decel, max_speed_mps=v_brake, margin_mps=v_brake - speed_mps,
        feasibility_class=classify_speed_margin(v_brake - speed_mps, speed_mps),
    )
    steering = _Steering(wheelbase_m, slip_rad_per_g, steer_rate_radps, max_steer_rad,
                         steer_dead_time_s)
    reach = 0.5 * (obstacle_width_m + vehicle_width_m) + clearance_margin_m
    needs = {"left": obstacle_offset_m + reach, "right": reach - obstacle_offset_m}
    rooms = {"left": room_left_m, "right": room_right_m}
    time_s = path / speed_mps

    def envelope(side: Literal["left", "right"]) -> EvasionEnvelope:
        need, room = needs[side], rooms[side]
        shift, ramp, a = _shift_m(speed_mps, time_s, a_max, room, steering)
        label: Literal["left", "right", "none"] = side
        if need <= 0.0:  # the obstacle does not reach into the vehicle's path
            v_max, label = math.inf, "none"
        else:
            v_max = _max_speed(need, path, a_max, room, steering) if need <= room else 0.0
        return EvasionEnvelope(
            side=label, required_shift_m=max(need, 0.0), achievable_shift_m=shift,
            spare_shift_m=shift - max(need, 0.0) if need <= room else -math.inf,
            time_to_obstacle_s=time_s, steer_ramp_s=ramp, lateral_accel_mps2=a,
            max_speed_mps=v_max, margin_mps=v_max - speed_mps,
            feasibility_class=classify_speed_margin(v_max - speed_mps, speed_mps),
        )

    evasion = max((envelope("left"), envelope("right")), key=lambda e: e.margin_mps)
    better = braking if braking.margin_mps >= evasion.margin_mps else evasion
    return PopupFeasibility(
        feasibility_class=better.feasibility_class, margin_mps=better.margin_mps,
        speed_mps=speed_mps, braking=braking, evasion=evasion,
    )
