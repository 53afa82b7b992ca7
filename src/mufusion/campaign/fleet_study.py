"""The acceptance study of shared friction reports (issue 40): vehicle N+1 of a fleet against the
same vehicle without reports, on the turn scenario, car and truck, over seeds.

Per vehicle type and seed: the turn with true μ 0.5 in the turn (the wet class's value, so that
F-safe, which plans on the class's lower edge until its slip estimator measures, has a gap to
GT), a random local error within ± 0.025, the camera's error none or random within its margin
(``CAMERA_ERRORS``), and a small start perturbation.

* Baselines on vehicle N+1's seed: GT, F, F-safe (no reports).
* Per family (F+shared, F-safe+shared): vehicles 1 … N drive the road one after another with
  fresh reports (``fleet_delay_s`` apart); their local estimates are the reports vehicle N+1
  receives, under three conditions: ``fresh`` (``fleet_delay_s`` apart), ``old`` (``OLD_AGE_TAUS``
  τ apart) and ``wrong`` (fresh, with ``WRONG_SHARE`` wrong reports of each kind).

Per run of vehicle N+1: kept its lane; any planned stage above the true μ (the plans' μ̂ against
μ_gt); the share of horizon points with μ̂ > μ_gt (the estimates); planned utilisation at the
comparison instant and the share of the baseline's gap to GT it closes. Proportions come with
Wilson intervals (:func:`~mufusion.campaign.stats.wilson_interval`). Run it as
``python -m mufusion.campaign.fleet_study OUT.json [SEEDS [CAMERA]]`` (nice it on a shared
machine); the acceptance table goes to ``OUT.md``.
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from mufusion.campaign.stats import wilson_interval
from mufusion.configurations import Configuration, make_estimator
from mufusion.estimators import class_table
from mufusion.metrics import compute_metrics
from mufusion.scenarios import load_scenario
from mufusion.scenarios.fleet import reports_from_log
from mufusion.scenarios.runner import run_scenario
from mufusion.scenarios.shared_section import make_inbox
from mufusion.sim.log import RunLog

N_AHEAD = 2
"""Vehicles ahead of the measured one (it is vehicle N + 1 = 3)."""
OLD_AGE_TAUS = 5.0
"""The ``old`` condition: vehicles this many τ apart."""
WRONG_SHARE = 0.2
"""The ``wrong`` condition: this share of wrong reports of each kind."""
GAP_MIN = 0.005
"""A baseline gap to GT in planned utilisation below this is no gap (closure not defined)."""
OVERRIDES = (
    "friction.mu_turn=0.5", "estimation.local_error=random", "perturbation.speed_mps=0.5",
    "perturbation.lateral_offset_m=0.1", "shared.validity_s=100000",
)
"""Every run's scenario overrides; the camera's error model is the study's parameter."""
CAMERA_ERRORS = ("none", "random")
"""``none``: the camera reports the class value (the paper's emulation; F-safe then plans on the
class's lower edge, a gap of the class margin); ``random``: uniform within the margin."""
FAMILIES = {Configuration.F_SHARED: Configuration.F,
            Configuration.F_SAFE_SHARED: Configuration.F_SAFE}


def _run_facts(log: RunLog) -> dict:
    """What the study reads of one run."""
    m = compute_metrics(log)
    plans, est = log.plans, log.estimates
    over_plan = bool((plans["mu_hat"] > plans["mu_true"] + 1e-9).any()) if len(plans) else False
    over_share = float(np.mean(est["mu_hat"] > est["mu_true"] + 1e-9)) if len(est) else 0.0
    probed = bool((log.events["kind"] == "probe_start").any()) if len(log.events) else False
    return {"kept_lane": not m.left_lane, "planned_above_mu": over_plan,
            "horizon_over_share": over_share, "util": m.planned_utilization_at_comparison,
            "probed": probed, "mean_mu_hat": float(est["mu_hat"].mean()) if len(est) else None}


def _vehicle(cfg, configuration, seed, inbox=None) -> RunLog:
    source = make_estimator(configuration, classes=class_table(cfg.estimation.class_table),
                            length_scale_m=cfg.estimation.length_scale_m,
                            shared=cfg.shared.settings(), inbox=inbox,
                            safe_beyond_camera=cfg.estimation.safe_beyond_camera)
    return run_scenario(cfg.model_copy(update={"seed": seed}), source)


def _received(cfg, logs: list[RunLog], delay_s: float, rng_key: tuple[int, ...],
              wrong: bool):
    """Vehicle N+1's inbox from the logs ahead, ``delay_s`` apart."""
    n = len(logs)
    reports = [
        replace(r, t_created_s=r.t_created_s - (n - j) * delay_s)
        for j, log in enumerate(logs)
        for r in reports_from_log(log, sender=f"vehicle-{j + 1}",
                                  position_std_m=cfg.shared.position_std_m)
    ]
    section = cfg.shared if not wrong else cfg.shared.model_copy(update={
        "offset_share": WRONG_SHARE, "replay_share": WRONG_SHARE, "sybil_share": WRONG_SHARE})
    return make_inbox(reports, section, np.random.default_rng(np.random.SeedSequence(rng_key)))


def study_seed(vehicle: str, seed: int, camera: str = "none") -> dict:
    """Every run of one vehicle type and seed; the facts of vehicle N+1 and the baselines."""
    cfg = load_scenario("turn", [*OVERRIDES, f"vehicle={vehicle}",
                                 f"estimation.predictive_error={camera}"])
    base_seed = 1000 * seed + N_AHEAD  # vehicle N+1's seed; vehicle j has 1000·seed + j − 1
    out: dict = {"vehicle": vehicle, "seed": seed}
    for c in (Configuration.GT, Configuration.F, Configuration.F_SAFE):
        out[c.value] = _run_facts(_vehicle(cfg, c, base_seed))
    delays = {"fresh": cfg.shared.fleet_delay_s, "old": OLD_AGE_TAUS * cfg.shared.tau_s,
              "wrong": cfg.shared.fleet_delay_s}
    for family in FAMILIES:
        ahead: list[RunLog] = []
        for j in range(N_AHEAD):
            inbox = _received(cfg, ahead, cfg.shared.fleet_delay_s, (seed, j), False) if ahead \
                else None
            ahead.append(_vehicle(cfg, family, 1000 * seed + j, inbox))
        out[f"{family.value} ahead probed"] = [_run_facts(v)["probed"] for v in ahead]
        for k, (cond, delay) in enumerate(delays.items()):
            inbox = _received(cfg, ahead, delay, (seed, 100 + k), cond == "wrong")
            out[f"{family.value} {cond}"] = _run_facts(_vehicle(cfg, family, base_seed, inbox))
    return out


def _share(flags: list[bool]) -> dict:
    n, k = len(flags), int(sum(flags))
    lo, hi = wilson_interval(k, n) if n else (float("nan"), float("nan"))
    return {"successes": k, "trials": n, "rate": k / n if n else None, "wilson95": [lo, hi]}


def summarise(rows: list[dict]) -> dict:
    """Acceptance figures per vehicle type, family and condition."""
    summary: dict = {}
    for vehicle in sorted({r["vehicle"] for r in rows}):
        mine = [r for r in rows if r["vehicle"] == vehicle]
        for family, base in FAMILIES.items():
            for cond in ("fresh", "old", "wrong"):
                key = f"{family.value} {cond}"
                runs = [r[key] for r in mine]
                closures, not_worse = [], []
                for r in mine:
                    u, b, gt = r[key]["util"], r[base.value]["util"], r["GT"]["util"]
                    if None in (u, b, gt):
                        continue
                    not_worse.append(u >= b - GAP_MIN)
                    if gt - b > GAP_MIN:
                        closures.append((u - b) / (gt - b))
                summary[f"{vehicle} {key}"] = {
                    "kept_lane": _share([x["kept_lane"] for x in runs]),
                    "never_planned_above_mu": _share([not x["planned_above_mu"] for x in runs]),
                    "horizon_over_share_max": max(x["horizon_over_share"] for x in runs),
                    "horizon_over_share_mean": float(np.mean(
                        [x["horizon_over_share"] for x in runs])),
                    "closure_median": float(np.median(closures)) if closures else None,
                    "closure_at_least_half": _share([c >= 0.5 for c in closures]),
                    "not_worse_than_baseline": _share(not_worse),
                    "baseline_over_share_mean": float(np.mean(
                        [r[base.value]["horizon_over_share"] for r in mine])),
                }
    return summary


def _wilson_cell(share: dict) -> str:
    lo, hi = share["wilson95"]
    return f"{share['successes']}/{share['trials']} [{lo:.2f}, {hi:.2f}]"


def report_markdown(summary: dict) -> str:
    """The acceptance table of :func:`summarise` as Markdown, one row per vehicle type, family
    and condition (the table docs/shared-friction.md quotes).

    Columns: kept its lane and never planned above μ (Wilson 95 % intervals); the share of
    horizon points with μ̂ > μ (mean and max over the runs; the baseline's mean); the median
    share of the baseline's gap to GT closed; how many runs closed at least half of it; how
    many were not worse than the baseline.
    """
    lines = [
        "| run | kept lane | never planned above μ | horizon points μ̂ > μ (mean / max; "
        "baseline mean) | gap closed (median) | closed ≥ half | not worse than baseline |",
        "|---|---|---|---|---|---|---|",
    ]
    for key, v in summary.items():
        median = "—" if v["closure_median"] is None else f"{v['closure_median']:.2f}"
        lines.append(
            f"| {key} | {_wilson_cell(v['kept_lane'])} | "
            f"{_wilson_cell(v['never_planned_above_mu'])} | "
            f"{100 * v['horizon_over_share_mean']:.2f} % / "
            f"{100 * v['horizon_over_share_max']:.2f} %; "
            f"{100 * v['baseline_over_share_mean']:.2f} % | {median} | "
            f"{_wilson_cell(v['closure_at_least_half'])} | "
            f"{_wilson_cell(v['not_worse_than_baseline'])} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> None:
    """``OUT.json [SEEDS [CAMERA]]``: run the study (car and truck, seeds 0 … SEEDS−1, the
    camera's error model one of ``CAMERA_ERRORS``, default none) and write it, with its table
    as ``OUT.md`` (:func:`report_markdown`)."""
    out = Path(argv[0])
    seeds = int(argv[1]) if len(argv) > 1 else 5
    camera = argv[2] if len(argv) > 2 else "none"
    if camera not in CAMERA_ERRORS:
        raise SystemExit(f"CAMERA must be one of {CAMERA_ERRORS}, got {camera!r}")
    rows = []
    for vehicle in ("car", "truck"):
        for seed in range(seeds):
            rows.append(study_seed(vehicle, seed, camera))
            print(f"{vehicle} seed {seed} done", flush=True)
            summary = summarise(rows)
            out.write_text(json.dumps({"rows": rows, "summary": summary}, indent=2))
            out.with_suffix(".md").write_text(report_markdown(summary))


if __name__ == "__main__":  # pragma: no cover
    main(sys.argv[1:])
