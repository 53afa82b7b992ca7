"""Shared reports: the record, the link (rate, loss, latency, validity), the message mappings
(VSS, IVIM, DENM) and the wrong-report generator."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.estimators.comm import (
    DENM_ADHESION,
    IVIM_MARGIN,
    CommModel,
    decode,
    encode,
    received,
    thin_to_rate,
    transmit,
)
from mufusion.estimators.misbehaviour import WrongReports, corrupt
from mufusion.estimators.shared import FrictionReport


def _stream(n=200, dt=0.1, mu=0.5, sender="v1"):
    return [FrictionReport.numeric(float(i), mu, 0.025, t_created_s=i * dt, sender=sender)
            for i in range(n)]


def test_rate_keeps_one_report_per_sender_and_slot():
    rs = _stream(100, 0.1) + _stream(100, 0.1, sender="v2")
    out = thin_to_rate(rs, 2.0)
    assert len(out) == 2 * 20
    assert len({(r.sender, int(r.t_created_s * 2.0)) for r in out}) == len(out)


def test_loss_latency_and_validity():
    rs = _stream(5000, 0.01)
    comm = CommModel(rate_hz=100.0, loss=0.3, latency_s=0.4, jitter_s=0.2)
    got = transmit(rs, comm, np.random.default_rng(1))
    assert 0.66 < len(got) / 5000 < 0.74  # ~0.7 delivered
    delays = np.array([d.t_arrival_s - d.report.t_created_s for d in got])
    assert delays.min() >= 0.4 and 0.55 < delays.mean() < 0.65
    again = transmit(rs, comm, np.random.default_rng(1))
    assert [d.t_arrival_s for d in again] == [d.t_arrival_s for d in got]  # seeded
    assert len(received(got, 10.0, comm)) < len(received(got, 60.0, comm))
    late = CommModel(rate_hz=100.0, loss=0.3, validity_s=5.0)
    assert all(60.0 - r.t_created_s <= 5.0 for r in received(got, 60.0, late))


@pytest.mark.parametrize(("field", "value"), [("loss", 1.0), ("rate_hz", 0.0),
                                              ("message", "cam"), ("validity_s", 1e6)])
def test_comm_model_names_the_bad_field(field, value):
    with pytest.raises(ValueError, match=field):
        CommModel(**{field: value})


@settings(max_examples=100, deadline=None, derandomize=True)
@given(mu=st.floats(0.05, 1.2), margin=st.floats(0.0, 0.3))
def test_vss_mapping_keeps_the_two_sided_band_within_rounding(mu, margin):
    r = FrictionReport.numeric(3.0, mu, margin, t_created_s=1.0, sender="x")
    back = decode(encode(r, "vss"), r)
    assert back.lower_mu <= back.mu <= back.upper_mu
    assert abs(back.mu - r.mu) <= 0.005 + 1e-9
    assert back.lower_mu <= r.lower_mu + 0.002  # a 5 % quantile never read as the 2.5 % one
    assert back.upper_mu >= r.upper_mu - 0.002
    assert (back.s_m, back.t_created_s, back.sender) == (3.0, 1.0, "x")


def test_ivim_gives_the_declared_margin():
    r = FrictionReport.numeric(0.0, 0.634, 0.01)
    back = decode(encode(r, "ivim"), r)
    assert back.mu == pytest.approx(0.63)
    assert back.margin == pytest.approx(IVIM_MARGIN + 0.005)


def test_denm_is_a_warning_whose_interval_holds_the_estimate():
    assert encode(FrictionReport.numeric(0.0, 0.6, 0.025), "denm") is None
    for mu in (0.08, 0.12, 0.2, 0.3, 0.39):
        r = FrictionReport.numeric(0.0, mu, 0.025)
        msg = encode(r, "denm")
        back = decode(msg, r)
        assert back.lower_mu <= mu <= back.upper_mu <= max(hi for _, hi in DENM_ADHESION.values())
    r = FrictionReport.numeric(0.0, 0.2, 0.025)
    sure = decode(encode(r, "denm"), r)
    unsure = decode(encode(FrictionReport.numeric(0.0, 0.2, 0.2), "denm"), r)
    assert unsure.lower_mu < sure.lower_mu  # lower informationQuality widens downwards
    assert set(DENM_ADHESION) <= set(range(11))


def test_corrupt_without_wrong_reports_changes_and_draws_nothing():
    rs = _stream(20)
    rng = np.random.default_rng(0)
    assert corrupt(rs, WrongReports(), rng) == rs
    assert rng.random() == np.random.default_rng(0).random()


def test_offset_senders_replays_and_sybils():
    rs = [r for k in range(50) for r in _stream(4, 1.0, sender=f"v{k}")]
    out = corrupt(rs, WrongReports(offset_share=0.2, offset=0.2), np.random.default_rng(3))
    raised = {r.sender for r, o in zip(rs, out, strict=True) if o.mu > r.mu}
    assert 4 <= len(raised) <= 18  # ~10 of 50 senders, all of their reports
    assert all(o.mu == pytest.approx(r.mu + 0.2) for r, o in zip(rs, out, strict=True)
               if r.sender in raised)
    rep = corrupt(rs, WrongReports(replay_share=0.2, replay_restamped=False),
                  np.random.default_rng(3))
    old = [o for r, o in zip(rs, rep, strict=True) if o.t_created_s < r.t_created_s]
    assert 20 <= len(old) <= 60 and all(o.mu > 0.5 for o in old)
    syb = corrupt(rs, WrongReports(sybil_share=0.2, sybil_identities=5), np.random.default_rng(3))
    extra = syb[len(rs):]
    assert len(extra) % 5 == 0 and len({r.sender for r in extra}) == len(extra)


def test_wrong_reports_name_the_bad_field():
    with pytest.raises(ValueError, match="offset_share"):
        WrongReports(offset_share=1.5)
    with pytest.raises(ValueError, match="sybil_identities"):
        WrongReports(sybil_identities=0)
