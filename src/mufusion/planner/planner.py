"""Traction-adaptive MPC planner (Svensson & Törngren, Sec. II; TAMP framework).

Each :meth:`TractionAdaptivePlanner.step` shifts the previous plan, evaluates the per-stage friction
estimate (sanitised, see :mod:`mufusion.planner.safeguards`), normal loads and rear stiffness at the
guess's predicted positions, builds the lateral corridor and runs one real-time iteration. A solve
that fails, raises, or returns a non-finite or implausible solution keeps the shifted plan, is
counted and logged, re-initialises the solver, and never raises. After
``SafetySettings.max_consecutive_fallbacks`` such steps in a row the caller should switch to
``mode="minimal_risk"`` (:mod:`mufusion.planner.minimal_risk`).

A step's stages: the obstacles it plans around; its guess (the shifted previous plan, a
sampled roll-out, :func:`~mufusion.planner.sampling.sampled_guess`, or the minimal-risk
roll-out) with the front force it starts from; the real-time iterations
(:func:`~mufusion.planner.rti.iterate`); the outcome counted; the plan
(:func:`~mufusion.planner.rti.plan_of`).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from mufusion.planner.backend import PlannerBackend, default_backend
from mufusion.planner.config import (
    PLANNER_MODES,
    CostWeights,
    PlannerConfig,
    PlannerMode,
    PlannerObstacle,
)
from mufusion.planner.minimal_risk import minimal_risk_rollout, stop_is_held
from mufusion.planner.ocp_state import anchored_first_forces
from mufusion.planner.passing import in_path
from mufusion.planner.plan import FallbackReason, Plan
from mufusion.planner.rti import Iterated, StepProblem, held_plan, iterate, plan_of
from mufusion.planner.safeguards import FrictionProfile, SanitizedFriction
from mufusion.planner.sampling import SamplingConfig, rk4_step, sampled_guess
from mufusion.planner.unseen_road import UnseenRoad
from mufusion.vehicle.params import VehicleParams
from mufusion.vehicle.planner_model import (
    N_INPUTS,
    N_STATES,
    State,
)

_log = logging.getLogger(__name__)

__all__ = [
    "CostWeights",
    "FallbackReason",
    "Plan",
    "PlannerConfig",
    "PlannerMemory",
    "PlannerObstacle",
    "TractionAdaptivePlanner",
    "rollout",
]


def rollout(
    x0: np.ndarray, inputs: np.ndarray, curvature: np.ndarray, rear_stiffness: np.ndarray,
    params: VehicleParams, dt_s: float,
) -> np.ndarray:
    """RK4 roll-out of the planner model; ``inputs (N, 3, ...)`` → states ``(N+1, 6, ...)``."""
    xs = [np.asarray(x0, dtype=float)]
    for k in range(inputs.shape[0]):
        xs.append(rk4_step(xs[-1], inputs[k], curvature[k], rear_stiffness[k], params, dt_s))
    return np.stack(xs)


@dataclass(frozen=True)
class PlannerMemory:
    """What a planning step hands to the next: the plan the next guess continues (shifted), the
    sanitised μ̂ profile that stands in for invalid estimates, and the count of fallback steps in
    a row. A caller that plans several candidates for one step (lane recovery) restores the
    memory of the candidate it adopts, so the next step continues the plan that is executed.
    """

    previous: Plan | None
    mu_profile: FrictionProfile | None
    consecutive_fallbacks: int
    carried: tuple[np.ndarray, np.ndarray] | None = None
    """A rejected but finite iterate (states, inputs) the next guess continues instead of
    ``previous``'s own states and inputs (``None``: none)."""


class TractionAdaptivePlanner:
    """Real-time traction-adaptive planner; keeps the warm start between calls.

    Parameters
    ----------
    params
        Vehicle parameters.
    config
        Planner configuration (default :class:`PlannerConfig`).
    sampling
        Sampling augmentation of the initial guess (default :class:`SamplingConfig`).
    backend
        The OCP solver; default: acados RTI for ``config.backend == "acados"`` (CasADi + IPOPT
        if acados cannot be loaded), else CasADi + IPOPT. Any object implementing
        :class:`~mufusion.planner.backend.PlannerBackend` (e.g. one that injects faults) works.
    """

    def __init__(
        self,
        params: VehicleParams,
        config: PlannerConfig | None = None,
        sampling: SamplingConfig | None = None,
        backend: PlannerBackend | None = None,
    ) -> None:
        self.params = params
        self.config = config or PlannerConfig()
        self.sampling = sampling or SamplingConfig()
        self.failures = 0
        self._consecutive_fallbacks = 0
        self._prev: Plan | None = None
        self._mu_profile: FrictionProfile | None = None
        self._carried: tuple[np.ndarray, np.ndarray] | None = None
        self._backend = backend if backend is not None else default_backend(params, self.config)

    @property
    def backend(self) -> PlannerBackend:
        """The OCP solver in use."""
        return self._backend

    @property
    def consecutive_fallbacks(self) -> int:
        """Planning steps in a row, up to the latest, without a usable solution."""
        return self._consecutive_fallbacks

    @property
    def last_plan(self) -> Plan | None:
        """The latest plan (the next step's warm start), or ``None`` after :meth:`reset`."""
        return self._prev

    @property
    def memory(self) -> PlannerMemory:
        """What the next :meth:`step` continues from (see :class:`PlannerMemory`)."""
        return PlannerMemory(self._prev, self._mu_profile, self._consecutive_fallbacks,
                             self._carried)

    def restore(self, memory: PlannerMemory) -> None:
        """Continue from ``memory`` (taken from :attr:`memory`) instead of the latest step.

        The solver's own warm start (its multipliers) is not part of it: it moves only where the
        next QP's interior-point iterations start, not (beyond the QP's tolerance) their end.
        """
        self._prev = memory.previous
        self._mu_profile = memory.mu_profile
        self._consecutive_fallbacks = memory.consecutive_fallbacks
        self._carried = memory.carried

    def reset(self) -> None:
        """Forget the warm start, the last friction profile and the failure counters, and
        re-initialise the solver (its iterates and memory). The next step is a cold start."""
        self._prev = None
        self._mu_profile = None
        self._carried = None
        self.failures = 0
        self._consecutive_fallbacks = 0
        self._backend.reset()

    # -- the guess ------------------------------------------------------------------------------
    def _previous_shift(self, x0: np.ndarray, t_s: float) -> int | None:
        """Stages the previous plan has advanced by ``t_s`` (``None``: no plan to continue)."""
        n, prev = self.config.horizon_steps, self._prev
        if prev is None:
            return None
        shift = int(min(max(round((t_s - prev.t0_s) / self.config.dt_s), 0), n))  # np.clip's
        if shift <= n - 1 and abs(prev.states[shift, State.s] - x0[State.s]) < 10.0:
            return shift
        return None

    def _initial_guess(self, x0: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        n, dt = self.config.horizon_steps, self.config.dt_s
        prev = self._prev
        if prev is not None and np.all(np.isfinite(prev.states)):
            shift = self._previous_shift(x0, t_s)
            if shift is not None:
                # After a rejected step the real-time iterations continue from the rejected
                # iterate (the vehicle follows the shifted plan meanwhile): restarted from the
                # shifted plan each time, a plan that needs several iterations to converge (a
                # hard stop before a hairpin) was rejected at every step (docs/decisions/0056).
                states, inputs = (prev.states, prev.inputs) if self._carried is None else (
                    self._carried)
                xs = np.concatenate([states[shift:], np.repeat(states[-1:], shift, 0)])
                us = np.concatenate([inputs[shift:], np.repeat(inputs[-1:], shift, 0)])
                xs = xs.copy()
                xs[0] = x0
                return xs, us
        # Cold start: coast at the current speed along the current offset.
        k = np.arange(n + 1)[:, None]
        xs = np.tile(x0, (n + 1, 1)).astype(float)
        xs[:, State.s] = x0[State.s] + k[:, 0] * dt * max(x0[State.vx], 0.0)
        xs[1:, State.dpsi] = xs[1:, State.psidot] = xs[1:, State.vy] = 0.0
        return xs, np.zeros((n, N_INPUTS))

    def _previous_forces_n(self, x0: np.ndarray, t_s: float) -> np.ndarray | None:
        """The forces ``(3,)`` the previous plan has at ``t_s`` (``None``: none)."""
        prev = self._prev
        if prev is None or not np.all(np.isfinite(prev.inputs)):
            return None
        shift = self._previous_shift(x0, t_s)
        return None if shift is None else np.array(prev.inputs[shift], dtype=float)

    # -- one planning step ----------------------------------------------------------------------
    def step(
        self,
        x0: np.ndarray,
        t_s: float,
        curvature_of_s: Callable[[np.ndarray], np.ndarray],
        mu_hat_of_s: Callable[[np.ndarray], np.ndarray],
        obstacles: Sequence[PlannerObstacle] = (),
        mode: PlannerMode = "cruise",
        reference_speed_mps: float = 10.0,
        reference_d_m: float = 0.0,
        lane_d_min_m: float | None = None,
        lane_d_max_m: float | None = None,
        front_force_n: float | None = None,
        longitudinal_forces_n: tuple[float, float] | None = None,
        unseen_road: UnseenRoad | None = None,
    ) -> Plan:
        """Plan from ``x0`` (Frenet state, shape (6,)) at time ``t_s`` [s].

        Parameters
        ----------
        x0
            Current state (s, d, Δψ, ψ̇, v_x, v_y) in the road-aligned frame.
        t_s
            Time of ``x0`` [s]; stage k of the plan is at ``t_s + k·dt``.
        curvature_of_s, mu_hat_of_s
            Road curvature [1/m] and friction estimate [-] as functions of absolute progress [m].
            μ̂ is sanitised (non-finite, ≤ 0 or out-of-range values; a source that raises), see
            :mod:`mufusion.planner.safeguards`.
        obstacles
            :class:`PlannerObstacle` (or ``(s_m, d_m, length_m, width_m)`` tuples).
        mode
            ``"cruise"`` (track speed and offset), ``"evade"`` (obstacles ahead: speed is
            held at most at its current value with a light weight, so the tires' friction goes to
            the lateral manoeuvre rather than to regaining speed), ``"emergency"`` (stop as short
            as the friction allows) or ``"minimal_risk"`` (brake to a stop at
            ``minimal_risk_decel_fraction · μ̂ g`` holding ``reference_d_m``, the lane centre;
            falls back to a solver-free roll-out, see :mod:`mufusion.planner.minimal_risk`).
            In the last two, a vehicle at rest, or one its brakes bring to rest whatever it
            plans, is held with the brakes on, no solve (``Plan.held``;
            :func:`~.minimal_risk.stop_is_held`).
        reference_speed_mps, reference_d_m
            Cruise references.
        lane_d_min_m, lane_d_max_m
            Bounds on the reference point's lateral offset [m] (lane or road edges already shrunk
            by half the vehicle width); default from the config.
        front_force_n
            The front axle's lateral force [N] the vehicle delivers now (body frame, as a force
            observer supplies it). With ``steering_rate_limit`` the plan's front-force state starts
            from it; ``None`` (or not finite: a measurement that failed degrades, never raises):
            from the force the previous plan commands now (planner/front_force.py).
        longitudinal_forces_n
            The front and rear longitudinal forces [N] the wheel torques deliver now. With
            ``torque_lag`` the plan's force states start from them; ``None`` (or not finite):
            from the previous plan's forces now (planner/ocp_state.py).
        unseen_road
            Where the estimate behind ``mu_hat_of_s`` ends and the friction the curve speed
            reference assumes beyond it (:class:`~mufusion.planner.unseen_road.UnseenRoad`);
            None: ``mu_hat_of_s`` everywhere.

        Returns
        -------
        Plan

        Raises
        ------
        ValueError
            If ``x0`` is not a finite 6-vector or ``mode`` is unknown.
        """
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (N_STATES,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"x0 must be a finite array of shape (6,), got {x0!r}")
        if mode not in PLANNER_MODES:
            raise ValueError(f"mode must be one of {list(PLANNER_MODES)}, got {mode!r}")
        if mode == "evade":
            reference_speed_mps = min(reference_speed_mps, float(x0[State.vx]))
        cfg = self.config
        problem = StepProblem(
            x0, mode, curvature_of_s,
            SanitizedFriction(mu_hat_of_s, self._mu_profile, cfg.safety.mu_floor),
            self._obstacles(x0, obstacles, mode), reference_speed_mps, reference_d_m,
            cfg.lane_d_min_m if lane_d_min_m is None else lane_d_min_m,
            cfg.lane_d_max_m if lane_d_max_m is None else lane_d_max_m,
            unseen_road,
        )
        if stop_is_held(mode, x0, longitudinal_forces_n, self.params, cfg):
            return self._held(problem, t_s)
        started = time.perf_counter()
        guess_x, guess_u, sampled = self._guess(problem, t_s, front_force_n,
                                                longitudinal_forces_n)
        # One real-time iteration per step; a cold start has no converged plan to iterate from,
        # so it takes a few (re-linearised at each iterate, as the next steps would).
        iterations = 1 if self._prev is not None else cfg.cold_start_iterations
        solved = iterate(self._backend, self.params, cfg, problem, guess_x, guess_u, iterations)
        states_inputs = self._settle(solved, mode)  # counts the step: before the plan
        plan = plan_of(self.params, cfg, problem, solved, states_inputs, t_s, started, sampled,
                       self._consecutive_fallbacks)
        self._prev = plan
        self._mu_profile = FrictionProfile.from_stages(
            solved.guess_x[:-1, State.s], solved.stage.mu_hat)
        return plan

    # -- the stages of one step -----------------------------------------------------------------
    def _obstacles(
        self, x0: np.ndarray, obstacles: Sequence[PlannerObstacle], mode: PlannerMode
    ) -> list[PlannerObstacle]:
        """The obstacles the step plans around (as :class:`PlannerObstacle`)."""
        cfg, par = self.config, self.params
        found = [
            o if isinstance(o, PlannerObstacle) else PlannerObstacle(*map(float, o))
            for o in obstacles
        ]
        if mode == "emergency":
            # The stop is in front of the obstacles in the path: the plan needs no room beside
            # them. Left in, the corridor (placed along the guess, which may still run past the
            # obstacle) opens a side and the stopping plan swerves into it at the friction limit:
            # its rear axle exceeds the polygon, the plan is rejected, the shifted cruise plan is
            # kept, and the stop under way turns into a late swerve (docs/decisions/0022).
            clear = 0.5 * par.width_m + cfg.obstacle_margin_m
            found = [o for o in found if not in_path(
                o.s_m, o.d_m, clear + 0.5 * o.width_m, float(x0[State.s]), float(x0[State.d]))]
        return found

    def _guess(
        self, problem: StepProblem, t_s: float, front_force_n: float | None,
        longitudinal_forces_n: tuple[float, float] | None = None,
    ) -> tuple[np.ndarray, np.ndarray, bool]:
        """The guess the iterations start from, and whether it is a sampled roll-out."""
        cfg, x0, mode = self.config, problem.x0, problem.mode
        sampled = False
        if mode == "minimal_risk":
            guess_x, guess_u = minimal_risk_rollout(
                x0, problem.reference_d_m, problem.curvature_of_s, problem.mu_of_s, self.params,
                cfg, self.sampling,
            )
        else:
            guess_x, guess_u = self._initial_guess(x0, t_s)
            if cfg.use_sampling:
                v_ref = 0.0 if mode == "emergency" else problem.reference_speed_mps
                guess_x, guess_u, sampled = sampled_guess(
                    x0, guess_x, guess_u, problem.curvature_of_s, problem.mu_of_s,
                    problem.obstacles, v_ref, problem.reference_d_m, problem.lane_d_min_m,
                    problem.lane_d_max_m, self.params, cfg, self.sampling,
                    continuing=self._prev is not None,
                )
        if not (cfg.steering_rate_limit or cfg.torque_lag):
            return guess_x, guess_u, sampled
        # The forces that are states cannot jump: whatever guess (sampled roll-out,
        # minimal-risk roll-out) the step starts from, the plan starts from the forces the
        # vehicle delivers now (planner/ocp_state.py).
        guess_u = guess_u.copy()
        guess_u[0] = anchored_first_forces(guess_u[0], self._previous_forces_n(x0, t_s),
                                           front_force_n, longitudinal_forces_n, cfg)
        return guess_x, guess_u, sampled

    def _settle(self, solved: Iterated, mode: PlannerMode) -> tuple[np.ndarray, np.ndarray]:
        """Count the step's outcome; the plan's states and inputs (the guess if it failed)."""
        self._carried = None
        if solved.reason is FallbackReason.NONE:
            self._consecutive_fallbacks = 0
            return solved.xs, solved.us
        self.failures += 1
        self._consecutive_fallbacks += 1
        _log.warning("planner solve failed (%s, status %s; %d in a row, %d so far); keeping "
                     "the %s plan", solved.reason.value, solved.status,
                     self._consecutive_fallbacks, self.failures,
                     "minimal-risk" if mode == "minimal_risk" else "shifted")
        if solved.reason is FallbackReason.IMPLAUSIBLE and solved.soft_only:
            # Finite and solved, outside only the soft rows (not diverged): unfit to execute,
            # but the next step's iterations continue from it, and the solver keeps its iterate.
            self._carried = (solved.xs, solved.us)
        else:
            # A failed QP can leave NaN multipliers that poison every later RTI step.
            self._reinitialise_backend()
        return solved.guess_x, solved.guess_u

    def _held(self, problem: StepProblem, t_s: float) -> Plan:
        """A stop at rest, held (:func:`~mufusion.planner.rti.held_plan`); the solver starts
        afresh when the vehicle moves off again, as it did after the failed solves at rest."""
        if self._prev is None or not self._prev.held:
            self._reinitialise_backend()
        self._consecutive_fallbacks, self._carried = 0, None
        self._prev = held_plan(self.params, self.config, problem, t_s, self.sampling)
        return self._prev

    def _reinitialise_backend(self) -> None:
        try:
            self._backend.reset()
        except Exception as exc:  # never raise inside the loop
            _log.warning("planner backend reset raised %r", exc)
