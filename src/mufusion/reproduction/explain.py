"""Explanations of the differences between our runs and the paper, computed from the run logs.

The report's verdicts say *that* a criterion differs; this module says *why*, from what the logs
hold: the estimate the planner used against the true friction, the vehicle's lane margin, the
lateral room an evasion needs. Every number in a text is read from a log or its metadata, so a
different run gives a different text (or none, when the criterion agrees).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from mufusion.configurations import Configuration
from mufusion.reproduction.slide import slide_diagnosis, slide_text
from mufusion.reproduction.variants import CLEARANCE_TOLERANCE_M, Criterion
from mufusion.reproduction.verdicts import Outcome, Verdict, compare_with_paper
from mufusion.sim.log import RunLog, load_run


def explain_differences(runs: Iterable[Mapping[str, Any]]) -> dict[str, str]:
    """Explanation texts for every criterion that differs from the paper.

    Parameters
    ----------
    runs
        The ``runs`` of a reproduction summary: ``variant``, ``config``, ``log`` (directory of
        the saved run log) and the run's metrics.

    Returns
    -------
    dict
        ``Verdict.key`` → text, for the differing criteria this module knows how to explain.
    """
    runs = list(runs)
    by_key = {(r["variant"], r["config"]): r for r in runs}
    texts: dict[str, str] = {}
    for run in runs:
        for verdict in compare_with_paper(run):
            if verdict.outcome is Outcome.AGREES:
                continue
            text = _explain(verdict, run, by_key)
            if text:
                texts[verdict.key] = text
    return texts


def _explain(verdict: Verdict, run: Mapping[str, Any], by_key: Mapping) -> str | None:
    log = _load(run)
    if log is None:
        return None
    criterion = verdict.fact.criterion
    if criterion in (Criterion.STAYS_IN_LANE, Criterion.OPPOSING_LANE):
        return _lane_text(verdict, run, log, by_key)
    if criterion is Criterion.COLLISION and run.get("collision"):
        return _collision_text(run, log, by_key)
    if criterion is Criterion.COLLISION and verdict.config is Configuration.P:
        return _evasion_text(run, log)
    if criterion is Criterion.CLEARANCE and run.get("collision"):
        return (f"{verdict.config.value} collided, so it has no clearance while passing "
                "(its collision is explained above).")
    if criterion is Criterion.CLEARANCE:
        return _clearance_text(log)
    return None


def _collision_text(run, log: RunLog, by_key) -> str | None:
    """Why a configuration the paper has passing hit the obstacle, against the GT run."""
    obstacles = log.meta.obstacles
    ts = log.timeseries
    hit = ts[ts["in_collision"].astype(bool)]
    if not obstacles or hit.empty:
        return None
    ob, first = obstacles[0], hit.iloc[0]
    need = 0.5 * (ob.width_m + log.meta.vehicle.width_m)
    mu_hat, mu_true = _estimate_at_comparison(log)
    name = log.meta.configuration
    text = (
        f"{name} planned with μ̂ = {mu_hat:.3f} against μ = {mu_true:.2f} (planned-force "
        f"utilisation {_budget(run)} GT's). It hit the obstacle at t = {float(first['t_s']):.2f} s "
        f"and {float(first['speed_mps']):.1f} m/s with its centre {float(first['d_m']):.2f} m "
        f"from the lane centre; an aligned body clears the obstacle (centre at "
        f"{ob.d_m:+.2f} m) only {need:.2f} m to its side."
    )
    gt = by_key.get((run["variant"], Configuration.GT.value))
    gt_log = _load(gt) if gt else None
    if gt_log is not None:
        gts = gt_log.timeseries
        d_gt = float(np.interp(float(first["s_m"]), gts["s_m"], gts["d_m"]))
        clearance = gt.get("min_clearance_m")
        outcome = ("also hit it" if gt.get("collision") else
                   f"passed with {fmt_clearance(clearance)} clearance")
        text += (
            f" GT, with the full force budget, was {d_gt:.2f} m from the lane centre at the "
            f"same progress ({abs(d_gt - float(first['d_m'])):.2f} m further aside) and "
            f"{outcome}."
        )
        if clearance is not None and clearance < CLEARANCE_TOLERANCE_M:
            text += (" Even the true friction leaves almost no margin at this obstacle "
                     "distance, and the smaller budget loses it.")
    return text


def fmt_clearance(value: Any) -> str:
    return "no" if value is None else f"{float(value):.2f} m"


def _clearance_text(log: RunLog) -> str | None:
    ts = log.timeseries
    obstacles = log.meta.obstacles
    near = ts[ts["obstacle_active"].astype(bool) & ~ts["passed_obstacle"].astype(bool)]
    if not obstacles or near.empty or not np.isfinite(near["clearance_m"]).any():
        return None
    row = near.loc[near["clearance_m"].idxmin()]
    ob = obstacles[0]
    half_w = 0.5 * log.meta.vehicle.width_m
    margin = log.meta.planner.obstacle_margin_m
    wanted = ob.d_m + 0.5 * ob.width_m + half_w + margin
    return (
        f"At the closest point (t = {float(row['t_s']):.2f} s, clearance "
        f"{float(row['clearance_m']):.2f} m) the vehicle's centre was {float(row['d_m']):.2f} m "
        f"to the side, where the planner's corridor asks for {wanted:.2f} m (obstacle and "
        f"vehicle half-widths plus its {margin:.2f} m margin): from the state the swerve had "
        "reached, no plan within the friction limits could open the full margin in time (the "
        "corridor is soft, so the least-violating plan is taken), and the body's heading of "
        f"{float(row['dpsi_rad']):.2f} rad swings its corners towards the obstacle."
    )


def _load(run: Mapping[str, Any]) -> RunLog | None:
    path = run.get("log")
    if not path or not Path(path).is_dir():
        return None
    return load_run(Path(path))


def _estimate_at_comparison(log: RunLog) -> tuple[float, float]:
    """μ̂ and true μ under the vehicle at the planning step nearest the comparison instant."""
    est = log.estimates
    t_c = log.meta.comparison_time_s
    steps = est["t_s"].unique()
    t = steps[np.argmin(np.abs(steps - t_c))]
    rows = est[(est["t_s"] == t)].sort_values("s_ahead_m")
    return float(rows["mu_hat"].iloc[0]), float(rows["mu_true"].iloc[0])


def _lane_margin_m(log: RunLog) -> float:
    return 0.5 * (log.meta.road.lane_width_m - log.meta.vehicle.width_m)


def _lane_text(verdict: Verdict, run, log: RunLog, by_key) -> str:
    text = _lane_estimate_text(verdict, run, log, by_key)
    mechanism = _mechanism(log)
    return f"{text} {mechanism}" if mechanism else text


def _mechanism(log: RunLog) -> str | None:
    """The slide mechanism of a lane-keeping run, if its log has what it takes."""
    if log.plans.empty or log.planning_steps.empty:
        return None
    try:
        return slide_text(slide_diagnosis(log))
    except ValueError:  # a log without a scenario to rebuild its road from
        return None


def _lane_estimate_text(verdict: Verdict, run, log: RunLog, by_key) -> str:
    mu_hat, mu_true = _estimate_at_comparison(log)
    margin = _lane_margin_m(log)
    offset = float(run.get("max_abs_lateral_offset_m") or 0.0)
    vehicle = log.meta.vehicle.name
    if verdict.fact.criterion is Criterion.STAYS_IN_LANE:
        text = (
            f"The planner used μ̂ = {mu_hat:.3f} under the vehicle against a true μ = "
            f"{mu_true:.2f} ({mu_hat / mu_true - 1.0:+.1%}); its largest planned front force "
            f"exceeded the true limit by {float(run.get('max_force_excess') or 0.0):.0%}. "
        )
        if verdict.config is Configuration.F and mu_hat > mu_true:
            text += (
                "With worst-case over-estimating inputs the paper's fusion counts the camera's "
                "copies of one class estimate as independent measurements, so its 'conservative' "
                "lower bound lies above the true friction (docs/fusion.md). "
            )
            safe = by_key.get((run["variant"], Configuration.F_SAFE.value))
            safe_log = _load(safe) if safe else None
            if safe_log is not None:
                safe_mu, _ = _estimate_at_comparison(safe_log)
                kept = "stayed in" if not safe.get("left_lane") else "also left"
                text += (
                    f"F-safe, which models the error the copies share, planned with μ̂ = "
                    f"{safe_mu:.3f} and {kept} its lane. "
                )
        text += (
            f"The vehicle has {margin:.2f} m of lane on each side; its centre deviated up to "
            f"{offset:.2f} m from the lane centre."
        )
        return text
    # Whether it slid is read from the log in the paragraph that follows (the axles'
    # utilisation, the body slip): here only what kept the corners in.
    return (
        f"L planned with its held estimate μ̂ = {mu_hat:.3f} (true μ = {mu_true:.2f}) like the "
        f"paper's truck, but the {vehicle} kept its lane: it has {margin:.2f} m of lane on each "
        f"side and its centre deviated up to {offset:.2f} m."
    )


def _evasion_text(run, log: RunLog) -> str | None:
    obstacles = log.meta.obstacles
    if not obstacles:
        return None
    width = log.meta.vehicle.width_m
    ob_width = obstacles[0].width_m
    need = 0.5 * (width + ob_width)
    mu_hat, mu_true = _estimate_at_comparison(log)
    clearance = run.get("min_clearance_m")
    passed = f"passed it with {clearance:.2f} m clearance" if clearance is not None else "passed"
    return (
        f"P planned with μ̂ = {mu_hat:.2f} against μ = {mu_true:.2f} as in the paper, but the "
        f"{log.meta.vehicle.name} ({width:.2f} m wide) has to move only {need:.2f} m "
        f"sideways to clear the {ob_width:.1f} m obstacle and {passed}: P's force budget "
        f"({_budget(run)} GT's) still suffices for a vehicle this narrow, so the paper's "
        "collision is an outcome for its truck, not for P on every vehicle."
    )


def _budget(run: Mapping[str, Any]) -> str:
    ratio = run.get("utilization_vs_gt")
    return "smaller than" if ratio is None else f"{float(ratio):+.1%} against"
