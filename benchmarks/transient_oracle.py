"""Could any driver of the vehicle have kept its lane? The transient oracle on a campaign's turns.

For each turn run of a campaign output directory (``mufusion campaign FILE --out DIR``; GT by
default) this solves :func:`mufusion.scenarios.feasibility.transient.least_lane_excursion` over
the run's road and entry speed, from its start to 20 m past the curve, and sets it beside what the
run did: the run's deepest lane excursion, the least excursion ``E*`` any controller of the
plant's physics reaches (ideal slip control, full knowledge of the road), and, where the run came
closest to an edge, its speed and heading error against the least-time trajectory's that keeps the
body in the lane. A run out of its lane where ``E* = 0`` is lost by the closed loop, not by
physics; ``E* > 0`` explains it.

Run: ``python benchmarks/transient_oracle.py DIR [DIR ...] [--where vehicle=truck]
[--where road.lane_width_m=3.0] [--exits-only] [--from-run] [--max-utilization 0.9] [--ds 1]
[--jobs 2] [--csv OUT.csv]``. ``--from-run`` starts each search from the run's own trajectory
(a run that kept its lane is then a point with ``E = 0``: the check that the oracle's model
admits what the plant did) before the point-mass speed profiles; ``--max-utilization`` keeps
the driver within that share of each axle's friction (a planner's reserve). One solve takes
tens of seconds to minutes (IPOPT over every metre of the manoeuvre). Prints a Markdown table and
a final JSON line; the findings are in docs/decisions/0108.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np
import pandas as pd

from mufusion.scenarios import load_scenario
from mufusion.scenarios.config import TurnScenario
from mufusion.scenarios.feasibility.transient import (
    EXCURSION_TOLERANCE_M,
    TrajectoryGuess,
    least_lane_excursion,
)
from mufusion.vehicle.params import vehicle_preset

PAST_THE_CURVE_M = 20.0
"""How far past the curve's end the manoeuvre is judged [m]."""


def _selected(directories: list[Path], config: str, where: list[str],
              exits_only: bool) -> list[tuple[Path, dict]]:
    runs = []
    for directory in directories:
        for result in sorted((directory / "runs").glob("*/result.json")):
            data = json.loads(result.read_text())
            spec = data["spec"]
            if spec["scenario"] != "turn" or spec["config"] != config:
                continue
            if any(w not in spec["overrides"] for w in where):
                continue
            if exits_only and not data["metrics"]["left_lane"]:
                continue
            runs.append((result.parent, data))
    return runs


def assess(run: tuple[Path, dict], ds_m: float, from_run: bool = False,
           max_utilization: float = 1.0) -> dict[str, object]:
    """The transient verdict of one run beside the run's own trajectory (``from_run``: the
    search starts from that trajectory before the point-mass speed profiles)."""
    directory, data = run
    cfg = load_scenario("turn", list(data["spec"]["overrides"]))
    assert isinstance(cfg, TurnScenario)
    params = vehicle_preset(cfg.vehicle)
    road = cfg.build_road(params)
    start = cfg.start_s_m
    curve_end = start + cfg.turn.start_ahead_m + cfg.turn.radius_m * cfg.turn.angle_rad \
        + cfg.turn.clothoid_m
    end = min(curve_end + PAST_THE_CURVE_M, road.length_m)
    ts = pd.read_csv(directory / "timeseries.csv")
    guess = TrajectoryGuess.from_timeseries(ts) if from_run else None
    verdict = least_lane_excursion(road, params, start, cfg.initial_speed_mps, end, ds_m=ds_m,
                                   guess=guess, max_utilization=max_utilization)
    ts = ts[ts.s_m <= end]
    worst = ts.iloc[int(np.argmin(ts.lane_margin_m.to_numpy()))]
    k = int(np.argmin(np.abs(verdict.s_m - worst.s_m)))
    metrics = data["metrics"]
    return {
        "run": directory.name,
        "run_excursion_m": round(float(metrics["max_lane_excursion_m"]), 4),
        "least_excursion_m": round(verdict.excursion_m, 4),
        "status": verdict.status,
        "guess": verdict.guess,
        "worst_s_ahead_m": round(float(worst.s_m - start), 1),
        "run_speed_mps": round(float(worst.vx_mps), 2),
        "least_time_speed_mps": round(float(verdict.speed_mps[k]), 2),
        "run_heading_rad": round(float(worst.dpsi_rad), 3),
        "least_time_heading_rad": round(float(verdict.heading_rad[k]), 3),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directories", nargs="+", type=Path)
    parser.add_argument("--config", default="GT", help="configuration whose runs are judged")
    parser.add_argument("--where", action="append", default=[], metavar="KEY=VALUE",
                        help="only runs with this override (repeatable)")
    parser.add_argument("--exits-only", action="store_true", help="only runs that left the lane")
    parser.add_argument("--ds", type=float, default=1.0, help="node spacing [m]")
    parser.add_argument("--from-run", action="store_true",
                        help="start the search from the run's own trajectory first")
    parser.add_argument("--max-utilization", type=float, default=1.0,
                        help="largest share of each axle's friction the driver may use, (0, 1]")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--csv", type=Path, default=None)
    args = parser.parse_args(argv)
    if not args.ds > 0.0:
        parser.error(f"--ds must be > 0, got {args.ds}")
    if not 0.0 < args.max_utilization <= 1.0:
        parser.error(f"--max-utilization must be in (0, 1], got {args.max_utilization}")
    if args.jobs < 1:
        parser.error(f"--jobs must be >= 1, got {args.jobs}")
    runs = _selected(args.directories, args.config, args.where, args.exits_only)
    if not runs:
        print("no turn runs match", file=sys.stderr)
        return 2
    # One solve takes minutes: report each as it ends, keep the table in the runs' order.
    rows: list[dict[str, object]] = [{} for _ in runs]
    with ProcessPoolExecutor(args.jobs) as pool:
        futures = {pool.submit(assess, run, args.ds, args.from_run,
                               args.max_utilization): i
                   for i, run in enumerate(runs)}
        for done, future in enumerate(as_completed(futures), start=1):
            row = future.result()
            rows[futures[future]] = row
            print(f"[{done}/{len(runs)}] {row['run']}: E* = {row['least_excursion_m']} m "
                  f"({row['status']})", file=sys.stderr, flush=True)
    columns = list(rows[0])
    print("| " + " | ".join(columns) + " |")
    print("|" + "---|" * len(columns))
    for row in rows:
        print("| " + " | ".join(str(row[c]) for c in columns) + " |")
    if args.csv is not None:
        with args.csv.open("w", newline="") as handle:
            writer = csv.DictWriter(handle, fieldnames=columns)
            writer.writeheader()
            writer.writerows(rows)
    solved = [r for r in rows if np.isfinite(float(r["least_excursion_m"]))]  # type: ignore[arg-type]
    fits = [r for r in solved if float(r["least_excursion_m"]) <= EXCURSION_TOLERANCE_M]  # type: ignore[arg-type]
    lost = [r for r in fits if float(r["run_excursion_m"]) > 0.0]  # type: ignore[arg-type]
    print(json.dumps({"runs": len(rows), "undecided": len(rows) - len(solved),
                      "body_fits": len(fits), "out_where_the_body_fits": len(lost),
                      "out_of_physics": len(solved) - len(fits)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
