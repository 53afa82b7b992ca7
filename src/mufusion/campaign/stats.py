"""Monte Carlo statistics of a campaign's results table: outcome rates with Wilson intervals, the
distributions of the graded outcomes, per configuration (and per grid point), and each
configuration against the reference (GT) on the same variants and starts.

Rates count completed runs only; failed runs are counted apart and never taken as "no collision".
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from scipy.stats import binomtest

from mufusion.configurations import Configuration

# Boolean outcomes reported as rates: (column, label). ``off_road`` is used where the metrics
# have it.
OUTCOMES: tuple[tuple[str, str], ...] = (
    ("collision", "collision"),
    ("left_lane", "lane exit"),
    ("entered_opposing_lane", "opposing lane"),
    ("off_road", "off road"),
)
# The outcomes compared against the reference run by run, each with the graded metric that says
# how far the failing run went and the one that says how close the other came:
# (column, label, magnitude column, reference margin column).
PAIRED_OUTCOMES: tuple[tuple[str, str, str, str], ...] = (
    ("left_lane", "lane exit", "max_lane_excursion_m", "min_lane_margin_m"),
    ("collision", "collision", "impact_speed_mps", "min_clearance_m"),
)
REFERENCE = Configuration.GT.value
"""The configuration the others are judged against: perfect knowledge of the friction."""
# A run's pair is the reference run of the same scenario, variant and seed.
PAIR_KEYS = ("scenario", "variant", "seed")
# Metrics in milliseconds are wall-clock timings of this machine, not outcomes of the run.
WALL_CLOCK_SUFFIX = "_ms"
CONFIDENCE = 0.95


def wilson_interval(
    successes: int, trials: int, confidence: float = CONFIDENCE
) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion (no continuity correction).

    Parameters
    ----------
    successes
        Number of runs with the outcome, ``0 <= successes <= trials``.
    trials
        Number of runs, ``>= 1``.
    confidence
        Two-sided confidence level in (0, 1).

    Returns
    -------
    tuple of float
        Lower and upper bound of the proportion.

    Raises
    ------
    ValueError
        If the counts or the level are out of range.

    Examples
    --------
    >>> low, high = wilson_interval(0, 20)
    >>> round(low, 4), round(high, 4)
    (0.0, 0.1611)
    """
    if trials < 1:
        raise ValueError(f"trials must be >= 1, got {trials}")
    if not 0 <= successes <= trials:
        raise ValueError(f"successes must be in [0, trials={trials}], got {successes}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    ci = binomtest(int(successes), int(trials)).proportion_ci(
        confidence_level=confidence, method="wilson"
    )
    return float(ci.low), float(ci.high)


def outcome_columns(table: pd.DataFrame) -> list[tuple[str, str]]:
    """The outcomes of :data:`OUTCOMES` the table has."""
    return [(c, label) for c, label in OUTCOMES if c in table.columns]


def graded_columns(table: pd.DataFrame, grid: Sequence[str] = ()) -> list[str]:
    """Numeric, non-boolean metric columns: every graded outcome the metrics have.

    Parameters (index, seed, the ``grid`` columns) and wall-clock timings are left out.
    """
    skip = {"index", "seed", *grid}
    out = []
    for column in table.columns:
        series = table[column]
        if column in skip or column.endswith(WALL_CLOCK_SUFFIX):
            continue
        if pd.api.types.is_bool_dtype(series) or not pd.api.types.is_numeric_dtype(series):
            continue
        out.append(column)
    return out


def completed(table: pd.DataFrame) -> pd.DataFrame:
    """The rows of runs that completed (no ``error``)."""
    if "error" not in table.columns:
        return table
    return table[table["error"].isna()]


def outcome_rates(table: pd.DataFrame, by: Sequence[str] = ("scenario", "config")) -> pd.DataFrame:
    """Rate of each outcome per group, with its Wilson 95 % interval.

    Parameters
    ----------
    table
        The campaign's results table.
    by
        Columns that define a group (default: scenario and configuration).

    Returns
    -------
    pandas.DataFrame
        One row per group and outcome: the ``by`` columns, ``outcome``, ``runs`` (completed),
        ``failed``, ``count``, ``rate``, ``ci_low``, ``ci_high``.
    """
    by = list(by)
    outcomes = outcome_columns(table)
    rows = []
    for key, group in table.groupby(by, sort=False, dropna=False):
        ok = completed(group)
        values = dict(zip(by, key if isinstance(key, tuple) else (key,), strict=True))
        for column, label in outcomes:
            flags = ok[column].dropna().astype(bool)
            n, k = len(flags), int(flags.sum())
            low, high = wilson_interval(k, n) if n else (np.nan, np.nan)
            rows.append({**values, "outcome": label, "runs": n, "failed": len(group) - len(ok),
                         "count": k, "rate": k / n if n else np.nan,
                         "ci_low": low, "ci_high": high})
    return pd.DataFrame(rows)


def graded_summary(
    table: pd.DataFrame, by: Sequence[str] = ("scenario", "config"), grid: Sequence[str] = ()
) -> pd.DataFrame:
    """Distribution of each graded outcome per group: count, mean, std, min, 5 %, 50 %, 95 %, max.

    Runs where a graded outcome is undefined (e.g. no clearance after a collision) are left out
    of its count; ``grid`` names the parameter columns that are not outcomes.
    """
    by = list(by)
    rows = []
    ok = completed(table)
    for key, group in ok.groupby(by, sort=False, dropna=False):
        values = dict(zip(by, key if isinstance(key, tuple) else (key,), strict=True))
        for column in graded_columns(table, grid):
            x = group[column].dropna().to_numpy(dtype=float)
            stats: dict[str, float] = {"count": len(x)}
            if len(x):
                p5, p50, p95 = np.percentile(x, [5, 50, 95])
                stats |= {"mean": x.mean(), "std": x.std(ddof=1) if len(x) > 1 else 0.0,
                          "min": x.min(), "p5": p5, "median": p50, "p95": p95, "max": x.max()}
            rows.append({**values, "metric": column, **stats})
    return pd.DataFrame(rows)


def _pairs(table: pd.DataFrame, reference: str) -> pd.DataFrame:
    """Every completed non-reference run joined with its completed reference run (columns of the
    reference suffixed ``_ref``); empty without both."""
    ok = completed(table)
    keys = [k for k in PAIR_KEYS if k in ok.columns]
    ref = ok[ok["config"] == reference]
    others = ok[ok["config"] != reference]
    if ref.empty or others.empty or len(keys) < len(PAIR_KEYS):
        return pd.DataFrame()
    return others.merge(ref.drop(columns=["config"]), on=keys, suffixes=("", "_ref"))


def paired_against_reference(
    table: pd.DataFrame, reference: str = REFERENCE, by: Sequence[str] = ("scenario", "config")
) -> pd.DataFrame:
    """Each configuration's outcomes against the reference's, run by run.

    A run is paired with the reference run of the same scenario, variant and seed (the same
    start); runs without a completed pair are left out. For each outcome of
    :data:`PAIRED_OUTCOMES` the table counts the pairs where only the configuration fails
    (``worse``), only the reference fails (``better``) and both fail (``both``), and gives the
    two-sided sign test on ``worse`` against ``better`` (``p_value``, NaN when neither occurs):
    whether one fails more often than the other beyond chance, on the same starts.

    Parameters
    ----------
    table
        The campaign's results table.
    reference
        The reference configuration (default GT).
    by
        Columns that define a group (default: scenario and configuration; add ``feasibility``
        for the oracle's classes).

    Returns
    -------
    pandas.DataFrame
        One row per group and outcome: the ``by`` columns, ``outcome``, ``pairs``, ``worse``,
        ``better``, ``both``, ``p_value``. Empty when the table has no pairs.
    """
    pairs = _pairs(table, reference)
    by = list(by)
    rows: list[dict[str, object]] = []
    if pairs.empty:
        return pd.DataFrame(rows)
    for key, group in pairs.groupby(by, sort=False, dropna=False):
        values = dict(zip(by, key if isinstance(key, tuple) else (key,), strict=True))
        for column, label, _, _ in PAIRED_OUTCOMES:
            if column not in group.columns:
                continue
            both_known = group[[column, f"{column}_ref"]].dropna()
            mine = both_known[column].astype(bool).to_numpy()
            ref = both_known[f"{column}_ref"].astype(bool).to_numpy()
            worse, better = int((mine & ~ref).sum()), int((~mine & ref).sum())
            p = binomtest(worse, worse + better).pvalue if worse + better else np.nan
            rows.append({**values, "outcome": label, "pairs": len(both_known), "worse": worse,
                         "better": better, "both": int((mine & ref).sum()), "p_value": float(p)})
    return pd.DataFrame(rows)


def _number(value: Any) -> float:
    """A metric's value as a float, NaN where it is undefined (None, NaN, absent)."""
    return float("nan") if value is None or pd.isna(value) else float(value)


def worse_than_reference(table: pd.DataFrame, reference: str = REFERENCE) -> pd.DataFrame:
    """The runs that fail an outcome their reference run does not, largest failure first.

    Returns
    -------
    pandas.DataFrame
        One row per such run and outcome: ``scenario``, ``variant``, ``seed``, ``config``,
        ``feasibility`` (when the table has it), ``outcome``, ``magnitude`` (how far the run went:
        the lane excursion [m], the impact speed [m/s]) and ``reference_margin`` (how close the
        reference came: its smallest lane margin [m], its smallest clearance [m]).
    """
    pairs = _pairs(table, reference)
    rows: list[dict[str, object]] = []
    if pairs.empty:
        return pd.DataFrame(rows)
    keep = [k for k in (*PAIR_KEYS, "config", "feasibility") if k in pairs.columns]
    for column, label, magnitude, margin in PAIRED_OUTCOMES:
        if column not in pairs.columns:
            continue
        known = pairs[[column, f"{column}_ref"]].notna().all(axis=1)
        sub = pairs[known]
        hit = sub[sub[column].astype(bool) & ~sub[f"{column}_ref"].astype(bool)]
        for _, r in hit.iterrows():
            rows.append({**{k: r[k] for k in keep}, "outcome": label,
                         "magnitude": _number(r.get(magnitude)),
                         "reference_margin": _number(r.get(f"{margin}_ref"))})
    out = pd.DataFrame(rows)
    if out.empty:
        return out
    return out.sort_values(["outcome", "magnitude"], ascending=[True, False], kind="stable",
                           ignore_index=True)
