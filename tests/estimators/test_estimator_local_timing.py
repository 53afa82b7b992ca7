"""Timing of the local estimator: sampling, buffer, axle, publishing and delay (LocalTiming)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from mufusion.estimators import (
    AUTHORS_LOCAL_TIMING,
    PAPER_LOCAL_TIMING,
    LocalEstimator,
    LocalTiming,
    local_timing,
)

PLANT_DT_S = 0.005  # 200 Hz plant, the loop's default
PLAN_EVERY = 20  # 10 Hz planner


def _drive(est, util_front, util_rear=None, mu_front=None, mu_rear=None, duration_s=3.0):
    """Run the loop's order: plan at t = k/10 s, then a plant step whose output is stamped t + dt.

    The signals are functions of time. Returns the planning times and the estimates.
    """
    util_rear = util_rear or (lambda t: 0.0)
    mu_front = mu_front or (lambda t: 0.8)
    mu_rear = mu_rear or mu_front
    times, outs = [], []
    for i in range(round(duration_s / PLANT_DT_S) + 1):
        t = i * PLANT_DT_S
        if i % PLAN_EVERY == 0:
            times.append(t)
            outs.append(est.update_at(t))
        t_end = (i + 1) * PLANT_DT_S
        est.observe(t_end, util_front(t_end), util_rear(t_end), mu_front(t_end), mu_rear(t_end))
    return np.array(times), outs


def _first_available(times, outs):
    hits = [t for t, o in zip(times, outs, strict=True) if o.available]
    return hits[0] if hits else math.nan


def _step(t0, high=0.8, low=0.2):
    return lambda t: high if t >= t0 - 1e-12 else low


@pytest.mark.parametrize("t0", [1.0, 1.005, 1.05, 1.095])
def test_paper_timing_detects_a_step_at_the_next_planning_step(t0):
    times, outs = _drive(LocalEstimator(initial_mu=0.8), _step(t0))
    # The first planning step whose interval holds an excited sample: no delay beyond it.
    assert _first_available(times, outs) == pytest.approx(math.ceil(t0 / 0.1 - 1e-9) * 0.1)


@pytest.mark.parametrize("t0", [1.0, 1.005, 1.1, 1.2, 1.26, 1.49])
def test_authors_timing_detects_at_the_next_4hz_sample_read_by_the_next_plan(t0):
    est = LocalEstimator(initial_mu=0.8, timing=AUTHORS_LOCAL_TIMING)
    times, outs = _drive(est, _step(t0))
    sample = math.ceil(t0 / 0.25 - 1e-9) * 0.25
    expected = math.ceil(sample / 0.1 - 1e-9) * 0.1
    first = _first_available(times, outs)
    assert first == pytest.approx(expected)
    assert 0.0 <= first - t0 <= 0.35 + 1e-9


def test_authors_sampling_phase_moves_the_detection():
    timing = dataclasses.replace(AUTHORS_LOCAL_TIMING, phase_s=0.1)
    times, outs = _drive(LocalEstimator(initial_mu=0.8, timing=timing), _step(1.01))
    assert _first_available(times, outs) == pytest.approx(1.1)  # sample at 1.1 s, not 1.25 s


def test_authors_timing_holds_one_excited_sample_for_three_samples():
    # A 10 ms pulse that the 4 Hz sample at t = 1.0 s catches.
    pulse = lambda t: 0.9 if 0.99 <= t <= 1.0 + 1e-9 else 0.1  # noqa: E731
    times, outs = _drive(LocalEstimator(initial_mu=0.8, timing=AUTHORS_LOCAL_TIMING), pulse)
    available = times[[o.available for o in outs]]
    assert available.min() == pytest.approx(1.0)
    assert available.max() == pytest.approx(1.7)  # published at 1.0, 1.25, 1.5; not at 1.75
    assert AUTHORS_LOCAL_TIMING.hold_s == pytest.approx(0.75)
    # The paper's timing sees the same pulse for one planning step only.
    times, outs = _drive(LocalEstimator(initial_mu=0.8), pulse)
    assert times[[o.available for o in outs]].tolist() == pytest.approx([1.0])


def test_instant_sampling_misses_excitation_between_samples_and_peak_does_not():
    pulse = lambda t: 0.9 if 1.05 <= t <= 1.2 else 0.1  # noqa: E731  between 1.0 and 1.25
    times, outs = _drive(LocalEstimator(initial_mu=0.8, timing=AUTHORS_LOCAL_TIMING), pulse)
    assert not any(o.available for o in outs)
    peak = dataclasses.replace(AUTHORS_LOCAL_TIMING, sample_statistic="peak")
    times, outs = _drive(LocalEstimator(initial_mu=0.8, timing=peak), pulse)
    assert _first_available(times, outs) == pytest.approx(1.3)


@pytest.mark.parametrize(
    ("axle", "front_excited", "rear_excited", "expected"),
    [
        ("front", True, False, True),
        ("front", False, True, False),
        ("rear", True, False, False),
        ("rear", False, True, True),
        ("either", True, False, True),
        ("either", False, True, True),
    ],
)
def test_axle_selects_whose_utilization_counts(axle, front_excited, rear_excited, expected):
    timing = dataclasses.replace(AUTHORS_LOCAL_TIMING, axle=axle)
    excited, calm = _step(1.0), (lambda t: 0.1)
    _, outs = _drive(
        LocalEstimator(initial_mu=0.8, timing=timing),
        excited if front_excited else calm,
        excited if rear_excited else calm,
        mu_front=lambda t: 0.4,
        mu_rear=lambda t: 0.6,
    )
    assert any(o.available for o in outs) is expected
    if expected:
        # μ is read under the front axle, or under the rear one when the rear decides.
        assert outs[-1].mu == pytest.approx(0.6 if axle == "rear" else 0.4)


def test_detection_delay_shifts_what_the_planner_sees():
    delayed = LocalTiming(detection_delay_s=0.2)
    times, outs = _drive(LocalEstimator(initial_mu=0.8, timing=delayed), _step(1.0))
    assert _first_available(times, outs) == pytest.approx(1.2)
    authors_delayed = dataclasses.replace(AUTHORS_LOCAL_TIMING, detection_delay_s=0.1)
    times, outs = _drive(LocalEstimator(initial_mu=0.8, timing=authors_delayed), _step(1.01))
    # Sampled at 1.25 s, visible from 1.35 s, read by the plan at 1.4 s.
    assert _first_available(times, outs) == pytest.approx(1.4)


def test_authors_timing_measures_the_mu_under_the_axle_at_publish_time():
    # Excited on μ = 0.4 until 1.0 s, then calm on μ = 0.8: while the excited sample is in the
    # buffer, each publish re-measures the μ under the front axle now (the authors' emulation).
    util = lambda t: 0.9 if t <= 1.0 + 1e-9 else 0.1  # noqa: E731
    mu = lambda t: 0.4 if t <= 1.1 else 0.8  # noqa: E731
    est = LocalEstimator(initial_mu=0.8, timing=AUTHORS_LOCAL_TIMING)
    times, outs = _drive(est, util, mu_front=mu)
    by_time = dict(zip(np.round(times, 3), outs, strict=True))
    assert by_time[1.0].available and by_time[1.0].mu == pytest.approx(0.4)
    assert by_time[1.3].available and by_time[1.3].mu == pytest.approx(0.8)
    assert not by_time[1.8].available and by_time[1.8].mu == pytest.approx(0.8)


def test_paper_timing_through_observe_matches_the_legacy_update():
    rng = np.random.default_rng(3)
    util = rng.uniform(0.0, 0.7, size=602)
    mu = np.where(np.arange(602) < 300, 0.8, 0.4)  # μ at t = i·dt
    timed = LocalEstimator(error="random", rng=np.random.default_rng(9), initial_mu=0.8)
    legacy = LocalEstimator(error="random", rng=np.random.default_rng(9), initial_mu=0.8)
    window = 0.0
    n_available = 0
    for i in range(601):
        if i % PLAN_EVERY == 0:
            a = timed.update_at(i * PLANT_DT_S)
            # The loop's aggregate: the peak of either axle since the last planning step.
            b = legacy.update(float(mu[i]), window)
            window = 0.0
            assert (a.available, a.mu) == (b.available, pytest.approx(b.mu))
            n_available += a.available
        timed.observe((i + 1) * PLANT_DT_S, util[i + 1], 0.0, float(mu[i + 1]))
        window = max(window, util[i + 1])
    assert 0 < n_available < 31  # both outcomes occur


def test_legacy_update_keeps_a_buffer_of_planning_steps():
    est = LocalEstimator(initial_mu=0.8, timing=LocalTiming(buffer_length=3))
    flags = [est.update(0.4, u).available for u in (0.7, 0.1, 0.1, 0.1, 0.6, 0.2)]
    assert flags == [True, True, True, False, True, True]


def test_first_observation_measures_when_there_is_no_initial_value():
    est = LocalEstimator(error="worst_under", timing=AUTHORS_LOCAL_TIMING)
    with pytest.raises(ValueError, match="observation first"):
        est.update_at(0.0)
    est.observe(0.0, 0.0, 0.0, 0.8)
    first = est.update_at(0.0)
    # The authors' wce_local = -0.025 is the worst-case under-estimate.
    assert not first.available and first.mu == pytest.approx(0.775)


def test_timed_and_legacy_paths_do_not_mix():
    with pytest.raises(ValueError, match="observe"):
        LocalEstimator(initial_mu=0.8, timing=AUTHORS_LOCAL_TIMING).update(0.8, 0.9)
    est = LocalEstimator(initial_mu=0.8)
    est.observe(0.1, 0.2, 0.2, 0.8)
    with pytest.raises(ValueError, match="update_at"):
        est.update(0.8, 0.9)
    est.reset()
    assert est.update(0.8, 0.9).available


def test_time_must_not_go_back():
    est = LocalEstimator(initial_mu=0.8)
    est.observe(1.0, 0.2, 0.2, 0.8)
    with pytest.raises(ValueError, match="back in time"):
        est.observe(0.5, 0.2, 0.2, 0.8)
    est.update_at(1.0)
    with pytest.raises(ValueError, match="back in time"):
        est.update_at(0.9)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (dict(sample_rate_hz=0.0), "sample_rate_hz"),
        (dict(sample_rate_hz=math.inf), "sample_rate_hz"),
        (dict(publish_rate_hz=4.0), "needs a sample_rate_hz"),
        (dict(buffer_length=0), "buffer_length"),
        (dict(buffer_length=2.0), "buffer_length"),
        (dict(axle="both"), "axle"),
        (dict(sample_statistic="mean"), "sample_statistic"),
        (dict(detection_delay_s=-0.1), "detection_delay_s"),
        (dict(sample_rate_hz=4.0, phase_s=0.25), "phase_s"),
        (dict(phase_s=0.1), "phase_s"),
    ],
)
def test_timing_rejects_bad_fields(kwargs, match):
    with pytest.raises(ValueError, match=match):
        LocalTiming(**kwargs)


def test_observe_rejects_bad_input():
    rear = dataclasses.replace(PAPER_LOCAL_TIMING, axle="rear")
    est = LocalEstimator(initial_mu=0.8, timing=rear)
    with pytest.raises(ValueError, match="mu_true_rear is needed"):
        est.observe(0.0, 0.1, 0.1, 0.8)
    with pytest.raises(ValueError, match="utilization_front"):
        est.observe(0.0, -0.1, 0.1, 0.8, 0.8)
    with pytest.raises(ValueError, match="mu_true_front"):
        est.observe(0.0, 0.1, 0.1, 0.0, 0.8)
    with pytest.raises(ValueError, match="t_s"):
        est.observe(math.nan, 0.1, 0.1, 0.8, 0.8)
    with pytest.raises(ValueError, match="timing must be a LocalTiming"):
        LocalEstimator(timing="authors")


def test_presets_by_name():
    assert local_timing("paper") is PAPER_LOCAL_TIMING
    assert local_timing("authors") is AUTHORS_LOCAL_TIMING
    assert PAPER_LOCAL_TIMING.hold_s is None
    with pytest.raises(ValueError, match="authors"):
        local_timing("fast")
