"""Planner step time: acados RTI planner against do-mpc (IPOPT) on the same OCP, in one run.

Run: ``python benchmarks/planner.py``. A fusion-free closed loop (≥ 200 planning steps, N = 40) on
a road with a curve and a friction drop; the plant is the planner's model under the first planned
input (fine RK4). Per step we time constraint update + solve + read-out. Prints a JSON line with
``median_step_ms``, ``p99_step_ms``, ``max_step_ms``, ``speedup_vs_dompc`` and, from acados' own
statistics of the fast solver after each step, the median ``acados_solve_ms`` (the whole RTI
iteration), ``acados_qp_ms`` and ``qp_iterations`` (where a QP setting's effect shows first,
docs/decisions/0102); numbers go to docs/performance.md, section "## Planner".

``python benchmarks/planner.py --capture`` instead times our planner's step with the solver's
output captured at the file-descriptor level (as every run does, ``mufusion.sim.solver_output``)
and without, alternating, three runs each, and prints both medians as a JSON line
(docs/performance-tests.md, "Quiet output").

``python benchmarks/planner.py --margins`` instead runs the shipped scenarios (pop-up and turn, all
five configurations, and the pop-up with ``emergency_on_obstacle=true``) and prints, as a JSON
line, how far the solutions the planner accepted went towards the limits of its solution check
(docs/planner.md, "Solution check").
"""

from __future__ import annotations

import dataclasses
import json
import logging
import sys
import time
import warnings

import numpy as np

from mufusion.planner.acados_backend import AcadosBackend
from mufusion.planner.ocp import (
    Param,
    PlannerConfig,
    constraint_expressions,
    lateral_corridor,
    longitudinal_force_bounds_n,
    plan_polygon_radii_n,
    polygon_directions,
    polygon_rows,
    stage_parameters,
)
from mufusion.planner.planner import TractionAdaptivePlanner, rollout
from mufusion.planner.safeguards import judged_rear_rows_n
from mufusion.vehicle.params import TRUCK
from mufusion.vehicle.planner_model import (
    Input,
    State,
    frenet_bicycle_dynamics,
    normal_loads_n,
    rear_cornering_stiffness_n_per_rad,
)

STEPS = 220
DOMPC_STEPS = 60
V_REF = 15.0
LANE = (-0.45, 0.45)  # lane edges shrunk by half the truck width


def curvature(s):
    s = np.asarray(s, dtype=float)
    return np.where((s > 60.0) & (s < 160.0), 1.0 / 80.0, 0.0)


def mu_hat(s):
    return np.where(np.asarray(s, dtype=float) > 100.0, 0.5, 0.8)


def plant_step(x, u, dt=0.1, substeps=10):
    fzr = normal_loads_n((u[1] + u[2]) / TRUCK.mass_kg, TRUCK)[1]
    c_r = rear_cornering_stiffness_n_per_rad(TRUCK, fzr)
    for _ in range(substeps):
        x = rollout(x, u[None], np.array([curvature(x[State.s])]), np.array([c_r]), TRUCK,
                    dt / substeps)[1]
    return x


QP_STATS = {"acados_solve_ms": "time_tot", "acados_qp_ms": "time_qp", "qp_iterations": "qp_iter"}
"""Result key → acados statistic, read after each planning step (times in s, scaled to ms)."""


def run_ours(config: PlannerConfig, qp_stats: dict[str, list[float]] | None = None) -> np.ndarray:
    """Step times [ms]; with ``qp_stats``, acados' statistics of each step appended to it."""
    planner = TractionAdaptivePlanner(TRUCK, config)
    x = np.array([0.0, 0.0, 0.0, 0.0, V_REF, 0.0])
    times = []
    for i in range(STEPS):
        start = time.perf_counter()
        plan = planner.step(x, 0.1 * i, curvature, mu_hat, [], "cruise", V_REF,
                            lane_d_min_m=LANE[0], lane_d_max_m=LANE[1])
        times.append(time.perf_counter() - start)
        if qp_stats is not None and isinstance(planner.backend, AcadosBackend):  # untimed
            fast = planner.backend.solvers()[0].solver
            for key, field in QP_STATS.items():
                value = float(np.ravel(fast.get_stats(field))[-1])
                qp_stats.setdefault(key, []).append(value if key == "qp_iterations"
                                                    else 1e3 * value)
        x = plant_step(x, plan.inputs[0])
    return 1e3 * np.array(times)


def run_dompc(config: PlannerConfig) -> np.ndarray:
    import casadi as ca
    import do_mpc

    n, dt, w = config.horizon_steps, config.dt_s, config.weights
    model = do_mpc.model.Model("discrete")
    x = model.set_variable("_x", "x", shape=(6, 1))
    u = model.set_variable("_u", "u", shape=(3, 1))
    tvp = {name: model.set_variable("_tvp", name) for name in
           ("kappa", "c_r", "r_f", "r_r", "lam_mu", "lam_mu_f", "d_lo", "d_hi")}
    # In Param's order (the heading rows' lane bounds unused: no heading rows here).
    p = ca.vertcat(tvp["kappa"], tvp["c_r"], tvp["r_f"], tvp["r_r"], tvp["lam_mu"], 0.0, 0.0,
                   tvp["lam_mu_f"])

    def f(xx):
        return frenet_bicycle_dynamics(xx, u, tvp["kappa"], tvp["c_r"], TRUCK)

    k1 = f(x)
    k2 = f(x + 0.5 * dt * k1)
    k3 = f(x + 0.5 * dt * k2)
    k4 = f(x + dt * k3)
    model.set_rhs("x", x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4))
    h = constraint_expressions(x, u, p, TRUCK, config.polygon_sides,
                               load_transfer=config.load_transfer)
    rows = polygon_rows(config.polygon_sides, load_transfer=config.load_transfer)
    model.set_expression("h_front", h[: rows.per_axle])
    model.set_expression("h_rear", h[rows.per_axle:])
    model.setup()

    mpc = do_mpc.controller.MPC(model)
    mpc.settings.n_horizon = n
    mpc.settings.t_step = dt
    mpc.settings.store_full_solution = False
    mpc.settings.nlpsol_opts = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes"}
    f_w = w.force_per_kn * 1e-6
    lterm = 0.5 * (w.speed * (x[State.vx] - V_REF) ** 2 + w.lateral_offset * x[State.d] ** 2
                   + w.heading_error * x[State.dpsi] ** 2 + w.lateral_speed * x[State.vy] ** 2
                   + w.yaw_rate * (x[State.psidot] - tvp["kappa"] * V_REF) ** 2
                   + f_w * ca.sumsqr(u))
    mpc.set_objective(lterm=lterm, mterm=0 * x[0])
    mpc.set_rterm(u=np.zeros(3))
    lower, upper = longitudinal_force_bounds_n(TRUCK)
    mpc.bounds["lower", "_u", "u"] = np.array([-1e6, lower[0], lower[1]])
    mpc.bounds["upper", "_u", "u"] = np.array([1e6, upper[0], upper[1]])
    # A two-sided row is a pair of opposite faces, |row| <= upper: one constraint per face.
    sides = (("a", 1.0), ("b", -1.0)) if rows.two_sided else (("", 1.0),)
    for j in range(rows.per_axle):
        for side, sign in sides:
            mpc.set_nl_cons(f"front{j}{side}", sign * model.aux["h_front"][j] - rows.upper,
                            ub=0.0)
            mpc.set_nl_cons(f"rear{j}{side}", sign * model.aux["h_rear"][j] - rows.upper,
                            ub=0.0, soft_constraint=True, penalty_term_cons=w.slack_l2)
    mpc.set_nl_cons("d_hi", x[State.d] - tvp["d_hi"], ub=0.0, soft_constraint=True,
                    penalty_term_cons=w.slack_l2)
    mpc.set_nl_cons("d_lo", tvp["d_lo"] - x[State.d], ub=0.0, soft_constraint=True,
                    penalty_term_cons=w.slack_l2)
    template = mpc.get_tvp_template()
    state = {"x": np.array([0.0, 0.0, 0.0, 0.0, V_REF, 0.0])}

    def tvp_fun(t_now):
        # A typical user's per-stage parameters: predicted s from constant speed.
        x0 = state["x"]
        guess = np.tile(x0, (n + 1, 1))
        guess[:, State.s] = x0[State.s] + np.arange(n + 1) * dt * x0[State.vx]
        stage = stage_parameters(guess, np.zeros((n, 3)), curvature, mu_hat, TRUCK,
                                 config.utilization_factor,
                                 front_axle=config.front_axle_polygon)
        lo, hi = lateral_corridor(guess, [], LANE[0], LANE[1], TRUCK, 0.5)
        for k in range(n + 1):
            kk = min(k, n - 1)
            template["_tvp", k, "kappa"] = stage.p[kk, Param.curvature]
            template["_tvp", k, "c_r"] = stage.p[kk, Param.rear_stiffness]
            template["_tvp", k, "r_f"] = stage.p[kk, Param.radius_front]
            template["_tvp", k, "r_r"] = stage.p[kk, Param.radius_rear]
            template["_tvp", k, "lam_mu"] = stage.p[kk, Param.utilized_friction]
            template["_tvp", k, "lam_mu_f"] = stage.p[kk, Param.utilized_friction_front]
            template["_tvp", k, "d_lo"] = lo[kk]
            template["_tvp", k, "d_hi"] = hi[kk]
        return template

    mpc.set_tvp_fun(tvp_fun)
    mpc.setup()
    xk = state["x"].copy()
    mpc.x0 = xk
    mpc.set_initial_guess()
    times = []
    for _ in range(DOMPC_STEPS):
        state["x"] = xk
        start = time.perf_counter()
        u0 = np.asarray(mpc.make_step(xk.reshape(-1, 1))).ravel()
        times.append(time.perf_counter() - start)
        xk = plant_step(xk, u0)
    return 1e3 * np.array(times)


def solution_margins() -> dict[str, float]:
    """Largest excursions of accepted solutions towards the solution check's limits."""
    import mufusion.planner.rti as rti_module
    from mufusion.scenarios import load_scenario
    from mufusion.scenarios.runner import run_scenario

    worst = {"front_polygon_excess": -np.inf, "rear_polygon_excess": -np.inf,
             "force_bound_excess": -np.inf, "corridor_excess_m": -np.inf,
             "abs_heading_error_rad": 0.0, "min_speed_mps": np.inf}
    judge = rti_module.judge_solution

    def measuring_check(xs, us, stage, d_lo, d_hi, params, n_sides, limits, *, load_transfer):
        judged = judge(xs, us, stage, d_lo, d_hi, params, n_sides, limits,
                       load_transfer=load_transfer)
        if judged[0].value != "none":
            return judged
        normals, ratio = polygon_directions(n_sides)
        # The radii the plan was solved with (its own loads with load transfer).
        radius_front, radius_rear = plan_polygon_radii_n(us, stage, params, load_transfer)
        front = normals @ np.stack([us[:, Input.fxf], us[:, Input.fyf]])
        rear = judged_rear_rows_n(xs, us, stage, params, normals, load_transfer=load_transfer)
        lower, upper = longitudinal_force_bounds_n(params)
        fx = us[:, [Input.fxf, Input.fxr]]
        bound = np.maximum(lower - fx, fx - upper) / np.maximum(np.abs(lower), np.abs(upper))
        d = xs[1:, State.d]
        for key, value in (
            ("front_polygon_excess", (front / radius_front - ratio).max()),
            ("rear_polygon_excess", (rear / radius_rear - ratio).max()),
            ("force_bound_excess", bound.max()),
            ("corridor_excess_m", np.maximum(d_lo - d, d - d_hi).max()),
            ("abs_heading_error_rad", np.abs(xs[:, State.dpsi]).max()),
        ):
            worst[key] = max(worst[key], float(value))
        worst["min_speed_mps"] = min(worst["min_speed_mps"], float(xs[:, State.vx].min()))
        return judged

    rti_module.judge_solution = measuring_check
    try:
        runs = [(name, [], c) for name in ("popup", "turn")
                for c in ("GT", "L", "P", "F", "F-safe")]
        runs.append(("popup", ["emergency_on_obstacle=true"], "F"))
        for name, overrides, configuration in runs:
            run_scenario(load_scenario(name, overrides), configuration)
    finally:
        rti_module.judge_solution = judge
    return {key: round(value, 3) for key, value in worst.items()}


def capture_cost(config: PlannerConfig, repeats: int = 3) -> dict[str, float]:
    """Median and p99 planner step [ms] with and without the run's output capture."""
    from mufusion.sim.solver_output import captured_output

    plain, captured, messages = [], [], 0
    for _ in range(repeats):  # alternating, so that a busy spell of the machine hits both
        plain.append(run_ours(config))
        with captured_output() as lines:
            captured.append(run_ours(config))
        messages += len(lines)
    a, b = np.concatenate(plain), np.concatenate(captured)
    return {
        "median_step_ms": round(float(np.median(a)), 3),
        "median_step_ms_captured": round(float(np.median(b)), 3),
        "p99_step_ms": round(float(np.percentile(a, 99)), 3),
        "p99_step_ms_captured": round(float(np.percentile(b, 99)), 3),
        "steps_each": int(a.size),
        "messages_captured": messages,
    }


def main() -> None:
    logging.basicConfig(level=logging.WARNING)
    warnings.filterwarnings("ignore")
    if "--margins" in sys.argv[1:]:
        print(json.dumps(solution_margins()))
        return
    config = PlannerConfig(lane_d_min_m=LANE[0], lane_d_max_m=LANE[1], use_sampling=True)
    if "--capture" in sys.argv[1:]:
        print(json.dumps(capture_cost(config)))
        return
    if "--torque-lag" in sys.argv[1:]:
        # The OCP with the longitudinal forces as lagging states (9 states) against the
        # default (7), alternating so that a busy machine weighs on both alike.
        runs: dict[bool, list[np.ndarray]] = {False: [], True: []}
        for _ in range(3):
            for lag in (False, True):
                runs[lag].append(run_ours(dataclasses.replace(config, torque_lag=lag)))
        off, on = (np.concatenate(runs[lag]) for lag in (False, True))
        print(json.dumps({"median_step_ms": round(float(np.median(off)), 3),
                          "torque_lag_median_step_ms": round(float(np.median(on)), 3),
                          "p99_step_ms": round(float(np.percentile(off, 99)), 3),
                          "torque_lag_p99_step_ms": round(float(np.percentile(on, 99)), 3),
                          "ratio": round(float(np.median(on) / np.median(off)), 2)}))
        return
    qp_stats: dict[str, list[float]] = {}
    ours = run_ours(config, qp_stats)
    theirs = run_dompc(config)
    result = {
        "median_step_ms": round(float(np.median(ours)), 3),
        "p99_step_ms": round(float(np.percentile(ours, 99)), 3),
        "max_step_ms": round(float(ours.max()), 3),
        "dompc_median_step_ms": round(float(np.median(theirs)), 3),
        "dompc_p99_step_ms": round(float(np.percentile(theirs, 99)), 3),
        "speedup_vs_dompc": round(float(np.median(theirs) / np.median(ours)), 1),
        **{key: round(float(np.median(values)), 3) for key, values in qp_stats.items()},
        "steps": STEPS,
        "dompc_steps": DOMPC_STEPS,
        "horizon_steps": config.horizon_steps,
    }
    print(json.dumps(result))


if __name__ == "__main__":
    main()
