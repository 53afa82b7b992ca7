"""Two campaigns of the same runs compared run by run (``mufusion campaign-diff``).

What a change did to a grid — an estimator, a planner setting, the vehicle — is read as the
code's decision records read it: the outcome counts per configuration and oracle class before
and after, every run whose outcome flipped (either way), and how far the graded outcomes moved
in the runs whose outcome did not. Runs are matched by scenario, variant, configuration and
seed; a run in one campaign only is counted, not compared.

>>> import pandas as pd
>>> row = dict(scenario="popup", variant="mu=0.5", config="F-safe", seed=0, collision=False,
...            min_clearance_m=0.10, feasibility="feasible")
>>> diff = campaign_diff(pd.DataFrame([row]),
...                      pd.DataFrame([{**row, "collision": True, "min_clearance_m": None}]))
>>> diff.flips[["config", "outcome", "before", "after"]].values.tolist()
[['F-safe', 'collision', False, True]]
>>> diff.worse
1
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from mufusion.campaign.results import PARAMETER_COLUMNS, STATUS_COLUMNS

RUN_KEY = tuple(c for c in PARAMETER_COLUMNS if c not in ("run", "index"))
"""The columns that name a run across campaigns of the same grid (the results table's
parameters but its directory name and position, which a re-run may number otherwise)."""
ERROR = STATUS_COLUMNS[0]
OUTCOMES = ("collision", "left_lane", "off_road", "spun")
"""Boolean outcomes, true where the run failed in that way (the columns of ``RunMetrics``)."""
GRADED = ("min_clearance_m", "max_lane_excursion_m", "impact_speed_mps", "max_body_slip_rad")
"""Graded outcomes whose moves are summarised (metres, m/s, rad)."""
UNCLASSED = "–"
"""The oracle class of a run without one (a campaign without a limit oracle)."""


@dataclass(frozen=True)
class CampaignDiff:
    """Two campaigns compared run by run.

    Attributes
    ----------
    counts
        Per configuration, oracle class and outcome: ``runs``, ``before``, ``after`` (runs with
        that outcome among the runs both campaigns have).
    flips
        One row per run and outcome that differs: the run's key, its class, the outcome, its
        value before and after, and the graded outcomes before and after.
    moved
        Per graded outcome, among runs finite in both and not flipped: how many moved by more
        than the tolerance, up and down, the largest rise and fall, the summed change.
    matched, only_before, only_after
        Runs in both campaigns, and in one only.
    """

    counts: pd.DataFrame
    flips: pd.DataFrame
    moved: pd.DataFrame
    matched: int
    only_before: int
    only_after: int

    @property
    def worse(self) -> int:
        """Outcomes that flipped from not failing to failing."""
        return int((~self.flips["before"].astype(bool) & self.flips["after"].astype(bool)).sum())


def _finished(table: pd.DataFrame, name: str) -> pd.DataFrame:
    missing = [c for c in RUN_KEY if c not in table.columns]
    if missing:
        raise ValueError(f"the {name} campaign's table has no {', '.join(missing)} column")
    done = table[table[ERROR].isna()] if ERROR in table.columns else table
    if done.duplicated(list(RUN_KEY)).any():
        raise ValueError(f"the {name} campaign names a run twice (scenario, variant, config, "
                         "seed): compare one campaign directory with another")
    return done.set_index(list(RUN_KEY))


def campaign_diff(before: pd.DataFrame, after: pd.DataFrame,
                  tolerance: float = 1e-6) -> CampaignDiff:
    """Compare two campaigns' results tables (:data:`~mufusion.campaign.results.TABLE_FILE`) run
    by run. ``tolerance``: the smallest move of a graded outcome counted [its unit].

    Raises
    ------
    ValueError
        If a table lacks the run key's columns, names a run twice, or the two share no run.
    """
    b_all, a_all = _finished(before, "first"), _finished(after, "second")
    shared = b_all.index.intersection(a_all.index)
    if shared.empty:
        raise ValueError("the two campaigns share no run (scenario, variant, config and seed): "
                         "compare two campaigns of the same grid")
    b, a = b_all.loc[shared], a_all.loc[shared]
    klass = (b["feasibility"].fillna(UNCLASSED) if "feasibility" in b.columns
             else pd.Series(UNCLASSED, index=shared))
    outcomes = [o for o in OUTCOMES if o in b.columns and o in a.columns]
    graded = [g for g in GRADED if g in b.columns and g in a.columns]
    flag_b = {o: b[o].fillna(False).astype(bool) for o in outcomes}
    flag_a = {o: a[o].fillna(False).astype(bool) for o in outcomes}

    count_rows = []
    configs = shared.get_level_values("config")
    for (config, cls), idx in pd.Series(range(len(shared)), index=shared).groupby(
            [configs, klass.to_numpy()]):
        rows = idx.index
        for o in outcomes:
            count_rows.append({"config": config, "class": cls, "outcome": o, "runs": len(rows),
                               "before": int(flag_b[o].loc[rows].sum()),
                               "after": int(flag_a[o].loc[rows].sum())})
    counts = pd.DataFrame(count_rows, columns=["config", "class", "outcome", "runs", "before",
                                               "after"])

    flip_rows = []
    flipped = pd.Series(False, index=shared)
    for o in outcomes:
        changed = flag_b[o] != flag_a[o]
        flipped |= changed
        for key in shared[changed.to_numpy()]:
            row = dict(zip(RUN_KEY, key, strict=True))
            row.update({"class": klass.loc[key], "outcome": o, "before": bool(flag_b[o].loc[key]),
                        "after": bool(flag_a[o].loc[key])})
            for g in graded:
                row[f"{g} before"], row[f"{g} after"] = b[g].loc[key], a[g].loc[key]
            flip_rows.append(row)
    flips = pd.DataFrame(flip_rows, columns=[*RUN_KEY, "class", "outcome", "before", "after",
                                             *(f"{g} {w}" for g in graded
                                               for w in ("before", "after"))])

    moved_rows = []
    for g in graded:
        x = pd.to_numeric(b[g], errors="coerce").to_numpy(dtype=float)
        y = pd.to_numeric(a[g], errors="coerce").to_numpy(dtype=float)
        both = np.isfinite(x) & np.isfinite(y) & ~flipped.to_numpy()
        delta = (y - x)[both]
        moved_rows.append({
            "graded": g, "runs": int(both.sum()), "up": int((delta > tolerance).sum()),
            "down": int((delta < -tolerance).sum()),
            "largest_rise": float(delta.max()) if delta.size else 0.0,
            "largest_fall": float(delta.min()) if delta.size else 0.0,
            "sum": float(delta.sum())})
    moved = pd.DataFrame(moved_rows, columns=["graded", "runs", "up", "down", "largest_rise",
                                              "largest_fall", "sum"])
    return CampaignDiff(counts, flips, moved, matched=len(shared),
                        only_before=len(b_all) - len(shared), only_after=len(a_all) - len(shared))


def _cell(value: object) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "–"
    return f"{value:.3g}" if isinstance(value, float) else str(value)


def diff_markdown(diff: CampaignDiff, before_name: str, after_name: str) -> str:
    """The comparison as Markdown: the counts that changed, the flips, the graded moves."""
    changed = diff.counts[diff.counts["before"] != diff.counts["after"]]
    lines = [f"# {before_name} → {after_name}", "",
             f"{diff.matched} runs in both; {diff.only_before} only in the first, "
             f"{diff.only_after} only in the second. Outcomes that got worse: {diff.worse}.", "",
             "## Outcome counts that changed", ""]
    if changed.empty:
        lines.append("None: every outcome count per configuration and class is the same.")
    else:
        lines += ["| config | class | outcome | runs | before | after |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {r['config']} | {r['class']} | {r['outcome']} | {r['runs']} | "
                  f"{r['before']} | {r['after']} |" for r in changed.to_dict("records")]
    lines += ["", "## Runs whose outcome flipped", ""]
    if diff.flips.empty:
        lines.append("None.")
    else:
        graded = [c[: -len(" before")] for c in diff.flips.columns if c.endswith(" before")]
        lines += ["| config | class | variant | seed | outcome | before → after | "
                  + " | ".join(graded) + " |", "|---" * (6 + len(graded)) + "|"]
        for r in diff.flips.to_dict("records"):
            cells = [f"{_cell(r[f'{g} before'])} → {_cell(r[f'{g} after'])}" for g in graded]
            lines.append(f"| {r['config']} | {r['class']} | {r['variant']} | {r['seed']} | "
                         f"{r['outcome']} | {r['before']} → {r['after']} | "
                         + " | ".join(cells) + " |")
    lines += ["", "## Graded outcomes of the runs that did not flip", "",
              "| outcome | runs | up | down | largest rise | largest fall | sum |",
              "|---|---|---|---|---|---|---|"]
    lines += [f"| {r.graded} | {r.runs} | {r.up} | {r.down} | {_cell(r.largest_rise)} | "
              f"{_cell(r.largest_fall)} | {_cell(r.sum)} |" for r in diff.moved.itertuples()]
    return "\n".join(lines) + "\n"
