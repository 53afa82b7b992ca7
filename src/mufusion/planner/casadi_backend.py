"""Reference backend: the same OCP description solved to convergence by CasADi + IPOPT.

Used in tests as the reference for the real-time iteration and as the fallback where acados has no
wheel. The objective matches acados' conventions: stage cost and slack penalties are multiplied by
``dt``, the terminal cost is not; least-squares terms carry the factor 1/2.
"""

from __future__ import annotations

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
    constraint_expressions,
    longitudinal_force_bounds_n,
    ocp_rear_stiffness,
    polygon_rows,
    slack_penalties,
)
from mufusion.planner.ocp_state import (
    augmented_problem,
    cost_forces,
    force_rates,
    ocp_rear_force_limit,
    ocp_state,
    plan_from_augmented,
    tire_forces,
)
from mufusion.planner.penalties import corridor_slack_scale
from mufusion.planner.stability import state_bounds
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import N_INPUTS, N_STATES, Input, State, frenet_bicycle_dynamics


class CasadiBackend:
    """Multiple shooting with RK4 steps per stage (as acados' ERK), solved by IPOPT."""

    last_solve_retried = False  # IPOPT is the robust solver: nothing to retry with

    def __init__(self, params: VehicleParams, config: PlannerConfig) -> None:
        import casadi as ca

        self.params, self.config = params, config
        n, ns, dt = config.horizon_steps, config.polygon_sides, config.dt_s
        rows = polygon_rows(ns, load_transfer=config.load_transfer)
        nh = HEADING_ROWS * int(config.heading_rows)
        ne = 2 * int(config.stability_envelope)  # soft ψ̇ and v_y bounds, stages 1..N-1
        pen = slack_penalties(config.weights, rows.per_axle, nh, config.speed_ceiling, ne)
        lead = corridor_slack_scale(n, config.lane_slack_lead)
        nv = (n - 1) * int(config.speed_ceiling)  # soft v_x bounds, stages 1..N-1 (as acados)
        layout = ocp_state(config, params)
        nx = layout.nx
        x = ca.SX.sym("x", nx)
        u = ca.SX.sym("u", N_INPUTS)
        p = ca.SX.sym("p", N_PARAMS)

        def forces(xx, uu):
            # The forces that are states (planner/ocp_state.py), the inputs' otherwise.
            return tire_forces(xx, uu, layout)

        def f(xx):
            fs = forces(xx, u)
            dx = frenet_bicycle_dynamics(xx[:N_STATES], fs, p[Param.curvature], ocp_rear_stiffness(
                p, fs, params, config.load_transfer), params,
                rear_force_limit_n=ocp_rear_force_limit(p, fs, params, config))
            return ca.vertcat(dx, *force_rates(xx, u, layout))

        # As acados' ERK: stage_steps RK4 steps per stage (planner/integration.py).
        h_step = dt / stage_steps(config, params)
        xk = x
        for _ in range(stage_steps(config, params)):
            k1 = f(xk)
            k2 = f(xk + 0.5 * h_step * k1)
            k3 = f(xk + 0.5 * h_step * k2)
            k4 = f(xk + h_step * k3)
            xk = xk + h_step / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        step = ca.Function("step", [x, u, p], [xk])
        h = ca.Function("h", [x, u, p],
                        [constraint_expressions(x[:N_STATES], forces(x, u), p, params, ns,
                                               load_transfer=config.load_transfer,
                                               heading=config.heading_rows,
                                               rear_force_limit_n=ocp_rear_force_limit(
                                                   p, forces(x, u), params, config))])

        ny = N_STATES + N_INPUTS
        X = ca.SX.sym("X", nx, n + 1)
        U = ca.SX.sym("U", N_INPUTS, n)
        S_lo = ca.SX.sym("S_lo", n)  # d-bound slacks, stages 1..N
        S_hi = ca.SX.sym("S_hi", n)
        S_vlo = ca.SX.sym("S_vlo", nv)  # v_x-bound slacks, with the speed ceiling
        S_vhi = ca.SX.sym("S_vhi", nv)
        # Rear-polygon slacks, stages 0..N-1, on each row's lower and upper side (as acados).
        S_rl = ca.SX.sym("S_rl", rows.per_axle, n)
        S_ru = ca.SX.sym("S_ru", rows.per_axle, n)
        S_hl = ca.SX.sym("S_hl", nh, n)  # heading rows' slacks, likewise
        S_hu = ca.SX.sym("S_hu", nh, n)
        S_el = ca.SX.sym("S_el", ne, n - 1)  # the stability envelope's slacks, stages 1..N-1
        S_eu = ca.SX.sym("S_eu", ne, n - 1)
        P = ca.SX.sym("P", N_PARAMS, n)
        YREF = ca.SX.sym("YREF", ny, n + 1)
        WD = ca.SX.sym("WD", ny)
        X0 = ca.SX.sym("X0", nx)
        DLO = ca.SX.sym("DLO", n)
        DHI = ca.SX.sym("DHI", n)
        VLO = ca.SX.sym("VLO", nv)
        VHI = ca.SX.sym("VHI", nv)
        ELO = ca.SX.sym("ELO", ne, n - 1)  # the envelope's bounds on (ψ̇, v_y), stages 1..N-1
        EHI = ca.SX.sym("EHI", ne, n - 1)

        def slack_cost(s, linear, quadratic):
            return ca.sum1(ca.DM(linear) * s + 0.5 * ca.DM(quadratic) * s**2)

        corridor, speed, rear, heading = pen.corridor, pen.speed, pen.rear_polygon, pen.heading
        envelope = pen.envelope
        cost: Any = 0
        g, lbg, ubg = [X[:, 0] - X0], [0.0] * nx, [0.0] * nx
        for k in range(n):
            r = ca.vertcat(X[:N_STATES, k], cost_forces(X[:, k], U[:, k], layout)) - YREF[:, k]
            cost += dt * 0.5 * ca.sum1(WD * r**2)
            for slack in (S_rl[:, k], S_ru[:, k]):
                cost += dt * slack_cost(slack, pen.linear_stage[rear], pen.quadratic_stage[rear])
            for slack in (S_hl[:, k], S_hu[:, k]) if nh else ():
                cost += dt * slack_cost(slack, pen.linear_stage[heading],
                                        pen.quadratic_stage[heading])
            g.append(X[:, k + 1] - step(X[:, k], U[:, k], P[:, k]))
            lbg += [0.0] * nx
            ubg += [0.0] * nx
            hk = h(X[:, k], U[:, k], P[:, k])
            m = rows.per_axle
            g.append(hk[:m])
            lbg += [rows.lower] * m
            ubg += [rows.upper] * m
            g.append(hk[m:2 * m] + S_rl[:, k])
            lbg += [rows.lower] * m
            ubg += [np.inf] * m
            g.append(hk[m:2 * m] - S_ru[:, k])
            lbg += [-np.inf] * m
            ubg += [rows.upper] * m
            if nh:
                g += [hk[2 * m:] + S_hl[:, k], hk[2 * m:] - S_hu[:, k]]
                lbg += [POLYGON_ROW_LOWER_BOUND] * nh + [-np.inf] * nh
                ubg += [np.inf] * nh + [0.0] * nh
            # d bounds at stage k+1 (softened); terminal slacks carry no dt factor.
            if k < n - 1:  # each stage's price at its scale (penalties.corridor_slack_scale)
                scale = dt * lead[k]
                z1, z2 = pen.linear_stage[corridor], pen.quadratic_stage[corridor]
            else:
                scale, z1, z2 = 1.0, pen.linear_terminal, pen.quadratic_terminal
            cost += scale * (slack_cost(S_lo[k], z1, z2) + slack_cost(S_hi[k], z1, z2))
            g.append(X[State.d, k + 1] + S_lo[k] - DLO[k])
            lbg.append(0.0)
            ubg.append(np.inf)
            g.append(X[State.d, k + 1] - S_hi[k] - DHI[k])
            lbg.append(-np.inf)
            ubg.append(0.0)
            if k < nv:  # v_x bounds at stage k+1, soft as in the acados description
                cost += dt * (
                    slack_cost(S_vlo[k], pen.linear_stage[speed], pen.quadratic_stage[speed])
                    + slack_cost(S_vhi[k], pen.linear_stage_upper[speed],
                                 pen.quadratic_stage_upper[speed]))
                g += [X[State.vx, k + 1] + S_vlo[k] - VLO[k],
                      X[State.vx, k + 1] - S_vhi[k] - VHI[k]]
                lbg += [0.0, -np.inf]
                ubg += [np.inf, 0.0]
            if ne and k < n - 1:  # ψ̇ and v_y at stage k+1, soft as in the acados description
                xe = ca.vertcat(X[State.psidot, k + 1], X[State.vy, k + 1])
                cost += dt * (
                    slack_cost(S_el[:, k], pen.linear_stage[envelope],
                               pen.quadratic_stage[envelope])
                    + slack_cost(S_eu[:, k], pen.linear_stage_upper[envelope],
                                 pen.quadratic_stage_upper[envelope]))
                g += [xe + S_el[:, k] - ELO[:, k], xe - S_eu[:, k] - EHI[:, k]]
                lbg += [0.0] * ne + [-np.inf] * ne
                ubg += [np.inf] * ne + [0.0] * ne
        r_e = X[:N_STATES, n] - YREF[:N_STATES, n]
        cost += 0.5 * ca.sum1(WD[:N_STATES] * r_e**2)

        self._nx, self._layout = nx, layout
        self._n_x = nx * (n + 1)
        self._n_u = N_INPUTS * n
        z = ca.vertcat(ca.vec(X), ca.vec(U), S_lo, S_hi, S_vlo, S_vhi, ca.vec(S_rl),
                       ca.vec(S_ru), ca.vec(S_hl), ca.vec(S_hu), ca.vec(S_el), ca.vec(S_eu))
        par = ca.vertcat(ca.vec(P), ca.vec(YREF), WD, X0, DLO, DHI, VLO, VHI, ca.vec(ELO),
                         ca.vec(EHI))
        self._lbg, self._ubg = np.array(lbg), np.array(ubg)
        self._n_z = z.shape[0]
        self._solver = ca.nlpsol(
            "tamp_ref", "ipopt", {"x": z, "p": par, "f": cost, "g": ca.vertcat(*g)},
            {"ipopt.print_level": 0, "print_time": False, "ipopt.tol": 1e-9,
             "ipopt.max_iter": 300, "ipopt.sb": "yes"},
        )
        lower, upper = longitudinal_force_bounds_n(params)
        rate = (front_force_rate_bound_n_per_s(params, config) if config.steering_rate_limit
                else np.inf)
        lbu = np.tile([-rate, lower[0], lower[1]], (n, 1))
        ubu = np.tile([rate, upper[0], upper[1]], (n, 1))
        self._lbu, self._ubu = lbu, ubu
        self._n_slack = 2 * n + 2 * nv + 2 * (rows.per_axle + nh) * n + 2 * ne * (n - 1)
        self._soft_speed = bool(nv)

    def solve(self, x0, guess_x, guess_u, p, yref, weights, d_lo, d_hi, min_speed_mps,
              max_drive_force_n=None, max_front_brake_force_n=None, max_speed_mps=None):
        """Solve to convergence; returns ``(status, states (N+1, 6), inputs (N, 3))``."""
        n = self.config.horizon_steps
        ubu = self._ubu.copy()
        if max_drive_force_n is not None:
            ubu[:, 2] = np.minimum(ubu[:, 2], max_drive_force_n)
        lbu = self._lbu.copy()
        if max_front_brake_force_n is not None:
            brake = np.asarray(max_front_brake_force_n, dtype=float)
            lbu[:, Input.fxf] = np.maximum(lbu[:, Input.fxf], -brake)
        guess_planner_x = guess_x  # the envelope's speeds: the planner's own states
        if self._layout.augmented:
            x0, guess_x, guess_u = augmented_problem(
                x0, guess_x, guess_u, p, self.params, self.config, self._layout)
        lbx_x = np.full((n + 1, self._nx), -np.inf)
        ubx_x = np.full((n + 1, self._nx), np.inf)
        v_hi = np.full(n - 1, MAX_SPEED_MPS)
        if max_speed_mps is not None:
            v_hi = np.minimum(v_hi, np.asarray(max_speed_mps, dtype=float)[: n - 1])
        if not self._soft_speed:
            # vx bounds at stages 1..N-1 are hard, as in the acados description.
            lbx_x[1:n, State.vx] = min_speed_mps
            ubx_x[1:n, State.vx] = v_hi
        lbz = np.concatenate([lbx_x.ravel(), lbu.ravel(), np.zeros(self._n_slack)])
        ubz = np.concatenate([ubx_x.ravel(), ubu.ravel(), np.full(self._n_slack, np.inf)])
        z0 = np.concatenate([guess_x.ravel(), guess_u.ravel(), np.zeros(self._n_slack)])
        soft = (np.full(n - 1, min_speed_mps), v_hi) if self._soft_speed else ()
        envelope = ()
        if self.config.stability_envelope:
            # Stages 1..N-1 of the bounds the acados backend writes (planner/stability.py), in
            # the order ca.vec lays out ELO and EHI (ne, N-1): stage by stage.
            lo, hi = state_bounds(d_lo, d_hi, min_speed_mps, guess_planner_x, p, self.config)
            envelope = (lo[: n - 1, 2:].ravel(), hi[: n - 1, 2:].ravel())
        par = np.concatenate([p.ravel(), yref.ravel(), weights, x0, d_lo, d_hi, *soft,
                              *envelope])
        sol = self._solver(x0=z0, p=par, lbx=lbz, ubx=ubz, lbg=self._lbg, ubg=self._ubg)
        ok = bool(self._solver.stats()["success"])
        z = np.asarray(sol["x"]).ravel()
        xs = z[: self._n_x].reshape(n + 1, self._nx)
        us = z[self._n_x : self._n_x + self._n_u].reshape(n, N_INPUTS)
        if self._layout.augmented:
            xs, us = plan_from_augmented(xs, us, self._layout)
        return (0 if ok else 1), xs, us

    def reset(self) -> None:
        """Nothing to forget: every solve starts from the guess it is given."""


__all__ = ["CasadiBackend", "Input"]
