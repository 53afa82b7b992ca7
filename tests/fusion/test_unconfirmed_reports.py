"""Reports no own datum lies near never raise μ̂, also not through the posterior they share
with the points other reports confirm (docs/decisions/0076)."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.estimators.shared import FrictionReport
from mufusion.fusion import PAPER_PRIOR, assemble_inputs, fuse
from mufusion.fusion.reports import report_data

GRID = np.arange(0.0, 51.0)


def _fused(mode: str, reports: list[FrictionReport]) -> np.ndarray:
    data = assemble_inputs(GRID, np.full(51, 0.5), np.full(51, 0.1), local_mu=None, mode=mode)
    rd = report_data(reports, t_now_s=1.0, s_ego_m=0.0, prior=PAPER_PRIOR)
    return fuse(data.s_m, data.mu, data.margin, PAPER_PRIOR, GRID, groups=data.groups,
                mode=mode, reports=rd).mu_hat


def _honest() -> list[FrictionReport]:
    return [FrictionReport.numeric(float(s), 0.5, 0.025, t_created_s=0.0, position_std_m=0.5,
                                   sender=f"v{i % 2}") for i, s in enumerate(range(0, 48, 2))]


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_a_cluster_behind_the_vehicle_never_lifts_the_band_ahead(mode) -> None:
    # The fleet study's Sybil copies (20 % of the reports, each under ten pseudonyms, raised by
    # 0.2): those within the camera's range fail the trust test, but 5–9 m behind the vehicle
    # no own datum lies near them to test them against. In paper mode, 30 of them lifted the
    # band the honest reports confirm ahead by up to 0.06 (the fleet study's car: 37 % of the
    # horizon points above μ with the shared error of decision 0075, 4.9 % with the window cap).
    cluster = [FrictionReport.numeric(s, 0.7, 0.025, t_created_s=0.0, position_std_m=0.5,
                                      sender=f"sybil-{s}-{k}")
               for s in (-8.7, -6.6, -5.5) for k in range(10)]
    honest = _fused(mode, _honest())
    both = _fused(mode, _honest() + cluster)
    assert (both <= honest + 1e-12).all()


def test_a_low_report_behind_the_vehicle_still_lowers_mu_hat() -> None:
    # Black ice reported just behind: it may lower μ̂ where no own datum confirms it, and
    # nowhere raise it (with L⁺ alone at the confirmed points the dip it pulls into the
    # posterior mean overshot 4–7 m ahead: μ̂ 0.485 → 0.493–0.525 there).
    ice = [FrictionReport.numeric(-3.0, 0.15, 0.025, t_created_s=0.0, sender=f"w{k}")
           for k in range(3)]
    honest = _fused("paper", _honest())
    both = _fused("paper", _honest() + ice)
    assert both[0] < honest[0] - 0.01 and (both <= honest + 1e-12).all()
