"""Input assembly (paper Sec. III): local near the vehicle, predictive classes ahead."""

from __future__ import annotations

import numpy as np
import pytest

from mufusion.fusion import (
    DEFAULT_GRID_M,
    DEFAULT_S_LOCAL_M,
    LOCAL_GROUP,
    FusionData,
    assemble_inputs,
    assemble_inputs_batch,
    declared_central_value,
    declared_upper_bound,
    local_surface_bound,
)

GRID = DEFAULT_GRID_M


def _classes(change_m: float | None, first=(0.8, 0.2), second=(0.5, 0.1)):
    before = GRID < change_m if change_m is not None else np.ones(GRID.size, dtype=bool)
    mu = np.where(before, first[0], second[0])
    margin = np.where(before, first[1], second[1])
    return mu, margin


def test_default_grid():
    assert GRID[0] == 0.0 and GRID[-1] == 50.0 and GRID.size == 51
    assert np.all(np.diff(GRID) == 1.0)


def test_predictive_only_keeps_every_point():
    mu, margin = _classes(20.0)
    d = assemble_inputs(GRID, mu, margin)
    np.testing.assert_array_equal(d.s_m, GRID)
    np.testing.assert_array_equal(d.mu, mu)
    np.testing.assert_array_equal(d.margin, margin)
    # Two class segments seen by the camera: two groups, none of them the local one.
    assert set(d.groups.tolist()) == {1, 2}
    assert (d.groups[GRID < 20.0] == 1).all() and (d.groups[GRID >= 20.0] == 2).all()


def test_local_replaces_points_before_s_local():
    mu, margin = _classes(None, first=(0.5, 0.1))
    d = assemble_inputs(GRID, mu, margin, local_mu=0.425, local_margin=0.025, s_local_m=5.0)
    local = d.s_m < 5.0
    assert local.sum() == 5
    np.testing.assert_array_equal(d.mu[local], 0.425)
    np.testing.assert_array_equal(d.margin[local], 0.025)
    np.testing.assert_array_equal(d.groups[local], LOCAL_GROUP)
    np.testing.assert_array_equal(d.mu[~local], 0.5)
    assert d.s_m.size == GRID.size


def test_nan_predictive_points_are_skipped():
    mu, margin = _classes(None, first=(0.5, 0.1))
    mu[31:] = np.nan
    margin[31:] = np.nan
    d = assemble_inputs(GRID, mu, margin)
    assert d.s_m.max() == 30.0 and d.s_m.size == 31
    # With a local estimate, camera-blind points near the vehicle still get the local value.
    mu[:3] = np.nan
    d = assemble_inputs(GRID, mu, margin, local_mu=0.45)
    np.testing.assert_array_equal(d.s_m[:5], [0.0, 1.0, 2.0, 3.0, 4.0])
    np.testing.assert_array_equal(d.mu[:5], 0.45)


def test_nan_gap_splits_a_class_segment():
    mu, margin = _classes(None, first=(0.5, 0.1))
    mu[20] = np.nan
    d = assemble_inputs(GRID, mu, margin)
    assert len(set(d.groups.tolist())) == 2


def test_paper_mode_carries_local_past_a_class_change():
    mu, margin = _classes(2.0)
    d = assemble_inputs(GRID, mu, margin, local_mu=0.8, s_local_m=5.0, mode="paper")
    np.testing.assert_array_equal(d.mu[d.s_m < 5.0], 0.8)
    np.testing.assert_array_equal(d.groups[d.s_m < 5.0], LOCAL_GROUP)


def test_safe_mode_stops_local_at_first_class_change():
    mu, margin = _classes(2.0)
    d = assemble_inputs(GRID, mu, margin, local_mu=0.8, s_local_m=5.0, mode="safe")
    assert (d.groups[d.s_m < 2.0] == LOCAL_GROUP).all()
    assert (d.groups[d.s_m >= 2.0] != LOCAL_GROUP).all()
    np.testing.assert_array_equal(d.mu[d.s_m >= 2.0], 0.5)
    # Without a change within reach the two modes agree.
    mu, margin = _classes(30.0)
    a = assemble_inputs(GRID, mu, margin, local_mu=0.8, mode="safe")
    b = assemble_inputs(GRID, mu, margin, local_mu=0.8, mode="paper")
    np.testing.assert_array_equal(a.mu, b.mu)
    np.testing.assert_array_equal(a.groups, b.groups)


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_local_surface_bound_covers_the_measured_class_only(mode: str) -> None:
    # Camera: 0.8 ± 0.2 up to 30 m, then 0.5 ± 0.1; the local estimate 0.925 ± 0.025 within 5 m.
    mu, margin = _classes(30.0)
    d = assemble_inputs(GRID, mu, margin, local_mu=0.925, mode=mode)
    bound = local_surface_bound(d, GRID)
    # 0.925 − 0.025 under the vehicle and over the rest of its class (to 29 m) ...
    np.testing.assert_allclose(bound[GRID < 30.0], 0.9)
    # ... nothing from the first change of class on.
    assert np.isinf(bound[GRID >= 30.0]).all()


def test_local_surface_bound_stops_at_a_class_change_within_reach() -> None:
    # The class changes 2 m ahead, inside the local estimate's 5 m reach: safe mode stops the
    # local data there, and so does the bound (paper mode keeps the local points to 4 m).
    mu, margin = _classes(2.0)
    safe = local_surface_bound(assemble_inputs(GRID, mu, margin, local_mu=0.8, mode="safe"), GRID)
    np.testing.assert_allclose(safe[:2], 0.775)
    assert np.isinf(safe[2:]).all()
    paper = local_surface_bound(assemble_inputs(GRID, mu, margin, local_mu=0.8), GRID)
    np.testing.assert_allclose(paper[:5], 0.775)
    assert np.isinf(paper[5:]).all()


def test_local_surface_bound_without_a_local_estimate_says_nothing() -> None:
    mu, margin = _classes(None)
    d = assemble_inputs(GRID, mu, margin, mode="safe")
    assert np.isinf(local_surface_bound(d, GRID)).all()
    assert np.isinf(local_surface_bound(FusionData([0.0, 1.0], [0.5, 0.5], 0.1), GRID)).all()


def test_default_s_local():
    mu, margin = _classes(None)
    d = assemble_inputs(GRID, mu, margin, local_mu=0.9)
    assert (d.groups == LOCAL_GROUP).sum() == int(np.sum(GRID < DEFAULT_S_LOCAL_M))


def test_output_is_sorted_and_read_only():
    mu, margin = _classes(10.0)
    d = assemble_inputs(GRID, mu, margin, local_mu=0.7)
    assert np.all(np.diff(d.s_m) > 0)
    with pytest.raises(ValueError):
        d.mu[0] = 1.0


@pytest.mark.parametrize(
    ("match", "kwargs"),
    [
        ("s_grid_m", {"s_grid_m": np.array([0.0, 2.0, 1.0])}),
        ("s_grid_m", {"s_grid_m": np.array([])}),
        ("predictive_mu", {"predictive_mu": np.full(50, 0.5)}),
        ("predictive_mu", {"predictive_mu": np.full(51, np.inf)}),
        ("predictive_margin", {"predictive_margin": np.full(51, -0.1)}),
        ("predictive_margin", {"predictive_margin": np.full(51, np.nan)}),
        ("local_mu", {"local_mu": float("nan")}),
        ("local_margin", {"local_margin": -0.01}),
        ("s_local_m", {"s_local_m": float("inf")}),
        ("mode", {"mode": "aggressive"}),
    ],
)
def test_assemble_validation(match, kwargs):
    args = {
        "s_grid_m": GRID,
        "predictive_mu": np.full(51, 0.5),
        "predictive_margin": np.full(51, 0.1),
    }
    args.update(kwargs)
    rest = {k: args.pop(k) for k in list(args) if k not in ("s_grid_m", "predictive_mu",
                                                            "predictive_margin")}
    with pytest.raises(ValueError, match=match):
        assemble_inputs(args["s_grid_m"], args["predictive_mu"], args["predictive_margin"], **rest)


def test_fusion_data_validation():
    with pytest.raises(ValueError, match="equal lengths"):
        FusionData(np.zeros(3), np.zeros(2), np.zeros(3), np.zeros(3, dtype=int))
    with pytest.raises(ValueError, match="margin"):
        FusionData(np.zeros(1), np.zeros(1), -np.ones(1), np.zeros(1, dtype=int))
    with pytest.raises(ValueError, match="mu"):
        FusionData(np.zeros(1), np.full(1, np.nan), np.ones(1), np.zeros(1, dtype=int))


@pytest.mark.parametrize("mode", ["paper", "safe"])
def test_batch_assembly_equals_assemble_inputs_row_by_row(mode):
    rng = np.random.default_rng(4)
    n_batch = 40
    values = np.array([0.25, 0.5, 0.8])
    margins = np.array([0.15, 0.1, 0.2])
    kind = np.minimum((GRID[None, :] >= rng.uniform(0, 50, (n_batch, 1))).astype(int)
                      + (GRID[None, :] >= rng.uniform(0, 8, (n_batch, 1))), 2)
    pmu = values[kind]
    pmar = margins[kind]
    pmu[rng.uniform(size=pmu.shape) < 0.05] = np.nan  # camera gaps
    local = np.where(rng.uniform(size=n_batch) < 0.5, rng.uniform(0.1, 1.0, n_batch), np.nan)
    batch = assemble_inputs_batch(GRID, pmu, pmar, local_mu=local, s_local_m=6.0, mode=mode)
    for b in range(n_batch):
        one = assemble_inputs(GRID, pmu[b], pmar[b], s_local_m=6.0, mode=mode,
                              local_mu=None if np.isnan(local[b]) else local[b])
        p = ~np.isnan(batch.mu[b])
        np.testing.assert_array_equal(batch.s_m[p], one.s_m)
        np.testing.assert_array_equal(batch.mu[b, p], one.mu)
        np.testing.assert_array_equal(batch.margin[b, p], one.margin)
        np.testing.assert_array_equal(batch.groups[b, p], one.groups)


def test_batch_assembly_validation():
    pmu = np.full((2, GRID.size), 0.5)
    with pytest.raises(ValueError, match="local_mu"):
        assemble_inputs_batch(GRID, pmu, pmu * 0.2, local_mu=[0.4, 3.0])
    with pytest.raises(ValueError, match="local_mu"):
        assemble_inputs_batch(GRID, pmu, pmu * 0.2, local_mu=0.4)
    with pytest.raises(ValueError, match="predictive_mu"):
        assemble_inputs_batch(GRID, pmu, pmu * 0.2, local_mu=[0.4])


def test_declared_upper_bound_is_the_lowest_y_plus_m_at_each_point() -> None:
    mu, margin = _classes(30.0)
    d = assemble_inputs(GRID, mu, margin, local_mu=0.925, mode="safe")
    bound = declared_upper_bound(d, GRID)
    np.testing.assert_allclose(bound[GRID < 5.0], 0.95)  # the local estimate's 0.925 + 0.025
    np.testing.assert_allclose(bound[(GRID >= 5.0) & (GRID < 30.0)], 1.0)
    np.testing.assert_allclose(bound[GRID >= 30.0], 0.6)
    # Two estimates at one point: the tighter holds; between points the looser neighbour's;
    # beyond the data nothing.
    two = FusionData([0.0, 0.0, 2.0], [0.5, 0.3, 0.9], [0.1, 0.1, 0.05])
    np.testing.assert_allclose(declared_upper_bound(two, np.array([0.0, 1.0, 2.0])),
                               [0.4, 0.95, 0.95])
    assert np.isinf(declared_upper_bound(two, np.array([-1.0, 3.0]))).all()


def test_declared_central_value_is_the_lowest_y_at_each_point() -> None:
    mu, margin = _classes(30.0)
    d = assemble_inputs(GRID, mu, margin, local_mu=0.925, mode="safe")
    value = declared_central_value(d, GRID)
    np.testing.assert_allclose(value[GRID < 5.0], 0.925)  # the local estimate's points
    np.testing.assert_allclose(value[(GRID >= 5.0) & (GRID < 30.0)], 0.8)
    np.testing.assert_allclose(value[GRID >= 30.0], 0.5)
    assert np.all(value <= declared_upper_bound(d, GRID))
    two = FusionData([0.0, 0.0, 2.0], [0.5, 0.3, 0.9], [0.1, 0.1, 0.05])
    np.testing.assert_allclose(declared_central_value(two, np.array([0.0, 1.0, 2.0])),
                               [0.3, 0.9, 0.9])
    assert np.isinf(declared_central_value(two, np.array([-1.0, 3.0]))).all()
