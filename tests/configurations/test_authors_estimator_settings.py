"""The authors' estimator settings pass through make_configuration; defaults stay the paper's."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.configurations import make_configuration
from mufusion.estimators import AUTHORS_CLASSES, AUTHORS_LOCAL_TIMING, PAPER_LOCAL_TIMING

GRID_M = np.arange(0.0, 51.0, 1.0)


def test_default_timing_is_the_papers_and_the_authors_preset_passes_through():
    assert make_configuration("L").local.timing is PAPER_LOCAL_TIMING
    conf = make_configuration("F", local_timing=AUTHORS_LOCAL_TIMING)
    assert conf.local.timing is AUTHORS_LOCAL_TIMING


def test_authors_local_error_sign_gives_l_two_margins_below_the_truth():
    # wce_local = -0.025 in both of the authors' scenario files: a worst-case under-estimate, and
    # L subtracts its margin once more (the authors report μ_local − |wce_local|).
    conf = make_configuration("L", local_error="worst_under", initial_local_mu=0.8)
    mu = np.full(GRID_M.shape, 0.4)
    est = conf.step(GRID_M, mu, utilization=0.9)
    assert est.local_available
    assert est.mu_hat == pytest.approx(np.full(GRID_M.shape, 0.35))


def test_authors_classes_make_p_plan_with_030_on_the_turn_surface():
    conf = make_configuration("P", classes=AUTHORS_CLASSES)
    mu = np.where(GRID_M < 20.0, 0.8, 0.4)
    est = conf.step(GRID_M, mu, utilization=0.0)
    assert est.mu_hat[0] == pytest.approx(0.6)
    assert est.mu_hat[-1] == pytest.approx(0.3)
