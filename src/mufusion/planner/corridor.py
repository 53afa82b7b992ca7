"""The lateral corridor of the OCP: bounds on the reference point's ``d`` per stage from the
lane, the curve's bulge, the heading's corner swing and the obstacles (planner/ocp.py re-exports
it)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from mufusion.planner.config import PlannerObstacle
from mufusion.planner.passing import passing_left
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State

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
    dt_s: float = 0.0,
    max_swing_rad: float = MAX_SWING_HEADING_RAD,
    exact_reach: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the reference point's ``d`` per stage 1..N, shape ``(N,)`` each.

    ``lane_d_min_m``/``lane_d_max_m`` bound the reference point itself (the caller has already
    shrunk the lane or road edges by half the vehicle width, TAMP framework). On a curve of
    curvature κ (``curvature_1pm`` at the stages' predicted positions) the body's ends, aligned
    with the lane at its middle, stick out of the curve by ``|κ| (l/2)² / 2``; that much is taken
    off the outer bound (right of a left curve, left of a right curve). Exact for a body centred
    on the reference point; the truck's rear end, 3.63 m behind it, sticks out by up to
    ``|κ| · 1.67 m²`` more, inside the lane's 0.1 m footprint margin above a 17 m radius (each
    end's own term measured and not adopted: docs/decisions/0087). A heading error Δψ (the
    guess's, as RTI linearises there) swings the front corners by ``a_f sin Δψ`` and the rear ones
    by ``a_r sin Δψ`` the other way (``a_f``, ``a_r``: CoG to the body's front and rear); the
    bounds shrink by that too. An obstacle
    overlapping the vehicle's footprint at the guess's predicted ``s_k`` closes the side opposite
    to the guess's ``d_k`` (pass left if the guess is left of the obstacle's centre), which keeps
    the problem convex, unless only the other side has room (:func:`~.passing.passing_left`,
    judged on the lane bounds and the bulge, not on the heading's swing).
    A moving obstacle is where it is predicted at each stage's time ``k · dt_s``
    (:meth:`PlannerObstacle.s_at_stages`). ``max_swing_rad``: the largest heading error whose
    swing is taken off (0: none, where :func:`heading_rows` keep the body's ends in the lane).
    ``exact_reach``: the bounds shrink instead by how far the body's long sides reach towards
    them, swing and bulge as one geometry (:func:`body_reach_m`, docs/decisions/0093: measured,
    not adopted).
    """
    s_k = guess_states[1:, State.s]
    d_k = guess_states[1:, State.d]
    half_w = 0.5 * params.width_m
    lo = np.full(s_k.shape, float(lane_d_min_m))
    hi = np.full(s_k.shape, float(lane_d_max_m))
    half_len = 0.5 * params.length_m
    a_front, a_rear = params.cog_to_body_front_m, params.cog_to_body_rear_m
    # Only lane-keeping headings count in full: in an evasive manoeuvre the heading reaches
    # 0.3-0.5 rad and the full swing (> 1 m each side) would close the corridor the manoeuvre
    # needs; the obstacle margin covers the corners there.
    sin_dpsi = np.sin(np.minimum(np.maximum(guess_states[1:, State.dpsi],
                                            -max_swing_rad), max_swing_rad))
    # Which side of an obstacle has room is a property of the road (its edges, the curve's
    # bulge), not of the guess's heading: a passage the swing below narrows is still passable,
    # with less than the margin, where the other side may need metres more (docs/decisions/0073).
    if exact_reach:
        kappa = (np.zeros_like(s_k) if curvature_1pm is None
                 else np.asarray(curvature_1pm, dtype=float) * np.ones_like(s_k))
        # Aligned with the lane, the end further from the reference point sticks out the most.
        bulge = 0.5 * kappa * max(a_front, a_rear) ** 2
        road_lo, road_hi = lo + np.maximum(bulge, 0.0), hi + np.minimum(bulge, 0.0)
        reach_lo, reach_hi = body_reach_m(sin_dpsi, kappa, a_front, a_rear)
        lo, hi = lo - reach_lo, hi - reach_hi
    else:
        if curvature_1pm is not None:
            kappa = np.asarray(curvature_1pm, dtype=float) * np.ones_like(s_k)
            bulge = 0.5 * np.abs(kappa) * half_len**2
            hi = np.where(kappa < 0.0, hi - bulge, hi)
            lo = np.where(kappa > 0.0, lo + bulge, lo)
        road_lo, road_hi = lo, hi
        hi = hi - a_front * np.maximum(sin_dpsi, 0.0) - a_rear * np.maximum(-sin_dpsi, 0.0)
        lo = lo + a_front * np.maximum(-sin_dpsi, 0.0) + a_rear * np.maximum(sin_dpsi, 0.0)
    # A corridor too tight for the vehicle leaves its midpoint rather than an empty interval.
    mid = 0.5 * (lo + hi)
    lo, hi = np.minimum(lo, mid), np.maximum(hi, mid)
    for ob in obstacles:
        s_ob = ob.s_at_stages(s_k.shape, dt_s)
        overlap = np.abs(s_k - s_ob) < half_len + 0.5 * ob.length_m + margin_m
        clear = 0.5 * ob.width_m + half_w + margin_m
        left = passing_left(d_k, ob.d_m, clear, road_lo, road_hi)
        lo = np.where(overlap & left, np.maximum(lo, ob.d_m + clear), lo)
        hi = np.where(overlap & ~left, np.minimum(hi, ob.d_m - clear), hi)
    return lo, hi


def body_reach_m(sin_dpsi: np.ndarray, kappa_1pm: np.ndarray, a_front_m: float,
                 a_rear_m: float) -> tuple[np.ndarray, np.ndarray]:
    """How far right (``lowest`` ≤ 0) and left (``highest`` ≥ 0) of the reference point's lane
    offset the body's long sides reach [m], per stage.

    A side point ``x`` ahead of the reference point (``−a_rear_m ≤ x ≤ a_front_m``) of a straight
    body at heading error Δψ (``sin_dpsi``) on a lane of curvature κ lies
    ``g(x) = x sin Δψ − κ x² / 2`` off the point's offset (small angles: the lane's frame at the
    reference point, each point's lane offset measured square to the lane there). Its extremes
    lie at the ends or, where κ bends it the other way, at ``x* = sin Δψ / κ`` inside the body,
    ``g(x*) = sin² Δψ / (2κ)`` (the largest on a left curve, the smallest on a right one). The
    reference point itself is on the body (``g(0) = 0``), so ``lowest ≤ 0 ≤ highest``. The
    width's ``cos Δψ`` is left at 1 (the caller's half-width, 6 mm more than the truck needs at
    0.1 rad).

    >>> lo, hi = body_reach_m(np.array([0.1, 0.0]), np.array([0.0, 0.1]), 2.0, 3.0)
    >>> [round(float(v), 3) for v in lo], [round(float(v), 3) for v in hi]
    ([-0.3, -0.45], [0.2, 0.0])
    """
    front = a_front_m * sin_dpsi - 0.5 * kappa_1pm * a_front_m**2
    rear = -a_rear_m * sin_dpsi - 0.5 * kappa_1pm * a_rear_m**2
    lowest, highest = np.minimum(front, rear), np.maximum(front, rear)
    curved = kappa_1pm != 0.0
    x_vertex = np.divide(sin_dpsi, kappa_1pm, out=np.zeros_like(sin_dpsi), where=curved)
    vertex = 0.5 * sin_dpsi * x_vertex
    inside = curved & (x_vertex > -a_rear_m) & (x_vertex < a_front_m)
    highest = np.where(inside & (kappa_1pm > 0.0), np.maximum(highest, vertex), highest)
    lowest = np.where(inside & (kappa_1pm < 0.0), np.minimum(lowest, vertex), lowest)
    return np.minimum(lowest, 0.0), np.maximum(highest, 0.0)


def reach_taken_m(sin_dpsi: np.ndarray, kappa_1pm: np.ndarray, params: VehicleParams,
                  exact_reach: bool = False) -> np.ndarray:
    """How much of the reference point's band [m] :func:`lateral_corridor` takes off for the
    body at heading error Δψ (``sin_dpsi``) on curvature κ, both sides together: the centred
    body's bulge and the ends' swing counted apart, or (``exact_reach``) the long sides' reach
    as one geometry (:func:`body_reach_m`). The corridor is empty where this exceeds the band.

    >>> from mufusion.vehicle.params import TRUCK
    >>> [round(float(v), 3) for v in reach_taken_m(np.array([0.0, 0.02]), np.full(2, 1 / 60),
    ...                                             TRUCK)]
    [0.082, 0.208]
    """
    kappa = np.asarray(kappa_1pm, dtype=float)
    if exact_reach:
        lowest, highest = body_reach_m(np.asarray(sin_dpsi, dtype=float), kappa,
                                       params.cog_to_body_front_m, params.cog_to_body_rear_m)
        return highest - lowest
    bulge = 0.5 * np.abs(kappa) * (0.5 * params.length_m) ** 2
    return bulge + (params.cog_to_body_front_m + params.cog_to_body_rear_m) * np.abs(sin_dpsi)


def heading_rows(d: Any, dpsi: Any, kappa: Any, lane_lo: Any, lane_hi: Any,
                 params: VehicleParams) -> list[Any]:
    """The body's front and rear ends within the lane at the plan's own heading error (CasADi).

    ``e_f = d + a_f sin Δψ − κ a_f² / 2`` and ``e_r = d − a_r sin Δψ − κ a_r² / 2`` (``a_f``,
    ``a_r``: centre of gravity to the body's front and rear; each end of a straight body sits
    ``κ a² / 2`` outside the lane curving away from it) between the reference point's lane
    bounds: the rows ``e − hi``, ``lo − e``, each ``≤ 0`` [m], soft and priced per metre as the
    bound on ``d``. The solver linearises them at each iterate, so a plan trades its heading
    against its offset and its speed, where a bound on ``d`` alone can take off only the guess's
    swing (docs/decisions/0081).
    """
    import casadi as ca

    swing = ca.sin(dpsi)
    a_f, a_r = params.cog_to_body_front_m, params.cog_to_body_rear_m
    front = d + a_f * swing - 0.5 * kappa * a_f**2
    rear = d - a_r * swing - 0.5 * kappa * a_r**2
    return [front - lane_hi, rear - lane_hi, lane_lo - front, lane_lo - rear]
