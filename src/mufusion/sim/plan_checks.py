"""Checks of a plan's predictions: how far its footprints leave the lane, how near they come to
the obstacles, whether they hit one, how far its rear tire leans past its friction (lane recovery
and the futile-evasion check, :mod:`mufusion.sim.supervision`, rank their candidate plans with
them)."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from mufusion.planner import Plan, PlannerObstacle
from mufusion.road.geometry import rectangle_corners, rectangles_overlap, signed_clearance_m
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import Input, State


def planned_footprint_violation_m(
    states: np.ndarray,
    curvature_1pm: np.ndarray,
    lane_bounds_m: tuple[float, float],
    params: VehicleParams,
) -> float:
    """How far a plan's predicted footprint leaves its lane [m] (0 inside).

    ``lane_bounds_m`` bound the reference point (the band's edges shrunk by half the vehicle
    width and by the planner's footprint margin, ``FOOTPRINT_MARGIN_M`` = 0.1 m for the
    scenarios), so the footprint may reach ``lane_bounds_m[0] − w/2`` and
    ``lane_bounds_m[1] + w/2``: that margin inside the edges, which a plan must leave for the
    plant's tracking error.
    A body point ``x`` ahead of the reference point and ``y`` left of it lies
    ``d + x sin Δψ + y cos Δψ − κ x² / 2`` from the lane centre (to second order in ``x κ``; the
    last term is the chord of a curve of curvature ``κ``): the four corners of each planned
    state are checked, not the reference point alone, which on a curve and yawed against the
    lane is up to the body's swing and bulge inside the corners.

    Parameters
    ----------
    states
        Planned states ``(K, 6)`` (:class:`~mufusion.vehicle.planner_model.State`).
    curvature_1pm
        Road curvature at the states' ``s`` [1/m], ``(K,)`` or a scalar.
    lane_bounds_m
        ``(d_min, d_max)`` of the reference point [m].
    params
        Vehicle dimensions (width, length, axle positions).

    Examples
    --------
    >>> from mufusion.vehicle.params import TRUCK
    >>> x = np.zeros((2, 6)); x[:, State.d] = [0.0, 0.5]
    >>> round(planned_footprint_violation_m(x, 0.0, (-0.45, 0.45), TRUCK), 6)
    0.05
    """
    x = np.asarray(states, dtype=float)
    d, dpsi = x[:, State.d], x[:, State.dpsi]
    kappa = np.broadcast_to(np.asarray(curvature_1pm, dtype=float), d.shape)
    half_w = 0.5 * params.width_m
    sin_dpsi, cos_dpsi = np.sin(dpsi), np.cos(dpsi)
    ends = [d + a * sin_dpsi - 0.5 * kappa * a * a
            for a in (params.cog_to_body_front_m, -params.cog_to_body_rear_m)]
    lowest = np.minimum(ends[0], ends[1]) - half_w * cos_dpsi
    highest = np.maximum(ends[0], ends[1]) + half_w * cos_dpsi
    lo, hi = lane_bounds_m
    return float(max(0.0, np.max(lo - half_w - lowest, initial=0.0),
                     np.max(highest - hi - half_w, initial=0.0)))


def planned_rear_overuse(plan: Plan) -> float:
    """The plan's largest rear tire force over its friction radius, stages 1 … N−1 [-].

    ``hypot(F_xr, F_yr) / (λ μ̂ F_zr)`` with the plan's own rear lateral force (the linear tire
    at its states) and radius (:attr:`~mufusion.planner.Plan.force_limit_rear_n`): 1 at the
    polygon's vertices, above 1 where the plan uses the rear polygon's slack (the OCP's rear rows
    are soft, since the rear lateral force follows the state). Stage 0 is left out: its lateral
    force is the measured state's, which no plan changes. 0 for a plan of one stage.
    """
    inputs = np.asarray(plan.inputs, dtype=float)[1:]
    if inputs.shape[0] == 0:
        return 0.0
    force = np.hypot(inputs[:, Input.fxr], np.asarray(plan.rear_lateral_force_n, dtype=float)[1:])
    radius = np.maximum(np.asarray(plan.force_limit_rear_n, dtype=float)[1:], 1e-9)
    return float(np.max(force / radius))


def planned_obstacle_clearance_m(
    states: np.ndarray,
    obstacles: Sequence[PlannerObstacle],
    params: VehicleParams,
    dt_s: float = 0.0,
) -> float:
    """Smallest gap between a plan's predicted footprints and the obstacles [m], negative when
    they overlap (minus the depth); ``inf`` without obstacles.

    Footprints and obstacles are rectangles in road coordinates ``(s, d)``, the footprint
    centred ``params.body_centre_ahead_of_cog_m`` ahead of the reference point along the heading
    error: exact on a straight road, the planner's own frame on a curved one. Row ``k`` of
    ``states`` is ``k · dt_s`` after the first: a moving obstacle is where it is then.

    Examples
    --------
    >>> from mufusion.planner import PlannerObstacle
    >>> from mufusion.vehicle.params import TRUCK
    >>> x = np.zeros((1, 6)); x[0, State.s] = 0.0
    >>> ob = PlannerObstacle(s_m=20.0, d_m=0.0, length_m=1.0, width_m=1.0)
    >>> gap = 20.0 - 0.5 - TRUCK.cog_to_body_front_m  # obstacle's near edge − footprint's front
    >>> bool(np.isclose(planned_obstacle_clearance_m(x, [ob], TRUCK), gap))
    True
    """
    if not obstacles:
        return math.inf
    x = np.asarray(states, dtype=float)
    ego = _footprints(x, params)
    return min(float(np.min(signed_clearance_m(ego, box)))
               for box in _obstacle_corners(obstacles, len(x), dt_s))


def planned_obstacle_shortfall_m(
    states: np.ndarray,
    obstacles: Sequence[PlannerObstacle],
    params: VehicleParams,
    margin_m: float,
    dt_s: float = 0.0,
) -> float:
    """How much closer than ``margin_m`` a plan's predicted footprints come to the obstacles
    [m]: ``max(0, margin_m − planned_obstacle_clearance_m(...))``, the same value bit for bit,
    computed only for the states that can come that close.

    A footprint's gap to an (axis-aligned) obstacle is at least the gap between its bounding box
    and the obstacle, so a state whose box stays ``margin_m`` (and a nanometre's rounding band)
    away cannot change the result: the exact clearance is computed for the others only, and
    without them the shortfall is 0. Non-finite input takes the full computation.

    Examples
    --------
    >>> from mufusion.planner import PlannerObstacle
    >>> from mufusion.vehicle.params import TRUCK
    >>> x = np.zeros((2, 6)); x[:, State.s] = [0.0, 14.0]
    >>> ob = [PlannerObstacle(s_m=20.0, d_m=0.0, length_m=1.0, width_m=1.0)]
    >>> gap = planned_obstacle_clearance_m(x, ob, TRUCK)
    >>> planned_obstacle_shortfall_m(x, ob, TRUCK, 0.5) == max(0.0, 0.5 - gap)
    True
    >>> planned_obstacle_shortfall_m(x[:1], ob, TRUCK, 0.5)
    0.0
    """
    if not obstacles or not margin_m > 0.0:
        return max(0.0, margin_m - planned_obstacle_clearance_m(states, obstacles, params, dt_s))
    x = np.asarray(states, dtype=float)
    boxes = _obstacle_corners(obstacles, len(x), dt_s)
    if not (np.all(np.isfinite(x)) and all(np.all(np.isfinite(box)) for box in boxes)):
        return max(0.0, margin_m - planned_obstacle_clearance_m(x, obstacles, params, dt_s))
    ego = _footprints(x, params)
    ego_lo, ego_hi = ego.min(axis=-2), ego.max(axis=-2)
    reach = margin_m + _ROUNDING_BAND_M
    gap = math.inf
    for box in boxes:
        # Per axis, how far apart the boxes are (0 where their extents overlap).
        apart = np.maximum(np.maximum(box.min(axis=-2) - ego_hi, ego_lo - box.max(axis=-2)), 0.0)
        near = np.hypot(apart[:, 0], apart[:, 1]) < reach
        if np.any(near):
            gap = min(gap, float(np.min(signed_clearance_m(
                ego[near], box[near] if box.ndim == 3 else box))))
    return max(0.0, margin_m - gap)


_ROUNDING_BAND_M = 1e-9
"""Beyond the margin, the bounding-box gap a state must keep to be left out of the exact
clearance: far above the rounding of the distances (≈ 1e-14 m at road scale), so a state left
out never has an exact clearance below the margin."""


def _footprints(states: np.ndarray, params: VehicleParams) -> np.ndarray:
    """The plan's predicted footprints in ``(s, d)``, ``(K, 4, 2)``: centred
    ``params.body_centre_ahead_of_cog_m`` ahead of the reference point along the heading error."""
    s, d, dpsi = states[:, State.s], states[:, State.d], states[:, State.dpsi]
    ahead = params.body_centre_ahead_of_cog_m
    return rectangle_corners(s + ahead * np.cos(dpsi), d + ahead * np.sin(dpsi), dpsi,
                             params.length_m, params.width_m)


def _obstacle_corners(
    obstacles: Sequence[PlannerObstacle], rows: int, dt_s: float
) -> list[np.ndarray]:
    """Each obstacle's corners in ``(s, d)``: ``(4, 2)``, or ``(rows, 4, 2)`` for a moving one,
    row ``k`` where it is ``k · dt_s`` after the first."""
    times_s = dt_s * np.arange(rows, dtype=float)
    return [rectangle_corners(ob.s_m + ob.speed_mps * times_s if ob.speed_mps else ob.s_m,
                              ob.d_m, 0.0, ob.length_m, ob.width_m)
            for ob in obstacles]


def planned_obstacle_hit(
    states: np.ndarray,
    obstacles: Sequence[PlannerObstacle],
    params: VehicleParams,
    dt_s: float = 0.0,
) -> bool:
    """Whether a plan's predicted footprints overlap an obstacle: the same answer as
    ``planned_obstacle_clearance_m(states, obstacles, params, dt_s) < 0.0``, at a fraction of
    its cost.

    Only where a footprint's bounding box overlaps an obstacle's (the obstacles are axis-aligned
    in ``(s, d)``) can the rectangles overlap: the separating-axis test of
    :func:`~mufusion.road.geometry.signed_clearance_m` projects onto the obstacle's edge normals,
    the coordinate axes, and these projections are the boxes' extents bit for bit, so where the
    boxes do not overlap its penetration is ≤ 0 and the clearance the distance, ≥ 0. The other
    states are judged by that penetration itself
    (:func:`~mufusion.road.geometry.rectangles_overlap`: the clearance is negative exactly where
    it is positive). Non-finite input takes the full computation.

    Examples
    --------
    >>> from mufusion.planner import PlannerObstacle
    >>> from mufusion.vehicle.params import TRUCK
    >>> x = np.zeros((2, 6)); x[:, State.s] = [0.0, 20.0]
    >>> planned_obstacle_hit(x, [PlannerObstacle(s_m=20.0, d_m=0.0, length_m=1.0, width_m=1.0)],
    ...                      TRUCK)
    True
    """
    if not obstacles:
        return False
    x = np.asarray(states, dtype=float)
    boxes = _obstacle_corners(obstacles, len(x), dt_s)
    if not (np.all(np.isfinite(x)) and all(np.all(np.isfinite(box)) for box in boxes)):
        return planned_obstacle_clearance_m(x, obstacles, params, dt_s) < 0.0
    ego = _footprints(x, params)
    ego_lo, ego_hi = ego.min(axis=-2), ego.max(axis=-2)
    for box in boxes:
        overlap = np.minimum(ego_hi, box.max(axis=-2)) - np.maximum(ego_lo, box.min(axis=-2))
        near = np.all(overlap > 0.0, axis=-1)
        if np.any(near) and bool(np.any(
                rectangles_overlap(ego[near], box[near] if box.ndim == 3 else box))):
            return True
    return False


def planned_contact_width_m(
    states: np.ndarray,
    obstacles: Sequence[PlannerObstacle],
    params: VehicleParams,
    dt_s: float = 0.0,
) -> float:
    """How wide a plan's first predicted contact with an obstacle is [m]: at the first state
    whose footprint overlaps one, the lateral (``d``) extent the footprint's bounding box shares
    with that obstacle; 0 where the plan hits nothing, ``inf`` for non-finite states.

    It tells a graze from a frontal impact: a plan that brakes in lane into an obstacle in its
    lane meets it across the shared width of the two, an evasion that comes up centimetres short
    with those centimetres (the futility check weighs the two, docs/decisions/0126).

    Examples
    --------
    >>> from mufusion.planner import PlannerObstacle
    >>> from mufusion.vehicle.params import CAR
    >>> ob = PlannerObstacle(s_m=20.0, d_m=0.5, length_m=1.0, width_m=2.0)
    >>> x = np.zeros((3, 6)); x[:, State.s] = [0.0, 10.0, 20.0]
    >>> round(planned_contact_width_m(x, [ob], CAR), 3)  # head on: half the car's width + 0.5 m
    1.305
    >>> x[:, State.d] = 2.2  # 2.2 m left: the obstacle's edge 1.5 m, the car's 2.2 − 0.805
    >>> round(planned_contact_width_m(x, [ob], CAR), 3)
    0.105
    >>> x[:, State.d] = 2.4
    >>> planned_contact_width_m(x, [ob], CAR)
    0.0
    """
    if not obstacles:
        return 0.0
    x = np.asarray(states, dtype=float)
    if not np.all(np.isfinite(x)):
        return math.inf
    ego = _footprints(x, params)
    ego_lo, ego_hi = ego.min(axis=-2), ego.max(axis=-2)
    first, width = len(x), 0.0
    for box in _obstacle_corners(obstacles, len(x), dt_s):
        per_state = box if box.ndim == 3 else np.broadcast_to(box, ego.shape)
        overlap = np.minimum(ego_hi, per_state.max(axis=-2)) - np.maximum(
            ego_lo, per_state.min(axis=-2))
        near = np.flatnonzero(np.all(overlap > 0.0, axis=-1)[:first])
        touching = near[rectangles_overlap(ego[near], per_state[near])] if near.size else near
        if touching.size:
            first, width = int(touching[0]), float(overlap[touching[0], 1])
    return width
