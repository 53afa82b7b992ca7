"""Shared reports as a third fusion source (decision 0060): no reports changes nothing; safe
mode's guarantee holds with reports; the one-sided rule, the trust test, ageing, the sender cap.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.estimators.shared import AGE_KERNELS, REPORT_BOUNDS, FrictionReport
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
from mufusion.fusion.reports import age_variance
from mufusion.fusion.shared_fusion import conflicts

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
    # Two senders (safe mode's hard bound needs two to vouch for it, decision 0063).
    rs = [FrictionReport.numeric(s, 0.5, 0.025, sender=f"v{i % 2}")
          for i, s in enumerate(np.arange(0.0, 51.0, 1.0))]
    fresh = _fuse(data, mode, report_data(rs, t_now_s=10.0, s_ego_m=0.0,
                                          prior=PAPER_PRIOR)).mu_hat
    old = _fuse(data, mode, report_data(rs, t_now_s=3.0 * 3600.0, s_ego_m=0.0, prior=PAPER_PRIOR,
                                        settings=SharedSettings(validity_s=1e5))).mu_hat
    assert (fresh >= base - 1e-12).all() and (fresh > base + 0.01).any()
    assert (fresh <= 0.5 + 1e-12).all()
    # Aged towards the prior (σ ≈ 0.23 each): each sender counts at most as three reports of
    # the prior's spread (decision 0077), next to 51 camera points of σ 0.05: (almost) nothing
    # left to add.
    assert (old <= base + 2e-3).all()


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
                         ("gradient_bound_per_m", 2.0), ("report_bound", "max"),
                         ("age_kernel", "rbf"), ("corroboration", 0)])
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
    bound=st.sampled_from(REPORT_BOUNDS),
    kernel=st.sampled_from(AGE_KERNELS),
)
def test_safe_mode_never_exceeds_the_truth_with_reports_in_their_bounds(
    seed, n_changes, n_reports, local, pos_sd, age_s, bound, kernel
):
    """Decisions 0060 and 0063: every own datum and every report within its declared bounds
    (errors within margins, position within 1.96 σ_s, surface constant within a camera class
    segment, unchanged since the report) ⇒ μ̂ ≤ μ_gt at every own data position, with either
    rule of combining the reports and either ageing kernel."""
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
    rd = report_data(reports, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR,
                     settings=SharedSettings(report_bound=bound, age_kernel=kernel))
    est = _fuse(data, "safe", rd)
    assert (est.mu_hat <= mu(GRID) + 1e-9).all()
    assert (est.mu_hat <= _fuse(data, "paper", rd).mu_hat + 1e-9).all()


def _honest(rng, mu, n, *, spacing_m=2.0, sender="v"):
    """``n`` honest slip-estimate reports (± 0.025) every ``spacing_m`` from 1 m on."""
    return [FrictionReport.numeric(1.0 + spacing_m * i, mu + rng.uniform(-0.025, 0.025), 0.025,
                                   position_std_m=0.5, sender=f"{sender}{i % 2}")
            for i in range(n)]


@pytest.mark.parametrize("kernel", AGE_KERNELS)
def test_consistent_rule_gains_over_the_lowest_report_with_honest_reports(kernel):
    """Decision 0063: with honest reports the hard bound takes the best of them, not the worst:
    μ̂ rises further towards μ than with the segment minimum, and stays at or below μ."""
    rng = np.random.default_rng(3)
    data = _own(np.full(51, 0.5), np.full(51, 0.1), None, "safe")  # wet class, true μ 0.5
    reports = _honest(rng, 0.5, 25)
    hat = {}
    for bound in REPORT_BOUNDS:
        rd = report_data(reports, t_now_s=5.0, s_ego_m=0.0, prior=PAPER_PRIOR,
                         settings=SharedSettings(report_bound=bound, age_kernel=kernel))
        hat[bound] = _fuse(data, "safe", rd).mu_hat
    covered = GRID <= 48.0
    assert (hat["consistent"] <= 0.5 + 1e-9).all()
    assert hat["consistent"][covered].mean() > hat["lowest"][covered].mean() + 0.01


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    seed=st.integers(0, 2**32 - 1),
    mu_true=st.floats(0.4, 0.6),
    offset=st.floats(0.0, 0.5),
    wrong_margin=st.sampled_from([0.001, 0.025, 0.1]),
    identities=st.integers(1, 30),
    share=st.floats(0.1, 1.0),
)
def test_wrong_reports_lift_safe_mode_at_most_by_an_honest_neighbours_interval(
    seed, mu_true, offset, wrong_margin, identities, share
):
    """Decision 0063, however many identities send the wrong reports (Sybil): an optimistic
    report whose interval, moved to an honest neighbour, lies wholly above the neighbour's is
    left out, so offsets beyond both margins and the position terms never lift μ̂ above μ; any
    other survivor lifts it by at most 2 m_h + 2 G (d_h + δ_h), h the honest report nearest s
    (here ± 0.025 reports 2 m apart, so d_h ≤ 1 m, δ_h = 0.98 m)."""
    rng = np.random.default_rng(seed)
    data = _own(np.full(51, 0.5), np.full(51, 0.1), None, "safe")
    honest = _honest(rng, mu_true, 25)
    wrong = [FrictionReport.numeric(r.s_m + rng.uniform(-1.0, 1.0), min(2.0, r.mu + offset),
                                    wrong_margin, position_std_m=0.5, sender=f"sybil-{i}-{k}")
             for i, r in enumerate(honest) if rng.random() < share for k in range(identities)]
    rd = report_data(honest + wrong, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    hat = _fuse(data, "safe", rd).mu_hat
    g, delta = 0.01, 1.96 * 0.5
    assert (hat <= mu_true + 2 * 0.025 + 2 * g * (1.0 + delta) + 1e-9).all()
    # Each wrong report is a copy of an honest one moved by at most 1 m: wholly above it once
    # the offset exceeds both margins and the position terms, and then never lifts μ̂ at all.
    if offset - wrong_margin - 0.025 - g * (1.0 + 2 * delta) > 1e-9:
        assert (hat <= mu_true + 1e-9).all()


def test_conflicts_compare_reports_at_one_place_and_time():
    """A report 0.2 above a ± 0.025 neighbour made at the same time conflicts with it (not the
    other way round); 0.02 above does not; made an hour apart, the surface may have changed."""
    same = [FrictionReport.numeric(10.0, 0.5, 0.025, sender="a"),
            FrictionReport.numeric(11.0, 0.7, 0.025, sender="b"),
            FrictionReport.numeric(12.0, 0.52, 0.025, sender="c")]
    c = conflicts(report_data(same, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR), PAPER_PRIOR.std)
    assert c.tolist() == [[False, False, False], [True, False, True], [False, False, False]]
    apart = [FrictionReport.numeric(10.0, 0.5, 0.025, sender="a"),
             FrictionReport.numeric(11.0, 0.7, 0.025, t_created_s=-3600.0, sender="b")]
    assert not conflicts(report_data(apart, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR),
                         PAPER_PRIOR.std).any()


def test_age_kernels_agree_at_long_ages_and_differ_at_short_ones():
    """Matérn-3/2 gains ≈ 1.5 σ² (Δt/τ)² at short ages, the Ornstein–Uhlenbeck σ² Δt/τ; both
    reach the prior's variance σ² at long ages."""
    s2, tau = PAPER_PRIOR.std ** 2, 1800.0
    short = np.array([1.0, 10.0])
    assert age_variance(short, PAPER_PRIOR.std, tau) == pytest.approx(
        1.5 * s2 * (short / tau) ** 2, rel=0.02)
    assert age_variance(short, PAPER_PRIOR.std, tau, "matern12") == pytest.approx(
        s2 * short / tau, rel=0.01)
    for kernel in AGE_KERNELS:
        assert age_variance(np.array([1e7]), PAPER_PRIOR.std, tau, kernel)[0] == pytest.approx(s2)


def test_one_miscalibrated_sender_alone_cannot_lift_the_bound():
    """Decision 0063's corroboration: where only one sender reported (0.06 too high; no other
    report there to conflict with), it lifts safe mode's μ̂ above μ when one sender suffices,
    not when a second sender must vouch for the bound."""
    data = _own(np.full(51, 0.5), np.full(51, 0.1), None, "safe")
    honest = [FrictionReport.numeric(float(s), 0.49, 0.025, sender="honest")
              for s in range(0, 15)]
    biased = [FrictionReport.numeric(float(s), 0.56, 0.025, sender="biased")
              for s in range(25, 51)]
    hat = {}
    for k in (1, 2):
        rd = report_data(honest + biased, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR,
                         settings=SharedSettings(corroboration=k))
        hat[k] = _fuse(data, "safe", rd).mu_hat
    assert hat[1].max() > 0.5
    assert (hat[2] <= 0.5 + 1e-9).all()


def test_an_honest_report_behind_the_vehicle_leaves_out_a_wrong_one_ahead():
    """Decision 0078: the camera errs high (0.6 ± 0.1 on μ 0.5) and an optimistic sender (+0.2)
    reported just ahead of the vehicle, where the honest sender's last reports lie behind it,
    outside the own data. The two cannot both be right under the gradient bound and no class
    change is known between them, so the wrong report is left out and μ̂ stays at or below μ."""
    data = _own(np.full(51, 0.6), np.full(51, 0.1), None, "safe")
    honest = [FrictionReport.numeric(s, 0.5, 0.025, position_std_m=0.5, sender="honest")
              for s in (-9.0, -6.0, -3.0)]
    wrong = [FrictionReport.numeric(s, 0.7, 0.025, position_std_m=0.5, sender="offset")
             for s in (-8.0, 0.5, 2.0)]
    rd = report_data(honest + wrong, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    assert (_fuse(data, "safe", rd).mu_hat <= 0.5 + 1e-9).all()
    # Alone, the wrong reports ahead lift it: the test above is not vacuous.
    alone = report_data(wrong, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    assert _fuse(data, "safe", alone).mu_hat.max() > 0.5 + 0.05


def test_a_report_behind_the_vehicle_leaves_none_out_beyond_a_class_change_the_camera_saw():
    """Decision 0078's limit: a low report behind the vehicle and a high one beyond a class
    change the camera saw (wet 0.5 up to 8 m, dry 0.8 after) can both be right, although they
    conflict under the gradient bound, so the high one still lifts safe mode's μ̂ in the dry
    segment as it does without the low one (exclusion wherever no change is *known* would
    leave it out: the mutation this test catches)."""
    cls = np.where(GRID < 8.0, 0.5, 0.8)
    margin = np.where(GRID < 8.0, 0.1, 0.2)
    data = _own(cls, margin, None, "safe")
    low = [FrictionReport.numeric(-3.0, 0.5, 0.025, position_std_m=0.5, sender="behind")]
    high = [FrictionReport.numeric(s, 0.8, 0.025, position_std_m=0.5, sender="ahead")
            for s in (9.0, 10.0, 11.0)]
    dry = (GRID >= 9.0) & (GRID <= 15.0)
    with_low = _fuse(data, "safe", report_data(low + high, t_now_s=0.0, s_ego_m=0.0,
                                               prior=PAPER_PRIOR)).mu_hat
    alone = _fuse(data, "safe", report_data(high, t_now_s=0.0, s_ego_m=0.0,
                                            prior=PAPER_PRIOR)).mu_hat
    without = _fuse(data, "safe").mu_hat
    assert conflicts(report_data(low + high, t_now_s=0.0, s_ego_m=0.0, prior=PAPER_PRIOR),
                     PAPER_PRIOR.std)[1:, 0].all()
    assert alone[dry].mean() > without[dry].mean() + 0.05
    # The low report enters the posterior (a few thousandths), not the hard bound.
    np.testing.assert_allclose(with_low[dry], alone[dry], atol=0.01)
