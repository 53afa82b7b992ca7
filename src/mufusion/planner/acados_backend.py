"""acados SQP_RTI backend: code generated once per problem hash and cached on disk."""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import io
import json
import logging
import os
from importlib import resources, util
from pathlib import Path
from types import ModuleType

import numpy as np

from mufusion.planner.acados_loader import (
    build_lock,
    cache_dir,
    load_acados_template,
)
from mufusion.planner.acados_ocp import (
    ITERATE_C,
    ITERATE_H,
    describe,
    input_bounds,
    stage_slack_penalties,
)
from mufusion.planner.integration import stage_steps
from mufusion.planner.ocp import N_PARAMS, PlannerConfig
from mufusion.planner.ocp_state import augmented_problem, ocp_state, plan_from_augmented
from mufusion.planner.penalties import corridor_slack_scale
from mufusion.planner.stability import state_bounds
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import N_INPUTS, N_STATES

_log = logging.getLogger(__name__)
_FORMAT_VERSION = "14"

# The problem's and the iterate's batch access compiled into the solver (acados' custom-update
# hook): one call writes the whole problem and guess, one reads the solution, where the
# wrapper's set/get take ≈ 300 calls per solve. The layout is documented in the C template.
# The sources are templates for ``str.format`` (``{name}``, ``{upper}``; literal braces doubled),
# package resources: their text is part of the problem hash, so an edit regenerates the solvers.
_TEMPLATES = resources.files("mufusion.planner") / "acados_c"
_ITERATE_HEADER = (_TEMPLATES / "mufusion_iterate.h.in").read_text(encoding="utf-8")
_ITERATE_SOURCE = (_TEMPLATES / "mufusion_iterate.c.in").read_text(encoding="utf-8")

_WRITE, _READ = 1.0, 2.0  # the modes of _ITERATE_SOURCE

FAST_HPIPM_MODE = "SPEED_ABS"
"""HPIPM's mode for every solve. ``SPEED_ABS`` stops on the duality measure without computing the
residuals: on today's OCP (nine states, load-transfer rows) 11 instead of 14 interior-point
iterations and two thirds of ``SPEED``'s QP time, and at the handling limit it fails fewer QPs than
``SPEED`` did (docs/decisions/0102)."""
ROBUST_HPIPM_MODE = "BALANCE"
"""HPIPM's mode for a solve that failed in :data:`FAST_HPIPM_MODE`. ``SPEED`` skipped safeguards
of the interior-point iteration and at the handling limit returned NaN (acados status 4) on
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
            "rear_saturation": config.rear_saturation,
            "speed_ceiling": config.speed_ceiling,
            # The parameter vector's layout (planner/ocp.py's Param).
            "n_params": N_PARAMS,
            "utilization": config.utilization_factor,
            # The slack penalties are written into the generated problem (ocp.cost.zl …).
            "slack_penalties": [config.weights.slack_l1, config.weights.slack_l2,
                                config.weights.speed_ceiling_l1, config.weights.speed_ceiling_l2],
            "rk4_steps": stage_steps(config, params),
            "iterate": _ITERATE_HEADER + _ITERATE_SOURCE,
            # The compiled solver links the acados libraries of the install that built it: a
            # cache shared by two installs (two virtual environments) keeps one solver each,
            # and one whose install is gone is never loaded (it failed to load, and the planner
            # fell back to CasADi).
            "acados_install": os.environ.get("ACADOS_SOURCE_DIR", ""),
            # The code that describes the problem: an edit to it regenerates the solvers, where
            # the format version alone relied on a bump that a cached solver outlived.
            "generator": generator_source_digest(),
        },
        sort_keys=True,
    )
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _generator_sources(root: str) -> dict[str, str]:
    """The source text of module ``root`` and of every ``mufusion`` module it imports,
    transitively (found in the text, not by importing), by module name."""
    sources: dict[str, str] = {}
    pending = [root]
    while pending:
        name = pending.pop()
        if name in sources:
            continue
        spec = util.find_spec(name)
        if spec is None or spec.origin is None:
            raise ModuleNotFoundError(f"{name}: imported by the solver's description")
        text = Path(spec.origin).read_text(encoding="utf-8")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mufusion"):
                pending.append(str(node.module))
            elif isinstance(node, ast.Import):
                pending.extend(a.name for a in node.names if a.name.startswith("mufusion"))
        sources[name] = text
    return sources


_DESCRIPTION = "mufusion.planner.acados_ocp"


def generator_modules(root: str = _DESCRIPTION) -> set[str]:
    """The modules whose source :func:`generator_source_digest` covers."""
    return set(_generator_sources(root))


@functools.cache
def generator_source_digest(root: str = _DESCRIPTION) -> str:
    """Hash of the code that writes the generated problem: the source of ``root`` (the OCP's
    description) and of every ``mufusion`` module it imports."""
    sources = _generator_sources(root)
    digest = hashlib.sha256()
    for name in sorted(sources):
        digest.update(f"{name}\0{sources[name]}\0".encode())
    return digest.hexdigest()


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
                ocp = describe(at, params, config, name, export, hpipm_mode)
                at.AcadosOcpSolver.generate(ocp, json_file=str(export / "ocp.json"))
                (export / ITERATE_H).write_text(_ITERATE_HEADER.format(name=name))
                (export / ITERATE_C).write_text(
                    _ITERATE_SOURCE.format(name=name, upper=name.upper()))
                # acados' ctypes wrapper, not its Cython one: each call below is one C call
                # either way, and the Cython module's 1.9 MB of C took 6 of a build's 8.5 s.
                at.AcadosOcpSolver.build(str(export), with_cython=False, verbose=False)
        with contextlib.redirect_stdout(io.StringIO()):  # it prints whether OpenMP is in
            self.solver = at.AcadosOcpSolver(None, json_file=str(export / "ocp.json"),
                                             build=False, generate=False, verbose=False)
        self._price_corridor_by_stage(config)
        self.n = n
        self.layout = ocp_state(config, params)
        self.params, self.config = params, config
        self._generated_lbu = np.tile(input_bounds(params, config)[0], (n, 1))
        self._lbu_changed = False

    def _price_corridor_by_stage(self, config: PlannerConfig) -> None:
        """Write each stage's corridor slack penalties at its scale (the generated problem
        prices every stage alike; the scale is data, not code, so it needs no other solver)."""
        scale = corridor_slack_scale(config.horizon_steps, config.lane_slack_lead)
        if np.all(scale == 1.0):
            return
        pen = stage_slack_penalties(config)
        for k in range(1, config.horizon_steps):  # stage 0 has no corridor (x_0 is fixed)
            for field, values in (("zl", pen.linear_stage), ("zu", pen.linear_stage_upper),
                                  ("Zl", pen.quadratic_stage), ("Zu", pen.quadratic_stage_upper)):
                scaled = values.copy()
                scaled[pen.corridor] *= scale[k - 1]
                self.solver.cost_set(k, field, scaled)

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
            np.broadcast_to(ubu, (n, ubu.shape[-1])), [float(write_lbu)], lbu,
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
        self._lbu, self._ubu = input_bounds(params, config)
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
        max_drive_force_n: float | np.ndarray | None = None,
        max_front_brake_force_n: np.ndarray | None = None,
        max_speed_mps: np.ndarray | None = None,
    ) -> tuple[int, np.ndarray, np.ndarray]:
        """One RTI step; returns ``(status, states (N+1, 6), inputs (N, 3))``.

        ``max_drive_force_n`` lowers the rear drive-force bound for this solve, one for every
        stage or ``(N,)`` one per stage (``None``: the actuator's bound);
        ``max_front_brake_force_n`` ``(N,)`` [N, ≥ 0, ``inf``: none] raises the front braking's
        bound per stage; ``max_speed_mps`` ``(N,)`` [m/s] is the soft speed
        ceiling of stages 1 … N (``None``: none)."""
        n = self.config.horizon_steps
        ubu = self._ubu.copy()
        if isinstance(max_drive_force_n, np.ndarray):  # one bound per stage
            ubu = np.tile(self._ubu, (n, 1))
            ubu[:, -1] = np.minimum(ubu[:, -1], max_drive_force_n)
        elif max_drive_force_n is not None:
            ubu[-1] = min(ubu[-1], float(max_drive_force_n))
        lbu = np.tile(self._lbu, (n, 1))
        if max_front_brake_force_n is not None:
            # F_xf is the second-last bounded input (F_xr last, see input_bounds).
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
        guess but not the multipliers, so without this every later RTI step of the robust
        mode's solver fails as well (the fast mode starts each QP afresh: decision 0102).
        """
        self._fast.reset()
        if self._robust is not None:
            self._robust.reset()
