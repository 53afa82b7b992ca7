"""The sender cap as one shared error per sender (decision 0077): however many reports one
sender sends, and wherever, paper mode's posterior counts them as at most ``sender_cap``
independent reports."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from mufusion.estimators.shared import FrictionReport, SharedSettings
from mufusion.fusion import PAPER_PRIOR, fuse
from mufusion.fusion.reports import report_data

GRID = np.arange(0.0, 51.0)
S0 = 30.0


def _std_at_s0(reports: list[FrictionReport], cap: float) -> float:
    data = report_data(reports, t_now_s=1.0, s_ego_m=0.0, prior=PAPER_PRIOR,
                       settings=SharedSettings(sender_cap=cap))
    fused = fuse(GRID, np.full(GRID.size, 0.5), 0.1, PAPER_PRIOR, GRID,
                 groups=np.zeros(GRID.size, dtype=np.int64), mode="paper", reports=data)
    return float(fused.std[int(S0)])


def _reports(n: int, senders: int) -> list[FrictionReport]:
    return [FrictionReport.numeric(S0, 0.5, 0.025, t_created_s=0.0, position_std_m=0.0,
                                   sender=f"v{i % senders}") for i in range(n)]


@settings(max_examples=25, deadline=None)
@given(n=st.integers(1, 80), cap=st.sampled_from([1.0, 2.0, 3.0, 5.0]))
def test_a_chatty_sender_counts_at_most_as_cap_independent_reports(n, cap) -> None:
    one_sender = _std_at_s0(_reports(n, 1), cap)
    # ``cap`` senders with one report each, independent of each other.
    independent = _std_at_s0(_reports(int(cap), int(cap)), cap)
    # (With sender_cap = 1 the common share is SHARED_ERROR_FRACTION, 0.999, not 1: the 0.1 %
    # of each report's variance kept apart may narrow the band by that much.)
    assert one_sender >= independent * (1.0 - 1e-3)
    # More reports of the same sender never widen the band (they narrow it towards that limit).
    assert _std_at_s0(_reports(n + 10, 1), cap) <= one_sender + 1e-12


def test_the_limit_is_reached_by_many_reports_and_senders_add_up() -> None:
    many = _std_at_s0(_reports(400, 1), 3.0)
    assert abs(many - _std_at_s0(_reports(3, 3), 3.0)) < 2e-4
    # Two senders with many reports each: as six independent reports.
    assert abs(_std_at_s0(_reports(800, 2), 3.0) - _std_at_s0(_reports(6, 6), 3.0)) < 2e-4



def test_a_senders_stretch_is_most_certain_in_its_middle() -> None:
    # One sender, a report every metre from 10 to 40 m. Counted in a window around each report
    # (decision 0060's cap), the reports in the middle, with the most neighbours, were weighed
    # least: the band was narrower 5 m into the stretch (std 0.00867) than in its middle
    # (0.00910). A common error per sender (decision 0077) weighs every report alike.
    reports = [FrictionReport.numeric(float(x), 0.5, 0.025, t_created_s=0.0, position_std_m=0.0,
                                      sender="a") for x in np.arange(10.0, 41.0)]
    data = report_data(reports, t_now_s=1.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    fused = fuse(GRID, np.full(GRID.size, 0.5), 0.1, PAPER_PRIOR, GRID,
                 groups=np.zeros(GRID.size, dtype=np.int64), mode="paper", reports=data)
    assert fused.std[25] <= fused.std[15] <= fused.std[10]
