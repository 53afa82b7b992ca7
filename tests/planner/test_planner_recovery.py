"""Recovery: sanitised μ̂, solver re-initialisation, solution checks, fallback counting, reset."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.planner.acados_backend import AcadosBackend
from mufusion.planner.ocp import PlannerConfig, PlausibilityLimits
from mufusion.planner.plan import FallbackReason
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.planner.safeguards import FrictionProfile, SanitizedFriction, sanitize_mu
from mufusion.planner.safety import SafetySettings
from mufusion.vehicle.params import GRAVITY_MPS2, TRUCK
from mufusion.vehicle.planner_model import Input, State

CONFIG = PlannerConfig(lane_d_min_m=-0.45, lane_d_max_m=0.45)
X0 = np.array([0.0, 0.0, 0.0, 0.0, 15.0, 0.0])


def straight(s):
    return 0.0 * np.asarray(s, dtype=float)


def mu_08(s):
    return 0.8 + 0.0 * np.asarray(s, dtype=float)


def mu_with_nan(s):
    s = np.asarray(s, dtype=float)
    return np.where((s > 20.0) & (s < 40.0), np.nan, 0.8)


class FaultyBackend:
    """Wraps a real backend; ``mode`` selects the fault of the next solves."""

    def __init__(self, inner, reset_works: bool = True) -> None:
        self.inner, self.reset_works = inner, reset_works
        self.mode = "none"
        self.resets = 0
        self.last_solve_retried = False  # the inner backend's, for the solves it ran

    def solve(self, x0, guess_x, guess_u, p, yref, weights, d_lo, d_hi, min_speed_mps,
              max_drive_force_n=None, max_front_brake_force_n=None, max_speed_mps=None):
        self.last_solve_retried = False
        if self.mode == "raise":
            raise RuntimeError("injected")
        if self.mode == "status4":
            return 4, guess_x.copy(), guess_u.copy()
        if self.mode == "poison":  # what a NaN in μ̂ did before sanitisation
            p = np.full_like(p, np.nan)
        status, xs, us = self.inner.solve(x0, guess_x, guess_u, p, yref, weights, d_lo, d_hi,
                                          min_speed_mps, max_drive_force_n,
                                          max_front_brake_force_n, max_speed_mps)
        self.last_solve_retried = self.inner.last_solve_retried
        if self.mode == "times1000":
            us = 1000.0 * us
        if self.mode == "nan_success":
            xs = xs.copy()
            xs[5, State.vx] = np.nan
        return status, xs, us

    def reset(self) -> None:
        self.resets += 1
        if self.reset_works:
            self.inner.reset()


@pytest.fixture(scope="module")
def faulty() -> tuple[TractionAdaptivePlanner, FaultyBackend]:
    inner = TractionAdaptivePlanner(TRUCK, CONFIG).backend
    backend = FaultyBackend(inner)
    return TractionAdaptivePlanner(TRUCK, CONFIG, backend=backend), backend


def curve(s):
    return 1.0 / 60.0 + 0.0 * np.asarray(s, dtype=float)


def _run(planner, steps, mu_at_step=lambda i: mu_08, fault_at_step=None, backend=None, t0=0.0,
         x=X0, mode="cruise", curvature=straight):
    plans = []
    for i in range(steps):
        if backend is not None:
            backend.mode = fault_at_step(i) if fault_at_step else "none"
        plan = planner.step(x, t0 + 0.1 * i, curvature, mu_at_step(i), [], mode, 15.0)
        plans.append(plan)
        x = plan.states[1]
    if backend is not None:
        backend.mode = "none"
    return plans


# -- μ̂ sanitisation -------------------------------------------------------------------------------
def test_sanitisation_rule_without_previous_profile():
    raw = np.array([0.8, np.nan, np.inf, -0.2, 0.0, 0.01, 2.5, 1.2])
    mu, count = sanitize_mu(raw, np.arange(8.0), None, floor=0.1)
    np.testing.assert_array_equal(mu, [0.8, 0.1, 0.1, 0.1, 0.1, 0.05, 2.0, 1.2])
    assert count == 6


def test_sanitisation_rule_takes_the_previous_profile_at_the_same_position():
    previous = FrictionProfile.from_stages(np.array([10.0, 0.0, 20.0]), np.array([0.6, 0.9, 0.3]))
    raw = np.array([np.nan, 0.7, np.nan, np.nan])
    mu, count = sanitize_mu(raw, np.array([5.0, 7.0, 15.0, 50.0]), previous, floor=0.1)
    # Interpolated inside the previous profile, held beyond its end; valid values untouched.
    np.testing.assert_allclose(mu, [0.75, 0.7, 0.45, 0.3])
    assert count == 3


def test_a_broken_friction_source_is_sanitised_not_raised():
    def raises(s):
        raise RuntimeError("camera gone")

    wrapped = SanitizedFriction(raises, None, 0.1)
    np.testing.assert_array_equal(wrapped(np.arange(3.0)), [0.1, 0.1, 0.1])
    assert wrapped.last_count == 3
    wrong_shape = SanitizedFriction(lambda s: np.ones(7), None, 0.2)
    np.testing.assert_array_equal(wrong_shape(np.arange(3.0)), [0.2, 0.2, 0.2])
    scalar = SanitizedFriction(lambda s: 0.7, None, 0.1)
    np.testing.assert_array_equal(scalar(np.arange(3.0)), [0.7, 0.7, 0.7])
    assert scalar.last_count == 0


def test_the_sanitised_count_is_the_stages_not_the_front_axles_reach():
    """``Plan.mu_sanitized_stages`` reads the count of the step's last μ̂ query; the stage
    parameters make the stages' own query last, after the front axle's reach (0064)."""
    from mufusion.planner.ocp import stage_parameters

    def nan_beyond_20_m(s):
        return np.where(np.asarray(s, dtype=float) > 20.0, np.nan, 0.8)

    n = CONFIG.horizon_steps
    guess_x = np.zeros((n + 1, 6))
    guess_x[:, State.vx] = 15.0
    guess_x[:, State.s] = np.arange(n + 1.0)  # stages at 0, 1, ..., 39 m
    wrapped = SanitizedFriction(nan_beyond_20_m, None, 0.1)
    stage = stage_parameters(guess_x, np.zeros((n, 3)), straight, wrapped, TRUCK,
                             CONFIG.utilization_factor, None, TRUCK.torque_time_constant_s)
    s_k = guess_x[:-1, State.s]
    # The front axle (1.2 m ahead) and its reach meet the patch stages earlier: more values.
    ahead = s_k + TRUCK.cog_to_front_axle_m
    assert np.count_nonzero(ahead > 20.0) > np.count_nonzero(s_k > 20.0) == 19
    assert wrapped.last_count == 19
    np.testing.assert_allclose(stage.mu_hat, np.where(s_k > 20.0, 0.1, 0.8))


def test_planner_reports_and_applies_the_sanitisation(faulty):
    planner, _ = faulty
    planner.reset()
    plans = _run(planner, 3)
    assert all(p.mu_sanitized_stages == 0 for p in plans)
    x = plans[-1].states[1]
    plan = planner.step(x, 0.3, straight, mu_with_nan, [], "cruise", 15.0)
    s_k = planner.last_plan.states[:-1, State.s]  # close to the stage positions used
    in_nan_region = (s_k > 21.0) & (s_k < 39.0)
    assert plan.ok and plan.mu_sanitized_stages >= in_nan_region.sum() > 0
    # The previous profile was 0.8 everywhere, so the NaN region reads 0.8.
    np.testing.assert_allclose(plan.mu_hat, 0.8)
    # Above the range: clipped to 2 and counted at every stage.
    plan = planner.step(plan.states[1], 0.4, straight, lambda s: 5.0 + 0 * s, [], "cruise", 15.0)
    assert plan.mu_sanitized_stages == CONFIG.horizon_steps
    np.testing.assert_allclose(plan.mu_hat, 2.0)


def test_all_nan_friction_from_a_cold_start_uses_the_floor():
    planner = TractionAdaptivePlanner(TRUCK, CONFIG)
    plan = planner.step(X0, 0.0, straight, lambda s: np.nan * np.asarray(s), [], "cruise", 15.0)
    assert plan.ok
    assert plan.mu_sanitized_stages == CONFIG.horizon_steps
    np.testing.assert_allclose(plan.mu_hat, CONFIG.safety.mu_floor)
    assert np.all(np.isfinite(plan.states))


# -- NaN once, solver re-initialisation ------------------------------------------------------------
def test_nan_once_in_mu_hat_recovers_within_two_steps(faulty):
    planner, _ = faulty
    planner.reset()
    plans = _run(planner, 10, mu_at_step=lambda i: mu_with_nan if i == 3 else mu_08)
    # Required: usable plans again within two steps of the NaN. Measured: the NaN step itself
    # plans normally, on the previous profile's values.
    assert all(p.ok and p.status == 0 for p in plans[3 + 2:])
    assert plans[3].ok and plans[3].mu_sanitized_stages > 0
    assert all(p.mu_sanitized_stages == 0 for p in plans[4:])


def _poisoned_run(reset_works: bool, robust_retry: bool = True,
                  robust_solver_only: bool = False) -> list:
    inner = AcadosBackend(TRUCK, CONFIG, robust_retry=robust_retry or robust_solver_only)
    if robust_solver_only:  # the robust mode's generated solver as the backend's only one
        inner._fast, inner._robust = inner._robust, None
    backend = FaultyBackend(inner, reset_works=reset_works)
    planner = TractionAdaptivePlanner(TRUCK, CONFIG, backend=backend)
    return _run(planner, 10, fault_at_step=lambda i: "poison" if i == 3 else "none",
                backend=backend)


def test_poisoned_solver_is_reinitialised_and_recovers_within_two_steps():
    plans = _poisoned_run(reset_works=True)
    assert all(p.ok for p in plans[:3])
    assert not plans[3].ok and plans[3].fallback_reason is FallbackReason.SOLVER_STATUS
    assert plans[3].status == 4
    # Within two steps is required; the reset makes the very next step succeed.
    assert all(p.ok for p in plans[4:]), [p.status for p in plans]


def test_without_reinitialisation_the_robust_mode_stays_poisoned():
    # The fault the reset fixes: after one NaN solve, acados' multipliers keep every later RTI
    # step of a BALANCE-mode solver failing although the inputs are finite again (one solver,
    # no retry). HPIPM's SPEED mode, the fast one before decision 0102, did the same.
    plans = _poisoned_run(reset_works=False, robust_retry=False, robust_solver_only=True)
    assert not any(p.ok for p in plans[3:])


def test_the_fast_mode_recovers_from_a_nan_solve_without_reinitialisation():
    # SPEED_ABS (decision 0102) starts each QP afresh: the NaN solve fails, the next succeeds
    # with the planner's reset disabled and no robust retry. The reset stays for the robust
    # mode (above) and costs nothing here.
    plans = _poisoned_run(reset_works=False, robust_retry=False)
    assert not plans[3].ok and plans[3].status == 4
    assert all(p.ok for p in plans[4:]), [p.status for p in plans]


def test_the_robust_retry_resets_the_fast_solver_it_gave_up_on():
    # With the retry, the backend resets its fast solver itself before asking the robust one,
    # so even a planner that never resets recovers at the next step.
    plans = _poisoned_run(reset_works=False, robust_retry=True)
    assert not plans[3].ok and plans[3].robust_qp_retry
    assert all(p.ok and not p.robust_qp_retry for p in plans[4:]), [p.status for p in plans]


class _FailingSolver:
    """Stands in for the fast generated solver: every solve fails like a NaN in HPIPM."""

    def __init__(self) -> None:
        self.resets = 0

    def solve(self, x0, guess_x, guess_u, *args):
        return 4, guess_x.copy(), guess_u.copy()

    def reset(self) -> None:
        self.resets += 1


def test_a_failed_fast_solve_is_repeated_by_the_robust_solver_and_logged():
    backend = AcadosBackend(TRUCK, CONFIG)
    reference = TractionAdaptivePlanner(TRUCK, CONFIG, backend=AcadosBackend(TRUCK, CONFIG))
    want = _run(reference, 3)
    failing = _FailingSolver()
    backend._fast, robust = failing, backend._robust
    assert robust is not None
    planner = TractionAdaptivePlanner(TRUCK, CONFIG, backend=backend)
    got = _run(planner, 3)
    # Every step failed in the fast mode and was solved by the robust one: plans, not fallbacks.
    assert all(p.ok and p.robust_qp_retry and not p.fallback for p in got)
    # One solve per step after the cold start's CONFIG.cold_start_iterations; each failed
    # solve is retried once, and the failed solver is reset before the retry.
    solves = CONFIG.cold_start_iterations + 2
    assert backend.robust_retries == failing.resets == solves and backend.last_solve_retried
    # The robust mode solves the same QP: the plans agree with the fast mode's to solver
    # tolerance (not bitwise: another interior-point path).
    for a, b in zip(want, got, strict=True):
        np.testing.assert_allclose(b.states, a.states, rtol=0, atol=1e-3)


def test_without_the_retry_a_failed_fast_solve_is_a_fallback():
    backend = AcadosBackend(TRUCK, CONFIG, robust_retry=False)
    backend._fast = _FailingSolver()
    planner = TractionAdaptivePlanner(TRUCK, CONFIG, backend=backend)
    plans = _run(planner, 3)
    assert all(p.fallback and not p.robust_qp_retry for p in plans)
    assert backend.robust_retries == 0 and not backend.last_solve_retried


# -- failure counting, solution checks -------------------------------------------------------------
def test_consecutive_fallbacks_are_counted_and_cleared(faulty):
    planner, backend = faulty
    planner.reset()
    k = CONFIG.safety.max_consecutive_fallbacks
    plans = _run(planner, 3 + k + 2, backend=backend,
                 fault_at_step=lambda i: "status4" if 3 <= i < 3 + k else "none")
    counts = [p.consecutive_fallbacks for p in plans]
    assert counts == [0, 0, 0, *range(1, k + 1), 0, 0]
    assert all(p.fallback_reason is FallbackReason.SOLVER_STATUS for p in plans[3:3 + k])
    assert planner.failures == k
    assert plans[3 + k - 1].consecutive_fallbacks >= CONFIG.safety.max_consecutive_fallbacks
    # The fallback is the previous plan shifted by one stage.
    np.testing.assert_allclose(plans[3].states[1:-1], plans[2].states[2:])
    assert plans[-1].ok and planner.consecutive_fallbacks == 0


def test_backend_exception_counts_as_fallback(faulty):
    planner, backend = faulty
    planner.reset()
    plans = _run(planner, 4, backend=backend, fault_at_step=lambda i: "raise" if i >= 2 else "none")
    assert [p.fallback_reason for p in plans[2:]] == [FallbackReason.EXCEPTION] * 2
    assert plans[-1].consecutive_fallbacks == 2


@pytest.mark.parametrize("fault, reason", [("times1000", FallbackReason.IMPLAUSIBLE),
                                           ("nan_success", FallbackReason.NON_FINITE)])
def test_a_successful_status_with_absurd_solution_is_rejected(faulty, fault, reason):
    planner, backend = faulty
    planner.reset()
    resets = backend.resets
    # In a curve, so that the true solution's forces are far from zero.
    plans = _run(planner, 4, backend=backend, fault_at_step=lambda i: fault if i == 2 else "none",
                 curvature=curve)
    assert np.abs(plans[1].inputs[:, Input.fyf]).max() > 10_000.0
    assert plans[2].status == 0  # the solver said success
    assert not plans[2].ok and plans[2].fallback and plans[2].fallback_reason is reason
    assert plans[2].consecutive_fallbacks == 1
    assert np.all(np.abs(plans[2].inputs) < 1e6)  # the kept plan, not the absurd one
    assert backend.resets == resets + 1
    assert plans[3].ok


# -- reset ----------------------------------------------------------------------------------------
def test_reset_forgets_everything_and_gives_a_cold_start(faulty):
    planner, backend = faulty
    planner.reset()
    fresh = planner.step(X0, 0.0, straight, mu_08, [], "cruise", 15.0)
    _run(planner, 5, backend=backend, fault_at_step=lambda i: "status4" if i == 4 else "none",
         t0=1.0, x=np.array([3.0, 0.2, 0.01, 0.0, 14.0, 0.1]))
    assert planner.failures == 1 and planner.consecutive_fallbacks == 1
    planner.reset()
    assert planner.last_plan is None
    assert planner.failures == 0 and planner.consecutive_fallbacks == 0
    again = planner.step(X0, 0.0, straight, mu_08, [], "cruise", 15.0)
    # Same input after reset → the same plan as after the first reset: no state survived.
    np.testing.assert_allclose(again.states, fresh.states, rtol=0, atol=1e-9)
    np.testing.assert_allclose(again.inputs, fresh.inputs, rtol=0, atol=1e-6)


# -- minimal-risk manoeuvre ------------------------------------------------------------------------
def _brake_to_stop(planner, mu, x, steps=80):
    xs = [x]
    plans = []
    for i in range(steps):
        plan = planner.step(x, 0.1 * i, straight, lambda s: mu + 0 * s, [], "minimal_risk", 15.0)
        plans.append(plan)
        x = plan.states[1]
        xs.append(x)
        if x[State.vx] < 0.05:
            break
    return np.array(xs), plans


@pytest.mark.parametrize("broken_solver", [False, True])
def test_minimal_risk_brakes_to_a_stop_in_lane_at_the_declared_rate(faulty, broken_solver):
    planner, backend = faulty
    planner.reset()
    mu = 0.6
    x0 = np.array([0.0, 0.3, 0.0, 0.0, 15.0, 0.0])
    backend.mode = "status4" if broken_solver else "none"
    try:
        xs, plans = _brake_to_stop(planner, mu, x0)
    finally:
        backend.mode = "none"
    assert all(p.mode == "minimal_risk" for p in plans)
    assert all(p.ok != broken_solver for p in plans)
    decel = CONFIG.safety.minimal_risk_decel_fraction * mu * GRAVITY_MPS2
    ideal = 15.0**2 / (2.0 * decel)
    assert xs[-1, State.vx] < 0.05
    assert 0.9 * ideal < xs[-1, State.s] < 1.2 * ideal
    assert abs(xs[-1, State.d]) < 0.15 and np.all(np.abs(xs[:, State.d]) <= 0.45 + 0.05)
    # No traction, and never more braking than the polygons allow.
    for plan in plans:
        assert np.all(plan.inputs[:, Input.fxr] <= 1.0)
        assert np.all(np.abs(plan.inputs[:, Input.fxf]) <= plan.force_limit_front_n + 1.0)


def test_config_validates_the_recovery_settings():
    with pytest.raises(ValueError, match="max_consecutive_fallbacks"):
        SafetySettings(max_consecutive_fallbacks=0)
    with pytest.raises(ValueError, match="max_consecutive_fallbacks"):
        SafetySettings(max_consecutive_fallbacks=True)
    with pytest.raises(ValueError, match="minimal_risk_decel_fraction"):
        SafetySettings(minimal_risk_decel_fraction=1.5)
    with pytest.raises(ValueError, match="mu_floor"):
        SafetySettings(mu_floor=0.0)
    with pytest.raises(ValueError, match="corridor_tolerance_m"):
        PlausibilityLimits(corridor_tolerance_m=-1.0)


class _RecordingBackend(FaultyBackend):
    """Passes through and keeps each solve's initial guess."""

    def __init__(self, inner) -> None:
        super().__init__(inner)
        self.guesses: list[np.ndarray] = []

    def solve(self, x0, guess_x, *args, **kwargs):
        self.guesses.append(np.array(guess_x, copy=True))
        return super().solve(x0, guess_x, *args, **kwargs)


def test_restored_memory_is_what_the_next_step_continues():
    backend = _RecordingBackend(TractionAdaptivePlanner(TRUCK, CONFIG).backend)
    planner = TractionAdaptivePlanner(TRUCK, CONFIG, backend=backend)
    adopted = planner.step(X0, 0.0, straight, mu_08, [], "cruise", 15.0)
    memory = planner.memory
    assert memory.previous is adopted and memory.consecutive_fallbacks == 0
    # A candidate for the same instant that fails: it becomes the latest plan and counts.
    backend.mode = "status4"
    failed = planner.step(X0, 0.0, straight, mu_08, [], "cruise", 15.0)
    assert failed.fallback and planner.last_plan is failed and planner.consecutive_fallbacks == 1
    planner.restore(memory)
    assert planner.last_plan is adopted and planner.consecutive_fallbacks == 0
    # A candidate that succeeds with another plan (it brakes to 10 m/s), not adopted.
    backend.mode = "none"
    other = planner.step(X0, 0.0, straight, mu_08, [], "cruise", 10.0)
    assert planner.last_plan is other
    assert np.abs(other.states[2:, State.s] - adopted.states[2:, State.s]).max() > 1.0
    planner.restore(memory)
    # The next step's guess is the adopted plan shifted by one stage, from the new state on.
    x1 = adopted.states[1].copy()
    planner.step(x1, 0.1, straight, mu_08, [], "cruise", 15.0)
    guess = backend.guesses[-1]
    np.testing.assert_array_equal(guess[0], x1)
    np.testing.assert_array_equal(guess[1:-1], adopted.states[2:])
