"""Outcomes of a limit-grid campaign per feasibility class, read from its run results.

For each campaign output directory (``mufusion campaign FILE --out DIR``) and each oracle class:
how many variants, how many GT runs left the lane (with the summed and the largest footprint
excursion) or hit the obstacle, and how many F-safe runs left the lane or hit the obstacle where
GT of the same variant did not, and (where the runs record it) how many GT runs kept a wheel
locked longer than one ABS cycle and GT's summed slip-control activity [s]. Every variant is
classified again with the oracle of the code that runs this script (not the class stored at run
time), so a "before" and an "after" campaign are split by the same verdicts.

Run: ``python benchmarks/limit_grid_outcomes.py DIR [DIR ...] [--by vehicle]``. Prints a Markdown
table per directory and a final JSON line; numbers go to docs/feasibility.md ("The general
grids").
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
from pathlib import Path

from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import classify_scenario
from mufusion.vehicle.params import vehicle_preset

CLASSES = ("feasible", "marginal", "infeasible")


def _runs(directory: Path) -> dict[tuple[str, str, str], dict[str, dict]]:
    """(scenario, variant, seed) → config → {"overrides", "metrics"} of the completed runs."""
    variants: dict[tuple[str, str, str], dict[str, dict]] = collections.defaultdict(dict)
    for result in sorted((directory / "runs").glob("*/result.json")):
        data = json.loads(result.read_text())
        spec = data["spec"]
        key = (spec["scenario"], spec["variant"], str(spec.get("seed")))
        variants[key][spec["config"]] = {"overrides": spec["overrides"],
                                         "metrics": data["metrics"]}
    return variants


def outcomes(directory: Path, by: str | None = None) -> dict[str, dict[str, float]]:
    """Per class (and per value of the override ``by``, if given) the counts described above."""
    rows: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    sums: dict[str, collections.defaultdict[str, float]] = collections.defaultdict(
        lambda: collections.defaultdict(float))
    for (scenario, _, _), configs in _runs(directory).items():
        gt = configs.get("GT")
        if gt is None:
            continue
        cfg = load_scenario(scenario, list(gt["overrides"]))
        verdict = classify_scenario(cfg, vehicle_preset(cfg.vehicle)).feasibility_class.value
        value = next((o.partition("=")[2] for o in gt["overrides"]
                      if by and o.partition("=")[0] == by), None)
        label = verdict if value is None else f"{verdict} / {by}={value}"
        m = gt["metrics"]
        count, total = rows[label], sums[label]
        count["variants"] += 1
        if m["left_lane"]:
            count["gt_out"] += 1
            total["gt_excursion_m"] += m["max_lane_excursion_m"]
            total["gt_max_m"] = max(total["gt_max_m"], m["max_lane_excursion_m"])
        count["gt_collisions"] += bool(m["collision"])
        # Slip-control activity, where the runs record it (absent before it existed).
        count["gt_lock_beyond_abs_cycle"] += m.get("wheel_lock_within_abs_cycle") is False
        total["gt_slip_control_active_s"] += m.get("slip_control_active_s") or 0.0
        total["gt_esc_active_s"] += m.get("stability_control_active_s") or 0.0
        fsafe = configs.get("F-safe")
        if fsafe is not None:
            f = fsafe["metrics"]
            count["fsafe_out_where_gt_in"] += bool(f["left_lane"] and not m["left_lane"])
            count["fsafe_hit_where_gt_clear"] += bool(f["collision"] and not m["collision"])
    return {label: {**rows[label], **{k: round(v, 2) for k, v in sums[label].items()}}
            for label in sorted(rows, key=lambda s: (CLASSES.index(s.split(" ")[0]), s))}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("directories", nargs="+", type=Path)
    parser.add_argument("--by", default=None, help="split each class by this override key")
    args = parser.parse_args(argv)
    results = {}
    columns = ("variants", "gt_out", "gt_excursion_m", "gt_max_m", "gt_collisions",
               "fsafe_out_where_gt_in", "fsafe_hit_where_gt_clear", "gt_lock_beyond_abs_cycle",
               "gt_slip_control_active_s", "gt_esc_active_s")
    for directory in args.directories:
        table = outcomes(directory, args.by)
        results[str(directory)] = table
        print(f"\n{directory}\n| class | " + " | ".join(columns) + " |")
        print("|---" * (len(columns) + 1) + "|")
        for label, row in table.items():
            print(f"| {label} | " + " | ".join(str(row.get(c, 0)) for c in columns) + " |")
    print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
