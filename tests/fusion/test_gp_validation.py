"""Bad input raises ValueError naming the argument."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.fusion import PAPER_PRIOR, GPFusion, GPPrior, fuse, fuse_batch

GRID = np.arange(0.0, 51.0)
S = np.array([0.0, 10.0])
MU = np.array([0.4, 0.5])
MARGIN = np.array([0.025, 0.1])


@pytest.mark.parametrize(
    ("field", "kwargs"),
    [
        ("std", {"mean": 0.5, "std": 0.0, "length_scale_m": 15.0}),
        ("std", {"mean": 0.5, "std": -0.1, "length_scale_m": 15.0}),
        ("length_scale_m", {"mean": 0.5, "std": 0.2, "length_scale_m": 0.0}),
        ("length_scale_m", {"mean": 0.5, "std": 0.2, "length_scale_m": -3.0}),
        ("mean", {"mean": float("nan"), "std": 0.2, "length_scale_m": 15.0}),
        ("std", {"mean": 0.5, "std": float("inf"), "length_scale_m": 15.0}),
    ],
)
def test_prior_validation(field, kwargs):
    with pytest.raises(ValueError, match=field):
        GPPrior(**kwargs)


def test_prior_interval_validation():
    with pytest.raises(ValueError, match="low"):
        GPPrior.from_interval(1.0, 0.1, 15.0)
    with pytest.raises(ValueError, match="length_scale_m"):
        GPPrior.from_interval(0.1, 1.0, 0.0)


@pytest.mark.parametrize(
    ("match", "args", "kwargs"),
    [
        ("s_m", (np.array([0.0, np.nan]), MU, MARGIN, PAPER_PRIOR, GRID), {}),
        ("mu", (S, np.array([0.4, np.inf]), MARGIN, PAPER_PRIOR, GRID), {}),
        ("margin", (S, MU, np.array([0.025, np.nan]), PAPER_PRIOR, GRID), {}),
        ("margin", (S, MU, np.array([0.025, -0.1]), PAPER_PRIOR, GRID), {}),
        ("equal lengths", (S, MU[:1], MARGIN, PAPER_PRIOR, GRID), {}),
        ("equal lengths", (S, MU, np.array([0.1, 0.1, 0.1]), PAPER_PRIOR, GRID), {}),
        ("s_eval_m", (S, MU, MARGIN, PAPER_PRIOR, np.array([])), {}),
        ("s_eval_m", (S, MU, MARGIN, PAPER_PRIOR, np.array([0.0, np.nan])), {}),
        ("prior", (S, MU, MARGIN, "prior", GRID), {}),
        ("mode", (S, MU, MARGIN, PAPER_PRIOR, GRID), {"mode": "optimistic"}),
        ("groups", (S, MU, MARGIN, PAPER_PRIOR, GRID), {"groups": np.array([0, 1, 2])}),
        ("groups", (S, MU, MARGIN, PAPER_PRIOR, GRID), {"groups": np.array([0.5, 1.0])}),
    ],
)
def test_fuse_validation(match, args, kwargs):
    with pytest.raises(ValueError, match=match):
        fuse(*args, **kwargs)


@pytest.mark.parametrize(
    ("match", "args", "kwargs"),
    [
        ("mu", (S, MU, MARGIN, PAPER_PRIOR, GRID), {}),
        ("mu", (S, np.array([[0.4, np.inf]]), MARGIN, PAPER_PRIOR, GRID), {}),
        ("s_m", (np.array([0.0, 1.0, 2.0]), MU[None], MARGIN, PAPER_PRIOR, GRID), {}),
        ("margin", (S, MU[None], np.array([0.1, -0.1]), PAPER_PRIOR, GRID), {}),
        ("groups", (S, MU[None], MARGIN, PAPER_PRIOR, GRID), {"groups": np.array([1])}),
        ("mode", (S, MU[None], MARGIN, PAPER_PRIOR, GRID), {"mode": "x"}),
    ],
)
def test_fuse_batch_validation(match, args, kwargs):
    with pytest.raises(ValueError, match=match):
        fuse_batch(*args, **kwargs)


def test_gpfusion_validation():
    with pytest.raises(ValueError, match="mode"):
        GPFusion(PAPER_PRIOR, GRID, mode="fast")
    with pytest.raises(ValueError, match="s_eval_m"):
        GPFusion(PAPER_PRIOR, np.array([]))


def test_fuse_batch_needs_a_horizon():
    with pytest.raises(ValueError, match="mu"):
        fuse_batch(S, np.empty((0, 2)), MARGIN, PAPER_PRIOR, GRID)
