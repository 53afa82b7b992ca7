"""Monte Carlo statistics of a campaign's results table: outcome rates with Wilson intervals and
the distributions of the graded outcomes, per configuration (and per grid point).

Rates count completed runs only; failed runs are counted apart and never taken as "no collision".
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
from scipy.stats import binomtest

# Boolean outcomes reported as rates: (column, label). ``off_road`` is used where the metrics
# have it.
OUTCOMES: tuple[tuple[str, str], ...] = (
    ("collision", "collision"),
    ("left_lane", "lane exit"),
    ("entered_opposing_lane", "opposing lane"),
    ("off_road", "off road"),
)
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
