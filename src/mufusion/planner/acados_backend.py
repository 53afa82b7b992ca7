"""acados SQP_RTI backend: code generated once per problem hash and cached on disk."""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import logging
from importlib import resources
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from mufusion.planner.acados_loader import (
    build_lock,
    cache_dir,
    load_acados_template,
)
from mufusion.planner.front_force import front_force_rate_bound_n_per_s
from mufusion.planner.integration import stage_steps
from mufusion.planner.ocp import (
    HEADING_ROWS,
    MAX_SPEED_MPS,
    N_PARAMS,
    POLYGON_ROW_LOWER_BOUND,
    Param,
    PlannerConfig,
    constraint_expressions,
    longitudinal_force_bounds_n,
    ocp_rear_stiffness,
    polygon_rows,
    slack_penalties,
)
from mufusion.planner.ocp_state import (
    augmented_problem,
    force_rates,
    ocp_state,
    plan_from_augmented,
    tire_forces,
)
from mufusion.planner.stability import state_bounds
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    Input,
    State,
    frenet_bicycle_dynamics,
)

_log = logging.getLogger(__name__)
_FORMAT_VERSION = "13"

# The problem's and the iterate's batch access compiled into the solver (acados' custom-update
# hook): one call writes the whole problem and guess, one reads the solution, where the
# wrapper's set/get take ≈ 300 calls per solve. The layout is documented in the C template.
_ITERATE_C = "mufusion_iterate.c"
_ITERATE_H = "mufusion_iterate.h"
# The sources are templates for ``str.format`` (``{name}``, ``{upper}``; literal braces doubled),
# package resources: their text is part of the problem hash, so an edit regenerates the solvers.
_TEMPLATES = resources.files("mufusion.planner") / "acados_c"
_ITERATE_HEADER = (_TEMPLATES / "mufusion_iterate.h.in").read_text(encoding="utf-8")
_ITERATE_SOURCE = (_TEMPLATES / "mufusion_iterate.c.in").read_text(encoding="utf-8")

_WRITE, _READ = 1.0, 2.0  # the modes of _ITERATE_SOURCE

FAST_HPIPM_MODE = "SPEED"
"""HPIPM's mode for every solve: about half the QP time of ``BALANCE`` on this problem."""
ROBUST_HPIPM_MODE = "BALANCE"
"""HPIPM's mode for a solve that failed in :data:`FAST_HPIPM_MODE`. ``SPEED`` skips safeguards
of the interior-point iteration and at the handling limit returns NaN (acados status 4) on
QPs that ``BALANCE`` solves: on the published turn grid it failed 173 planning steps of GT in
variants the oracle calls feasible, and five failures in a row stopped the truck before the
curve (docs/decisions/0019, "A QP that fails at the limit")."""


def problem_hash(params: VehicleParams, config: PlannerConfig,
                 hpipm_mode: str = FAST_HPIPM_MODE) -> str:
    """Hash of everything that shapes the generated code."""
    text = json.dumps(
        {
            "v": _FORMAT_VERSION,
            "params": repr(params),
            "N": config.horizon_steps,
            "dt": config.dt_s,
            "sides": config.polygon_sides,
            "hpipm_mode": hpipm_mode,
            "steering_rate_limit": config.steering_rate_limit,
            "load_transfer": config.load_transfer,
            "torque_lag": config.torque_lag,
            "stability_envelope": config.stability_envelope, "heading_rows": config.heading_rows,
            "speed_ceiling": config.speed_ceiling,
            # The parameter vector's layout (planner/ocp.py's Param).
            "n_params": N_PARAMS,
            "utilization": config.utilization_factor,
            # The slack penalties are written into the generated problem (ocp.cost.zl …).
            "slack_penalties": [config.weights.slack_l1, config.weights.slack_l2,
                                config.weights.speed_ceiling_l1, config.weights.speed_ceiling_l2],
            "rk4_steps": stage_steps(config, params),
            "iterate": _ITERATE_HEADER + _ITERATE_SOURCE,
        },
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class _GeneratedSolver:
    """One generated acados solver (one HPIPM mode) and the problem data last written to it."""

    def __init__(
        self, at: ModuleType, params: VehicleParams, config: PlannerConfig, hpipm_mode: str
    ) -> None:
        n = config.horizon_steps
        digest = problem_hash(params, config, hpipm_mode)
        export = cache_dir() / f"tamp_{digest}"
        name = f"tamp_{digest}"
        lib = export / f"libacados_ocp_solver_{name}.so"
        with build_lock(export):  # another process may be building this very solver
            if not lib.exists():
                # The problem description is needed only to generate the code (the hash names it).
                _log.info("generating and compiling the acados solver in %s", export)
                ocp = _describe(at, params, config, name, export, hpipm_mode)
                at.AcadosOcpSolver.generate(ocp, json_file=str(export / "ocp.json"))
                (export / _ITERATE_H).write_text(_ITERATE_HEADER.format(name=name))
                (export / _ITERATE_C).write_text(
                    _ITERATE_SOURCE.format(name=name, upper=name.upper()))
                # acados' ctypes wrapper, not its Cython one: each call below is one C call
                # either way, and the Cython module's 1.9 MB of C took 6 of a build's 8.5 s.
                at.AcadosOcpSolver.build(str(export), with_cython=False, verbose=False)
        with contextlib.redirect_stdout(io.StringIO()):  # it prints whether OpenMP is in
            self.solver = at.AcadosOcpSolver(None, json_file=str(export / "ocp.json"),
                                             build=False, generate=False, verbose=False)
        self.n = n
        self.layout = ocp_state(config, params)
        self.params, self.config = params, config
        self._generated_lbu = np.tile(_input_bounds(params, config)[0], (n, 1))
        self._lbu_changed = False

    def solve(
        self,
        x0: np.ndarray,
        guess_x: np.ndarray,
        guess_u: np.ndarray,
        p: np.ndarray,
        yref: np.ndarray,
        weights: np.ndarray,
        lbx: np.ndarray,
        ubx: np.ndarray,
        ubu: np.ndarray,
        lbu: np.ndarray,
    ) -> tuple[int, np.ndarray, np.ndarray]:
        """Write the problem and the guess in one call, run one RTI step, read the plan.

        Takes and returns the planner's states ``(N+1, 6)`` and forces ``(N, 3)``; with the
        force states (planner/ocp_state.py) the OCP's state is formed and dropped here."""
        n = self.n
        # The lower bounds as generated need no write; after a solve that changed them, one
        # more restores them.
        changed = not np.array_equal(lbu, self._generated_lbu)
        write_lbu = changed or self._lbu_changed
        self._lbu_changed = changed
        if self.layout.augmented:
            x0, guess_x, guess_u = augmented_problem(
                x0, guess_x, guess_u, p, self.params, self.config, self.layout)
        w_stage = np.diag(weights[: N_STATES + N_INPUTS])
        # The layout of _ITERATE_SOURCE's mode 1; the terminal stage takes the last stage's
        # parameters, the reference's and weights' state part and the lateral bound only.
        problem = (
            _WRITE, x0, p[:n], p[n - 1], yref[:n], yref[n, :N_STATES],
            np.broadcast_to(w_stage.ravel(order="F"), (n, w_stage.size)),
            w_stage[:N_STATES, :N_STATES].ravel(order="F"),
            np.broadcast_to(ubu, (n, ubu.size)), [float(write_lbu)], lbu,
            lbx[:-1], lbx[-1, :1], ubx[:-1], ubx[-1, :1],
        )
        data = np.concatenate([np.ravel(part) for part in (*problem, guess_x, guess_u)])
        self._exchange(data)
        status = self.solver.solve()
        plan = np.empty(1 + guess_x.size + guess_u.size)
        plan[0] = _READ
        self._exchange(plan)
        split = 1 + guess_x.size
        xs = plan[1:split].reshape(guess_x.shape)
        us = plan[split:].reshape(guess_u.shape)
        if self.layout.augmented:
            xs, us = plan_from_augmented(xs, us, self.layout)
        return int(status), xs, us

    def _exchange(self, data: np.ndarray) -> None:
        """Write the problem and the guess (``data[0] = 1``) or read the plan (``2``) in one
        call (see ``_ITERATE_SOURCE``); a buffer of another layout is refused untouched."""
        size = data.size
        self.solver.custom_update(data)
        if data[0] != size:
            raise RuntimeError(
                f"the solver's problem and iterate have another layout than the planner's "
                f"({size} values)"
            )

    def reset(self) -> None:
        """Zero every iterate (primal, dual, slacks) and the QP solver's memory."""
        self.solver.reset(1)


class AcadosBackend:
    """One RTI iteration per call on the shared OCP description.

    Each solve runs HPIPM in :data:`FAST_HPIPM_MODE`; a solve that fails there (a status other
    than 0 or 2) is repeated once, on the same data, by a second generated solver in
    :data:`ROBUST_HPIPM_MODE` (``robust_retry=False``: no second solver). ``robust_retries``
    counts those repeats; ``last_solve_retried`` says whether the latest solve needed one.
    """

    def __init__(
        self, params: VehicleParams, config: PlannerConfig, *, robust_retry: bool = True
    ) -> None:
        at = load_acados_template()
        self.params, self.config = params, config
        # The drive bound varies with the mode, the front braking's with the stages' friction.
        self._lbu, self._ubu = _input_bounds(params, config)
        self._fast = _GeneratedSolver(at, params, config, FAST_HPIPM_MODE)
        self._robust = (
            _GeneratedSolver(at, params, config, ROBUST_HPIPM_MODE) if robust_retry else None
        )
        self.robust_retries = 0
        self.last_solve_retried = False

    def solvers(self) -> tuple[_GeneratedSolver, ...]:
        """The generated solvers, fast mode first (for statistics and instrumentation)."""
        return (self._fast,) if self._robust is None else (self._fast, self._robust)

    def solve(
        self,
        x0: np.ndarray,
        guess_x: np.ndarray,
        guess_u: np.ndarray,
        p: np.ndarray,
        yref: np.ndarray,
        weights: np.ndarray,
        d_lo: np.ndarray,
        d_hi: np.ndarray,
        min_speed_mps: float,
        max_drive_force_n: float | None = None,
        max_front_brake_force_n: np.ndarray | None = None,
        max_speed_mps: np.ndarray | None = None,
    ) -> tuple[int, np.ndarray, np.ndarray]:
        """One RTI step; returns ``(status, states (N+1, 6), inputs (N, 3))``.

        ``max_drive_force_n`` lowers the rear drive-force bound for this solve (``None``: the
        actuator's bound); ``max_front_brake_force_n`` ``(N,)`` [N, ≥ 0, ``inf``: none] raises
        the front braking's bound per stage; ``max_speed_mps`` ``(N,)`` [m/s] is the soft speed
        ceiling of stages 1 … N (``None``: none)."""
        n = self.config.horizon_steps
        ubu = self._ubu.copy()
        if max_drive_force_n is not None:
            ubu[-1] = min(ubu[-1], max_drive_force_n)
        lbu = np.tile(self._lbu, (n, 1))
        if max_front_brake_force_n is not None:
            # F_xf is the second-last bounded input (F_xr last, see _input_bounds).
            lbu[:, -2] = np.maximum(lbu[:, -2], -np.asarray(max_front_brake_force_n, float))
        lbx, ubx = state_bounds(d_lo, d_hi, min_speed_mps, guess_x, p, self.config,
                                max_speed_mps)
        args = (x0, guess_x, guess_u, p, yref, weights, lbx, ubx, ubu, lbu)
        self.last_solve_retried = False
        status, xs, us = self._fast.solve(*args)
        if status in (0, 2) or self._robust is None:
            return status, xs, us
        # The failed QP can leave NaN multipliers in the fast solver; its next solve starts
        # clean, as after any failure (see reset).
        self._fast.reset()
        self.robust_retries += 1
        self.last_solve_retried = True
        return self._robust.solve(*args)

    def reset(self) -> None:
        """Zero every iterate (primal, dual, slacks) and the QP solver's memory.

        After a failed QP the multipliers can hold NaN; ``solve`` overwrites x and u from the
        guess but not the multipliers, so without this every later RTI step fails as well.
        """
        self._fast.reset()
        if self._robust is not None:
            self._robust.reset()


def _input_bounds(params: VehicleParams, config: PlannerConfig) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of the bounded inputs: ``(F_xf, F_xr)``, led by the front force's rate with the
    steering's rate limit (``F_xr`` last either way)."""
    lower, upper = longitudinal_force_bounds_n(params)
    if config.steering_rate_limit:
        rate = front_force_rate_bound_n_per_s(params, config)
        lower, upper = np.concatenate([[-rate], lower]), np.concatenate([[rate], upper])
    return np.array(lower, dtype=float), np.array(upper, dtype=float)


def _describe(
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
    f = frenet_bicycle_dynamics(x[:N_STATES], forces, p[Param.curvature],
                                ocp_rear_stiffness(p, forces, params, config.load_transfer), params)
    f = ca.vertcat(f, *force_rates(x, u, layout))
    model.f_expl_expr = f
    model.f_impl_expr = model.xdot - f
    model.con_h_expr = constraint_expressions(x[:N_STATES], forces, p, params, ns,
                                             load_transfer=config.load_transfer,
                                             heading=config.heading_rows)
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
    ocp.constraints.lbu, ocp.constraints.ubu = _input_bounds(params, config)
    rows = polygon_rows(ns, load_transfer=config.load_transfer)
    heading = HEADING_ROWS * int(config.heading_rows)
    ocp.constraints.lh = np.r_[np.full(rows.count, rows.lower), [POLYGON_ROW_LOWER_BOUND] * heading]
    ocp.constraints.uh = np.r_[np.full(rows.count, rows.upper), np.zeros(heading)]
    # Front forces are inputs and always have a feasible choice (hard); the rear lateral force
    # follows the state, which at stage 0 is fixed, so the rear polygon is soft (and the heading
    # rows). acados orders a stage's slacks as the soft bounds first (d, v_x, the envelope's),
    # then the soft h rows: SlackPenalties' layout; zl prices the lower sides, zu the upper.
    ocp.constraints.idxsh = np.arange(rows.per_axle, rows.count + heading)
    penalties = slack_penalties(config.weights, rows.per_axle, heading, config.speed_ceiling,
                                envelope)
    ocp.cost.zl, ocp.cost.zu = penalties.linear_stage, penalties.linear_stage_upper
    ocp.cost.Zl, ocp.cost.Zu = penalties.quadratic_stage, penalties.quadratic_stage_upper
    ocp.cost.zl_e = ocp.cost.zu_e = penalties.linear_terminal
    ocp.cost.Zl_e = ocp.cost.Zu_e = penalties.quadratic_terminal

    so = ocp.solver_options
    so.tf = n * config.dt_s
    so.nlp_solver_type = "SQP_RTI"
    so.qp_solver = "PARTIAL_CONDENSING_HPIPM"
    so.qp_solver_cond_N = max(1, n // 4)
    so.hpipm_mode = hpipm_mode
    so.hessian_approx = "GAUSS_NEWTON"
    so.integrator_type = "ERK"
    so.sim_method_num_stages = 4
    # Enough RK4 steps per stage that the model stays stable down to rest (planner/integration.py).
    so.sim_method_num_steps = stage_steps(config, params)
    so.qp_solver_iter_max = 50
    # Written into the export directory by the caller, compiled there (no copy from the cwd).
    so.custom_update_filename = _ITERATE_C
    so.custom_update_header_filename = _ITERATE_H
    so.custom_update_copy = False
    ocp.code_export_directory = str(export)
    return ocp
