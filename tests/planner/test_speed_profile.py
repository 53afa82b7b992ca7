"""Curvature- and friction-aware speed reference: hand calculations and its effect on the plan."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.planner.axle_reach import PitchTransfer
from mufusion.planner.ocp import PlannerConfig
from mufusion.planner.planner import TractionAdaptivePlanner
from mufusion.planner.speed_profile import (
    curve_speed_reference_mps,
    descent_limited_profile_mps,
    max_speed_profile_mps,
    regain_limited_profile_mps,
)
from mufusion.planner.under_axles import sharpest_under_axles
from mufusion.vehicle.params import CAR, GRAVITY_MPS2, TRUCK
from mufusion.vehicle.planner_model import State

ARC_START_M = 30.0
RADIUS_M = 28.0


def _curvature(s):
    return np.where(np.asarray(s, dtype=float) >= ARC_START_M, 1.0 / RADIUS_M, 0.0)


def _mu(value):
    return lambda s: value + 0.0 * np.asarray(s, dtype=float)


def test_profile_matches_hand_calculation_on_a_fine_grid() -> None:
    s = np.arange(0.0, 40.01, 0.01)
    v = max_speed_profile_mps(s, _curvature(s), np.full(s.size, 0.4), 0.9, 30.0)
    # On the arc: √(0.9·0.4·9.81·28) = √98.8848 = 9.94408 m/s
    assert v[-1] == pytest.approx(9.94408, abs=1e-5)
    # 30 m before it: √(98.8848 + 2·3.5316·30) = √310.7808 = 17.62898 m/s, less one 1 cm step
    # (√(98.8848 + 2·3.5316·29.99) = √310.71016 = 17.62697)
    assert v[0] == pytest.approx(17.62697, abs=1e-4)


def test_profile_is_capped_by_the_end_speed_and_flat_on_a_straight() -> None:
    s = np.arange(0.0, 100.0)
    v = max_speed_profile_mps(s, np.zeros_like(s), np.full(s.size, 0.5), 0.9, 14.0)
    assert np.allclose(v, 14.0)


def test_profile_respects_every_curvature_limit() -> None:
    s = np.arange(0.0, 120.0, 0.5)
    kappa = np.interp(s, [0, 40, 45, 80, 85, 120], [0, 0, 1 / 20, 1 / 20, 0, 0])
    mu = np.where(s > 60.0, 0.3, 0.8)
    v = max_speed_profile_mps(s, kappa, mu, 0.9, 25.0)
    with np.errstate(divide="ignore"):
        limit = np.sqrt(0.9 * mu * 9.81 / kappa)
    assert np.all(v <= limit + 1e-9)
    # Decelerating between grid points never needs more than the friction the profile may use.
    dv2 = np.diff(v**2) / np.diff(s)
    assert np.all(-dv2 / 2.0 <= 0.9 * 0.8 * 9.81 + 1e-9)


def test_braking_fraction_starts_the_ramp_earlier_by_hand() -> None:
    s = np.arange(0.0, 40.01, 0.01)
    v = max_speed_profile_mps(s, _curvature(s), np.full(s.size, 0.4), 0.9, 30.0,
                              braking_fraction=0.5)
    # The arc's limit is unchanged: √98.8848 = 9.94408 m/s.
    assert v[-1] == pytest.approx(9.94408, abs=1e-5)
    # Half the deceleration before it: √(98.8848 + 3.5316·29.99) = √204.7974 = 14.31074 m/s.
    assert v[0] == pytest.approx(14.31074, abs=1e-4)
    full = max_speed_profile_mps(s, _curvature(s), np.full(s.size, 0.4), 0.9, 30.0)
    assert np.all(v <= full)
    np.testing.assert_array_equal(v[s >= ARC_START_M], full[s >= ARC_START_M])


def test_reference_with_a_braking_reserve_slows_earlier_and_reaches_as_far() -> None:
    stages = np.linspace(0.0, 56.0, 41)
    curve = lambda s: np.where(np.asarray(s) >= 60.0, 1 / 28, 0.0)  # noqa: E731
    full = curve_speed_reference_mps(stages, curve, _mu(0.4), 14.0, 0.9, 4.0)
    reserve = curve_speed_reference_mps(stages, curve, _mu(0.4), 14.0, 0.9, 4.0,
                                        braking_fraction=0.6)
    np.testing.assert_array_equal(
        full, curve_speed_reference_mps(stages, curve, _mu(0.4), 14.0, 0.9, 4.0, 1.0))
    # Full braking reaches 14 m/s 12.9 m before the arc ((196 − 98.88) / (2·3.5316) = 13.75 m,
    # on the 1 m grid); with 0.6 of it, (196 − 98.88) / (1.2·3.5316) = 22.9 m before it.
    assert full[stages <= 60.0 - 14.0].min() == pytest.approx(14.0)
    assert reserve[stages >= 60.0 - 22.0].max() < 14.0
    assert np.all(reserve <= full)


def test_profile_rejects_bad_input() -> None:
    s = np.arange(3.0)
    with pytest.raises(ValueError, match="accel_fraction"):
        max_speed_profile_mps(s, np.zeros(3), np.ones(3), 1.5, 10.0)
    for bad in (0.0, 1.2, float("nan")):
        with pytest.raises(ValueError, match="braking_fraction"):
            max_speed_profile_mps(s, np.zeros(3), np.ones(3), 0.9, 10.0, braking_fraction=bad)
    with pytest.raises(ValueError, match="s_m must increase"):
        max_speed_profile_mps(s[::-1], np.zeros(3), np.ones(3), 0.9, 10.0)
    with pytest.raises(ValueError, match="equal length"):
        max_speed_profile_mps(s, np.zeros(2), np.ones(3), 0.9, 10.0)


def test_reference_sees_a_curve_beyond_the_time_horizon() -> None:
    # Stages cover 0–56 m (4 s at 14 m/s); the arc starts at 100 m on μ 0.4.
    stages = np.linspace(0.0, 56.0, 41)
    ref = curve_speed_reference_mps(stages, lambda s: np.where(np.asarray(s) >= 100.0, 1 / 28, 0.0),
                                    _mu(0.4), 14.0, 0.9, 4.0)
    assert ref[0] == pytest.approx(14.0)
    # 44 m before the arc: √(98.8848 + 2·3.5316·43) = 19.4 m/s > 14, so still the cruise speed;
    # a tighter curve (R = 10 m) at 100 m must already slow the last stages.
    tight = curve_speed_reference_mps(stages, lambda s: np.where(np.asarray(s) >= 100.0, 0.1, 0.0),
                                      _mu(0.2), 14.0, 0.9, 4.0)
    assert tight[-1] < 14.0 - 0.5
    assert np.all(np.diff(tight) <= 1e-12)


@pytest.fixture(scope="module")
def planners() -> tuple[TractionAdaptivePlanner, TractionAdaptivePlanner]:
    lane = dict(lane_d_min_m=-0.35, lane_d_max_m=0.35)
    return (TractionAdaptivePlanner(TRUCK, PlannerConfig(**lane)),
            TractionAdaptivePlanner(TRUCK, PlannerConfig(curve_speed_reference=False, **lane)))


def _arc_entry_speed(planner: TractionAdaptivePlanner, steps: int = 25) -> float:
    """Speed at the arc's start when the planner's model follows each plan's first step."""
    planner._prev = None
    x = np.array([0.0, 0.0, 0.0, 0.0, 14.0, 0.0])
    states = [x]
    for i in range(steps):
        plan = planner.step(x, 0.1 * i, _curvature, _mu(0.4), [], "cruise", 14.0)
        x = plan.states[1]
        states.append(x)
    trajectory = np.array(states)
    return float(np.interp(ARC_START_M, trajectory[:, State.s], trajectory[:, State.vx]))


def test_plan_enters_the_arc_at_the_speed_it_can_hold(planners) -> None:
    with_ref, without = planners
    # What the 12-gon of radius λμF_z grants in pure cornering: √(0.9·cos15°·0.4·9.81·28) = 9.773
    v_polygon = math.sqrt(0.9 * math.cos(math.pi / 12) * 0.4 * 9.81 * RADIUS_M)
    v_with, v_without = _arc_entry_speed(with_ref), _arc_entry_speed(without)
    assert v_with <= v_polygon + 0.15
    # Tracking the cruise speed alone, the plans brake as late as their horizon allows and the
    # vehicle reaches the arc far above what it can hold there (11.4 m/s when this was written).
    assert v_without > v_with + 1.0


def test_the_reference_reaches_the_curve_speed_before_the_front_axle_and_a_torque_lag() -> None:
    """With the curvature under the axles (as the planner builds its reference) the arc's speed
    is reached where the front axle plus one torque lag at the speed reaches the arc; at the
    centre of gravity's curvature the reference is still above it there."""
    speed, fraction, mu = 18.0, 0.9 * math.cos(math.pi / 12), 0.9
    ahead = TRUCK.cog_to_front_axle_m + speed * TRUCK.torque_time_constant_s
    s = np.array([ARC_START_M - ahead - 30.0, ARC_START_M - ahead, ARC_START_M])
    v_arc = math.sqrt(fraction * mu * GRAVITY_MPS2 * RADIUS_M)
    kappa = sharpest_under_axles(_curvature, TRUCK.cog_to_rear_axle_m, ahead)
    at_axles = curve_speed_reference_mps(s, kappa, _mu(mu), speed, fraction, 4.0)
    at_cog = curve_speed_reference_mps(s, _curvature, _mu(mu), speed, fraction, 4.0)
    assert at_axles[1] <= v_arc + 0.05
    assert at_cog[1] > v_arc + 0.5
    assert at_axles[2] == pytest.approx(at_cog[2], abs=0.05)


def _textbook_profile(s, kappa, mu, accel_fraction, end_speed):
    """The recursion written out on numpy arrays (what the fast pass must reproduce bit for bit)."""
    kappa = np.abs(kappa)
    accel = accel_fraction * mu * GRAVITY_MPS2
    u = np.minimum(np.where(kappa > 0.0, accel / np.maximum(kappa, 1e-300), np.inf),
                   end_speed**2)
    for i in range(s.size - 2, -1, -1):
        lateral = u[i + 1] * max(kappa[i], kappa[i + 1])
        # Squares as products, like the fast pass: numpy's scalar ``** 2`` may round differently.
        braking = np.sqrt(max(accel[i] * accel[i] - lateral * lateral, 0.0))
        u[i] = min(u[i], u[i + 1] + 2.0 * braking * (s[i + 1] - s[i]))
    return np.sqrt(u)


@settings(max_examples=200, deadline=None)
@given(
    steps=st.lists(st.floats(0.1, 3.0), min_size=1, max_size=120),
    data=st.data(),
    end_speed=st.floats(1.0, 40.0),
)
def test_profile_equals_the_textbook_recursion_bit_for_bit(steps, data, end_speed):
    n = len(steps)
    s = np.cumsum(steps)
    kappa = np.array(data.draw(st.lists(st.sampled_from([0.0, 1 / 25, -1 / 60, 1 / 150]),
                                        min_size=n, max_size=n)))
    mu = np.array(data.draw(st.lists(st.floats(0.05, 1.2), min_size=n, max_size=n)))
    with np.errstate(divide="ignore"):
        expected = _textbook_profile(s, kappa, mu, 0.9, end_speed)
    np.testing.assert_array_equal(max_speed_profile_mps(s, kappa, mu, 0.9, end_speed), expected)


def test_regaining_speed_in_a_curve_by_hand() -> None:
    s = np.array([0.0, 1.0, 2.0])
    kappa, mu, frac = np.full(3, 1 / 28), np.full(3, 0.9), 0.9 * math.cos(math.pi / 12)
    v = regain_limited_profile_mps(s, kappa, mu, frac, np.full(3, 14.66), 13.4, 1.5)
    a = frac * 0.9 * GRAVITY_MPS2  # 7.6762 m/s²
    share = math.sqrt(1 - (13.4**2 / 28 / a) ** 2)  # 0.5495: the ellipse at 6.41 m/s² lateral
    assert v[0] == 13.4
    assert v[1] == pytest.approx(math.sqrt(13.4**2 + 2 * 1.5 * share * 1.0), rel=1e-12)
    straight = regain_limited_profile_mps(s, np.zeros(3), mu, frac, np.full(3, 14.66), 13.4, 1.5)
    assert straight[1] == pytest.approx(math.sqrt(13.4**2 + 3.0), rel=1e-12)
    assert v[2] < straight[2]
    # At the lateral limit nothing is left to regain speed with.
    at_limit = regain_limited_profile_mps(s, np.full(3, 1.0), mu, frac, np.full(3, 20.0),
                                          math.sqrt(a), 1.5)
    np.testing.assert_allclose(at_limit, math.sqrt(a), rtol=1e-7)  # rounding of v²κ/a at 1


def test_regain_within_a_share_of_the_lateral_friction_by_hand() -> None:
    s = np.array([0.0, 1.0, 2.0])
    kappa, mu, frac = np.full(3, 1 / 28), np.full(3, 0.9), 0.9 * math.cos(math.pi / 12)
    a = frac * 0.9 * GRAVITY_MPS2  # 7.6762 m/s²
    # 13.4 m/s on R 28 m is 6.41 m/s² lateral: within the whole friction, beyond 0.8 of it.
    beyond = regain_limited_profile_mps(s, kappa, mu, frac, np.full(3, 14.66), 13.4, 1.5, 0.8)
    np.testing.assert_array_equal(beyond, 13.4)
    # 12 m/s is 5.14 m/s² lateral, within 0.8 a = 6.14 m/s²: the ellipse against 0.8 a.
    within = regain_limited_profile_mps(s, kappa, mu, frac, np.full(3, 14.66), 12.0, 1.5, 0.8)
    ellipse = math.sqrt(1 - (12.0**2 / 28 / (0.8 * a)) ** 2)
    assert within[1] == pytest.approx(math.sqrt(12.0**2 + 2 * 1.5 * ellipse), rel=1e-12)
    whole = regain_limited_profile_mps(s, kappa, mu, frac, np.full(3, 14.66), 12.0, 1.5)
    assert within[1] < whole[1]
    # On a straight the share changes nothing; the share is validated.
    straight = regain_limited_profile_mps(s, np.zeros(3), mu, frac, np.full(3, 14.66), 12.0, 1.5,
                                          0.8)
    assert straight[1] == pytest.approx(math.sqrt(12.0**2 + 3.0), rel=1e-12)
    with pytest.raises(ValueError, match="share"):
        regain_limited_profile_mps(s, kappa, mu, frac, np.full(3, 14.66), 12.0, 1.5, 0.0)


def _random_road(data, n: int):
    """A 1 m grid of ``n`` points with drawn curvatures and frictions, and its profile."""
    s = np.arange(float(n))
    kappa = np.array(data.draw(st.lists(st.sampled_from([0.0, 1 / 25, -1 / 60]),
                                        min_size=n, max_size=n)))
    mu = np.array(data.draw(st.lists(st.floats(0.05, 1.2), min_size=n, max_size=n)))
    with np.errstate(divide="ignore"):
        profile = max_speed_profile_mps(s, kappa, mu, 0.9, 25.0)
    return s, kappa, mu, profile


@settings(max_examples=100, deadline=None)
@given(start=st.floats(0.0, 30.0), cap=st.floats(0.1, 3.0),
       data=st.data(), n=st.integers(2, 60))
def test_regain_never_exceeds_the_profile_and_starts_at_the_vehicle(start, cap, data, n) -> None:
    s, kappa, mu, profile = _random_road(data, n)
    v = regain_limited_profile_mps(s, kappa, mu, 0.9, profile, start, cap)
    assert np.all(v <= profile + 1e-12)
    assert v[0] == pytest.approx(min(start, profile[0]), rel=1e-12)
    # Each step adds at most what the cap adds on a straight.
    assert np.all(np.diff(v**2) <= 2.0 * cap * np.diff(s) + 1e-9)


@settings(max_examples=100, deadline=None)
@given(start=st.floats(0.0, 30.0), data=st.data(), n=st.integers(2, 60))
def test_no_speed_is_regained_before_the_lowest_point_below_the_vehicle(start, data, n) -> None:
    s, kappa, mu, profile = _random_road(data, n)
    v = regain_limited_profile_mps(s, kappa, mu, 0.9, profile, start, 1.5)
    if profile.min() < v[0]:
        bottom = int(np.argmin(profile))
        # On the way there the reference never rises: the running minimum of the profile.
        held = np.minimum.accumulate(np.minimum(profile, v[0]))
        np.testing.assert_array_equal(v[: bottom + 1], held[: bottom + 1])
    else:
        # Nothing ahead is slower than the vehicle: the reference never asks it to slow down.
        assert np.all(v >= v[0] - 1e-12)


@settings(max_examples=100, deadline=None)
@given(start=st.floats(0.0, 30.0), share=st.floats(0.3, 1.0), data=st.data(),
       n=st.integers(2, 60))
def test_no_speed_is_regained_while_cornering_beyond_the_share(start, share, data, n) -> None:
    s, kappa, mu, profile = _random_road(data, n)
    v = regain_limited_profile_mps(s, kappa, mu, 0.9, profile, start, 1.5, share)
    lateral = v[:-1] ** 2 * np.maximum(np.abs(kappa[:-1]), np.abs(kappa[1:]))
    beyond = lateral >= share * 0.9 * mu[:-1] * GRAVITY_MPS2
    # Cornering at or beyond the share, the next point is never faster than this one.
    assert np.all(v[1:][beyond] <= v[:-1][beyond])
    # And the share never asks for more speed than the whole friction's ellipse.
    assert v[1] <= regain_limited_profile_mps(s, kappa, mu, 0.9, profile, start, 1.5)[1]


def test_a_vehicle_below_the_ramp_to_a_curve_holds_its_speed() -> None:
    # 16 m/s, 40 m before an arc whose limit on μ̂ 0.9 is 14.2 m/s, cruise speed 18 m/s: the
    # braking ramp towards the arc is above the vehicle for its first metres. Before it the
    # reference asked the vehicle to regain speed at the drive's cap there, to brake it away
    # again before the arc.
    curve = lambda s: np.where(np.asarray(s, dtype=float) >= 40.0, 1 / 28, 0.0)  # noqa: E731
    stages = np.linspace(0.0, 60.0, 41)
    ref = curve_speed_reference_mps(stages, curve, _mu(0.9), 18.0, 0.9, 4.0, 0.8,
                                    regain=(16.0, 1.5, 1.0))
    unlimited = curve_speed_reference_mps(stages, curve, _mu(0.9), 18.0, 0.9, 4.0, 0.8)
    assert unlimited[0] > 16.5  # the ramp lies above the vehicle here
    assert ref[0] == pytest.approx(16.0)
    assert np.all(ref[stages < 40.0] <= 16.0 + 1e-9)
    # The ramp itself is kept where it is below the vehicle: braking for the arc is unchanged.
    below = unlimited < 16.0
    np.testing.assert_allclose(ref[below & (stages < 40.0)], unlimited[below & (stages < 40.0)])


def test_regain_rejects_bad_input() -> None:
    s = np.arange(3.0)
    with pytest.raises(ValueError, match="start_speed_mps"):
        regain_limited_profile_mps(s, np.zeros(3), np.ones(3), 0.9, np.ones(3), -1.0, 1.5)
    with pytest.raises(ValueError, match="max_accel_mps2"):
        regain_limited_profile_mps(s, np.zeros(3), np.ones(3), 0.9, np.ones(3), 1.0, 0.0)


def test_the_cruise_reference_regains_speed_from_the_vehicle_in_a_curve() -> None:
    lane = dict(lane_d_min_m=-0.35, lane_d_max_m=0.35, use_sampling=False)
    refs = {}
    for limit in (True, False):
        planner = TractionAdaptivePlanner(TRUCK, PlannerConfig(reference_regain_limit=limit,
                                                               **lane))
        solve, seen = planner.backend.solve, []

        def spy(*args, _solve=solve, _seen=seen):
            _seen.append(np.array(args[4][:, State.vx]))  # the tracking reference's speeds
            return _solve(*args)

        planner._backend.solve = spy
        x = np.array([ARC_START_M + 5.0, 0.0, 0.0, 12.0 / RADIUS_M, 12.0, 0.0])
        planner.step(x, 0.0, _curvature, _mu(0.9), [], "cruise", 14.0)
        refs[limit] = seen[-1]
    # Without the limit the arc's reference is the cruise speed from the first stage (the arc
    # holds 14.66 m/s); with it the reference starts at the vehicle's 12 m/s and rises by less
    # than the cap's 1.5 m/s² would give on a straight over the first stages' distance.
    assert refs[False][0] == pytest.approx(14.0)
    assert refs[True][0] == pytest.approx(12.0)
    assert refs[True][5] < math.sqrt(12.0**2 + 2 * 1.5 * 5 * 0.1 * 12.0)
    assert np.all(np.diff(refs[True][:20]) >= -1e-12)


@settings(max_examples=150, deadline=None)
@given(
    steps=st.lists(st.floats(0.1, 3.0), min_size=1, max_size=120),
    data=st.data(),
    start=st.floats(0.0, 30.0),
    braking_fraction=st.floats(0.05, 1.0),
    transfer=st.sampled_from([None, PitchTransfer.of(TRUCK), PitchTransfer.of(CAR),
                              PitchTransfer(0.5, 0.0)]),
)
def test_the_compiled_passes_equal_the_python_loops_bit_for_bit(
    steps, data, start, braking_fraction, transfer
):
    # The compiled passes (where the install built them) replace the Python loops at every
    # planning step: the same IEEE operations in the same order, NaN and ties included.
    import mufusion.planner.speed_profile as sp

    if sp._COMPILED is None:
        pytest.fail("this install lacks the compiled speed-profile passes (pip install -e .)")
    n = len(steps)
    s = np.cumsum(steps)
    kappa = np.array(data.draw(st.lists(st.sampled_from([0.0, 1 / 25, -1 / 60, np.nan]),
                                        min_size=n, max_size=n)))
    mu = np.array(data.draw(st.lists(st.one_of(st.floats(0.05, 1.2), st.just(np.nan)),
                                     min_size=n, max_size=n)))

    def both():
        with np.errstate(divide="ignore", invalid="ignore"):
            profile = max_speed_profile_mps(s, kappa, mu, 0.9, 20.0, braking_fraction,
                                            transfer)
            return (profile, regain_limited_profile_mps(s, kappa, mu, 0.9, profile, start, 1.5),
                    descent_limited_profile_mps(s, kappa, mu, 0.9, profile, start + 5.0,
                                                braking_fraction, transfer))

    compiled = both()
    with pytest.MonkeyPatch.context() as m:
        m.setattr(sp, "_COMPILED", None)
        python = both()
    for got, expected in zip(compiled, python, strict=True):
        np.testing.assert_array_equal(got, expected)
