"""A held-out draw at the edge of physics (issue 38): random turn or pop-up variants, each driven
at a fixed fraction of the highest entry speed the oracle allows it.

The published and held-out grids set their speeds on a grid, so most of their feasible variants
have metres per second to spare. Here every variant is as hard as a feasible one can be: its
geometry and friction are drawn from a seeded ``numpy.random.Generator`` over the whole space
(turn: car and truck, radii 15-150 m, angles 0.4-3.14 rad, clothoids 0-30 m, the curve 20-80 m
ahead, the friction changing before, at or inside the arc, μ 0.15-1.0 before and after it, lanes
3.0, 3.5 and 4.0 m wide, left and right; pop-up: μ 0.15-1.0, the obstacle 12-45 m ahead and
offset -0.8 to 1.2 m), and its entry speed is ``fraction`` × the oracle's highest entry speed
(:func:`mufusion.scenarios.feasibility.classify_scenario`: entry speed + margin). A variant is
kept if the oracle calls it feasible at that speed (``fraction`` below 1 / 1.05 is needed) and
the speed lies in 5-35 m/s; the vehicles alternate.

Prints a campaign file (GT and F-safe unless ``--configs`` names others, built-in or a plug-in's
import path, e.g. ``--configs GT F F-safe mypkg.estimators:SlipRLS``; one zipped axis: the
variants as drawn)::

    python benchmarks/limit_edge_draw.py turn --seed 9 --variants 80 > edge_turn.toml
    mufusion campaign edge_turn.toml --out edge_turn --jobs 2
    python benchmarks/limit_grid_outcomes.py edge_turn

(80 turn variants, 160 runs: about 3 minutes on two cores.) Results: docs/limit-grids.md.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable, Sequence

import numpy as np
from pydantic import ValidationError

from mufusion.campaign.schema import CampaignFile
from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import FeasibilityClass, classify_scenario
from mufusion.vehicle.params import vehicle_preset

VEHICLES = ("truck", "car")
SPEED_RANGE_MPS = (5.0, 35.0)
PROBE_SPEED_MPS = 10.0
"""The entry speed the oracle is asked at: its margin gives the highest entry speed."""
MAX_TRIES_PER_VARIANT = 20


def _turn_geometry(rng: np.random.Generator, vehicle: str) -> list[str]:
    radius = round(float(rng.uniform(15.0, 150.0)))
    angle = round(float(rng.uniform(0.4, 3.14)), 2)
    # Each clothoid no longer than the turn (the scenario's rule: the arc between them is what
    # the turn leaves).
    clothoid = float(rng.choice([c for c in (0.0, 10.0, 20.0, 30.0) if c <= radius * angle]))
    start = round(float(rng.uniform(20.0, 80.0)))
    where = rng.choice(["before", "at", "inside"])
    if where == "before":
        change = start - round(float(rng.uniform(5.0, min(30.0, start - 2.0))))
    elif where == "at":
        change = start + clothoid
    else:
        # Up to 0.7 of the arc in, and no further than the scenario's 200 m.
        inside = min(max(6.0, 0.7 * radius * angle), 200.0 - start - clothoid)
        change = start + clothoid + round(float(rng.uniform(5.0, inside)))
    mu_before, mu_turn = (round(float(x), 2) for x in rng.uniform(0.15, 1.0, 2))
    return [f"vehicle={vehicle}", f"turn.radius_m={radius:.1f}", f"turn.angle_rad={angle}",
            f"turn.clothoid_m={clothoid}", f"turn.start_ahead_m={start:.1f}",
            f"friction.change_ahead_m={float(change)}", f"friction.mu_before={mu_before}",
            f"friction.mu_turn={mu_turn}",
            f"road.lane_width_m={float(rng.choice([3.0, 3.5, 3.5, 4.0]))}",
            f"turn.direction={rng.choice(['left', 'right'])}"]


def _turn_duration_s(overrides: list[str], speed_mps: float) -> float:
    """Long enough to drive the approach, both clothoids, the arc (at most 150 m of it) and 15 m,
    at 0.6 of the entry speed; at most 26 s (the general grid's longest)."""
    value = {k: float(v) for k, _, v in (o.partition("=") for o in overrides)
             if k.startswith("turn.") and k != "turn.direction"}
    path_m = (value["turn.start_ahead_m"] + 2.0 * value["turn.clothoid_m"]
              + min(value["turn.radius_m"] * value["turn.angle_rad"], 150.0) + 15.0)
    return float(math.ceil(min(26.0, path_m / max(0.6 * speed_mps, 4.0))))


def _popup_geometry(rng: np.random.Generator, vehicle: str) -> list[str]:
    return [f"vehicle={vehicle}", f"friction.mu={round(float(rng.uniform(0.15, 1.0)), 2)}",
            f"obstacle.distance_m={float(round(float(rng.uniform(12.0, 45.0))))}",
            f"obstacle.lateral_offset_m={float(rng.choice([-0.8, -0.4, 0.0, 0.5, 1.2]))}"]


def _verdict(kind: str, overrides: list[str]):
    cfg = load_scenario(kind, overrides)
    return classify_scenario(cfg, vehicle_preset(cfg.vehicle))


def draw(kind: str, rng: np.random.Generator, variants: int, fraction: float) -> list[list[str]]:
    """``variants`` feasible variants of ``kind``, each at ``fraction`` of its highest entry
    speed (overrides as a campaign gives them).

    Raises
    ------
    RuntimeError
        If fewer than ``variants`` were found in ``MAX_TRIES_PER_VARIANT × variants`` draws.
    """
    geometry: Callable[[np.random.Generator, str], list[str]] = (
        _turn_geometry if kind == "turn" else _popup_geometry)
    rows: list[list[str]] = []
    for _ in range(MAX_TRIES_PER_VARIANT * variants):
        if len(rows) == variants:
            return rows
        base = geometry(rng, VEHICLES[len(rows) % 2])
        highest = PROBE_SPEED_MPS + _verdict(
            kind, [*base, f"initial_speed_mps={PROBE_SPEED_MPS}"]).margin_mps
        speed = round(fraction * highest, 1)
        if not SPEED_RANGE_MPS[0] <= speed <= SPEED_RANGE_MPS[1]:
            continue
        row = [*base, f"initial_speed_mps={speed}"]
        if kind == "turn":
            row.append(f"duration_s={_turn_duration_s(base, speed)}")
        # A campaign refuses a variant listed twice; a repeat of the quantised draw is skipped.
        if row not in rows and _verdict(kind, row).feasibility_class is FeasibilityClass.FEASIBLE:
            rows.append(row)
    if len(rows) < variants:
        raise RuntimeError(f"only {len(rows)} of {variants} feasible variants drawn")
    return rows


def campaign_text(kind: str, rows: list[list[str]], seed: int, fraction: float,
                  configs: Sequence[str] = ("GT", "F-safe")) -> str:
    """The campaign file: ``configs`` over one zipped axis holding every drawn variant."""
    keys = [o.partition("=")[0] for o in rows[0]]

    def value(text: str) -> str:
        try:
            float(text)
        except ValueError:
            return f'"{text}"'
        return text

    chosen = "" if list(configs) == ["GT", "F-safe"] else " --configs " + " ".join(configs)
    lines = [f"# python benchmarks/limit_edge_draw.py {kind} --seed {seed} "
             f"--variants {len(rows)} --fraction {fraction}{chosen}",
             f'name = "{kind} at {fraction} of the oracle\'s highest entry speed, seed {seed}"',
             f'scenarios = ["{kind}"]', f"configs = {json.dumps(list(configs))}", "", "[grid]",
             '"' + ", ".join(keys) + '" = [']
    lines += ["    [" + ", ".join(value(o.partition("=")[2]) for o in row) + "]," for row in rows]
    return "\n".join([*lines, "]", ""])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("kind", choices=["turn", "popup"])
    parser.add_argument("--seed", type=int, default=9)
    parser.add_argument("--variants", type=int, default=80)
    parser.add_argument("--fraction", type=float, default=1 / 1.07,
                        help="entry speed / the oracle's highest (default 1/1.07 = 0.935)")
    parser.add_argument("--configs", nargs="+", default=["GT", "F-safe"],
                        help="configurations to run: built-in names or plug-in import paths")
    args = parser.parse_args(argv)
    try:  # before any draw: a misspelt configuration is named at once
        CampaignFile.model_validate({"scenarios": [args.kind], "configs": args.configs})
    except ValidationError as err:
        parser.error("; ".join(str(e["msg"]) for e in err.errors()))
    if args.variants < 1:
        parser.error(f"--variants must be >= 1, got {args.variants}")
    if not 0.0 < args.fraction < 1.0 / 1.05:
        parser.error(f"--fraction must be in (0, {1 / 1.05:.4f}) (feasible: more than the "
                     f"oracle's 5 % band below the highest speed), got {args.fraction}")
    rows = draw(args.kind, np.random.default_rng(args.seed), args.variants, args.fraction)
    sys.stdout.write(campaign_text(args.kind, rows, args.seed, round(args.fraction, 6),
                                   args.configs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
