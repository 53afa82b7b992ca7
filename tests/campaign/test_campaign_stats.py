"""Monte Carlo statistics: Wilson intervals against published values and the closed form, rates
and distributions per configuration from a results table."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from scipy.stats import norm

from mufusion.campaign.stats import (
    graded_columns,
    graded_summary,
    outcome_rates,
    paired_against_reference,
    wilson_interval,
    worse_than_reference,
)


# Newcombe (1998), "Two-sided confidence intervals for the single proportion", Stat. Med. 17,
# Table II, method 3 (Wilson score interval without continuity correction), 95 %.
@pytest.mark.parametrize(
    ("k", "n", "low", "high"),
    [(81, 263, 0.2553, 0.3662), (15, 148, 0.0624, 0.1605), (0, 20, 0.0, 0.1611),
     (1, 29, 0.0061, 0.1718)],
)
def test_wilson_interval_matches_published_values(k, n, low, high):
    lo, hi = wilson_interval(k, n)
    assert lo == pytest.approx(low, abs=5e-5) and hi == pytest.approx(high, abs=5e-5)


@pytest.mark.parametrize(("k", "n", "level"), [(3, 10, 0.95), (50, 50, 0.95), (7, 200, 0.9)])
def test_wilson_interval_matches_the_closed_form(k, n, level):
    z = norm.ppf(0.5 + level / 2)
    p = k / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z / (1 + z**2 / n) * math.sqrt(p * (1 - p) / n + z**2 / (4 * n**2))
    lo, hi = wilson_interval(k, n, level)
    assert lo == pytest.approx(max(0.0, centre - half), abs=1e-12)
    assert hi == pytest.approx(min(1.0, centre + half), abs=1e-12)


@pytest.mark.parametrize(
    ("k", "n", "level", "match"),
    [(0, 0, 0.95, "trials"), (4, 3, 0.95, "successes"), (-1, 3, 0.95, "successes"),
     (1, 3, 1.0, "confidence")],
)
def test_wilson_interval_rejects_bad_counts(k, n, level, match):
    with pytest.raises(ValueError, match=match):
        wilson_interval(k, n, level)


def _table() -> pd.DataFrame:
    rng = np.random.default_rng(0)
    rows = []
    for config, crashes in (("GT", 0), ("P", 3)):
        for seed in range(10):
            rows.append({
                "scenario": "popup", "config": config, "seed": seed, "index": len(rows),
                "friction.mu": 0.8 if seed % 2 else 1.0, "error": None,
                "collision": seed < crashes, "left_lane": seed < 5,
                "entered_opposing_lane": False,
                "min_clearance_m": None if seed < crashes else float(rng.uniform(0.1, 1.0)),
                "planner_median_ms": 3.0, "fallbacks": seed,
            })
    rows.append({**rows[-1], "seed": 99, "error": "RuntimeError: boom", "collision": None,
                 "left_lane": None, "entered_opposing_lane": None, "min_clearance_m": None})
    return pd.DataFrame(rows)


def test_outcome_rates_count_completed_runs_with_wilson_intervals():
    rates = outcome_rates(_table()).set_index(["config", "outcome"])
    p = rates.loc[("P", "collision")]
    assert (p["runs"], p["failed"], p["count"]) == (10, 1, 3)
    assert (p["ci_low"], p["ci_high"]) == pytest.approx(wilson_interval(3, 10))
    assert rates.loc[("GT", "collision"), "rate"] == 0.0
    assert rates.loc[("GT", "lane exit"), "rate"] == 0.5
    assert "off road" not in set(rates.index.get_level_values("outcome"))
    with_off_road = _table().assign(off_road=True)
    assert outcome_rates(with_off_road).query("outcome == 'off road'")["rate"].tolist() == [1, 1]


def test_graded_outcomes_are_the_numeric_metrics_without_parameters_or_timings():
    table = _table()
    assert graded_columns(table, grid=["friction.mu"]) == ["min_clearance_m", "fallbacks"]
    summary = graded_summary(table, grid=["friction.mu"]).set_index(["config", "metric"])
    clear = table[(table["config"] == "P") & table["error"].isna()]["min_clearance_m"].dropna()
    row = summary.loc[("P", "min_clearance_m")]
    assert row["count"] == 7 == len(clear)
    assert row["mean"] == pytest.approx(clear.mean())
    assert row["p95"] == pytest.approx(np.percentile(clear, 95))
    by_cell = graded_summary(table, by=["config", "friction.mu"], grid=["friction.mu"])
    assert len(by_cell.query("metric == 'fallbacks'")) == 4


def _paired_table() -> pd.DataFrame:
    """Four variants × two seeds of GT and F-safe, outcomes set by hand (below)."""
    # (variant, seed): (GT out, F-safe out); excursions in m where out, margins where in.
    lane = {("a", 0): (False, True), ("a", 1): (False, True), ("b", 0): (False, True),
            ("b", 1): (True, False), ("c", 0): (True, True), ("c", 1): (False, False),
            ("d", 0): (False, False), ("d", 1): (False, False)}
    rows = []
    for (variant, seed), flags in lane.items():
        for config, out in zip(("GT", "F-safe"), flags, strict=True):
            depth = 0.01 * (1 + len(rows)) if out else 0.0
            rows.append({"scenario": "turn", "variant": variant, "seed": seed, "config": config,
                         "feasibility": "marginal" if variant == "a" else "feasible",
                         "error": None, "left_lane": out, "collision": False,
                         "max_lane_excursion_m": depth,
                         "min_lane_margin_m": -depth if out else 0.02 * (1 + seed),
                         "impact_speed_mps": np.nan, "min_clearance_m": np.nan})
    # A failed F-safe run has no outcome and no pair; a GT run without its F-safe run neither.
    rows.append({**rows[-1], "seed": 7, "error": "RuntimeError: boom", "left_lane": None})
    rows.append({**rows[0], "variant": "e"})
    return pd.DataFrame(rows)


def test_paired_comparison_counts_each_start_against_its_gt_run():
    table = _paired_table()
    paired = paired_against_reference(table).set_index("outcome")
    lane = paired.loc["lane exit"]
    # F-safe alone out at (a, 0), (a, 1), (b, 0); GT alone at (b, 1); both at (c, 0).
    assert (lane["pairs"], lane["worse"], lane["better"], lane["both"]) == (8, 3, 1, 1)
    assert lane["p_value"] == pytest.approx(0.625)  # 2 · P(X ≥ 3), X ~ B(4, 1/2)
    assert np.isnan(paired.loc["collision", "p_value"])  # no discordant pair
    by_class = paired_against_reference(table, by=("feasibility", "config"))
    marginal = by_class.query("feasibility == 'marginal' and outcome == 'lane exit'").iloc[0]
    assert (marginal["pairs"], marginal["worse"], marginal["p_value"]) == (2, 2, 0.5)
    assert paired_against_reference(table[table["config"] == "GT"]).empty


def test_runs_worse_than_gt_are_listed_largest_first_with_gts_margin():
    worse = worse_than_reference(_paired_table())
    assert worse[["variant", "seed"]].values.tolist() == [["b", 0], ["a", 1], ["a", 0]]
    assert worse["magnitude"].tolist() == pytest.approx([0.06, 0.04, 0.02])
    # GT's smallest lane margin on the same start: 0.02 m at seed 0, 0.04 m at seed 1.
    assert worse["reference_margin"].tolist() == pytest.approx([0.02, 0.04, 0.02])
    assert set(worse["outcome"]) == {"lane exit"} and set(worse["config"]) == {"F-safe"}
