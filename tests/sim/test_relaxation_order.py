"""Lane recovery gives up the lower bound's guarantee faster where a measurement vouches for
more (``lane_recovery.measured_surface_first``, docs/decisions/0122): the surface the local
estimate measured at twice the pace of the road only the camera has seen."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from factories import straight_plan
from mufusion.configurations import FrictionEstimate
from mufusion.fusion import FusedEstimate, assemble_inputs
from mufusion.planner import Plan
from mufusion.sim.lane_recovery import LaneRecovery, RecoveryOutcome
from mufusion.sim.settings import LaneRecoverySettings
from mufusion.sim.supervision import RelaxationGain, relaxation_gain, relaxed_estimate
from mufusion.sim.supervisor import PlanningContext
from mufusion.vehicle.params import TRUCK

GRID = np.arange(0.0, 51.0)
N = 20
SURFACE_END_M = 30.0
"""The measured surface's class reaches 30 m ahead; a low class (0.25 ± 0.15) follows."""


def _estimate() -> FrictionEstimate:
    """F-safe before a drop to a surface only the camera has seen: the local estimate 0.805 ±
    0.025 on a dry class (0.8 ± 0.2) up to 30 m, a low class 0.25 ± 0.15 beyond. μ̂ is the
    classes' lower bounds (0.6 and 0.1); the relaxation's targets are 0.78 (the local guarantee)
    and 0.25 (the low class's reported value)."""
    near = GRID < SURFACE_END_M
    camera_mu, camera_margin = np.where(near, 0.8, 0.25), np.where(near, 0.2, 0.15)
    data = assemble_inputs(GRID, camera_mu, camera_margin, local_mu=0.805, mode="safe")
    mean = np.where(near, 0.8, 0.5)
    post = FusedEstimate(GRID, mean, np.full(51, 0.02), np.full(51, 0.6), np.full(51, 0.6))
    return FrictionEstimate(GRID, np.where(near, 0.6, 0.1), True, 0.805, fused=post, data=data)


def _plan(d_m: float) -> Plan:
    """A straight cruising plan at 20 m/s whose reference point ends ``d_m`` off the centre."""
    return straight_plan(d_m, n=N, length_m=40.0, speed_mps=20.0)


class _Planner:
    memory: object = None

    def restore(self, memory: object) -> None:
        self.memory = memory


def _recover(measured_first: bool) -> tuple[LaneRecovery, FrictionEstimate, list[float]]:
    """One cruising step whose friction-limited plan leaves a 4 m lane by 2 m; a candidate keeps
    the lane once μ̂ on the measured surface is at least 0.7 (braking harder there is what keeps
    it). Returns the supervisor, the estimate adopted and each candidate's μ̂ beyond the
    surface."""
    beyond: list[float] = []

    def plan(estimate: FrictionEstimate, mode: str) -> Plan:
        beyond.append(float(estimate.mu_hat[-1]))
        return _plan(0.0 if estimate.mu_hat[0] >= 0.7 - 1e-9 else 3.0)

    settings_ = LaneRecoverySettings(measured_surface_first=measured_first)
    recovery = LaneRecovery(settings_, _Planner(), TRUCK, (-0.7, 0.7), lambda s: np.zeros_like(s),
                            lambda *a: None)
    ctx = PlanningContext(0.0, np.array([0.0, 0.0, 0.0, 0.0, 20.0, 0.0]), [], False, "cruise",
                          plan, lambda e: "cruise")
    _, adopted = recovery.review(ctx, "cruise", _estimate(), _plan(3.0))
    return recovery, adopted, beyond


def test_the_measured_surface_is_relaxed_at_twice_the_pace_of_the_road_beyond() -> None:
    recovery, adopted, beyond = _recover(measured_first=True)
    assert recovery.recoveries[-1].outcome is RecoveryOutcome.RELAXED
    assert recovery.recoveries[-1].alpha == 0.5
    near = GRID < SURFACE_END_M
    # The measured surface at what the local estimate guarantees, the low class half its way.
    np.testing.assert_allclose(adopted.mu_hat, np.where(near, 0.78, 0.175))
    assert beyond == pytest.approx([0.1375, 0.175])
    # At one pace (the setting off) the plan that keeps the lane comes a step later, with the low
    # class at 0.2125: above a road of 0.19, which the class allows.
    recovery, adopted, beyond = _recover(measured_first=False)
    assert recovery.recoveries[-1].alpha == 0.75
    np.testing.assert_allclose(adopted.mu_hat, np.where(near, 0.735, 0.2125))
    assert beyond == pytest.approx([0.1375, 0.175, 0.2125])


def test_the_gain_splits_at_the_measured_surfaces_end() -> None:
    gain = relaxation_gain(_estimate())
    assert gain is not None
    near = GRID < SURFACE_END_M
    np.testing.assert_allclose(gain.measured, np.where(near, 0.18, 0.0), atol=1e-12)
    np.testing.assert_allclose(gain.reported, np.where(near, 0.0, 0.15), atol=1e-12)
    # At the top of the range the same estimate either way.
    a, b = relaxed_estimate(_estimate(), 1.0), relaxed_estimate(_estimate(), 1.0, False)
    assert a is not None and b is not None
    np.testing.assert_array_equal(a.mu_hat, b.mu_hat)


_PARTS = st.lists(st.tuples(st.booleans(), st.floats(0.0, 0.5)), min_size=1, max_size=12)


@settings(max_examples=200, deadline=None)
@given(parts=_PARTS, alpha=st.floats(0.0, 1.0), beta=st.floats(0.0, 1.0),
       measured_first=st.booleans())
def test_the_raise_grows_with_alpha_to_the_whole_gain(
    parts: list[tuple[bool, float]], alpha: float, beta: float, measured_first: bool
) -> None:
    on_surface = np.array([m for m, _ in parts])
    size = np.array([g for _, g in parts])
    gain = RelaxationGain(np.where(on_surface, size, 0.0), np.where(on_surface, 0.0, size))
    low, high = sorted((alpha, beta))
    raise_low, raise_high = gain.at(low, measured_first), gain.at(high, measured_first)
    assert np.all(raise_low >= 0.0) and np.all(raise_low <= raise_high + 1e-15)
    assert np.all(raise_high <= size + 1e-15)
    np.testing.assert_allclose(gain.at(1.0, measured_first), size, rtol=0, atol=1e-15)
    # The road beyond the measured surface is raised as at one pace, the surface at least so.
    at = gain.at(alpha, measured_first)
    np.testing.assert_array_equal(at[~on_surface], alpha * size[~on_surface])
    assert np.all(at >= alpha * size)
    staged = (measured_first and np.any(gain.measured > 1e-9)
              and np.any(gain.reported > 1e-9))
    pace = min(2.0 * alpha, 1.0) if staged else alpha
    np.testing.assert_array_equal(at[on_surface], pace * size[on_surface])


def test_measured_surface_first_must_be_a_bool() -> None:
    with pytest.raises(ValueError, match=r"lane_recovery\.measured_surface_first"):
        LaneRecoverySettings(measured_surface_first="yes")  # type: ignore[arg-type]
