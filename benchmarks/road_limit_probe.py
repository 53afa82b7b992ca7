"""A held-out probe of GT and F-safe on general roads (issue 38): S-curves, short low-μ patches
before, at or inside the second bend, a patch that ends inside an arc (the friction rises there)
and long bends with a patch in the middle; car and truck; entry speeds set from the oracle.

Writes one `road` scenario per variant (road × vehicle × speed) to ``OUT/roads/``, the oracle's
verdict per variant to ``OUT/verdicts.csv`` and ``OUT/campaign.toml`` (GT and F-safe). The
vehicle starts 15 m before the first bend's entry clothoid (15 m clothoids), so the oracle's
highest entry speed includes braking into that bend. Speeds are fractions of the oracle's
highest entry speed for the road and vehicle: below 0.952 feasible, up to 1.053 marginal.

Run::

    python benchmarks/road_limit_probe.py OUT
    mufusion campaign OUT/campaign.toml --jobs 2 --out OUT/runs
    python benchmarks/limit_grid_outcomes.py OUT/runs --by vehicle

(86 variants, 172 runs, about 3 minutes on two cores.) One run per variant decides "in lane" or
"out" on centimetres; ``--seeds N`` runs each variant from N nearby starts instead (the speed
within ±0.1 m/s, the centre of gravity within ±5 cm of the lane centre, the heading within
±0.01 rad, as ``examples/limits_perturbed.toml``), so a change can be judged on the share of
starts that leave the lane (``--seeds 8``: 1,376 runs). Results: docs/limit-grids.md.
"""

from __future__ import annotations

import argparse
import collections
import csv
import math
from pathlib import Path

from mufusion.scenarios import load_scenario
from mufusion.scenarios.feasibility import classify_scenario
from mufusion.vehicle.params import GRAVITY_MPS2, vehicle_preset

PERTURBATION = ("perturbation.speed_mps=0.1", "perturbation.lateral_offset_m=0.05",
                "perturbation.heading_rad=0.01")
"""The nearby starts of ``--seeds`` (half-widths, as examples/limits_perturbed.toml)."""
START_S_M = 40.0
LEAD_M = 55.0  # the first straight: the vehicle starts 15 m before the first clothoid
CLOTHOID_M = 15.0
REFERENCE_UTILIZATION = 0.9  # for the run's duration only
LOW, MID, HIGH = (0.80, 0.92, 1.00), (0.84, 0.93, 1.03), (0.86, 0.94)

# bends: (radius m, signed total angle rad incl. clothoids); the patch at `where` of the last.
ROADS = [
    ("s_before_a", [(90, 0.6), (60, -0.6)], 30, 0.9, 20, 0.3, "before", LOW),
    ("s_before_b", [(40, -0.8), (120, 0.5)], 35, 0.8, 30, 0.4, "before", HIGH),
    ("s_before_c", [(60, 0.7), (30, -1.0)], 25, 0.85, 15, 0.2, "before", MID),
    ("s_entry_a", [(80, 0.5), (40, -0.8)], 20, 0.9, 15, 0.25, "entry", LOW),
    ("s_entry_b", [(60, -0.6), (90, 0.6)], 25, 0.85, 25, 0.35, "entry", HIGH),
    ("s_entry_c", [(100, -0.5), (50, 0.7)], 20, 0.8, 10, 0.2, "entry", MID),
    ("s_inside_a", [(30, 0.9), (60, -0.7)], 25, 0.9, 20, 0.3, "inside", LOW),
    ("s_inside_b", [(90, -0.5), (30, 1.0)], 20, 0.8, 10, 0.2, "inside", HIGH),
    ("s_inside_c", [(50, 0.7), (120, -0.6)], 30, 0.9, 30, 0.4, "inside", MID),
    ("rise_s_a", [(80, 0.5), (50, -0.8)], 25, 0.9, 25, 0.3, "ends_in_arc", LOW),
    ("rise_s_b", [(45, -0.8), (100, 0.6)], 20, 0.85, 30, 0.2, "ends_in_arc", HIGH),
    ("rise_single", [(70, 1.0)], 0, 0.8, 20, 0.25, "ends_in_arc", MID),
    ("long_a", [(30, 2.5)], 0, 0.9, 15, 0.3, "inside", LOW),
    ("long_b", [(60, -2.2)], 0, 0.8, 25, 0.25, "inside", MID),
    ("long_c", [(100, 1.5)], 0, 0.9, 30, 0.4, "inside", HIGH),
    ("long_d", [(45, -2.5)], 0, 0.85, 10, 0.2, "inside", LOW),
]


def _bend(radius: float, angle: float) -> tuple[list[dict], float, float, float]:
    """Clothoid in, arc, clothoid out turning ``angle`` in all: segments, arc start and end
    from the bend's start, and its length."""
    kappa = math.copysign(1.0 / radius, angle)
    arc_m = radius * abs(angle) - CLOTHOID_M  # the two clothoids turn CLOTHOID_M / R together
    segments = [
        {"kind": "clothoid", "length_m": CLOTHOID_M, "curvature_start_1pm": 0.0,
         "curvature_end_1pm": kappa},
        {"kind": "arc", "radius_m": radius, "angle_rad": math.copysign(arc_m / radius, angle)},
        {"kind": "clothoid", "length_m": CLOTHOID_M, "curvature_start_1pm": kappa,
         "curvature_end_1pm": 0.0},
    ]
    return segments, CLOTHOID_M, CLOTHOID_M + arc_m, 2 * CLOTHOID_M + arc_m


def _layout(bends: list, gap_m: float) -> tuple[list[dict], list[dict]]:
    """The path's segments and, per bend, its entry, arc start and end, and end [m]."""
    segments: list[dict] = [{"kind": "straight", "length_m": LEAD_M}]
    s, marks = LEAD_M, []
    for i, (radius, angle) in enumerate(bends):
        if i:
            segments.append({"kind": "straight", "length_m": gap_m})
            s += gap_m
        pieces, arc0, arc1, length = _bend(radius, angle)
        segments += pieces
        marks.append({"entry": s, "arc0": s + arc0, "arc1": s + arc1, "end": s + length,
                      "radius": radius})
        s += length
    return segments, marks


def _patch(where: str, length_m: float, last: dict) -> tuple[float, float]:
    if where == "before":  # ends 3 m before the last bend's entry clothoid
        return last["entry"] - 3.0 - length_m, last["entry"] - 3.0
    if where == "entry":  # starts 5 m into the entry clothoid
        return last["entry"] + 5.0, last["entry"] + 5.0 + length_m
    if where == "inside":  # centred on the arc
        mid = 0.5 * (last["arc0"] + last["arc1"])
        return mid - 0.5 * length_m, mid + 0.5 * length_m
    return last["arc0"] + 10.0 - length_m, last["arc0"] + 10.0  # ends 10 m into the arc


def _toml(segments: list[dict], patch: tuple[float, float], mu: float, patch_mu: float,
          vehicle: str, speed: float, duration: float, tail_m: float, label: str) -> str:
    def seg(d: dict) -> str:
        return "  { " + ", ".join(f'{k} = "{v}"' if isinstance(v, str) else f"{k} = {round(v, 6)}"
                                  for k, v in d.items()) + " },"
    return "\n".join([
        f"# {label}: benchmarks/road_limit_probe.py",
        'name = "road"', f'description = "{label}, {vehicle} at {speed} m/s"',
        f'vehicle = "{vehicle}"', f"initial_speed_mps = {speed}", f"duration_s = {duration}",
        "seed = 0", f"start_s_m = {START_S_M}", "", "[path]", "segments = [",
        *[seg(d) for d in segments], f'  {{ kind = "straight", length_m = {tail_m} }},', "]",
        "", "[lanes]", "ego_width_m = 3.5", "opposing_width_m = 3.5", 'drivable = "ego_lane"',
        "", "[friction]", f"mu = {mu}", "[[friction.zones]]", f"start_m = {round(patch[0], 3)}",
        f"end_m = {round(patch[1], 3)}", f"mu = {patch_mu}", "", "[estimation]",
        'local_error = "none"', 'predictive_error = "none"', "",
    ])


def main(argv: list[str] | None = None) -> None:
    """Write the probe's scenarios, verdicts and campaign to OUT."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--seeds", type=int, default=0,
                        help="run each variant from this many nearby starts (0: the nominal "
                             "start only)")
    args = parser.parse_args(argv)
    if args.seeds < 0:
        parser.error(f"--seeds must be >= 0, got {args.seeds}")
    out = args.out.resolve()
    (out / "roads").mkdir(parents=True, exist_ok=True)
    rows, files = [], []
    for name, bends, gap_m, mu, patch_m, patch_mu, where, fractions in ROADS:
        segments, marks = _layout(bends, gap_m)
        patch = _patch(where, patch_m, marks[-1])
        for vehicle in ("car", "truck"):
            params = vehicle_preset(vehicle)
            probe = out / "roads" / f"_{name}__{vehicle}.toml"
            probe.write_text(_toml(segments, patch, mu, patch_mu, vehicle, 10.0, 10.0, 800.0,
                                   name))
            v_max = 10.0 + classify_scenario(load_scenario(str(probe)), params).margin_mps
            probe.unlink()
            for fraction in fractions:
                speed = round(fraction * v_max, 1)
                slowest = min(speed, *(math.sqrt(REFERENCE_UTILIZATION * patch_mu
                                                 * GRAVITY_MPS2 * m["radius"]) for m in marks))
                duration = float(math.ceil((marks[-1]["end"] - START_S_M) / slowest + 3.0))
                tail_m = float(max(60, math.ceil(START_S_M + speed * duration
                                                 + params.cog_to_body_front_m + 30.0
                                                 - marks[-1]["end"])))
                path = out / "roads" / f"{name}__{vehicle}_v{speed:.1f}.toml"
                path.write_text(_toml(segments, patch, mu, patch_mu, vehicle, speed, duration,
                                      tail_m, name))
                verdict = classify_scenario(load_scenario(str(path)), params)
                rows.append({"file": path.name, "road": name, "patch": where,
                             "vehicle": vehicle, "speed_mps": speed,
                             "oracle": verdict.feasibility_class.value,
                             "margin_mps": round(verdict.margin_mps, 3)})
                files.append(str(path))
    with open(out / "verdicts.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    (out / "campaign.toml").write_text("\n".join([
        "# The held-out road probe (benchmarks/road_limit_probe.py).",
        'name = "road limit probe"', "scenarios = [", *[f'  "{f}",' for f in files], "]",
        'configs = ["GT", "F-safe"]',
        *([f"overrides = {list(PERTURBATION)!r}".replace("'", '"'), f"seeds = {args.seeds}"]
          if args.seeds else []), ""]))
    print(len(rows), "variants", dict(collections.Counter(r["oracle"] for r in rows)))


if __name__ == "__main__":
    main()
