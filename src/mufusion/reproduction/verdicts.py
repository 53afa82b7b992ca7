"""Verdicts: each of the paper's reported outcomes against a run's metrics.

A verdict is computed, never written by hand: ``agrees`` or ``differs`` from the run's metric and
the fact's expected value or tolerance, ``no data`` when the run has no value for the metric.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from typing import Any

from mufusion.configurations import Configuration
from mufusion.reproduction.variants import Fact, FlagFact, NumberFact, variant


class Outcome(str, Enum):
    AGREES = "agrees"
    DIFFERS = "differs"
    NO_DATA = "no data"


@dataclass(frozen=True)
class Verdict:
    """One criterion of one run compared with the paper."""

    variant: str
    config: Configuration
    fact: Fact
    ours: str
    outcome: Outcome
    difference: str

    @property
    def criterion(self) -> str:
        return self.fact.criterion.value

    @property
    def paper(self) -> str:
        return self.fact.paper

    @property
    def key(self) -> str:
        """Identifies the verdict: ``"<variant>/<config>/<criterion>"``."""
        return f"{self.variant}/{self.config.value}/{self.criterion}"


def fmt(value: Any, unit: str = "", digits: int = 2) -> str:
    """A metric value for a table: yes/no, integers, fixed-point floats, — for none."""
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return f"{value:.{digits}f}{(' ' + unit) if unit else ''}"
    return str(value)


def pct(value: float | None) -> str:
    """A fraction as a signed percentage, — for none."""
    return "—" if value is None else f"{100 * value:+.1f} %"


def _judge(fact: Fact, run: Mapping[str, Any]) -> tuple[str, Outcome, str]:
    ours = run.get(fact.metric)
    if ours is None:
        return "—", Outcome.NO_DATA, f"our run has no value for {fact.metric}"
    if isinstance(fact, FlagFact):
        ok = bool(ours) == fact.expected
        diff = "" if ok else (
            f"{fact.metric} is {fmt(bool(ours))}, the paper's outcome needs {fmt(fact.expected)}"
        )
        return f"{fact.metric} = {fmt(bool(ours))}", Outcome.AGREES if ok else Outcome.DIFFERS, diff
    return _judge_number(fact, float(ours))


def _judge_number(fact: NumberFact, ours: float) -> tuple[str, Outcome, str]:
    def show(v: float) -> str:
        return pct(v) if fact.as_percent else fmt(v, fact.unit)

    delta = ours - fact.target
    ok = abs(delta) <= fact.tolerance
    if fact.as_percent:
        tol = f"{100 * delta:+.1f} percentage points (tolerance ±{100 * fact.tolerance:.0f} pp)"
    else:
        tol = f"{delta:+.2f} {fact.unit} (tolerance ±{fact.tolerance:g} {fact.unit})"
    diff = "" if ok else f"{fact.metric} is {show(ours)} vs the paper's {show(fact.target)}: {tol}"
    return f"{fact.metric} = {show(ours)}", Outcome.AGREES if ok else Outcome.DIFFERS, diff


def compare_with_paper(run: Mapping[str, Any]) -> list[Verdict]:
    """Verdicts of one run against the paper's outcomes (Section IV, Fig. 3 and Fig. 4).

    Parameters
    ----------
    run : mapping
        ``variant`` (a :data:`~mufusion.reproduction.variants.VARIANTS` key), ``config`` and the
        run's metrics (``RunMetrics.to_dict()``).

    Returns
    -------
    list of Verdict
        Empty for configurations the paper does not have (F-safe).

    Raises
    ------
    ValueError
        If ``variant`` or ``config`` is missing or unknown.

    Examples
    --------
    >>> [v.outcome.value for v in compare_with_paper(
    ...     {"variant": "turn-paper", "config": "L", "entered_opposing_lane": True})]
    ['agrees']
    """
    for key in ("variant", "config"):
        if key not in run:
            raise ValueError(f"run must have a {key!r} entry; got keys {sorted(run)}")
    var = variant(str(run["variant"]))
    config = Configuration.parse(str(run["config"]))
    verdicts = []
    for fact in var.facts(config):
        ours, outcome, diff = _judge(fact, run)
        verdicts.append(Verdict(var.key, config, fact, ours, outcome, diff))
    return verdicts
