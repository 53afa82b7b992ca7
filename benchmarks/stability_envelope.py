"""GT's runs of a turn campaign against the classical stability envelope (issue 38, item 4).

The envelope of the vehicle-dynamics literature (Rajamani, *Vehicle Dynamics and Control*, 8.4;
Beal & Gerdes 2013): a yaw rate no higher than the friction holds at the speed,
``|ψ̇| v ≤ μ g``, and a body slip close to the kinematic one. For each GT run the oracle calls
feasible this script reads from the run's log

- ``yaw_ratio_max``: the largest ``|ψ̇| v / (μ g)`` the vehicle reached (μ the lower of the two
  axles' true friction; above 3 m/s), and ``yaw_over_s`` how long it was above 1;
- ``body_slip_max``: the largest ``|β|`` [rad] (on a 15 m arc the truck's kinematic body slip,
  ``l_r / R``, is already 0.15 rad);
- ``plan_yaw_ratio_p99``, ``plan_body_slip_max``: the same over the plans' stages 1…N−1 (with
  the plan's μ̂), what the planner asked for;

and prints them per vehicle, split by whether GT left its lane, then the runs that did.

Run: ``python benchmarks/stability_envelope.py OUT`` (a ``mufusion campaign`` output directory).
Numbers go to docs/decisions/0061.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from mufusion.sim.log import load_run

GRAVITY_MPS2 = 9.81
MIN_SPEED_MPS = 3.0


def envelope_row(run_dir: Path) -> dict[str, float | str | bool] | None:
    """The envelope figures of one GT run the oracle calls feasible (None for any other run)."""
    result = json.loads((run_dir / "result.json").read_text())
    if result["spec"]["config"] != "GT" or result["metrics"]["feasibility"] != "feasible":
        return None
    log = load_run(run_dir)
    t = log.timeseries
    mu = np.minimum(t.mu_front, t.mu_rear)
    moving = t.speed_mps > MIN_SPEED_MPS
    yaw_ratio = (t.psidot_radps.abs() * t.speed_mps / (mu * GRAVITY_MPS2))[moving]
    dt_s = float(np.median(np.diff(t.t_s)))
    p = log.plans
    p = p[(p.k >= 1) & (p.vx_mps > MIN_SPEED_MPS)]
    plan_yaw = p.psidot_radps.abs() * p.vx_mps / (p.mu_hat * GRAVITY_MPS2)
    plan_slip = np.arctan2(p.vy_mps.abs(), p.vx_mps)
    overrides = dict(o.split("=", 1) for o in result["spec"]["overrides"])
    m = result["metrics"]
    return {
        "run": run_dir.name.split("-")[0],
        "vehicle": overrides.get("vehicle", "truck"),
        "radius_m": float(overrides.get("turn.radius_m", "nan")),
        "left_lane": bool(m["left_lane"]),
        "excursion_m": float(m["max_lane_excursion_m"]) if m["left_lane"] else 0.0,
        "yaw_ratio_max": float(yaw_ratio.max()),
        "yaw_over_s": float((yaw_ratio > 1.0).sum() * dt_s),
        "body_slip_max": float(t.body_slip_rad.abs().max()),
        "plan_yaw_ratio_p99": float(np.percentile(plan_yaw, 99)) if len(p) else float("nan"),
        "plan_body_slip_max": float(plan_slip.max()) if len(p) else float("nan"),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directory", type=Path)
    args = parser.parse_args(argv)
    rows = [r for d in sorted((args.directory / "runs").iterdir())
            if (r := envelope_row(d)) is not None]
    df = pd.DataFrame(rows)
    figures = ["yaw_ratio_max", "yaw_over_s", "body_slip_max", "plan_yaw_ratio_p99",
               "plan_body_slip_max"]
    pd.set_option("display.width", 200)
    print(df.groupby(["vehicle", "left_lane"])[figures].agg(["median", "max"]).round(3)
          .to_string())
    print(df[df.left_lane].round(3).to_string(index=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
