"""The feasibility oracle over a campaign file's grid: how many variants are feasible, marginal,
infeasible (no simulation).

Run: ``python benchmarks/feasibility_grids.py examples/limits_turn.toml``. ``--axis KEY=V1,V2,...``
replaces (or adds) a grid axis, e.g. to count a widened grid:
``--axis initial_speed_mps=8,9,10,11,12,13,14,15,16,17,18``. ``--by KEY`` adds a breakdown per
value of one axis; ``--csv FILE`` writes every variant's verdict and margin. Prints one table per
file and a final JSON line; numbers go to docs/feasibility.md.
"""

from __future__ import annotations

import argparse
import collections
import csv
import json
import sys

from mufusion.campaign import CampaignFile, campaign_specs, load_campaign
from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import classify_scenario
from mufusion.vehicle.params import vehicle_preset

CLASSES = ("feasible", "marginal", "infeasible")


def _value(text: str) -> bool | int | float | str:
    for cast in (int, float):
        try:
            return cast(text)
        except ValueError:
            pass
    return {"true": True, "false": False}.get(text, text)


def _with_axes(campaign: CampaignFile, axes: list[str]) -> CampaignFile:
    grid = dict(campaign.grid)
    for item in axes:
        key, _, values = item.partition("=")
        grid[key.strip()] = [_value(v.strip()) for v in values.split(",") if v.strip()]
    return campaign.model_copy(update={"grid": grid, "configs": ["GT"]})


def count(campaign: CampaignFile, by: str | None = None, rows: list | None = None) -> dict:
    """Class counts over the campaign's variants (one per scenario × grid point); each variant's
    label, class and margin is appended to ``rows`` if given."""
    totals: collections.Counter[str] = collections.Counter()
    per_value: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    for spec in campaign_specs(campaign.model_copy(update={"configs": ["GT"]})):
        cfg = load_scenario(spec.scenario, list(spec.overrides))
        result = classify_scenario(cfg, vehicle_preset(cfg.vehicle))
        verdict = result.feasibility_class.value
        totals[verdict] += 1
        if rows is not None:
            rows.append((spec.scenario, spec.variant, verdict, round(result.margin_mps, 3)))
        if by is not None:
            value = next((o.partition("=")[2] for o in spec.overrides if o.startswith(by + "=")),
                         "(not on the grid)")
            per_value[value][verdict] += 1
    return {"variants": sum(totals.values()), **{c: totals[c] for c in CLASSES},
            **({"by": {by: {v: dict(c) for v, c in per_value.items()}}} if by else {})}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("files", nargs="+")
    parser.add_argument("--axis", action="append", default=[], help="KEY=V1,V2,... (repeatable)")
    parser.add_argument("--by", default=None, help="break the counts down by this grid key")
    parser.add_argument("--csv", default=None, help="write every variant's verdict to this file")
    args = parser.parse_args(argv)
    results = {}
    rows: list = []
    for file in args.files:
        campaign = _with_axes(load_campaign(file), args.axis)
        result = count(campaign, args.by, rows)
        results[file] = result
        print(f"{file}: {result['variants']} variants  " + "  ".join(
            f"{c} {result[c]}" for c in CLASSES))
        for value, counter in sorted(result.get("by", {}).get(args.by, {}).items()):
            print(f"  {args.by}={value}: " + "  ".join(f"{c} {counter.get(c, 0)}" for c in CLASSES))
    if args.csv:
        with open(args.csv, "w", newline="") as handle:
            writer = csv.writer(handle)
            writer.writerow(["scenario", "variant", "feasibility", "margin_mps"])
            writer.writerows(rows)
    print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
