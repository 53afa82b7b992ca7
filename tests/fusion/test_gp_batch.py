"""fuse_batch equals fuse applied horizon by horizon."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.fusion import DEFAULT_GRID_M, PAPER_PRIOR, assemble_inputs, fuse, fuse_batch

GRID = DEFAULT_GRID_M


def _compare(batch, rows):
    for i, row in enumerate(rows):
        for field in ("mean", "std", "lower", "mu_hat"):
            np.testing.assert_allclose(
                getattr(batch, field)[i], getattr(row, field), rtol=0, atol=1e-9
            )


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_batch_equals_loop_on_assembled_horizons(mode):
    rng = np.random.default_rng(11)
    n_batch = 25
    mu = np.empty((n_batch, GRID.size))
    margin = np.empty((n_batch, GRID.size))
    groups = np.empty((n_batch, GRID.size), dtype=int)
    rows = []
    for b in range(n_batch):
        change = rng.uniform(0.0, 50.0)
        first, second = rng.choice([0.8, 0.5, 0.25], 2)
        value = np.where(GRID < change, first, second)
        mar = np.select([value == 0.8, value == 0.5], [0.2, 0.1], 0.15)
        local = rng.uniform(0.2, 0.9) if b % 2 else None
        d = assemble_inputs(GRID, value, mar, local_mu=local, mode=mode)
        assert d.s_m.size == GRID.size
        mu[b], margin[b], groups[b] = d.mu, d.margin, d.groups
        rows.append(fuse(d.s_m, d.mu, d.margin, PAPER_PRIOR, GRID, groups=d.groups, mode=mode))
    batch = fuse_batch(GRID, mu, margin, PAPER_PRIOR, GRID, groups=groups, mode=mode)
    assert batch.mean.shape == (n_batch, GRID.size)
    _compare(batch, rows)


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_batch_with_absent_points_and_own_positions(mode):
    rng = np.random.default_rng(5)
    n_batch, n = 12, 20
    s = rng.uniform(0.0, 50.0, (n_batch, n))
    mu = rng.uniform(0.1, 1.0, (n_batch, n))
    margin = rng.uniform(0.02, 0.3, (n_batch, n))
    groups = rng.integers(0, 4, (n_batch, n))
    mu[rng.uniform(size=(n_batch, n)) < 0.3] = np.nan
    mu[0] = np.nan  # a horizon with no data at all
    s_eval = np.linspace(-5.0, 60.0, 33)
    batch = fuse_batch(s, mu, margin, PAPER_PRIOR, s_eval, groups=groups, mode=mode)
    rows = []
    for b in range(n_batch):
        p = ~np.isnan(mu[b])
        rows.append(
            fuse(s[b][p], mu[b][p], margin[b][p], PAPER_PRIOR, s_eval, groups=groups[b][p],
                 mode=mode)
        )
    _compare(batch, rows)
    np.testing.assert_allclose(batch.mean[0], PAPER_PRIOR.mean, atol=1e-15)


def test_batch_zero_margin_falls_back_to_jitter():
    mu = np.tile(np.linspace(0.4, 0.8, GRID.size), (3, 1))
    margin = np.zeros(GRID.size)
    batch = fuse_batch(GRID, mu, margin, PAPER_PRIOR, GRID)
    row = fuse(GRID, mu[0], margin, PAPER_PRIOR, GRID)
    np.testing.assert_allclose(batch.mean[2], row.mean, atol=1e-10)


def test_batch_shared_positions_with_absent_points():
    # Paper mode, shared positions: the vectorized feature path; NaN removes a point exactly.
    rng = np.random.default_rng(9)
    mu = rng.uniform(0.1, 1.0, (30, GRID.size))
    margin = rng.uniform(0.02, 0.3, GRID.size)
    mu[rng.uniform(size=mu.shape) < 0.4] = np.nan
    mu[3] = np.nan
    batch = fuse_batch(GRID, mu, margin, PAPER_PRIOR, GRID)
    rows = []
    for b in range(mu.shape[0]):
        p = ~np.isnan(mu[b])
        rows.append(fuse(GRID[p], mu[b][p], margin[p], PAPER_PRIOR, GRID))
    _compare(batch, rows)
    np.testing.assert_allclose(batch.std[3], PAPER_PRIOR.std, atol=1e-12)


def test_safe_batch_vectorizes_complete_rows_and_matches_fuse(monkeypatch):
    import mufusion.fusion.batch as batch_module

    rng = np.random.default_rng(21)
    n_batch = 12
    mu = rng.uniform(0.1, 1.0, (n_batch, GRID.size))
    margin = rng.uniform(0.025, 0.2, (n_batch, GRID.size))
    groups = np.repeat(np.arange(GRID.size) // 10, 1)[None, :].repeat(n_batch, axis=0)
    groups[:4] = rng.permutation(groups[0])  # unsorted labels, still vectorized
    mu[4, 7] = np.nan  # an absent point: horizon by horizon
    groups[5] = np.arange(GRID.size)  # every point its own group: the paper posterior
    groups[6, :-1] = np.arange(GRID.size - 1)  # more groups than n / 2: the dense path
    groups[6, -1] = 0
    margin[7] = 0.0  # noise at the floor: too small for the feature path with shared errors
    calls = []
    real = batch_module.fuse_validated
    monkeypatch.setattr(
        batch_module, "fuse_validated", lambda *a, **k: calls.append(1) or real(*a, **k)
    )
    batch = fuse_batch(GRID, mu, margin, PAPER_PRIOR, GRID, groups=groups, mode="safe")
    assert len(calls) == 3  # rows 4, 6 and 7
    for b in range(n_batch):
        p = ~np.isnan(mu[b])
        row = fuse(GRID[p], mu[b][p], margin[b][p], PAPER_PRIOR, GRID, groups=groups[b][p],
                   mode="safe")
        for field in ("mean", "std", "lower", "mu_hat"):
            np.testing.assert_allclose(
                getattr(batch, field)[b], getattr(row, field), rtol=0, atol=1e-10
            )
