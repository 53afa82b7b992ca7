"""Hand-made OCP data for tests that call a planner backend directly."""

from __future__ import annotations

import numpy as np

from mufusion.planner.ocp import Param, PlannerConfig
from mufusion.vehicle.params import GRAVITY_MPS2, TRUCK
from mufusion.vehicle.planner_model import N_STATES, State, normal_loads_n


def cruise_problem(cfg: PlannerConfig, speed_mps: float, mu: float):
    """The truck cruising straight at ``speed_mps`` on ``mu``: ``(guess_x, guess_u, p, yref,
    weights)`` for ``backend.solve``, the speed tracked and the forces almost free."""
    n = cfg.horizon_steps
    guess_x = np.zeros((n + 1, N_STATES))
    guess_x[:, State.vx] = speed_mps
    guess_x[:, State.s] = speed_mps * cfg.dt_s * np.arange(n + 1)
    p = np.zeros((n, len(Param)))
    p[:, Param.utilized_friction] = cfg.utilization_factor * mu
    p[:, Param.utilized_friction_front] = p[:, Param.utilized_friction]
    p[:, Param.radius_front] = p[:, Param.radius_rear] = mu * TRUCK.mass_kg * GRAVITY_MPS2
    guess_load = p[:, Param.radius_rear] / p[:, Param.utilized_friction]
    p[:, Param.rear_stiffness] = 3e5 * guess_load / normal_loads_n(0.0, TRUCK)[1]
    yref = np.zeros((n + 1, N_STATES + 3))
    yref[:, State.vx] = speed_mps
    weights = np.ones(N_STATES + 3)
    weights[State.s], weights[N_STATES:] = 0.0, 1e-8
    return guess_x, np.zeros((n, 3)), p, yref, weights
