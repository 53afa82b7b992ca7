"""Shared reports as a third fusion source (decision 0060): no reports changes nothing; safe
mode's guarantee holds with reports; the one-sided rule, the trust test, ageing, the sender cap.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.estimators.shared import FrictionReport
from mufusion.fusion import (
    DEFAULT_GRID_M,
    PAPER_PRIOR,
    GPFusion,
    SharedSettings,
    assemble_inputs,
    fuse,
    report_data,
    screen_reports,
)

GRID = DEFAULT_GRID_M
CLASSES = ((0.25, 0.15), (0.5, 0.1), (0.8, 0.2))  # snow/ice, wet, dry: (value, margin)


def _own(mu_class, margin_class, local_mu, mode):
    return assemble_inputs(GRID, mu_class, margin_class, local_mu=local_mu, mode=mode)


def _fuse(data, mode, reports=None):
    return fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, GRID, groups=data.groups,
                mode=mode, reports=reports)


def _reports(pairs, *, t_now_s=0.0, s_ego_m=0.0, settings_=None, **kw):
    rs = [FrictionReport.numeric(s, mu, 0.025, **kw) for s, mu in pairs]
    extra = {} if settings_ is None else {"settings": settings_}
    return report_data(rs, t_now_s=t_now_s, s_ego_m=s_ego_m, prior=PAPER_PRIOR, **extra)


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_no_reports_is_bit_identical(mode):
    data = _own(np.full(51, 0.5), np.full(51, 0.1), 0.48, mode)
    base = _fuse(data, mode)
    empty = _reports([])
    for other in (_fuse(data, mode, None), _fuse(data, mode, empty)):
        for name in ("mean", "std", "lower", "mu_hat"):
            assert np.array_equal(getattr(base, name), getattr(other, name))
    step = GPFusion(PAPER_PRIOR, GRID, mode=mode).step(data, empty)
    assert np.array_equal(step.mu_hat, base.mu_hat)


def test_fuse_rejects_a_wrong_reports_type():
    data = _own(np.full(51, 0.5), np.full(51, 0.1), None, "safe")
    with pytest.raises(ValueError, match="reports must be a ReportData"):
        _fuse(data, "safe", reports=[1, 2])


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_fresh_accurate_reports_raise_the_bound_and_old_ones_do_not(mode):
    # True μ 0.5 on wet: the camera's class 0.5 ± 0.1, no local estimate.
    data = _own(np.full(51, 0.5), np.full(51, 0.1), None, mode)
    base = _fuse(data, mode).mu_hat
    pairs = [(s, 0.5) for s in np.arange(0.0, 51.0, 2.0)]
    fresh = _fuse(data, mode, _reports(pairs, t_now_s=10.0)).mu_hat
    old = _fuse(data, mode, _reports(pairs, t_now_s=3.0 * 3600.0,
                                     settings_=SharedSettings(validity_s=1e5))).mu_hat
    assert (fresh >= base - 1e-12).all() and (fresh > base + 0.01).any()
    assert (fresh <= 0.5 + 1e-12).all()
    assert (old <= base + 1e-3).all()  # aged towards the prior: (almost) nothing left to add


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_an_unconfirmed_high_report_never_raises_mu_hat(mode):
    # The camera is out (no class data): only the local estimate near the vehicle is own data.
    nan = np.full(51, np.nan)
    data = _own(nan, nan, 0.3, mode)
    base = _fuse(data, mode).mu_hat
    high = _fuse(data, mode, _reports([(30.0, 0.9), (32.0, 0.9), (34.0, 0.9)], t_now_s=1.0))
    assert (high.mu_hat <= base + 1e-12).all()


def test_a_low_report_lowers_mu_hat_even_against_the_camera():
    data = _own(np.full(51, 0.8), np.full(51, 0.2), None, "safe")
    base = _fuse(data, "safe").mu_hat
    ice = _fuse(data, "safe", _reports([(20.0, 0.15)], t_now_s=1.0)).mu_hat
    assert ice[20] < base[20] - 0.1
    assert (ice <= base + 1e-12).all()


def test_trust_test_rejects_only_optimistic_inconsistency():
    data = _own(np.full(51, 0.5), np.full(51, 0.1), None, "safe")
    rd = _reports([(10.0, 0.55), (10.0, 0.9), (10.0, 0.1)])
    assert screen_reports(data, rd).kept.tolist() == [True, False, True]
    off = _reports([(10.0, 0.9)], settings_=SharedSettings(trust_test=False))
    assert screen_reports(data, off).kept.tolist() == [True]


def test_one_sender_many_copies_shrink_the_band_less_than_many_senders():
    data = _own(np.full(51, 0.5), np.full(51, 0.1), None, "paper")
    pairs = [(25.0, 0.5)] * 12
    one = _fuse(data, "paper", _reports(pairs, sender="one")).std
    rs = [FrictionReport.numeric(25.0, 0.5, 0.025, sender=f"s{i}") for i in range(12)]
    many = _fuse(data, "paper", report_data(rs, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR)).std
    assert one[25] > many[25] * 1.5


def test_reports_are_placed_relative_to_the_vehicle_and_expire():
    rd = _reports([(110.0, 0.5), (500.0, 0.5)], t_now_s=0.0, s_ego_m=100.0)
    assert rd.s_m.tolist() == [10.0]
    gone = _reports([(110.0, 0.5)], t_now_s=4000.0, s_ego_m=100.0)
    assert gone.size == 0


@pytest.mark.parametrize(
    ("field", "value"), [("tau_s", 0.0), ("reach_m", -1.0), ("sender_cap", 0.5),
                         ("gradient_bound_per_m", 2.0)])
def test_settings_name_the_bad_field(field, value):
    with pytest.raises(ValueError, match=field):
        SharedSettings(**{field: value})


def test_report_record_checks_its_triple():
    with pytest.raises(ValueError, match="lower_mu <= mu <= upper_mu"):
        FrictionReport(1.0, 0.5, 0.6, 0.7)
    with pytest.raises(ValueError, match="position_std_m"):
        FrictionReport(1.0, 0.5, 0.4, 0.6, position_std_m=-1.0)


def _truth(changes, values):
    """True μ(x): ``values[k]`` between ``changes[k-1]`` and ``changes[k]`` (piecewise constant)."""
    def mu(x):
        return np.asarray(values)[np.searchsorted(np.asarray(changes), x, side="right")]
    return mu


@settings(max_examples=80, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_changes=st.integers(0, 3),
    n_reports=st.integers(1, 40),
    local=st.booleans(),
    pos_sd=st.sampled_from([0.0, 0.3, 1.5]),
    age_s=st.sampled_from([0.0, 30.0, 900.0, 7200.0]),
)
def test_safe_mode_never_exceeds_the_truth_with_reports_in_their_bounds(
    seed, n_changes, n_reports, local, pos_sd, age_s
):
    """Decision 0060's guarantee: every own datum and every report within its declared bounds
    (errors within margins, position within 1.96 σ_s, surface constant within a camera class
    segment, unchanged since the report) ⇒ μ̂ ≤ μ_gt at every own data position."""
    rng = np.random.default_rng(seed)
    changes = np.sort(rng.uniform(0.5, 49.5, n_changes))
    cls = [int(rng.integers(3))]
    for _ in range(n_changes):  # neighbouring segments of different classes
        cls.append(int(rng.choice([c for c in range(3) if c != cls[-1]])))
    values = [CLASSES[c][0] + rng.uniform(-1.0, 1.0) * CLASSES[c][1] for c in cls]
    mu = _truth(changes, values)
    seg_at = np.searchsorted(changes, GRID, side="right")
    mu_class = np.array([CLASSES[cls[k]][0] for k in seg_at])
    margin_class = np.array([CLASSES[cls[k]][1] for k in seg_at])
    local_mu = float(mu(0.0)) + rng.uniform(-0.025, 0.025) if local else None
    data = _own(mu_class, margin_class, local_mu, "safe")
    reports = []
    for i in range(n_reports):
        x_true = rng.uniform(-5.0, 55.0)
        x_rep = x_true + rng.uniform(-1.0, 1.0) * 1.96 * pos_sd
        margin = rng.choice([0.025, 0.05, 0.1])
        y = float(np.clip(mu(x_true) + rng.uniform(-1.0, 1.0) * margin, 0.0, 2.0))
        reports.append(FrictionReport.numeric(
            x_rep, y, margin, t_created_s=-age_s, position_std_m=pos_sd, sender=f"v{i % 4}"))
    rd = report_data(reports, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    est = _fuse(data, "safe", rd)
    assert (est.mu_hat <= mu(GRID) + 1e-9).all()
    assert (est.mu_hat <= _fuse(data, "paper", rd).mu_hat + 1e-9).all()
