"""GT in the turn at the limit: why the footprint leaves the lane, measured from the run logs.

Runs GT over the variants of a campaign file (default ``benchmarks/gt_turn_subset.toml``: entry
speed 12/14/16 m/s × μ_turn 0.3/0.4/0.5 × truck/car, the grid of issue 10) and reports per run:
the oracle's verdict and margin, the speed at the curve's start and at the arc's start against the
arc's limit ``√(λ μ g R)``, the speed the first plan meant to have at the arc's start, the deepest
footprint point outside the lane [cm] with the corner and where, the largest planned excursion
beyond the planner's own lateral corridor (slack in use) [cm], and the largest tracking error of
the lateral offset against the current plan [cm], and the time at which the curve's end is
passed [s].

Run: ``python benchmarks/gt_turn_limits.py [--out DIR] [--jobs N] [FILE]``; ``--reuse`` reads the
logs of an earlier run in DIR instead of simulating; ``--where KEY=VALUE`` keeps only the variants
with that grid value (e.g. ``--where vehicle=truck``). Prints a table and a final JSON line; numbers
go to docs/feasibility.md, section "GT at the limit".
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from mufusion.campaign import campaign_specs, load_campaign, run_campaign
from mufusion.planner.ocp import lateral_corridor
from mufusion.road.geometry import rectangle_corners
from mufusion.scenarios import TurnScenario, load_scenario
from mufusion.scenarios.config import planner_lane_bounds_m
from mufusion.scenarios.feasibility import classify_scenario
from mufusion.sim.log import load_run
from mufusion.vehicle.params import vehicle_preset
from mufusion.vehicle.planner_model import State

CORNERS = ("front-left", "front-right", "rear-right", "rear-left")


def diagnose(directory: Path, overrides: list[str]) -> dict:
    """The quantities of the module docstring for one GT run's log."""
    cfg = load_scenario("turn", overrides)
    if not isinstance(cfg, TurnScenario):
        raise ValueError("the diagnosis is for the turn scenario")
    par = vehicle_preset(cfg.vehicle)
    log = load_run(directory)
    ts, plans = log.timeseries, log.plans
    road, s0 = cfg.build_road(par), cfg.start_s_m
    curve_start = s0 + cfg.turn.start_ahead_m
    arc_start = curve_start + cfg.turn.clothoid_m
    curve_end = curve_start + cfg.turn.radius_m * cfg.turn.angle_rad + cfg.turn.clothoid_m
    verdict = classify_scenario(cfg, par)
    # Footprint (centred between the axles) corners, projected on the lane centre.
    shift = 0.5 * (par.cog_to_front_axle_m - par.cog_to_rear_axle_m)
    x, y, psi = (ts[c].to_numpy() for c in ("x_m", "y_m", "psi_rad"))
    corners = rectangle_corners(x + shift * np.cos(psi), y + shift * np.sin(psi), psi,
                                par.length_m, par.width_m)
    _, d_corner, _ = road.path.to_frenet(corners[..., 0], corners[..., 1])
    outside = np.maximum(np.abs(d_corner) - 0.5 * cfg.road.lane_width_m, 0.0)
    i, c = np.unravel_index(int(np.argmax(outside)), outside.shape)
    s, v = ts["s_m"].to_numpy(), ts["vx_mps"].to_numpy()
    # Slack: planned offsets beyond the planner's corridor (computed from the plan's own states).
    lo, hi = planner_lane_bounds_m(cfg, par)
    slack = 0.0
    first_plan_v_arc = math.nan
    track = 0.0
    for step, plan in plans.groupby("step"):
        states = np.zeros((len(plan) + 1, len(State)))
        states[1:, State.s] = plan["s_m"].to_numpy()
        states[1:, State.d] = plan["d_m"].to_numpy()
        states[1:, State.dpsi] = plan["dpsi_rad"].to_numpy()
        d_lo, d_hi = lateral_corridor(states, [], lo, hi, par, 0.0,
                                      road.curvature(states[1:, State.s]))
        d = states[1:, State.d]
        slack = max(slack, float(np.max(np.maximum(d - d_hi, d_lo - d))))
        if step == 0:
            first_plan_v_arc = float(np.interp(arc_start, plan["s_m"], plan["vx_mps"]))
        t0, t1 = float(plan["t_s"].iloc[0]), float(plan["t_s"].iloc[0]) + 0.1
        now = ts[(ts["t_s"] >= t0 - 1e-9) & (ts["t_s"] < t1 - 1e-9)]
        if not now.empty:
            planned = np.interp(now["t_s"], plan["t_k_s"], plan["d_m"])
            track = max(track, float(np.max(np.abs(now["d_m"].to_numpy() - planned))))
    v_lim = math.sqrt(cfg.planner.utilization_factor * cfg.friction.mu_turn * 9.81
                      * cfg.turn.radius_m)
    return {
        "vehicle": cfg.vehicle, "dir": cfg.turn.direction, "start_m": cfg.turn.start_ahead_m,
        "clothoid_m": cfg.turn.clothoid_m, "v0_mps": cfg.initial_speed_mps,
        "mu": cfg.friction.mu_turn,
        "oracle": verdict.feasibility_class.value, "margin_mps": round(verdict.margin_mps, 2),
        "v_lim_mps": round(v_lim, 2),
        "v_curve_mps": round(float(np.interp(curve_start, s, v)), 2),
        "v_arc_mps": round(float(np.interp(arc_start, s, v)), 2),
        "plan0_v_arc_mps": round(first_plan_v_arc, 2),
        "excursion_cm": round(100.0 * float(outside.max()), 1),
        "corner": CORNERS[c] if outside.max() > 0.0 else "-",
        "at_s_m": round(float(s[i] - curve_start), 1) if outside.max() > 0.0 else None,
        "slack_cm": round(100.0 * max(slack, 0.0), 1),
        "tracking_cm": round(100.0 * track, 1),
        "t_exit_s": round(float(np.interp(curve_end, s, ts["t_s"])), 2)
        if s[-1] >= curve_end else None,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("file", nargs="?", default="benchmarks/gt_turn_subset.toml")
    parser.add_argument("--out", default="results/gt-turn-limits")
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--reuse", action="store_true", help="read existing logs in --out")
    parser.add_argument("--where", action="append", default=[],
                        help="KEY=VALUE: keep only the variants with this grid value")
    args = parser.parse_args(argv)
    campaign = load_campaign(args.file)
    specs = [s for s in campaign_specs(campaign) if s.config == "GT"
             and all(w in s.overrides for w in args.where)]
    out = Path(args.out)
    if not args.reuse:
        run_campaign(specs, out / "runs", jobs=args.jobs)
    rows = [diagnose(out / "runs" / spec.name, spec.all_overrides) for spec in specs]
    keys = list(rows[0])
    width = {k: max(len(k), *(len(str(r[k])) for r in rows)) for k in keys}
    print(" ".join(f"{k:>{width[k]}}" for k in keys))
    for row in rows:
        print(" ".join(f"{row[k]!s:>{width[k]}}" for k in keys))
    feasible = [r for r in rows if r["oracle"] == "feasible"]
    print(json.dumps({
        "runs": len(rows), "feasible": len(feasible),
        "feasible_left_lane": sum(r["excursion_cm"] > 0.0 for r in feasible),
        "max_excursion_feasible_cm": max((r["excursion_cm"] for r in feasible), default=0.0),
        "rows": rows,
    }))
    return 0


if __name__ == "__main__":
    sys.exit(main())
