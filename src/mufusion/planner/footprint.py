"""How far planned or rolled-out trajectories leave the road or reach into obstacles, and how
well they track: the scores the sampling augmentation ranks its candidates by
(planner/sampling.py)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mufusion.planner.config import PlannerObstacle
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import State


def stage_violations_m(
    states: np.ndarray,
    obstacles: Sequence[PlannerObstacle],
    lane_d_min_m: float,
    lane_d_max_m: float,
    params: VehicleParams,
    margin_m: float,
    dt_s: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """The road's and the obstacles' footprint violation [m] of trajectories
    ``states (N+1, 6, M)`` at the stages 1…N → ``(N, M)``, ``(N, M)``.

    Road: how far ``d`` lies beyond ``[lane_d_min_m, lane_d_max_m]``. Obstacles: how far the
    footprint, widened by ``margin_m``, reaches into an obstacle's where they overlap along
    ``s`` (summed over the obstacles). Stage ``k`` is ``k · dt_s`` after the first state: a
    moving obstacle is where it is then
    (:meth:`~mufusion.planner.config.PlannerObstacle.s_at_stages`).
    """
    s, d = states[1:, State.s], states[1:, State.d]
    half_w = 0.5 * params.width_m
    road = np.maximum(lane_d_min_m - d, 0.0) + np.maximum(d - lane_d_max_m, 0.0)
    overlap = np.zeros_like(d)
    for ob in obstacles:
        reach = 0.5 * params.length_m + 0.5 * ob.length_m + margin_m
        near = np.abs(s - ob.s_at_stages(s.shape, dt_s)) < reach
        clear = 0.5 * ob.width_m + half_w + margin_m
        overlap = overlap + np.where(near, np.maximum(clear - np.abs(d - ob.d_m), 0.0), 0.0)
    return road, overlap


def tracking_cost(states: np.ndarray, v_ref: float, d_ref: float) -> np.ndarray:
    """Speed and lateral tracking cost of trajectories ``(N+1, 6, M)`` → ``(M,)``."""
    x = states[1:]
    return ((x[:, State.vx] - v_ref) ** 2 + 0.5 * (x[:, State.d] - d_ref) ** 2).sum(axis=0)
