"""F-safe in the pop-up: does it leave its lane for want of information or of planning?

For every variant of a finished pop-up campaign (GT and F-safe, e.g. ``mufusion campaign
examples/limits_popup.toml --out DIR``) in which F-safe leaves its lane and GT keeps it, this
reads both runs' logs and reports, at the obstacle's appearance (the first planning step):

* ``need``: the least friction with which the loop's own stop-or-evade test
  (:func:`mufusion.planner.passing.stopping_possible`, with the run's λ, polygon, obstacle margin,
  planning period and brake lag) grants a stop in front of the obstacle;
* ``mu_hat``: F-safe's friction estimate there (the lowest between the vehicle and the obstacle,
  as the test takes it), and ``mean``: the fusion's posterior mean there (what relaxing F-safe
  fully would give it);
* the truth, both runs' planning modes and F-safe's graded outcome.

A variant with ``need > mean`` is one where no estimate the fusion stands behind grants the stop:
leaving the lane is then the price of the estimate's declared uncertainty, not of the planner.

Run: ``python benchmarks/fsafe_popup_stops.py DIR``. Prints a table and a final JSON line; numbers
go to docs/decisions/0027 ("F-safe's lane in the pop-up").
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import pandas as pd

from mufusion.planner.passing import stopping_possible
from mufusion.sim.log import RunLog, load_run
from mufusion.vehicle.params import vehicle_preset


def needed_friction(log: RunLog) -> float:
    """Least μ̂ with which the stop-or-evade test grants a stop at the run's first planning step."""
    meta, planner = log.meta, log.meta.planner
    params = vehicle_preset(str(meta.scenario_config["vehicle"]))
    obstacle = meta.obstacles[0]
    first = log.timeseries.iloc[0]
    ahead = obstacle.s_m - float(first["s_m"])
    gap = ahead - params.cog_to_body_front_m - 0.5 * obstacle.length_m - planner.obstacle_margin_m
    speed = float(first["vx_mps"])
    dead_time = planner.dt_s + params.torque_time_constant_s

    def stops(mu: float) -> bool:
        return stopping_possible(speed_mps=speed, gap_m=gap, mu_hat=mu,
                                 utilization_factor=planner.utilization_factor,
                                 polygon_sides=planner.polygon_sides, dead_time_s=dead_time)

    lo, hi = 0.0, 10.0
    if not stops(hi):
        return float("inf")
    for _ in range(60):  # bisection to ~1e-17: the test is monotone in μ̂
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if stops(mid) else (mid, hi)
    return hi


def _first_estimate(log: RunLog) -> tuple[float, float]:
    """F-safe's μ̂ and the posterior mean, lowest between the vehicle and the obstacle, at step 0."""
    est = log.frame("estimates")
    obstacle = log.meta.obstacles[0]
    first = est[est["step"] == est["step"].min()]
    ahead = obstacle.s_m - float(first["s_m"].iloc[0])
    between = first[first["s_ahead_m"] <= ahead]
    return float(between["mu_hat"].min()), float(between["mean"].min())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", type=Path, help="a finished pop-up campaign (GT and F-safe)")
    args = parser.parse_args(argv)
    table = pd.read_parquet(args.directory / "results.parquet")
    if not {"GT", "F-safe"} <= set(table["config"]):
        print(f"{args.directory}: the campaign needs configurations GT and F-safe", file=sys.stderr)
        return 2
    grid = [c for c in table.columns if "." in c or c in ("initial_speed_mps", "vehicle")]
    pairs = table[table["config"] == "F-safe"].merge(
        table[table["config"] == "GT"], on=grid, suffixes=("", "_gt"))
    out = pairs[(pairs["max_lane_excursion_m"] > 0) & ~(pairs["max_lane_excursion_m_gt"] > 0)]
    rows = []
    for _, run in out.iterrows():
        log = load_run(args.directory / run["log"])
        gt_log = load_run(args.directory / run["log_gt"])
        mu_hat, mean = _first_estimate(log)
        rows.append({
            **{k: run[k] for k in grid},
            "need": needed_friction(log), "mu_hat": mu_hat, "mean": mean,
            "mode": log.frame("planning_steps")["mode"].iloc[0],
            "gt_mode": gt_log.frame("planning_steps")["mode"].iloc[0],
            "excursion_m": float(run["max_lane_excursion_m"]),
            "collision": bool(run["collision"]), "off_road": bool(run["off_road"]),
        })
    result = pd.DataFrame(rows)
    print(f"{len(result)} variants where F-safe leaves its lane and GT keeps it")
    if result.empty:
        print(json.dumps({"variants": 0}))
        return 0
    print(result.to_string(index=False, float_format=lambda v: f"{v:.3f}"))
    summary = {
        "variants": len(result),
        "need_above_mu_hat": int((result["need"] > result["mu_hat"]).sum()),
        "need_above_mean": int((result["need"] > result["mean"]).sum()),
        "need_range": [float(result["need"].min()), float(result["need"].max())],
        "mu_hat_range": [float(result["mu_hat"].min()), float(result["mu_hat"].max())],
        "mean_range": [float(result["mean"].min()), float(result["mean"].max())],
    }
    print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main())
