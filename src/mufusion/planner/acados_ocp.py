"""The acados description of the shared OCP (``AcadosOcp``), for code generation only, and the
inputs' bounds it is generated with (:mod:`mufusion.planner.acados_backend` runs it)."""

from __future__ import annotations

from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from mufusion.planner.front_force import front_force_rate_bound_n_per_s
from mufusion.planner.integration import stage_steps
from mufusion.planner.ocp import (
    HEADING_ROWS,
    MAX_SPEED_MPS,
    N_PARAMS,
    POLYGON_ROW_LOWER_BOUND,
    Param,
    PlannerConfig,
    SlackPenalties,
    constraint_expressions,
    longitudinal_force_bounds_n,
    ocp_rear_stiffness,
    polygon_rows,
    slack_penalties,
)
from mufusion.planner.ocp_state import force_rates, ocp_rear_force_limit, ocp_state, tire_forces
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    frenet_bicycle_dynamics,
)

ITERATE_C = "mufusion_iterate.c"
ITERATE_H = "mufusion_iterate.h"
"""The batch access's source and header in the export directory (acados' custom-update hook)."""


def stage_slack_penalties(config: PlannerConfig) -> SlackPenalties:
    """The slack penalties of stages 1 … N−1 as generated (before the corridor's per-stage
    scale, :func:`~mufusion.planner.penalties.corridor_slack_scale`, written at load time)."""
    rows = polygon_rows(config.polygon_sides, load_transfer=config.load_transfer)
    return slack_penalties(config.weights, rows.per_axle, HEADING_ROWS * int(config.heading_rows),
                           config.speed_ceiling, 2 * int(config.stability_envelope))


def input_bounds(params: VehicleParams, config: PlannerConfig) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of the bounded inputs: ``(F_xf, F_xr)``, led by the front force's rate with the
    steering's rate limit (``F_xr`` last either way)."""
    lower, upper = longitudinal_force_bounds_n(params)
    if config.steering_rate_limit:
        rate = front_force_rate_bound_n_per_s(params, config)
        lower, upper = np.concatenate([[-rate], lower]), np.concatenate([[rate], upper])
    return np.array(lower, dtype=float), np.array(upper, dtype=float)


def describe(
    at: ModuleType, params: VehicleParams, config: PlannerConfig, name: str, export: Path,
    hpipm_mode: str,
) -> Any:
    """The ``AcadosOcp`` description of the shared problem (for code generation)."""
    import casadi as ca

    n, ns = config.horizon_steps, config.polygon_sides
    ocp = at.AcadosOcp()
    model = at.AcadosModel()
    model.name = name
    layout = ocp_state(config, params)
    nx = layout.nx
    x = ca.SX.sym("x", nx)
    u = ca.SX.sym("u", N_INPUTS)
    p = ca.SX.sym("p", N_PARAMS)
    model.x, model.u, model.p = x, u, p
    model.xdot = ca.SX.sym("xdot", nx)
    # The tire forces: those that are states (planner/ocp_state.py), the inputs' otherwise.
    forces = tire_forces(x, u, layout)
    rear_limit = ocp_rear_force_limit(p, forces, params, config)
    f = frenet_bicycle_dynamics(x[:N_STATES], forces, p[Param.curvature],
                                ocp_rear_stiffness(p, forces, params, config.load_transfer), params,
                                rear_force_limit_n=rear_limit)
    f = ca.vertcat(f, *force_rates(x, u, layout))
    model.f_expl_expr = f
    model.f_impl_expr = model.xdot - f
    model.con_h_expr = constraint_expressions(x[:N_STATES], forces, p, params, ns,
                                             load_transfer=config.load_transfer,
                                             heading=config.heading_rows,
                                             rear_force_limit_n=rear_limit)
    ocp.model = model
    ocp.dims.N = n
    ocp.parameter_values = np.ones(N_PARAMS)

    ny = N_STATES + N_INPUTS
    ocp.cost.cost_type = "LINEAR_LS"
    ocp.cost.cost_type_e = "LINEAR_LS"
    # y = [planner state (6), F_yf, F_xf, F_xr]: the tracking reference's layout. With the
    # steering's rate limit the F_yf weight acts on the force state; the rate is bounded only.
    # The longitudinal weights act on the inputs, the commands where the forces lag.
    vx = np.zeros((ny, nx))
    vx[:N_STATES, :N_STATES] = np.eye(N_STATES)
    vu = np.zeros((ny, N_INPUTS))
    vu[N_STATES:, :] = np.eye(N_INPUTS)
    if layout.front_force is not None:
        vu[N_STATES + Input.fyf, Input.fyf] = 0.0
        vx[N_STATES + Input.fyf, layout.front_force] = 1.0
    ocp.cost.Vx, ocp.cost.Vu = vx, vu
    ocp.cost.Vx_e = np.eye(N_STATES, nx)
    ocp.cost.W, ocp.cost.W_e = np.eye(ny), np.eye(N_STATES)
    ocp.cost.yref, ocp.cost.yref_e = np.zeros(ny), np.zeros(N_STATES)

    ocp.constraints.x0 = np.eye(nx)[State.vx] * 10.0  # an example: the solve writes x_0
    envelope = 2 * int(config.stability_envelope)  # ψ̇ and v_y, soft, written per solve
    ocp.constraints.idxbx = np.array([State.d, State.vx, State.psidot, State.vy][: 2 + envelope])
    box = np.array([[-1.0, 0.0, -10.0, -10.0], [1.0, MAX_SPEED_MPS, 10.0, 10.0]])
    ocp.constraints.lbx, ocp.constraints.ubx = box[:, : 2 + envelope]
    # d soft, v_x with the speed ceiling (it can be below the vehicle's own speed), the envelope.
    soft_speed = [1] if config.speed_ceiling else []
    ocp.constraints.idxsbx = np.array([0, *soft_speed, 2, 3][: 1 + len(soft_speed) + envelope])
    ocp.constraints.idxbx_e = np.array([State.d])
    ocp.constraints.lbx_e = np.array([-1.0])
    ocp.constraints.ubx_e = np.array([1.0])
    ocp.constraints.idxsbx_e = np.array([0])
    ocp.constraints.idxbu = np.array(
        [Input.fyf, Input.fxf, Input.fxr] if config.steering_rate_limit else [Input.fxf, Input.fxr]
    )
    ocp.constraints.lbu, ocp.constraints.ubu = input_bounds(params, config)
    rows = polygon_rows(ns, load_transfer=config.load_transfer)
    heading = HEADING_ROWS * int(config.heading_rows)
    ocp.constraints.lh = np.r_[np.full(rows.count, rows.lower), [POLYGON_ROW_LOWER_BOUND] * heading]
    ocp.constraints.uh = np.r_[np.full(rows.count, rows.upper), np.zeros(heading)]
    # Front forces are inputs and always have a feasible choice (hard); the rear lateral force
    # follows the state, which at stage 0 is fixed, so the rear polygon is soft (and the heading
    # rows). acados orders a stage's slacks as the soft bounds first (d, v_x, the envelope's),
    # then the soft h rows: SlackPenalties' layout; zl prices the lower sides, zu the upper.
    ocp.constraints.idxsh = np.arange(rows.per_axle, rows.count + heading)
    penalties = stage_slack_penalties(config)
    ocp.cost.zl, ocp.cost.zu = penalties.linear_stage, penalties.linear_stage_upper
    ocp.cost.Zl, ocp.cost.Zu = penalties.quadratic_stage, penalties.quadratic_stage_upper
    ocp.cost.zl_e = ocp.cost.zu_e = penalties.linear_terminal
    ocp.cost.Zl_e = ocp.cost.Zu_e = penalties.quadratic_terminal

    so = ocp.solver_options
    so.tf = n * config.dt_s
    so.nlp_solver_type = "SQP_RTI"
    so.qp_solver = "PARTIAL_CONDENSING_HPIPM"
    # Blocks of two stages: with nine states the Riccati recursion on 20 blocks was the fastest
    # of N/8, N/5, N/4, N/2 and N (docs/decisions/0102).
    so.qp_solver_cond_N = max(1, n // 2)
    so.hpipm_mode = hpipm_mode
    so.hessian_approx = "GAUSS_NEWTON"
    so.integrator_type = "ERK"
    so.sim_method_num_stages = 4
    # Enough RK4 steps per stage that the model stays stable down to rest (planner/integration.py).
    so.sim_method_num_steps = stage_steps(config, params)
    so.qp_solver_iter_max = 50
    # Written into the export directory by the caller, compiled there (no copy from the cwd).
    so.custom_update_filename = ITERATE_C
    so.custom_update_header_filename = ITERATE_H
    so.custom_update_copy = False
    ocp.code_export_directory = str(export)
    return ocp
